"""3-axis tool paths on whole parts from the exact drop-cutter: raster (zig-zag or one-way, any angle;
waterline in :mod:`machsurf_cad.threeaxis.zlevel`), linked with plunges, retracts and rapids at a clearance height,
staying down between adjacent raster lines where the tool can follow the part.

Every position is an exact drop-cutter height on every face given (machined and checked faces); the
chordal error between positions is measured on the exact drop-cutter at points the path never used.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import Enum

import numpy as np

from .. import checks
from ..cam.chordal import douglas_peucker
from ..cam.toolpath import Move, ToolPath
from ..errors import InputError
from ..glossary import renamed
from ..results import Progress
from ..scallop import scallop_stepover
from ..typing import FacesLike, ToolLike, Vector3
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
    return drop_cutter(None, cutter, xy, face_set=fs, progress=progress)


MAX_DROP_POINTS = 20_000_000
"""Most drop-cutter points a raster or waterline plans before it refuses (about 1 ms a point: hours)."""


@renamed(
    cutter="tool",
    stepover_mm="stepover",
    scallop_mm="scallop",
    angle_deg="angle",
    chordal_tolerance_mm="chordal_tolerance",
    clearance_mm="clearance",
    sample_step_mm="sample_step",
    seed_spacing_mm="seed_spacing",
    verify_tolerance_mm="gouge_tolerance",
)
def raster(
    faces: FacesLike,
    tool: ToolLike,
    *,
    check_faces: FacesLike = (),
    stepover: float | None = None,
    scallop: float | None = None,
    angle: float = 0.0,
    direction: Direction | str = Direction.ZIGZAG,
    chordal_tolerance: float = 0.01,
    clearance: float = 5.0,
    axis: Vector3 = (0.0, 0.0, 1.0),
    extent: Sequence[float] | None = None,
    sample_step: float | None = None,
    seed_spacing: float | None = None,
    gouge_tolerance: float | None = None,
    progress: Progress | None = None,
) -> ToolPath:
    """Raster tool path over ``faces``, avoiding ``faces`` and ``check_faces``.

    Parameters
    ----------
    faces : sequence of Face
        Faces to machine: the raster covers their plan extent (tool frame).
    tool : Cutter
        Any profile cutter.
    check_faces : sequence of Face
        Further faces the tool must not cut into (not machined: they only lift the tool).
    stepover, scallop_mm : float
        Distance between lines, or the largest scallop (cusp height above the part along its normal) the
        path may leave: then each line is placed as far from the last as the cusp between the two allows
        (:func:`~machsurf_cad.threeaxis.scallop.plan_lines`; the flat-floor step-over of
        :func:`scallop_stepover` is the first guess) and ``info`` holds the planned largest scallop.
    angle : float
        Line direction in the tool frame's plane (0: along x).
    direction : Direction
        ``zigzag`` or ``one-way``.
    chordal_tolerance : float
        Largest height of the exact drop-cutter above the straight move between two positions,
        measured at every move's middle (never used as a position).
    clearance : float
        Rapids run this far above the highest point of the part (along the axis).
    axis : 3-vector
        Fixed tool axis (3+2).
    extent : (x0, x1, y0, y1), optional
        Plan box in the tool frame (default: the machined faces' extent).
    sample_step : float, optional
        Dense sampling along lines before chordal reduction (default ``min(0.25, D/20)``).
    gouge_tolerance : float, optional
        Check the tool body against the faces and split cutting moves that gouge deeper than this
        (:func:`refine_gouging_moves`); the caller still checks the path it writes.

    Returns
    -------
    ToolPath
        ``info`` holds the step-over, the chordal error measured, the numbers of lines and links.
    """
    tool = checks.tool(tool)
    for name, val in (("chordal tolerance", chordal_tolerance), ("clearance", clearance)):
        checks.positive(name, val)
    if (stepover is None) == (scallop is None):
        raise InputError("give a step-over or a scallop height (one of them)")
    if scallop is not None:
        step = scallop_stepover(checks.positive("scallop height", scallop), tool)
    else:
        step = checks.positive("step-over", stepover)
    direction = Direction(direction)
    machined = list(faces)
    fs, box = machining_face_set(machined, check_faces, tool, axis=axis, seed_spacing=seed_spacing,
                                 what="a raster path")  # fmt: skip
    extent = box if extent is None else extent
    d, nrm, offsets, (s0, s1) = _lines(extent, angle, step)
    ds = float(sample_step) if sample_step is not None else min(0.25, tool.D / 20)
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
    if scallop is not None:  # each line as far from the last as the cusp between them allows
        offsets, H, CC, plan_info = plan_lines(fs, tool, scallop, d, nrm, (offsets[0], offsets[-1]), s, _drop,
                                               step, progress)  # fmt: skip
        step = float(np.diff(offsets).max())
    else:
        S, T = np.meshgrid(s, offsets, indexing="ij")
        pts = S.T.reshape(-1, 1) * d + T.T.reshape(-1, 1) * nrm
        res = _drop(fs, tool, pts, progress)
        H = res.height.reshape(len(offsets), len(s))
        CC = res.contact.reshape(len(offsets), len(s), 3)
    z_top = float(fs.pool_xyz[:, 2].max())
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
    passes = _reduce_chordal(fs, tool, passes, d, nrm, offsets, chordal_tolerance)
    if direction is Direction.ZIGZAG:
        for p in passes:
            if p[3] % 2 == 1:
                p[0], p[1], p[2] = p[0][::-1], p[1][::-1], p[2][::-1]
    tp = _link(fs, tool, passes, d, nrm, offsets, step, z_top + clearance, chordal_tolerance, direction,
               info={"pattern": "raster", "direction": direction.value, "angle_deg": float(angle),
                     "stepover_mm": step, "scallop_target_mm": scallop, "n_lines": int(len(offsets)),
                     "sample_step_mm": ds, "extent_mm": [float(e) for e in extent], **plan_info})  # fmt: skip
    if gouge_tolerance is not None:
        tp = refine_gouging_moves(tp, machined + list(check_faces), tool, fs, gouge_tolerance=gouge_tolerance)
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


def refine_gouging_moves(tp: ToolPath, faces, cutter, fs: FaceSet, *, gouge_tolerance: float, rounds: int = 6,
                         n_sub: int = 8, jump_mm: float = 2e-3) -> ToolPath:  # fmt: skip
    """Cutting moves the tool body check finds gouging (deeper than ``gouge_tolerance``) are split into
    ``n_sub`` moves at exact drop-cutter heights, and the path is checked again, up to ``rounds`` times.
    The chordal check samples each move at three points; a narrow rise of the heights between them (a
    thin blade's edge) is only seen by the body check. ``info`` gets ``n_moves_split``."""
    from ..gougecheck import GOUGE, verify

    split_total = 0
    for _ in range(rounds):
        v = verify(faces, tp, cutter, gouge_tolerance=gouge_tolerance)
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
        r = drop_cutter(None, cutter, q, face_set=fs)
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


def _down_link(fs: FaceSet, cutter, prev_end, start, i, step, d, nrm):
    """A link cutting along the part between the end of the last line and the start of line ``i``: where
    the lines are adjacent, no more than 1.5 step-overs apart, and a face is under the tool all the way.
    Returns ``(s, t, drop-cutter result or None)`` of its inner points, or None."""
    ps, pt, _, pi = prev_end
    gap = math.hypot(start[0] - ps, start[1] - pt)
    if abs(i - pi) != 1 or gap > 1.5 * step + 1e-9:
        return None
    n = max(2, math.ceil(gap / min(step, 0.25)) + 1)
    w = np.linspace(0, 1, n)[1:-1]
    ls = ps + w * (start[0] - ps)
    lt = pt + w * (start[1] - pt)
    lr = _drop(fs, cutter, ls[:, None] * d + lt[:, None] * nrm) if w.size else None
    if lr is not None and not np.all(np.isfinite(lr.height)):
        return None
    return ls, lt, lr


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
        link = None
        if prev_end is not None and direction is Direction.ZIGZAG:
            link = _down_link(fs, cutter, prev_end, start, i, step, d, nrm)
        if link is not None:
            ls, lt, lr = link
            if lr is not None:
                T.append(world(ls, lt, lr.height))
                M.append(np.full(ls.size, Move.CUT))
                P.append(np.full(ls.size, k))
                C.append(lr.contact)
            n_links_down += 1
        else:
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
