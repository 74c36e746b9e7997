"""Which faces of a part a 3-axis job machines: ``all``, ``top`` (visible along the tool axis) or a list."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..geometry.face import Face
from ..typing import FacesLike, Vector3
from .faceset import axis_frame


def _normals(face: Face, n: int = 12):
    """Samples (points, outward unit normals) of a face on an ``n x n`` trimmed grid."""
    u0, u1, v0, v1 = face.uv_bounds
    us, vs = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
    U, V = np.meshgrid(us, vs, indexing="ij")
    d = face.surface.derivatives(U.ravel(), V.ravel(), 1)
    nrm = np.cross(d.su, d.sv)
    ln = np.linalg.norm(nrm, axis=1)
    ok = ln > 1e-12 * max(float(ln.max(initial=0.0)), 1e-300)
    if face.is_trimmed:
        ok &= face.contains_uv(U.ravel(), V.ravel())
    nrm = nrm[ok] / ln[ok, None]
    return d.point[ok], (-nrm if face.reversed else nrm)


def _as_faces(faces) -> list[Face]:
    if isinstance(faces, Face):
        return [faces]
    try:
        out = list(faces)
    except TypeError:
        raise InputError(f"faces must be a sequence of Face, got {type(faces).__name__}") from None
    if not out or not all(isinstance(f, Face) for f in out):
        raise InputError("faces must be a non-empty sequence of Face")
    return out


def top_faces(faces: FacesLike, *, axis: Vector3 = (0.0, 0.0, 1.0), min_fraction: float = 0.05) -> list[int]:
    """Indices of the faces seen from above along ``axis``: at least ``min_fraction`` of a face's samples
    face the axis (outward normal . axis > 0.01) and have no other face above them along the axis
    (a vertical ray to the sky, tested on the exact surfaces by a drop of a 0.002 mm ball)."""
    from ..cutters import BallEndMill
    from .dropcutter import drop_cutter

    faces = _as_faces(faces)
    a = axis_frame(axis)[2]
    pts, owner = [], []
    for i, f in enumerate(faces):
        p, n = _normals(f)
        up = (n @ a) > 0.01
        pts.append(p[up])
        owner.append(np.full(int(up.sum()), i))
    P = np.concatenate(pts)
    F = np.concatenate(owner)
    if P.size == 0:
        return []
    frame = axis_frame(axis)
    local = P @ frame.T
    probe = BallEndMill(0.002)
    res = drop_cutter(faces, probe, local[:, :2], axis=axis, seed_spacing=2.0)
    seen = res.height <= local[:, 2] + 1e-4
    out = []
    for i in range(len(faces)):
        total = max(1, int(np.count_nonzero(F == i)))
        if np.count_nonzero(seen & (F == i)) >= max(1, min_fraction * total) and np.any(F == i):
            out.append(i)
    return out


def select_faces(faces, text: str, *, axis=(0.0, 0.0, 1.0), what: str = "--faces") -> list[int]:
    """Indices named by ``all``, ``top``, ``none`` or a comma list like ``0,3,5`` (checked to exist)."""
    t = str(text).strip().lower()
    n = len(faces)
    if t == "all":
        return list(range(n))
    if t == "none":
        return []
    if t == "top":
        idx = top_faces(faces, axis=axis)
        if not idx:
            raise InputError(f"no face of the part is visible along the axis {tuple(float(x) for x in axis)}")
        return idx
    try:
        idx = [int(x) for x in t.split(",") if x.strip()]
    except ValueError:
        raise InputError(f"{what} must be all, top, none or face indices like 0,3,5; got {text!r}") from None
    bad = [i for i in idx if not 0 <= i < n]
    if bad:
        raise InputError(f"{what}: face {bad[0]} does not exist (the part has {n} faces, 0..{n - 1})")
    if not idx:
        raise InputError(f"{what} names no face")
    if what == "--faces":
        for i in idx:
            if faces_away(faces[i], axis):
                raise InputError(
                    f"face {i} faces away from {_axis_text(axis)} (its outward normal points against the tool axis "
                    "everywhere): no tool position along this axis touches it; give another --axis or other --faces"
                )
    return sorted(set(idx))


def faces_away(face: Face, axis, n: int = 24, *, below: float = -1e-6) -> bool:
    """Whether ``face``'s outward normal . ``axis`` is under ``below`` at every sample of an ``n x n`` trimmed
    grid (with the default, a tool coming down the axis touches such a face nowhere but on edges it shares
    with others; with ``below=0.01``, the face is also vertical where it does not face away)."""
    a = axis_frame(axis)[2]
    _, nrm = _normals(face, n)
    return nrm.shape[0] > 0 and float((nrm @ a).max()) < below


def _axis_text(axis) -> str:
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    for name, v in (("+Z", (0, 0, 1)), ("-Z", (0, 0, -1)), ("+X", (1, 0, 0)), ("-X", (-1, 0, 0)),
                    ("+Y", (0, 1, 0)), ("-Y", (0, -1, 0))):  # fmt: skip
        if np.allclose(a, v, atol=1e-12):
            return name
    return "the axis (" + ", ".join(f"{x:.4g}" for x in a) + ")"
