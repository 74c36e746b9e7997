"""Exact knot insertion, degree elevation and knot merging of B-spline curves and surfaces."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .basis import basis_derivatives, collocation_matrix, find_spans, greville
from .bspline import BSplineCurve, BSplineSurface


def insert_knot_curve(curve: BSplineCurve, x: float, times: int = 1) -> BSplineCurve:
    """Boehm knot insertion (exact: the curve is unchanged). Non-periodic curves only."""
    if curve.periodic:
        raise InputError("knot insertion on periodic curves is not supported; unperiodise first")
    c = curve
    for _ in range(times):
        c = _insert_once(c, float(x))
    return c


def _insert_once(c: BSplineCurve, x: float) -> BSplineCurve:
    p = c.degree
    t = np.repeat(c.knots, c.mults)
    n = c.poles.shape[0]
    lo, hi = c.bounds
    if not (lo < x < hi):
        raise InputError(f"knot {x} outside the open domain ({lo}, {hi})")
    k = int(find_spans(t, p, n, np.array([x]))[0])
    hp = c.poles if c.weights is None else np.concatenate([c.poles * c.weights[:, None], c.weights[:, None]], 1)
    new = np.empty((n + 1, hp.shape[1]))
    new[: k - p + 1] = hp[: k - p + 1]
    new[k + 1 :] = hp[k:]
    for i in range(k - p + 1, k + 1):
        alpha = (x - t[i]) / (t[i + p] - t[i])
        new[i] = alpha * hp[i] + (1 - alpha) * hp[i - 1]
    knots, mults = list(c.knots), list(c.mults)
    j = np.searchsorted(c.knots, x)
    if j < len(knots) and knots[j] == x:
        mults[j] += 1
        if mults[j] > p:
            raise InputError(f"knot {x} would exceed multiplicity {p}")
    else:
        knots.insert(j, x)
        mults.insert(j, 1)
    if c.weights is None:
        return BSplineCurve(p, knots, mults, new)
    return BSplineCurve(p, knots, mults, new[:, :-1] / new[:, -1:], new[:, -1])


def _curve_as_surface_rows(s: BSplineSurface, direction: str):
    """Helper: view a surface as a bundle of curves along ``direction`` (homogeneous poles)."""
    hp = s.poles if s.weights is None else np.concatenate([s.poles * s.weights[..., None], s.weights[..., None]], 2)
    return hp if direction == "u" else hp.transpose(1, 0, 2)


def insert_knot_surface(surface: BSplineSurface, x: float, direction: str = "u", times: int = 1) -> BSplineSurface:
    """Exact knot insertion along ``direction`` ("u" or "v"); the surface is unchanged."""
    if direction not in ("u", "v"):
        raise InputError("direction must be 'u' or 'v'")
    s = surface
    if (s.periodic_u and direction == "u") or (s.periodic_v and direction == "v"):
        raise InputError("knot insertion on a periodic direction is not supported")
    hp = _curve_as_surface_rows(s, direction)  # (n_dir, n_other, dim)
    deg = s.degree_u if direction == "u" else s.degree_v
    knots = s.knots_u if direction == "u" else s.knots_v
    mults = s.mults_u if direction == "u" else s.mults_v
    n, m, dim = hp.shape
    # treat all rows at once as one vector-valued curve of dimension m*dim
    flat = hp.reshape(n, m * dim)
    out_poles = None
    new_knots, new_mults = knots, mults
    for _ in range(times):
        t = np.repeat(new_knots, new_mults)
        nn = flat.shape[0]
        k = int(find_spans(t, deg, nn, np.array([x]))[0])
        lo, hi = t[deg], t[nn]
        if not (lo < x < hi):
            raise InputError(f"knot {x} outside the open domain ({lo}, {hi})")
        new = np.empty((nn + 1, flat.shape[1]))
        new[: k - deg + 1] = flat[: k - deg + 1]
        new[k + 1 :] = flat[k:]
        for i in range(k - deg + 1, k + 1):
            alpha = (x - t[i]) / (t[i + deg] - t[i])
            new[i] = alpha * flat[i] + (1 - alpha) * flat[i - 1]
        flat = new
        kl, ml = list(new_knots), list(new_mults)
        j = int(np.searchsorted(new_knots, x))
        if j < len(kl) and kl[j] == x:
            ml[j] += 1
            if ml[j] > deg:
                raise InputError(f"knot {x} would exceed multiplicity {deg}")
        else:
            kl.insert(j, x)
            ml.insert(j, 1)
        new_knots, new_mults = np.array(kl), np.array(ml)
    out = flat.reshape(-1, m, dim)
    if direction == "v":
        out = out.transpose(1, 0, 2)
    out_poles = out[..., :3]
    weights = None
    if s.weights is not None:
        weights = out[..., 3]
        out_poles = out_poles / weights[..., None]
    if direction == "u":
        return BSplineSurface(
            s.degree_u,
            s.degree_v,
            new_knots,
            new_mults,
            s.knots_v,
            s.mults_v,
            out_poles,
            weights,
            False,
            s.periodic_v,
            s.name,
        )
    return BSplineSurface(
        s.degree_u,
        s.degree_v,
        s.knots_u,
        s.mults_u,
        new_knots,
        new_mults,
        out_poles,
        weights,
        s.periodic_u,
        False,
        s.name,
    )


def refit_curve_in_space(curve: BSplineCurve, degree: int, knots, mults) -> BSplineCurve:
    """Represent ``curve`` exactly in a larger spline space (degree elevation / knot merging).

    The target space must contain the curve (higher or equal degree, knots including the
    curve's knots with multiplicity raised by the degree increase); the poles are found by
    interpolation at the Greville abscissae of the target space, which is exact for a curve
    of that space up to round-off. Works in homogeneous coordinates for rational curves.
    """
    knots = np.asarray(knots, float)
    mults = np.asarray(mults, int)
    t = np.repeat(knots, mults)
    n = int(mults.sum()) - degree - 1
    g = greville(t, degree, n)
    b = collocation_matrix(t, degree, n, g)
    tc, hp = curve._eval_data
    spans = find_spans(tc, curve.degree, hp.shape[0], g)
    ders = basis_derivatives(tc, curve.degree, spans, g, 0)[:, 0, :]
    idx = spans[:, None] - curve.degree + np.arange(curve.degree + 1)[None, :]
    vals = np.einsum("mj,mjd->md", ders, hp[idx])
    sol = np.linalg.solve(b, vals)
    if curve.weights is None:
        return BSplineCurve(degree, knots, mults, sol)
    return BSplineCurve(degree, knots, mults, sol[:, :-1] / sol[:, -1:], sol[:, -1])


def elevate_and_merge(curves: list[BSplineCurve]) -> list[BSplineCurve]:
    """Bring curves to a common degree and knot vector (exactly), e.g. for ruled surfaces.

    Parameter domains are first mapped to the domain of the first curve by an affine change.
    """
    if any(c.periodic for c in curves):
        raise InputError("periodic curves are not supported here")
    deg = max(c.degree for c in curves)
    lo, hi = curves[0].bounds
    mapped = []
    for c in curves:
        a, b = c.bounds
        k = lo + (c.knots - a) * (hi - lo) / (b - a)
        k[np.isclose(k, lo, rtol=0, atol=1e-13 * (hi - lo))] = lo
        k[np.isclose(k, hi, rtol=0, atol=1e-13 * (hi - lo))] = hi
        mapped.append(BSplineCurve(c.degree, k, c.mults, c.poles, c.weights))
    all_knots: dict[float, int] = {}
    for c in mapped:
        inc = deg - c.degree
        for kk, mm in zip(c.knots, c.mults):
            key = float(np.round(kk, 14))
            if not (lo < key < hi):
                continue  # ends are clamped below; knots outside an open domain are not breaks
            all_knots[key] = max(all_knots.get(key, 0), min(int(mm) + inc, deg))
    all_knots[lo] = all_knots[hi] = deg + 1
    ks = np.array(sorted(all_knots))
    ms = np.array([all_knots[float(k)] for k in ks])
    ms[0] = ms[-1] = deg + 1
    return [refit_curve_in_space(c, deg, ks, ms) for c in mapped]
