"""Fixed-axis paths (3 axes, 3+2) cut down to where the tool reaches and linked just above the part.

A machining-surface path along a fixed axis follows one face, and the part's other faces may stand in
the tool's way (the hub beside a blade, the next blade). At each cutting position the exact drop-cutter
on every face of the part gives the lowest tip height at which the tool enters no face: its cutting part
(an infinite cylinder above its profile, as OpenCAMLib's) and, where wider than the cutter, its shank and
holder (flat discs at their heights). A position lower than that by more than the gouge tolerance cannot
be reached from anywhere: it is cut out of the path instead of the path being refused.

The runs left are joined by **skim links**: up along the axis by the clearance, or higher until the whole
tool (cutting part, shank and holder: the drop-cutter of the body grown by the clearance) keeps the
clearance from every face; across at the highest such height along the straight plan line between the
two ends (sampled at most a fifth of the tool's radius apart); down along the axis and onto the next
run. Rapid, approach and retract distances are so measured from the whole tool, not from the tip. The
path starts and ends on a plane ``clearance`` above the whole part. Every position of a link is certified clear by the
drop-cutter; the motions between positions are for the tool-body check
(:func:`machsurf_cad.check_toolpath`) to confirm.
"""

from __future__ import annotations

import math

import numpy as np

from .. import checks
from ..cam.toolpath import Move, ToolPath
from ..cutters import FlatEndMill
from ..errors import InputError
from ..machining.toolpath import part_plane
from ..typing import FaceLike, PartLike, ToolLike
from . import cache
from .dropcutter import default_seed_spacing, drop_cutter
from .faceset import face_set as build_face_set

_LINK_SAMPLES_MAX = 2000


def _fixed_axis(tp: ToolPath) -> np.ndarray:
    cutting = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)
    if not np.any(cutting):
        raise InputError("the tool path has no cutting position")
    a = tp.axis[cutting]
    if np.abs(a - a[0]).max() > 1e-9:
        raise InputError("trimming to the tool's reach needs a fixed tool axis (3 axes or 3+2)")
    return a[0] / np.linalg.norm(a[0])


class _Heights:
    """Lowest tip heights (tool frame z) at which the whole tool body (cutting part, and its shank and
    holder where wider) keeps ``margin`` mm from every face: the drop-cutter of the body offset by
    ``margin`` (:meth:`~machsurf_cad.Cutter.offset` lowers the tip by as much), raised by ``margin``."""

    def __init__(self, faces, cutter, axis, margin: float = 0.0):
        self.margin = float(margin)
        body = cutter.offset(self.margin) if self.margin > 0 else cutter
        self.sets = [(body, -self.margin, self._fs(faces, body, axis))]
        for r, z0, _ in cutter.body_parts():
            if r > cutter.radius + 1e-12:
                disc = FlatEndMill(2 * (r + self.margin))
                self.sets.append((disc, z0 - self.margin, self._fs(faces, disc, axis)))
        self.frame = self.sets[0][2].frame

    @staticmethod
    def _fs(faces, tool, axis):
        return cache.face_set(build_face_set, faces, axis=axis, spacing=default_seed_spacing(tool))

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """The heights at the plan points ``xy`` (n, 2); NaN where no face lies under the body."""
        H = np.full(xy.shape[0], -np.inf)
        for tool, z0, fs in self.sets:
            H = np.fmax(H, drop_cutter(None, tool, xy, face_set=fs).height - z0)
        return np.where(np.isfinite(H), H, np.nan)


