"""Verification of a tool path against every face of a part: gouges and collisions of the tool body (mm, degrees).

For every tool position, and for the motion between consecutive positions as a CNC makes it
(tip and axis interpolated linearly between the positions, then the axis normalised, sampled at
most ``step_mm`` and ``step_deg`` apart), the signed distance between the tool body and the part
is computed on the exact surfaces:

1. every face (trimmed region only) is sampled on a parameter grid about ``spacing_mm`` apart;
   a k-d tree of the samples gives, per placement, those within the tool's bounding sphere;
2. the signed distance of each such sample to the body is computed exactly from the tool's
   profile in its (rho, z) half-plane (:meth:`~machsurf_cad.cutters.Cutter.cutting_distance_rz`,
   shank and holder separately);
3. around the closest sample of every placement that comes within ``tolerance + spacing`` of the
   part, the face is searched again on the exact NURBS: three nested 5 x 5 parameter patches, each
   a third of the previous, down to 1/18 of the sample spacing (the distance error is then about
   the square of that step over the tool radius: below 1e-3 mm for 1 mm samples), inside the trimmed region.

Negative distances are depths inside the tool: a point of the part inside the cutting part is a
**gouge** (the tool removes material beyond the surface by about that depth), inside the shank or
holder a **collision**; a rapid move whose cutting part touches the part is a collision too. A tool
buried in the material touches no face: when the middle of its cutting part lies behind the nearest
face (by its outward normal) by more than the tool radius plus the sampling, it is a gouge of at
least that depth.
"""

from __future__ import annotations

import math
import warnings
from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from .buried import buried
from .cam.toolpath import Move, ToolPath
from .coarsepass import coarse_pass
from .errors import InputError
from .geometry.bspline import BSplineSurface
from .geometry.face import Face
from .glossary import renamed
from .results import Progress, Result
from .typing import MapChunks, PartLike, ToolLike

CLEAR, GOUGE, COLLISION = 0, 1, 2
STATUS = {CLEAR: "clear", GOUGE: "gouge", COLLISION: "collision"}


@dataclass(frozen=True, eq=False)
class VerifyResult(Result):
    """Per position of the tool path: the smallest signed distance (mm) between the cutting part and
    the part over the motion that ends there, the same for shank and holder, where it happens, and
    the status (0 clear, 1 gouge, 2 collision); per part sample: the deepest the tool went into it."""

    toolpath: ToolPath
    cutter: object
    tolerance: float
    cut_distance: np.ndarray
    holder_distance: np.ndarray
    worst_face: np.ndarray
    worst_xyz: np.ndarray
    status: np.ndarray
    sample_points: np.ndarray
    sample_face: np.ndarray
    sample_depth: np.ndarray
    face_names: tuple
    spacing_mm: float
    step_mm: float
    step_deg: float
    n_placements: int
    warnings: tuple = ()
    time_s: dict | None = None
    motion_bound_mm: float = 0.0
    clearance_mm: float | None = None
    """Least distance of rapids, shank and holder from the part (mm); ``None``: the tolerance."""

    @property
    def gouge_depth(self) -> np.ndarray:
        """Depth (mm, >= 0) of the cutting part inside the part per position."""
        return np.maximum(0.0, -self.cut_distance)

    @property
    def max_gouge(self) -> float:
        cutting = self.toolpath.move != Move.RAPID
        return float(self.gouge_depth[cutting].max()) if cutting.any() else 0.0

    @property
    def clean(self) -> bool:
        return bool(np.all(self.status == CLEAR))

    def worst(self, k: int = 10) -> list[dict]:
        """The ``k`` deepest gouging or colliding positions (GOTO index, tip, depth, face)."""
        bad = np.nonzero(self.status != CLEAR)[0]
        depth = np.maximum(-self.cut_distance[bad], -self.holder_distance[bad])
        order = bad[np.argsort(-depth)][:k]
        return [
            {
                "index": int(i),
                "pass": int(self.toolpath.pass_index[i]),
                "move": Move(int(self.toolpath.move[i])).name.lower(),
                "status": STATUS[int(self.status[i])],
                "tip_mm": self.toolpath.tip[i].tolist(),
                "depth_mm": float(max(-self.cut_distance[i], -self.holder_distance[i])),
                "face": self.face_names[int(self.worst_face[i])] if self.worst_face[i] >= 0 else None,
                "face_index": int(self.worst_face[i]),
                "part_point_mm": self.worst_xyz[i].tolist(),
            }
            for i in order
        ]

    def report(self) -> dict:
        rapid = self.toolpath.move == Move.RAPID
        clearances = [x for x in list(self.holder_distance) + list(self.cut_distance[rapid]) if np.isfinite(x)]
        return {
            "n_positions": int(self.toolpath.n_positions),
            "n_placements_checked": int(self.n_placements),
            "n_faces": len(self.face_names),
            "n_part_samples": int(self.sample_points.shape[0]),
            "sample_spacing_mm": self.spacing_mm,
            "motion_step_mm": self.step_mm,
            "motion_step_deg": self.step_deg,
            "motion_bound_mm": self.motion_bound_mm,
            "tolerance_mm": self.tolerance,
            "clearance_mm": self.tolerance if self.clearance_mm is None else self.clearance_mm,
            "n_gouging_positions": int(np.count_nonzero(self.status == GOUGE)),
            "max_gouge_mm": self.max_gouge,
            "n_collisions": int(np.count_nonzero(self.status == COLLISION)),
            "min_clearance_mm": float(min(clearances)) if clearances else None,
            "min_cut_distance_mm": float(self.cut_distance.min()),
            "clean": self.clean,
            "worst": self.worst(),
            "warnings": list(self.warnings),
            "time_s": dict(self.time_s or {}),
        }


