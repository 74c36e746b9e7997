"""Whole-surface flank milling: settings on every rule, CL data, swept envelope, radius search (mm, deg).

The rules are chosen adaptively along u: a span is split until the axis interpolated linearly
between its two settings stays within ``tolerance`` of the exact setting at its middle (over
the tool's working length). The tool motion is ``S(a, t) = P(t) + a A(t)``, ``P`` the tool-tip
point (the axis point level with the C0 end of the rule, minus ``overhang``), ``A`` the axis
towards C1, both interpolated by cubic splines through the settings. For a cylinder the
envelope is ``X = S + R n`` with ``n`` the unit normal of S pointing towards the surface (the
envelope paper's eq. (21) with r' = 0); it is fitted by the certified engine.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..cam.toolpath import ToolPath
from ..chunking import check_chunks, map_pieces
from ..errors import InputError
from ..glossary import renamed
from ..results import Result
from ..typing import MapChunks, ProgressLike
from .ruled import RuledSurface
from .settings import NoAdmissibleSetting, Setting, interference, tool_setting


@dataclass(frozen=True, eq=False)
class FlankPath(Result):
    """Settings along the surface and the CL data derived from them."""

    surface: RuledSurface
    R: float
    kind: str
    side: int
    settings: tuple
    u: np.ndarray
    tip: np.ndarray
    axis: np.ndarray
    length: float
    max_gouge: float
    max_undercut: float
    worst: dict
    step_tolerance: float
    discontinuities: tuple = ()
    smoothness: dict | None = None
    """For a smooth minimax path: the axis turn bound and the turn rate reached (deg/mm)."""
    rule_errors: tuple = ()
    """Per rule: ``(max_gouge, max_undercut, worst)`` of its interference (101 samples along the rule)."""

    @property
    def fallback_u(self) -> np.ndarray:
        """Rules where the requested setting does not exist and Rubio's standard-distributed one is used."""
        return np.array([s.frame.u_p for s in self.settings if s.kind != self.kind], float)

    def segment_slices(self) -> list[slice]:
        """Runs of rules with no discontinuity between them (one per continuous branch of the setting)."""
        cuts = sorted({int(np.searchsorted(self.u, d["u"])) for d in self.discontinuities})
        edges = [0] + [c for c in cuts if 0 < c < len(self.u)] + [len(self.u)]
        return [slice(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]

    def segments(self) -> tuple[FlankPath, ...]:
        """The path cut at its discontinuities: continuous sub-paths (their own gouge and undercut)."""
        if not self.discontinuities:
            return (self,)
        out = []
        for sl in self.segment_slices():
            errs = self.rule_errors[sl]
            out.append(
                FlankPath(
                    self.surface, self.R, self.kind, self.side, self.settings[sl], self.u[sl], self.tip[sl],
                    self.axis[sl], self.length, *_aggregate(errs), self.step_tolerance, rule_errors=errs,
                )
            )  # fmt: skip
        return tuple(out)

    @property
    def contact_points(self) -> np.ndarray:
        """Per rule the contact M2 of its setting (mm; NaN where the setting has none)."""
        return np.array([s.contacts.get("M2", [np.nan] * 3) for s in self.settings], float).reshape(-1, 3)

    def toolpath(self, cutter=None, *, clearance: float = 5.0) -> ToolPath:
        """The settings as 5-axis passes of the one :class:`~machsurf_cad.cam.ToolPath` type, one pass per
        continuous segment (retract and approach between them): tips on the axis below the C0 end
        (``overhang`` mm beyond the surface), axes towards C1 (tip to shank), CC at the rule contact M2
        where the setting has one. The tool lies along the surface, so it approaches and leaves
        sideways, away from the rule (from the contact M2 towards its axis), not along its axis (which
        would slide it along the surface)."""
        from ..cutters import FlatEndMill

        c = cutter if cutter is not None else FlatEndMill(2 * self.R, self.length)
        cc = self.contact_points
        extras = {
            "u": self.u,
            "gamma_deg": np.array([s.gamma_deg for s in self.settings]),
            "h0_mm": np.array([s.h0 for s in self.settings]),
        }
        slices = self.segment_slices()
        away = leave_direction
        return ToolPath.from_passes(
            [self.tip[sl] for sl in slices],
            [self.axis[sl] for sl in slices],
            cc=[cc[sl] for sl in slices],
            extras=[{k: v[sl] for k, v in extras.items()} for sl in slices],
            clearance=clearance,
            cutter=c,
            name=f"flank_{self.kind}",
            info={
                "setting": self.kind,
                "n_rules": len(self.settings),
                "step_tolerance_mm": self.step_tolerance,
                "n_segments": len(slices),
                "n_fallback_rules": int(self.fallback_u.size),
            },
            linking=[(away(self.settings[sl.start]), away(self.settings[sl.stop - 1])) for sl in slices],
        )

    def report(self) -> dict:
        return {
            "setting": self.kind,
            "R_mm": self.R,
            "side": self.side,
            "n_rules": len(self.settings),
            "u": self.u.tolist(),
            "tool_length_mm": self.length,
            "step_tolerance_mm": self.step_tolerance,
            "max_gouge_mm": self.max_gouge,
            "max_undercut_mm": self.max_undercut,
            "worst": self.worst,
            "discontinuities": list(self.discontinuities),
            "n_segments": len(self.segment_slices()),
            "segments_u": [[float(self.u[sl.start]), float(self.u[sl.stop - 1])] for sl in self.segment_slices()],
            "smoothness": self.smoothness,
            "n_fallback_rules": int(self.fallback_u.size),
            "fallback_u_range": (
                [float(self.fallback_u.min()), float(self.fallback_u.max())] if self.fallback_u.size else None
            ),
        }


def leave_direction(s: Setting) -> np.ndarray:
    """From the rule contact (M2, else the rule's middle) towards the axis, across it: the side a flank tool
    leaves the face by (unit)."""
    m2 = np.asarray(s.contacts.get("M2", s.frame.p0 + 0.5 * (s.frame.p1 - s.frame.p0)), float)
    w = s.q - m2
    w = w - (w @ s.a) * s.a
    return w / np.linalg.norm(w)


@renamed(R="radius", kind="setting")
def flank_path(
    surface: RuledSurface,
    radius: float,
    setting: str = "optimum",
    *,
    side: int = 1,
    tolerance: float = 0.01,
    overhang: float = 1.0,
    max_rules: int = 2000,
    min_rules: int = 9,
    n_rules: int | None = None,
    progress: ProgressLike = None,
    chunks: int = 1,
    map_chunks: MapChunks = None,
) -> FlankPath:
    """Settings on rules along u and their CL points and axes.

    With ``n_rules`` the rules are uniform; otherwise the step follows ``tolerance`` (mm): a span
    is halved until the axis interpolated between its ends is within the tolerance of the exact
    setting at its middle, down to 1e-5 of the range (a jump of the setting there is reported
    in ``discontinuities``). Each setting starts from its neighbour's (continuation).

    Parameters
    ----------
    surface : RuledSurface
        The ruled surface.
    radius : float
        Cylinder radius, mm.
    setting : {"standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax"}
        The setting on each rule.
    side : {1, -1}
        Tool side.
    tolerance : float
        Step criterion, mm.
    overhang : float
        Tool length beyond each directrix, mm.
    progress : Progress, optional
        ``progress(done, total, message)``.
    chunks : int
        Split the surface into this many spans of the initial rules, refined and checked
        independently (each span starts from the same settings as a single run: the same figures,
        unless the rule budget ``max_rules`` is reached, which each span then meets on its own).
    map_chunks : callable, optional
        ``map``-like callable running the spans (e.g. :func:`machsurf_cad.batchrun.dask_map`).

    Returns
    -------
    FlankPath
        Settings, tips and axes per rule, max gouge and undercut; ``toolpath()`` gives the
        :class:`~machsurf_cad.cam.ToolPath` (one pass per continuous segment). Where the setting
        does not exist on a rule (the optimum beyond its existence limit) Rubio's standard-distributed
        setting is used there (``fallback_u``); where the setting jumps between neighbouring rules
        (a branch ends, or a fallback begins) the path is cut into segments (``discontinuities``,
        ``segments()``).

    Examples
    --------
    >>> from machsurf_cad import examples
    >>> p = flank_path(examples.liu_ruled(), 10.0, "optimum", n_rules=9)
    >>> len(p.settings), p.max_gouge < 0.5
    (9, True)
    """
    if not tolerance > 0:
        raise InputError("tolerance must be > 0 mm")
    check_chunks(chunks)
    lo, hi = surface.u_range
    eps = 1e-6 * (hi - lo)  # sqrt-type directrices can be singular exactly at the ends
    us = list(np.linspace(lo + eps, hi - eps, n_rules or min_rules))
    sets0: list[Setting] = []
    prev = None
    for u in us:  # sweep once in order so each rule continues from the previous one
        prev = setting_or_fallback(surface, float(u), radius, setting, side, prev)
        sets0.append(prev)
    n_chunks = max(1, min(int(chunks), len(us) - 1))
    cuts = np.linspace(0, len(us) - 1, n_chunks + 1).astype(int)
    spans = [(us[a : b + 1], sets0[a : b + 1], k > 0) for k, (a, b) in enumerate(zip(cuts[:-1], cuts[1:]))]
    job = functools.partial(
        _refine_span, surface, float(radius), setting, side, float(tolerance), float(overhang), n_rules is None,
        max_rules - len(us), 1e-5 * (hi - lo), progress if n_chunks == 1 else None,
    )  # fmt: skip
    parts = map_pieces(job, spans, map_chunks)
    us = [u for p in parts for u in p[0]]
    sets = tuple(x for p in parts for x in p[1])
    jumps = [j for p in parts for j in p[2]]
    errs = tuple(e for p in parts for e in p[3])
    tips, axes, lengths = zip(*(s.placement(overhang) for s in sets))
    return FlankPath(
        surface,
        float(radius),
        setting,
        side,
        sets,
        np.array(us),
        np.array(tips),
        np.array(axes),
        float(max(lengths)),
        *_aggregate(errs),
        float(tolerance),
        tuple(jumps),
        rule_errors=errs,
    )


def rule_error(surface: RuledSurface, st: Setting) -> tuple:
    """``(max_gouge, max_undercut, worst)`` of a setting's interference along its rule (101 samples)."""
    e = interference(surface, st, n_v=101)
    return e.max_gouge, e.max_undercut, {**e.worst(), "rule_u": st.frame.u_p}


def _aggregate(errs) -> tuple[float, float, dict]:
    """Largest gouge, largest undercut and the worst point over rules' ``rule_error`` figures."""
    worst: dict = max((w for _, _, w in errs), key=lambda w: abs(w["e_mm"]), default={})
    return max((g for g, _, _ in errs), default=0.0), max((u for _, u, _ in errs), default=0.0), worst


def setting_or_fallback(surface, u, R, kind, side, start=None):
    """The setting ``kind`` on the rule at ``u``, continuing from ``start``; where it does not exist (the
    optimum beyond its existence limit), Rubio's standard-distributed setting, so that a whole surface
    always gets a path (the rules are listed in :attr:`FlankPath.fallback_u` and the report)."""
    try:
        return tool_setting(
            surface, u, R, kind, side=side, start=start if start is None or start.kind == kind else None
        )
    except NoAdmissibleSetting:
        return tool_setting(surface, u, R, "standard-distributed", side=side)


def _refine_span(surface, R, kind, side, tolerance, overhang, adaptive, budget, min_span, progress, span):
    """Rules between consecutive initial rules of one span (``(us, settings, drop_first)``), split
    until the interpolated axis is within ``tolerance``, and their interference. Module level: spans
    travel to workers; each span sees exactly what a single run sees there (same starts)."""
    us0, sets0, drop_first = span
    us = [float(u) for u in us0]
    cache: dict[float, Setting] = {u: st for u, st in zip(us, sets0)}

    def setting(u, near=None):
        key = float(u)
        if key not in cache:
            cache[key] = setting_or_fallback(surface, key, R, kind, side, near)
        return cache[key]

    jumps = []
    n_added = 0
    if adaptive:
        i = 0
        while i < len(us) - 1:
            a, b = us[i], us[i + 1]
            m = 0.5 * (a + b)
            sa, sb = setting(a), setting(b)
            sm = setting(m, sa)
            (ta, aa, La), (tb, ab, Lb), (tm, am, Lm) = (x.placement(overhang) for x in (sa, sb, sm))
            L = max(La, Lb, Lm)
            ti, ai = 0.5 * (ta + tb), (aa + ab) / np.linalg.norm(aa + ab)
            err = max(np.linalg.norm((ti + s_ * ai) - (tm + s_ * am)) for s_ in (0.0, 0.5 * L, L))
            if err > tolerance and n_added < budget and (b - a) > min_span:
                us.insert(i + 1, m)
                n_added += 1
                continue
            if err > tolerance:
                jumps.append({"u": float(m), "axis_jump_mm": float(err)})
            if progress is not None:
                progress(i, len(us), "settings along the surface")
            i += 1
    if drop_first:  # the previous span ends on this rule
        us = us[1:]
    sets = [setting(u) for u in us]
    return us, sets, jumps, [rule_error(surface, st) for st in sets]


# ----------------------------------------------------------------------------- envelope
def envelope_map(path: FlankPath):
    """The exact envelope map ``X(a, t)`` of the cylinder along the (spline-interpolated) motion.

    The envelope is the sweep package's eq. (21) (:class:`~machsurf_cad.sweep.Envelope`) for the
    cylinder's sphere family (r' = 0), on the sheet facing the surface. Returns ``(f, bounds)``
    with ``f(as_, ts) -> (len(as_), len(ts), 3)``: ``a`` along the axis from the tip (mm), ``t``
    the rule parameter u.
    """
    from scipy.interpolate import CubicSpline

    from ..cutters import FlatEndMill
    from ..sweep.core import Envelope, Motion

    if len(path.settings) < 4:
        raise InputError("the envelope needs at least 4 rules")
    P = CubicSpline(path.u, path.tip, axis=0)
    A = CubicSpline(path.u, path.axis, axis=0)
    dP, dA = P.derivative(), A.derivative()
    motion = Motion(
        P, A, (float(path.u[0]), float(path.u[-1])), "flank motion (cubic splines through the settings)", dP, dA
    )
    cutter = FlatEndMill(2 * path.R, path.length)
    seg = cutter.sweep_segment()
    # the sheet facing the surface: the rules lie on that side of the tool (checked at every rule)
    ts = path.u
    probe = Envelope(motion, cutter, seg, 1)
    n, _ = probe.normals(np.full(ts.shape, 0.5 * path.length), ts)
    S, _, _, _, _, _ = probe.frame(np.full(ts.shape, 0.5 * path.length), ts)
    to_surf = path.surface.evaluate(ts, np.full(ts.shape, 0.5)) - S
    side = 1 if float(np.sum(np.sign(np.einsum("ij,ij->i", n, to_surf)))) >= 0 else -1
    env = Envelope(motion, cutter, seg, side, (0.0, path.length), "flank_envelope")
    return env.grid, (0.0, path.length, float(path.u[0]), float(path.u[-1]))


def envelope_surface(path: FlankPath, tolerance: float = 1e-3, max_poles: int = 40000):
    """The envelope as a certified B-spline surface (u along the axis, v along the motion)."""
    from ..approx import fit_surface

    f, bounds = envelope_map(path)
    knots = path.u[1:-1]
    breaks = ((np.array([]), np.array([], int)), (knots, np.full(knots.size, 1)))
    return fit_surface(f, bounds, tolerance=tolerance, max_poles=max_poles, name="flank_envelope", breaks=breaks)


def position_deviation(path: FlankPath, n_u: int = 121, n_v: int = 61, refine: int = 4):
    """Signed deviation of the nominal from the tool positions, brute force (mm): for every
    nominal sample, min over densely interpolated positions of (distance to the axis - R).
    Negative = gouge, positive = undercut. Returns (points (n_u, n_v, 3), e (n_u, n_v))."""
    from scipy.interpolate import CubicSpline

    surf = path.surface
    us = np.linspace(path.u[0], path.u[-1], n_u)
    vs = np.linspace(0, 1, n_v)
    pts = surf.grid_map(us, vs)
    tt = np.linspace(path.u[0], path.u[-1], refine * len(path.u))
    P = CubicSpline(path.u, path.tip, axis=0)(tt)
    A = CubicSpline(path.u, path.axis, axis=0)(tt)
    A /= np.linalg.norm(A, axis=1, keepdims=True)
    best = np.full(pts.shape[:2], np.inf)
    for p, a in zip(P, A):
        w = pts - p
        w = w - np.einsum("ijk,k->ij", w, a)[..., None] * a
        best = np.minimum(best, np.linalg.norm(w, axis=-1) - path.R)
    return pts, best


# ----------------------------------------------------------------------------- radius search
def whole_surface_error(surface: RuledSurface, R: float, kind: str, side: int, n_rules: int = 21) -> float:
    """Largest |interference| over ``n_rules`` rules (mm); inf where no admissible setting exists."""
    lo, hi = surface.u_range
    eps = 1e-6 * (hi - lo)
    worst = 0.0
    prev = None
    for u in np.linspace(lo + eps, hi - eps, n_rules):
        try:
            s = tool_setting(surface, float(u), R, kind, side=side, start=prev)  # continuation along u
        except NoAdmissibleSetting:
            return math.inf
        prev = s
        worst = max(worst, interference(surface, s, n_v=81).max_abs)
    return worst


def radius_range(
    surface: RuledSurface,
    tolerance: float,
    *,
    kind: str = "optimum",
    side: int = 1,
    r_min: float = 1.0,
    r_max: float = 200.0,
    n_scan: int = 24,
    n_rules: int = 21,
    rel_precision: float = 1e-3,
) -> dict:
    """Smallest and largest tool radius (mm) keeping the whole surface within ``tolerance`` (mm).

    Scans R on a log grid, then bisects each boundary of the feasible set. Returns the range,
    and every iteration ``(R, error)`` in order.
    """
    if not tolerance > 0 or not 0 < r_min < r_max:
        raise InputError("need tolerance > 0 and 0 < r_min < r_max (mm)")
    its = []

    def err(R):
        e = whole_surface_error(surface, R, kind, side, n_rules)
        its.append({"R_mm": float(R), "max_error_mm": e})
        return e

    grid = np.geomspace(r_min, r_max, n_scan)
    ok = [err(R) <= tolerance for R in grid]
    if not any(ok):
        return {
            "feasible": False,
            "R_min_mm": None,
            "R_max_mm": None,
            "iterations": its,
            "message": f"no radius in [{r_min:g}, {r_max:g}] mm keeps the surface within {tolerance:g} mm",
        }
    first = ok.index(True)
    last = len(ok) - 1 - ok[::-1].index(True)

    def bisect(a, b, want_low):
        # a infeasible, b feasible (or vice versa); converge on the boundary
        while abs(b - a) > rel_precision * b:
            m = math.sqrt(a * b)
            if (err(m) <= tolerance) == want_low:
                b = m
            else:
                a = m
        return b

    R_lo = grid[first] if first == 0 else bisect(grid[first - 1], grid[first], True)
    R_hi = grid[last] if last == len(grid) - 1 else bisect(grid[last + 1], grid[last], True)
    return {
        "feasible": True,
        "R_min_mm": float(R_lo),
        "R_max_mm": float(R_hi),
        "scan": [float(x) for x in grid],
        "iterations": its,
        "note": ("bounded by the scan range" if first == 0 or last == len(grid) - 1 else ""),
        "contiguous": all(ok[first : last + 1]),
    }


def envelope_deviation(path: FlankPath, env_surface, n: int = 121):
    """Deviation of the nominal ruled surface from the swept envelope (mm): gouge negative, as everywhere.

    The magnitude is the distance to the fitted envelope surface; where the closest envelope
    point is on its start or end edge (the first or last tool position), the distance to that
    whole cylinder is used instead of the distance to the edge curve. The sign says whether the
    nominal point is inside the swept tool (gouge, -) or outside (undercut, +), decided by the
    densely interpolated tool positions. Returns a :class:`~machsurf_cad.measure.DeviationResult`.
    """
    from ..measure import DeviationResult, deviation_stats, project_points

    pts_grid, brute = position_deviation(path, n_u=n, n_v=n)
    pts = pts_grid.reshape(-1, 3)
    proj = project_points(env_surface, pts)
    mag = np.linalg.norm(pts - proj.foot, axis=1)
    t0, t1 = env_surface.bounds[2], env_surface.bounds[3]
    at_end = proj.on_boundary & (
        (np.abs(proj.uv[:, 1] - t0) < 1e-9 * (t1 - t0)) | (np.abs(proj.uv[:, 1] - t1) < 1e-9 * (t1 - t0))
    )
    if np.any(at_end):
        ends = []
        for k in (0, -1):
            w = pts - path.tip[k]
            w = w - (w @ path.axis[k])[:, None] * path.axis[k]
            ends.append(np.abs(np.linalg.norm(w, axis=1) - path.R))
        mag = np.where(at_end, np.minimum(ends[0], ends[1]), mag)
    sign = np.where(brute.ravel() < 0, -1.0, 1.0)
    signed = sign * mag
    uu, vv = np.meshgrid(np.linspace(path.u[0], path.u[-1], n), np.linspace(0, 1, n), indexing="ij")
    uv = np.stack([uu.ravel(), vv.ravel()], 1)
    stats = deviation_stats(signed, pts, uv)
    stats["n_measured_to_end_positions"] = int(at_end.sum())
    stats["sign_convention"] = "gouge negative (nominal inside the swept tool), undercut positive"
    return DeviationResult(pts, signed, uv, proj.foot, proj.on_boundary, (n, n), None, path.step_tolerance, stats)


def positions_deviation(path: FlankPath, n: int = 121):
    """Deviation of the nominal from the swept tool measured on the tool positions themselves (mm, gouge
    negative): :func:`position_deviation` (every nominal sample against densely interpolated
    positions) as a :class:`~machsurf_cad.measure.DeviationResult`. The map of a segment whose swept
    envelope could not be fitted (a folding motion); needs at least 2 rules."""
    from ..measure import DeviationResult, deviation_stats

    if len(path.settings) < 2:
        raise InputError("a deviation map needs at least 2 rules")
    pts_grid, brute = position_deviation(path, n_u=n, n_v=n)
    pts = pts_grid.reshape(-1, 3)
    signed = brute.ravel()
    uu, vv = np.meshgrid(np.linspace(path.u[0], path.u[-1], n), np.linspace(0, 1, n), indexing="ij")
    uv = np.stack([uu.ravel(), vv.ravel()], 1)
    stats = deviation_stats(signed, pts, uv)
    stats["measured_to"] = "the interpolated tool positions (no envelope surface)"
    stats["sign_convention"] = "gouge negative (nominal inside the swept tool), undercut positive"
    return DeviationResult(
        pts, signed, uv, pts.copy(), np.zeros(len(pts), bool), (n, n), None, path.step_tolerance, stats
    )
