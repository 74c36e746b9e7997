"""Beyond the paper: a minimax flank path over the whole surface with a smooth axis motion (mm, degrees).

Rule-by-rule settings (the optimum, or the minimax of one rule) are each best on their own rule, but
nothing bounds how fast the tool axis turns from one rule to the next: a machine's rotary axes
then jerk, and between two rules the interpolated tool leaves the surface. Here the rules are
visited in order and each setting minimises the largest absolute error along its rule (over ``h0``,
``gamma``, ``phi``) subject to the axis turning by at most ``max_turn_rate`` deg per mm of
travel of the rule's middle from the previous rule (a penalty in the Nelder-Mead cost, the
constraint checked afterwards). :func:`compare_with_rule_optima` puts it beside the rule-by-rule
optimum path: largest error and largest turn rate of each.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from ..glossary import renamed
from .path import FlankPath, _aggregate, rule_error
from .ruled import RuledSurface
from .settings import NoAdmissibleSetting, RuleFrame, Setting, axis_of, interference, rule_frame, tool_setting


def _turn_deg(a, b) -> float:
    return math.degrees(math.acos(float(np.clip(a @ b, -1.0, 1.0))))


def _turn_rates(axes, frames) -> np.ndarray:
    mids = np.array([0.5 * (f.p0 + f.p1) for f in frames])
    travel = np.linalg.norm(np.diff(mids, axis=0), axis=1)
    turns = np.array([_turn_deg(a, b) for a, b in zip(axes[:-1], axes[1:])])
    return turns / np.maximum(travel, 1e-12)


def axis_turn_rates(path: FlankPath) -> np.ndarray:
    """Angle between consecutive tool axes per mm of travel of the rules' middles (deg/mm)."""
    return _turn_rates(path.axis, [s.frame for s in path.settings])


@renamed(R="radius", max_turn_deg_per_mm="max_turn_rate")
def smooth_minimax_path(
    surface: RuledSurface,
    radius: float,
    *,
    side: int = 1,
    n_rules: int = 41,
    max_turn_rate: float | None = None,
    n_v: int = 41,
    overhang: float = 1.0,
) -> FlankPath:
    """Minimax settings on ``n_rules`` uniform rules with the axis turn between rules bounded.

    Parameters
    ----------
    surface : RuledSurface
        The ruled surface.
    radius : float
        Cylinder radius, mm.
    side : {1, -1}
        Tool side.
    n_rules : int
        Uniform rules along u (at least 4).
    max_turn_rate : float, optional
        Largest angle between consecutive axes per mm of travel (deg/mm). Default: 1.5 times the
        largest turn rate of the rules themselves (the surface's own twist), which any path
        following the surface needs.
    n_v : int
        Samples along each rule in the minimax cost (the reported errors use 101).
    overhang : float
        Tool length beyond each directrix, mm.

    Returns
    -------
    FlankPath
        Kind ``minimax-smooth``; its report says the bound and the largest turn rate reached.
    """
    if n_rules < 4:
        raise InputError("a smooth path needs at least 4 rules")
    if max_turn_rate is not None and not max_turn_rate > 0:
        raise InputError("max_turn_rate must be > 0 deg/mm")
    lo, hi = surface.u_range
    eps = 1e-6 * (hi - lo)
    us = np.linspace(lo + eps, hi - eps, n_rules)
    frames = [rule_frame(surface, float(u), side) for u in us]
    mids = np.array([0.5 * (f.p0 + f.p1) for f in frames])
    travel = np.linalg.norm(np.diff(mids, axis=0), axis=1)
    own = _turn_rates([f.z1 for f in frames], frames)
    bound = float(max_turn_rate) if max_turn_rate is not None else 1.5 * float(own.max())
    sets: list[Setting] = []
    prev_a = None
    for i, fr in enumerate(frames):
        prev = sets[-1] if sets else None
        limit = bound * travel[i - 1] if sets else None
        st = _smooth_rule(surface, radius, side, float(us[i]), fr, prev, prev_a, limit, n_v)
        sets.append(st)
        prev_a = st.a
    errs = tuple(rule_error(surface, st) for st in sets)
    tips, axes, lengths = zip(*(s.placement(overhang) for s in sets))
    axes = np.array(axes)
    reached = float(_turn_rates(axes, frames).max())
    smoothness = {
        "max_turn_bound_deg_per_mm": bound,
        "max_turn_reached_deg_per_mm": reached,
        "rules_own_max_turn_deg_per_mm": float(own.max()),
        "bound_met": reached <= bound * (1 + 1e-6),
    }
    return FlankPath(
        surface, float(radius), "minimax-smooth", side, tuple(sets), us, np.array(tips), axes, float(max(lengths)),
        *_aggregate(errs), float("nan"), smoothness=smoothness, rule_errors=errs,
    )  # fmt: skip