def _faces(part, what: str = "verify") -> list[Face]:
    """The part as a list of :class:`Face` (B-spline surfaces wrapped); ``what`` names the caller in errors."""
    items = part if isinstance(part, (list, tuple)) else [part]
    out = []
    for i, f in enumerate(items):
        if isinstance(f, BSplineSurface):
            f = Face(f, name=f.name or f"face_{i}")
        if not isinstance(f, Face):
            raise InputError(f"{what} needs the part's faces (Face or BSplineSurface objects)")
        out.append(f)
    if not out:
        raise InputError(f"{what} needs at least one face of the part")
    return out


def face_size(face: Face) -> tuple[float, float]:
    """Longest iso-line lengths of the face's parameter box along u and along v (mm, 9 x 9 samples)."""
    u0, u1, v0, v1 = face.uv_bounds
    g = face.surface.evaluate_grid(np.linspace(u0, u1, 9), np.linspace(v0, v1, 9))
    lu = float(np.linalg.norm(np.diff(g, axis=0), axis=-1).sum(axis=0).max())
    lv = float(np.linalg.norm(np.diff(g, axis=1), axis=-1).sum(axis=1).max())
    return lu, lv


def _sample_face(face: Face, spacing: float):
    """Trim-aware parameter grid about ``spacing`` mm apart; returns points, u, v, du, dv."""
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    lu, lv = face_size(face)
    nu = int(np.clip(math.ceil(lu / spacing) + 1, 8, 3000))
    nv = int(np.clip(math.ceil(lv / spacing) + 1, 8, 3000))
    us, vs = np.linspace(u0, u1, nu), np.linspace(v0, v1, nv)
    U, V = np.meshgrid(us, vs, indexing="ij")
    P = s.evaluate_grid(us, vs).reshape(-1, 3)
    keep = face.contains_uv_grid(us, vs).ravel() if face.is_trimmed else np.ones(U.size, bool)
    return P[keep], U.ravel()[keep], V.ravel()[keep], (u1 - u0) / (nu - 1), (v1 - v0) / (nv - 1)


def motion_radius(cutter) -> float:
    """Smallest radius (mm) whose sagitta bounds what sampling a motion misses: the smallest convex arc
    of the cutting profile, or the tool radius (its rim's circle in plan)."""
    from .cutter_profiles import ArcSegment

    rs = [seg.radius for seg in cutter.profile() if isinstance(seg, ArcSegment) and seg.convex]
    return float(min(rs + [float(cutter.radius)]))


