"""Ruled surfaces ``S(u, v) = (1 - v) C0(u) + v C1(u)`` with exact directrices (mm).

A :class:`RuledSurface` holds two vectorised directrix maps returning points and
derivatives, either analytic (the papers' test surfaces, evaluated exactly) or B-spline
curves (from a STEP face or a script). The surface normal is ``S_u x S_v``; at the rule
ends it is along the paper's ``N0 = T0 x P0P1`` and ``N1 = T1 x P0P1``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..geometry.bspline import BSplineCurve, BSplineSurface

# a directrix: f(u, order) -> array (..., order + 1, 3): point, first and second derivative
Directrix = Callable[[np.ndarray, int], np.ndarray]


def _curve_directrix(c: BSplineCurve) -> Directrix:
    if c.is_rational or c.periodic or len(c.knots) != 2:

        def f(u, order=2):
            return c.derivatives(np.asarray(u, dtype=float), order)

        return f
    # one polynomial span: its power-basis coefficients in s = (u - a) / L, then Horner (the
    # optimum solver calls this thousands of times on a few points; exact to rounding)
    a, b = c.bounds
    L = b - a
    s = np.linspace(0.0, 1.0, c.degree + 1)
    coef = [np.linalg.solve(np.vander(s, c.degree + 1, increasing=True), c.evaluate(a + s * L))]
    for _ in range(2):
        prev = coef[-1]
        coef.append(prev[1:] * np.arange(1, prev.shape[0])[:, None] / L if prev.shape[0] > 1 else np.zeros((1, 3)))

    def g(u, order=2):
        t = (np.asarray(u, dtype=float) - a) / L
        out = np.empty(t.shape + (order + 1, 3))
        for k in range(order + 1):
            ck = coef[k]
            acc = np.broadcast_to(ck[-1], t.shape + (3,)).copy()
            for row in ck[-2::-1]:
                acc = acc * t[..., None] + row
            out[..., k, :] = acc
        return out

    return g


@dataclass(frozen=True)
class RuledSurface:
    """Ruled surface from two directrices over ``u`` in ``[u0, u1]``, ``v`` in [0, 1] (mm)."""

    c0: Directrix
    c1: Directrix
    u_range: tuple = (0.0, 1.0)
    name: str = "ruled"
    source_deviation: float = 0.0
    """Largest distance (mm) from the face this ruled surface was made from (0 when exact)."""

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_curves(cls, c0: BSplineCurve, c1: BSplineCurve, name: str = "ruled") -> RuledSurface:
        if c0.dim != 3 or c1.dim != 3:
            raise InputError("directrices must be 3-D curves")
        a, b = c0.bounds, c1.bounds
        if not (np.isclose(a[0], b[0]) and np.isclose(a[1], b[1])):
            raise InputError("directrices must share their parameter range")
        return cls(_curve_directrix(c0), _curve_directrix(c1), a, name)

    @classmethod
    def from_surface(cls, s: BSplineSurface, *, tolerance: float = 1e-6, name: str | None = None) -> RuledSurface:
        """The ruled surface of a B-spline face, rules along v (or u, swapped).

        The ruled surface through the face's two boundary curves is measured against the face
        (61 x 21 samples); when they differ by more than ``tolerance`` (mm) this raises
        :class:`InputError` with the largest deviation. Pass a larger tolerance to accept a
        ruled approximation; its measured deviation is kept in ``source_deviation``.
        """
        from ..geometry.builders import ruled_surface

        best = np.inf
        for direction in ("v", "u"):
            surf = s if direction == "v" else _swap_uv(s)
            u0, u1, v0, v1 = surf.bounds
            c0 = _iso_curve(surf, v0)
            c1 = _iso_curve(surf, v1)
            rs = ruled_surface(c0, c1)
            uu = np.linspace(u0, u1, 61)
            vv = np.linspace(v0, v1, 21)
            pts = surf.evaluate_grid(uu, vv)
            # the ruled surface's v runs over [0, 1]; map the face's v range onto it
            ref = rs.evaluate_grid(uu, (vv - v0) / (v1 - v0))
            dev = float(np.linalg.norm(pts - ref, axis=-1).max())
            if dev <= tolerance:
                r = cls.from_curves(c0, c1, name or s.name or "ruled")
                return cls(r.c0, r.c1, r.u_range, r.name, dev)
            best = dev if direction == "v" else min(best, dev)
        dev = best
        raise InputError(
            f"face is not a ruled surface: it deviates by {dev:.4g} mm from the ruled surface through "
            f"its boundary curves (tolerance {tolerance:g} mm)"
        )

    # ------------------------------------------------------------------ evaluation
    def rule(self, u: float):
        """End points ``P0 = C0(u)``, ``P1 = C1(u)`` of the rule at ``u``."""
        return self.c0(np.array([u]), 0)[0, 0], self.c1(np.array([u]), 0)[0, 0]

    def derivatives(self, u, v):
        """Point, S_u, S_v, S_uu, S_uv at (u, v) (broadcast); S_vv is zero."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        a = self.c0(u, 2)
        b = self.c1(u, 2)
        vv = v[..., None]
        p = (1 - vv) * a[..., 0, :] + vv * b[..., 0, :]
        su = (1 - vv) * a[..., 1, :] + vv * b[..., 1, :]
        sv = b[..., 0, :] - a[..., 0, :]
        suu = (1 - vv) * a[..., 2, :] + vv * b[..., 2, :]
        suv = b[..., 1, :] - a[..., 1, :]
        return p, su, sv, suu, suv

    def evaluate(self, u, v) -> np.ndarray:
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        vv = v[..., None]
        return (1 - vv) * self.c0(u, 0)[..., 0, :] + vv * self.c1(u, 0)[..., 0, :]

    def normal(self, u, v) -> np.ndarray:
        _, su, sv, _, _ = self.derivatives(u, v)
        n = np.cross(su, sv)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def grid_map(self, us, vs) -> np.ndarray:
        """Points on the grid ``us x vs`` (for the approximation engine)."""
        U, V = np.meshgrid(np.asarray(us, float), np.asarray(vs, float), indexing="ij")
        return self.evaluate(U, V)

    def check_rule(self, u: float) -> None:
        lo, hi = self.u_range
        if not lo <= u <= hi:
            raise InputError(f"rule parameter {u:g} is outside [{lo:g}, {hi:g}]")
        p0, p1 = self.rule(u)
        if np.linalg.norm(p1 - p0) < 1e-9:
            raise InputError(f"the rule at u = {u:g} has zero length: the directrices cross there")

    def to_bspline(self, tolerance: float = 1e-4):
        """B-spline approximation within ``tolerance`` (mm), by the certified engine; returns a SurfaceFit."""
        from ..approx import fit_surface

        lo, hi = self.u_range
        return fit_surface(
            self.grid_map, (lo, hi, 0.0, 1.0), tolerance=tolerance, degree=(3, 1), initial_spans=(8, 1), name=self.name
        )


