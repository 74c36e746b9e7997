"""3-axis tool paths on whole parts from the exact drop-cutter: raster (zig-zag or one-way, any angle)
and waterline (constant-z contours), linked with plunges, retracts and rapids at a clearance height,
staying down between adjacent raster lines where the tool can follow the part.

Every position is an exact drop-cutter height on every face given (machined and checked faces); the
chordal error between positions is measured on the exact drop-cutter at points the path never used.
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np

from .. import checks
from ..cam.chordal import douglas_peucker
from ..cam.toolpath import Move, ToolPath
from ..errors import InputError
from ..results import Progress
from .dropcutter import DropCutterResult, drop_cutter, machining_face_set
from .faceset import FaceSet
from .scallop import plan_lines


class Pattern(Enum):
    """3-axis path patterns."""

    RASTER = "raster"
    """Parallel lines at an angle, the tool on the part along each."""
    WATERLINE = "waterline"
    """Constant-height contours of the tool's lowest positions."""


class Direction(Enum):
    """How raster lines follow each other."""

    ZIGZAG = "zigzag"
    """Every other line reversed; adjacent lines linked on the part where possible."""
    ONE_WAY = "one-way"
    """Every line in the same direction; a retract and a rapid between lines."""


def scallop_stepover(cutter, scallop: float) -> float:
    """Step-over (mm) leaving a cusp of ``scallop`` mm between two passes of the cutter's smallest
    corner arc on a flat floor, ``2 sqrt(2 r H - H^2)`` (ball: ``r = D/2``). The flat bottom of a
    bull-nose adds ``2 R_t``; a flat end mill has no arc and is refused (its scallop on slopes depends on
    the slope, not on a radius)."""
    if not scallop > 0:
        raise InputError(f"scallop must be > 0 mm, got {scallop}")
    r = float(cutter.corner_radius)
    if r <= 0:
        raise InputError(f"a scallop height needs a cutter with a corner radius, not {cutter.spec()}: give --stepover")
    h = min(scallop, r)
    return 2 * math.sqrt(2 * r * h - h * h) + 2 * float(cutter.torus_radius if r < cutter.radius else 0.0)


def _lines(extent, angle_deg: float, stepover: float):
    """Raster lines over the plan box ``extent = (x0, x1, y0, y1)`` at ``angle_deg``: unit direction,
    normal and per-line offsets; the s-range covering the box."""
    a = math.radians(angle_deg)
    d = np.array([math.cos(a), math.sin(a)])
    n = np.array([-math.sin(a), math.cos(a)])
    x0, x1, y0, y1 = extent
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    s, t = corners @ d, corners @ n
    k = max(1, math.ceil((t.max() - t.min()) / stepover - 1e-9))
    offsets = np.linspace(t.min(), t.max(), k + 1)
    return d, n, offsets, (float(s.min()), float(s.max()))


def _drop(fs, cutter, xy, progress=None) -> DropCutterResult:
    return drop_cutter(None, cutter, xy, face_set_=fs, progress=progress)


MAX_DROP_POINTS = 20_000_000
"""Most drop-cutter points a raster or waterline plans before it refuses (about 1 ms a point: hours)."""


