"""Triangle-mesh helpers in numpy: midpoint subdivision to measure a mesh between its vertices."""

from __future__ import annotations

import numpy as np


def subdivide(points: np.ndarray, triangles: np.ndarray, levels: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Split every triangle into 4 (edge midpoints), ``levels`` times; shared edges share midpoints.

    The new points lie on the flat triangles, so measuring them against a curved reference
    measures the mesh's chordal deviation inside its triangles, not only at its vertices.
    """
    pts = np.asarray(points, dtype=float)
    tris = np.asarray(triangles, dtype=np.int64)
    for _ in range(levels):
        edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
        key = np.sort(edges, axis=1)
        uniq, inv = np.unique(key, axis=0, return_inverse=True)
        inv = np.asarray(inv).ravel()
        mids = 0.5 * (pts[uniq[:, 0]] + pts[uniq[:, 1]])
        base = pts.shape[0]
        m = tris.shape[0]
        m01, m12, m20 = (base + inv[k * m : (k + 1) * m] for k in range(3))
        a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
        tris = np.concatenate(
            [
                np.stack([a, m01, m20], 1),
                np.stack([m01, b, m12], 1),
                np.stack([m20, m12, c], 1),
                np.stack([m01, m12, m20], 1),
            ]
        )
        pts = np.concatenate([pts, mids])
    return pts, tris
