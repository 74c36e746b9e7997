"""Iso-scallop tool paths: passes spaced on the surface so that the predicted scallop is ``h`` (mm, degrees).

The passes are fronts over the face's parameter box: ``level = f(t)`` on a fixed grid of the parameter
the passes run along (``v`` stepping in ``u`` or the reverse: the strategy's iso direction, or for
parallel planes the parameter across which their level grows most). The first pass runs along the
box's edge where the strategy starts. Each next pass is the previous pass's contact curve offset **on
the surface** by the local spacing ``w``: at every contact point, across the pass (``c = +-(n x f)``,
``f`` the pass's direction read over a few points), the tool's effective radius in that section
(relation (30) in the tool frame: the angle ``S`` between the axis and the normal, ``alpha`` between
the steepest slope and the pass; the ball's radius for a ball) and the surface's normal curvature across
the pass give ``w`` by the circle-circle construction
(:func:`~machsurf_cad.scallop.spacing_for_scallop`). The point is moved by ``w`` along ``c`` on
the surface (four steps, re-projected on the tangent plane), ``w`` is evaluated again where it lands and
the smaller of the two kept. Where the moved points fold over each other the front keeps the least
advance (no spacing exceeds its own). Passes end when the front has crossed the far edge, where a last
pass runs; positions are clipped to the trimmed face, and each pass runs on past the face's edge along
the face's smooth extrapolation (``overrun``).
"""

from __future__ import annotations

import math

import numpy as np

from ..cam.chordal import chord_error, douglas_peucker
from ..cam.toolpath import Move, ToolPath
from ..effradius import effective_radius
from ..errors import InputError
from ..geometry.normals import unit_normals
from .strategies import IsoFeed, PlanesFeed
from .surfaces import MachiningSurface

_SUBSTEPS = 4
_N_POINTS = 400
_STENCIL = 6  # points each side for the pass direction (1.5 % of the pass)


def _frame(F, reversed_: bool, uv):
    d = F.derivatives(uv[:, 0], uv[:, 1], 2)
    n = unit_normals(d.su, d.sv, F.scale, check=False)
    return d, (-n if reversed_ else n)


def _tangents(pts, half: int = 1):
    """Unit tangents of a polyline by central differences over ``half`` points each side (one-sided at the
    ends): a wider stencil reads the pass's direction, not a kink of one step."""
    n = pts.shape[0]
    i = np.arange(n)
    a, b = np.clip(i - half, 0, n - 1), np.clip(i + half, 0, n - 1)
    t = pts[b] - pts[a]
    return t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)