class _Dense:
    """The path's cutting positions in the tool frame with points inserted along every cutting move the part
    stops the tool on (every ``step`` mm, the boundaries between reached and stopped points bisected to
    ``step / 256``): each point as ``(i0, i1, w)`` (``w`` of the way from planned position ``i0`` to ``i1``),
    its pass, and whether the tool reaches it (:func:`trim_to_reach`)."""

    def __init__(self, tp: ToolPath, q: np.ndarray, heights: _Heights, tol: float, step: float):
        cutting = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)
        self.q, self.heights, self.tol = q, heights, tol
        idx = np.nonzero(cutting)[0]
        ok = self._ok(np.column_stack([idx, idx, np.ones(idx.size)]))
        I0, I1, W = [idx], [idx], [np.ones(idx.size)]
        # cutting moves: from a cutting position to the next one of the same pass
        mv = idx[1:][(np.diff(idx) == 1) & (tp.pass_index[idx[1:]] == tp.pass_index[idx[:-1]])]
        if mv.size:
            plan = np.hypot(*(q[mv, :2] - q[mv - 1, :2]).T)
            n = np.maximum(np.ceil(plan / step).astype(int), 1)
            j = np.repeat(np.arange(mv.size), n - 1)
            w = (np.arange(j.size) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1) + 1) / np.repeat(n, n - 1)
            inner = np.column_stack([mv[j] - 1, mv[j], w])
            inner_ok = self._ok(inner)
            bad = np.unique(j[~inner_ok])  # the moves the part stops the tool on somewhere: split
            bad_mv = np.isin(j, bad)
            inner, inner_ok = inner[bad_mv], inner_ok[bad_mv]
            edge = self._boundaries(inner, inner_ok, mv, n)
            I0 += [inner[:, 0], edge[:, 0]]
            I1 += [inner[:, 1], edge[:, 1]]
            W += [inner[:, 2], edge[:, 2]]
            ok = np.concatenate([ok, inner_ok, np.ones(edge.shape[0], bool)])
        i0, i1, w = (np.concatenate(x) for x in (I0, I1, W))
        order = np.lexsort((w, i1))
        self.i0, self.i1, self.w = i0[order].astype(int), i1[order].astype(int), w[order]
        self.ok = ok[order]
        self.pass_index = tp.pass_index[self.i1]
        self.planned = np.where(self.w == 1.0, self.i1, -1)

    def points(self, rows=None) -> np.ndarray:
        sel = slice(None) if rows is None else rows
        w = self.w[sel][:, None]
        return self.q[self.i0[sel]] * (1 - w) + self.q[self.i1[sel]] * w

    def _ok(self, rows: np.ndarray) -> np.ndarray:
        i0, i1, w = rows[:, 0].astype(int), rows[:, 1].astype(int), rows[:, 2:3]
        p = self.q[i0] * (1 - w) + self.q[i1] * w
        with np.errstate(invalid="ignore"):
            return ~(p[:, 2] < self.heights(p[:, :2]) - self.tol)  # NaN: no face under the tool

    def _boundaries(self, inner, inner_ok, mv, n) -> np.ndarray:
        """Bisected points next to every change between reached and stopped along the split moves."""
        rows = np.column_stack([inner[:, :2], inner[:, 2]])
        # the move's ends count too: prepend/append them per move
        ends0 = np.column_stack([mv - 1, mv, np.zeros(mv.size)])
        ends1 = np.column_stack([mv - 1, mv, np.ones(mv.size)])
        allr = np.concatenate([rows, ends0, ends1])
        okr = np.concatenate([inner_ok, self._ok(np.column_stack([mv - 1, mv - 1, np.ones(mv.size)])),
                              self._ok(np.column_stack([mv, mv, np.ones(mv.size)]))])  # fmt: skip
        order = np.lexsort((allr[:, 2], allr[:, 1]))
        allr, okr = allr[order], okr[order]
        same = allr[1:, 1] == allr[:-1, 1]
        change = np.nonzero(same & (okr[1:] != okr[:-1]))[0]
        if change.size == 0:
            return np.empty((0, 3))
        good_w = np.where(okr[change], allr[change, 2], allr[change + 1, 2])
        bad_w = np.where(okr[change], allr[change + 1, 2], allr[change, 2])
        base = allr[change, :2]
        for _ in range(8):
            mid = 0.5 * (good_w + bad_w)
            m_ok = self._ok(np.column_stack([base, mid]))
            good_w, bad_w = np.where(m_ok, mid, good_w), np.where(m_ok, bad_w, mid)
        keep = (good_w > 0) & (good_w < 1)
        return np.column_stack([base[keep], good_w[keep]])


def _runs(d: _Dense) -> list[np.ndarray]:
    """Runs (rows of ``d``) of at least two consecutive points of one pass that the tool all reaches."""
    runs = []
    for p in np.unique(d.pass_index):
        idx = np.nonzero(d.pass_index == p)[0]
        breaks = np.nonzero(~d.ok[idx][:-1] | ~d.ok[idx][1:] | (np.diff(d.i1[idx]) > 1))[0]
        for seg in np.split(idx, breaks + 1):
            seg = seg[d.ok[seg]]
            if seg.size >= 2:
                runs.append(seg)
    return runs


def _link_height(heights: _Heights, a: np.ndarray, b: np.ndarray, R: float) -> float:
    """The highest clear tip height along the plan segment ``a`` -> ``b`` (tool frame), -inf if none."""
    n = int(min(_LINK_SAMPLES_MAX, max(2, math.ceil(float(np.hypot(*(b[:2] - a[:2]))) / (0.2 * R)) + 1)))
    w = np.linspace(0.0, 1.0, n)[:, None]
    H = heights(a[None, :2] * (1 - w) + b[None, :2] * w)
    return float(np.nanmax(H)) if np.any(np.isfinite(H)) else -math.inf


