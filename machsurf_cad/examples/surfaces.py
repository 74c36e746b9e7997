"""The papers' test surfaces and the example parts, built in numpy (lengths in mm, angles in degrees).

* :func:`hyperbolic_paraboloid` and :func:`liu_surface` are exact (polynomial directrices), as B-spline
  patches or (``*_ruled``) as :class:`RuledSurface` for flank milling; the directrices are defined once.
* :func:`eq18_surface` has a sqrt(u) directrix: it is fitted within a stated tolerance and
  carries the error measured on points the fit never saw.
* :func:`bezier5_patch` is a degree-5 Bezier patch of about 100 mm, like the
  machining-surface paper's example; :func:`propeller_blade` is a free-form blade face of
  about 400 mm span, like the effective-radius paper's industrial case.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..flank_milling.ruled import RuledSurface
from ..geometry import BSplineCurve, BSplineSurface, builders


# ----------------------------------------------------------------------------- flank-milling paper
def hypar_directrices(
    alpha0_deg: float = 30.0, h_p: float = 80.0, k: float | None = None
) -> tuple[BSplineCurve, BSplineCurve]:
    """Directrices of Redonnet et al. section 3.2's hyperbolic paraboloid (exact lines, mm).

    ``C0(u) = (k u, k tan(alpha0) (u - 1/2), h_p/2)``, ``C1(u) = (k u, -k tan(alpha0) (u - 1/2), -h_p/2)``,
    u in [0, 1], with ``k = h_p`` by default as in the paper.
    """
    k = h_p if k is None else k
    t = k * np.tan(np.radians(alpha0_deg))
    c0 = builders.line_segment([0.0, -t / 2, h_p / 2], [k, t / 2, h_p / 2])
    c1 = builders.line_segment([0.0, t / 2, -h_p / 2], [k, -t / 2, -h_p / 2])
    return c0, c1


def hyperbolic_paraboloid(alpha0_deg: float = 30.0, h_p: float = 80.0, k: float | None = None) -> BSplineSurface:
    """The hyperbolic paraboloid as an exact bilinear B-spline patch (u, v in [0, 1])."""
    return builders.ruled_surface(*hypar_directrices(alpha0_deg, h_p, k), name=f"hypar_a{alpha0_deg:g}_h{h_p:g}")


def hypar_ruled(alpha0_deg: float = 30.0, h_p: float = 80.0, k: float | None = None) -> RuledSurface:
    """The hyperbolic paraboloid as a :class:`RuledSurface` for flank milling (exact)."""
    return RuledSurface.from_curves(*hypar_directrices(alpha0_deg, h_p, k), name=f"hypar_a{alpha0_deg:g}_h{h_p:g}")


def liu_directrices() -> tuple[BSplineCurve, BSplineCurve]:
    """Liu's directrices: ``C0(u) = (u, 20.429, 0)``, ``C1(u) = (u, 0.0382 u^2, 33.995)``, 0 <= u <= 23.014 (exact)."""
    L = 23.014
    c0 = BSplineCurve(2, [0.0, L], [3, 3], [[0.0, 20.429, 0.0], [L / 2, 20.429, 0.0], [L, 20.429, 0.0]])
    c1 = BSplineCurve(2, [0.0, L], [3, 3], [[0.0, 0.0, 33.995], [L / 2, 0.0, 33.995], [L, 0.0382 * L * L, 33.995]])
    return c0, c1


def liu_surface() -> BSplineSurface:
    """Liu's ruled surface as an exact B-spline patch (u keeps its physical range 0..23.014)."""
    return builders.ruled_surface(*liu_directrices(), name="liu")


def liu_ruled() -> RuledSurface:
    """Liu's surface as a :class:`RuledSurface` for flank milling (exact)."""
    return RuledSurface.from_curves(*liu_directrices(), name="liu")


def _directrix(value, d1, d2):
    """A directrix ``f(u, order) -> (..., order + 1, 3)`` from vectorised maps of u (mm)."""

    def f(u, order=2):
        u = np.asarray(u, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):  # NaN outside a directrix's domain
            return np.stack([g(u) for g in (value, d1, d2)[: order + 1]], axis=-2)

    return f


def _eq18_directrices():
    """Eq. (18)'s directrices with their first and second derivatives, exact (the one definition)."""
    k = 0.5 * np.pi

    def c0(u):
        return np.stack([30 * u**2 + 10 * u + 30, 100 * np.sqrt(u) - 50, 70 - 30 * u**2], axis=-1)

    def c0_d1(u):  # sqrt(u): derivatives are infinite at u = 0; clamp to u >= 1e-12 so they stay finite
        return np.stack([60 * u + 10, 50 / np.sqrt(np.maximum(u, 1e-12)), -60 * u], axis=-1)

    def c0_d2(u):
        return np.stack([60 + 0 * u, -25 * np.maximum(u, 1e-12) ** -1.5, -60 + 0 * u], axis=-1)

    def c1(u):
        return np.stack([50 * u**2 + 20, 40 - 60 * np.sin(k * u), -60 + 20 * u**2], axis=-1)

    def c1_d1(u):
        return np.stack([100 * u, -60 * k * np.cos(k * u), 40 * u], axis=-1)

    def c1_d2(u):
        return np.stack([100 + 0 * u, 60 * k * k * np.sin(k * u), 40 + 0 * u], axis=-1)

    return _directrix(c0, c0_d1, c0_d2), _directrix(c1, c1_d1, c1_d2)


