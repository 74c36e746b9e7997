"""Chordal sampling of dense polylines (mm): keep the fewest positions whose chords stay within a
tolerance of every dense point, and measure the error reached. Tool paths pass 6-D points (the tip
and a point one tool diameter up the axis) so that the chords hold for the whole tool in 5 axes."""

from __future__ import annotations

import numpy as np


def douglas_peucker(pts: np.ndarray, tol: float) -> np.ndarray:
    """Indices of points kept so that every point is within ``tol`` of its chord."""
    n = pts.shape[0]
    if n <= 2:
        return np.arange(n)
    keep = np.zeros(n, bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = pts[b] - pts[a]
        L2 = float(seg @ seg)
        rel = pts[a + 1 : b] - pts[a]
        if L2 > 0:
            t = np.clip(rel @ seg / L2, 0, 1)
            d = np.linalg.norm(rel - t[:, None] * seg, axis=1)
        else:
            d = np.linalg.norm(rel, axis=1)
        i = int(np.argmax(d))
        if d[i] > tol:
            m = a + 1 + i
            keep[m] = True
            stack += [(a, m), (m, b)]
    return np.nonzero(keep)[0]


def chord_error(dense: np.ndarray, kept_idx: np.ndarray) -> float:
    err = 0.0
    for a, b in zip(kept_idx[:-1], kept_idx[1:]):
        if b - a < 2:
            continue
        seg = dense[b] - dense[a]
        L2 = float(seg @ seg)
        rel = dense[a + 1 : b] - dense[a]
        t = np.clip(rel @ seg / L2, 0, 1) if L2 > 0 else np.zeros(len(rel))
        err = max(err, float(np.linalg.norm(rel - t[:, None] * seg, axis=1).max()))
    return err


__all__ = ["douglas_peucker", "chord_error"]
