"""Tool paths on the machining surface and cutter-location (CL) output (mm, degrees).

Curves C1 on the guiding surface S1 are intersections with parallel planes (a step-over
apart) or iso-parametric lines; the matching C2 on S2 comes from the shared parameters.
Each curve is traced densely, each point projected exactly onto its plane by Newton's
method, then sampled with a chordal tolerance on the tool-tip path (Douglas-Peucker: every
dense point within the tolerance of the chords). Output: CSV and APT CLDATA.

Vocabulary (after OpenCAMLib): CC cutter-contact point on F, K torus centre-circle point on
S1, CL axis point in the torus plane on S2, tip = CL - r u the tool-tip point written to
GOTO statements, u the tool axis.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from ..cam.chordal import chord_error, douglas_peucker
from ..cam.toolpath import ToolPath
from ..errors import InputError
from ..glossary import renamed
from ..typing import FaceLike, StrategyLike
from .positions import _positions
from .strategies import IsoFeed, PlanesFeed
from .surfaces import MachiningSurface


@renamed(ms="surface")
def tool_paths(
    surface: MachiningSurface,
    *,
    stepover: float | None = None,
    scallop: float | None = None,
    overrun: float | None = None,
    chordal_tolerance: float = 0.005,
    strategy: StrategyLike | None = None,
    grid: int = 401,
    zigzag: bool = True,
    clearance: float = 5.0,
    max_passes: int = 5000,
    safe_sphere: tuple | None = None,
    safe_plane: float | None = None,
    safe_cylinder: tuple | None = None,
) -> ToolPath:
    """Tool paths on S1: plane sections (``PlanesFeed``) or iso-parametric lines (``IsoFeed``).

    Parameters
    ----------
    surface : MachiningSurface
        The certified S1/S2 surfaces.
    stepover : float
        Distance between planes (mm) or, for iso lines, the approximate distance between lines
        measured on S1.
    scallop : float, optional
        Instead of ``stepover``: iso-scallop passes, spaced on the surface so that the predicted cusp
        between neighbours is ``scallop`` mm (:func:`~machsurf_cad.machining.isoscallop.iso_scallop_paths`).
    overrun : float, optional
        With ``scallop``: passes run on past the face's edges by this much (mm, default the tool radius).
    chordal_tolerance : float
        Max distance of the dense tip path from the chords between written positions, mm.
    strategy : PlanesFeed or IsoFeed, optional
        Defaults to the machining surface's feed.
    clearance : float
        Approach and retract distance along the tool axis, mm.
    max_passes : int
        Work-size bound: more passes than this is refused (with the smallest admissible step-over).
    safe_sphere : (centre, radius), optional
        A sphere around the whole part (mm): passes are linked over it instead of by straight rapids
        (:meth:`~machsurf_cad.cam.ToolPath.from_passes`).
    safe_plane : float, optional
        3 axes and 3+2: the height along the fixed axis of a plane above the whole part (:func:`part_plane`):
        the path starts and ends on it and passes are linked in it.
    safe_cylinder : (point, axis, radius, half_length), optional
        A cylinder around the whole part (:func:`part_cylinder`): passes are linked over it.

    Returns
    -------
    ToolPath
        Positions at the tool tip with unit axes, CC points, extras ``uv`` (on the nominal),
        ``K`` (S1), ``CL`` (S2 / ball centre) and ``level``; ``info`` holds the measured chordal
        error and, in 5 axes, the measured axis error. Points outside the trimmed face are
        dropped (a pass is split there).

    Raises
    ------
    InputError
        Non-positive step-over or tolerance, no pass crossing the face, a strategy without a feed.

    Examples
    --------
    >>> from machsurf_cad import example, machining_surface
    >>> ms = machining_surface(example("bezier5"), "bull:D=28,r=4", lead=20, tolerance=1e-3)
    >>> tp = tool_paths(ms, stepover=10.0, chordal_tolerance=0.01)
    >>> import numpy as np
    >>> lv = tp.extras["level"]
    >>> np.unique(lv[~np.isnan(lv)]).tolist()[:3], tp.info["chordal_error_measured_mm"] <= 0.01
    ([0.0, 10.0, 20.0], True)
    """
    from .. import checks
    from .strategies import as_feed

    if not isinstance(surface, MachiningSurface):
        raise InputError(f"tool_paths needs a MachiningSurface (ms.machining_surface), got {type(surface).__name__}")
    if (stepover is None) == (scallop is None):
        raise InputError("tool_paths needs a stepover or a scallop height (one of them)")
    if scallop is not None:
        from .isoscallop import iso_scallop_paths

        return iso_scallop_paths(
            surface, scallop=scallop, chordal_tolerance=chordal_tolerance, strategy=strategy, zigzag=zigzag,
            clearance=clearance, overrun=overrun, max_passes=max_passes, safe_sphere=safe_sphere,
            safe_plane=safe_plane, safe_cylinder=safe_cylinder,
        )  # fmt: skip
    if overrun is not None:
        raise InputError("overrun applies to iso-scallop passes: give scallop")
    stepover = checks.positive("stepover", stepover)
    checks.positive("chordal tolerance", chordal_tolerance)
    checks.positive("clearance", clearance)
    grid = checks.index("grid", grid, low=3)
    feed = as_feed(strategy) if strategy is not None else getattr(surface.strategy, "feed", None)
    if feed is None:
        feed = IsoFeed("u")
    us, vs, g_masked, levels, kind, N = _section_levels(surface, feed, grid, stepover)
    if len(levels) > max_passes:
        raise InputError(
            f"step-over {stepover:g} mm gives {len(levels)} passes over this face (at most {max_passes}, "
            f"--stepover >= {stepover * len(levels) / max_passes:.3g} mm)"
        )
    tips, axes, ccs, extras, chord_err, axis_err = _trace_passes(
        surface, us, vs, g_masked, levels, kind, N, chordal_tolerance, zigzag
    )
    if not tips:
        raise InputError("no tool pass crosses the face: reduce the step-over")
    info = {
        "kind": kind,
        "stepover_mm": float(stepover),
        "chordal_tolerance_mm": float(chordal_tolerance),
        "chordal_error_measured_mm": chord_err,
        "axis_error_deg_measured": axis_err if surface.axes == 5 else None,
        "n_cut_positions": int(sum(t.shape[0] for t in tips)),
    }
    return ToolPath.from_passes(
        tips,
        axes,
        cc=ccs,
        extras=extras,
        clearance=clearance,
        cutter=surface.cutter,
        name="machining_surface",
        info=info,
        safe_sphere=safe_sphere,
        safe_plane=safe_plane,
        safe_cylinder=safe_cylinder,
    )


def _section_levels(surface: MachiningSurface, feed, grid: int, stepover: float):
    """The feed's section function on a ``grid`` x ``grid`` (u, v) grid of the trimmed S1 and its pass levels."""
    s1 = surface.s1.surface
    u0, u1, v0, v1 = surface.s1.uv_bounds
    us, vs = np.linspace(u0, u1, grid), np.linspace(v0, v1, grid)
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = surface.s1.contains_uv(U, V)  # the trimmed face, loop holes included
    N: np.ndarray | None = None
    if isinstance(feed, PlanesFeed):
        N = np.asarray(feed.plane_normal)
        g = np.einsum("ijk,k->ij", s1.evaluate_grid(us, vs), N)
        kind = "planes"
    elif isinstance(feed, IsoFeed):
        # iso lines: v = const for a feed along u; levels spaced by the S1 arc length across them
        across = vs if feed.direction == "u" else us
        d = s1.derivatives_grid(us, vs, 1)
        speed = np.linalg.norm(d.sv if feed.direction == "u" else d.su, axis=-1).mean(
            axis=0 if feed.direction == "u" else 1
        )
        s_len = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(across))])
        g = np.broadcast_to(V if feed.direction == "u" else U, U.shape).copy()
        kind = f"iso-{feed.direction}"
    else:
        raise InputError("tool paths need a planes or iso-parametric strategy")
    g_masked = np.where(inside, g, np.nan)
    if kind == "planes":
        lo, hi = np.nanmin(g_masked), np.nanmax(g_masked)
        levels = np.arange(math.floor(lo / stepover) * stepover + stepover, hi, stepover)
    else:
        total = s_len[-1]
        n_lines = max(1, int(math.floor(total / stepover)))
        targets = (np.arange(n_lines) + 0.5) * total / n_lines
        levels = np.interp(targets, s_len, across)
    return us, vs, g_masked, levels, kind, N