MAX_PLACEMENTS = 20_000_000
"""Most tool placements verify checks before it refuses (about 10 us each in the sampled pass)."""


def _face_sizes(faces, fk: str) -> np.ndarray:
    """:func:`face_size` of every face, kept for the last part (by its content key ``fk``): a path's links
    are checked in many calls on the same part."""
    if fk and fk in _SIZES:
        return _SIZES[fk]
    sizes = np.array([face_size(f) for f in faces], float).reshape(-1, 2)
    if fk:
        _SIZES.clear()
        _SIZES[fk] = sizes
    return sizes


def _auto_spacing(faces, c, max_samples: int, fk: str = "") -> float:
    """The part's sample spacing when none is given: min(1, D/8) mm, or larger where the faces' parameter
    boxes would hold more than 80 % of ``max_samples`` (large faces are checked, not refused: every close
    approach is refined on the exact surfaces whatever the spacing)."""
    h = min(1.0, c.D / 8.0)
    sizes = _face_sizes(faces, fk)
    for _ in range(40):
        n = np.clip(np.ceil(sizes / h) + 1, 8, 3000).prod(axis=1).sum()
        if n <= 0.8 * max_samples:
            return h
        h *= 1.25
    return h


def _check_placements(tp: ToolPath, step_mm: float, step_deg: float) -> None:
    """Refuse, with the figure and the option that lowers it, a path whose motion sampling is too dense."""
    seg = np.linalg.norm(np.diff(tp.tip, axis=0), axis=1)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", tp.axis[:-1], tp.axis[1:]), -1.0, 1.0)))
    n = float(np.maximum(np.maximum(np.ceil(seg / step_mm), np.ceil(ang / step_deg)), 1).sum()) + 1
    if n > MAX_PLACEMENTS:
        raise InputError(
            f"checking this path every {step_mm:g} mm and {step_deg:g} deg needs {n:.3g} tool placements "
            f"({tp.n_positions:,} positions, {float(seg.sum()):.4g} mm of motion), more than {MAX_PLACEMENTS:,}: "
            "give a larger step (--step, --step-deg)"
        )


def _placements(tp: ToolPath, step_mm: float, step_deg: float, jumps=None):
    """Tips, axes and owning position of every checked placement (positions and the motion between); a
    position of ``jumps`` (a mask) has no motion into it, only its own placement."""
    tips, axes, owner = [tp.tip[:1]], [tp.axis[:1]], [np.array([0])]
    for k in range(1, tp.n_positions):
        if jumps is not None and jumps[k]:
            tips.append(tp.tip[k : k + 1])
            axes.append(tp.axis[k : k + 1])
            owner.append(np.array([k]))
            continue
        a, b = tp.tip[k - 1], tp.tip[k]
        ta, tb = tp.axis[k - 1], tp.axis[k]
        ang = math.degrees(math.acos(float(np.clip(ta @ tb, -1.0, 1.0))))
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / step_mm), math.ceil(ang / step_deg))
        s = (np.arange(1, n + 1) / n)[:, None]
        ax = (1 - s) * ta + s * tb
        nrm = np.linalg.norm(ax, axis=1, keepdims=True)
        if np.any(nrm < 1e-9):
            raise InputError(f"the axis turns by 180 deg between positions {k - 1} and {k}: no linear motion")
        tips.append((1 - s) * a + s * b)
        axes.append(ax / nrm)
        owner.append(np.full(n, k))
    return np.concatenate(tips), np.concatenate(axes), np.concatenate(owner)


_RECENT: OrderedDict = OrderedDict()
_MAX_RECENT = 2
_SAMPLED: OrderedDict = OrderedDict()
_SIZES: dict = {}


