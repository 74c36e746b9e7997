"""A trimmed face as plain data: a B-spline surface plus parameter-space trimming loops."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..arrays import concat_ranges
from ..errors import InputError
from .bspline import BSplineCurve, BSplineSurface

TRIM_TOLERANCE = 1e-6
"""How far (mm, on the surface) the polygons that classify points against a face's trimming loops may stray
from the loops' curves (:meth:`Face.contains_uv`)."""


@dataclass(frozen=True, eq=False)
class Face:
    """A face of a part (numpy form).

    Attributes
    ----------
    surface : BSplineSurface
        The underlying (possibly converted) B-spline surface, lengths in mm.
    loops : tuple of tuple of BSplineCurve
        Trimming loops in the surface's (u, v) domain; ``loops[0]`` is the outer loop,
        the rest are holes. Empty for a face bounded by the surface's natural bounds.
    name : str
        The face's name (from STEP, or given).
    index : int
        Position of the face in its source file (0-based), -1 if built in a script.
    reversed : bool
        True when the face's outward normal is opposite to the surface normal ``su x sv``.
    source_type : str
        Surface type before NURBS conversion ("BSplineSurface", "Plane", "Cylinder", ...).
    uv_bounds : tuple
        Parameter box ``(u0, u1, v0, v1)`` of the trimmed face.
    area : float
        Face area in mm^2 (as computed by the kernel), NaN if unknown.
    body : int
        The solid the face bounds in its source file (0-based, in file order), -1 if none or unknown. A STEP
        assembly holds several: the part a face is machined in is its body.
    """

    surface: BSplineSurface
    loops: tuple = ()
    name: str = ""
    index: int = -1
    reversed: bool = False
    source_type: str = "BSplineSurface"
    uv_bounds: tuple = field(default=())
    area: float = float("nan")
    body: int = -1

    def __post_init__(self):
        from .bspline import BSplineSurface as _Surface

        if not isinstance(self.surface, _Surface):
            raise InputError(f"a Face needs a BSplineSurface, got {type(self.surface).__name__}")
        loops = tuple(tuple(loop) for loop in self.loops)
        for loop in loops:
            for c in loop:
                if not isinstance(c, BSplineCurve) or c.dim != 2:
                    raise TypeError("trimming loops must hold 2-D BSplineCurve objects")
        object.__setattr__(self, "loops", loops)
        if not self.uv_bounds:
            object.__setattr__(self, "uv_bounds", self.surface.bounds)

    @property
    def is_trimmed(self) -> bool:
        return len(self.loops) > 0

    def with_surface(self, surface: BSplineSurface, name: str | None = None) -> Face:
        """Same trimming (same parameter domain), another surface: how S1/S2 keep F's trimming."""
        return Face(
            surface,
            self.loops,
            self.name if name is None else name,
            -1,
            False,
            "BSplineSurface",
            self.uv_bounds,
            float("nan"),
        )

    def contains_uv(self, u, v, n_per_curve: int | None = None, *, tolerance: float = TRIM_TOLERANCE) -> np.ndarray:
        """Boolean mask of parameter points inside the trimmed region (even-odd rule on the loops).

        The loops are polygons whose edges, mapped onto the surface, stay within ``tolerance`` mm of the
        loops' curves (:meth:`trim_polygons`): a point is classified as the exact loops classify it
        unless it lies within about ``tolerance`` mm of a loop. ``n_per_curve`` instead gives uniform
        polygons of that many samples per curve (coarse: a 64-sample polygon is off by 0.01 mm on a hole
        of 10 mm radius).
        """
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        if not self.loops:
            u0, u1, v0, v1 = self.uv_bounds
            return (u >= u0) & (u <= u1) & (v >= v0) & (v <= v1)
        polys = self._polygons(n_per_curve) if n_per_curve is not None else self.trim_polygons(tolerance)
        return _points_in_polygons(u, v, polys)

    def contains_uv_grid(self, us, vs, *, tolerance: float = TRIM_TOLERANCE) -> np.ndarray:
        """:meth:`contains_uv` on the grid ``us x vs`` (both ascending): a boolean array ``(len(us), len(vs))``,
        the same classification point for point, in time of the grid's size plus the loops' crossings of its
        rows (instead of each polygon edge against every point of its rows)."""
        us, vs = np.asarray(us, float), np.asarray(vs, float)
        if not self.loops:
            u0, u1, v0, v1 = self.uv_bounds
            return ((us >= u0) & (us <= u1))[:, None] & ((vs >= v0) & (vs <= v1))[None, :]
        return _grid_in_polygons(us, vs, self.trim_polygons(tolerance))

    def _polygons(self, n_per_curve: int = 64) -> list:
        """The trimming loops as closed (u, v) polygons of ``n_per_curve`` samples a curve (cached)."""
        key = ("_polys", n_per_curve)
        cache = self.__dict__.setdefault("_cache", {})
        if key not in cache:
            cache[key] = [
                np.concatenate([c.evaluate(np.linspace(*c.bounds, n_per_curve))[:-1] for c in loop])
                for loop in self.loops
            ]
        return cache[key]

    def trim_polygons(self, tolerance: float = TRIM_TOLERANCE) -> list:
        """The trimming loops as closed (u, v) polygons whose edges, mapped onto the surface, stay within
        ``tolerance`` mm of the loops' curves (adaptive bisection from 64 samples a curve, at most 2^16 a
        curve; the deviation is checked at each edge's middle). Cached on the face."""
        cache = self.__dict__.setdefault("_cache", {})
        key = ("_adaptive_polys", float(tolerance))
        if key not in cache:
            s = self.surface
            polys = []
            for loop in self.loops:
                parts = []
                for c in loop:
                    t = np.linspace(*c.bounds, 65)
                    for _ in range(16):
                        tm = 0.5 * (t[1:] + t[:-1])
                        ends = c.evaluate(t)
                        chord = s.evaluate(*(0.5 * (ends[1:] + ends[:-1])).T)
                        err = np.linalg.norm(s.evaluate(*c.evaluate(tm).T) - chord, axis=1)
                        bad = err > tolerance
                        if not bad.any() or t.size > 1 << 16:
                            break
                        t = np.sort(np.concatenate([t, tm[bad]]))
                    parts.append(c.evaluate(t)[:-1])
                polys.append(np.concatenate(parts))
            cache[key] = polys
        return cache[key]


