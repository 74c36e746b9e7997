"""Flank-milling settings of a cylindrical cutter on a rule, and their interference (mm, degrees).

After Redonnet, Rubio, Dessein (1998), rewritten in vector form:

* Frame at the rule ``u = u_p``: ``z1`` along the rule ``P0 -> P1`` (length ``h_p``), ``n0``,
  ``n1`` the unit surface normals ``S_u x S_v`` at the rule's ends (the paper's ``N0 = T0 x P0P1``,
  ``N1``), both normal to the rule; ``side = +1`` puts the tool on the side of the normal,
  ``-1`` on the other. ``y1`` is the bisector of ``side*n0`` and ``side*n1`` (the paper's
  reference R1), ``x1 = y1 x z1``; ``alpha0`` is half the angle between ``n0`` and ``n1``.
* A setting is the axis line ``Q + t a`` of the cylinder of radius ``R``. The tool touches the
  rule at ``M2 = P0 + h0 z1``: ``Q = M2 + R y``, ``a = cos(gamma) z1 + sin(gamma) x``, with ``y = y1``
  (``x = x1``) unless rotated about the rule by ``phi`` (minimax only). The rule lies in the
  cylinder's tangent plane at M2, so it touches the tool there.

Settings: **standard tangent** (axis along the rule, tool tangent to C0 at P0, or C1 at P1),
**standard distributed** (Rubio's, the paper's baseline: axis along the rule, offset so that the
errors at both directrices are equal), **standard bisector** (axis along the rule, offset along
``y1``; equal to the distributed one on straight directrices), **optimum** (the paper's: also
tangent to C0 at M0 and C1 at M1, solved for ``h0`` and ``gamma``), **minimax** (beyond the paper:
minimises the largest |error| over ``h0, gamma, phi``).

Interference convention: along the rule, for each ``v``, ``e(v) = min_u dist(S(u, v), axis) - R``
over a band of the surface around the rule (``band_mm`` of surface length each side).
``e < 0`` is a **gouge** (the tool is inside the material by ``-e``), ``e > 0`` an **undercut**
(material left, ``e`` thick).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, MachsurfError
from ..results import Result
from . import tangency
from .ruled import RuledSurface


class NoAdmissibleSetting(MachsurfError):
    """The tangency system has no solution on this side (e.g. R too large for the twist)."""

    exit_code = 1


@dataclass(frozen=True, eq=False)
class RuleFrame(Result):
    """The rule at ``u_p`` and its frame (paper's reference R1), unit vectors; mm."""

    u_p: float
    p0: np.ndarray
    p1: np.ndarray
    h_p: float
    z1: np.ndarray
    y1: np.ndarray
    x1: np.ndarray
    n0: np.ndarray
    n1: np.ndarray
    alpha0_deg: float
    side: int


def rule_frame(surface: RuledSurface, u_p: float, side: int = 1) -> RuleFrame:
    surface.check_rule(u_p)
    if side not in (1, -1):
        raise InputError("side must be +1 or -1")
    p0, p1 = surface.rule(u_p)
    h_p = float(np.linalg.norm(p1 - p0))
    z1 = (p1 - p0) / h_p
    n = surface.normal(np.array([u_p, u_p]), np.array([0.0, 1.0]))
    n0, n1 = side * n[0], side * n[1]
    # remove any round-off along the rule
    n0 = n0 - (n0 @ z1) * z1
    n1 = n1 - (n1 @ z1) * z1
    n0 /= np.linalg.norm(n0)
    n1 /= np.linalg.norm(n1)
    bis = n0 + n1
    if np.linalg.norm(bis) < 1e-9:
        raise InputError(f"the surface turns by 180 deg along the rule at u = {u_p:g}: no bisector")
    y1 = bis / np.linalg.norm(bis)
    x1 = np.cross(y1, z1)
    alpha0 = 0.5 * math.degrees(math.acos(float(np.clip(n0 @ n1, -1, 1))))
    return RuleFrame(float(u_p), p0, p1, h_p, z1, y1, x1, n0, n1, alpha0, side)


@dataclass(frozen=True, eq=False)
class Setting(Result):
    """A cylinder position: axis point ``q`` and unit direction ``a``, radius ``R`` (mm, degrees)."""

    kind: str
    frame: RuleFrame
    R: float
    q: np.ndarray
    a: np.ndarray
    h0: float
    gamma_deg: float
    phi_deg: float = 0.0
    contacts: dict = field(default_factory=dict)

    @property
    def h1(self) -> float:
        return self.frame.h_p - self.h0

    def placement(self, overhang: float = 0.0) -> tuple[np.ndarray, np.ndarray, float]:
        """``(tip, axis, length)`` of the cylinder covering the rule: the tip on the axis level with the
        C0 end minus ``overhang`` (mm), the unit axis towards C1 (tip to shank), the length (mm)."""
        fr = self.frame
        t0 = float((fr.p0 - self.q) @ self.a)
        t1 = float((fr.p1 - self.q) @ self.a)
        sign = 1.0 if t1 >= t0 else -1.0
        start = t0 - sign * overhang
        return self.q + start * self.a, sign * self.a, abs(t1 - t0) + 2 * overhang

    def report(self) -> dict:
        return {
            "kind": self.kind,
            "R_mm": self.R,
            "u_p": self.frame.u_p,
            "side": self.frame.side,
            "h_p_mm": self.frame.h_p,
            "alpha0_deg": self.frame.alpha0_deg,
            "h0_mm": self.h0,
            "h1_mm": self.h1,
            "gamma_deg": self.gamma_deg,
            "phi_deg": self.phi_deg,
            "axis_point_mm": self.q.tolist(),
            "axis_direction": self.a.tolist(),
            "contacts": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.contacts.items()},
        }


