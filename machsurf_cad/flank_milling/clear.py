"""Flank milling beside other faces: each rule's cylinder lifted along its axis until it clears the part's
other faces, rules it cannot clear left out.

A flank setting puts the cylinder along the whole rule with its end ``overhang`` beyond the C0 end. The
faces around the flank face (a hub under a blade, the next blade, a fillet) can lie inside that cylinder:
at the C0 end (the cylinder's end sinks into the hub) or along it. Here every other face of the part is
sampled; at each rule the samples inside the cylinder (radius R less the gouge tolerance, from its tip
upwards without end: the shank and holder are at least as wide in this test) are found, and the tool is
lifted along its axis until its end is ``clearance`` mm above the highest of them. The contact then covers
the rule from that height up: the part of the rule below it is left to another tool and reported. A rule
whose cylinder would keep less than ``min_contact`` of the rule (a neighbour along the side of the tool, or
above the rule) is left out and its u range reported. The path that is written is then checked against
every face by the whole-part check as any other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..arrays import unique_sorted
from ..errors import InputError
from ..results import Result
from .path import FlankPath, _aggregate


@dataclass(frozen=True, eq=False)
class ClearedFlank(Result):
    """A flank path with each rule's tool lifted clear of the part's other faces.

    Attributes
    ----------
    path : FlankPath or None
        The kept rules, tips lifted along their axes (None when no rule is kept).
    kept : ndarray of bool
        Per rule of the planned path: kept.
    lift : ndarray
        Per rule of the planned path: how far its tip was lifted along the axis (mm; NaN where left out).
    contact_fraction : ndarray
        Per rule: the fraction of the rule's length the lifted cylinder still covers (0 where left out).
    rules_left_out : tuple of dict
        Runs of left-out rules: their u range and the deepest intrusion there of what lifting cannot clear
        (mm, radial).
    """

    path: FlankPath | None
    kept: np.ndarray
    lift: np.ndarray
    contact_fraction: np.ndarray
    rules_left_out: tuple
    clearance: float
    sample_spacing: float

    @property
    def machined_fraction(self) -> float:
        """The fraction of the flank face's rules' length still in contact (mean over the planned rules)."""
        return float(np.mean(self.contact_fraction)) if self.contact_fraction.size else 0.0

    def report(self) -> dict:
        lifted = self.lift[self.kept]
        return {
            "n_rules_planned": int(self.kept.size),
            "n_rules_kept": int(self.kept.sum()),
            "n_rules_lifted": int(np.count_nonzero(lifted > 0)),
            "max_lift_mm": float(lifted.max()) if lifted.size else None,
            "machined_fraction": self.machined_fraction,
            "rules_left_out": list(self.rules_left_out),
            "clearance_mm": self.clearance,
            "check_sample_spacing_mm": self.sample_spacing,
        }


def clear_flank(
    path: FlankPath,
    check_faces,
    *,
    gouge_tolerance: float,
    clearance: float = 0.1,
    min_contact: float = 0.25,
    spacing: float | None = None,
) -> ClearedFlank:
    """Lift each rule's cylinder of ``path`` clear of ``check_faces`` (the part's faces other than the flank
    face), leave out the rules it cannot clear (module docstring).

    Parameters
    ----------
    path : FlankPath
        The planned path (:func:`~machsurf_cad.flank_milling.flank_path`).
    check_faces : list of Face
        The faces the tool must not enter (not the flank face itself).
    gouge_tolerance : float
        How far a check face may lie inside the cylinder (mm, radial depth).
    clearance : float
        How far above the highest sample inside its cylinder the tool's end is lifted (mm); the samples'
        spacing is added so that a surface between samples is cleared too.
    min_contact : float
        The least fraction of a rule the lifted cylinder must still cover; below it the rule is left out.
    spacing : float, optional
        Check-face sample spacing (mm); default R / 10, within [0.05, 0.5].

    Returns
    -------
    ClearedFlank
    """
    from ..gougecheck import _sampled

    if not (gouge_tolerance >= 0 and np.isfinite(gouge_tolerance)):
        raise InputError(f"gouge tolerance must be >= 0 mm, got {gouge_tolerance}")
    if not (clearance >= 0 and np.isfinite(clearance)):
        raise InputError(f"clearance must be >= 0 mm, got {clearance}")
    if not 0 < min_contact <= 1:
        raise InputError(f"min_contact must be in (0, 1], got {min_contact}")
    R = float(path.R)
    h = float(spacing) if spacing is not None else float(np.clip(R / 10, 0.05, 0.5))
    n = len(path.settings)
    lift = np.zeros(n)
    kept = np.ones(n, bool)
    depth = np.zeros(n)
    faces = list(check_faces)
    limit = np.zeros(n)
    span = np.zeros((n, 2))
    for i, st in enumerate(path.settings):
        t_end = sorted(float((p - path.tip[i]) @ path.axis[i]) for p in (st.frame.p0, st.frame.p1))
        span[i] = t_end
        limit[i] = t_end[0] + (1 - min_contact) * (t_end[1] - t_end[0])
    if faces:
        smp, tree = _sampled(faces, "", h, 20_000_000)
        body = _Body(smp.P, tree, R, float(gouge_tolerance), float(clearance) + h)
        for i in range(n):
            need, d = body.need(path.tip[i], path.axis[i], span[i, 1], limit[i])
            if need > limit[i]:
                kept[i], depth[i] = False, d
            else:
                lift[i] = max(need, 0.0)
        _clear_moves(path, body, kept, lift, limit, span, h)
    lift[~kept] = np.nan
    frac = np.where(kept, np.clip((span[:, 1] - np.maximum(np.nan_to_num(lift), span[:, 0]))
                                  / np.maximum(span[:, 1] - span[:, 0], 1e-12), 0.0, 1.0), 0.0)  # fmt: skip
    out_path = _kept_path(path, kept, lift) if kept.any() else None
    return ClearedFlank(out_path, kept, lift, frac, _runs_left_out(path, kept, depth), float(clearance), h)


class _Body:
    """The tool as a cylinder of radius R from its tip upwards without end, against part samples ``P``."""

    def __init__(self, P, tree, R, gouge_tolerance, margin):
        self.P, self.tree, self.R, self.tol, self.margin = P, tree, R, gouge_tolerance, margin

    def need(self, tip, a, t_top, limit):
        """How far the tip must rise along ``a`` for no sample to lie inside (``margin`` mm above the
        highest inside, <= 0: none inside), and the deepest radial intrusion of the samples that rising to
        ``limit`` would not clear."""
        R = self.R
        centres = tip + np.outer(np.arange(0.0, t_top + 3 * R, R), a)
        near = unique_sorted(np.concatenate([np.asarray(k, int) for k in self.tree.query_ball_point(centres, 1.5 * R)]))
        if near.size == 0:
            return -np.inf, 0.0
        d = self.P[near] - tip
        t = d @ a
        rho = np.linalg.norm(d - np.outer(t, a), axis=1)
        inside = (rho < R - self.tol) & (t > -self.margin)
        if not inside.any():
            return -np.inf, 0.0
        need = float(t[inside].max()) + self.margin
        blocking = inside & (t + self.margin > limit)
        return need, float((R - rho[blocking]).max()) if blocking.any() else 0.0


def _clear_moves(path: FlankPath, body: _Body, kept, lift, limit, span, h: float, rounds: int = 8) -> None:
    """The motion between neighbouring kept rules (tip and axis interpolated, every ``h`` mm) cleared too:
    where a position between two rules has a sample inside, both rules are lifted by as much (rules lifted
    past their limit are left out, and their neighbours then checked)."""
    jumps = {int(np.searchsorted(path.u, d["u"])) for d in path.discontinuities}
    for _ in range(rounds):
        changed = False
        idx = np.nonzero(kept)[0]
        for i, j in zip(idx[:-1], idx[1:]):
            if j != i + 1 or j in jumps:  # not one cutting move: a link joins them
                continue
            t0, t1 = path.tip[i] + lift[i] * path.axis[i], path.tip[j] + lift[j] * path.axis[j]
            turn = float(np.arccos(np.clip(path.axis[i] @ path.axis[j], -1, 1)))
            k = int(np.ceil(max(np.linalg.norm(t1 - t0), turn * (span[i, 1] + body.R)) / h))
            for s in np.arange(1, k) / k:
                a = (1 - s) * path.axis[i] + s * path.axis[j]
                a /= np.linalg.norm(a)
                need, _ = body.need((1 - s) * t0 + s * t1, a, max(span[i, 1], span[j, 1]), np.inf)
                if need > 1e-6:
                    for r in (i, j):
                        lift[r] += need + 1e-6
                        kept[r] = lift[r] <= limit[r]
                    changed = True
                    break
        if not changed:
            return
    # still not clear after the rounds: leave out the rules of the moves that are not
    idx = np.nonzero(kept)[0]
    for i, j in zip(idx[:-1], idx[1:]):
        if j == i + 1 and j not in jumps:
            t0, t1 = path.tip[i] + lift[i] * path.axis[i], path.tip[j] + lift[j] * path.axis[j]
            mid_a = path.axis[i] + path.axis[j]
            if body.need(0.5 * (t0 + t1), mid_a / np.linalg.norm(mid_a), span[i, 1], np.inf)[0] > 1e-6:
                kept[i] = kept[j] = False


def _kept_path(path: FlankPath, kept: np.ndarray, lift: np.ndarray) -> FlankPath:
    """``path`` with the kept rules only, tips lifted, and a discontinuity where rules were left out."""
    from dataclasses import replace

    idx = np.nonzero(kept)[0]
    tip = path.tip[idx] + lift[idx, None] * path.axis[idx]
    errs = tuple(path.rule_errors[i] for i in idx) if path.rule_errors else ()
    jumps = [dict(d) for d in path.discontinuities]
    for k in range(1, idx.size):
        if idx[k] != idx[k - 1] + 1:  # rules left out between: the path leaves and comes back
            jumps.append({"u": float(path.u[idx[k]]), "why": "rules left out: the tool does not clear the part"})
    return replace(
        path,
        settings=tuple(path.settings[i] for i in idx),
        u=path.u[idx],
        tip=tip,
        axis=path.axis[idx],
        rule_errors=errs,
        **(dict(zip(("max_gouge", "max_undercut", "worst"), _aggregate(errs))) if errs else {}),
        discontinuities=tuple(sorted(jumps, key=lambda d: d["u"])),
    )


def _runs_left_out(path: FlankPath, kept: np.ndarray, depth: np.ndarray) -> tuple:
    out = []
    i, n = 0, kept.size
    while i < n:
        if kept[i]:
            i += 1
            continue
        j = i
        while j + 1 < n and not kept[j + 1]:
            j += 1
        out.append({"u_range": [float(path.u[i]), float(path.u[j])], "n_rules": j - i + 1,
                    "deepest_intrusion_mm": float(depth[i : j + 1].max())})  # fmt: skip
        i = j + 1
    return tuple(out)
