"""Certified approximation of a surface map by a B-spline surface (numpy only).

A map ``f(us, vs) -> (len(us), len(vs), 3)`` in mm (evaluated on tensor grids) is fitted
by a B-spline surface of chosen degrees (default bicubic with simple interior knots, so C2)
keeping the map's parameterisation: ``fit.surface(u, v)`` approximates ``f(u, v)``. Knots are
refined where the error is, until the max-norm error measured on points the fit never saw
(the midpoints between fit samples in every knot span, plus an independent uniform grid)
is within the tolerance. When the pole budget runs out first, :class:`ToleranceError` says
the error reached. This engine is shared by the machining surfaces and the envelopes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, ToleranceError
from .geometry.basis import collocation_matrix
from .geometry.bspline import BSplineSurface
from .results import Result
from .typing import ArrayLike, ProgressLike

GridMap = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class SurfaceFit(Result):
    """A fitted surface with its measured error (mm), never a tolerance it did not measure.

    ``max_error`` is the largest distance ``|fit(u, v) - f(u, v)|`` over ``n_check`` points the
    least-squares fit never used; ``history`` lists ``(poles_u, poles_v, max_error)`` per
    refinement step.
    """

    surface: BSplineSurface
    tolerance: float
    max_error: float
    rms_error: float
    n_check: int
    worst_uv: tuple
    history: tuple = field(default_factory=tuple)

    @property
    def n_poles(self) -> int:
        return int(self.surface.shape[0] * self.surface.shape[1])

    def report(self) -> dict:
        s = self.surface
        return {
            "tolerance_mm": self.tolerance,
            "max_error_mm": self.max_error,
            "rms_error_mm": self.rms_error,
            "n_check_points": self.n_check,
            "worst_uv": list(self.worst_uv),
            "degrees": [s.degree_u, s.degree_v],
            "poles": [int(s.shape[0]), int(s.shape[1])],
            "n_poles": self.n_poles,
            "knot_spans": [int(s.knots_u.size - 1), int(s.knots_v.size - 1)],
            "iterations": len(self.history),
        }


def _fractions(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Fit-sample and check-point positions inside one knot span (as fractions of it)."""
    k = degree + 2
    fit = np.arange(k) / k  # span start included, end belongs to the next span
    check = (np.arange(k) + 0.5) / k  # halfway between fit samples: never seen by the fit
    return fit, check


def _params(breaks: np.ndarray, fracs: np.ndarray, include_end: bool) -> np.ndarray:
    a, b = breaks[:-1, None], breaks[1:, None]
    x = (a + (b - a) * fracs[None, :]).ravel()
    if include_end:
        x = np.append(x, breaks[-1])
    return x


def _knot_vectors(breaks: np.ndarray, degree: int, fixed: dict | None = None):
    mults = np.ones(breaks.size, dtype=int)
    if fixed:
        for i, b in enumerate(breaks):
            mults[i] = max(1, min(degree, fixed.get(float(b), 1)))
    mults[0] = mults[-1] = degree + 1
    return breaks, mults, np.repeat(breaks, mults)