def raster(
    faces,
    cutter,
    *,
    check_faces=(),
    stepover_mm: float | None = None,
    scallop_mm: float | None = None,
    angle_deg: float = 0.0,
    direction: Direction | str = Direction.ZIGZAG,
    chordal_tolerance_mm: float = 0.01,
    clearance_mm: float = 5.0,
    axis=(0.0, 0.0, 1.0),
    extent=None,
    sample_step_mm: float | None = None,
    seed_spacing_mm: float | None = None,
    verify_tolerance_mm: float | None = None,
    progress: Progress | None = None,
) -> ToolPath:
    """Raster tool path over ``faces``, avoiding ``faces`` and ``check_faces``.

    Parameters
    ----------
    faces : sequence of Face
        Faces to machine: the raster covers their plan extent (tool frame).
    cutter : Cutter
        Any profile cutter.
    check_faces : sequence of Face
        Further faces the tool must not cut into (not machined: they only lift the tool).
    stepover_mm, scallop_mm : float
        Distance between lines, or the largest scallop (cusp height above the part along its normal) the
        path may leave: then each line is placed as far from the last as the cusp between the two allows
        (:func:`~machsurf_cad.threeaxis.scallop.plan_lines`; the flat-floor step-over of
        :func:`scallop_stepover` is the first guess) and ``info`` holds the planned largest scallop.
    angle_deg : float
        Line direction in the tool frame's plane (0: along x).
    direction : Direction
        ``zigzag`` or ``one-way``.
    chordal_tolerance_mm : float
        Largest height of the exact drop-cutter above the straight move between two positions,
        measured at every move's middle (never used as a position).
    clearance_mm : float
        Rapids run this far above the highest point of the part (along the axis).
    axis : 3-vector
        Fixed tool axis (3+2).
    extent : (x0, x1, y0, y1), optional
        Plan box in the tool frame (default: the machined faces' extent).
    sample_step_mm : float, optional
        Dense sampling along lines before chordal reduction (default ``min(0.25, D/20)``).
    verify_tolerance_mm : float, optional
        Check the tool body against the faces and split cutting moves that gouge deeper than this
        (:func:`refine_gouging_moves`); the caller still checks the path it writes.

    Returns
    -------
    ToolPath
        ``info`` holds the step-over, the chordal error measured, the numbers of lines and links.
    """
    cutter = checks.tool(cutter)
    for name, val in (("chordal tolerance", chordal_tolerance_mm), ("clearance", clearance_mm)):
        checks.positive(name, val)
    if (stepover_mm is None) == (scallop_mm is None):
        raise InputError("give a step-over or a scallop height (one of them)")
    if scallop_mm is not None:
        step = scallop_stepover(cutter, checks.positive("scallop height", scallop_mm))
    else:
        step = checks.positive("step-over", stepover_mm)
    direction = Direction(direction)
    machined = list(faces)
    fs, box = machining_face_set(machined, check_faces, cutter, axis=axis, seed_spacing_mm=seed_spacing_mm,
                                 what="a raster path")  # fmt: skip
    extent = box if extent is None else extent
    d, nrm, offsets, (s0, s1) = _lines(extent, angle_deg, step)
    ds = float(sample_step_mm) if sample_step_mm is not None else min(0.25, cutter.D / 20)
    if not ds > 0:
        raise InputError(f"sample step must be > 0 mm, got {ds}")
    n_lines = (s1 - s0) / ds * (abs(offsets[-1] - offsets[0]) / step + 1)
    if n_lines > MAX_DROP_POINTS:
        raise InputError(
            f"this raster needs about {n_lines:.3g} drop-cutter points (step-over {step:g} mm, sample step {ds:g} mm "
            f"over {s1 - s0:.4g} x {abs(offsets[-1] - offsets[0]):.4g} mm), more than {MAX_DROP_POINTS:,}: "
            "give a larger step-over (or scallop height) or machine fewer faces"
        )
    s = np.linspace(s0, s1, max(2, math.ceil((s1 - s0) / ds) + 1))
    plan_info: dict = {}
    if scallop_mm is not None:  # each line as far from the last as the cusp between them allows
        offsets, H, CC, plan_info = plan_lines(fs, cutter, scallop_mm, d, nrm, (offsets[0], offsets[-1]), s, _drop,
                                               step, progress)  # fmt: skip
        step = float(np.diff(offsets).max())
    else:
        S, T = np.meshgrid(s, offsets, indexing="ij")
        pts = S.T.reshape(-1, 1) * d + T.T.reshape(-1, 1) * nrm
        res = _drop(fs, cutter, pts, progress)
        H = res.height.reshape(len(offsets), len(s))
        CC = res.contact.reshape(len(offsets), len(s), 3)
    z_top = float(max(fs.sample_xyz[:, 2].max(), fs.edge_xyz[:, 2].max()))
    passes = []  # per pass: (s values, heights, contacts, line index)
    for i in range(len(offsets)):
        ok = np.isfinite(H[i])
        runs = _runs(ok)
        for a, b in runs:
            if b - a < 1:
                continue
            passes.append([s[a : b + 1], H[i, a : b + 1], CC[i, a : b + 1], i])
    if not passes:
        raise InputError("no face lies under the tool anywhere in the raster's extent")
    passes = _reduce_chordal(fs, cutter, passes, d, nrm, offsets, chordal_tolerance_mm)
    if direction is Direction.ZIGZAG:
        for p in passes:
            if p[3] % 2 == 1:
                p[0], p[1], p[2] = p[0][::-1], p[1][::-1], p[2][::-1]
    tp = _link(fs, cutter, passes, d, nrm, offsets, step, z_top + clearance_mm, chordal_tolerance_mm, direction,
               info={"pattern": "raster", "direction": direction.value, "angle_deg": float(angle_deg),
                     "stepover_mm": step, "scallop_target_mm": scallop_mm, "n_lines": int(len(offsets)),
                     "sample_step_mm": ds, "extent_mm": [float(e) for e in extent], **plan_info})  # fmt: skip
    if verify_tolerance_mm is not None:
        tp = refine_gouging_moves(tp, machined + list(check_faces), cutter, fs, tolerance_mm=verify_tolerance_mm)
    return tp


