"""Tools buried in the material, for the tool-body check (:func:`machsurf_cad.verify`): a placement that
touches no face can still lie inside the part. It is buried when it lies behind each of its nearest part
samples along their inward normals (within 60 deg: not past a sheet's edge) by more than the sampling can
explain, and, far from every face where the nearest samples can all be the back of a thin feature, when
the part's winding number says it is inside.
"""

from __future__ import annotations

import math

import numpy as np


def buried(faces, c, tree, smp, T, A, h, gouge_tolerance, cut_d, seed, best_face, best_xyz) -> None:
    """Mark the placements buried in the material as gouges (``cut_d``, ``seed`` and the worst points, in place)."""
    # a tool buried in the material touches no face: behind the nearest face (its outward normal) by
    # more than the sampling can explain, with no face point inside the cutting part, is a gouge too;
    # behind every one of its nearest samples: the nearest alone can be a wall facing away (a tool high
    # above a hole's edge is "behind" the hole's wall, not in the material)
    P, F, SU, SV = smp.P, smp.F, smp.SU, smp.SV
    L_cut = float(c.length)
    r_cut = float(c.profile_points(16)[:, 0].max())
    mid = T + A * min(L_cut, c.D) / 2
    kn = min(8, P.shape[0])
    dk, nk = tree.query(mid, k=kn, workers=-1)
    nk = nk.reshape(mid.shape[0], kn)
    dk = dk.reshape(mid.shape[0], kn)
    flat = nk.ravel()
    nrm = np.empty((flat.size, 3))
    for fi in np.unique(F[flat]):
        k = np.nonzero(F[flat] == fi)[0]
        fc = faces[fi]
        nrm[k] = fc.surface.normals(SU[flat[k]], SV[flat[k]], check=False) * (-1.0 if fc.reversed else 1.0)
    behind_k = -np.einsum("ij,ij->i", np.repeat(mid, kn, axis=0) - P[flat], nrm).reshape(-1, kn)
    ni = nk[:, 0]
    # behind each along its normal, not past its face's edge (a point above a sheet's top edge is behind
    # its nearest samples only by a sliver of its distance): within 60 deg of the inward normal
    behind_k = np.where(behind_k >= 0.5 * dk, behind_k, -np.inf)
    behind = np.where(np.isfinite(behind_k).all(axis=1), behind_k.min(axis=1), np.nan)
    inside = np.isfinite(behind) & (behind > h + gouge_tolerance + r_cut) & (cut_d > -gouge_tolerance)
    # far from every face the nearest samples can all be the back of a thin feature (a rapid far above an
    # impeller's blade tips): there the samples' winding number must say inside too
    far = np.flatnonzero(inside & (dk[:, 0] > L_cut + c.D))
    if far.size:
        inside[far[winding_number(faces, smp, mid[far]) < 0.5]] = False
    if np.any(inside):
        cut_d[inside] = -behind[inside]
        best_face[inside] = F[ni[inside]]
        best_xyz[inside] = P[ni[inside]]
        seed[inside] = ni[inside]


def winding_number(faces, smp, X: np.ndarray, budget: float = 2e8) -> np.ndarray:
    """The generalized winding number of the sampled faces at the points ``X`` (about 1 inside a closed
    part, 0 outside): the sum over the samples of their outward area element's solid angle, each sample
    standing for its parameter cell (``|S_u x S_v| du dv``). Over ``budget`` sample-point pairs every
    k-th sample stands for k cells (the points asking are far from every face, where this is smooth)."""
    n = smp.P.shape[0]
    k = max(1, math.ceil(n * X.shape[0] / budget))
    idx = np.arange(0, n, k)
    F = smp.F[idx]
    dA = np.empty((idx.size, 3))
    for fi in np.unique(F):
        j = np.nonzero(F == fi)[0]
        fc = faces[fi]
        d = fc.surface.derivatives(smp.SU[idx[j]], smp.SV[idx[j]], order=1)
        cell = smp.dus[fi] * smp.dvs[fi] * k * (-1.0 if fc.reversed else 1.0)
        dA[j] = np.cross(d.su, d.sv) * cell
    P = smp.P[idx]
    out = np.empty(X.shape[0])
    rows = max(1, int(2e6 // idx.size))  # pairs per chunk: about 50 MB
    for a in range(0, X.shape[0], rows):
        q = P[None, :, :] - X[a : a + rows, None, :]
        r3 = np.maximum(np.linalg.norm(q, axis=2) ** 3, 1e-30)
        out[a : a + rows] = (np.einsum("mnk,nk->mn", q, dA) / r3).sum(axis=1)
    return out / (4.0 * math.pi)