def _machined_fraction(face, tp: ToolPath, d: _Dense, runs, step: float) -> float:
    """:func:`~machsurf_cad.pathcheck.machined_area_fraction` of the planned path with the points ``d``
    inserted (contacts along the chords), the runs' rows kept."""
    from ..pathcheck import machined_area_fraction

    w = d.w[:, None]
    cc = np.asarray(tp.cc, float)
    dense = ToolPath(tp.tip[d.i0] * (1 - w) + tp.tip[d.i1] * w, tp.axis[d.i1], np.full(d.w.size, Move.CUT),
                     d.pass_index, cc[d.i0] * (1 - w) + cc[d.i1] * w)  # fmt: skip
    return machined_area_fraction(face, dense, np.concatenate(runs), step=step)


def _carried(tp: ToolPath, d: _Dense, row: np.ndarray):
    """Contact points and extras of the new positions (``row``: their rows of ``d``, -1 on links): a planned
    position's own, NaN contacts at inserted points (they lie on a chord, not on the surface), float
    extras interpolated along the move and others taken from its end."""
    n = row.size
    on = row >= 0
    r = row[on]
    planned = d.planned[r]
    cc = None
    if tp.cc is not None:
        cc = np.full((n, 3), np.nan)
        got = np.full((r.size, 3), np.nan)
        got[planned >= 0] = np.asarray(tp.cc)[planned[planned >= 0]]
        cc[on] = got
    extras = {"planned_index": np.where(on, -1, -1)}
    extras["planned_index"][on] = planned
    for key, v in tp.extras.items():
        v = np.asarray(v)
        pad = np.full((n,) + v.shape[1:], np.nan if v.dtype.kind == "f" else -1, dtype=v.dtype)
        if v.dtype.kind == "f":
            w = d.w[r].reshape((-1,) + (1,) * (v.ndim - 1))
            pad[on] = v[d.i0[r]] * (1 - w) + v[d.i1[r]] * w
        else:
            pad[on] = v[d.i1[r]]
        extras[key] = pad
    return cc, extras


