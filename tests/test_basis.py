"""Basis functions against scipy's independent B-spline implementation and Bernstein polynomials."""

from math import comb

import numpy as np
from scipy.interpolate import BSpline

from machsurf_cad.geometry.basis import basis_derivatives, collocation_matrix, find_spans, greville


def test_basis_and_derivatives_match_scipy(rng):
    p = 3
    t = np.concatenate([[0] * 4, np.sort(rng.uniform(0, 1, 6)), [0.5, 0.5], [1] * 4])
    t = np.sort(t)
    n = t.size - p - 1
    x = rng.uniform(0, 1, 500)
    for k in range(3):
        ours = collocation_matrix(t, p, n, x, deriv=k)
        ref = np.stack([BSpline(t, np.eye(n)[i], p)(x, nu=k) for i in range(n)], axis=1)
        assert np.abs(ours - ref).max() < 1e-9 * max(1, np.abs(ref).max())


def test_partition_of_unity_and_right_end():
    t = np.array([0, 0, 0, 0.3, 0.7, 1, 1, 1.0])
    x = np.linspace(0, 1, 101)
    b = collocation_matrix(t, 2, 5, x)
    assert np.abs(b.sum(axis=1) - 1).max() < 1e-14
    assert b[-1, -1] == 1.0  # u at the right end maps to the last span
    assert find_spans(t, 2, 5, np.array([1.0]))[0] == 4


def test_bezier_basis_is_bernstein():
    p = 5
    t = np.array([0.0] * 6 + [1.0] * 6)
    x = np.linspace(0, 1, 37)
    spans = find_spans(t, p, 6, x)
    b = basis_derivatives(t, p, spans, x, 1)
    for i in range(6):
        bern = comb(p, i) * x**i * (1 - x) ** (p - i)
        assert np.abs(b[:, 0, i] - bern).max() < 1e-14


def test_greville_of_clamped_cubic():
    t = np.array([0, 0, 0, 0, 1, 2, 2, 2, 2.0])
    assert np.allclose(greville(t, 3, 5), [0, 1 / 3, 1, 5 / 3, 2], rtol=0, atol=1e-9)