def _iso_curve(s: BSplineSurface, v: float) -> BSplineCurve:
    """The iso-curve v = const of a B-spline surface, exactly (blossom via evaluation of poles rows)."""
    from ..geometry.basis import basis_derivatives, find_spans

    tv, hp = s._eval_data[1], s._eval_data[2]
    q = s.degree_v
    nv = hp.shape[1]
    span = find_spans(tv, q, nv, np.array([v]))
    b = basis_derivatives(tv, q, span, np.array([v]), 0)[0, 0]
    cols = span[0] - q + np.arange(q + 1)
    rows = np.einsum("j,ijd->id", b, hp[:, cols, :])
    if s.periodic_u:
        raise InputError("periodic ruled faces are not supported")
    if s.weights is None:
        return BSplineCurve(s.degree_u, s.knots_u, s.mults_u, rows)
    return BSplineCurve(s.degree_u, s.knots_u, s.mults_u, rows[:, :3] / rows[:, 3:], rows[:, 3])


def _swap_uv(s: BSplineSurface) -> BSplineSurface:
    return BSplineSurface(
        s.degree_v,
        s.degree_u,
        s.knots_v,
        s.mults_v,
        s.knots_u,
        s.mults_u,
        s.poles.transpose(1, 0, 2),
        None if s.weights is None else s.weights.T,
        s.periodic_v,
        s.periodic_u,
        s.name,
    )
