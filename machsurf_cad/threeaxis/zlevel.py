"""Waterline (constant-z) tool paths on whole parts: the closed contours where the exact drop-cutter
height crosses each level, refined on the exact faces, linked level by level (mm)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .. import checks
from ..cam.toolpath import Move, ToolPath
from ..errors import InputError
from ..glossary import renamed
from ..results import Progress
from ..typing import FacesLike, ToolLike, Vector3
from .dropcutter import machining_face_set
from .paths import MAX_DROP_POINTS, _drop

LEVEL_MARGIN_MM = 1e-9
"""Each level's contour is traced where the exact height crosses the level plus this (mm): a horizontal
floor exactly at a level (a level 4 mm under a top at 29 mm meets a floor at 25 mm) is where the tool may
stand, and its heights, equal to the level up to rounding, no longer make contours of their rounding noise
(on the mould insert they made 16 passes at 25 mm and 5 at 15 mm, different ones after any change of the
order of operations)."""


def _crossing(fs, cutter, a, b, fa, fb, level, iters: int = 40, tol: float = 1e-10, bracket_mm: float = 1e-6):
    """Points between ``a`` and ``b`` (rows, tool-frame plan) where the drop-cutter height equals
    ``level`` (per row; Illinois regula falsi on the exact heights; ``fa``, ``fb`` the heights minus
    ``level`` at the ends, of opposite signs; a bracket narrower than ``bracket_mm`` in plan is a jump
    and stops). Returns, per row, the bracket's end at or below the level
    (where a wall's edge makes the heights jump, the foot of the jump) and its contact."""
    a, b = a.copy(), b.copy()
    fa, fb = fa.copy(), fb.copy()
    side = np.zeros(a.shape[0])
    ca = np.full((a.shape[0], 3), np.nan)
    cb = np.full((a.shape[0], 3), np.nan)
    level = np.broadcast_to(np.asarray(level, float), fa.shape)
    live = np.ones(fa.shape, bool)
    x_last, c_last = a.copy(), ca.copy()
    f_last = np.full(fa.shape, np.inf)
    for _ in range(iters):
        i = np.nonzero(live)[0]
        if i.size == 0:
            break
        with np.errstate(invalid="ignore", divide="ignore"):
            w = fa[i] / (fa[i] - fb[i])
        w = np.clip(np.where(np.isfinite(w), w, 0.5), 0.0, 1.0)
        x = a[i] + w[:, None] * (b[i] - a[i])
        r = _drop(fs, cutter, x)
        fx = r.height - level[i]
        fx = np.where(np.isfinite(fx), fx, -1.0)  # no face under the tool: below the level
        left = np.sign(fx) == np.sign(fa[i])
        # Illinois: halve the kept end's value when the same end is kept twice
        fb[i] = np.where(left & (side[i] == 1), 0.5 * fb[i], fb[i])
        fa[i] = np.where(~left & (side[i] == -1), 0.5 * fa[i], fa[i])
        a[i] = np.where(left[:, None], x, a[i])
        ca[i] = np.where(left[:, None], r.contact, ca[i])
        fa[i] = np.where(left, fx, fa[i])
        b[i] = np.where(left[:, None], b[i], x)
        cb[i] = np.where(left[:, None], cb[i], r.contact)
        fb[i] = np.where(left, fb[i], fx)
        side[i] = np.where(left, 1, -1)
        x_last[i], c_last[i], f_last[i] = x, r.contact, fx
        live[i] = (np.abs(fx) > tol) & (np.linalg.norm(b[i] - a[i], axis=1) > bracket_mm)
    # converged: the last iterate; else (a jump at a wall's edge) the end of the bracket below the
    # level, where the tool touches nothing above it
    a_safe = fa <= fb
    done = np.abs(f_last) <= tol
    x_out = np.where(done[:, None], x_last, np.where(a_safe[:, None], a, b))
    return x_out, np.where(done[:, None], c_last, np.where(a_safe[:, None], ca, cb))


@renamed(
    cutter="tool",
    stepdown_mm="stepdown",
    chordal_tolerance_mm="chordal_tolerance",
    clearance_mm="clearance",
    grid_mm="grid_step",
    z_min_mm="z_min",
    seed_spacing_mm="seed_spacing",
    verify_tolerance_mm="gouge_tolerance",
)
def waterline(
    faces: FacesLike,
    tool: ToolLike,
    *,
    check_faces: FacesLike = (),
    stepdown: float,
    chordal_tolerance: float = 0.01,
    clearance: float = 5.0,
    axis: Vector3 = (0.0, 0.0, 1.0),
    extent: Sequence[float] | None = None,
    grid_step: float | None = None,
    z_min: float | None = None,
    seed_spacing: float | None = None,
    gouge_tolerance: float | None = None,
    progress: Progress | None = None,
) -> ToolPath:
    """Waterline (constant-z) tool path: at each level, the closed contours where the exact drop-cutter
    height equals the level (found on a plan grid of exact heights with contourpy, each vertex then
    moved onto the exact crossing by regula falsi); moves whose quarter points rise above the level by
    more than ``chordal_tolerance`` get the exact crossing next to their middle inserted.

    Parameters
    ----------
    stepdown : float
        Distance between levels, from the part's top down to ``z_min`` (default: the lowest tool
        height over the machined faces).
    grid_step : float, optional
        Plan grid of exact heights the contours are found on (default ``min(1, D/10)``). A feature
        narrower than the grid may leave moves above their level after refinement: they are dropped
        (the contour is cut open, the tool retracts and plunges again) and counted in ``info``
        (``n_moves_dropped_above_level``, ``length_dropped_above_level_mm``).
    gouge_tolerance : float, optional
        Check the tool body against the faces and drop cutting moves that gouge deeper than this
        (counted in ``info``); the caller still checks the path it writes.

    Other parameters as :func:`raster`.
    """
    import contourpy

    tool = checks.tool(tool)
    for name, val in (
        ("chordal tolerance", chordal_tolerance),
        ("clearance", clearance),
        ("step-down", stepdown),
    ):
        checks.positive(name, val)
    fs, (x0, x1, y0, y1) = machining_face_set(faces, check_faces, tool, axis=axis,
                                               seed_spacing=seed_spacing, what="a waterline path")  # fmt: skip
    R = float(tool.profile_points(16)[:, 0].max())
    if extent is None:
        extent = (x0 - R, x1 + R, y0 - R, y1 + R)
    g = checks.positive("grid", grid_step) if grid_step is not None else min(1.0, tool.D / 10)
    n_grid = ((extent[1] - extent[0]) / g + 1) * ((extent[3] - extent[2]) / g + 1)
    if n_grid > MAX_DROP_POINTS:
        raise InputError(
            f"this waterline needs about {n_grid:.3g} drop-cutter points (grid {g:g} mm over "
            f"{extent[1] - extent[0]:.4g} x {extent[3] - extent[2]:.4g} mm), more than {MAX_DROP_POINTS:,}: "
            "give a larger grid"
        )
    xs = np.linspace(extent[0], extent[1], max(3, math.ceil((extent[1] - extent[0]) / g) + 1))
    ys = np.linspace(extent[2], extent[3], max(3, math.ceil((extent[3] - extent[2]) / g) + 1))
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    res = _drop(fs, tool, np.column_stack([X.ravel(), Y.ravel()]), progress)
    Z = res.height.reshape(X.shape)
    fin = np.isfinite(Z)
    if not fin.any():
        raise InputError("no face lies under the tool anywhere in the waterline's extent")
    z_low = float(np.nanmin(Z)) - 1.0
    Zf = np.where(fin, Z, z_low)
    z_top = float(fs.pool_xyz[:, 2].max())
    z_bottom = float(np.nanmin(Z[fin])) if z_min is None else float(z_min)
    levels = np.arange(float(np.nanmax(Z)) - stepdown, z_bottom - 1e-9, -stepdown)
    if levels.size == 0:
        raise InputError(f"step-down {stepdown:g} mm leaves no level between the top and {z_bottom:g} mm")
    gen = contourpy.contour_generator(xs, ys, Zf, line_type=contourpy.LineType.Separate)
    lines, lv = [], []
    for level in levels:
        for line in gen.lines(level + LEVEL_MARGIN_MM):
            line = np.asarray(line, float)
            if line.ndim == 2 and line.shape[0] >= 3:
                lines.append(line)
                lv.append(float(level))
    if not lines:
        raise InputError("no waterline contour: the part is flat under every level")
    pts, ccs, rise, lv = _refine_contours(fs, tool, xs, ys, Zf, lines, np.array(lv) + LEVEL_MARGIN_MM,
                                          chordal_tolerance, g)  # fmt: skip
    lv = levels[np.abs(levels[:, None] - np.asarray(lv)[None, :]).argmin(axis=0)]  # the levels themselves
    # moves still above their level (a feature narrower than the grid the contours were found on) are
    # dropped: the contour is cut open there, the tool retracts and plunges again (material left there)
    pts, ccs, lv, n_drop, l_drop = _split_at(pts, ccs, lv, [r > chordal_tolerance for r in rise])
    above = max([0.0] + [float(r[r <= chordal_tolerance].max(initial=0.0)) for r in rise])
    info = {"pattern": "waterline", "stepdown_mm": float(stepdown), "grid_mm": g, "n_levels": int(levels.size),
            "extent_mm": [float(e) for e in extent], "n_moves_dropped_above_level": n_drop,
            "length_dropped_above_level_mm": l_drop}  # fmt: skip
    if not pts:
        raise InputError("no waterline contour stays at its level: refine --grid")
    z_safe = z_top + clearance
    tp = _link_levels(fs, tool, list(zip(pts, lv, ccs)), z_safe, chordal_tolerance, above, info=info)
    if gouge_tolerance is not None:
        tp = _drop_gouging_moves(tp, fs, tool, list(faces) + list(check_faces), pts, ccs, lv, z_safe,
                                 chordal_tolerance, above, info, gouge_tolerance)  # fmt: skip
    return tp


def _drop_gouging_moves(tp, fs, cutter, faces, pts, ccs, lv, z_safe, tol, above, info, verify_tol, rounds=4):
    """Waterline moves the tool body check finds gouging (deeper than ``verify_tol``: between two exact
    crossings the part rises above the level, or the shank or holder meets it) are dropped and their
    contours cut open there, until the check is clean. ``info`` counts them."""
    from ..gougecheck import GOUGE, verify

    n_total, l_total = 0, 0.0
    for _ in range(rounds):
        v = verify(faces, tp, cutter, gouge_tolerance=verify_tol)
        k = np.nonzero((v.status == GOUGE) & (tp.move == Move.CUT))[0]
        if k.size == 0:
            break
        first = np.searchsorted(tp.pass_index, np.arange(len(pts)))  # each pass's rapid
        drop = [np.zeros(p.shape[0] - 1, bool) for p in pts]
        for kk in k:
            j = int(tp.pass_index[kk])
            drop[j][kk - first[j] - 2] = True  # rapid, approach (contour position 0), then the moves
        pts, ccs, lv, n, length = _split_at(pts, ccs, lv, drop)
        n_total, l_total = n_total + n, l_total + length
        tp = _link_levels(fs, cutter, list(zip(pts, lv, ccs)), z_safe, tol, above, info=info)
    return ToolPath(tp.tip, tp.axis, tp.move, tp.pass_index, tp.cc, None, tp.cutter, tp.name, {},
                    dict(tp.info, n_moves_dropped_after_body_check=n_total,
                         length_dropped_after_body_check_mm=l_total))  # fmt: skip


def _grid_values(xs, ys, Zf, pts, levels):
    """The grid edge each contour vertex lies on (a horizontal or a vertical one, whichever straddles
    the vertex's level): its two end nodes and their heights. Vertices on no straddling edge get the
    nearest horizontal edge (their bracket is checked by the caller)."""
    dx, dy = xs[1] - xs[0], ys[1] - ys[0]
    fx = np.clip((pts[:, 0] - xs[0]) / dx, 0, xs.size - 1)
    fy = np.clip((pts[:, 1] - ys[0]) / dy, 0, ys.size - 1)
    ix0 = np.clip(np.floor(fx).astype(int), 0, xs.size - 2)
    iy0 = np.clip(np.floor(fy).astype(int), 0, ys.size - 2)
    ixr = np.clip(np.round(fx).astype(int), 0, xs.size - 1)
    iyr = np.clip(np.round(fy).astype(int), 0, ys.size - 1)
    # horizontal edge (iyr; ix0 .. ix0 + 1) and vertical edge (ixr; iy0 .. iy0 + 1)
    h_a, h_b = Zf[iyr, ix0], Zf[iyr, ix0 + 1]
    v_a, v_b = Zf[iy0, ixr], Zf[iy0 + 1, ixr]
    h_ok = (h_a - levels) * (h_b - levels) <= 0
    v_ok = (v_a - levels) * (v_b - levels) <= 0
    use_h = h_ok & (~v_ok | (np.abs(fy - iyr) <= np.abs(fx - ixr)))
    a = np.where(use_h[:, None], np.column_stack([xs[ix0], ys[iyr]]), np.column_stack([xs[ixr], ys[iy0]]))
    b = np.where(use_h[:, None], np.column_stack([xs[ix0 + 1], ys[iyr]]), np.column_stack([xs[ixr], ys[iy0 + 1]]))
    return a, b, np.where(use_h, h_a, v_a), np.where(use_h, h_b, v_b), h_ok | v_ok


def _refine_contours(fs, cutter, xs, ys, Zf, lines, levels, tol, g, rounds: int = 6):
    """All contours' vertices on their exact crossings (one batched solve), then, round by round, the
    middles of moves whose quarter points rise above their level by more than ``tol`` replaced by exact
    crossings across the move. Returns per contour the points and contacts, and per move the measured
    bound on how deep the tool at the level cuts in between positions (mm; see ``measure``)."""
    sizes = [ln.shape[0] for ln in lines]
    allv = np.concatenate(lines)
    lev = np.repeat(levels, sizes)
    a, b, za, zb, straddles = _grid_values(xs, ys, Zf, allv, lev)
    x, c = _crossing(fs, cutter, a, b, za - lev, zb - lev, lev)
    x = np.where(straddles[:, None], x, np.nan)  # a vertex with no bracket is dropped
    cut = np.cumsum(sizes)[:-1]
    pts, ccs = np.split(x, cut), np.split(c, cut)
    keep = [np.isfinite(p[:, 0]) for p in pts]
    pts = [p[k] for p, k in zip(pts, keep)]
    ccs = [cc[k] for cc, k in zip(ccs, keep)]
    good = [p.shape[0] >= 2 for p in pts]
    pts = [p for p, g_ in zip(pts, good) if g_]
    ccs = [cc for cc, g_ in zip(ccs, good) if g_]
    levels = levels[np.array(good)]
    lines = [ln for ln, g_ in zip(lines, good) if g_]
    closed = [bool(np.allclose(ln[0], ln[-1])) for ln in lines]
    fr = np.array([0.25, 0.5, 0.75])

    def measure():
        """Per quarter point: the exact height's rise above the level, and a bound on how deep the
        tool at the level cuts in there: the rise, or, beside a wall (the height jumps within a plan
        distance ``tol / 2`` of the point), ``tol / 2`` plus the rise at the wall's foot."""
        q = np.concatenate(
            [(p[:-1, None, :] * (1 - fr)[:, None] + p[1:, None, :] * fr[:, None]).reshape(-1, 2) for p in pts]
        )
        qlev = np.concatenate([np.full(3 * (p.shape[0] - 1), lv) for p, lv in zip(pts, levels)])
        h = _drop(fs, cutter, q).height - qlev
        h = np.where(np.isfinite(h), h, -np.inf)
        bound = np.maximum(h, 0.0)
        hi = np.nonzero(h > tol)[0]
        if hi.size:  # a translation by delta clears the tool: it cuts in by at most delta (plus the rise)
            t = np.concatenate([np.repeat(np.diff(p, axis=0), 3, axis=0) for p in pts])[hi]
            n = np.column_stack([t[:, 1], -t[:, 0]]) / np.maximum(np.linalg.norm(t, axis=1), 1e-300)[:, None]
            d = 0.5 * tol
            side = _drop(fs, cutter, np.vstack([q[hi] + d * n, q[hi] - d * n])).height - np.tile(qlev[hi], 2)
            side = np.where(np.isfinite(side), side, -np.inf).reshape(2, -1).min(axis=0)
            bound[hi] = np.minimum(h[hi], d + np.maximum(side, 0.0))
        return h.reshape(-1, 3), bound.reshape(-1, 3)

    for k, cl in enumerate(closed):
        if cl and not np.allclose(pts[k][0], pts[k][-1]):
            pts[k] = np.vstack([pts[k], pts[k][:1]])
            ccs[k] = np.vstack([ccs[k], ccs[k][:1]])
    for _ in range(rounds):
        h, bound = measure()
        bad = np.nonzero(bound.max(axis=1) > tol)[0]
        if bad.size == 0:
            break
        starts = np.concatenate([[0], np.cumsum([p.shape[0] - 1 for p in pts])])
        owner = np.searchsorted(starts, bad, side="right") - 1
        local = bad - starts[owner]
        P0 = np.array([pts[o][i] for o, i in zip(owner, local)])
        P1 = np.array([pts[o][i + 1] for o, i in zip(owner, local)])
        lvb = levels[owner]
        mid = 0.5 * (P0 + P1)
        t = P1 - P0
        n = np.column_stack([t[:, 1], -t[:, 0]]) / np.maximum(np.linalg.norm(t, axis=1), 1e-300)[:, None]
        hm = h[bad, 1]
        # the level's crossing across the move: the nearest of 2 x 4 points at plan distances g / 64 .. g
        # on either side that is below the level (a dip narrower than the grid has one only close by)
        dist = g * np.array([1 / 64, 1 / 16, 1 / 4, 1.0, -1 / 64, -1 / 16, -1 / 4, -1.0])
        trial = mid[None] + dist[:, None, None] * n[None]
        ht = (_drop(fs, cutter, trial.reshape(-1, 2)).height.reshape(dist.size, -1) - lvb).T
        ht = np.where(np.isfinite(ht), ht, -1.0)
        below = ht < 0
        order = np.argsort(np.abs(dist), kind="stable")
        pick = order[np.argmax(below[:, order], axis=1)]
        rows = np.arange(bad.size)
        out_pt = trial[pick, rows]
        ho = ht[rows, pick]
        ok = (ho < 0) & np.isfinite(hm) & (hm > 0)
        if not ok.any():
            break
        xk, ck = _crossing(fs, cutter, mid[ok], out_pt[ok], hm[ok], ho[ok], lvb[ok])
        for o in np.unique(owner[ok]):
            sel = owner[ok] == o
            at = local[ok][sel] + 1
            pts[o] = np.insert(pts[o], at, xk[sel], axis=0)
            ccs[o] = np.insert(ccs[o], at, ck[sel], axis=0)
    rise = measure()[1].max(axis=1)
    starts = np.concatenate([[0], np.cumsum([p.shape[0] - 1 for p in pts])])
    return pts, ccs, [rise[starts[k] : starts[k + 1]] for k in range(len(pts))], levels


def _split_at(pts, ccs, levels, drop):
    """Contours cut open at the moves flagged in ``drop`` (one boolean array per contour, per move):
    pieces of two positions or more, with their levels; the number and plan length of dropped moves."""
    out_p, out_c, out_l, n, length = [], [], [], 0, 0.0
    for p, c, lv, d in zip(pts, ccs, levels, drop):
        if not d.any():
            out_p.append(p)
            out_c.append(c)
            out_l.append(lv)
            continue
        n += int(d.sum())
        length += float(np.linalg.norm(np.diff(p, axis=0)[d], axis=1).sum())
        closed = bool(np.allclose(p[0], p[-1])) and p.shape[0] > 2
        if closed:  # the loop restarted after its first dropped move: no piece ends at the seam
            k = int(np.argmax(d)) + 1
            p = np.vstack([p[k:-1], p[: k + 1]])
            c = np.vstack([c[k:-1], c[: k + 1]])
            d = np.concatenate([d[k:], d[:k]])
        cut = np.flatnonzero(d) + 1  # a dropped move i runs from position i to i + 1
        for pp, cc in zip(np.split(p, cut), np.split(c, cut)):
            if pp.shape[0] >= 2:
                out_p.append(pp)
                out_c.append(cc)
                out_l.append(lv)
    return out_p, out_c, np.array(out_l, float), n, length


def _link_levels(fs, cutter, passes, z_safe, tol, above, info) -> ToolPath:
    """Each contour: rapid above its start at ``z_safe``, plunge, cut around it, retract."""
    frame = fs.frame
    T, M, P, C = [], [], [], []
    for k, (pts, level, cc) in enumerate(passes):
        n = pts.shape[0]
        T += [np.column_stack([pts[:1], [z_safe]]), np.column_stack([pts, np.full(n, level)]),
              np.column_stack([pts[-1:], [z_safe]])]  # fmt: skip
        M += [[Move.RAPID], [Move.APPROACH] + [Move.CUT] * (n - 1), [Move.RETRACT]]
        P += [np.full(n + 2, k)]
        C += [np.full((1, 3), np.nan), cc, np.full((1, 3), np.nan)]
    tip = np.concatenate(T) @ frame
    info = dict(info, chordal_tolerance_mm=tol, chordal_error_measured_mm=float(above),
                chord_below_drop_height_mm=float(above), clearance_height_mm=z_safe, n_passes=len(passes))  # fmt: skip
    return ToolPath(
        tip,
        np.repeat(frame[2][None, :], tip.shape[0], axis=0),
        np.concatenate([np.asarray(m, np.int8) for m in M]),
        np.concatenate(P),
        np.concatenate(C),
        None,
        cutter,
        "waterline",
        {},
        info,
    )