def _memo_key(fk: str, toolpath, tool, params, map_chunks) -> str:
    """The content key of a check (the faces' key ``fk``, positions, axes, moves, the whole tool, every
    parameter); empty when it cannot be keyed (faces not given as faces, a custom chunk runner)."""
    from .contentkey import content_key

    if not fk or map_chunks is not None:
        return ""
    if toolpath is None:  # the sampled pass's placements: their own bits are their key
        return content_key(fk, repr(tool), params)
    tp = toolpath
    return content_key(fk, np.asarray(tp.tip), np.asarray(tp.axis), np.asarray(tp.move), repr(tool), params)


@renamed(
    cutter="tool",
    tolerance="gouge_tolerance",
    step_mm="step",
    step_deg="angle_step",
    spacing_mm="spacing",
    clearance_mm="clearance",
)
def verify(
    part: PartLike,
    toolpath: ToolPath,
    tool: ToolLike | None = None,
    *,
    gouge_tolerance: float = 0.01,
    step: float | None = None,
    angle_step: float = 1.0,
    spacing: float | None = None,
    progress: Progress | None = None,
    max_samples: int = 20_000_000,
    chunks: int = 1,
    map_chunks: MapChunks = None,
    clearance: float | None = None,
    jumps: np.ndarray | None = None,
) -> VerifyResult:
    """Gouges and collisions of a tool path's tool body against every face of a part.

    Parameters
    ----------
    part : Face, BSplineSurface or sequence of them
        Every face of the part (trimmed regions respected).
    toolpath : ToolPath
        Positions, axes and move kinds; its cutter is used unless ``tool`` is given.
    tool : Cutter, optional
        The tool with its shank and holder.
    gouge_tolerance : float
        A part point deeper than this inside the cutting part is a gouge (mm).
    clearance : float, optional
        Shank or holder closer than this to the part, or a rapid move's cutting part, is a collision (mm;
        default ``gouge_tolerance``).
    step, angle_step : float
        Largest step of the tip (mm) and of the axis (degrees) between checked placements along
        each linear move. Between two placements the swept tool can reach deeper than both by up to
        ``step^2 / (8 rho)`` (``rho`` the smallest profile arc radius, or the tool radius: the rim's
        circle in plan); that bound is reported (``motion_bound_mm``) and the default step,
        ``min(1, sqrt(4 rho gouge_tolerance))``, keeps it at half the tolerance: a gouge deeper than 1.5
        times the tolerance is never read as clear.
    spacing : float, optional
        Part sample spacing (default min(1, D/8) mm); every close approach is refined on the exact
        surface to 1/18 of it.
    progress : Progress, optional
        ``progress(done, total, message)`` over the placements.
    max_samples : int
        Work-size bound on the part's samples (about 100 bytes each with the k-d tree).
    chunks : int
        Split the placements into this many chunks for the sampled pass (each placement's result
        depends on no other: the figures are the same to the last digit).
    map_chunks : callable, optional
        ``map``-like callable running the chunks (e.g. :func:`machsurf_cad.batchrun.dask_map`).
    jumps : array of bool, optional
        Positions with no motion into them: each starts a separate stretch (several candidate moves
        checked in one call); only the position itself is placed there.

    Returns
    -------
    VerifyResult

    Raises
    ------
    InputError
        No cutter, no face, non-positive steps or tolerance, a 180 deg axis flip between positions.

    Examples
    --------
    >>> import numpy as np
    >>> from machsurf_cad import BallEndMill, ToolPath
    >>> from machsurf_cad.geometry import builders
    >>> plane = builders.plane_patch()  # z = 0, 100 x 100 mm
    >>> tips = [np.array([[20.0, 50, z], [80, 50, z]]) for z in (0.0, -0.05)]  # on it, then 0.05 mm into it
    >>> tp = ToolPath.from_passes(tips, [np.array([[0.0, 0, 1]] * 2)] * 2, cutter=BallEndMill(10))
    >>> res = verify(plane, tp, gouge_tolerance=0.01)
    >>> round(res.max_gouge, 6), res.report()["n_gouging_positions"]
    (0.05, 2)
    """
    import time

    t0 = time.perf_counter()
    from . import checks
    from .checks import positive

    toolpath = checks.toolpath(toolpath)
    c = checks.tool(tool) if tool is not None else toolpath.cutter
    if c is None:
        raise InputError("verify needs the tool: give --tool (the tool path carries none)")

    gouge_tolerance = positive("gouge_tolerance", gouge_tolerance)
    clear = gouge_tolerance if clearance is None else checks.finite("clearance", clearance)
    rho_motion = motion_radius(c)
    step = min(1.0, math.sqrt(4.0 * rho_motion * gouge_tolerance)) if step is None else positive("step", step)
    angle_step = positive("angle_step", angle_step, "deg")
    given = _faces(part)
    faces, perm, fk = _canonical(given)  # the check's memo, the part's samples and sizes are keyed by fk
    h = positive("spacing", spacing) if spacing is not None else _auto_spacing(faces, c, max_samples, fk)
    if jumps is not None:
        jumps = np.asarray(jumps, bool).reshape(-1)
        if jumps.shape != (toolpath.n_positions,):
            raise InputError(f"jumps: one flag per position ({toolpath.n_positions}), got {jumps.size}")
    _check_placements(toolpath, step, angle_step)
    jk = None if jumps is None else np.flatnonzero(jumps).tolist()
    key = _memo_key(fk, toolpath, c, (gouge_tolerance, clear, step, angle_step, h, max_samples, jk), map_chunks)
    if key in _RECENT:  # the very same check just ran (a raster's own check, then the check before writing)
        _RECENT.move_to_end(key)
        res = _RECENT[key]
        for w in res.warnings:
            warnings.warn(w, stacklevel=2)
        return _in_order(replace(res, toolpath=toolpath), perm, given)
    smp, tree = _sampled(faces, fk, h, max_samples)
    T, A, owner = _placements(toolpath, step, angle_step, jumps)
    m = T.shape[0]
    t1 = time.perf_counter()
    coarse_key = _memo_key(fk, None, c, (gouge_tolerance, clear, h, max_samples), map_chunks)
    cut_d, hold_d, seed, hold_seed, depth = coarse_pass(
        c, tree, smp.P, h, gouge_tolerance, T, A, chunks, map_chunks, progress, clear=clear, memo_key=coarse_key
    )
    t2 = time.perf_counter()
    best_face, best_xyz = _refine_close(faces, c, smp, T, A, seed, cut_d, gouge_tolerance, h)
    buried(faces, c, tree, smp, T, A, h, gouge_tolerance, cut_d, seed, best_face, best_xyz)
    far = seed < 0
    best_face[far] = -1
    pos_cut, pos_hold, pos_face, pos_xyz, status = _per_position(
        toolpath, owner, smp, cut_d, hold_d, hold_seed, best_face, best_xyz, gouge_tolerance, clear
    )
    warns = []
    if np.all(~np.isfinite(pos_cut)) or (np.isfinite(pos_cut).any() and np.nanmin(pos_cut) > c.D):
        warns.append(f"the tool never comes within {c.D:g} mm of the part: is this the part the path was made for?")
    for w in warns:
        warnings.warn(w, stacklevel=2)
    t3 = time.perf_counter()
    times = {"sample_s": t1 - t0, "coarse_s": t2 - t1, "refine_s": t3 - t2, "total_s": t3 - t0}
    res = VerifyResult(
        toolpath,
        c,
        float(gouge_tolerance),
        pos_cut,
        pos_hold,
        pos_face,
        pos_xyz,
        status,
        smp.P,
        smp.F,
        depth,
        tuple(f.name or f"face_{i}" for i, f in enumerate(faces)),
        float(h),
        float(step),
        float(angle_step),
        int(m),
        tuple(warns),
        times,
        float(step) * float(step) / (8.0 * rho_motion),  # inf, not OverflowError, for an absurd step
        float(clear),
    )
    if key:
        _RECENT[key] = res
        while len(_RECENT) > _MAX_RECENT:
            _RECENT.popitem(last=False)
    return _in_order(res, perm, given)