def cross_feed(ms: MachiningSurface, uv: np.ndarray, feed3: np.ndarray):
    """Effective tool radius (mm) and normal curvature of the surface (1/mm, > 0 convex) across the feed
    ``feed3`` (unit 3-D tangents) at the nominal's points ``uv``; also the cross direction and normals."""
    from .positions import _positions

    F = ms.nominal.surface
    d, n = _frame(F, ms.nominal.reversed, uv)
    f = feed3 - np.einsum("ij,ij->i", feed3, n)[:, None] * n
    f /= np.linalg.norm(f, axis=1, keepdims=True)
    c = np.cross(n, f)
    axis = _positions(ms, uv)["axis"]
    cosS = np.clip(np.einsum("ij,ij->i", axis, n), -1.0, 1.0)
    n_perp = n - cosS[:, None] * axis
    f_perp = f - np.einsum("ij,ij->i", f, axis)[:, None] * axis
    sinS = np.linalg.norm(n_perp, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_a = np.abs(np.einsum("ij,ij->i", n_perp, f_perp)) / (sinS * np.linalg.norm(f_perp, axis=1))
    cos_a = np.where((sinS > 1e-15) & np.isfinite(cos_a), np.clip(cos_a, 0.0, 1.0), 1.0)
    S = np.degrees(np.arctan2(sinS, cosS))
    r_eff = effective_radius(ms.cutter, S, np.degrees(np.arccos(cos_a)))
    # normal curvature along c: II(c) / I(c) with c = a su + b sv; n outward: II > 0 bends towards the tool
    E, Fm, G = (np.einsum("ij,ij->i", x, y) for x, y in ((d.su, d.su), (d.su, d.sv), (d.sv, d.sv)))
    L, M, N = (np.einsum("ij,ij->i", x, n) for x in (d.suu, d.suv, d.svv))
    ca, cb = np.einsum("ij,ij->i", c, d.su), np.einsum("ij,ij->i", c, d.sv)
    det = E * G - Fm * Fm
    du, dv = (G * ca - Fm * cb) / det, (E * cb - Fm * ca) / det
    kn = (L * du * du + 2 * M * du * dv + N * dv * dv) / (E * du * du + 2 * Fm * du * dv + G * dv * dv)
    return r_eff, -kn, c, n


def _move_on_surface(F, reversed_, uv, c, w):
    """Move each point by arc length ``w`` along the tangent direction ``c`` (re-projected each step)."""
    uv = uv.copy()
    c = c.copy()
    for _ in range(_SUBSTEPS):
        d, n = _frame(F, reversed_, uv)
        c = c - np.einsum("ij,ij->i", c, n)[:, None] * n
        c /= np.linalg.norm(c, axis=1, keepdims=True)
        step = (w / _SUBSTEPS)[:, None] * c
        E, Fm, G = (np.einsum("ij,ij->i", x, y) for x, y in ((d.su, d.su), (d.su, d.sv), (d.sv, d.sv)))
        a, b = np.einsum("ij,ij->i", step, d.su), np.einsum("ij,ij->i", step, d.sv)
        det = E * G - Fm * Fm
        uv[:, 0] += (G * a - Fm * b) / det
        uv[:, 1] += (E * b - Fm * a) / det
    return uv


def _uv_step(F, uv, vec):
    """The parameter step ``(du, dv)`` whose image on the surface is the tangent vector ``vec`` (least squares)."""
    d = F.derivatives(uv[:, 0], uv[:, 1], 1)
    E, Fm, G = (np.einsum("ij,ij->i", x, y) for x, y in ((d.su, d.su), (d.su, d.sv), (d.sv, d.sv)))
    a, b = np.einsum("ij,ij->i", vec, d.su), np.einsum("ij,ij->i", vec, d.sv)
    det = E * G - Fm * Fm
    return np.stack([(G * a - Fm * b) / det, (E * b - Fm * a) / det], 1)


def _resample(uv, F, n_points: int):
    """Points spread evenly by 3-D arc length along the polyline ``uv``."""
    p = F.evaluate(uv[:, 0], uv[:, 1])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    if s[-1] <= 0:
        return uv[:1]
    t = np.linspace(0.0, s[-1], n_points)
    return np.stack([np.interp(t, s, uv[:, 0]), np.interp(t, s, uv[:, 1])], 1)


def _offset(ms, F, rev, cur, forward, scallop, bounds):
    """The next pass from ``cur``: every point moved across the feed by the spacing that leaves ``scallop``
    (the smaller of the spacings at the start and where it lands). Returns spacing and points."""
    from ..scallop import spacing_for_scallop

    u0, u1, v0, v1 = bounds
    r_eff, kappa, c, _ = cross_feed(ms, cur, _tangents(F.evaluate(cur[:, 0], cur[:, 1]), _STENCIL))
    c = np.where((_uv_step(F, cur, c) * forward(cur)).sum(axis=1)[:, None] < 0, -c, c)  # towards uncut
    w = spacing_for_scallop(scallop, r_eff, kappa)
    good = np.isfinite(w) & (w > 0)
    if not good.any():
        raise InputError(
            "no spacing leaves that scallop on this pass (flat spots with an infinite effective radius, or concave "
            "regions tighter than the tool)"
        )
    # an infinite effective radius (a flat spot) allows any spacing: the largest of the pass; a concave region
    # tighter than the tool none: the smallest
    w = np.where(np.isinf(r_eff), w[good].max(), np.where(good, w, w[good].min()))
    nxt = _move_on_surface(F, rev, cur, c, w)

    probe = np.clip(nxt, [u0, v0], [u1, v1])
    r2, k2, _, _ = cross_feed(ms, probe, _tangents(F.evaluate(nxt[:, 0], nxt[:, 1]), _STENCIL))
    w2 = spacing_for_scallop(scallop, r2, k2)
    w2 = np.where(np.isfinite(w2) & (w2 > 0), w2, w)
    if np.any(w2 < w):
        w = np.minimum(w, w2)
        nxt = _move_on_surface(F, rev, cur, c, w)
    return w, nxt


def _front(t_pts, lvl_pts, grid, sign: float) -> np.ndarray:
    """The next front on the pass grid: the landed polyline ``(t, level)`` read as ``level = f(t)``, taking
    where it folds over itself the point that advanced least (so no spacing exceeds its own); ends held."""
    out = np.full(grid.size, np.inf if sign > 0 else -np.inf)
    a_t, b_t = t_pts[:-1], t_pts[1:]
    a_l, b_l = lvl_pts[:-1], lvl_pts[1:]
    lo, hi = np.minimum(a_t, b_t), np.maximum(a_t, b_t)
    i0 = np.searchsorted(grid, lo, side="left")
    i1 = np.searchsorted(grid, hi, side="right")
    for s_ in np.flatnonzero(i1 > i0):
        g = grid[i0[s_] : i1[s_]]
        span = b_t[s_] - a_t[s_]
        f = (g - a_t[s_]) / span if abs(span) > 0 else np.zeros_like(g)
        val = a_l[s_] + f * (b_l[s_] - a_l[s_])
        seg = out[i0[s_] : i1[s_]]
        out[i0[s_] : i1[s_]] = np.minimum(seg, val) if sign > 0 else np.maximum(seg, val)
    missing = ~np.isfinite(out)
    if missing.all():
        return np.interp(grid, np.sort(t_pts), lvl_pts[np.argsort(t_pts)])
    if missing.any():  # beyond the landed points' range: the nearest value
        ok = np.flatnonzero(~missing)
        out[missing] = np.interp(grid[missing], grid[ok], out[ok])
    return out


def _plane_start(F, feed: PlanesFeed, bounds):
    """For parallel planes: the passes step along the parameter across which the planes' level grows most
    (on average), from the edge where it is lowest. Returns ``(k, sign)``: k = 0 steps in u, 1 in v."""
    N = np.asarray(feed.plane_normal)
    u0, u1, v0, v1 = bounds
    d = F.derivatives_grid(np.linspace(u0, u1, 33), np.linspace(v0, v1, 33), 1)
    gu = float(np.mean(d.su @ N)) * (u1 - u0)
    gv = float(np.mean(d.sv @ N)) * (v1 - v0)
    if abs(gu) < 1e-12 and abs(gv) < 1e-12:
        raise InputError("the guiding planes are parallel to the face: choose another plane direction")
    return (0, 1.0 if gu > 0 else -1.0) if abs(gu) >= abs(gv) else (1, 1.0 if gv > 0 else -1.0)


def _runs(mask):
    """Index runs of consecutive True values."""
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1)
    return np.split(idx, breaks + 1)


