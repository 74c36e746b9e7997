"""Vectorised B-spline basis functions (numpy only).

All functions work on a *flat* knot vector ``t`` (knots repeated by their
multiplicities) of a non-periodic spline; periodic splines are evaluated through
their unperiodised equivalent (see :mod:`machsurf_cad.geometry.bspline`).
Algorithms follow Piegl & Tiller, *The NURBS Book* (A2.1, A2.3), vectorised over
the evaluation points.
"""

from __future__ import annotations

import numpy as np


def find_spans(t: np.ndarray, degree: int, n_poles: int, x: np.ndarray) -> np.ndarray:
    """Knot span index ``i`` with ``t[i] <= x < t[i+1]`` for every ``x`` (clamped to the domain).

    The domain is ``[t[degree], t[n_poles]]``; ``x`` at the right end maps to the last span.
    """
    x = np.asarray(x, dtype=float)
    i = np.searchsorted(t, x, side="right") - 1
    return np.clip(i, degree, n_poles - 1)


def basis_derivatives(t: np.ndarray, degree: int, spans: np.ndarray, x: np.ndarray, n_derivs: int) -> np.ndarray:
    """Non-zero basis functions and their derivatives at ``x``.

    Returns an array of shape ``(len(x), n_derivs + 1, degree + 1)``: entry ``[m, k, j]`` is the
    ``k``-th derivative of ``N_{spans[m] - degree + j, degree}`` at ``x[m]``. Derivatives above
    ``degree`` are zero.
    """
    p = degree
    x = np.asarray(x, dtype=float).ravel()
    spans = np.asarray(spans).ravel()
    m = x.shape[0]
    nd = min(n_derivs, p)
    ndu = np.zeros((p + 1, p + 1, m))
    ndu[0, 0] = 1.0
    left = np.zeros((p + 1, m))
    right = np.zeros((p + 1, m))
    for j in range(1, p + 1):
        left[j] = x - t[spans + 1 - j]
        right[j] = t[spans + j] - x
        saved = np.zeros(m)
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    ders = np.zeros((m, n_derivs + 1, p + 1))
    for j in range(p + 1):
        ders[:, 0, j] = ndu[j, p]
    if nd > 0:
        a = np.zeros((2, p + 1, m))
        for r in range(p + 1):
            s1, s2 = 0, 1
            a[0, 0] = 1.0
            for k in range(1, nd + 1):
                d = np.zeros(m)
                rk, pk = r - k, p - k
                if r >= k:
                    a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                    d = a[s2, 0] * ndu[rk, pk]
                j1 = 1 if rk >= -1 else -rk
                j2 = k - 1 if r - 1 <= pk else p - r
                for jj in range(j1, j2 + 1):
                    a[s2, jj] = (a[s1, jj] - a[s1, jj - 1]) / ndu[pk + 1, rk + jj]
                    d = d + a[s2, jj] * ndu[rk + jj, pk]
                if r <= pk:
                    a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                    d = d + a[s2, k] * ndu[r, pk]
                ders[:, k, r] = d
                s1, s2 = s2, s1
        fac = float(p)
        for k in range(1, nd + 1):
            ders[:, k, :] *= fac
            fac *= p - k
    return ders


def collocation_matrix(t: np.ndarray, degree: int, n_poles: int, x: np.ndarray, deriv: int = 0) -> np.ndarray:
    """Dense matrix ``B[m, i] = d^deriv N_i(x[m])`` (for interpolation and least squares)."""
    x = np.asarray(x, dtype=float).ravel()
    spans = find_spans(t, degree, n_poles, x)
    ders = basis_derivatives(t, degree, spans, x, deriv)[:, deriv, :]
    b = np.zeros((x.shape[0], n_poles))
    rows = np.arange(x.shape[0])[:, None]
    cols = spans[:, None] - degree + np.arange(degree + 1)[None, :]
    b[rows, cols] = ders
    return b


def greville(t: np.ndarray, degree: int, n_poles: int) -> np.ndarray:
    """Greville abscissae (knot averages), one per pole; good interpolation sites."""
    if degree == 0:
        return 0.5 * (t[:n_poles] + t[1 : n_poles + 1])
    idx = np.arange(n_poles)[:, None] + 1 + np.arange(degree)[None, :]
    return t[idx].mean(axis=1)