def _lstsq(b: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    sol, *_ = np.linalg.lstsq(b, rhs, rcond=None)
    return sol


def fit_surface(
    f: GridMap,
    bounds: Sequence[float],
    *,
    tolerance: float,
    degree: Sequence[int] = (3, 3),
    max_poles: int = 40000,
    initial_spans: Sequence[int] = (4, 4),
    max_iter: int = 40,
    check_grid: int = 101,
    name: str = "",
    breaks: tuple[tuple[ArrayLike, ArrayLike], tuple[ArrayLike, ArrayLike]] | None = None,
    progress: ProgressLike = None,
) -> SurfaceFit:
    """Fit ``f`` over ``bounds = (u0, u1, v0, v1)`` within ``tolerance`` (max-norm distance, mm).

    Parameters
    ----------
    f : callable
        Vectorised map on tensor grids: ``f(us, vs)`` returns shape ``(len(us), len(vs), 3)``.
    tolerance : float
        Required max-norm error ``|fit - f|`` in mm, measured on points the fit never saw.
    degree : (int, int)
        Degrees along u and v (default bicubic; interior knots are simple, so C^(degree-1)).
    max_poles : int
        Pole budget; reaching it before the tolerance raises :class:`ToleranceError`.
    breaks : ((knots_u, mults_u), (knots_v, mults_v)), optional
        Knots where the map is less smooth (e.g. the knots of the surface it is derived
        from), kept in the fit with these multiplicities (C^(degree - mult) there).
    progress : callable, optional
        :data:`~machsurf_cad.results.Progress`: ``progress(iteration, None, "<poles> poles, error <e> mm")``
        after each refinement (the total is not known in advance).

    Returns
    -------
    SurfaceFit
        The B-spline surface and its error measured on unseen points (max, RMS, worst uv).

    Raises
    ------
    ToleranceError
        The pole budget or iteration limit was reached first; ``reached`` holds the error (mm).
    DegenerateGeometryError
        The map returned non-finite values (the region is named).

    Examples
    --------
    >>> import numpy as np
    >>> def paraboloid(us, vs):
    ...     U, V = np.meshgrid(us, vs, indexing="ij")
    ...     return np.stack([U, V, 0.01 * (U ** 2 + V ** 2)], axis=-1)
    >>> fit = fit_surface(paraboloid, (0, 100, 0, 100), tolerance=1e-6)
    >>> fit.max_error < 1e-6
    True
    """
    if not tolerance > 0:
        raise InputError("tolerance must be > 0 mm")
    p, q = (int(d) for d in degree)
    if p < 1 or q < 1 or p > 9 or q > 9:
        raise InputError("fit degrees must be between 1 and 9")
    u0, u1, v0, v1 = (float(x) for x in bounds)
    if not (u1 > u0 and v1 > v0):
        raise InputError("empty parameter domain")
    bu, bv, fixed_u, fixed_v = _initial_breaks(u0, u1, v0, v1, initial_spans, breaks)
    fu, cu = _fractions(p)
    fv, cv = _fractions(q)
    # an independent uniform grid shifted by an irrational fraction of its step, so that it never
    # meets a knot or a fit sample (those sit at rational fractions of the spans)
    shift = (np.arange(check_grid) + 0.3819660112501051) / check_grid
    gu = u0 + (u1 - u0) * shift
    gv = v0 + (v1 - v0) * shift
    f_grid = np.asarray(f(gu, gv), dtype=float)
    _check_map_values(f_grid, "the map")
    history = []
    for it in range(max_iter):
        surf, mu, mv, nu, nv = _least_squares(f, bu, bv, p, q, fu, fv, fixed_u, fixed_v, name)
        # error on the span interiors between fit samples (never seen) ...
        cus, cvs = _params(bu, cu, False), _params(bv, cv, False)
        err = np.linalg.norm(surf.evaluate_grid(cus, cvs) - np.asarray(f(cus, cvs), dtype=float), axis=-1)
        # ... and on the independent uniform grid
        err_g = np.linalg.norm(surf.evaluate_grid(gu, gv) - f_grid, axis=-1)
        max_err = float(max(err.max(), err_g.max()))
        history.append((nu, nv, max_err))
        if progress is not None:
            progress(it, None, f"{nu * nv} poles, error {max_err:.3g} mm")
        if max_err <= tolerance:
            return _surface_fit(surf, tolerance, max_err, err, err_g, (cus, cvs), (gu, gv), history)
        # refine: split every knot span that holds a point above tolerance, per direction
        bad_u, bad_v = _spans_to_split(err, err_g, bu, bv, cu.size, cv.size, gu, gv, tolerance)
        new_u = int(mu.sum()) - p - 1 + int(bad_u.sum())
        new_v = int(mv.sum()) - q - 1 + int(bad_v.sum())
        if new_u * new_v > max_poles:
            raise ToleranceError(
                f"surface fit did not reach {tolerance:g} mm within {max_poles} poles "
                f"(reached {max_err:.3g} mm with {nu}x{nv} poles)",
                max_err,
            )
        bu = _split(bu, bad_u)
        bv = _split(bv, bad_v)
    raise ToleranceError(
        f"surface fit did not reach {tolerance:g} mm in {max_iter} refinements (reached {history[-1][2]:.3g} mm)",
        history[-1][2],
    )


def _initial_breaks(u0: float, u1: float, v0: float, v1: float, initial_spans, breaks):
    """The first span breaks along u and v, with the given ``breaks`` inside the domain and their multiplicities."""
    bu = np.linspace(u0, u1, max(1, initial_spans[0]) + 1)
    bv = np.linspace(v0, v1, max(1, initial_spans[1]) + 1)
    fixed_u, fixed_v = {}, {}
    if breaks is not None:
        (ku_, mu_), (kv_, mv_) = breaks
        for k, m in zip(np.asarray(ku_, float), np.asarray(mu_, int)):
            if u0 < k < u1:
                fixed_u[float(k)] = int(m)
        for k, m in zip(np.asarray(kv_, float), np.asarray(mv_, int)):
            if v0 < k < v1:
                fixed_v[float(k)] = int(m)
        bu = _merge_breaks(bu, np.array(sorted(fixed_u)))
        bv = _merge_breaks(bv, np.array(sorted(fixed_v)))
    return bu, bv, fixed_u, fixed_v


def _least_squares(f: GridMap, bu, bv, p: int, q: int, fu, fv, fixed_u: dict, fixed_v: dict, name: str):
    """The least-squares B-spline surface on the breaks ``bu`` x ``bv``, its multiplicities and pole counts."""
    ku, mu, tu = _knot_vectors(bu, p, fixed_u)
    kv, mv, tv = _knot_vectors(bv, q, fixed_v)
    nu, nv = tu.size - p - 1, tv.size - q - 1
    us, vs = _params(bu, fu, True), _params(bv, fv, True)
    vals = np.asarray(f(us, vs), dtype=float)
    _check_map_values(vals, "the map")
    Bu = collocation_matrix(tu, p, nu, us)
    Bv = collocation_matrix(tv, q, nv, vs)
    tmp = _lstsq(Bu, vals.reshape(us.size, -1)).reshape(nu, vs.size, 3)
    poles = _lstsq(Bv, tmp.transpose(1, 0, 2).reshape(vs.size, -1)).reshape(nv, nu, 3).transpose(1, 0, 2)
    return BSplineSurface(p, q, ku, mu, kv, mv, poles, name=name), mu, mv, nu, nv


def _surface_fit(surf, tolerance: float, max_err: float, err, err_g, check, grid, history: list) -> SurfaceFit:
    """The fit within tolerance: its worst point (on the span check points or the uniform grid) and RMS error."""
    cus, cvs = check
    gu, gv = grid
    if err.max() >= err_g.max():
        i, j = np.unravel_index(np.argmax(err), err.shape)
        worst = (float(cus[i]), float(cvs[j]))
    else:
        i, j = np.unravel_index(np.argmax(err_g), err_g.shape)
        worst = (float(gu[i]), float(gv[j]))
    rms = float(np.sqrt((np.sum(err**2) + np.sum(err_g**2)) / (err.size + err_g.size)))
    return SurfaceFit(surf, float(tolerance), max_err, rms, int(err.size + err_g.size), worst, tuple(history))


def _spans_to_split(err, err_g, bu, bv, k_u: int, k_v: int, gu, gv, tolerance: float):
    """The knot spans along u and along v that hold a check point above tolerance (:func:`_directional`)."""
    bad_u = np.zeros(bu.size - 1, bool)
    bad_v = np.zeros(bv.size - 1, bool)
    e4 = err.reshape(bu.size - 1, k_u, bv.size - 1, k_v)
    bad_u |= e4.max(axis=(1, 2, 3)) > tolerance
    bad_v |= e4.max(axis=(0, 1, 3)) > tolerance
    iu = np.clip(np.searchsorted(bu, gu, side="right") - 1, 0, bu.size - 2)
    iv = np.clip(np.searchsorted(bv, gv, side="right") - 1, 0, bv.size - 2)
    gi, gj = np.nonzero(err_g > tolerance)
    bad_u[iu[gi]] = True
    bad_v[iv[gj]] = True
    return _directional(bad_u, bad_v, e4, tolerance)


def _directional(bad_u, bad_v, e4, tol):
    """Refine only the direction whose error varies most within the bad spans.

    In a bad span pair, compare the error's spread along u and along v over the span's check
    points: a map that is hard along u only needs no new v knots there. Always refines at
    least one direction.
    """
    if not bad_u.any() or not bad_v.any():
        return bad_u, bad_v
    sub = e4[bad_u][:, :, bad_v]  # (bu, ku, bv, kv)
    spread_u = np.ptp(sub, axis=1).max()
    spread_v = np.ptp(sub, axis=3).max()
    if spread_u > 4 * spread_v:
        return bad_u, np.zeros_like(bad_v)
    if spread_v > 4 * spread_u:
        return np.zeros_like(bad_u), bad_v
    return bad_u, bad_v


def _merge_breaks(base: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """Union of break points, dropping uniform breaks that nearly coincide with given ones."""
    if extra.size == 0:
        return base
    span = base[-1] - base[0]
    keep = [b for b in base[1:-1] if np.min(np.abs(extra - b)) > 1e-3 * span]
    return np.unique(np.concatenate([[base[0]], keep, extra, [base[-1]]]))


def _split(breaks: np.ndarray, bad: np.ndarray) -> np.ndarray:
    mids = 0.5 * (breaks[:-1] + breaks[1:])[bad]
    return np.sort(np.concatenate([breaks, mids]))


def _check_map_values(vals: np.ndarray, what: str) -> None:
    if vals.ndim != 3 or vals.shape[2] != 3:
        raise InputError(f"{what} must return an array of shape (len(us), len(vs), 3)")
    if not np.all(np.isfinite(vals)):
        bad = np.argwhere(~np.isfinite(vals).all(axis=2))
        raise InputError(f"{what} is not finite at {len(bad)} sample(s) (first at grid index {bad[0].tolist()})")
