"""The one tool-path type of machsurf_cad (mm, unit axes).

A :class:`ToolPath` is a sequence of tool positions. Each position is the tool tip (the
lowest point of the tool axis, OpenCAMLib's CL for a tip-referenced cutter) and the unit
tool axis pointing from the tip towards the shank, with the kind of the move that *ends*
at it (:class:`Move`), the pass it belongs to, optionally the cutter-contact point CC on
the part and the feed. Machining surfaces, flank milling and swept envelopes all produce
it; :mod:`machsurf_cad.cam.cldata` writes and reads it (CSV, APT CLDATA, JSON).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np

from ..errors import InputError
from ..results import Result, readonly
from .clearance import in_plane, over_cylinder, over_sphere


class Move(IntEnum):
    """Kind of the move that ends at a position.

    ``RAPID`` positioning at rapid traverse, ``APPROACH`` the plunge onto the start of a
    pass along the tool axis (plunge feed), ``CUT`` a cutting move (cutting feed),
    ``RETRACT`` a move that does not cut at the plunge feed: off the end of a pass along the tool axis, or a
    link move the tool may not make at rapid traverse (the whole tool within the clearance of the part).
    """

    RAPID = 0
    APPROACH = 1
    CUT = 2
    RETRACT = 3


_AXIS_UNIT_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class ToolPath(Result):
    """Tool positions: tip (n, 3) mm, unit axis (n, 3), move kind and pass index per position.

    Attributes
    ----------
    tip : ndarray (n, 3)
        Tool-tip points, mm.
    axis : ndarray (n, 3)
        Unit tool axes, tip towards shank.
    move : ndarray (n,) of int
        :class:`Move` of the move ending at each position.
    pass_index : ndarray (n,) of int
        Pass of each position (linking moves belong to the pass they reach or leave).
    cc : ndarray (n, 3) or None
        Cutter-contact points on the part, mm (NaN where there is none: linking moves).
    feed : ndarray (n,) or None
        Feed of the move in mm/min (NaN: the writer's default for the move kind).
    cutter : Cutter or None
        The tool, with its body.
    extras : mapping of str to ndarray
        Per-position arrays a producer adds (e.g. ``uv`` on the nominal face).
    info : mapping
        Producer figures (JSON-ready, unit-suffixed keys), e.g. the chordal tolerance.
    """

    tip: np.ndarray
    axis: np.ndarray
    move: np.ndarray
    pass_index: np.ndarray
    cc: np.ndarray | None = None
    feed: np.ndarray | None = None
    cutter: Any = None
    name: str = "toolpath"
    extras: Mapping[str, np.ndarray] = field(default_factory=dict)
    info: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        tip = np.asarray(self.tip, float).reshape(-1, 3)
        n = tip.shape[0]
        axis = np.asarray(self.axis, float).reshape(-1, 3)
        if axis.shape != tip.shape:
            raise InputError(f"tool path: {axis.shape[0]} axes for {n} positions")
        if not (np.all(np.isfinite(tip)) and np.all(np.isfinite(axis))):
            raise InputError("tool path: positions and axes must be finite")
        norm = np.linalg.norm(axis, axis=1)
        if n and np.abs(norm - 1).max() > _AXIS_UNIT_TOL:
            raise InputError(f"tool path: axes must be unit vectors (|a| - 1 up to {np.abs(norm - 1).max():.2g})")
        move = np.asarray(self.move, dtype=np.int8).reshape(-1)
        pidx = np.asarray(self.pass_index, dtype=np.int64).reshape(-1)
        if move.shape != (n,) or pidx.shape != (n,):
            raise InputError("tool path: one move kind and one pass index per position")
        if n and (move.min() < 0 or move.max() > 3):
            raise InputError("tool path: move kinds are 0 rapid, 1 approach, 2 cut, 3 retract")
        object.__setattr__(self, "tip", tip)
        object.__setattr__(self, "axis", axis)
        object.__setattr__(self, "move", move)
        object.__setattr__(self, "pass_index", pidx)
        if self.cc is not None:
            cc = np.asarray(self.cc, float).reshape(-1, 3)
            if cc.shape != tip.shape:
                raise InputError("tool path: one CC point per position (NaN where there is none)")
            object.__setattr__(self, "cc", cc)
        if self.feed is not None:
            feed = np.asarray(self.feed, float).reshape(-1)
            if feed.shape != (n,):
                raise InputError("tool path: one feed per position (NaN for the default)")
            object.__setattr__(self, "feed", feed)
        extras = {}
        for k, v in dict(self.extras).items():
            a = np.asarray(v)
            if a.shape[:1] != (n,):
                raise InputError(f"tool path: extra column {k!r} needs one row per position")
            extras[k] = readonly(a)
        object.__setattr__(self, "extras", extras)
        object.__setattr__(self, "info", dict(self.info))
        super().__post_init__()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_passes(
        cls,
        tips: Sequence,
        axes: Sequence,
        *,
        cc: Sequence | None = None,
        extras: Sequence | None = None,
        clearance: float = 5.0,
        cutter=None,
        name: str = "toolpath",
        info=None,
        linking: Sequence | None = None,
        safe_sphere: tuple | None = None,
        safe_plane: float | None = None,
        safe_cylinder: tuple | None = None,
    ) -> ToolPath:
        """Cutting passes linked the safe way: rapid to ``clearance`` mm above each pass start along
        its tool axis, approach along the axis, cut, retract ``clearance`` mm along the axis.

        Parameters
        ----------
        tips, axes : sequence of (m_i, 3) arrays
            Tip points (mm) and axes (normalised here) of each pass's cutting positions.
        cc : sequence of (m_i, 3) arrays, optional
            Cutter-contact points per pass.
        extras : sequence of dict, optional
            Per-pass dicts of per-position arrays (linking rows get NaN / -1).
        clearance : float
            Approach and retract distance along the tool axis, mm (> 0).
        linking : sequence of (start_dir, end_dir), optional
            Per pass, the unit directions to approach from and retract to instead of the tool
            axis (a flank tool lies along the surface: it leaves sideways, away from it).
        safe_sphere : (centre, radius), optional
            A sphere around the whole part (mm). Between passes the tool then leaves along its axis to
            the sphere, travels over it (great-circle steps of at most 5 deg, the axis pointing out of
            it, the radius raised by the chords' sag) and comes back along the next pass's axis: the
            moves over the sphere stay clear of the part; those out and back along an axis are straight
            and may still cross other parts of it (a propeller's next blade), which the tool-body
            check finds. Without it a rapid runs straight from one pass's retract point to the next
            one's approach point.
        safe_cylinder : (point, axis, radius, half_length), optional
            The same over a cylinder around the part (:func:`~machsurf_cad.part_cylinder`): helical steps of
            at most 5 deg, the axis at right angles to the cylinder's and pointing out of it; an axis that
            would leave through an end goes out beyond it first (:mod:`machsurf_cad.cam.clearance`).
        safe_plane : float, optional
            For a fixed tool axis (3 axes, 3+2): the height along the axis of a plane above the whole part
            (mm, :func:`~machsurf_cad.machining.toolpath.part_plane`). The path starts on it, and between
            passes the tool leaves along its axis up to it, travels in it and comes down along the axis
            above the next pass: no link crosses the part. Passes with another axis are linked straight.

        Examples
        --------
        >>> import numpy as np
        >>> p = ToolPath.from_passes([np.array([[0., 0, 0], [10, 0, 0]])], [np.array([[0., 0, 1]] * 2)])
        >>> [Move(m).name for m in p.move]
        ['RAPID', 'APPROACH', 'CUT', 'RETRACT']
        >>> p.tip[0].tolist(), p.tip[-1].tolist()
        ([0.0, 0.0, 5.0], [10.0, 0.0, 5.0])
        """
        if not clearance > 0:
            raise InputError("clearance must be > 0 mm")
        if len(tips) != len(axes):
            raise InputError("one axis array per pass")
        T: list = []
        A: list = []
        M: list = []
        P: list = []
        C: list = []
        X: dict[str, list] = {}
        keys = sorted(extras[0]) if extras else []
        for i, (t, a) in enumerate(zip(tips, axes)):
            t = np.asarray(t, float).reshape(-1, 3)
            a = np.asarray(a, float).reshape(-1, 3)
            if t.shape[0] < 1:
                continue
            a = a / np.linalg.norm(a, axis=1, keepdims=True)
            m = t.shape[0]
            d0, d1 = (a[0], a[-1]) if linking is None else (np.asarray(x, float) for x in linking[i])
            d0, d1 = d0 / np.linalg.norm(d0), d1 / np.linalg.norm(d1)
            link_t = None
            if safe_plane is not None and (not T or abs(float(A[-1][-1] @ d0) - 1.0) < 1e-9):
                link_t, link_a = in_plane(T[-1][-1] if T else None, t[0] + clearance * d0, d0, safe_plane)
            elif safe_sphere is not None and T:  # from the last pass's retract over the sphere to this one
                link_t, link_a = over_sphere(T[-1][-1], A[-1][-1], t[0] + clearance * d0, d0, safe_sphere)
            elif safe_cylinder is not None and T:
                link_t, link_a = over_cylinder(T[-1][-1], A[-1][-1], t[0] + clearance * d0, d0, safe_cylinder)
            if link_t is not None and len(link_t):
                T.append(link_t)
                A.append(link_a)
                M.append([Move.RAPID] * len(link_t))
                P.append(np.full(len(link_t), P[-1][-1] if P else i))
                if cc is not None:
                    C.append(np.full((len(link_t), 3), np.nan))
                for k in keys:
                    v = np.asarray(extras[i][k])  # type: ignore[index]
                    pad = np.full((len(link_t),) + v.shape[1:], np.nan if v.dtype.kind == "f" else -1, dtype=v.dtype)
                    X.setdefault(k, []).append(pad)
            T += [t[:1] + clearance * d0[None, :], t, t[-1:] + clearance * d1[None, :]]
            A += [a[:1], a, a[-1:]]
            M += [[Move.RAPID, Move.APPROACH], [Move.CUT] * (m - 1), [Move.RETRACT]]
            P.append(np.full(m + 2, i))
            if cc is not None:
                c = np.asarray(cc[i], float).reshape(-1, 3)
                C += [np.full((1, 3), np.nan), c, np.full((1, 3), np.nan)]
            for k in keys:
                v = np.asarray(extras[i][k])  # type: ignore[index]
                pad = np.full((1,) + v.shape[1:], np.nan if v.dtype.kind == "f" else -1, dtype=v.dtype)
                X.setdefault(k, []).extend([pad, v, pad])
        if not T:
            raise InputError("a tool path needs at least one pass with a position")
        if safe_plane is not None:  # the path ends on the plane: the next operation starts clear of the part
            last, a_last = np.asarray(T[-1][-1], float), np.asarray(A[-1][-1], float)
            lift = float(safe_plane) - float(last @ a_last)
            if lift > 0:
                T.append((last + lift * a_last)[None, :])
                A.append(a_last[None, :])
                M.append([Move.RAPID])
                P.append(np.full(1, P[-1][-1]))
                if cc is not None:
                    C.append(np.full((1, 3), np.nan))
                for k in keys:
                    v = np.asarray(X[k][-1])
                    X[k].append(np.full((1,) + v.shape[1:], np.nan if v.dtype.kind == "f" else -1, dtype=v.dtype))
        return cls(
            np.concatenate(T),
            np.concatenate(A),
            np.concatenate([np.asarray(x, np.int8) for x in M]),
            np.concatenate(P),
            np.concatenate(C) if cc is not None else None,
            None,
            cutter,
            name,
            {k: np.concatenate(v) for k, v in X.items()},
            dict(info or {}, clearance_mm=float(clearance))
            | ({} if safe_sphere is None else {"safe_sphere_radius_mm": float(safe_sphere[1])})
            | ({} if safe_plane is None else {"safe_plane_height_mm": float(safe_plane)})
            | ({} if safe_cylinder is None else {"safe_cylinder_radius_mm": float(safe_cylinder[2])}),
        )

    # ------------------------------------------------------------------ views
    @property
    def n_positions(self) -> int:
        return int(self.tip.shape[0])

    @property
    def n_cut(self) -> int:
        """Number of positions reached by cutting (approach end included)."""
        return int(np.count_nonzero((self.move == Move.CUT) | (self.move == Move.APPROACH)))

    @property
    def n_passes(self) -> int:
        return int(np.unique(self.pass_index).size)

    @property
    def is_multiaxis(self) -> bool:
        """True when any axis differs from +Z (then APT needs ``MULTAX/ON`` and i, j, k on GOTOs)."""
        return bool(np.any(np.abs(self.axis - [0.0, 0.0, 1.0]) > 1e-12))

    def cutting_passes(self) -> tuple[ToolPath, ...]:
        """Each pass's cutting positions (approach end and cuts) as its own :class:`ToolPath`."""
        out = []
        cutting = (self.move == Move.CUT) | (self.move == Move.APPROACH)
        for i in np.unique(self.pass_index):
            sel = np.nonzero(cutting & (self.pass_index == i))[0]
            if sel.size:
                out.append(self.subset(sel))
        return tuple(out)

    def subset(self, index) -> ToolPath:
        """The positions at ``index`` (an index or boolean array) as a new tool path."""
        idx = np.asarray(index)
        return ToolPath(
            self.tip[idx],
            self.axis[idx],
            self.move[idx],
            self.pass_index[idx],
            None if self.cc is None else self.cc[idx],
            None if self.feed is None else self.feed[idx],
            self.cutter,
            self.name,
            {k: v[idx] for k, v in self.extras.items()},
            self.info,
        )

    def cut_length(self) -> float:
        """Length of the cutting moves of the tool tip, mm."""
        seg = np.linalg.norm(np.diff(self.tip, axis=0), axis=1)
        return float(seg[self.move[1:] == Move.CUT].sum())

    def link_length(self) -> float:
        """Length of the tip's moves that do not cut (rapids, approaches, retracts), mm."""
        seg = np.linalg.norm(np.diff(self.tip, axis=0), axis=1)
        return float(seg[self.move[1:] != Move.CUT].sum())

    def report(self) -> dict:
        lo, hi = (self.tip.min(axis=0), self.tip.max(axis=0)) if self.n_positions else (np.zeros(3), np.zeros(3))
        return {
            "name": self.name,
            "n_positions": self.n_positions,
            "n_passes": self.n_passes,
            "n_cut": self.n_cut,
            "cut_length_mm": self.cut_length(),
            "link_length_mm": self.link_length(),
            "multiaxis": self.is_multiaxis,
            "tip_bbox_mm": [lo.tolist(), hi.tolist()],
            "tool": None if self.cutter is None else self.cutter.spec(),
            **self.info,
        }


__all__ = ["Move", "ToolPath"]
