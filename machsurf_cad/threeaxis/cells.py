"""Fine cells of a face set's seed samples: tighter bounds for the compiled drop-cutter's branch and bound.

The seed samples of :class:`.FaceSet` are a third of the tool radius apart, so the bound they give a
neighbourhood (``z + rise - h(rho - cover)``) is loose by millimetres: most local solves of a query are
spent on neighbourhoods that cannot beat the contact already found. Here every face is sampled ``factor``
times finer (the same grid refined, and every trimming edge refined between its samples), and each fine
sample is given to the nearest seed sample of its face: the seed sample's *cell*. A cell's bound is the
largest over its fine samples of the same formula with the fine cover, ``factor`` times tighter.

Every face point lies within its fine sample's cover of a fine sample (the fine grid's argument of
:func:`.faceset.face_set`), so the cells of the samples within ``R + radius`` of a query cover every face
point within ``R`` of it: a neighbourhood whose cells' bounds are below a contact found cannot beat it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .faceset import FaceSet, _slope, _slopes, capped_rise, grid_counts

MAX_FINE_SAMPLES = 4_000_000
"""Fine samples at most (the factor falls for face sets that would need more)."""


@dataclass(frozen=True, eq=False)
class FineCells:
    """Per pool sample (face samples, then edge samples, as :class:`.FaceSet` orders them) its cell.

    Attributes
    ----------
    start : ndarray (n_pool + 1,)
        The fine samples of pool sample ``j`` are ``start[j]:start[j + 1]``.
    xyz, rise, cover : ndarray
        Fine samples (tool frame) with the rise of z within their cover radius (mm).
    radius : ndarray (n_pool,)
        Every point of a sample's cell lies within this distance of it (mm).
    contained : bool
        Whether every cell lies within its sample's cover (:attr:`.FaceSet.cover`): then a neighbourhood
        may be skipped on either bound (a point in a cell is in its sample's neighbourhood too).
    top : ndarray (n_pool,)
        The highest ``z + rise`` of the cell's fine samples (mm).
    uv : ndarray (n_fine, 2)
        The face parameters of the fine samples (inside the face and on its edges).
    steps : ndarray (n_faces, 8)
        Per face the parameter steps of its seed grid and of its fine grid, ``du, dv, du / factor, dv /
        factor`` (0 for a vertical face), then the same for the samples on its edges: a step and one and a
        half times the largest parameter gap between neighbouring edge samples (seed, then fine). A face
        point in a grid cell lies within the cover radius of each of the cell's corners, so a sample's bound
        covers no point outside the parameter box of one step about it; where the trimming cuts the cell, the
        edge samples that bound it lie within the edge step of it (the rim certificate of the compiled
        drop-cutter relies on this).
    factor : int
        How many times finer than the seed samples.
    """

    start: np.ndarray
    xyz: np.ndarray
    rise: np.ndarray
    cover: np.ndarray
    radius: np.ndarray
    top: np.ndarray
    factor: int
    uv: np.ndarray
    steps: np.ndarray
    contained: bool


def _refined(t: np.ndarray, factor: int) -> np.ndarray:
    """``t`` with ``factor - 1`` equally spaced values inserted between neighbours (``t`` kept)."""
    if factor == 1 or t.size < 2:
        return t
    w = np.arange(factor) / factor
    inner = (t[:-1, None] * (1 - w) + t[1:, None] * w).ravel()
    return np.append(inner, t[-1])


def _face_fine(fs: FaceSet, i: int, factor: int):
    """Fine samples of face ``i`` (grid inside the trim, then its edges): points, rise, cover."""
    face = fs.faces[i]
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    nu, nv = grid_counts(face, fs.spacing)
    us = _refined(np.linspace(u0, u1, nu), factor)
    vs = _refined(np.linspace(v0, v1, nv), factor)
    d = s.derivatives_grid(us, vs, 1)
    slope, delta, kappa = _slopes(d, us.size, vs.size)
    if face.is_trimmed:
        keep = face.contains_uv_grid(us, vs).ravel()
    else:
        keep = np.ones(us.size * vs.size, bool)
    pts = [d.point.reshape(-1, 3)[keep]]
    U, V = np.meshgrid(us, vs, indexing="ij")
    uvs = [np.stack([U.ravel(), V.ravel()], axis=1)[keep]]
    slopes = [slope[keep]]
    gaps = np.zeros((2, 2))  # the largest parameter gaps between neighbouring edge samples: seed, fine
    for e in np.nonzero(fs.edge_face == i)[0]:
        t0 = np.sort(fs.edge_t[fs.edge_id == e])
        t = _refined(t0, factor)
        uv = fs.edges[e].evaluate(t)
        de = s.derivatives(uv[:, 0], uv[:, 1], 1)
        pts.append(de.point)
        uvs.append(uv)
        slopes.append(_slope(de.su, de.sv))
        for g, w in enumerate((fs.edges[e].evaluate(t0), uv)):
            if w.shape[0] > 1:
                gaps[g] = np.maximum(gaps[g], np.abs(np.diff(w, axis=0)).max(axis=0))
    p, sl = np.concatenate(pts), np.concatenate(slopes)
    rise = capped_rise(delta * np.minimum(1.0, sl + kappa * delta), p[:, 2], float(fs.face_top[i]))
    du, dv = (u1 - u0) / (nu - 1), (v1 - v0) / (nv - 1)
    # a face point in a grid cell the trimming cuts lies within a step of the trimming curve (the cell's
    # corners on its other side are not samples) and so within a step and a half gap of an edge sample
    steps = (du, dv, du / factor, dv / factor, du + 1.5 * gaps[0, 0], dv + 1.5 * gaps[0, 1],
             du / factor + 1.5 * gaps[1, 0], dv / factor + 1.5 * gaps[1, 1])  # fmt: skip
    return p, rise, np.full(p.shape[0], delta), np.concatenate(uvs), steps


def fine_cells(fs: FaceSet, factor: int = 4) -> FineCells:
    """The cells of ``fs``'s pool samples (cached on the face set); ``factor`` falls when the fine samples would
    exceed :data:`MAX_FINE_SAMPLES`."""
    cache = fs.__dict__.setdefault("_cells", {})
    n_pool = fs.n_samples
    while factor > 1 and n_pool * factor * factor > MAX_FINE_SAMPLES:
        factor -= 1
    if factor in cache:
        return cache[factor]
    pool_xyz, pool_face = fs.pool_xyz, fs.pool_face
    XYZ, RISE, COV, OWN, DIST, UV = [], [], [], [], [], []
    steps = np.zeros((len(fs.faces), 8))
    for i in range(len(fs.faces)):
        mine = np.nonzero(pool_face == i)[0]
        if mine.size == 0 or fs.face_vertical[i]:  # (a vertical face's samples bound nothing: no cells)
            continue
        p, rise, cov, uv, steps[i] = _face_fine(fs, i, factor)
        UV.append(uv)
        dist, k = cKDTree(pool_xyz[mine]).query(p, workers=-1)
        XYZ.append(p)
        RISE.append(rise)
        COV.append(cov)
        OWN.append(mine[k])
        DIST.append(dist + cov)
    if not OWN:  # only vertical faces: no cells
        OWN, XYZ, UV = [np.zeros(0, np.int64)], [np.zeros((0, 3))], [np.zeros((0, 2))]
        RISE = COV = DIST = [np.zeros(0)]
    own = np.concatenate(OWN)
    order = np.argsort(own, kind="stable")
    own = own[order]
    xyz, rise, cov, dist, uv = (np.concatenate(a)[order] for a in (XYZ, RISE, COV, DIST, UV))
    start = np.zeros(n_pool + 1, np.int64)
    np.cumsum(np.bincount(own, minlength=n_pool), out=start[1:])
    radius = np.zeros(n_pool)
    np.maximum.at(radius, own, dist)
    top = np.full(n_pool, -np.inf)
    np.maximum.at(top, own, xyz[:, 2] + rise)
    bounding = np.isfinite(fs.cover)
    contained = bool(np.all(radius[bounding] <= fs.cover[bounding] * (1 + 1e-9)))
    cells = FineCells(
        start, np.ascontiguousarray(xyz), rise, cov, radius, top, factor, np.ascontiguousarray(uv), steps, contained
    )
    cache[factor] = cells
    return cells
