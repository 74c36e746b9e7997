"""Flank milling with several cylinder diameters: each stretch of the ruled face by the largest tool that clears
the part's other faces there (mm).

Every tool's settings are computed on the whole face (:func:`~machsurf_cad.flank_milling.flank_path`) and
lifted clear of the check faces (:func:`~machsurf_cad.flank_milling.clear.clear_flank`). The rules are then
given out largest tool first: a rule stands for the stretch of the face between the midpoints to its
neighbours (its cell in ``u``); a smaller tool keeps the rules it clears whose cells no larger tool's kept
rule covers. A kept rule's cell counts as machined in the fraction of its length its cylinder still
touches after the lift (``contact_fraction``); a stretch no tool clears is reported by its ``u`` range.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..results import Result


@dataclass(frozen=True, eq=False)
class FlankToolPass(Result):
    """One tool's share of a flank face.

    Attributes
    ----------
    cutter : Cutter
        The cylinder.
    cleared : ClearedFlank
        Its settings on the whole face, lifted clear of the part or left out.
    path : FlankPath or None
        The rules it machines (those no larger tool machines), None when it machines none.
    toolpath : ToolPath or None
        Those rules linked clear of the part.
    u_machined : tuple of (float, float)
        The ``u`` ranges of the face its rules stand for.
    machined_fraction : float
        The share of the face's ``u`` range it machines, weighted by each rule's contact fraction.
    """

    cutter: Any
    cleared: Any
    path: Any
    toolpath: Any
    u_machined: tuple
    machined_fraction: float
    why_none: str = ""
    """Where it machines nothing: why (it clears no rule, a larger tool machines every rule it clears, or no
    clear link reaches its stretches)."""

    def report(self) -> dict:
        return {
            "tool": self.cutter.spec(),
            "n_rules_kept_alone": int(self.cleared.kept.sum()),
            "n_rules_machined": 0 if self.path is None else len(self.path.settings),
            "u_machined": [list(r) for r in self.u_machined],
            "machined_fraction": self.machined_fraction,
            "toolpath": None if self.toolpath is None else self.toolpath.report(),
            "why_none": self.why_none or None,
        }


def _cells(u: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Per rule the ``u`` interval it stands for: between the midpoints to its neighbours (the ends: the range's)."""
    mid = 0.5 * (u[1:] + u[:-1])
    return np.column_stack([np.r_[lo, mid], np.r_[mid, hi]])


def _covered(u: np.ndarray, taken: list) -> np.ndarray:
    """Which of the parameters ``u`` lie in a cell already taken by a larger tool."""
    out = np.zeros(u.size, bool)
    for a, b in taken:
        out |= (u >= a) & (u <= b)
    return out


def _ranges(cells: np.ndarray) -> tuple:
    """Touching cells merged into ranges."""
    out: list[list[float]] = []
    for a, b in cells:
        if out and abs(a - out[-1][1]) <= 1e-12 * max(1.0, abs(a)):
            out[-1][1] = float(b)
        else:
            out.append([float(a), float(b)])
    return tuple((a, b) for a, b in out)


def by_diameter(surf, cutters, whole_path, check_faces, *, gouge_tolerance: float, link) -> tuple:
    """The face shared among ``cutters`` (largest first, module docstring): one :class:`FlankToolPass` each.
    ``whole_path(cutter)`` gives a tool's settings on the whole face; ``link(path, cutter)`` its linked tool
    path. The machined fractions are measured on 4001 points of the ``u`` range, each given to the first tool
    whose kept rule's cell holds it (cells of two tools may overlap by part of a rule step)."""
    from .clear import _kept_path, clear_flank

    lo, hi = surf.u_range
    grid = np.linspace(lo, hi, 4001)
    owner = np.full(grid.size, -1)
    weight = np.zeros(grid.size)
    taken: list = []
    parts = []
    for k, cutter in enumerate(sorted(cutters, key=lambda c: -c.D)):
        path = whole_path(cutter)
        cleared = clear_flank(path, list(check_faces), gouge_tolerance=gouge_tolerance)
        cells = _cells(path.u, lo, hi)
        mine = cleared.kept & ~_covered(path.u, taken)
        sub = tp = None
        why = "it clears no rule" if not cleared.kept.any() else "a larger tool machines every rule it clears"
        if mine.any():
            sub = _kept_path(path, mine, np.nan_to_num(cleared.lift))
            try:
                tp, why = link(sub, cutter), ""
            except InputError:  # no clear way into or out of its stretches: left to the smaller tools
                sub, mine = None, np.zeros_like(mine)
                why = "no clear link reaches or leaves the stretches it clears"
        for (a, b), w in zip(cells[mine], cleared.contact_fraction[mine]):
            at = (owner < 0) & (grid >= a) & (grid <= b)
            owner[at], weight[at] = k, w
        taken.extend(map(tuple, cells[mine]))
        parts.append((cutter, cleared, sub, tp, _ranges(cells[mine]), why))
    return tuple(
        FlankToolPass(cutter, cleared, sub, tp, ranges, float(np.where(owner == k, weight, 0.0).mean()), why)
        for k, (cutter, cleared, sub, tp, ranges, why) in enumerate(parts)
    )


def left_out(passes, lo: float, hi: float) -> tuple:
    """The ``u`` ranges no tool machines."""
    taken = sorted(r for p in passes for r in p.u_machined)
    gaps, at = [], lo
    for a, b in taken:
        if a > at + 1e-12 * max(1.0, abs(a)):
            gaps.append((float(at), float(a)))
        at = max(at, b)
    if at < hi - 1e-12 * max(1.0, abs(hi)):
        gaps.append((float(at), float(hi)))
    return tuple(gaps)


__all__ = ["FlankToolPass", "by_diameter", "left_out"]
