"""Iso-scallop tool paths: passes spaced on the surface so that the predicted scallop is ``h`` (mm, degrees).

The first pass runs along the face's boundary where the strategy's passes start (the iso-line
``v = v0`` for a feed along u, ``u = u0`` for a feed along v, the lowest plane section for parallel
planes). Each next pass is the previous pass's contact curve offset **on the surface** by the local
spacing ``w``: at every contact point, across the feed (``c = +-(n x f)``, ``f`` the pass's tangent),
the tool's effective radius in that section (relation (30) in the tool frame: the angle ``S``
between the axis and the normal, ``alpha`` between the steepest slope and the feed; the ball's
radius for a ball) and the surface's normal curvature across the feed give ``w`` by the
circle-circle construction (:func:`~machsurf_cad.simulation.scallop.spacing_for_scallop`). The point
is moved by ``w`` along ``c`` on the surface (in four steps, re-projected on the tangent plane), and
``w`` is re-evaluated where it lands: the smaller of the two is kept, so that both passes' geometry
respects ``h``. The offset curve is extended to the domain's edges, clipped to the trimmed face and
resampled; passes end when an offset curve leaves the face, and a last pass runs along the far edge.
"""

from __future__ import annotations

import math

import numpy as np

from ..cam.chordal import chord_error, douglas_peucker
from ..cam.toolpath import ToolPath
from ..effradius import effective_radius
from ..errors import InputError
from ..geometry.normals import unit_normals
from .strategies import IsoFeed, PlanesFeed
from .surfaces import MachiningSurface

_SUBSTEPS = 4
_N_POINTS = 400


def _frame(F, reversed_: bool, uv):
    d = F.derivatives(uv[:, 0], uv[:, 1], 2)
    n = unit_normals(d.su, d.sv, F.scale, check=False)
    return d, (-n if reversed_ else n)


def _tangents(pts):
    t = np.gradient(pts, axis=0)
    return t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)


def cross_feed(ms: MachiningSurface, uv: np.ndarray, feed3: np.ndarray):
    """Effective tool radius (mm) and normal curvature of the surface (1/mm, > 0 convex) across the feed
    ``feed3`` (unit 3-D tangents) at the nominal's points ``uv``; also the cross direction and normals."""
    from .toolpath import _positions

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


def _move_on_surface(F, reversed_, uv, c, w, bounds):
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


def _extend_to_box(uv, bounds):
    """Extend both ends along their end tangents (in uv) to the parameter box."""
    u0, u1, v0, v1 = bounds
    out = [uv]
    for end, nxt, where in ((uv[0], uv[1], 0), (uv[-1], uv[-2], 1)):
        dvec = end - nxt
        nrm = np.hypot(*dvec)
        if nrm < 1e-15:
            continue
        dvec = dvec / nrm
        ts = []
        for k, (lo, hi) in enumerate(((u0, u1), (v0, v1))):
            if abs(dvec[k]) > 1e-15:
                for b in (lo, hi):
                    t = (b - end[k]) / dvec[k]
                    if t > 0:
                        ts.append(t)
        if ts:
            t = min(ts)
            new = (end + t * dvec)[None]
            out = [new, *out] if where == 0 else [*out, new]
    return np.concatenate(out)