def axis_of(frame: RuleFrame, R: float, h0: float, gamma: float, phi: float = 0.0):
    """Axis point and direction for parameters ``h0`` (mm), ``gamma``, ``phi`` (radians)."""
    y = math.cos(phi) * frame.y1 + math.sin(phi) * frame.x1
    x = np.cross(y, frame.z1)
    m2 = frame.p0 + h0 * frame.z1
    return m2 + R * y, math.cos(gamma) * frame.z1 + math.sin(gamma) * x


def _dist_axis(p, q, a):
    w = p - q
    w = w - (w @ a)[..., None] * a if w.ndim > 1 else w - (w @ a) * a
    return np.linalg.norm(w, axis=-1)


def standard_setting(
    surface: RuledSurface,
    u_p: float,
    R: float,
    *,
    side: int = 1,
    distributed: bool = True,
    end: int = 0,
    split: str = "equal-error",
) -> Setting:
    """Standard setting, axis collinear with the rule: tangent to one directrix (a) or the error distributed (b).

    ``distributed=False``: tangent to C0 at P0 (``end=0``) or to C1 at P1 (``end=1``), kind
    ``standard-tangent``. ``distributed=True`` with ``split="equal-error"`` is Rubio's setting (the
    paper's baseline, kind ``standard-distributed``): the axis offset from the rule in the direction
    that makes the errors at the two directrices equal (min over u of the distance from each directrix
    to the axis, minus R); on straight directrices it is the bisector of the end normals. With
    ``split="bisector"`` the offset is along the bisector ``y1`` whatever the curvature (kind
    ``standard-bisector``).
    """
    _check_R(R)
    fr = rule_frame(surface, u_p, side)
    phi = 0.0
    if not distributed:
        y, kind = (fr.n0 if end == 0 else fr.n1), "standard-tangent"
    elif split == "bisector":
        y, kind = fr.y1, "standard-bisector"
    elif split == "equal-error":
        phi = _equal_error_phi(surface, fr, float(R))
        y, kind = math.cos(phi) * fr.y1 + math.sin(phi) * fr.x1, "standard-distributed"
    else:
        raise InputError(f"split must be 'equal-error' or 'bisector', got {split!r}")
    q = fr.p0 + R * y
    contacts: dict = {"P0": fr.p0, "P1": fr.p1, "tangent_end": None if distributed else end}
    if kind == "standard-distributed":
        contacts["end_errors_mm"] = [float(e) for e in _end_errors(surface, fr, float(R), phi)]
    return Setting(kind, fr, float(R), q, fr.z1.copy(), fr.h_p / 2, 0.0, math.degrees(phi), contacts)


def _end_errors(surface: RuledSurface, fr: RuleFrame, R: float, phi: float) -> tuple[float, float]:
    """Errors at the two directrices (mm, negative = gouge) of the axis along the rule offset at ``phi``."""
    q, a = axis_of(fr, R, 0.0, 0.0, phi)
    lo, hi = surface.u_range
    out = []
    for c in (surface.c0, surface.c1):
        r = tangency.contact_points(c, q[None], a[None], [fr.u_p], (lo, hi))
        out.append(min(0.0, float(r.dist[0]) - R) if r.ok[0] else 0.0)
    return out[0], out[1]


