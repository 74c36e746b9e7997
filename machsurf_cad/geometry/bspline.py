"""Immutable B-spline / NURBS curve and surface types with exact vectorised evaluation.

Geometry crosses kernels as plain arrays in the OpenCASCADE convention: ``degree``,
distinct ``knots`` with integer ``mults``, ``poles`` and optional ``weights``, and a
``periodic`` flag. Coordinates are millimetres; parameters are dimensionless.

Knot conventions (as in OCCT's ``Geom_BSplineCurve``):

* non-periodic: ``sum(mults) == n_poles + degree + 1``; clamped when the end
  multiplicities are ``degree + 1``, otherwise "open" (unclamped), with the domain
  ``[t[degree], t[n_poles]]`` of the flat knot vector ``t``;
* periodic: ``mults[0] == mults[-1]`` and ``sum(mults[:-1]) == n_poles``; the domain is
  ``[knots[0], knots[-1]]`` and the basis repeats with that period.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import InputError
from ..results import Result
from .basis import basis_derivatives, find_spans
from .normals import unit_normals

_CHUNK = 1 << 14  # best of 2^13..2^16 on the benchmark machine (fits the caches)
_THREADS = max(1, min(4, os.cpu_count() or 1))
_POWER_MAX_DEGREE = 7  # power basis on [0, 1] spans is well conditioned up to here


def _power_rows(x: np.ndarray, degree: int, order: int, h: np.ndarray) -> np.ndarray:
    """Rows ``[x^a]``, ``[d/du x^a]``, ``[d2/du2 x^a]`` (x = (u - t_i)/h) for a = 0..degree."""
    m = x.shape[0]
    pw = np.empty((m, degree + 1))
    pw[:, 0] = 1.0
    for a in range(1, degree + 1):
        pw[:, a] = pw[:, a - 1] * x
    rows = np.zeros((m, order + 1, degree + 1))
    rows[:, 0] = pw
    if order >= 1:
        rows[:, 1, 1:] = pw[:, :-1] * (np.arange(1, degree + 1) / h[:, None])
    if order >= 2 and degree >= 2:
        k2 = np.arange(2, degree + 1)
        rows[:, 2, 2:] = pw[:, :-2] * (k2 * (k2 - 1) / (h * h)[:, None])
    return rows


def _wrap_period(x: np.ndarray, x0: float, x1: float) -> np.ndarray:
    w = np.mod(x - x0, x1 - x0)
    return x0 + np.where(w >= x1 - x0, 0.0, w)


def _frozen(a, dtype=float) -> np.ndarray:
    arr = np.array(a, dtype=dtype)  # copy: callers keep their arrays
    arr.setflags(write=False)
    return arr


def _check_knots(degree: int, knots: np.ndarray, mults: np.ndarray, n_poles: int, periodic: bool, what: str) -> None:
    if degree < 1:
        raise InputError(f"{what}: degree must be >= 1, got {degree}")
    if knots.ndim != 1 or knots.shape != mults.shape or knots.size < 2:
        raise InputError(f"{what}: knots and mults must be 1-D arrays of equal length >= 2")
    if not np.all(np.isfinite(knots)):
        raise InputError(f"{what}: knots must be finite")
    if np.any(np.diff(knots) <= 0):
        raise InputError(f"{what}: knots must be strictly increasing (repeat them with mults)")
    if np.any(mults < 1) or np.any(mults[1:-1] > degree) or mults[0] > degree + 1 or mults[-1] > degree + 1:
        raise InputError(f"{what}: multiplicities out of range for degree {degree}: {mults.tolist()}")
    if periodic:
        if mults[0] != mults[-1] or int(mults[:-1].sum()) != n_poles:
            raise InputError(f"{what}: periodic knots need mults[0] == mults[-1] and sum(mults[:-1]) == n_poles")
    elif int(mults.sum()) != n_poles + degree + 1:
        raise InputError(f"{what}: sum(mults) = {int(mults.sum())} but n_poles + degree + 1 = {n_poles + degree + 1}")


def _unperiodize(degree: int, knots: np.ndarray, mults: np.ndarray, periodic: bool):
    """Flat knot vector and pole index map of the equivalent non-periodic spline.

    Returns ``(t, index)`` where pole ``index[i]`` of the original spline is the ``i``-th
    pole of the non-periodic spline with flat knots ``t``.
    """
    if not periodic:
        t = np.repeat(knots, mults)
        return t, np.arange(int(mults.sum()) - degree - 1)
    n = int(mults[:-1].sum())
    period = knots[-1] - knots[0]
    base = np.repeat(knots[:-1], mults[:-1])  # t_0 .. t_{n-1}
    j = np.arange(-degree - mults[0] + 1, n + degree + 1 + mults[0])
    t_all = base[j % n] + period * (j // n)
    # choose the window of n + 2p + 1 knots whose middle span starts at knots[0]
    first = int(np.nonzero(j == 0)[0][0]) + mults[0] - 1  # index of last copy of knots[0]
    start = first - degree
    t = t_all[start : start + n + 2 * degree + 1]
    index = np.arange(n + degree) % n  # OCCT's convention, checked against Geom_BSplineSurface
    return t, index


@dataclass(frozen=True, eq=False)
class BSplineCurve:
    """A B-spline or NURBS curve in 2-D or 3-D (coordinates in mm).

    Parameters
    ----------
    degree : int
        Polynomial degree (>= 1).
    knots, mults : array_like
        Distinct knots and their multiplicities.
    poles : array_like, shape (n, dim)
        Control points, ``dim`` 2 or 3.
    weights : array_like, shape (n,), optional
        Positive weights; ``None`` for a non-rational curve.
    periodic : bool
        Periodic knot vector (see module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> from machsurf_cad.geometry import BSplineCurve
    >>> c = BSplineCurve(1, [0.0, 1.0], [2, 2], [[0, 0, 0], [10, 0, 0]])
    >>> c.evaluate(0.25).tolist()
    [2.5, 0.0, 0.0]
    """

    degree: int
    knots: np.ndarray
    mults: np.ndarray
    poles: np.ndarray
    weights: np.ndarray | None = None
    periodic: bool = False

    def __post_init__(self):
        object.__setattr__(self, "degree", int(self.degree))
        object.__setattr__(self, "knots", _frozen(self.knots))
        object.__setattr__(self, "mults", _frozen(self.mults, dtype=np.int64))
        poles = _frozen(self.poles)
        if poles.ndim != 2 or poles.shape[1] not in (2, 3) or not np.all(np.isfinite(poles)):
            raise InputError("curve poles must be a finite (n, 2) or (n, 3) array")
        object.__setattr__(self, "poles", poles)
        if self.weights is not None:
            w = _frozen(self.weights)
            if w.shape != (poles.shape[0],) or not np.all(w > 0):
                raise InputError("curve weights must be positive, one per pole")
            object.__setattr__(self, "weights", w)
        object.__setattr__(self, "periodic", bool(self.periodic))
        _check_knots(self.degree, self.knots, self.mults, poles.shape[0], self.periodic, "curve")

    def __eq__(self, other):  # exact, never tolerant
        if not isinstance(other, BSplineCurve):
            return NotImplemented
        return (
            self.degree == other.degree
            and self.periodic == other.periodic
            and np.array_equal(self.knots, other.knots)
            and np.array_equal(self.mults, other.mults)
            and np.array_equal(self.poles, other.poles)
            and (
                (self.weights is None and other.weights is None)
                or (
                    self.weights is not None
                    and other.weights is not None
                    and np.array_equal(self.weights, other.weights)
                )
            )
        )

    __hash__ = None  # type: ignore[assignment]  # arrays inside: not hashable by value

    @property
    def is_rational(self) -> bool:
        return self.weights is not None

    @property
    def dim(self) -> int:
        return self.poles.shape[1]

    @property
    def bounds(self) -> tuple[float, float]:
        t = self._eval_knots
        return float(t[self.degree]), float(t[-self.degree - 1])

    @property
    def flat_knots(self) -> np.ndarray:
        """Knots repeated by multiplicity (non-periodic form for periodic curves)."""
        return self._eval_knots

    @cached_property
    def _eval_data(self):
        t, index = _unperiodize(self.degree, self.knots, self.mults, self.periodic)
        hp = self.poles[index]
        if self.weights is not None:
            w = self.weights[index]
            hp = np.concatenate([hp * w[:, None], w[:, None]], axis=1)
        return t, hp

    @property
    def _eval_knots(self) -> np.ndarray:
        return self._eval_data[0]

    def derivatives(self, x, order: int = 1) -> np.ndarray:
        """Point and derivatives, shape ``x.shape + (order + 1, dim)`` (mm, mm per unit parameter)."""
        x = np.asarray(x, dtype=float)
        shape = x.shape
        x = x.ravel()
        t, hp = self._eval_data
        n = hp.shape[0]
        spans = find_spans(t, self.degree, n, x)
        ders = basis_derivatives(t, self.degree, spans, x, order)
        idx = spans[:, None] - self.degree + np.arange(self.degree + 1)[None, :]
        cw = np.einsum("mkj,mjd->mkd", ders, hp[idx])
        if self.weights is not None:
            cw = _rational_curve_derivs(cw, order)
        return cw.reshape(shape + (order + 1, self.dim))

    def evaluate(self, x) -> np.ndarray:
        """Points at parameters ``x``, shape ``x.shape + (dim,)`` in mm."""
        return self.derivatives(x, 0)[..., 0, :]

    def with_poles(self, poles, weights=None) -> BSplineCurve:
        return BSplineCurve(self.degree, self.knots, self.mults, poles, weights, self.periodic)

    def to_dict(self) -> dict:
        """Plain-data form (JSON-friendly) of the curve."""
        return {
            "degree": self.degree,
            "knots": self.knots.tolist(),
            "mults": self.mults.tolist(),
            "poles": self.poles.tolist(),
            "weights": None if self.weights is None else self.weights.tolist(),
            "periodic": self.periodic,
        }


def _rational_curve_derivs(cw: np.ndarray, order: int) -> np.ndarray:
    a = cw[..., :-1]
    w = cw[..., -1]
    out = np.empty_like(a)
    from math import comb

    for k in range(order + 1):
        v = a[:, k].copy()
        for i in range(1, k + 1):
            v -= comb(k, i) * w[:, i, None] * out[:, k - i]
        out[:, k] = v / w[:, 0, None]
    return out


@dataclass(frozen=True, eq=False)
class SurfaceDerivatives(Result):
    """Point and partial derivatives of a surface (mm per unit parameter), each shape ``(..., 3)``."""

    point: np.ndarray
    su: np.ndarray
    sv: np.ndarray
    suu: np.ndarray | None = None
    suv: np.ndarray | None = None
    svv: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class BSplineSurface:
    """A tensor-product B-spline or NURBS surface (coordinates in mm).

    Poles are indexed ``poles[i, j]`` with ``i`` along u and ``j`` along v. Normals are
    ``su x sv / |su x sv|``; curvatures are signed with respect to that normal.

    Examples
    --------
    >>> import numpy as np
    >>> from machsurf_cad.geometry import BSplineSurface
    >>> poles = [[[0, 0, 0], [0, 10, 0]], [[10, 0, 0], [10, 10, 0]]]
    >>> s = BSplineSurface(1, 1, [0, 1], [2, 2], [0, 1], [2, 2], poles)
    >>> s.evaluate(0.5, 0.5).tolist()
    [5.0, 5.0, 0.0]
    """

    degree_u: int
    degree_v: int
    knots_u: np.ndarray
    mults_u: np.ndarray
    knots_v: np.ndarray
    mults_v: np.ndarray
    poles: np.ndarray
    weights: np.ndarray | None = None
    periodic_u: bool = False
    periodic_v: bool = False
    name: str = field(default="", compare=False)

    def __post_init__(self):
        for key in ("degree_u", "degree_v"):
            object.__setattr__(self, key, int(getattr(self, key)))
        for key in ("knots_u", "knots_v"):
            object.__setattr__(self, key, _frozen(getattr(self, key)))
        for key in ("mults_u", "mults_v"):
            object.__setattr__(self, key, _frozen(getattr(self, key), dtype=np.int64))
        poles = _frozen(self.poles)
        if poles.ndim != 3 or poles.shape[2] != 3 or not np.all(np.isfinite(poles)):
            raise InputError("surface poles must be a finite (nu, nv, 3) array")
        object.__setattr__(self, "poles", poles)
        if self.weights is not None:
            w = _frozen(self.weights)
            if w.shape != poles.shape[:2] or not np.all(w > 0):
                raise InputError("surface weights must be positive, shape (nu, nv)")
            object.__setattr__(self, "weights", w)
        object.__setattr__(self, "periodic_u", bool(self.periodic_u))
        object.__setattr__(self, "periodic_v", bool(self.periodic_v))
        _check_knots(self.degree_u, self.knots_u, self.mults_u, poles.shape[0], self.periodic_u, "surface u")
        _check_knots(self.degree_v, self.knots_v, self.mults_v, poles.shape[1], self.periodic_v, "surface v")

    def __eq__(self, other):  # exact, never tolerant
        if not isinstance(other, BSplineSurface):
            return NotImplemented
        same_w = (self.weights is None and other.weights is None) or (
            self.weights is not None and other.weights is not None and np.array_equal(self.weights, other.weights)
        )
        return (
            (self.degree_u, self.degree_v, self.periodic_u, self.periodic_v)
            == (other.degree_u, other.degree_v, other.periodic_u, other.periodic_v)
            and all(
                np.array_equal(getattr(self, k), getattr(other, k))
                for k in ("knots_u", "mults_u", "knots_v", "mults_v", "poles")
            )
            and same_w
        )

    __hash__ = None  # type: ignore[assignment]  # arrays inside: not hashable by value

    # ------------------------------------------------------------------ properties
    @property
    def is_rational(self) -> bool:
        return self.weights is not None

    @property
    def shape(self) -> tuple[int, int]:
        """Number of poles along u and v."""
        return self.poles.shape[0], self.poles.shape[1]

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """Parameter domain ``(u0, u1, v0, v1)``."""
        tu, tv = self._eval_data[0], self._eval_data[1]
        p, q = self.degree_u, self.degree_v
        return float(tu[p]), float(tu[-p - 1]), float(tv[q]), float(tv[-q - 1])

    @cached_property
    def _eval_data(self):
        tu, iu = _unperiodize(self.degree_u, self.knots_u, self.mults_u, self.periodic_u)
        tv, iv = _unperiodize(self.degree_v, self.knots_v, self.mults_v, self.periodic_v)
        hp = self.poles[np.ix_(iu, iv)]
        if self.weights is not None:
            w = self.weights[np.ix_(iu, iv)]
            hp = np.concatenate([hp * w[..., None], w[..., None]], axis=2)
        return tu, tv, np.ascontiguousarray(hp)

    def with_poles(self, poles, weights=None, name: str | None = None) -> BSplineSurface:
        """Same knots and degrees, new poles (and weights)."""
        return BSplineSurface(
            self.degree_u,
            self.degree_v,
            self.knots_u,
            self.mults_u,
            self.knots_v,
            self.mults_v,
            poles,
            weights,
            self.periodic_u,
            self.periodic_v,
            self.name if name is None else name,
        )

    def renamed(self, name: str) -> BSplineSurface:
        return self.with_poles(self.poles, self.weights, name=name)

    # ------------------------------------------------------------------ evaluation
    def _homogeneous_derivs(self, u: np.ndarray, v: np.ndarray, order: int) -> np.ndarray:
        """Homogeneous derivatives ``H[m, k, l, :]`` (k along u, l along v) at scattered points."""
        tu, tv, hp = self._eval_data
        p, q = self.degree_u, self.degree_v
        nu, nv, dim = hp.shape
        su = find_spans(tu, p, nu, u)
        sv = find_spans(tv, q, nv, v)
        bu = basis_derivatives(tu, p, su, u, order)  # (m, k, p+1)
        bv = basis_derivatives(tv, q, sv, v, order)  # (m, l, q+1)
        flat = hp.reshape(nu * nv, dim)
        idx = (
            (su - p)[:, None, None] * nv
            + (sv - q)[:, None, None]
            + (np.arange(p + 1)[None, :, None] * nv + np.arange(q + 1)[None, None, :])
        )
        g = flat[idx]  # (m, p+1, q+1, dim)
        w = np.matmul(bv[:, None, :, :], g)  # (m, p+1, l, dim)
        m = u.shape[0]
        h = np.matmul(bu, w.reshape(m, p + 1, -1))  # (m, k, l*dim)
        return h.reshape(m, order + 1, order + 1, dim)

    def _wrap(self, u: np.ndarray, v: np.ndarray):
        """Bring parameters of periodic directions into the base period ``[start, end)`` (a parameter a
        rounding below the start, such as -1e-30 from a STEP face's bounds, maps to the start, not to
        ``end``)."""
        if self.periodic_u:
            u = _wrap_period(u, self.knots_u[0], self.knots_u[-1])
        if self.periodic_v:
            v = _wrap_period(v, self.knots_v[0], self.knots_v[-1])
        return u, v

    @cached_property
    def _power_data(self):
        """Per knot-span pair, the patch's Taylor (power-basis) coefficients in local [0, 1] coordinates.

        ``C[i, j, a, b] = d^a/du^a d^b/dv^b H(t_i, t_j) h_i^a h_j^b / (a! b!)`` for the homogeneous
        map H, exact for a polynomial piece. Evaluating a point is then a gather of one
        contiguous block and two small contractions, much cheaper than de Boor per point.
        """
        from math import factorial

        tu, tv, hp = self._eval_data
        p, q = self.degree_u, self.degree_v
        nu, nv, dim = hp.shape
        su = np.arange(p, nu)
        su = su[tu[su + 1] > tu[su]]
        sv = np.arange(q, nv)
        sv = sv[tv[sv + 1] > tv[sv]]
        hu = tu[su + 1] - tu[su]
        hv = tv[sv + 1] - tv[sv]
        bu = (
            basis_derivatives(tu, p, su, tu[su], p)
            * (hu[:, None] ** np.arange(p + 1) / np.array([factorial(a) for a in range(p + 1)]))[:, :, None]
        )
        bv = (
            basis_derivatives(tv, q, sv, tv[sv], q)
            * (hv[:, None] ** np.arange(q + 1) / np.array([factorial(b) for b in range(q + 1)]))[:, :, None]
        )
        iu = su[:, None] - p + np.arange(p + 1)
        iv = sv[:, None] - q + np.arange(q + 1)
        blocks = hp[iu[:, None, :, None], iv[None, :, None, :]]  # (nsu, nsv, p+1, q+1, dim)
        coeffs = np.einsum("iak,jbl,ijkld->ijabd", bu, bv, blocks)
        mapu = np.full(nu, -1)
        mapu[su] = np.arange(su.size)
        mapv = np.full(nv, -1)
        mapv[sv] = np.arange(sv.size)
        flat = np.ascontiguousarray(coeffs.reshape(su.size * sv.size, -1))
        return flat, mapu, mapv, hu, hv, sv.size

    def _power_derivs(self, u: np.ndarray, v: np.ndarray, order: int) -> np.ndarray:
        """Homogeneous derivatives ``H[m, k, l, :]`` from the power-basis patches (order <= 2)."""
        tu, tv, hp = self._eval_data
        flat, mapu, mapv, hu, hv, nsv = self._power_data
        p, q = self.degree_u, self.degree_v
        dim = hp.shape[2]
        m = u.shape[0]
        i = find_spans(tu, p, hp.shape[0], u)
        j = find_spans(tv, q, hp.shape[1], v)
        ci, cj = mapu[i], mapv[j]
        hi, hj = hu[ci], hv[cj]
        s = (u - tu[i]) / hi
        t = (v - tv[j]) / hj
        rows_u = _power_rows(s, p, order, hi)  # (m, order+1, p+1)
        rows_v = _power_rows(t, q, order, hj)  # (m, order+1, q+1)
        g = np.take(flat, ci * nsv + cj, axis=0).reshape(m, p + 1, (q + 1) * dim)
        a = np.matmul(rows_u, g).reshape(m, order + 1, q + 1, dim)  # contract over the u powers
        h = np.empty((m, order + 1, order + 1, dim))
        for k in range(order + 1):
            for l in range(order + 1 - k):
                h[:, k, l] = np.einsum("mbd,mb->md", a[:, k], rows_v[:, l])
        return h

    def derivatives(self, u, v, order: int = 1) -> SurfaceDerivatives:
        """Exact point and partial derivatives up to ``order`` (1 or 2) at scattered ``(u, v)``.

        ``u`` and ``v`` broadcast together; each output has shape ``broadcast.shape + (3,)``.
        Evaluation is chunked, so millions of points run in bounded memory.
        """
        if order not in (0, 1, 2):
            raise InputError("derivative order must be 0, 1 or 2")
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        shape = u.shape
        uf, vf = self._wrap(u.ravel(), v.ravel())
        m = uf.shape[0]
        keys = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)][: {0: 1, 1: 3, 2: 6}[order]]
        out = {k: np.empty((m, 3)) for k in keys}
        self._chunked(uf, vf, order, out, keys)
        res = [out[k].reshape(shape + (3,)) for k in keys]
        res += [None] * (6 - len(res))
        if order == 0:
            return SurfaceDerivatives(res[0], None, None)
        return SurfaceDerivatives(*res)

    def _chunked(self, uf, vf, order, out, keys, normals=None):
        """Evaluate in chunks (on all cores for large inputs); optionally unit normals per chunk."""
        m = uf.shape[0]
        use_power = self.degree_u <= _POWER_MAX_DEGREE and self.degree_v <= _POWER_MAX_DEGREE
        if use_power:
            _ = self._power_data  # build the cache once, before any worker thread

        def work(start):
            sl = slice(start, min(m, start + _CHUNK))
            if use_power:
                h = self._power_derivs(uf[sl], vf[sl], order)
            else:
                h = self._homogeneous_derivs(uf[sl], vf[sl], order)
            d = _rational_surface_derivs(h, order) if self.weights is not None else h
            for k in keys:
                out[k][sl] = d[:, k[0], k[1]]
            if normals is not None:
                normals[sl] = unit_normals(d[:, 1, 0], d[:, 0, 1], self.scale, check=False)

        starts = range(0, m, _CHUNK)
        if m > 4 * _CHUNK and _THREADS > 1:
            # numpy releases the GIL in these kernels: chunks run on all cores
            with ThreadPoolExecutor(_THREADS) as pool:
                list(pool.map(work, starts))
        else:
            for start in starts:
                work(start)

    def evaluate_with_normals(self, u, v, *, check: bool = True):
        """Points (mm) and unit normals ``su x sv / |su x sv|`` at ``(u, v)``, computed chunk by chunk.

        Raises :class:`DegenerateGeometryError` where the normal does not exist unless ``check=False``.
        """
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        shape = u.shape
        uf, vf = self._wrap(u.ravel(), v.ravel())
        out = {(0, 0): np.empty((uf.size, 3)), (1, 0): np.empty((uf.size, 3)), (0, 1): np.empty((uf.size, 3))}
        nrm = np.empty((uf.size, 3))
        self._chunked(uf, vf, 1, out, list(out), nrm)
        if check and not np.all(np.isfinite(nrm)):
            bad = ~np.isfinite(nrm).all(axis=1)
            unit_normals(out[(1, 0)][bad], out[(0, 1)][bad], self.scale, uf[bad], vf[bad], check=True)
        return out[(0, 0)].reshape(shape + (3,)), nrm.reshape(shape + (3,))

    def evaluate(self, u, v) -> np.ndarray:
        """Points at ``(u, v)`` (broadcast), in mm."""
        return self.derivatives(u, v, 0).point

    def derivatives_grid(self, us, vs, order: int = 1) -> SurfaceDerivatives:
        """Derivatives on the tensor grid ``us x vs``; outputs have shape ``(len(us), len(vs), 3)``.

        Faster than :meth:`derivatives` because basis functions are evaluated once per line.
        """
        us, vs = self._wrap(np.asarray(us, dtype=float).ravel(), np.asarray(vs, dtype=float).ravel())
        tu, tv, hp = self._eval_data
        p, q = self.degree_u, self.degree_v
        nu, nv, dim = hp.shape
        bu_full = _dense_basis(tu, p, nu, us, order)  # (k, mu, nu)
        bv_full = _dense_basis(tv, q, nv, vs, order)  # (l, mv, nv)
        # H[k, l] = Bu_k @ P @ Bv_l^T for each coordinate, as dense BLAS products
        mu, mv = us.size, vs.size
        h = np.empty((mu, mv, order + 1, order + 1, dim))
        for k in range(order + 1):
            tmp = (bu_full[k] @ hp.reshape(nu, nv * dim)).reshape(mu, nv, dim).transpose(0, 2, 1)
            for l in range(order + 1 - k):
                h[:, :, k, l] = (tmp.reshape(mu * dim, nv) @ bv_full[l].T).reshape(mu, dim, mv).transpose(0, 2, 1)
        d = (
            _rational_surface_derivs(h.reshape(-1, order + 1, order + 1, dim), order)
            if self.weights is not None
            else h.reshape(-1, order + 1, order + 1, dim)
        )
        d = d.reshape(us.size, vs.size, order + 1, order + 1, 3)
        keys = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)][: {0: 1, 1: 3, 2: 6}[order]]
        res = [d[:, :, k[0], k[1]] for k in keys]
        res += [None] * (6 - len(res))
        if order == 0:
            return SurfaceDerivatives(res[0], None, None)
        return SurfaceDerivatives(*res)

    def evaluate_grid(self, us, vs) -> np.ndarray:
        """Points on the grid ``us x vs``, shape ``(len(us), len(vs), 3)`` in mm."""
        return self.derivatives_grid(us, vs, 0).point

    def normals(self, u, v, *, check: bool = True) -> np.ndarray:
        """Unit normals ``su x sv / |su x sv|`` at ``(u, v)``.

        Raises :class:`DegenerateGeometryError` naming the parameters where the normal does
        not exist (``|su x sv|`` below 1e-12 of the squared pole extent) unless ``check=False``,
        in which case those normals are NaN.
        """
        d = self.derivatives(u, v, 1)
        return unit_normals(
            d.su, d.sv, self.scale, np.asarray(u, float), np.asarray(v, float), check=check, surface=self
        )

    @cached_property
    def scale(self) -> float:
        """Size of the control net (mm), used to make degeneracy tests scale-free."""
        ext = np.ptp(self.poles.reshape(-1, 3), axis=0)
        return float(max(np.linalg.norm(ext), 1e-300))

    def sample_grid(self, n_u: int, n_v: int) -> tuple[np.ndarray, np.ndarray]:
        """Uniform parameter samples over the domain (including its edges)."""
        u0, u1, v0, v1 = self.bounds
        return np.linspace(u0, u1, n_u), np.linspace(v0, v1, n_v)

    def to_dict(self) -> dict:
        return {
            "degree_u": self.degree_u,
            "degree_v": self.degree_v,
            "knots_u": self.knots_u.tolist(),
            "mults_u": self.mults_u.tolist(),
            "knots_v": self.knots_v.tolist(),
            "mults_v": self.mults_v.tolist(),
            "poles": self.poles.tolist(),
            "weights": None if self.weights is None else self.weights.tolist(),
            "periodic_u": self.periodic_u,
            "periodic_v": self.periodic_v,
            "name": self.name,
        }

    @classmethod
    def from_dict(cls, d: dict) -> BSplineSurface:
        return cls(
            d["degree_u"],
            d["degree_v"],
            d["knots_u"],
            d["mults_u"],
            d["knots_v"],
            d["mults_v"],
            d["poles"],
            d.get("weights"),
            d.get("periodic_u", False),
            d.get("periodic_v", False),
            d.get("name", ""),
        )


def _dense_basis(t, degree, n_poles, x, order) -> np.ndarray:
    """``B[k, m, i]``: k-th derivative of basis function i at x[m] (dense)."""
    spans = find_spans(t, degree, n_poles, x)
    ders = basis_derivatives(t, degree, spans, x, order)
    b = np.zeros((order + 1, x.size, n_poles))
    rows = np.arange(x.size)[:, None]
    cols = spans[:, None] - degree + np.arange(degree + 1)[None, :]
    for k in range(order + 1):
        b[k][rows, cols] = ders[:, k, :]
    return b


def _rational_surface_derivs(h: np.ndarray, order: int) -> np.ndarray:
    """Cartesian derivatives from homogeneous ones (The NURBS Book, A4.4), up to order 2."""
    a = h[..., :3]
    w = h[..., 3]
    m = h.shape[0]
    s = np.zeros((m, order + 1, order + 1, 3))
    w0 = w[:, 0, 0, None]
    s[:, 0, 0] = a[:, 0, 0] / w0
    if order >= 1:
        s[:, 1, 0] = (a[:, 1, 0] - w[:, 1, 0, None] * s[:, 0, 0]) / w0
        s[:, 0, 1] = (a[:, 0, 1] - w[:, 0, 1, None] * s[:, 0, 0]) / w0
    if order >= 2:
        s[:, 2, 0] = (a[:, 2, 0] - 2 * w[:, 1, 0, None] * s[:, 1, 0] - w[:, 2, 0, None] * s[:, 0, 0]) / w0
        s[:, 0, 2] = (a[:, 0, 2] - 2 * w[:, 0, 1, None] * s[:, 0, 1] - w[:, 0, 2, None] * s[:, 0, 0]) / w0
        s[:, 1, 1] = (
            a[:, 1, 1] - w[:, 1, 0, None] * s[:, 0, 1] - w[:, 0, 1, None] * s[:, 1, 0] - w[:, 1, 1, None] * s[:, 0, 0]
        ) / w0
    return s


# ---------------------------------------------------------------------- knot operations