def _trace_passes(surface: MachiningSurface, us, vs, g_masked, levels, kind: str, N, chordal_tolerance, zigzag):
    """The passes along the level lines of ``g_masked``: positions within the chordal tolerance; the largest errors."""
    import contourpy

    gen = contourpy.contour_generator(x=vs, y=us, z=g_masked, line_type="Separate")
    tips: list[np.ndarray] = []
    axes: list[np.ndarray] = []
    ccs: list[np.ndarray] = []
    extras: list[dict] = []
    chord_err = 0.0
    axis_err = 0.0
    for level in levels:
        for line in gen.lines(float(level)):
            if len(line) < 2:
                continue
            uv = np.stack([line[:, 1], line[:, 0]], 1)
            uv = _densify(uv, surface, float(level), kind, N if kind == "planes" else None)
            if uv.shape[0] < 2:
                continue
            p = _positions(surface, uv)
            # the chords must hold for the whole tool, not only its tip: a point one diameter up the axis
            # is sampled with the tip (a 5-axis lead that turns between positions moves the body)
            six = np.concatenate([p["tip"], p["tip"] + surface.cutter.D * p["axis"]], axis=1)
            idx = douglas_peucker(six, chordal_tolerance)
            chord_err = max(chord_err, chord_error(six, idx))
            axis_err = max(axis_err, p["axis_err"])
            if zigzag and len(tips) % 2 == 1:
                idx = idx[::-1]
            tips.append(p["tip"][idx])
            axes.append(p["axis"][idx])
            ccs.append(p["cc"][idx])
            extras.append(
                {"uv": uv[idx], "K": p["k"][idx], "CL": p["cl"][idx], "level": np.full(idx.size, float(level))}
            )
    return tips, axes, ccs, extras, chord_err, axis_err


