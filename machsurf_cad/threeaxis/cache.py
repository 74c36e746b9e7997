"""Caches of the 3-axis work on a part: face sets (seed samples, kernel arrays) and exact drop-cutter
heights, reused by repeated queries (a raster, then a waterline, the scallop planner, a FreeCAD recompute
with another step-over).

Face sets are keyed by the faces' content (every degree, knot, pole, weight, trimming curve and name), the
tool axis and the seed spacing: a changed part never reuses one. Heights are kept per face set, tool (every
field of it at full precision: a diameter 1e-7 mm larger is another tool) and engine, point by point (the
exact query coordinates): a changed tool never reuses them, and a repeated point returns the very same
numbers. Both are bounded (:data:`MAX_FACE_SETS`, :data:`MAX_HEIGHTS`) and can be emptied with :func:`clear`.
"""

from __future__ import annotations

from collections import OrderedDict
from itertools import repeat

import numpy as np

from ..contentkey import faces_key

MAX_FACE_SETS = 8
"""Face sets kept (least recently used dropped first)."""
MAX_HEIGHTS = 500_000
"""Heights kept per face set, tool and engine (then the memo starts again)."""

_face_sets: OrderedDict = OrderedDict()


def clear() -> None:
    """Forget every cached face set and height."""
    _face_sets.clear()


def face_set(build, faces, *, axis, spacing: float, **kw):
    """``build(faces, axis=, spacing=, **kw)``, or the face set built earlier from the same content."""
    faces = list(faces)
    fk = faces_key(faces)
    if not fk:
        return build(faces, axis=axis, spacing=spacing, **kw)
    key = (fk, tuple(float(a) for a in np.asarray(axis, float).ravel()), float(spacing), tuple(sorted(kw.items())))
    if key in _face_sets:
        _face_sets.move_to_end(key)
        return _face_sets[key]
    fs = build(faces, axis=axis, spacing=spacing, **kw)
    _face_sets[key] = fs
    while len(_face_sets) > MAX_FACE_SETS:
        _face_sets.popitem(last=False)
    return fs


class HeightMemo:
    """Heights already computed on one face set for one tool and engine, by exact query point."""

    def __init__(self):
        self.index: dict = {}
        self.chunks: list = []
        self.n = 0
        self._joined = None

    @staticmethod
    def of(fs, tool_key: str, engine: str) -> HeightMemo:
        memos = fs.__dict__.setdefault("_height_memos", {})
        return memos.setdefault((tool_key, engine), HeightMemo())

    def lookup(self, xy: np.ndarray):
        """Row of each point in the memo (-1: not computed) and the points' keys (their 16 bytes, an array)."""
        keys = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2).view("V16").ravel()
        get = self.index.get
        return np.fromiter(map(get, keys.tolist(), repeat(-1)), np.int64, keys.size), keys

    def take(self, rows):
        """Height, contact kind, face and contact point of memo rows."""
        if self._joined is None:
            self._joined = [np.concatenate([c[i] for c in self.chunks]) for i in range(4)]
        return tuple(a[rows] for a in self._joined)

    def store(self, keys, height, kind, face, point) -> None:
        """Remember the results of the points ``keys`` (from :meth:`lookup`)."""
        if self.n + len(keys) > MAX_HEIGHTS:
            self.__init__()
        # (a point twice in one batch has the same numbers in both rows: either may stay)
        self.index.update(zip(np.asarray(keys).tolist(), range(self.n, self.n + len(keys))))
        self.chunks.append((np.array(height, float), np.array(kind, np.int8), np.array(face, np.int64),
                            np.array(point, float).reshape(-1, 3)))  # fmt: skip
        self.n += len(keys)
        self._joined = None