def iso_scallop_paths(
    ms: MachiningSurface,
    *,
    scallop: float,
    chordal_tolerance: float = 0.005,
    strategy=None,
    zigzag: bool = True,
    clearance: float = 5.0,
    overrun: float | None = None,
    max_passes: int = 5000,
    safe_sphere: tuple | None = None,
    safe_plane: float | None = None,
    safe_cylinder: tuple | None = None,
) -> ToolPath:
    """Passes spaced on the surface so that the predicted scallop between neighbours is ``scallop`` mm.

    Parameters
    ----------
    ms : MachiningSurface
        Ball, flat or bull-nose; 3 or 5 axes.
    scallop : float
        Scallop height h between adjacent passes, mm.
    chordal_tolerance : float
        Max distance of the dense tool motion from the chords between written positions, mm.
    strategy : PlanesFeed or IsoFeed, optional
        Where the passes start: the default is the machining surface's feed.
    overrun : float, optional
        Each pass runs on straight beyond its ends by this much (mm; default the tool radius), so that a
        pass meeting the face's edge at an angle still cuts the edge to the scallop height. The
        path-writing commands check these moves against the whole part like any other.
    safe_sphere, safe_plane, safe_cylinder : optional
        Link the passes over a sphere (5 axes) or in a plane (fixed axis) around the whole part
        (:meth:`~machsurf_cad.cam.ToolPath.from_passes`).

    Returns
    -------
    ToolPath
        As :func:`~machsurf_cad.machining.toolpath.tool_paths`; ``info`` also holds the spacing on the
        surface (min/mean/max, mm), the number of passes and the number a constant spacing would need
        to keep the same scallop (the smallest spacing everywhere).

    Raises
    ------
    InputError
        ``scallop`` not > 0 or not smaller than the tool can leave, no pass on the face, too many passes.
    """
    if not scallop > 0 or not chordal_tolerance > 0:
        raise InputError("scallop height and chordal tolerance must be > 0 mm")
    em = ms.cutter.end_mill_radii("iso-scallop tool paths")
    if scallop >= em.R:
        raise InputError(
            f"scallop height {scallop:g} mm is not smaller than the tool radius {em.R:g} mm: no spacing leaves it"
        )
    feed = strategy if strategy is not None else getattr(ms.strategy, "feed", None)
    if feed is None:
        feed = IsoFeed("u")
    F = ms.nominal.surface
    bounds = ms.nominal.uv_bounds
    # the passes are fronts level = f(t): "level" the parameter the passes step along (index k), t the other
    if isinstance(feed, IsoFeed):
        k, sign = (1, 1.0) if feed.direction == "u" else (0, 1.0)
    elif isinstance(feed, PlanesFeed):
        k, sign = _plane_start(F, feed, bounds)
    else:
        raise InputError("iso-scallop paths start from a planes or iso-parametric strategy")
    passes_uv, spacings = _plan_fronts(ms, k, sign, scallop, max_passes)
    # positions along each pass, inside the trimmed face, sampled within the chordal tolerance
    over = em.R if overrun is None else float(overrun)
    if not (math.isfinite(over) and over >= 0):
        raise InputError(f"overrun must be >= 0 mm, got {overrun!r}")
    runs_over, chord_err, axis_err = _pass_runs(ms, passes_uv, over, chordal_tolerance, zigzag)
    dropped = _drop_gouging_overruns(ms, runs_over) if over > 0 else 0
    tips: list = []
    axes: list = []
    ccs: list = []
    extras: list = []
    for pos in runs_over:
        tips.append(pos["tip"])
        axes.append(pos["axis"])
        ccs.append(pos["cc"])
        extras.append({"uv": pos["uv"], "K": pos["K"], "CL": pos["CL"], "level": pos["level"]})
    if not tips:
        raise InputError("no iso-scallop pass crosses the face")
    w_all, width = _spacing_figures(spacings, len(passes_uv))
    info = {
        "kind": "iso-scallop",
        "scallop_mm": float(scallop),
        "n_passes_planned": len(passes_uv),
        "spacing_min_mm": float(w_all.min()),
        "spacing_mean_mm": float(w_all.mean()),
        "spacing_max_mm": float(w_all.max()),
        "n_passes_constant_spacing": int(math.ceil(width / float(w_all.min()))) + 1,
        "chordal_tolerance_mm": float(chordal_tolerance),
        "chordal_error_measured_mm": chord_err,
        "axis_error_deg_measured": axis_err if ms.axes == 5 else None,
        "n_cut_positions": int(sum(t.shape[0] for t in tips)),
        "overrun_mm": over,
        "n_overruns_shortened_for_gouging": dropped,
    }
    return ToolPath.from_passes(
        tips, axes, cc=ccs, extras=extras, clearance=clearance, cutter=ms.cutter, name="iso_scallop", info=info,
        safe_sphere=safe_sphere, safe_plane=safe_plane, safe_cylinder=safe_cylinder,
    )  # fmt: skip