def _points_in_polygons(u, v, polys, batch: int = 4_000_000) -> np.ndarray:
    """Even-odd rule over several closed polygons at once (a face's outer loop and holes), vectorised.

    The points are sorted by v once and grouped in rows of equal v. Each polygon edge crosses the
    horizontal rays of the rows in its v range ``lo < v <= hi`` at ``x`` (computed once per edge and row),
    and flips the points of the row with ``u < x``. A row of many points (e.g. points clipped onto a side
    of the parameter box, where a loop runs along that side) is counted by sorting its crossings with its
    points instead of comparing every crossing with every point. The edges go in batches of at most
    ``batch`` (edge, row) crossings; a batch compares its crossings with the points of their rows when that
    takes at most ``batch`` comparisons, else sorts them with the points of its span of rows (memory
    O(N + batch), no points x edges array)."""
    uf = np.asarray(u, float).ravel()
    vf = np.asarray(v, float).ravel()
    order = np.argsort(vf, kind="stable")
    vs, us = vf[order], uf[order]
    new_row = np.r_[True, vs[1:] != vs[:-1]] if vs.size else np.zeros(0, bool)
    row_first = np.nonzero(new_row)[0]  # in the sorted order
    mult = np.diff(np.r_[row_first, vs.size])
    (x0, y0, x1, y1), e, start, counts = _edge_runs(polys, vs[row_first])
    flips = np.zeros(uf.size, bool)
    done = 0
    while done < e.size:  # edges in batches of at most ``batch`` (edge, row) crossings
        stop = done + max(1, int(np.searchsorted(np.cumsum(counts[done:]), batch)))
        eb, cb = e[done:stop], counts[done:stop]
        edge = np.repeat(eb, cb)
        row = concat_ranges(start[eb], cb)
        xint = x0[edge] + (vs[row_first[row]] - y0[edge]) * (x1[edge] - x0[edge]) / (y1[edge] - y0[edge])
        m = mult[row]
        if int(m.sum()) <= batch:  # each crossing against each point of its row
            k = concat_ranges(row_first[row], m)
            right = us[k] < np.repeat(xint, m)
            flips ^= (np.bincount(k[right], minlength=uf.size) & 1).astype(bool)
        else:  # the rows' crossings and points sorted together: per point, the crossings right of it
            lo, hi = row_first[row.min()], row_first[row.max()] + mult[row.max()]
            row_of = row.min() - 1 + np.cumsum(new_row[lo:hi])  # the points' rows (the span starts a row)
            flips[lo:hi] ^= (_crossings_right(row, xint, row_of, us[lo:hi]) & 1).astype(bool)
        done = stop
    out = np.empty(uf.size, bool)
    out[order] = flips
    return out.reshape(np.shape(u))