def _canonical(faces: list[Face]):
    """The faces in the order of their content keys, that order (``perm[i]``: the given index of the
    i-th), and the key of them all: a check's figures, memo and samples do not depend on the order the
    faces come in (a raster's own check on its machined faces then the rest, and the check of the whole
    part before writing, are one check). Faces that cannot be keyed keep their order (key empty)."""
    from .contentkey import content_key, faces_key

    keys = [faces_key([f]) for f in faces]
    if not all(keys):
        return faces, np.arange(len(faces)), ""
    perm = np.array(sorted(range(len(faces)), key=keys.__getitem__), dtype=np.int64)
    return [faces[i] for i in perm], perm, content_key(tuple(keys[i] for i in perm))


def _in_order(res: VerifyResult, perm: np.ndarray, given: list[Face]) -> VerifyResult:
    """``res`` (faces in :func:`_canonical` order) with its face indices and names in the given order."""
    wf = np.asarray(res.worst_face)
    return replace(
        res,
        worst_face=np.where(wf >= 0, perm[np.maximum(wf, 0)], -1),
        sample_face=perm[np.asarray(res.sample_face)],
        face_names=tuple(f.name or f"face_{i}" for i, f in enumerate(given)),
    )


class _Samples(NamedTuple):
    """The part's samples: points, face index, (u, v) of each, and each face's parameter steps."""

    P: np.ndarray
    F: np.ndarray
    SU: np.ndarray
    SV: np.ndarray
    dus: list
    dvs: list


