"""How much of a face a 3-axis (or 3+2) tool can touch: the area it reaches, and what a dropped tool touches.

For a part point ``p`` with outward normal ``n`` (facing the tool: ``n . axis >= 0``), the tool touches
``p`` where its lower surface ``z = h(rho)`` has the same tangent plane: at the radius ``rho`` where
``h'(rho) = |n_h| / n_z`` (the rim for steeper points), on the side ``e_r = -n_h / |n_h|``, so its tip is
``p - rho e_r - h(rho) axis`` (moved a tenth of the tolerance further along ``-e_r``: a tool tangent to a
wall along its equator slides past it). The point is **reachable** when that placement cuts into no face: the exact
drop-cutter height ``H`` at the tip's plan point is not above the tip (``H <= tip + tolerance``). It is
**touched by the dropped tool** (what a raster or the CL surface machines) when ``|H - tip| <=
tolerance``. A point facing away from the axis is neither. The fractions are area-weighted over a grid of
samples inside each face's trimming.
"""

from __future__ import annotations

import numpy as np

from .. import checks
from ..errors import InputError
from . import cache
from .dropcutter import default_seed_spacing, drop_cutter
from .faceset import FaceSet
from .faceset import face_set as build_face_set
from .solves import _Profile


def _samples(face, n: int):
    """Cell-centre samples of a face (in its own frame), their unit outward normals and area weights."""
    u0, u1, v0, v1 = face.uv_bounds
    du, dv = (u1 - u0) / n, (v1 - v0) / n
    U, V = np.meshgrid(u0 + du * (np.arange(n) + 0.5), v0 + dv * (np.arange(n) + 0.5), indexing="ij")
    u, v = U.ravel(), V.ravel()
    if face.is_trimmed:
        keep = face.contains_uv(u, v)
        u, v = u[keep], v[keep]
    d = face.surface.derivatives(u, v, 1)
    cr = np.cross(d.su, d.sv)
    area = np.linalg.norm(cr, axis=1)
    nrm = cr / np.where(area > 0, area, 1.0)[:, None]
    if face.reversed:
        nrm = -nrm
    return d.point, nrm, area * du * dv


def reachable_area(
    faces,
    machined,
    tool,
    *,
    axis=(0.0, 0.0, 1.0),
    samples: int = 8_000,
    tolerance: float = 1e-3,
    face_set: FaceSet | None = None,
) -> list[dict]:
    """Per machined face: its area, the area a tool along ``axis`` can touch without cutting into any face
    of ``faces``, and the area the dropped tool touches (mm^2 and fractions; module docstring).

    Parameters
    ----------
    faces : sequence of Face
        Every face the tool must not cut into (the part).
    machined : sequence of int
        Indices of the faces to measure.
    tool : Cutter or str
    axis : 3-vector
        The fixed tool axis.
    samples : int
        Samples over all the measured faces, shared by area (at least 8 x 8 a face; area-weighted).
    tolerance : float
        How close (mm) a placement must come to touch a point.
    face_set : FaceSet, optional
        The prepared drop-cutter faces (same faces and axis), reused.

    Returns
    -------
    list of dict
        ``face``, ``area_mm2``, ``reachable_mm2``, ``reachable_fraction``, ``touched_mm2``,
        ``touched_fraction``, ``facing_away_fraction``.
    """
    cutter = checks.tool(tool)
    if int(samples) < 4:
        raise InputError("samples must be >= 4")
    prof = _Profile(cutter)
    fs = face_set or cache.face_set(build_face_set, list(faces), axis=axis, spacing=default_seed_spacing(cutter))
    machined = list(machined)
    areas = np.array([_samples(fs.faces[i], 16)[2].sum() for i in machined])
    share = areas / areas.sum() if areas.sum() > 0 else np.full(len(machined), 1.0 / max(len(machined), 1))
    eps = 0.1 * float(tolerance)  # the placement a hair away from the point: tangency to a wall is no contact
    out = []
    for i, a in zip(machined, share):
        n_i = max(8, int(np.sqrt(int(samples) * a)))
        P, n, w = _samples(fs.faces[i], n_i)  # the face set's faces are in the tool frame
        nh = np.hypot(n[:, 0], n[:, 1])
        facing = n[:, 2] >= -1e-9
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(n[:, 2] > 1e-12, nh / n[:, 2], np.inf)
            er = np.where(nh[:, None] > 1e-12, -n[:, :2] / nh[:, None], 0.0)
        rho = prof.radius_of_slope(slope)
        h = prof(rho)[0]
        tip_xy = P[:, :2] - (rho[:, None] + eps) * er
        tip_z = P[:, 2] - h
        H = np.full(P.shape[0], np.nan)
        if facing.any():
            H[facing] = drop_cutter(None, cutter, tip_xy[facing], face_set=fs).height
        with np.errstate(invalid="ignore"):
            reach = facing & np.isfinite(H) & (H <= tip_z + tolerance)
            touch = reach & (H >= tip_z - tolerance)
        total = float(w.sum())
        out.append(
            {
                "face": int(i),
                "area_mm2": total,
                "reachable_mm2": float(w[reach].sum()),
                "reachable_fraction": float(w[reach].sum() / total) if total > 0 else 0.0,
                "touched_mm2": float(w[touch].sum()),
                "touched_fraction": float(w[touch].sum() / total) if total > 0 else 0.0,
                "facing_away_fraction": float(w[~facing].sum() / total) if total > 0 else 0.0,
            }
        )
    return out
