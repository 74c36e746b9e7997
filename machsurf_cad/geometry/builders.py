"""Factory functions for curves and surfaces (all lengths in mm, angles in degrees).

Exact builders return the geometry exactly (Bezier patches, control grids, ruled surfaces
of B-spline directrices, quadrics as rational surfaces). Approximating builders (fitting an
analytic curve) return the measured error with the result.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, ToleranceError
from ..results import Result
from .basis import collocation_matrix
from .bspline import BSplineCurve, BSplineSurface
from .knots import elevate_and_merge


# ----------------------------------------------------------------------------- curves
def bezier_curve(poles, weights=None) -> BSplineCurve:
    """Bezier curve of degree ``len(poles) - 1`` on [0, 1]."""
    poles = np.asarray(poles, dtype=float)
    deg = poles.shape[0] - 1
    return BSplineCurve(deg, [0.0, 1.0], [deg + 1, deg + 1], poles, weights)


def line_segment(p0, p1) -> BSplineCurve:
    """Straight segment from ``p0`` to ``p1`` on [0, 1] (degree 1)."""
    return bezier_curve([p0, p1])


def clamped_knots(n_poles: int, degree: int, lo: float = 0.0, hi: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Uniform clamped knots for ``n_poles`` poles of ``degree``."""
    n_int = n_poles - degree - 1
    if n_int < 0:
        raise InputError(f"need at least degree + 1 = {degree + 1} poles, got {n_poles}")
    knots = np.linspace(lo, hi, n_int + 2)
    mults = np.ones(n_int + 2, dtype=int)
    mults[0] = mults[-1] = degree + 1
    return knots, mults


def interpolate_curve(points, degree: int = 3, params=None) -> BSplineCurve:
    """Global interpolation of points (chord-length parameters on [0, 1] unless given)."""
    pts = np.asarray(points, dtype=float)
    n = pts.shape[0]
    if n < degree + 1:
        raise InputError(f"interpolation of degree {degree} needs at least {degree + 1} points")
    if params is None:
        d = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(d <= 0):
            raise InputError("interpolation points must be distinct")
        params = np.concatenate([[0.0], np.cumsum(d)]) / d.sum()
    params = np.asarray(params, dtype=float)
    knots, mults = _averaged_knots(params, degree)
    t = np.repeat(knots, mults)
    b = collocation_matrix(t, degree, n, params)
    return BSplineCurve(degree, knots, mults, np.linalg.solve(b, pts))