def _smooth_setting(fr: RuleFrame, radius: float, x, kind: str = "minimax-smooth") -> Setting:
    """The setting of parameters ``x = (h0 / h_p, gamma, phi)`` (rad) on the rule of frame ``fr``."""
    q, a = axis_of(fr, radius, x[0] * fr.h_p, x[1], x[2])
    return Setting(kind, fr, float(radius), q, a, float(x[0] * fr.h_p), math.degrees(x[1]), math.degrees(x[2]),
                   {"M2": fr.p0 + x[0] * fr.h_p * fr.z1})  # fmt: skip


def _smooth_rule(surface: RuledSurface, radius: float, side: int, u: float, fr: RuleFrame, prev, prev_a, limit, n_v):
    """One rule's minimax setting (Nelder-Mead), its axis turn from the previous rule's ``prev`` at most ``limit``."""
    from scipy.optimize import minimize

    try:  # start from the rule's optimum when it exists (continuing the previous one), else the standard
        st0 = tool_setting(surface, u, radius, "optimum", side=side)
    except NoAdmissibleSetting:
        st0 = tool_setting(surface, u, radius, "standard-distributed", side=side)
    x0 = np.array([st0.h0 / fr.h_p, math.radians(st0.gamma_deg), math.radians(st0.phi_deg)])
    if prev is not None:
        x_prev = np.array([prev.h0 / fr.h_p, math.radians(prev.gamma_deg), math.radians(prev.phi_deg)])

        def cost(x):
            st = _smooth_setting(fr, radius, x)
            over = max(0.0, _turn_deg(st.a, prev_a) - limit)
            return interference(surface, st, n_v=n_v).max_abs + 10.0 * radius * math.radians(over)

        starts = [x0, x_prev]
    else:

        def cost(x):
            return interference(surface, _smooth_setting(fr, radius, x), n_v=n_v).max_abs

        starts = [x0]
    best: Any = None
    for s0 in starts:
        simplex = np.vstack([s0] + [s0 + np.eye(3)[k] * (0.02, 0.005, 0.005)[k] for k in range(3)])
        opts = {"xatol": 1e-8, "fatol": 1e-8, "maxiter": 1500, "initial_simplex": simplex}
        res = minimize(cost, s0, method="Nelder-Mead", options=opts)
        if best is None or res.fun < best.fun:
            best = res
    return _smooth_setting(fr, radius, best.x)


@renamed(R="radius")
def compare_with_rule_optima(surface: RuledSurface, radius: float, *, side: int = 1, n_rules: int = 41, **kw) -> dict:
    """The smooth minimax path beside the rule-by-rule optimum path on the same rules: largest gouge,
    undercut and absolute error (mm), and largest axis turn rate (deg/mm) of each."""
    from .path import flank_path

    smooth = smooth_minimax_path(surface, radius, side=side, n_rules=n_rules, **kw)
    opt = flank_path(surface, radius, "optimum", side=side, n_rules=n_rules)

    def row(p):
        return {
            "max_gouge_mm": p.max_gouge,
            "max_undercut_mm": p.max_undercut,
            "max_abs_mm": max(p.max_gouge, p.max_undercut),
            "max_turn_deg_per_mm": float(axis_turn_rates(p).max()),
        }

    return {
        "smooth_minimax": {**row(smooth), **(smooth.smoothness or {})},
        "rule_optima": row(opt),
        "n_rules": n_rules,
    }