def _insert(tp: ToolPath, k, tips, ccs) -> ToolPath:
    """``tips[i]`` (m, 3) inserted as cutting positions before position ``k[i]``."""
    m = tips.shape[1]
    at = np.repeat(k, m)
    return ToolPath(
        np.insert(tp.tip, at, tips.reshape(-1, 3), axis=0),
        np.insert(tp.axis, at, np.repeat(tp.axis[k], m, axis=0), axis=0),
        np.insert(tp.move, at, Move.CUT),
        np.insert(tp.pass_index, at, np.repeat(tp.pass_index[k], m)),
        None if tp.cc is None else np.insert(tp.cc, at, ccs.reshape(-1, 3), axis=0),
        None,
        tp.cutter,
        tp.name,
        {},
        dict(tp.info),
    )


def refine_gouging_moves(tp: ToolPath, faces, cutter, fs: FaceSet, *, tolerance_mm: float, rounds: int = 6,
                         n_sub: int = 8, jump_mm: float = 2e-3) -> ToolPath:  # fmt: skip
    """Cutting moves the tool body check finds gouging (deeper than ``tolerance_mm``) are split into
    ``n_sub`` moves at exact drop-cutter heights, and the path is checked again, up to ``rounds`` times.
    The chordal check samples each move at three points; a narrow rise of the heights between them (a
    thin blade's edge) is only seen by the body check. ``info`` gets ``n_moves_split``."""
    from ..gougecheck import GOUGE, verify

    split_total = 0
    for _ in range(rounds):
        v = verify(faces, tp, cutter, tolerance=tolerance_mm)
        k = np.nonzero((v.status == GOUGE) & (tp.move == Move.CUT))[0]  # gouge at the move ending at k
        k = k[k > 0]  # a cutting move (a line's or a link's on the part) from the position before
        if k.size == 0:
            break
        fa_, fb_ = fs.to_frame(tp.tip[k - 1]), fs.to_frame(tp.tip[k])
        short = np.linalg.norm(fb_[:, :2] - fa_[:, :2], axis=1) < jump_mm
        if short.any():  # across a jump of the heights (a wall's edge): up (or down) plus a level move
            ks = k[short]
            corner = np.where((fa_[short, 2] < fb_[short, 2])[:, None],
                              np.column_stack([fa_[short, :2], fb_[short, 2]]),
                              np.column_stack([fb_[short, :2], fa_[short, 2]]))  # fmt: skip
            tp = _insert(tp, ks, fs.to_world(corner)[:, None, :], np.full((ks.size, 1, 3), np.nan))
            split_total += int(ks.size)
            continue
        a = fa_[:, :2]
        b = fb_[:, :2]
        w = (np.arange(1, n_sub) / n_sub)[None, :, None]
        q = (a[:, None, :] * (1 - w) + b[:, None, :] * w).reshape(-1, 2)
        r = drop_cutter(None, cutter, q, face_set_=fs)
        z = r.height.reshape(k.size, n_sub - 1)
        za = fs.to_frame(tp.tip[k - 1])[:, 2]
        zb = fs.to_frame(tp.tip[k])[:, 2]
        # where no face is under the tool, stay on the chord
        z = np.where(np.isfinite(z), z, za[:, None] * (1 - w[..., 0]) + zb[:, None] * w[..., 0])
        new_tip = fs.to_world(np.concatenate([q, z.reshape(-1, 1)], axis=1)).reshape(k.size, n_sub - 1, 3)
        tp = _insert(tp, k, new_tip, r.contact.reshape(k.size, n_sub - 1, 3))
        split_total += int(k.size)
    return ToolPath(tp.tip, tp.axis, tp.move, tp.pass_index, tp.cc, None, tp.cutter, tp.name, {},
                    dict(tp.info, n_moves_split_after_body_check=split_total))  # fmt: skip