def _equal_error_phi(surface: RuledSurface, fr: RuleFrame, R: float) -> float:
    """Rubio's distributed standard setting: the offset angle from ``y1`` (radians, about the rule) at
    which the errors at both directrices are equal, between the two tangent settings (offset along
    ``n0`` and along ``n1``). Where they never become equal there, the end with the smaller larger error."""
    from scipy.optimize import brentq

    phis = [math.atan2(float(n @ fr.x1), float(n @ fr.y1)) for n in (fr.n0, fr.n1)]
    a, b = min(phis), max(phis)
    if b - a < 1e-12:
        return 0.0

    def g(phi):
        e0, e1 = _end_errors(surface, fr, R, phi)
        return e0 - e1

    ga, gb = g(a), g(b)
    if ga == 0.0:
        return a
    if gb == 0.0:
        return b
    if ga * gb > 0:
        return min((a, b), key=lambda p: max(-e for e in _end_errors(surface, fr, R, p)))
    return float(brentq(g, a, b, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200))


def _check_R(R):
    if not (isinstance(R, (int, float)) and math.isfinite(R) and R > 0):
        raise InputError(f"tool radius must be a positive number of mm, got {R!r}")


def optimum_setting(
    surface: RuledSurface, u_p: float, R: float, *, side: int = 1, start: Setting | None = None
) -> Setting:
    """The paper's optimum: tangent to the rule at M2 and to C0 at M0 and C1 at M1.

    Solved for ``h0`` and ``gamma`` with the tangency points found by Newton from the rule. With
    ``start`` (a neighbouring rule's setting) its branch is continued when it holds; otherwise
    Newton runs from starts over the admissible (h0, gamma) range, every admissible solution is
    kept, and the one with the smallest interference along the rule is returned, the others in
    ``contacts["other_solutions"]``. Raises :class:`NoAdmissibleSetting` when no solution has M2
    on the rule, |gamma| < 80 deg and true tangencies (minima of the distance) on this side.
    """
    _check_R(R)
    fr = rule_frame(surface, u_p, side)
    lo0, hi0 = surface.u_range
    span = hi0 - lo0
    # tangency is sought on the directrices' natural extension too (end rules touch it there)
    lo, hi = lo0 - 0.5 * span, hi0 + 0.5 * span

    starts = [(0.5, -0.05), (0.5, 0.05), (0.25, 0.1), (0.75, -0.1), (0.25, -0.1), (0.75, 0.1), (0.5, 0.3), (0.5, -0.3)]
    # gamma = 0 (the standard setting) makes the Jacobian singular: the starts are off it
    # (a 4 x 8 grid of starts out to |gamma| = 65 deg found no better setting on 176 rules of the paper's
    # surfaces, only repeats on degenerate rules: these 12 are kept for the time)
    wide = [(h, g) for h in (0.25, 0.6) for g in np.radians([-45, -25, -12, 12, 25, 45])]

    if start is not None:  # continuation along a path: the branch of the neighbouring rule, when it holds
        x0 = (start.h0 / start.frame.h_p, math.radians(start.gamma_deg))
        warm = None
        if start.kind == "optimum":  # the tangency points move little between neighbouring rules
            du = u_p - start.frame.u_p
            warm = (start.contacts["u0"] + du, start.contacts["u1"] + du)
        found = _admissible(surface, fr, R, u_p, tangency.solve(surface, fr, R, [x0], (lo, hi), warm=warm))
        if found:
            return _optimum(surface, fr, R, found[0])
        starts.insert(0, x0)
    # every three-tangency solution from starts over the admissible (h0, gamma) range (all advanced
    # together), then the best by the interference along the rule (the first found is not always the
    # best: Liu's surface, side -1)
    # (scipy's hybrid solver from the same starts found nothing more on the paper's surfaces: 24 rules
    # without a solution over 3 radii per surface, both sides)
    found = _admissible(surface, fr, R, u_p, tangency.solve(surface, fr, R, starts + wide, (lo, hi)))
    if not found:
        raise NoAdmissibleSetting(
            f"no admissible optimum setting for R = {R:g} mm on side {side:+d} at u = {u_p:g}: the three-tangency "
            f"system has no solution with M2 on the rule and true tangencies with both directrices (alpha0 = "
            f"{fr.alpha0_deg:.3g} deg, h_p = {fr.h_p:.4g} mm"
            + (
                f"; on straight directrices it exists up to R = h_p / (2 sin alpha0) = "
                f"{fr.h_p / (2 * math.sin(math.radians(fr.alpha0_deg))):.4g} mm)"
                if fr.alpha0_deg > 1e-9
                else ")"
            )
        )
    if len(found) == 1:
        return _optimum(surface, fr, R, found[0])
    settings = [_optimum(surface, fr, R, f) for f in found]
    errors = [interference(surface, st, n_v=41).max_abs for st in settings]  # ranking: 41 samples along the rule
    order = np.argsort(errors)
    others = [
        {"h0_mm": float(found[i][0]), "gamma_deg": math.degrees(found[i][1]), "max_abs_mm": float(errors[i])}
        for i in order[1:]
    ]
    return _optimum(surface, fr, R, found[order[0]], others)


