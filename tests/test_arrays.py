import numpy as np
import pytest

from machsurf_cad.arrays import concat_ranges, unique_sorted


@pytest.mark.parametrize("n, hi", [(0, 5), (1, 5), (1000, 3), (100_000, 10**12)])
def test_unique_sorted_equals_numpys_unique(n, hi):
    a = np.random.default_rng(n).integers(-hi, hi, n)
    got = unique_sorted(a)
    np.testing.assert_array_equal(got, np.unique(a))
    assert got.dtype == a.dtype


def test_concat_ranges_equals_the_ranges_one_after_the_other():
    rng = np.random.default_rng(1)
    start = rng.integers(-50, 50, 200)
    counts = rng.integers(0, 6, 200)
    want = np.concatenate([np.arange(s, s + c) for s, c in zip(start, counts)])
    np.testing.assert_array_equal(concat_ranges(start, counts), want)
    assert concat_ranges([], []).size == 0