def _plan_fronts(ms: MachiningSurface, k: int, sign: float, scallop: float, max_passes: int):
    """The passes in (u, v), each offset from the last by the spacing that leaves ``scallop``; the spacings."""
    F = ms.nominal.surface
    rev = ms.nominal.reversed
    bounds = ms.nominal.uv_bounds
    lo_k, hi_k = (bounds[2 * k], bounds[2 * k + 1])
    t_lo, t_hi = (bounds[2 * (1 - k)], bounds[2 * (1 - k) + 1])
    grid = np.linspace(t_lo, t_hi, _N_POINTS)
    start, end = (lo_k, hi_k) if sign > 0 else (hi_k, lo_k)

    def as_uv(level):
        uv = np.empty((grid.size, 2))
        uv[:, k], uv[:, 1 - k] = level, grid
        return uv

    fwd = np.zeros(2)
    fwd[k] = sign
    level = np.full(grid.size, start)
    passes_uv = [as_uv(level)]
    spacings: list[np.ndarray] = []
    while True:
        if len(passes_uv) > max_passes:
            raise InputError(f"scallop {scallop:g} mm needs more than {max_passes} passes on this face")
        was_in = sign * (end - level) > 0
        cur = as_uv(np.clip(level, min(lo_k, hi_k), max(lo_k, hi_k)))  # points past the far edge stay put
        w, nxt = _offset(ms, F, rev, cur, lambda uv: np.tile(fwd, (uv.shape[0], 1)), scallop, bounds)
        new = _front(nxt[:, 1 - k], nxt[:, k], grid, sign)
        # every point advances (never back)
        new = np.where(sign * (new - level) > 0, new, level + sign * 1e-9 * abs(hi_k - lo_k))
        if len(passes_uv) == 1:  # the first step tells how many passes the face needs: refuse before planning them
            step = float(np.median(np.abs(new - level)))
            need = abs(hi_k - lo_k) / max(step, 1e-300)
            if need > max_passes:
                raise InputError(
                    f"scallop {scallop:g} mm needs about {need:.3g} passes on this face (the first step is "
                    f"{float(np.median(w)):.3g} mm), more than {max_passes}: give a larger scallop height"
                )
        spacings.append(w[was_in])
        level = np.where(was_in, new, level)
        inside = sign * (end - level) > 0
        if not inside.any():
            break
        # the stretch past the far edge runs along that edge (the last pass cuts there anyway): every pass
        # ends on the parameter box, where it can run on past the face
        passes_uv.append(as_uv(np.clip(level, min(lo_k, hi_k), max(lo_k, hi_k))))
    last = as_uv(np.full(grid.size, end))
    passes_uv.append(last)
    return passes_uv, spacings