def trim_to_reach(
    toolpath: ToolPath,
    part: PartLike,
    *,
    gouge_tolerance: float = 0.01,
    clearance: float = 5.0,
    tool: ToolLike | None = None,
    face: FaceLike | None = None,
) -> ToolPath:
    """``toolpath`` (fixed axis) without the positions the tool cannot reach, its runs skim-linked.

    Parameters
    ----------
    toolpath : ToolPath
        A path along one fixed axis (3 axes or 3+2), e.g. from :func:`machsurf_cad.tool_paths`.
    part : sequence of Face
        Every face of the part (the drop-cutter runs on all of them).
    gouge_tolerance : float
        How far (mm) a kept position may lie below the drop-cutter height.
    clearance : float
        Least retract and approach along the axis, and the distance the whole tool (holder included)
        keeps from every face on links, mm.
    tool : Cutter or str, optional
        The tool with its shank and holder; the path's own by default.
    face : Face, optional
        The machined face: the share of its area whose planned contacts are kept is reported.

    Returns
    -------
    ToolPath
        The kept runs, skim-linked (module docstring). ``extras["planned_index"]`` gives each position's
        index in ``toolpath`` (-1 on links); ``info`` adds ``reach_positions_planned``,
        ``reach_positions_trimmed`` (planned positions where the part stops the tool),
        ``reach_positions_kept`` (with ``reach_positions_inserted`` points put along moves the part stops
        part-way), ``reach_runs``, ``machined_area_fraction`` (with ``face``),
        ``links_skim``, ``link_height_max_mm`` (the highest link above the higher of its two ends) and
        ``safe_plane_mm``.

    Examples
    --------
    A wall beside a floor: the positions the wall stands over are cut out, the rest linked above it.

    >>> import numpy as np
    >>> from machsurf_cad import BallEndMill, builders
    >>> floor = builders.plane_patch((-30, -30, 0), (60, 0, 0), (0, 60, 0))
    >>> block = builders.plane_patch((0, -30, 8), (10, 0, 0), (0, 60, 0))
    >>> tips = [np.column_stack([np.linspace(-20, 20, 41), np.full(41, y), np.zeros(41)]) for y in (-5.0, 5.0)]
    >>> tp = ToolPath.from_passes(tips, [np.tile([0.0, 0, 1], (41, 1))] * 2, cutter=BallEndMill(6))
    >>> out = trim_to_reach(tp, [floor, block])
    >>> out.info["reach_positions_trimmed"], out.info["reach_runs"]
    (30, 4)
    """
    cutter = checks.tool(tool if tool is not None else toolpath.cutter)
    tol = checks.positive("gouge_tolerance", gouge_tolerance)
    clearance = checks.positive("clearance", clearance)
    faces: list = list(part) if isinstance(part, (list, tuple)) else [part]
    if not faces:
        raise InputError("trimming to the tool's reach needs the part's faces")
    a = _fixed_axis(toolpath)
    heights = _Heights(faces, cutter, a)
    clear = _Heights(faces, cutter, a, margin=clearance)  # links: the whole body keeps the clearance
    F = heights.frame
    q = toolpath.tip @ F.T  # tool frame
    cutting = (toolpath.move == Move.CUT) | (toolpath.move == Move.APPROACH)
    d = _Dense(toolpath, q, heights, tol, min(0.2 * cutter.radius, 1.0))
    runs = _runs(d)
    if not runs:
        raise InputError(
            f"the tool reaches none of the path's {int(cutting.sum())} cutting positions along the axis "
            f"{np.round(a, 4).tolist()}: every one lies more than {tol:g} mm below where the part stops the tool"
        )
    kept = np.zeros(toolpath.n_positions, bool)
    for r in runs:
        kept[d.planned[r][d.planned[r] >= 0]] = True
    qd = d.points()
    z_plane = part_plane(faces, F[2], clearance)
    R = cutter.radius
    T: list[np.ndarray] = []
    M: list[int] = []
    P: list[int] = []
    X: list[int] = []

    def add(p, move, k, src=-1):
        T.append(np.asarray(p, float))
        M.append(int(move))
        P.append(k)
        X.append(src)

    link_max = -math.inf
    up = np.full(qd.shape[0], np.nan)  # per run end: how high the tool must go to move freely
    ends = np.array([i for r in runs for i in (r[0], r[-1])])
    up[ends] = np.fmax(clear(qd[ends, :2]), qd[ends, 2] + clearance)
    for k, r in enumerate(runs):
        start = qd[r[0]]
        if k == 0:
            zl = max(z_plane, up[r[0]])
        else:
            e = runs[k - 1][-1]
            zl = max(up[e], up[r[0]], _link_height(clear, qd[e], start, R))
            link_max = max(link_max, zl - max(qd[e, 2], start[2]))
            add((qd[e, 0], qd[e, 1], up[e]), Move.RETRACT, k - 1)
            if zl > up[e] + 1e-12:
                add((qd[e, 0], qd[e, 1], zl), Move.RAPID, k - 1)
        add((start[0], start[1], zl), Move.RAPID, k)
        if zl > up[r[0]] + 1e-12:
            add((start[0], start[1], up[r[0]]), Move.RAPID, k)
        add(start, Move.APPROACH, k, int(r[0]))
        for i in r[1:]:
            add(qd[i], Move.CUT, k, int(i))
    last = runs[-1][-1]
    add((qd[last, 0], qd[last, 1], up[last]), Move.RETRACT, len(runs) - 1)
    if z_plane > up[last]:
        add((qd[last, 0], qd[last, 1], z_plane), Move.RAPID, len(runs) - 1)
    row = np.array(X)
    tips = np.array(T) @ F
    cc, extras = _carried(toolpath, d, row)
    n_cut = int(cutting.sum())
    n_inserted = int(np.sum(d.planned[np.concatenate(runs)] < 0))
    info = dict(
        toolpath.info,
        reach_positions_planned=n_cut,
        reach_positions_trimmed=n_cut - int(kept.sum()),
        reach_positions_inserted=n_inserted,
        reach_positions_kept=int(sum(len(r) for r in runs)),
        n_cut_positions=int(sum(len(r) for r in runs)),
        reach_runs=len(runs),
        links_skim=len(runs) - 1,
        link_height_max_mm=float(link_max) if np.isfinite(link_max) else 0.0,
        safe_plane_mm=z_plane,
        clearance_mm=clearance,
    )
    if face is not None and toolpath.cc is not None:
        info["machined_area_fraction"] = _machined_fraction(face, toolpath, d, runs, 0.2 * cutter.radius)
    return ToolPath(
        tips,
        np.tile(a, (len(T), 1)),
        np.array(M, np.int8),
        np.array(P, np.int64),
        cc,
        None,
        cutter,
        toolpath.name,
        extras,
        info,
    )


__all__ = ["trim_to_reach"]