def _admissible(surface: RuledSurface, fr: RuleFrame, R: float, u_p: float, sols: tangency.Solutions) -> list[tuple]:
    """The distinct solutions with M2 on the rule, |gamma| < 80 deg and true tangencies near the rule."""
    lo0, hi0 = surface.u_range
    span = hi0 - lo0
    out: list[tuple] = []
    for i in range(sols.h0.size):
        h0, gamma = float(sols.h0[i]), float(sols.gamma[i])
        r0, r1 = ((float(c.u[i]), float(c.dist[i]), c.point[i], float(c.slope[i])) for c in (sols.c0, sols.c1))
        # a true tangency: the distance is stationary there (not a minimum clipped at the domain's edge)
        tangent = all(
            abs(r_[3]) <= 1e-7 * R * max(1.0, float(np.linalg.norm(d(np.array([r_[0]]), 1)[0, 1])))
            for r_, d in ((r0, surface.c0), (r1, surface.c1))
        )
        ok = (
            -1e-9 <= h0 <= fr.h_p + 1e-9
            and abs(gamma) < math.radians(80)
            and tangent
            and abs(r0[0] - u_p) < 0.5 * span
            and abs(r1[0] - u_p) < 0.5 * span
            and np.all(np.isfinite(r0[2]))
            and np.all(np.isfinite(r1[2]))
        )
        if ok and all(abs(h0 - f[0]) > 1e-6 * fr.h_p or abs(gamma - f[1]) > 1e-9 for f in out):
            q, a = axis_of(fr, R, h0, gamma)
            out.append((h0, gamma, q, a, r0, r1))
    return out


def _optimum(surface: RuledSurface, fr: RuleFrame, R: float, sol: tuple, others=()) -> Setting:
    """The optimum :class:`Setting` of one admissible solution; ``others``: the other solutions' figures."""
    lo0, hi0 = surface.u_range
    h0, gamma, q, a, r0, r1 = sol
    return Setting(
        "optimum",
        fr,
        float(R),
        q,
        a,
        float(h0),
        math.degrees(gamma),
        0.0,
        {
            "u0": r0[0],
            "u1": r1[0],
            "M0": r0[2],
            "M1": r1[2],
            "M2": fr.p0 + h0 * fr.z1,
            "tangency_residual_mm": max(abs(r0[1] - R), abs(r1[1] - R)),
            "contact_outside_surface": bool(not (lo0 <= r0[0] <= hi0 and lo0 <= r1[0] <= hi0)),
            "tangency_slope_residual": max(abs(r0[3]), abs(r1[3])),
            "other_solutions": list(others),
        },
    )


@dataclass(frozen=True, eq=False)
class Interference(Result):
    """Error profile along the rule (mm): ``e[i]`` at ``v[i]``, negative = gouge, positive = undercut."""

    v: np.ndarray
    u: np.ndarray
    e: np.ndarray
    points: np.ndarray
    band_mm: float

    @property
    def max_gouge(self) -> float:
        return float(max(0.0, -self.e.min()))

    @property
    def max_undercut(self) -> float:
        return float(max(0.0, self.e.max()))

    @property
    def max_abs(self) -> float:
        return float(np.abs(self.e).max())

    def worst(self) -> dict:
        i = int(np.argmax(np.abs(self.e)))
        return {"v": float(self.v[i]), "u": float(self.u[i]), "xyz": self.points[i].tolist(), "e_mm": float(self.e[i])}

    def report(self) -> dict:
        return {
            "max_gouge_mm": self.max_gouge,
            "max_undercut_mm": self.max_undercut,
            "max_abs_mm": self.max_abs,
            "worst": self.worst(),
            "band_mm": self.band_mm,
            "n_samples": int(self.v.size),
        }


