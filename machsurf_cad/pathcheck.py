"""Check-before-write: a tool path's tool body against every face of its part, and what may be written.

One core step used by the command line, the batch runner and the FreeCAD operation alike: the path
is verified (:func:`machsurf_cad.verify`); a clean path is written as is; a gouging one is refused,
cut down to its clear stretches and relinked (``on_gouge="trim"``, the new links checked again), or
written with its gouges listed (``on_gouge="allow"``). A gouge is never written silently: the
verdict says which of these happened.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from . import checks
from .cam.clearance import beyond
from .cam.toolpath import Move, ToolPath
from .checks import positive
from .errors import InputError
from .gougecheck import CLEAR, VerifyResult, verify
from .results import Progress, Result
from .typing import MapChunks, PartLike, ToolLike

OnGouge = Literal["refuse", "trim", "allow"]
"""What to do with a path that gouges or collides: refuse it, keep its clear stretches, or write it anyway."""

COLLISION_CLEARANCE = 0.01
"""Least distance (mm) rapids, shank and holder keep from the part, or the gouge tolerance when smaller:
a large gouge tolerance (flank's interference tolerance) is not a clearance."""


@dataclass(frozen=True, eq=False)
class PathCheck(Result):
    """The verdict of :func:`check_toolpath`.

    ``toolpath`` is what may be written (the path, its clear stretches, or the gouging path when
    allowed), ``None`` when refused; ``check`` is the whole-part check of the path as planned and
    ``recheck`` that of the trimmed path.
    """

    planned: ToolPath
    toolpath: ToolPath | None
    check: VerifyResult
    recheck: VerifyResult | None
    verdict: Literal["clean", "trimmed", "gouges allowed", "refused"]
    link_clearance: float
    trimmed_from: ToolPath | None = None
    """The planned path with points inserted along its long cutting moves, which the trimmed path's
    ``extras["planned_index"]`` refers to."""
    beyond_axis_limit: int = 0
    """Positions of the planned path whose axis lies past the machine's rotary limit (``max_axis_angle``)."""

    @property
    def written(self) -> bool:
        return self.toolpath is not None

    def report(self) -> dict:
        rep = dict(self.check.report(), verdict=self.verdict, n_positions_beyond_axis_limit=self.beyond_axis_limit)
        if self.toolpath is not None:  # the written path's rapids (holder included) and its links' length
            info = self.toolpath.info
            rep["rapids"] = {
                "clearance_mm": self.link_clearance,
                "n_rapids_at_feed": info.get("n_rapids_at_feed", 0),
                "rapid_distance_min_mm": info.get("rapid_distance_min_mm"),
                "link_length_mm": self.toolpath.link_length(),
                "n_links_split": info.get("n_links_split", 0),
                "link_length_at_feed_mm": _length(self.toolpath, (Move.RETRACT, Move.APPROACH)),
                "rapid_length_mm": _length(self.toolpath, (Move.RAPID,)),
            }
        if self.recheck is not None and self.toolpath is not None:
            rep["trimmed"] = {
                "n_cut_kept": self.toolpath.n_cut,
                "n_cut_before": self.planned.n_cut,
                "n_cut_split": (self.trimmed_from or self.planned).n_cut,  # long moves split before trimming
                "n_passes": self.toolpath.n_passes,
                "clearance_mm": self.link_clearance,
                **{
                    k: self.toolpath.info[k]
                    for k in (
                        "links_direct",
                        "links_over_surface",
                        "runs_left_out",
                        "runs_reversed",
                        "runs_visited_later",
                        "gaps_not_linked",
                        "clearance_surface",
                    )
                    if k in self.toolpath.info
                },  # fmt: skip
                "recheck": self.recheck.report(),
            }
        return rep


def densified(toolpath: ToolPath, step: float) -> ToolPath:
    """``toolpath`` with points inserted along its cutting moves longer than ``step`` mm (tips and contacts
    on the chord, axes interpolated and normalised, the same motion): a stretch to cut out is then found
    to within ``step``. The path itself when no move is that long."""
    t, a = toolpath.tip, toolpath.axis
    cut = toolpath.move == Move.CUT
    length = np.r_[0.0, np.linalg.norm(np.diff(t, axis=0), axis=1)]
    k = np.where(cut, np.ceil(length / step).astype(int), 1)
    k[0] = 1
    if k.max() <= 1:
        return toolpath
    src = np.repeat(np.arange(toolpath.n_positions), k)  # each position, preceded by the points before it
    w = (np.arange(src.size) - np.repeat(np.cumsum(k) - k, k) + 1) / np.repeat(k, k)
    prev = np.maximum(src - 1, 0)
    wc = w[:, None]
    tips = t[prev] * (1 - wc) + t[src] * wc
    axes = a[prev] * (1 - wc) + a[src] * wc
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    inserted = w < 1
    move = np.where(inserted, Move.CUT, toolpath.move[src]).astype(np.int8)
    cc = None
    if toolpath.cc is not None:
        cc = np.asarray(toolpath.cc)[prev] * (1 - wc) + np.asarray(toolpath.cc)[src] * wc
    extras = {}
    for key, v in toolpath.extras.items():
        v = np.asarray(v)
        if v.dtype.kind == "f":  # per-position figures along the chord, like the tips
            w_ = w.reshape((-1,) + (1,) * (v.ndim - 1))
            extras[key] = v[prev] * (1 - w_) + v[src] * w_
        else:
            extras[key] = v[src]
    return ToolPath(tips, axes, move, toolpath.pass_index[src], cc, None if toolpath.feed is None else
                    np.asarray(toolpath.feed)[src], toolpath.cutter, toolpath.name, extras, toolpath.info)  # fmt: skip


def _relinked(toolpath, res, part, tool, gouge_tolerance, clearance, clear, surface=("auto", None, None)):
    """The clear stretches of ``toolpath`` joined by links checked clear (:func:`~machsurf_cad.linking.link_runs`)."""
    from .gougecheck import _faces
    from .linking import link_runs

    runs = clear_stretches(toolpath, res, ~beyond(toolpath.axis, surface[2]))
    if not runs:
        return None
    cc = toolpath.cc
    try:
        return link_runs(
            [(toolpath.tip[r], toolpath.axis[r], None if cc is None else cc[r], r) for r in runs],
            _faces(part),
            tool if tool is not None else toolpath.cutter,
            clearance=clearance,
            gouge_tolerance=gouge_tolerance,
            link_clearance=clear,
            name=toolpath.name,
            info=dict(toolpath.info, trimmed_to_clear_runs=len(runs)),
            clearance_surface=surface[0],
            clearance_axis=surface[1],
            axis_limit=surface[2],
        )
    except InputError:  # no run can be reached and left
        return None


def _length(tp: ToolPath, kinds) -> float:
    """Length (mm) of the moves of ``kinds`` (the move into each position)."""
    seg = np.linalg.norm(np.diff(tp.tip, axis=0), axis=1)
    return float(seg[np.isin(tp.move[1:], kinds)].sum())


def check_toolpath(
    toolpath: ToolPath,
    part: PartLike,
    *,
    gouge_tolerance: float = 0.01,
    on_gouge: OnGouge = "refuse",
    clearance: float = 5.0,
    tool: ToolLike | None = None,
    step: float | None = None,
    angle_step: float = 1.0,
    spacing: float | None = None,
    chunks: int = 1,
    map_chunks: MapChunks = None,
    progress: Progress | None = None,
    clearance_surface: str = "auto",
    clearance_axis: Sequence[float] | None = None,
    max_axis_angle: float | None = None,
    machine_axis: Sequence[float] = (0.0, 0.0, 1.0),
) -> PathCheck:
    """Verify ``toolpath`` against every face of ``part`` and decide what may be written.

    Parameters
    ----------
    toolpath : ToolPath
        The path as planned.
    part : sequence of Face
        Every face of the part.
    gouge_tolerance : float
        Deepest the cutting part may go into the part, mm.
    on_gouge : {"refuse", "trim", "allow"}
        A gouging path is refused (``toolpath`` None), cut to its clear stretches joined by links the
        tool-body check finds clear (:mod:`machsurf_cad.linking`: direct where clear, else over a plane,
        sphere or cylinder around the part; a stretch no clear link reaches is left out) and checked again, or kept
        with its gouges listed.
    clearance : float
        Approach and retract of the relinked stretches, mm.
    clearance_surface : {"auto", "plane", "sphere", "cylinder"}
        What the relinked stretches' links travel on (:func:`machsurf_cad.linking.surface_for`); a cylinder
        about ``clearance_axis`` (x, y, z; default the part's longest side).
    max_axis_angle : float, optional
        The machine's rotary limit, degrees: the largest angle of the tool axis from ``machine_axis`` (a
        head's B or a table's A range, the other rotary axis turning freely). Positions past it are cut out
        like gouges (``trim``) or refuse the path, and links are routed within it.
    tool, step, angle_step, spacing, chunks, map_chunks, progress
        As :func:`machsurf_cad.verify`.

    Returns
    -------
    PathCheck
    """
    if on_gouge not in ("refuse", "trim", "allow"):
        raise InputError(f"on_gouge must be refuse, trim or allow, got {on_gouge!r}")
    gouge_tolerance = positive("gouge_tolerance", gouge_tolerance)
    clearance = positive("clearance", clearance)
    clear = min(gouge_tolerance, COLLISION_CLEARANCE)
    res = verify(
        part,
        toolpath,
        tool,
        gouge_tolerance=gouge_tolerance,
        step=step,
        angle_step=angle_step,
        spacing=spacing,
        progress=progress,
        chunks=chunks,
        map_chunks=map_chunks,
        clearance=clear,
    )
    limit = None
    if max_axis_angle is not None:
        if not (np.isfinite(max_axis_angle) and 0.0 < max_axis_angle <= 180.0):
            raise InputError(f"max_axis_angle must be within 0..180 deg, got {max_axis_angle!r}")
        limit = (np.asarray(machine_axis, float), float(max_axis_angle))
    n_out = int(beyond(toolpath.axis, limit).sum())
    surface = (clearance_surface, clearance_axis, limit)
    if res.clean and not n_out:
        out = _rapids_clear(toolpath, part, tool, clearance, surface)
        return PathCheck(toolpath, out, res, None, "clean", float(clearance))
    if on_gouge == "allow" and not n_out:
        out = _rapids_clear(toolpath, part, tool, clearance, surface)
        return PathCheck(toolpath, out, res, None, "gouges allowed", float(clearance))
    if on_gouge == "trim":
        cutter = checks.tool(tool if tool is not None else toolpath.cutter)
        dense = densified(toolpath, max(0.5 * cutter.radius, 0.25))
        res_d = (
            res if dense is toolpath else verify(part, dense, tool, gouge_tolerance=gouge_tolerance, clearance=clear)
        )
        cut = _relinked(dense, res_d, part, tool, gouge_tolerance, clearance, clear, surface)
        if cut is not None and not beyond(cut.axis, limit).any():
            again = verify(part, cut, tool, gouge_tolerance=gouge_tolerance, clearance=clear)
            if again.clean:
                return PathCheck(toolpath, cut, res, again, "trimmed", float(clearance), dense, n_out)
    return PathCheck(toolpath, None, res, None, "refused", float(clearance), None, n_out)


def _rapids_clear(toolpath: ToolPath, part, tool, clearance: float, surface) -> ToolPath:
    """The path to write: its rapids that come within ``clearance`` of the part made feed moves
    (:func:`~machsurf_cad.linking.rapids_kept_clear`)."""
    from .gougecheck import _faces
    from .linking import rapids_kept_clear, surface_for

    if "n_rapids_at_feed" in toolpath.info:  # linked by link_runs: done there
        return toolpath

    faces = _faces(part)
    cutter = checks.tool(tool if tool is not None else toolpath.cutter)
    a = toolpath.axis
    fixed = a[0] if a.shape[0] and np.abs(a - a[0]).max() <= 1e-9 else None
    kind = surface[0] if fixed is not None or surface[0] != "plane" else "auto"
    geo = surface_for(faces, fixed, clearance, kind, surface[1])
    return rapids_kept_clear(toolpath, faces, cutter, clearance, (*geo, surface[2]))


def machined_area_fraction(face, planned: ToolPath, kept, *, step: float = 1.0, samples: int = 80) -> float:
    """Area-weighted share of ``face`` left to the kept positions: the face sampled on a
    ``samples x samples`` grid (inside its trimming), each sample given to the nearest point of the
    planned path's contact polyline (its cutting moves sampled every ``step`` mm), counted when that point
    lies on a kept position or on a move whose two ends are kept. ``kept``: indices into ``planned``."""
    from scipy.spatial import cKDTree

    from .geometry.face import Face
    from .threeaxis.reach import _samples

    if planned.cc is None:
        return float("nan")
    cc = np.asarray(planned.cc, float)
    keep = np.zeros(planned.n_positions, bool)
    keep[np.asarray(kept, int)] = True
    cutting = ((planned.move == Move.CUT) | (planned.move == Move.APPROACH)) & np.all(np.isfinite(cc), axis=1)
    idx = np.nonzero(cutting)[0]
    if idx.size == 0:
        return float("nan")
    mv = idx[1:][(np.diff(idx) == 1) & (planned.pass_index[idx[1:]] == planned.pass_index[idx[:-1]])]
    k = np.maximum(np.ceil(np.linalg.norm(cc[mv] - cc[mv - 1], axis=1) / step).astype(int), 1)
    j = np.repeat(np.arange(mv.size), k)
    w = ((np.arange(j.size) - np.repeat(np.cumsum(k) - k, k) + 0.5) / np.repeat(k, k))[:, None]
    pts = np.concatenate([cc[idx], cc[mv[j] - 1] * (1 - w) + cc[mv[j]] * w])
    ok = np.concatenate([keep[idx], keep[mv[j] - 1] & keep[mv[j]]])
    P, _, wt = _samples(face if isinstance(face, Face) else Face(face), samples)
    _, near = cKDTree(pts).query(P)
    return float(wt[ok[near]].sum() / wt.sum()) if wt.sum() > 0 else float("nan")


def clear_stretches(toolpath: ToolPath, result: VerifyResult, usable=None) -> list[np.ndarray]:
    """Within each pass, the index runs of consecutive cutting positions whose motion in was clear (at
    least two), among the ``usable`` ones when given (a mask: those within the machine's rotary limit)."""
    cutting = (toolpath.move == Move.CUT) | (toolpath.move == Move.APPROACH)
    ok = cutting & (result.status == CLEAR) & (True if usable is None else np.asarray(usable, bool))
    runs: list[np.ndarray] = []
    for p in np.unique(toolpath.pass_index):
        idx = np.nonzero(cutting & (toolpath.pass_index == p))[0]
        good = ok[idx]
        # split where a position is not clear or the cutting positions are not consecutive
        breaks = np.nonzero(~good[:-1] | ~good[1:] | (np.diff(idx) != 1))[0]
        for seg in np.split(np.arange(idx.size), breaks + 1):
            seg = seg[good[seg]]
            if seg.size >= 2 and np.all(np.diff(idx[seg]) == 1):
                runs.append(idx[seg])
    return runs


def clear_runs(toolpath: ToolPath, result: VerifyResult, *, clearance: float = 5.0) -> ToolPath | None:
    """The tool path cut down to its clear stretches (:func:`clear_stretches`), each relinked as its own
    pass (approach and retract ``clearance`` mm along the axis, straight rapids between).
    ``None`` when nothing clear is left. Check the result again: its new linking moves are not checked here
    (:func:`machsurf_cad.check_toolpath` links the stretches by checked links instead)."""
    runs = clear_stretches(toolpath, result)
    if not runs:
        return None
    return ToolPath.from_passes(
        [toolpath.tip[r] for r in runs],
        [toolpath.axis[r] for r in runs],
        cc=None if toolpath.cc is None else [toolpath.cc[r] for r in runs],
        extras=[{k: v[r] for k, v in toolpath.extras.items()} for r in runs] if toolpath.extras else None,
        clearance=clearance,
        cutter=toolpath.cutter,
        name=toolpath.name,
        info=dict(toolpath.info, trimmed_to_clear_runs=len(runs)),
    )