def part_sphere(faces: Iterable[FaceLike], clearance: float = 5.0) -> tuple:
    """(centre, radius) of a sphere holding every face (their poles' bounding box: a B-spline with positive
    weights lies in its poles' convex hull) with ``clearance`` mm to spare: the sphere 5-axis passes are
    linked over (``tool_paths(..., safe_sphere=...)``)."""
    pts = part_poles(faces, "a sphere around the part")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo)) + float(clearance)


def part_cylinder(faces: Iterable[FaceLike], axis: Sequence[float] | None = None, clearance: float = 5.0) -> tuple:
    """``(point, axis, radius, half_length)`` of a cylinder around every face (their poles: a B-spline with
    positive weights lies in its poles' convex hull) with ``clearance`` mm to spare, about ``axis`` through
    the poles' bounding box centre (default: the box's longest side): the cylinder 5-axis passes are linked
    over (``tool_paths(..., safe_cylinder=...)``), tighter than a sphere around a long part.

    Examples
    --------
    >>> from machsurf_cad import builders
    >>> bar = builders.plane_patch((0, -1, 0), (100, 0, 0), (0, 2, 0))
    >>> point, axis, radius, half_length = part_cylinder([bar], clearance=5.0)
    >>> axis.tolist(), round(radius, 9), round(half_length, 9)
    ([1.0, 0.0, 0.0], 6.0, 55.0)
    """
    pts = part_poles(faces, "a cylinder around the part")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if axis is None:
        w = np.eye(3)[int(np.argmax(hi - lo))]
    else:
        w = np.asarray(axis, float)
        if w.shape != (3,) or not np.all(np.isfinite(w)) or np.linalg.norm(w) < 1e-12:
            raise InputError(f"a cylinder's axis must be a non-zero x,y,z, got {axis!r}")
        w = w / np.linalg.norm(w)
    c = 0.5 * (lo + hi)
    q = pts - c
    s = q @ w
    rho = np.linalg.norm(q - s[:, None] * w, axis=1)
    c = c + 0.5 * (s.min() + s.max()) * w
    return c, w, float(rho.max()) + float(clearance), 0.5 * float(s.max() - s.min()) + float(clearance)


def part_plane(faces: Iterable[FaceLike], axis: Sequence[float] = (0.0, 0.0, 1.0), clearance: float = 5.0) -> float:
    """Height along ``axis`` (mm, ``x . axis``) of a plane ``clearance`` mm above every face (above their
    poles: a B-spline with positive weights lies in its poles' convex hull): the plane 3-axis and 3+2
    passes are linked in (``tool_paths(..., safe_plane=...)``).

    Examples
    --------
    >>> from machsurf_cad import example
    >>> round(part_plane([example("bezier5")], clearance=5.0) - float(example("bezier5").poles[..., 2].max()), 9)
    5.0
    """
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    return float((part_poles(faces, "a plane above the part") @ a).max()) + float(clearance)


def part_poles(faces: Iterable[FaceLike], what: str = "the part") -> np.ndarray:
    """Every face's poles, ``(n, 3)`` mm: a B-spline with positive weights lies in its poles' convex hull, so
    what holds them holds the part. No face is an input error naming ``what`` needs them."""
    from ..geometry.face import Face

    poles = [np.asarray((f.surface if isinstance(f, Face) else f).poles, float).reshape(-1, 3) for f in faces]
    if not poles:
        raise InputError(f"{what} needs at least one face")
    return np.concatenate(poles)


def _densify(uv: np.ndarray, ms: MachiningSurface, level: float, kind: str, N) -> np.ndarray:
    """Put the contour's points exactly on the level (Newton on S1 . N = level) and double them."""
    mid = 0.5 * (uv[1:] + uv[:-1])
    dense = np.empty((uv.shape[0] + mid.shape[0], 2))
    dense[0::2] = uv
    dense[1::2] = mid
    if kind != "planes":
        k = 1 if kind == "iso-u" else 0
        dense[:, k] = level
        return dense
    s1 = ms.s1.surface
    u0, u1, v0, v1 = ms.s1.uv_bounds
    for _ in range(6):
        d = s1.derivatives(dense[:, 0], dense[:, 1], 1)
        r = d.point @ N - level
        gu, gv = d.su @ N, d.sv @ N
        g2 = gu * gu + gv * gv
        step = np.where(g2 > 0, r / np.where(g2 > 0, g2, 1), 0.0)
        dense[:, 0] = np.clip(dense[:, 0] - step * gu, u0, u1)
        dense[:, 1] = np.clip(dense[:, 1] - step * gv, v0, v1)
        if np.abs(r).max() < 1e-11:
            break
    d = s1.derivatives(dense[:, 0], dense[:, 1], 0)
    on_plane = np.abs(d.point @ N - level) < 1e-9 * max(1.0, abs(level))
    return dense[on_plane]  # points clipped at the domain edge could not reach the plane