def _sampled(faces: list[Face], fk: str, h: float, max_samples: int):
    """The part's samples and their k-d tree, kept for the last two parts (by their content key ``fk``) and
    spacings (a path's links are checked in several calls on the same part)."""
    key = (fk, float(h), int(max_samples))
    if fk and key in _SAMPLED:
        _SAMPLED.move_to_end(key)
        return _SAMPLED[key]
    smp = _sample_part(faces, h, max_samples)
    out = (smp, cKDTree(smp.P))
    if not fk:
        return out
    _SAMPLED[key] = out
    while len(_SAMPLED) > 2:
        _SAMPLED.popitem(last=False)
    return out


def _sample_part(faces: list[Face], h: float, max_samples: int) -> _Samples:
    """Sample every face about ``h`` mm apart (trimmed regions only), refusing more than ``max_samples``."""
    pts, fid, us, vs, dus, dvs = [], [], [], [], [], []
    total = 0
    for i, f in enumerate(faces):
        P, U, V, du, dv = _sample_face(f, h)
        total += P.shape[0]
        if total > max_samples:
            raise InputError(
                f"sampling the part every {h:g} mm needs more than {max_samples} points (face {i} of {len(faces)}): "
                "give a larger spacing_mm (--spacing) or fewer faces (--faces)"
            )
        pts.append(P)
        fid.append(np.full(P.shape[0], i))
        us.append(U)
        vs.append(V)
        dus.append(du)
        dvs.append(dv)
    P = np.concatenate(pts)
    F = np.concatenate(fid)
    SU, SV = np.concatenate(us), np.concatenate(vs)
    if P.shape[0] == 0:
        raise InputError("the part's faces have no sample inside their trimmed regions")
    return _Samples(P, F, SU, SV, dus, dvs)


def _refine_close(faces, c, smp: _Samples, T, A, seed, cut_d, gouge_tolerance, h):
    """Refine every close approach on the exact surfaces (``cut_d`` lowered in place); its face and point."""
    P, F, SU, SV, dus, dvs = smp
    m = T.shape[0]
    close = np.nonzero((seed >= 0) & (cut_d < gouge_tolerance + h))[0]
    best_xyz = np.full((m, 3), np.nan)
    best_face = np.full(m, -1)
    if close.size:
        best_face[close] = F[seed[close]]
        best_xyz[close] = P[seed[close]]
        for fi in np.unique(F[seed[close]]):
            sel = close[F[seed[close]] == fi]
            d_new, xyz = _refine(faces[fi], c, T[sel], A[sel], SU[seed[sel]], SV[seed[sel]], dus[fi], dvs[fi])
            better = d_new < cut_d[sel]
            cut_d[sel[better]] = d_new[better]
            best_xyz[sel[better]] = xyz[better]
    return best_face, best_xyz