def _pass_runs(ms: MachiningSurface, passes_uv: list, over: float, chordal_tolerance: float, zigzag: bool):
    """Every pass's runs inside the face as positions (chordal tolerance, overruns); the largest errors."""
    from .positions import _positions

    F = ms.nominal.surface
    bounds = ms.nominal.uv_bounds
    runs_over: list[dict] = []
    chord_err = axis_err = 0.0
    for lvl, uv in enumerate(passes_uv):
        for fin in _runs(np.isfinite(uv).all(axis=1)):
            if fin.size < 2:
                continue
            dense = _resample(uv[fin], F, 4 * _N_POINTS)
            keep = ms.s1.contains_uv(dense[:, 0], dense[:, 1]) if ms.s1.is_trimmed else np.ones(len(dense), bool)
            for run in _runs(keep):
                if run.size < 2:
                    continue
                seg, flag = _extend_past_edges(dense[run], F, bounds, over) if over > 0 else (dense[run], None)
                p = _positions(ms, seg)
                six = np.concatenate([p["tip"], p["tip"] + ms.cutter.D * p["axis"]], axis=1)
                idx = douglas_peucker(six, chordal_tolerance)
                if flag is not None:  # where the run leaves the face stays, so an overrun can be cut off there
                    edge = np.flatnonzero(np.diff(flag.astype(int)) != 0)
                    idx = np.unique(np.concatenate([idx, edge, edge + 1]))
                chord_err = max(chord_err, chord_error(six, idx))
                axis_err = max(axis_err, p["axis_err"])
                off = flag[idx] if flag is not None else np.zeros(idx.size, bool)
                cc = np.where(off[:, None], np.nan, p["cc"][idx])  # no contact with the face beyond its edge
                pos = {"tip": p["tip"][idx], "axis": p["axis"][idx], "cc": cc, "uv": seg[idx], "K": p["k"][idx],
                       "CL": p["cl"][idx], "overrun": off, "level": np.full(idx.size, float(lvl))}  # fmt: skip
                if zigzag and len(runs_over) % 2 == 1:
                    pos = {key: val[::-1] for key, val in pos.items()}
                runs_over.append(pos)
    return runs_over, chord_err, axis_err