def eq18_ruled() -> RuledSurface:
    """Redonnet et al. eq. (18) as a :class:`RuledSurface`, evaluated exactly:
    C0 = (30u^2 + 10u + 30, 100 sqrt(u) - 50, 70 - 30u^2), C1 = (50u^2 + 20, 40 - 60 sin(pi u / 2), -60 + 20u^2),
    u in [0, 1]."""
    c0, c1 = _eq18_directrices()
    return RuledSurface(c0, c1, (0.0, 1.0), "eq18")


def eq18_directrix_maps():
    """The two directrices of Redonnet et al. eq. (18) as exact vectorised maps of u in [0, 1]."""
    c0, c1 = _eq18_directrices()
    return (lambda u: c0(u, 0)[..., 0, :]), (lambda u: c1(u, 0)[..., 0, :])


@dataclass(frozen=True)
class FittedSurface:
    """A surface approximating an exact map, with the max error (mm) measured on unseen points."""

    surface: BSplineSurface
    max_error: float
    n_check: int


def eq18_surface(tolerance: float = 1e-4) -> FittedSurface:
    """Ruled surface of eq. (18) of the flank-milling paper, fitted within ``tolerance`` (mm).

    ``S(u, v) = (1 - v) C0(u) + v C1(u)`` with C0 containing ``100 sqrt(u)``; each directrix is
    fitted keeping the parameterisation, then the surface error is measured on a grid of
    points between the fit's samples. (The paper's printed equation is more twisted at
    u_p = 0.4 than its figures suggest: see ../shared/papers/README.md.)
    """
    m0, m1 = eq18_directrix_maps()
    f0 = builders.fit_curve(m0, 0.0, 1.0, tolerance=tolerance)
    f1 = builders.fit_curve(m1, 0.0, 1.0, tolerance=tolerance)
    s = builders.ruled_surface(f0.curve, f1.curve, name="eq18")
    u = np.linspace(0, 1, 2003)[1:-1] + 1.7e-4
    u = u[u < 1]
    v = np.linspace(0, 1, 11)
    pts = s.evaluate_grid(u, v)
    exact = (1 - v)[None, :, None] * m0(u)[:, None, :] + v[None, :, None] * m1(u)[:, None, :]
    err = float(np.linalg.norm(pts - exact, axis=-1).max())
    return FittedSurface(s, max(err, f0.max_error, f1.max_error), int(pts.shape[0] * pts.shape[1]))


# ----------------------------------------------------------------------------- machining-surface paper
def bezier5_patch(size: float = 100.0) -> BSplineSurface:
    """Degree-5 Bezier patch of about ``size`` mm (default 100), a smooth free-form bump.

    Gentle enough that the offsets of the paper's example (r = 4 mm, R_t = 10 mm) are free of
    loops: its smallest concave radius of curvature is well above 14 mm.
    """
    n = 6
    x = np.linspace(0.0, size, n)
    X, Y = np.meshgrid(x, x, indexing="ij")
    s = np.linspace(0, 1, n)
    S, T = np.meshgrid(s, s, indexing="ij")
    Z = size * (0.18 * np.sin(np.pi * S) * np.sin(np.pi * T) + 0.06 * S * T - 0.04 * (S - 0.5) ** 2)
    poles = np.stack([X + 3.0 * np.sin(np.pi * T), Y, Z], axis=-1)
    return builders.bezier_surface(poles, name="bezier5")


# ----------------------------------------------------------------------------- effective-radius paper
def propeller_blade(span: float = 400.0, hub_radius: float = 60.0) -> BSplineSurface:
    """Pressure face of a twisted, cambered propeller blade of ``span`` mm (bicubic B-spline).

    u runs along the span (hub to tip), v along the chord (leading to trailing edge). The
    chord grows then shrinks along the span, the twist goes from 55 to 20 degrees and the
    camber is 6 % of the chord: a free-form face like the effective-radius paper's blade.
    """
    nu, nv = 11, 9
    s = np.linspace(0, 1, nu)[:, None]
    t = np.linspace(-0.5, 0.5, nv)[None, :]
    rho = hub_radius + span * s
    chord = 110 + 90 * np.sin(np.pi * (0.15 + 0.7 * s)) - 40 * s**2
    beta = np.radians(55 - 35 * s)
    camber = 0.06 * chord * (1 - (2 * t) ** 2)
    skew = 25 * s**2
    xc = t * chord
    y = xc * np.cos(beta) - camber * np.sin(beta) + skew
    z = xc * np.sin(beta) + camber * np.cos(beta)
    pts = np.stack([np.broadcast_to(rho, y.shape), y, z], axis=-1)
    return builders.interpolate_grid(
        pts, 3, 3, params_u=np.linspace(0, 1, nu), params_v=np.linspace(0, 1, nv), name="propeller_blade"
    )