def _to_box(pts, run, bounds):
    """The inside stretch ``pts[run]`` closed at the box: where the offset curve leaves the box, the crossing
    (interpolated between the last point in and the first out); where it stops short, extended along its end."""
    u0, u1, v0, v1 = bounds
    piece = pts[run]
    ends = []
    for i_in, i_out in ((run[0], run[0] - 1), (run[-1], run[-1] + 1)):
        if 0 <= i_out < pts.shape[0]:
            a, b = pts[i_in], pts[i_out]
            t = 1.0
            for k, (lo, hi) in enumerate(((u0, u1), (v0, v1))):
                if b[k] < lo:
                    t = min(t, (lo - a[k]) / (b[k] - a[k]))
                elif b[k] > hi:
                    t = min(t, (hi - a[k]) / (b[k] - a[k]))
            ends.append(a + t * (b - a))
        else:
            ends.append(None)
    if ends[0] is not None:
        piece = np.concatenate([ends[0][None], piece])
    if ends[1] is not None:
        piece = np.concatenate([piece, ends[1][None]])
    if ends[0] is None or ends[1] is None:
        ext = _extend_to_box(piece, bounds)
        head = ext[:1] if ends[0] is None and ext.shape[0] > piece.shape[0] else np.empty((0, 2))
        tail = ext[-1:] if ends[1] is None and ext.shape[0] > piece.shape[0] + head.shape[0] else np.empty((0, 2))
        piece = np.concatenate([head, piece, tail])
    return piece


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
    from ..simulation.scallop import spacing_for_scallop
    from .toolpath import _positions

    feed = strategy if strategy is not None else getattr(ms.strategy, "feed", None)
    if feed is None:
        feed = IsoFeed("u")
    F = ms.nominal.surface
    rev = ms.nominal.reversed
    bounds = ms.nominal.uv_bounds
    u0, u1, v0, v1 = bounds
    s = np.linspace(0.0, 1.0, _N_POINTS)
    if isinstance(feed, IsoFeed) and feed.direction == "u":
        first, far = (
            np.stack([u0 + s * (u1 - u0), np.full_like(s, v0)], 1),
            np.stack([u0 + s * (u1 - u0), np.full_like(s, v1)], 1),
        )
        forward = lambda uv: np.tile([0.0, 1.0], (uv.shape[0], 1))  # noqa: E731
    elif isinstance(feed, IsoFeed):
        first, far = (
            np.stack([np.full_like(s, u0), v0 + s * (v1 - v0)], 1),
            np.stack([np.full_like(s, u1), v0 + s * (v1 - v0)], 1),
        )
        forward = lambda uv: np.tile([1.0, 0.0], (uv.shape[0], 1))  # noqa: E731
    elif isinstance(feed, PlanesFeed):
        first, far, forward = _plane_ends(F, feed, bounds, ms.nominal)
    else:
        raise InputError("iso-scallop paths start from a planes or iso-parametric strategy")
    passes_uv = [first]
    spacings: list[np.ndarray] = []
    cur = first
    while True:
        if len(passes_uv) > max_passes:
            raise InputError(f"scallop {scallop:g} mm needs more than {max_passes} passes on this face")
        p3 = F.evaluate(cur[:, 0], cur[:, 1])
        r_eff, kappa, c, _ = cross_feed(ms, cur, _tangents(p3))
        # c towards the unmachined side
        c = np.where((_uv_step(F, cur, c) * forward(cur)).sum(axis=1)[:, None] < 0, -c, c)
        w = spacing_for_scallop(scallop, r_eff, kappa)
        w = np.where(np.isinf(r_eff), np.nanmax(np.where(np.isfinite(w), w, np.nan), initial=0.0), w)
        if np.all(~np.isfinite(w)):
            raise InputError("no spacing leaves that scallop on this face (concave regions tighter than the tool)")
        w = np.where(np.isfinite(w), w, np.nanmin(w))
        nxt = _move_on_surface(F, rev, cur, c, w, bounds)
        # the spacing where it lands; keep the smaller and move again from the same start
        inside_box = (nxt[:, 0] >= u0) & (nxt[:, 0] <= u1) & (nxt[:, 1] >= v0) & (nxt[:, 1] <= v1)
        if inside_box.any():
            probe = np.clip(nxt, [u0, v0], [u1, v1])
            r2, k2, _, _ = cross_feed(ms, probe, _tangents(F.evaluate(nxt[:, 0], nxt[:, 1])))
            w2 = spacing_for_scallop(scallop, r2, k2)
            w2 = np.where(np.isfinite(w2), w2, w)
            if np.any(w2 < w):
                w = np.minimum(w, w2)
                nxt = _move_on_surface(F, rev, cur, c, w, bounds)
                inside_box = (nxt[:, 0] >= u0) & (nxt[:, 0] <= u1) & (nxt[:, 1] >= v0) & (nxt[:, 1] <= v1)
        spacings.append(w[inside_box] if inside_box.any() else w)
        if not inside_box.any():
            break
        # extend the inside stretch to the box and resample
        run = max(_runs(inside_box), key=len)
        piece = _to_box(nxt, run, bounds) if run.size >= 2 else nxt[run]
        piece = np.clip(piece, [u0, v0], [u1, v1])
        if piece.shape[0] < 2:
            break
        cur = _resample(piece, F, _N_POINTS)
        passes_uv.append(cur)
    passes_uv.append(far)
    # positions along each pass, inside the trimmed face, sampled within the chordal tolerance
    over = em.R if overrun is None else float(overrun)
    if not (math.isfinite(over) and over >= 0):
        raise InputError(f"overrun must be >= 0 mm, got {overrun!r}")
    tips, axes, ccs, extras = [], [], [], []
    chord_err = axis_err = 0.0
    for k, uv in enumerate(passes_uv):
        dense = _resample(uv, F, 4 * _N_POINTS)
        keep = ms.s1.contains_uv(dense[:, 0], dense[:, 1]) if ms.s1.is_trimmed else np.ones(len(dense), bool)
        for run in _runs(keep):
            if run.size < 2:
                continue
            seg = dense[run]
            p = _positions(ms, seg)
            six = np.concatenate([p["tip"], p["tip"] + ms.cutter.D * p["axis"]], axis=1)
            idx = douglas_peucker(six, chordal_tolerance)
            chord_err = max(chord_err, chord_error(six, idx))
            axis_err = max(axis_err, p["axis_err"])
            pos = {"tip": p["tip"][idx], "axis": p["axis"][idx], "cc": p["cc"][idx], "uv": seg[idx],
                   "K": p["k"][idx], "CL": p["cl"][idx]}  # fmt: skip
            if over > 0:
                pos = _overrun(pos, over)
            if zigzag and len(tips) % 2 == 1:
                pos = {key: val[::-1] for key, val in pos.items()}
            tips.append(pos["tip"])
            axes.append(pos["axis"])
            ccs.append(pos["cc"])
            extras.append(
                {"uv": pos["uv"], "K": pos["K"], "CL": pos["CL"], "level": np.full(pos["tip"].shape[0], float(k))}
            )
    if not tips:
        raise InputError("no iso-scallop pass crosses the face")
    w_all = np.concatenate(spacings)
    w_all = w_all[np.isfinite(w_all)]
    mean_gap = float(np.mean([np.mean(x[np.isfinite(x)]) for x in spacings if np.isfinite(x).any()]))
    width = mean_gap * (len(passes_uv) - 2) + (float(np.mean(spacings[-1])) if len(spacings) else 0.0)
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
    }
    return ToolPath.from_passes(
        tips, axes, cc=ccs, extras=extras, clearance=clearance, cutter=ms.cutter, name="iso_scallop", info=info
    )