def _runs(ok: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [a, b] of consecutive True values."""
    idx = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    return [(int(a), int(b) - 1) for a, b in zip(idx[::2], idx[1::2])]


def _reduce_chordal(fs, cutter, passes, d, nrm, offsets, tol, jump_mm: float = 1e-3, max_rounds: int = 16):
    """Keep the fewest positions per pass whose chords stay within ``tol`` of the dense heights, then
    check every kept move at its quarter points on the exact drop-cutter (only moves not checked yet): a
    move off by more than ``tol`` gets its worst quarter point inserted; a move shorter than ``jump_mm``
    that is still off crosses a jump of the heights (a wall's edge): it becomes a move straight up or
    down plus a level move at the higher height (the tool is never below the drop-cutter height there).
    Each pass gets the measured figures: the largest height of the exact drop-cutter above a move (a
    gouge if positive) and below it."""
    kept = []
    for s_, h_, c_, i in passes:
        idx = douglas_peucker(np.column_stack([s_, h_]), tol)
        # per move: its measured error once checked (NaN: not checked yet)
        kept.append([s_[idx], h_[idx], c_[idx], i, np.full(idx.size - 1, np.nan)])
    fr = np.array([0.25, 0.5, 0.75])  # each move is checked at its quarter points
    for _ in range(max_rounds):
        todo = [np.nonzero(np.isnan(p[4]))[0] for p in kept]
        if not any(t.size for t in todo):
            break
        pts = []
        for (s_, _, _, i, _), t in zip(kept, todo):
            m = (s_[t, None] * (1 - fr) + s_[t + 1, None] * fr).ravel()
            pts.append(np.column_stack([m, np.full(m.size, offsets[i])]))
        Q = np.concatenate(pts)
        res = _drop(fs, cutter, Q[:, :1] * d + Q[:, 1:] * nrm)
        j = 0
        for k, ((s_, h_, c_, i, e_), t) in enumerate(zip(kept, todo)):
            n = t.size
            if n == 0:
                continue
            hq = res.height[j : j + 3 * n].reshape(n, 3)
            cq = res.contact[j : j + 3 * n].reshape(n, 3, 3)
            j += 3 * n
            chq = h_[t, None] * (1 - fr) + h_[t + 1, None] * fr
            eq = np.where(np.isfinite(hq), hq - chq, 0.0)
            w = np.argmax(np.abs(eq), axis=1)  # the worst quarter point of each move
            r_ = np.arange(n)
            hm, cm, err = hq[r_, w], cq[r_, w], eq[r_, w]
            sm = s_[t] * (1 - fr[w]) + s_[t + 1] * fr[w]
            vertical = s_[t + 1] == s_[t]
            flat_jump = (h_[t + 1] == h_[t]) & (np.abs(s_[t + 1] - s_[t]) < jump_mm)
            err = np.where(vertical, 0.0, err)
            e_[t] = np.where(flat_jump, np.maximum(err, 0.0), err)  # a level move over a jump: only a gouge counts
            bad_l = (err > tol) | ((-err > tol) & ~flat_jump)
            bad = t[bad_l]
            if bad.size == 0:
                continue
            short = np.abs(s_[bad + 1] - s_[bad]) < jump_mm
            mid, jmp = bad[~short], bad[short]
            lm = np.nonzero(bad_l)[0][~short]  # positions of the long bad moves in this round's arrays
            # middles of long moves; upper corners of short ones (at the lower end's s, the higher height)
            ins_s = np.concatenate([sm[lm], np.where(h_[jmp] < h_[jmp + 1], s_[jmp], s_[jmp + 1])])
            ins_h = np.concatenate([hm[lm], np.maximum(h_[jmp], h_[jmp + 1])])
            ins_c = np.concatenate([cm[lm], np.where((h_[jmp] < h_[jmp + 1])[:, None], c_[jmp + 1], c_[jmp])])
            ins_at = np.concatenate([mid + 1, jmp + 1])
            keep = np.isfinite(ins_h)
            order = np.argsort(ins_at[keep], kind="stable")
            at = ins_at[keep][order]
            e_ = e_.copy()
            e_[ins_at[keep] - 1] = np.nan  # a split move becomes two unchecked moves
            kept[k] = [
                np.insert(s_, at, ins_s[keep][order]),
                np.insert(h_, at, ins_h[keep][order]),
                np.insert(c_, at, ins_c[keep][order], axis=0),
                i,
                np.insert(e_, at, np.nan),
            ]
    errs = np.concatenate([p[4] for p in kept])
    errs = np.where(np.isnan(errs), 0.0, errs)
    above = float(errs.max(initial=0.0))
    below = float((-errs).max(initial=0.0))
    return [[s_, h_, c_, i, (above, below)] for s_, h_, c_, i, _ in kept]


def _link(fs: FaceSet, cutter, passes, d, nrm, offsets, step, z_safe, tol, direction, info) -> ToolPath:
    """Join passes: stay down (cutting along the part's exact drop-cutter heights) between the ends of
    adjacent zig-zag lines no more than 1.5 step-overs apart where a face is under the tool all the
    way; elsewhere retract to ``z_safe``, rapid, and plunge."""
    frame = fs.frame
    T, M, P, C = [], [], [], []
    n_links_down = 0
    n_retracts = 0

    def world(s_, t_, z_):
        q = np.column_stack([s_[:, None] * d + np.asarray(t_).reshape(-1, 1) * nrm, z_])
        return q @ frame

    def up(p):
        return world(np.array([p[0]]), [p[1]], [z_safe])

    prev_end = None
    for k, (s_, h_, c_, i, _) in enumerate(passes):
        start = (s_[0], offsets[i])
        link_ok = False
        if prev_end is not None and direction is Direction.ZIGZAG:
            (ps, pt, ph, pi) = prev_end
            gap = math.hypot(s_[0] - ps, offsets[i] - pt)
            if abs(i - pi) == 1 and gap <= 1.5 * step + 1e-9:
                n = max(2, math.ceil(gap / min(step, 0.25)) + 1)
                w = np.linspace(0, 1, n)[1:-1]
                ls = ps + w * (s_[0] - ps)
                lt = pt + w * (offsets[i] - pt)
                lr = _drop(fs, cutter, ls[:, None] * d + lt[:, None] * nrm) if w.size else None
                if lr is None or np.all(np.isfinite(lr.height)):
                    link_ok = True
                    if lr is not None:
                        T.append(world(ls, lt, lr.height))
                        M.append(np.full(w.size, Move.CUT))
                        P.append(np.full(w.size, k))
                        C.append(lr.contact)
                    n_links_down += 1
        if not link_ok:
            if prev_end is not None:
                T.append(up((prev_end[0], prev_end[1])))
                M.append([Move.RETRACT])
                P.append([k - 1])
                C.append(np.full((1, 3), np.nan))
                n_retracts += 1
            T.append(up(start))
            M.append([Move.RAPID])
            P.append([k])
            C.append(np.full((1, 3), np.nan))
            T.append(world(s_[:1], [offsets[i]], h_[:1]))
            M.append([Move.APPROACH])
            P.append([k])
            C.append(c_[:1])
            s_, h_, c_ = s_[1:], h_[1:], c_[1:]
        T.append(world(s_, np.full(s_.size, offsets[i]), h_))
        M.append(np.full(s_.size, Move.CUT))
        P.append(np.full(s_.size, k))
        C.append(c_)
        prev_end = (
            float(s_[-1]) if s_.size else float(start[0]),
            float(offsets[i]),
            float(h_[-1]) if h_.size else 0.0,
            i,
        )
    T.append(up((prev_end[0], prev_end[1])))
    M.append([Move.RETRACT])
    P.append([len(passes) - 1])
    C.append(np.full((1, 3), np.nan))
    tip = np.concatenate(T)
    n = tip.shape[0]
    cc = np.concatenate(C)  # contacts are world points already
    above = max((p[4][0] for p in passes), default=0.0)
    below = max((p[4][1] for p in passes), default=0.0)
    info = dict(
        info,
        chordal_tolerance_mm=tol,
        chordal_error_measured_mm=float(max(above, below)),
        chord_below_drop_height_mm=float(above),
        chord_above_drop_height_mm=float(below),
        clearance_height_mm=z_safe,
        n_passes=len(passes),
        n_links_on_part=n_links_down,
        n_retracts=n_retracts,
    )
    return ToolPath(
        tip,
        np.repeat(frame[2][None, :], n, axis=0),
        np.concatenate([np.asarray(m, np.int8) for m in M]),
        np.concatenate([np.asarray(p, np.int64) for p in P]),
        cc,
        None,
        cutter,
        "raster",
        {},
        info,
    )


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


def waterline(
    faces,
    cutter,
    *,
    check_faces=(),
    stepdown_mm: float,
    chordal_tolerance_mm: float = 0.01,
    clearance_mm: float = 5.0,
    axis=(0.0, 0.0, 1.0),
    extent=None,
    grid_mm: float | None = None,
    z_min_mm: float | None = None,
    seed_spacing_mm: float | None = None,
    verify_tolerance_mm: float | None = None,
    progress: Progress | None = None,
) -> ToolPath:
    """Waterline (constant-z) tool path: at each level, the closed contours where the exact drop-cutter
    height equals the level (found on a plan grid of exact heights with contourpy, each vertex then
    moved onto the exact crossing by regula falsi); moves whose quarter points rise above the level by
    more than ``chordal_tolerance_mm`` get the exact crossing next to their middle inserted.

    Parameters
    ----------
    stepdown_mm : float
        Distance between levels, from the part's top down to ``z_min_mm`` (default: the lowest tool
        height over the machined faces).
    grid_mm : float, optional
        Plan grid of exact heights the contours are found on (default ``min(1, D/10)``). A feature
        narrower than the grid may leave moves above their level after refinement: they are dropped
        (the contour is cut open, the tool retracts and plunges again) and counted in ``info``
        (``n_moves_dropped_above_level``, ``length_dropped_above_level_mm``).
    verify_tolerance_mm : float, optional
        Check the tool body against the faces and drop cutting moves that gouge deeper than this
        (counted in ``info``); the caller still checks the path it writes.

    Other parameters as :func:`raster`.
    """
    import contourpy

    cutter = checks.tool(cutter)
    for name, val in (
        ("chordal tolerance", chordal_tolerance_mm),
        ("clearance", clearance_mm),
        ("step-down", stepdown_mm),
    ):
        checks.positive(name, val)
    fs, (x0, x1, y0, y1) = machining_face_set(faces, check_faces, cutter, axis=axis,
                                               seed_spacing_mm=seed_spacing_mm, what="a waterline path")  # fmt: skip
    R = float(cutter.profile_points(16)[:, 0].max())
    if extent is None:
        extent = (x0 - R, x1 + R, y0 - R, y1 + R)
    g = checks.positive("grid", grid_mm) if grid_mm is not None else min(1.0, cutter.D / 10)
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
    res = _drop(fs, cutter, np.column_stack([X.ravel(), Y.ravel()]), progress)
    Z = res.height.reshape(X.shape)
    fin = np.isfinite(Z)
    if not fin.any():
        raise InputError("no face lies under the tool anywhere in the waterline's extent")
    z_low = float(np.nanmin(Z)) - 1.0
    Zf = np.where(fin, Z, z_low)
    z_top = float(max(fs.sample_xyz[:, 2].max(), fs.edge_xyz[:, 2].max()))
    z_bottom = float(np.nanmin(Z[fin])) if z_min_mm is None else float(z_min_mm)
    levels = np.arange(float(np.nanmax(Z)) - stepdown_mm, z_bottom - 1e-9, -stepdown_mm)
    if levels.size == 0:
        raise InputError(f"step-down {stepdown_mm:g} mm leaves no level between the top and {z_bottom:g} mm")
    gen = contourpy.contour_generator(xs, ys, Zf, line_type=contourpy.LineType.Separate)
    lines, lv = [], []
    for level in levels:
        for line in gen.lines(level):
            line = np.asarray(line, float)
            if line.ndim == 2 and line.shape[0] >= 3:
                lines.append(line)
                lv.append(float(level))
    if not lines:
        raise InputError("no waterline contour: the part is flat under every level")
    pts, ccs, rise, lv = _refine_contours(fs, cutter, xs, ys, Zf, lines, np.array(lv), chordal_tolerance_mm, g)
    # moves still above their level (a feature narrower than the grid the contours were found on) are
    # dropped: the contour is cut open there, the tool retracts and plunges again (material left there)
    pts, ccs, lv, n_drop, l_drop = _split_at(pts, ccs, lv, [r > chordal_tolerance_mm for r in rise])
    above = max([0.0] + [float(r[r <= chordal_tolerance_mm].max(initial=0.0)) for r in rise])
    info = {"pattern": "waterline", "stepdown_mm": float(stepdown_mm), "grid_mm": g, "n_levels": int(levels.size),
            "extent_mm": [float(e) for e in extent], "n_moves_dropped_above_level": n_drop,
            "length_dropped_above_level_mm": l_drop}  # fmt: skip
    if not pts:
        raise InputError("no waterline contour stays at its level: refine --grid")
    z_safe = z_top + clearance_mm
    tp = _link_levels(fs, cutter, list(zip(pts, lv, ccs)), z_safe, chordal_tolerance_mm, above, info=info)
    if verify_tolerance_mm is not None:
        tp = _drop_gouging_moves(tp, fs, cutter, list(faces) + list(check_faces), pts, ccs, lv, z_safe,
                                 chordal_tolerance_mm, above, info, verify_tolerance_mm)  # fmt: skip
    return tp


def _drop_gouging_moves(tp, fs, cutter, faces, pts, ccs, lv, z_safe, tol, above, info, verify_tol, rounds=4):
    """Waterline moves the tool body check finds gouging (deeper than ``verify_tol``: between two exact
    crossings the part rises above the level, or the shank or holder meets it) are dropped and their
    contours cut open there, until the check is clean. ``info`` counts them."""
    from ..gougecheck import GOUGE, verify

    n_total, l_total = 0, 0.0
    for _ in range(rounds):
        v = verify(faces, tp, cutter, tolerance=verify_tol)
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
            out_p.append(p), out_c.append(c), out_l.append(lv)
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
                out_p.append(pp), out_c.append(cc), out_l.append(lv)
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