def interference(
    surface: RuledSurface, setting: Setting, *, n_v: int = 201, band_mm: float | None = None, n_u: int = 41
) -> Interference:
    """Signed distance between the cylinder and the surface along the rule (see module docstring)."""
    fr, R = setting.frame, setting.R
    band = float(band_mm) if band_mm is not None else R
    lo, hi = surface.u_range
    v = np.linspace(0.0, 1.0, n_v)
    su = np.linalg.norm(surface.derivatives(np.full(n_v, fr.u_p), v)[1], axis=1)
    du = band / np.maximum(su, 1e-12)
    # dense start, then Newton per v on u (vectorised)
    t = np.linspace(-1.0, 1.0, n_u)
    U = np.clip(fr.u_p + du[:, None] * t[None, :], lo, hi)
    P = surface.evaluate(U, np.broadcast_to(v[:, None], U.shape))
    d = _dist_axis(P, setting.q, setting.a)
    j = np.argmin(d, axis=1)
    u = U[np.arange(n_v), j]
    ulo = np.clip(fr.u_p - du, lo, hi)
    uhi = np.clip(fr.u_p + du, lo, hi)
    q, a = setting.q, setting.a
    for _ in range(30):
        p, s_u, _, s_uu, _ = surface.derivatives(u, v)
        w = p - q
        w = w - (w @ a)[:, None] * a
        s1 = s_u - (s_u @ a)[:, None] * a
        g = np.einsum("ij,ij->i", w, s_u)
        h = np.einsum("ij,ij->i", s1, s1) + np.einsum("ij,ij->i", w, s_uu)
        step = np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0)
        u_new = np.clip(u - step, ulo, uhi)
        done = np.abs(u_new - u).max() < 1e-13 * (hi - lo)
        u = u_new
        if done:
            break
    p = surface.evaluate(u, v)
    e = _dist_axis(p, q, a) - R
    return Interference(v, u, e, p, band)


def minimax_setting(
    surface: RuledSurface, u_p: float, R: float, *, side: int = 1, start: Setting | None = None, n_v: int = 81
) -> Setting:
    """Beyond the paper: the setting minimising the largest |error| along the rule over (h0, gamma, phi).

    Starts from the optimum setting when it exists, else from the distributed standard one.
    """
    from scipy.optimize import minimize

    _check_R(R)
    fr = rule_frame(surface, u_p, side)
    if start is None:
        try:
            start = optimum_setting(surface, u_p, R, side=side)
        except NoAdmissibleSetting:
            start = standard_setting(surface, u_p, R, side=side)
    x0 = np.array([start.h0 / fr.h_p, math.radians(start.gamma_deg), math.radians(start.phi_deg)])

    def make(x):
        q, a = axis_of(fr, R, x[0] * fr.h_p, x[1], x[2])
        return Setting("minimax", fr, float(R), q, a, float(x[0] * fr.h_p), math.degrees(x[1]), math.degrees(x[2]))

    def cost(x):
        return interference(surface, make(x), n_v=n_v).max_abs

    res = minimize(
        cost,
        x0,
        method="Nelder-Mead",
        options={"xatol": 1e-9, "fatol": 1e-9, "maxiter": 2000, "initial_simplex": _simplex(x0)},
    )
    best = make(res.x)
    return Setting(
        "minimax",
        fr,
        float(R),
        best.q,
        best.a,
        best.h0,
        best.gamma_deg,
        best.phi_deg,
        {"M2": fr.p0 + best.h0 * fr.z1, "iterations": int(res.nit)},
    )


def _simplex(x0):
    steps = np.array([0.05, 0.01, 0.01])
    return np.vstack([x0] + [x0 + np.eye(3)[i] * steps[i] for i in range(3)])


SETTINGS = ("standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax")


def tool_setting(
    surface: RuledSurface, u_p: float, R: float, kind: str, *, side: int = 1, start: Setting | None = None
) -> Setting:
    """Setting by name, one of :data:`SETTINGS` (``start``: a neighbouring rule's setting to continue from)."""
    if kind == "standard-tangent":
        return standard_setting(surface, u_p, R, side=side, distributed=False)
    if kind == "standard-distributed":
        return standard_setting(surface, u_p, R, side=side, distributed=True)
    if kind == "standard-bisector":
        return standard_setting(surface, u_p, R, side=side, split="bisector")
    if kind == "optimum":
        return optimum_setting(surface, u_p, R, side=side, start=start)
    if kind == "minimax":
        return minimax_setting(surface, u_p, R, side=side, start=start)
    raise InputError(f"unknown setting {kind!r}; use one of {', '.join(SETTINGS)}")