def _overrun(pos: dict, length: float) -> dict:
    """One more position at each end, ``length`` mm on along the end chord (same axis; no contact point)."""
    tip = pos["tip"]
    if tip.shape[0] < 2:
        return pos
    out = {}
    d0 = tip[0] - tip[1]
    d1 = tip[-1] - tip[-2]
    d0 = d0 / max(np.linalg.norm(d0), 1e-300)
    d1 = d1 / max(np.linalg.norm(d1), 1e-300)
    for key, val in pos.items():
        if key == "tip":
            first, last = tip[0] + length * d0, tip[-1] + length * d1
        elif key == "axis":
            first, last = val[0], val[-1]
        else:
            first, last = np.full(val.shape[1], np.nan), np.full(val.shape[1], np.nan)
        out[key] = np.concatenate([first[None], val, last[None]])
    return out


def _plane_ends(F, feed: PlanesFeed, bounds, face):
    """First and last plane sections (lowest and highest level on the face) and the forward direction."""
    import contourpy

    N = np.asarray(feed.plane_normal)
    u0, u1, v0, v1 = bounds
    us, vs = np.linspace(u0, u1, 301), np.linspace(v0, v1, 301)
    g = np.einsum("ijk,k->ij", F.evaluate_grid(us, vs), N)
    lo, hi = float(g.min()), float(g.max())
    eps = 1e-6 * max(1.0, hi - lo)
    gen = contourpy.contour_generator(x=vs, y=us, z=g, line_type="Separate")

    def section(level):
        lines = [ln for ln in gen.lines(level) if len(ln) >= 2]
        if not lines:
            raise InputError("the guiding planes do not cross the face")
        ln = max(lines, key=len)
        return _resample(np.stack([ln[:, 1], ln[:, 0]], 1), F, _N_POINTS)

    def forward(uv):
        d = F.derivatives(uv[:, 0], uv[:, 1], 1)
        return np.stack([d.su @ N, d.sv @ N], 1)

    return section(lo + eps), section(hi - eps), forward
