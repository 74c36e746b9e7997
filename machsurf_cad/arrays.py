"""Array helpers the core shares."""

from __future__ import annotations

import numpy as np


def unique_sorted(a) -> np.ndarray:
    """The distinct values of the integer array ``a`` (flattened), ascending: ``np.unique(a)`` by one sort.
    numpy 2.3+ answers ``np.unique`` on integers through a hash table, about a second per million distinct
    values (measured: 4 million int64 in 5.7 s, against 0.06 s for their sort).

    >>> unique_sorted(np.array([3, 1, 3, 2])).tolist()
    [1, 2, 3]
    """
    s = np.sort(np.asarray(a).ravel())
    return s[np.r_[True, s[1:] != s[:-1]]] if s.size else s


def concat_ranges(start, counts) -> np.ndarray:
    """The ranges ``start[i], ..., start[i] + counts[i] - 1`` of every ``i``, one after the other (int64):
    the indices of runs of an array that were counted per run.

    >>> concat_ranges([5, 0, 9], [2, 0, 3]).tolist()
    [5, 6, 9, 10, 11]
    """
    counts = np.asarray(counts, np.int64)
    first = np.asarray(start, np.int64) - np.cumsum(counts) + counts  # each run's start, less its offset
    return np.repeat(first, counts) + np.arange(int(counts.sum()))