def _spacing_figures(spacings: list, n_planned: int):
    """The finite spacings (mm) and the width they cover, for the count a constant spacing would need."""
    w_all = np.concatenate(spacings)
    w_all = w_all[np.isfinite(w_all)]
    mean_gap = float(np.mean([np.mean(x[np.isfinite(x)]) for x in spacings if np.isfinite(x).any()]))
    width = mean_gap * (n_planned - 2) + (float(np.mean(spacings[-1])) if len(spacings) else 0.0)
    return w_all, width


def _extend_past_edges(seg, F, bounds, length: float):
    """The run ``seg`` (uv) continued beyond the parameter box by ``length`` mm where it ends on the box's
    edge, along its end direction in uv on the extrapolated surface (the tool stays on the face's smooth
    continuation). Returns the points and a flag per point: beyond the edge."""
    u0, u1, v0, v1 = bounds
    tol = 1e-9 * max(u1 - u0, v1 - v0)

    def on_edge(q):
        return min(abs(q[0] - u0), abs(q[0] - u1), abs(q[1] - v0), abs(q[1] - v1)) <= tol

    parts, flags = [seg], [np.zeros(seg.shape[0], bool)]
    for end, prev, where in ((seg[0], seg[1], 0), (seg[-1], seg[-2], 1)):
        if not on_edge(end):
            continue
        dvec = end - prev
        p0, p1 = F.evaluate(np.array([prev[0], end[0]]), np.array([prev[1], end[1]]))
        speed = np.linalg.norm(p1 - p0) / max(np.hypot(*dvec), 1e-300)  # mm per unit of uv along the end
        if not np.isfinite(speed) or speed <= 0:
            continue
        dvec = dvec / np.hypot(*dvec)
        ext = end + np.outer(np.linspace(0.0, length / speed, 17)[1:], dvec)
        if where == 0:
            parts.insert(0, ext[::-1])
            flags.insert(0, np.ones(ext.shape[0], bool))
        else:
            parts.append(ext)
            flags.append(np.ones(ext.shape[0], bool))
    return np.concatenate(parts), np.concatenate(flags)


def _drop_gouging_overruns(ms: MachiningSurface, runs: list) -> int:
    """Overruns follow the face's extrapolation; one that still cuts into the face (checked by the tool-body
    check on the exact face, motion sampled every 0.25 mm) is shortened to its placements before the first
    gouging one (at worst cut off at the face's edge). Returns how many were shortened."""
    from ..gougecheck import verify

    stretches = []  # (run, slice of the overrun with the edge position)
    for i, pos in enumerate(runs):
        off = pos["overrun"]
        for rr in _runs(off):
            lo, hi = max(rr[0] - 1, 0), min(rr[-1] + 1, off.size - 1)
            stretches.append((i, lo, hi, rr))
    if not stretches:
        return 0
    chk = ToolPath.from_passes(
        [runs[i]["tip"][lo : hi + 1] for i, lo, hi, _ in stretches],
        [runs[i]["axis"][lo : hi + 1] for i, lo, hi, _ in stretches],
        cutter=ms.cutter,
        clearance=1.0,
    )
    res = verify(ms.nominal, chk, gouge_tolerance=1e-3, step=0.25, angle_step=0.5, spacing=0.5)
    depth = np.maximum(0.0, -np.asarray(res.cut_distance))
    bad: dict[int, list] = {}
    n_bad = 0
    for k, (i, lo, _hi, rr) in enumerate(stretches):
        sel = np.flatnonzero((chk.pass_index == k) & (chk.move == Move.CUT))
        if sel.size == 0 or depth[sel].max() <= 1e-4:
            continue
        # keep the overrun from the edge up to its first gouging placement (a placement's figure covers the
        # motion into it); the edge position sits at the stretch's end nearer the face
        d = depth[sel]  # along the stretch, lo..hi
        from_edge = d if rr[0] > lo else d[::-1]
        cut_at = int(np.argmax(from_edge > 1e-4))
        n_keep = max(cut_at - 1, 0)  # overrun placements kept (the edge position is the first of from_edge)
        drop = rr[n_keep:] if rr[0] > lo else rr[: rr.size - n_keep]
        bad.setdefault(i, []).extend(drop.tolist())
        n_bad += 1
    for i, idx in bad.items():
        keep = np.ones(runs[i]["tip"].shape[0], bool)
        keep[idx] = False
        runs[i] = {key: val[keep] for key, val in runs[i].items()}
    return n_bad
