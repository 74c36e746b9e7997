import numpy as np
import pytest

from machsurf_cad.arrays import unique_sorted


@pytest.mark.parametrize("n, hi", [(0, 5), (1, 5), (1000, 3), (100_000, 10**12)])
def test_unique_sorted_equals_numpys_unique(n, hi):
    a = np.random.default_rng(n).integers(-hi, hi, n)
    got = unique_sorted(a)
    np.testing.assert_array_equal(got, np.unique(a))
    assert got.dtype == a.dtype