def _averaged_knots(params: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    n = params.size
    inner = np.array([params[j : j + degree].mean() for j in range(1, n - degree)])
    knots = np.concatenate([[params[0]], inner, [params[-1]]])
    mults = np.ones(knots.size, dtype=int)
    mults[0] = mults[-1] = degree + 1
    return knots, mults


@dataclass(frozen=True, eq=False)
class CurveFit(Result):
    """A B-spline curve fitted to an exact map, with the error measured on unseen points (mm)."""

    curve: BSplineCurve
    max_error: float
    n_check: int


def fit_curve(
    func: Callable[[np.ndarray], np.ndarray],
    lo: float,
    hi: float,
    *,
    tolerance: float,
    degree: int = 3,
    max_poles: int = 2000,
    n_start: int = 8,
) -> CurveFit:
    """Fit a B-spline curve to ``func`` on [lo, hi] within ``tolerance`` (max-norm distance, mm).

    The parameterisation of ``func`` is kept (the curve at ``x`` approximates ``func(x)``).
    Knots are refined where the error is: each span whose error exceeds the tolerance is
    split. The error is measured on 16 points inside every span that the fit never used.
    Raises :class:`ToleranceError` when ``max_poles`` is reached first.
    """
    if not tolerance > 0:
        raise InputError("tolerance must be > 0 mm")
    breaks = np.linspace(lo, hi, n_start + 1)
    while True:
        knots = breaks
        mults = np.ones(knots.size, dtype=int)
        mults[0] = mults[-1] = degree + 1
        t = np.repeat(knots, mults)
        n = int(mults.sum()) - degree - 1
        # least squares on 4 samples per span + ends (over-determined, stable)
        x_fit = np.unique(np.concatenate([np.linspace(a, b, 5) for a, b in zip(breaks[:-1], breaks[1:])]))
        b_mat = collocation_matrix(t, degree, n, x_fit)
        vals = np.asarray(func(x_fit), dtype=float)
        poles, *_ = np.linalg.lstsq(b_mat, vals, rcond=None)
        curve = BSplineCurve(degree, knots, mults, poles)
        # check on points the fit never saw
        frac = (np.arange(16) + 0.5) / 16 * 0.999 + 0.0005
        x_chk = breaks[:-1, None] + (breaks[1:] - breaks[:-1])[:, None] * frac[None, :]
        err = np.linalg.norm(curve.evaluate(x_chk.ravel()) - np.asarray(func(x_chk.ravel())), axis=-1)
        err = err.reshape(x_chk.shape)
        span_err = err.max(axis=1)
        max_err = float(span_err.max())
        if max_err <= tolerance:
            return CurveFit(curve, max_err, int(err.size))
        if n >= max_poles:
            raise ToleranceError(
                f"curve fit did not reach {tolerance:g} mm within {max_poles} poles (reached {max_err:.3g} mm)", max_err
            )
        bad = span_err > tolerance
        mids = 0.5 * (breaks[:-1] + breaks[1:])[bad]
        breaks = np.sort(np.concatenate([breaks, mids]))


# ----------------------------------------------------------------------------- surfaces
def bezier_surface(poles, weights=None, name: str = "") -> BSplineSurface:
    """Bezier patch of degree ``(nu - 1, nv - 1)`` on [0, 1]^2 from a control grid (nu, nv, 3)."""
    poles = np.asarray(poles, dtype=float)
    p, q = poles.shape[0] - 1, poles.shape[1] - 1
    return BSplineSurface(p, q, [0, 1], [p + 1, p + 1], [0, 1], [q + 1, q + 1], poles, weights, name=name)


def surface_from_grid(poles, degree_u: int = 3, degree_v: int = 3, weights=None, name: str = "") -> BSplineSurface:
    """B-spline surface from a control grid with uniform clamped knots on [0, 1]^2."""
    poles = np.asarray(poles, dtype=float)
    ku, mu = clamped_knots(poles.shape[0], degree_u)
    kv, mv = clamped_knots(poles.shape[1], degree_v)
    return BSplineSurface(degree_u, degree_v, ku, mu, kv, mv, poles, weights, name=name)


def interpolate_grid(
    points, degree_u: int = 3, degree_v: int = 3, params_u=None, params_v=None, name: str = ""
) -> BSplineSurface:
    """Surface through a grid of points (nu, nv, 3), exactly at the given or chord-length parameters."""
    pts = np.asarray(points, dtype=float)
    nu, nv = pts.shape[:2]
    if nu < degree_u + 1 or nv < degree_v + 1:
        raise InputError("grid too small for the requested degrees")
    if params_u is None:
        d = np.linalg.norm(np.diff(pts, axis=0), axis=2).mean(axis=1)
        params_u = np.concatenate([[0.0], np.cumsum(d)]) / d.sum()
    if params_v is None:
        d = np.linalg.norm(np.diff(pts, axis=1), axis=2).mean(axis=0)
        params_v = np.concatenate([[0.0], np.cumsum(d)]) / d.sum()
    ku, mu = _averaged_knots(np.asarray(params_u, float), degree_u)
    kv, mv = _averaged_knots(np.asarray(params_v, float), degree_v)
    bu = collocation_matrix(np.repeat(ku, mu), degree_u, nu, params_u)
    bv = collocation_matrix(np.repeat(kv, mv), degree_v, nv, params_v)
    tmp = np.linalg.solve(bu, pts.reshape(nu, -1)).reshape(nu, nv, 3)
    poles = np.linalg.solve(bv, tmp.transpose(1, 0, 2).reshape(nv, -1)).reshape(nv, nu, 3).transpose(1, 0, 2)
    return BSplineSurface(degree_u, degree_v, ku, mu, kv, mv, poles, name=name)


def ruled_surface(c0: BSplineCurve, c1: BSplineCurve, name: str = "") -> BSplineSurface:
    """Exact ruled surface ``S(u, v) = (1 - v) C0(u) + v C1(u)``, v in [0, 1].

    The directrices are brought to a common degree and knot vector exactly; ``u`` keeps the
    domain of ``c0`` (``c1`` is mapped affinely onto it). Rational directrices stay rational.
    """
    if c0.dim != 3 or c1.dim != 3:
        raise InputError("ruled surface directrices must be 3-D curves")
    a, b = elevate_and_merge([c0, c1])
    poles = np.stack([a.poles, b.poles], axis=1)
    weights = None
    if a.weights is not None or b.weights is not None:
        wa = a.weights if a.weights is not None else np.ones(a.poles.shape[0])
        wb = b.weights if b.weights is not None else np.ones(b.poles.shape[0])
        if not np.allclose(wa, wb, rtol=0, atol=0):
            raise InputError(
                "rational directrices need identical weights for an exact ruled surface "
                "S = (1-v)C0 + vC1; reparameterise or fit them first"
            )
        weights = np.stack([wa, wb], axis=1)
    return BSplineSurface(a.degree, 1, a.knots, a.mults, [0.0, 1.0], [2, 2], poles, weights, name=name)


def revolve_profile(profile: BSplineCurve, angle_deg: float = 360.0, name: str = "") -> BSplineSurface:
    """Exact rational surface of revolution of a planar profile about the z axis.

    ``profile`` is a 2-D curve ``(rho, z)`` (rho >= 0 the distance to the axis) or a 3-D
    curve in the xz plane. ``u`` follows the profile, ``v`` the angle (degrees of turn map
    to ``v`` in [0, 1]); circular arcs are exact rational quadratics (<= 90 degrees each).
    """
    prof = profile.poles if profile.dim == 2 else profile.poles[:, [0, 2]]
    if not 0 < angle_deg <= 360:
        raise InputError("revolution angle must be in (0, 360] degrees")
    n_arcs = int(np.ceil(angle_deg / 90.0 - 1e-12))
    dth = np.radians(angle_deg) / n_arcs
    w_mid = np.cos(dth / 2)
    angles, wts = [], []
    for k in range(n_arcs):
        th0 = k * dth
        angles += [th0, th0 + dth / 2]
        wts += [1.0, w_mid]
    angles.append(n_arcs * dth)
    wts.append(1.0)
    ang = np.array(angles)
    wts_a = np.array(wts)
    rad = np.where(np.arange(ang.size) % 2 == 1, 1.0 / w_mid, 1.0)  # mid poles at the tangent corner
    cu, su_ = np.cos(ang) * rad, np.sin(ang) * rad
    rho, z = prof[:, 0], prof[:, 1]
    poles = np.stack(
        [rho[:, None] * cu[None, :], rho[:, None] * su_[None, :], np.broadcast_to(z[:, None], (rho.size, ang.size))],
        axis=-1,
    )
    pw = profile.weights if profile.weights is not None else np.ones(rho.size)
    weights = pw[:, None] * wts_a[None, :]
    kv = np.linspace(0.0, 1.0, n_arcs + 1)
    mv = np.full(n_arcs + 1, 2)
    mv[0] = mv[-1] = 3
    return BSplineSurface(profile.degree, 2, profile.knots, profile.mults, kv, mv, poles, weights, False, False, name)


def circular_arc(radius: float, start_deg: float, end_deg: float, center=(0.0, 0.0)) -> BSplineCurve:
    """Exact rational quadratic arc in the plane (2-D), counter-clockwise from start to end (degrees)."""
    if not radius > 0:
        raise InputError("arc radius must be > 0 mm")
    sweep = end_deg - start_deg
    if not 0 < abs(sweep) <= 360:
        raise InputError("arc sweep must be in (0, 360] degrees")
    n_arcs = int(np.ceil(abs(sweep) / 90.0 - 1e-12))
    d = np.radians(sweep) / n_arcs
    wm = np.cos(d / 2)
    pts, w = [], []
    for k in range(n_arcs):
        a0 = np.radians(start_deg) + k * d
        pts.append([np.cos(a0), np.sin(a0)])
        am = a0 + d / 2
        pts.append([np.cos(am) / wm, np.sin(am) / wm])
        w += [1.0, wm]
    a1 = np.radians(end_deg)
    pts.append([np.cos(a1), np.sin(a1)])
    w.append(1.0)
    pts = np.array(pts) * radius + np.asarray(center, float)
    kn = np.linspace(0, 1, n_arcs + 1)
    mu = np.full(n_arcs + 1, 2)
    mu[0] = mu[-1] = 3
    return BSplineCurve(2, kn, mu, pts, np.array(w))


def sphere_patch(
    radius: float = 50.0, lat_deg=(-60.0, 60.0), lon_deg: float = 90.0, name: str = "sphere"
) -> BSplineSurface:
    """Exact rational patch of a sphere of ``radius`` mm centred at the origin.

    u runs along the meridian from ``lat_deg[0]`` to ``lat_deg[1]`` (degrees), v along the
    longitude from 0 to ``lon_deg``. With this parameterisation ``su x sv`` points to the
    centre, so both principal curvatures are ``+1/radius``.
    """
    prof = circular_arc(radius, lat_deg[0], lat_deg[1])  # (cos, sin) -> (rho, z)
    return revolve_profile(prof, lon_deg, name=name)


def cylinder_patch(
    radius: float = 30.0, height: float = 60.0, angle_deg: float = 90.0, name: str = "cylinder"
) -> BSplineSurface:
    """Exact rational patch of a cylinder of axis z (u along z from 0 to ``height``)."""
    prof = BSplineCurve(1, [0, 1], [2, 2], [[radius, 0.0], [radius, height]])
    return revolve_profile(prof, angle_deg, name=name)


def torus_patch(
    major: float = 40.0, minor: float = 10.0, tube_deg=(-90.0, 90.0), angle_deg: float = 90.0, name: str = "torus"
) -> BSplineSurface:
    """Exact rational patch of a torus of axis z: centre-circle radius ``major``, tube radius ``minor``."""
    prof = circular_arc(minor, tube_deg[0], tube_deg[1], center=(major, 0.0))
    return revolve_profile(prof, angle_deg, name=name)


def plane_patch(
    origin=(0.0, 0.0, 0.0), du=(100.0, 0.0, 0.0), dv=(0.0, 100.0, 0.0), name: str = "plane"
) -> BSplineSurface:
    """Planar bilinear patch ``origin + u du + v dv`` on [0, 1]^2."""
    o, a, b = (np.asarray(x, float) for x in (origin, du, dv))
    return bezier_surface([[o, o + b], [o + a, o + a + b]], name=name)