def _crossings_right(row, xint, prow, pu) -> np.ndarray:
    """Per point (row ``prow``, abscissa ``pu``): how many crossings ``(row, xint)`` of its row have
    ``pu < xint``, by one sort of both (a crossing at a point's own abscissa sorts before it; a NaN crossing,
    from a NaN or overflowing polygon, is right of no point, as the comparison ``pu < xint`` says)."""
    real = ~np.isnan(xint)
    row, xint = row[real], xint[real]
    n = row.size
    if n == 0:
        return np.zeros(pu.size, np.int64)
    kind = np.r_[np.zeros(n, np.int8), np.ones(pu.size, np.int8)]
    order = np.lexsort((kind, np.r_[xint, pu], np.r_[row, prow]))
    is_cross = order < n
    seen = np.cumsum(is_cross)  # crossings up to each sorted position
    r0 = min(int(row.min()), int(prow.min()))
    per_row = np.bincount(row - r0, minlength=int(max(row.max(), prow.max())) - r0 + 1)
    before_row = np.cumsum(per_row) - per_row
    at = order[~is_cross] - n
    r = prow[at] - r0
    out = np.empty(pu.size, np.int64)
    out[at] = per_row[r] - (seen[~is_cross] - before_row[r])
    return out


def _grid_in_polygons(us, vs, polys) -> np.ndarray:
    """:func:`_points_in_polygons` on the grid ``us x vs`` (both ascending), ``(len(us), len(vs))``: each
    polygon edge crosses the rows with ``lo < v <= hi`` at ``x`` (the same formula), and flips the points of
    the row with ``u < x``, the first ``searchsorted(us, x)`` of them; a row's parities are a cumulative sum
    from its right end."""
    (x0, y0, x1, y1), e, start, counts = _edge_runs(polys, vs)
    edge = np.repeat(e, counts)
    row = concat_ranges(start[e], counts)
    xint = x0[edge] + (vs[row] - y0[edge]) * (x1[edge] - x0[edge]) / (y1[edge] - y0[edge])
    D = np.zeros((vs.size, us.size + 1), np.uint8)  # crossing counts mod 256: their parity is all that counts
    np.add.at(D, (row, np.searchsorted(us, xint, side="left")), 1)
    inside = (np.cumsum(D[:, ::-1], axis=1, dtype=np.uint8)[:, ::-1][:, 1:] & 1).astype(bool)
    return inside.T


def _edge_runs(polys, vs):
    """The polygons' edges ``(x0, y0, x1, y1)`` and, for the ascending ``vs``, the edges ``e`` whose v range
    ``lo < v <= hi`` holds some of them (``(y0 > v) != (y1 > v)``, horizontal edges left out): the first of
    those values ``start[e]`` and how many ``counts``."""
    x0 = np.concatenate([p[:, 0] for p in polys])
    y0 = np.concatenate([p[:, 1] for p in polys])
    x1 = np.concatenate([np.roll(p[:, 0], -1) for p in polys])
    y1 = np.concatenate([np.roll(p[:, 1], -1) for p in polys])
    start = np.searchsorted(vs, np.minimum(y0, y1), side="right")
    end = np.searchsorted(vs, np.maximum(y0, y1), side="right")
    e = np.nonzero((end > start) & (y0 != y1))[0]
    return (x0, y0, x1, y1), e, start, (end - start)[e]


def close_loop(loop, rel_gap: float = 1e-3) -> tuple[list[BSplineCurve], float]:
    """The loop with each pair of consecutive curve ends joined at their mid point in (u, v).

    Only gaps smaller than ``rel_gap`` times the loop's parameter-box diagonal are closed (a
    larger jump, e.g. across a periodic seam, is left to the kernel). Returns the curves and
    the largest gap closed (in parameter units). Clamped B-splines pass through their end
    poles, so moving an end pole moves the curve by at most the half gap, only near that end.
    """
    loop = list(loop)
    n = len(loop)
    if n == 0:
        return loop, 0.0
    ends = np.array([[c.poles[0], c.poles[-1]] for c in loop])
    diag = float(np.linalg.norm(ends.reshape(-1, 2).max(axis=0) - ends.reshape(-1, 2).min(axis=0))) or 1.0
    poles = [np.array(c.poles, dtype=float) for c in loop]
    worst = 0.0
    for i in range(n):
        j = (i + 1) % n
        if loop[i].periodic or loop[j].periodic:
            continue
        a, b = poles[i][-1], poles[j][0]
        gap = float(np.linalg.norm(a - b))
        if 0.0 < gap <= rel_gap * diag:
            m = 0.5 * (a + b)
            poles[i][-1] = m
            poles[j][0] = m
            worst = max(worst, gap)
    out = [
        c if np.array_equal(p, c.poles) else BSplineCurve(c.degree, c.knots, c.mults, p, c.weights, c.periodic)
        for c, p in zip(loop, poles)
    ]
    return out, worst