def _per_position(
    toolpath, owner, smp: _Samples, cut_d, hold_d, hold_seed, best_face, best_xyz, gouge_tolerance, clear
):
    """Per position, the worst placement of the motion ending there: distances, face, part point and status."""
    n = toolpath.n_positions
    pos_cut = np.full(n, np.inf)
    pos_hold = np.full(n, np.inf)
    np.minimum.at(pos_cut, owner, cut_d)
    np.minimum.at(pos_hold, owner, hold_d)
    order = np.lexsort((cut_d, owner))
    first = np.r_[True, owner[order][1:] != owner[order][:-1]]
    wp = order[first]
    pos_face = np.full(n, -1)
    pos_xyz = np.full((n, 3), np.nan)
    pos_face[owner[wp]] = best_face[wp]
    pos_xyz[owner[wp]] = best_xyz[wp]
    status = np.full(n, CLEAR, np.int8)
    rapid = toolpath.move == Move.RAPID
    status[(~rapid) & (pos_cut < -gouge_tolerance)] = GOUGE
    status[rapid & (pos_cut < clear)] = COLLISION
    status[pos_hold < clear] = COLLISION
    # where shank or holder collide and the cutting part does not gouge: their part point
    hold_pos = np.nonzero((pos_hold < clear) & (pos_cut >= -gouge_tolerance))[0]
    if hold_pos.size:
        order_h = np.lexsort((hold_d, owner))
        wh = order_h[np.r_[True, owner[order_h][1:] != owner[order_h][:-1]]]
        by_pos = np.full(n, -1)
        by_pos[owner[wh]] = hold_seed[wh]
        hs = by_pos[hold_pos]
        ok = hs >= 0
        pos_face[hold_pos[ok]] = smp.F[hs[ok]]
        pos_xyz[hold_pos[ok]] = smp.P[hs[ok]]
    return pos_cut, pos_hold, pos_face, pos_xyz, status


def _refine(face: Face, c, T, A, u, v, du, dv, levels: int = 3, k: int = 5):
    """Nested parameter patches around ``(u, v)``: the smallest signed distance of the face to the
    cutting part placed at ``T``, ``A`` (one per seed) and the part point where it is."""
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    m = u.size
    best = np.full(m, np.inf)
    xyz = np.full((m, 3), np.nan)
    cu, cv = u.copy(), v.copy()
    hu, hv = du, dv
    off = np.linspace(-1.0, 1.0, k)
    grid_u, grid_v = np.meshgrid(off, off, indexing="ij")
    OU, OV = grid_u.ravel(), grid_v.ravel()
    for _ in range(levels):
        uu = np.clip(cu[:, None] + hu * OU[None, :], u0, u1)
        vv = np.clip(cv[:, None] + hv * OV[None, :], v0, v1)
        Q = s.evaluate(uu.ravel(), vv.ravel()).reshape(m, -1, 3)
        rel = Q - T[:, None, :]
        z = np.einsum("mkj,mj->mk", rel, A)
        rho = np.linalg.norm(rel - z[..., None] * A[:, None, :], axis=-1)
        d = c.cutting_distance_rz(rho, z)
        if face.is_trimmed:  # the trimming test only where it can matter (a candidate better than the best)
            cand = d < best[:, None]
            if cand.any():
                inside = face.contains_uv(uu[cand], vv[cand])
                dc = d[cand]
                dc[~inside] = np.inf
                d[cand] = dc
        j = np.argmin(d, axis=1)
        dj = d[np.arange(m), j]
        better = dj < best
        best[better] = dj[better]
        xyz[better] = Q[np.arange(m), j][better]
        cu = np.where(better, uu[np.arange(m), j], cu)
        cv = np.where(better, vv[np.arange(m), j], cv)
        hu, hv = hu / 3.0, hv / 3.0
    return best, xyz


__all__ = ["verify", "VerifyResult", "CLEAR", "GOUGE", "COLLISION", "STATUS"]
