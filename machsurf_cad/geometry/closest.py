"""Closest points of a trimmed face: the exact point-to-face distance (numpy only, mm).

The distance of a point ``p`` to a face is the smallest of

* the distances to the surface's local closest points (``(S - p) . Su = (S - p) . Sv = 0``, or
  constrained minima on a parameter-box edge of an untrimmed face) that lie inside the
  trimming loops, and
* the distance to the face's boundary: the trimming loops' 3-D curves ``S(c(t))``.

Every candidate foot is a point of the face (up to the polygons that decide "inside the loops",
within 2e-5 mm of the loops), so the result is not below the true distance; it equals it when the
global foot is among the candidates. To find it, the surface is sampled on a parameter grid over the
face's box; every grid node that is a discrete local minimum of ``|S - p|`` among its grid
neighbours and within about a cell of the nearest node seeds a projected, damped Newton descent
(one per basin, the way OCCT's ``Extrema_GenExtPS`` seeds from a sample grid), and the loops are
searched the same way in one dimension. A parameter direction in which the face is closed
(periodic, or its two box edges are one 3-D curve: a seam) is searched across the seam, so a point
near a seam is not stopped on the edge ``v = v0`` when its foot is at ``v1 - e``. A grid line that
is a single point (a pole) keeps one node, so its copies do not crowd out the nodes around it; the
normal at a pole is taken just inside the face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..results import Result
from .bspline import BSplineCurve, BSplineSurface, SurfaceDerivatives

_K_MAX = 4096  # samples examined per point at most (a point far away from a finely sampled face)
_CHUNK = 1 << 13  # points per batch (bounds the work arrays)


@dataclass(frozen=True, eq=False)
class FaceProjection(Result):
    """Closest points on a face, per query point.

    ``uv`` (n, 2) and ``foot`` (n, 3) of the closest point, ``normal`` (n, 3) the unit
    ``su x sv`` there (taken just inside the face at a pole), ``distance`` (n,) in mm (unsigned),
    ``on_boundary`` where the foot is on an edge of the face (box edge or trimming loop),
    ``on_trim`` where it is on a trimming loop, ``converged`` where its refinement converged.
    """

    uv: np.ndarray
    foot: np.ndarray
    normal: np.ndarray
    distance: np.ndarray
    on_boundary: np.ndarray
    on_trim: np.ndarray
    converged: np.ndarray


@dataclass(frozen=True)
class _Domain:
    lo: np.ndarray  # (2,) parameter box of the face
    hi: np.ndarray
    wrap: np.ndarray  # (2,) bool: closed direction, searched across the seam


def face_domain(surface: BSplineSurface, box) -> _Domain:
    """The face's parameter box and, per direction, whether the face closes on itself there (its two
    box edges are the same 3-D curve to 1e-9 of the surface size, 1e-6 mm at least)."""
    u0, u1, v0, v1 = (float(x) for x in box)
    lo, hi = np.array([u0, v0]), np.array([u1, v1])
    tol = max(1e-6, 1e-9 * surface.scale)
    t = np.linspace(0.0, 1.0, 17)
    wrap = np.zeros(2, bool)
    for k in range(2):
        other = lo[1 - k] + t * (hi[1 - k] - lo[1 - k])
        a = np.full_like(t, lo[k])
        b = np.full_like(t, hi[k])
        pa = surface.evaluate(a, other) if k == 0 else surface.evaluate(other, a)
        pb = surface.evaluate(b, other) if k == 0 else surface.evaluate(other, b)
        wrap[k] = hi[k] > lo[k] and float(np.abs(pa - pb).max()) <= tol
    return _Domain(lo, hi, wrap)


def _grid_size(knots: np.ndarray, degree: int, lo: float, hi: float) -> int:
    spans = 1 + int(np.count_nonzero((knots > lo) & (knots < hi)))
    return int(np.clip(4 * (degree + 1) * spans, 33, 257))


class _SeedGrid:
    """Surface samples over the face's box, their grid neighbours and a k-d tree."""

    def __init__(self, surface: BSplineSurface, dom: _Domain):
        nu = _grid_size(surface.knots_u, surface.degree_u, dom.lo[0], dom.hi[0])
        nv = _grid_size(surface.knots_v, surface.degree_v, dom.lo[1], dom.hi[1])
        self.us = np.linspace(dom.lo[0], dom.hi[0], nu, endpoint=not dom.wrap[0])
        self.vs = np.linspace(dom.lo[1], dom.hi[1], nv, endpoint=not dom.wrap[1])
        g = surface.evaluate_grid(self.us, self.vs)
        self.shape = (nu, nv)
        self.points = g.reshape(-1, 3)
        gu = np.concatenate([g, g[:1]], 0) if dom.wrap[0] else g
        gv = np.concatenate([gu, gu[:, :1]], 1) if dom.wrap[1] else gu
        diag = np.maximum(
            np.linalg.norm(gv[1:, 1:] - gv[:-1, :-1], axis=-1), np.linalg.norm(gv[1:, :-1] - gv[:-1, 1:], axis=-1)
        )
        self.reach = 0.6 * float(diag.max())  # about the farthest a face point can be from its nearest node
        # per node, the same over the cells around it: a node farther than the nearest by more than its
        # own reach is the nearest node of no closer face point
        cell = np.zeros((gv.shape[0] + 1, gv.shape[1] + 1))
        cell[1:-1, 1:-1] = diag
        around = np.maximum.reduce([cell[:-1, :-1], cell[1:, :-1], cell[:-1, 1:], cell[1:, 1:]])
        self.node_reach = 0.6 * around[:nu, :nv].ravel()
        # a grid line that is one point (a pole, a degenerate edge) keeps one node in the tree and is
        # nobody's neighbour: its copies would fill the k nearest and hide the ring around it
        tol = 1e-9 * surface.scale
        pole = np.zeros((nu, nv), bool)
        pole[:, np.ptp(g, axis=0).max(axis=-1) <= tol] = True
        pole[np.ptp(g, axis=1).max(axis=-1) <= tol, :] = True
        keep = ~pole
        for j in np.nonzero(pole.all(axis=0))[0]:
            keep[nu // 2, j] = True
        for i in np.nonzero(pole.all(axis=1))[0]:
            keep[i, nv // 2] = True
        self.nodes = np.nonzero(keep.ravel())[0]  # tree index -> flat grid index
        self.tree = cKDTree(self.points[self.nodes])
        nb = _grid_neighbours(nu, nv, dom.wrap)
        self.neighbours = np.where((nb >= 0) & ~pole.ravel()[np.maximum(nb, 0)], nb, -1)


def _grid_neighbours(nu: int, nv: int, wrap) -> np.ndarray:
    """(nu * nv, 8) flat indices of each node's grid neighbours; -1 where there is none."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    out = []
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di == 0 and dj == 0:
                continue
            a, b = i + di, j + dj
            if wrap[0]:
                a = a % nu
            if wrap[1]:
                b = b % nv
            ok = (a >= 0) & (a < nu) & (b >= 0) & (b < nv)
            out.append(np.where(ok, a * nv + b, -1).ravel())
    return np.stack(out, axis=1)


def _window(tree: cKDTree, p: np.ndarray, reach: float):
    """Pairs ``(row, sample, distance)``: every sample within ``reach`` of the distance of each point's
    nearest sample (at most the ``_K_MAX`` nearest, for a point so far away that more are in reach).
    Sorted by row, then distance: each point's nearest sample comes first."""
    from itertools import chain

    d0 = tree.query(p, 1)[0].reshape(len(p))
    lim = d0 + reach
    lens = np.asarray(tree.query_ball_point(p, lim, return_length=True)).reshape(len(p))
    lens = np.maximum(lens, 1)  # the nearest sample, should rounding leave it out of the ball
    small = np.nonzero(lens <= _K_MAX)[0]
    balls = tree.query_ball_point(p[small], lim[small] * (1 + 1e-12) + 1e-300)
    n_pairs = sum(len(b) for b in balls)
    idx = np.fromiter(chain.from_iterable(balls), dtype=np.intp, count=n_pairs)
    rows = np.repeat(small, [len(b) for b in balls])
    out = [(rows, idx)]
    big = np.nonzero(lens > _K_MAX)[0]
    k = min(_K_MAX, tree.n)
    for a in range(0, big.size, max(1, (1 << 20) // k)):  # about a million pairs at a time
        r = big[a : a + max(1, (1 << 20) // k)]
        ik = tree.query(p[r], k)[1].reshape(r.size, k)
        out.append((np.repeat(r, k), ik.ravel()))
    rows, idx = (np.concatenate(x) for x in zip(*out))
    dist = np.linalg.norm(tree.data[idx] - p[rows], axis=1)
    order = np.lexsort((dist, rows))
    return rows[order], idx[order], dist[order]


def _local_minima(p, rows, nodes, dist, pts, neighbours):
    """The pairs whose node is no farther from the point than any of the node's neighbours (-1: none)."""
    nb = neighbours[nodes]
    w = pts[np.maximum(nb, 0)] - p[rows, None, :]
    nd2 = np.where(nb < 0, np.inf, np.einsum("ijk,ijk->ij", w, w))
    return dist**2 <= nd2.min(axis=1)


def _wrap_into(x: np.ndarray, dom: _Domain) -> np.ndarray:
    """Parameters of closed directions brought into ``[lo, hi)``; the others clipped to the box."""
    out = np.clip(x, dom.lo, dom.hi)
    for k in range(2):
        if dom.wrap[k]:
            per = dom.hi[k] - dom.lo[k]
            w = np.mod(x[:, k] - dom.lo[k], per)
            out[:, k] = dom.lo[k] + np.where(w >= per, 0.0, w)
    return out


def _newton_step(d, r, uv, dom: _Domain):
    """Projected Newton step (to subtract) for ``|S - p|^2 / 2`` with an active set on the box edges of
    directions that are not closed; Gauss-Newton with a small ridge where the Hessian is not definite."""
    g = np.stack([np.einsum("ij,ij->i", d.su, r), np.einsum("ij,ij->i", d.sv, r)], axis=1)
    a = np.einsum("ij,ij->i", d.su, d.su)
    b = np.einsum("ij,ij->i", d.su, d.sv)
    c = np.einsum("ij,ij->i", d.sv, d.sv)
    huu = a + np.einsum("ij,ij->i", d.suu, r)
    huv = b + np.einsum("ij,ij->i", d.suv, r)
    hvv = c + np.einsum("ij,ij->i", d.svv, r)
    ridge = 1e-10 * (a + c) + 1e-300
    # one free coordinate (the other held on the box): its own second derivative where positive
    h1u = np.where(huu > ridge, huu, a + ridge)
    h1v = np.where(hvv > ridge, hvv, c + ridge)
    det = huu * hvv - huv * huv
    gn = ~((huu > 0) & (hvv > 0) & (det > 1e-12 * (huu * hvv)))
    huu = np.where(gn, a + ridge, huu)
    huv = np.where(gn, b, huv)
    hvv = np.where(gn, c + ridge, hvv)
    det = huu * hvv - huv * huv
    span = dom.hi - dom.lo
    at_lo = ~dom.wrap & (uv <= dom.lo + 1e-15 * span)
    at_hi = ~dom.wrap & (uv >= dom.hi - 1e-15 * span)
    fix = (at_lo & (g > 0)) | (at_hi & (g < 0))
    step = np.empty_like(uv)
    safe = np.where(det > 0, det, 1.0)
    step[:, 0] = (hvv * g[:, 0] - huv * g[:, 1]) / safe
    step[:, 1] = (huu * g[:, 1] - huv * g[:, 0]) / safe
    fu, fv = fix[:, 0], fix[:, 1]
    step[fv, 0] = g[fv, 0] / h1u[fv]  # at a pole h1u is the ridge, and g vanishes with it
    step[fu, 1] = g[fu, 1] / h1v[fu]
    step[fu] *= np.array([0.0, 1.0])
    step[fv] *= np.array([1.0, 0.0])
    return np.clip(step, -0.25 * span, 0.25 * span)


def descend(surface: BSplineSurface, p: np.ndarray, uv: np.ndarray, dom: _Domain, max_iter: int = 60):
    """Damped projected Newton from ``uv`` to a local minimum of ``|S(u, v) - p|`` on the face's box
    (closed directions wrap). Each step is halved until the distance does not grow. Returns
    ``(uv, point, converged)``."""
    uv = _wrap_into(np.array(uv, float), dom)
    d = surface.derivatives(uv[:, 0], uv[:, 1], 2)
    pt = d.point.copy()
    w = pt - p
    f = np.einsum("ij,ij->i", w, w)
    conv = np.zeros(len(p), bool)
    act = np.arange(len(p))
    tol = 1e-14 * float((dom.hi - dom.lo).max())
    ptol = 1e-13 * surface.scale
    for _ in range(max_iter):
        if act.size == 0:
            break
        step = _newton_step(d, pt[act] - p[act], uv[act], dom)
        t_uv, t_d, t_f, taken = _backtrack(surface, p[act], uv[act], step, f[act], dom)
        # converged: the parameters stopped, or the point did (sliding along a pole's degenerate edge)
        done = (np.abs(taken).max(axis=1) <= tol) | (np.linalg.norm(t_d.point - pt[act], axis=1) <= ptol)
        uv[act], pt[act], f[act] = t_uv, t_d.point, t_f
        conv[act[done]] = True
        act = act[~done]
        d = _subset(t_d, ~done)
    return uv, pt, conv


def _subset(d, keep):
    return SurfaceDerivatives(*(None if x is None else x[keep] for x in (d.point, d.su, d.sv, d.suu, d.suv, d.svv)))


def _backtrack(surface, p, cur, step, f0, dom: _Domain, halvings: int = 30):
    """Trial ``cur - step``, halving the step where the squared distance grew (at most ``halvings``
    times; then the point stays). Returns the accepted uv, derivatives, squared distance and step."""
    taken = step.copy()
    trial = _wrap_into(cur - taken, dom)
    d = surface.derivatives(trial[:, 0], trial[:, 1], 2)
    fields = [d.point.copy(), d.su.copy(), d.sv.copy(), d.suu.copy(), d.suv.copy(), d.svv.copy()]
    w = fields[0] - p
    f = np.einsum("ij,ij->i", w, w)
    slack = 1e-12 * f0 + 1e-24  # rounding of the squared distance
    bad = np.nonzero(f > f0 + slack)[0]
    for _ in range(halvings):
        if bad.size == 0:
            break
        taken[bad] *= 0.5
        trial[bad] = _wrap_into(cur[bad] - taken[bad], dom)
        db = surface.derivatives(trial[bad, 0], trial[bad, 1], 2)
        for arr, x in zip(fields, (db.point, db.su, db.sv, db.suu, db.suv, db.svv)):
            arr[bad] = x
        w = db.point - p[bad]
        f[bad] = np.einsum("ij,ij->i", w, w)
        bad = bad[f[bad] > f0[bad] + slack[bad]]
    if bad.size:  # no descent along the step: a minimum to rounding, stay
        taken[bad] = 0.0
        trial[bad] = cur[bad]
        db = surface.derivatives(cur[bad, 0], cur[bad, 1], 2)
        for arr, x in zip(fields, (db.point, db.su, db.sv, db.suu, db.suv, db.svv)):
            arr[bad] = x
        f[bad] = f0[bad]
    return trial, SurfaceDerivatives(*fields), f, taken


class _EdgeSamples:
    """The trimming loops' 3-D curves ``S(c(t))`` sampled by arc length (about 4000 samples in all),
    with each sample's neighbours along its curve and a k-d tree."""

    def __init__(self, face, surface: BSplineSurface):
        self.curves: list[BSplineCurve] = [c for loop in face.loops for c in loop]
        lengths = []
        for c in self.curves:
            xyz = surface.evaluate(*c.evaluate(np.linspace(*c.bounds, 65)).T)
            lengths.append(float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum()))
        h = max(sum(lengths) / 4000.0, 1e-300)
        ts, ids, pts = [], [], []
        for k, (c, length) in enumerate(zip(self.curves, lengths)):
            if length <= 1e-9 * surface.scale:  # a degenerate edge (a pole): one sample, not 17 copies
                t = np.array([0.5 * sum(c.bounds)])
            else:
                t = np.linspace(*c.bounds, int(np.clip(np.ceil(length / h) + 1, 17, 2049)))
            ts.append(t)
            ids.append(np.full(t.size, k))
            pts.append(surface.evaluate(*c.evaluate(t).T))
        self.t = np.concatenate(ts)
        self.curve_id = np.concatenate(ids)
        self.points = np.concatenate(pts)
        n = self.t.size
        same_prev = np.r_[False, self.curve_id[1:] == self.curve_id[:-1]]
        same_next = np.r_[self.curve_id[:-1] == self.curve_id[1:], False]
        self.neighbours = np.stack(
            [np.where(same_prev, np.arange(n) - 1, -1), np.where(same_next, np.arange(n) + 1, -1)], axis=1
        )
        seg = np.linalg.norm(self.points[1:] - self.points[:-1], axis=1)[same_next[:-1]]
        self.reach = 0.6 * float(seg.max()) if seg.size else 0.0
        self.tree = cKDTree(self.points)

    def closest(self, surface: BSplineSurface, p: np.ndarray, best: np.ndarray):
        """Closest loop points of the points that could be nearer to a loop than ``best`` (mm):
        ``(rows, uv, foot, distance, converged)`` for those rows."""
        d0 = self.tree.query(p, 1)[0].reshape(len(p))
        need = np.nonzero(d0 - self.reach < best)[0]
        empty = np.zeros(0)
        if need.size == 0:
            return need, empty.reshape(0, 2), empty.reshape(0, 3), empty, empty.astype(bool)
        q = p[need]
        rows, samp, dist = _window(self.tree, q, self.reach)
        first = np.r_[True, rows[1:] != rows[:-1]]
        keep = first | _local_minima(q, rows, samp, dist, self.points, self.neighbours)
        rows, samp = rows[keep], samp[keep]
        uv = np.empty((rows.size, 2))
        foot = np.empty((rows.size, 3))
        conv = np.zeros(rows.size, bool)
        for cid in np.unique(self.curve_id[samp]):
            sel = np.nonzero(self.curve_id[samp] == cid)[0]
            uv[sel], foot[sel], conv[sel] = descend_curve(surface, self.curves[cid], q[rows[sel]], self.t[samp[sel]])
        dist = np.linalg.norm(foot - q[rows], axis=1)
        first = _best_per_row(rows, dist)
        return need, uv[first], foot[first], dist[first], conv[first]


def _best_per_row(rows: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Index of the smallest ``dist`` of each row (rows numbered 0..m-1, every row present)."""
    order = np.lexsort((dist, rows))
    r = rows[order]
    return order[np.r_[True, r[1:] != r[:-1]]]


def _curve_on_surface(surface: BSplineSurface, c: BSplineCurve, t: np.ndarray, order: int):
    """Point and derivatives of ``S(c(t))`` up to ``order`` (0..2), and ``c(t)``."""
    cd = c.derivatives(t, order)
    d = surface.derivatives(cd[:, 0, 0], cd[:, 0, 1], order)
    if order == 0:
        return cd[:, 0], d.point, None, None
    u1, v1 = cd[:, 1, 0:1], cd[:, 1, 1:2]
    f1 = d.su * u1 + d.sv * v1
    if order == 1:
        return cd[:, 0], d.point, f1, None
    u2, v2 = cd[:, 2, 0:1], cd[:, 2, 1:2]
    f2 = d.suu * u1 * u1 + 2.0 * d.suv * u1 * v1 + d.svv * v1 * v1 + d.su * u2 + d.sv * v2
    return cd[:, 0], d.point, f1, f2


def descend_curve(surface: BSplineSurface, c: BSplineCurve, p: np.ndarray, t: np.ndarray, max_iter: int = 60):
    """Damped Newton on ``|S(c(t)) - p|^2`` over the curve's range (its ends are feet too).
    Returns ``(uv, point, converged)``."""
    a, b = c.bounds
    t = np.clip(np.array(t, float), a, b)
    uv, pt, _, _ = _curve_on_surface(surface, c, t, 0)
    w = pt - p
    f = np.einsum("ij,ij->i", w, w)
    conv = np.zeros(len(p), bool)
    act = np.arange(len(p))
    tol = 1e-14 * (b - a)
    for _ in range(max_iter):
        if act.size == 0:
            break
        _, x, f1, f2 = _curve_on_surface(surface, c, t[act], 2)
        r = x - p[act]
        g = np.einsum("ij,ij->i", f1, r)
        gg = np.einsum("ij,ij->i", f1, f1)
        h = gg + np.einsum("ij,ij->i", f2, r)
        h = np.where(h > 1e-12 * gg, h, gg + 1e-300)
        step = np.clip(g / h, -0.25 * (b - a), 0.25 * (b - a))
        ta = t[act]
        step = np.where(((ta <= a) & (step > 0)) | ((ta >= b) & (step < 0)), 0.0, step)
        f0 = f[act]
        slack = 1e-12 * f0 + 1e-24
        new_t, new_f = ta.copy(), f0.copy()
        pend = np.arange(act.size)
        for _ in range(30):
            trial = np.clip(ta[pend] - step[pend], a, b)
            _, y, _, _ = _curve_on_surface(surface, c, trial, 0)
            ft = np.einsum("ij,ij->i", y - p[act[pend]], y - p[act[pend]])
            ok = ft <= f0[pend] + slack[pend]
            new_t[pend[ok]], new_f[pend[ok]] = trial[ok], ft[ok]
            pend = pend[~ok]
            if pend.size == 0:
                break
            step[pend] *= 0.5
        step[pend] = 0.0
        moved = np.abs(new_t - ta)
        t[act], f[act] = new_t, new_f
        done = moved <= tol
        conv[act[done]] = True
        act = act[~done]
    uv, pt, _, _ = _curve_on_surface(surface, c, t, 0)
    return uv, pt, conv


def closest_points(reference, points, *, progress=None) -> FaceProjection:
    """Closest points of a face (trimming honoured) or of a whole surface, for many points (mm).

    Parameters
    ----------
    reference : Face or BSplineSurface
        The face measured against; a surface stands for its whole parameter box.
    points : array_like (n, 3)
        Query points, mm.
    progress : Progress, optional
        ``progress(done, total, message)`` after each batch of points.

    Returns
    -------
    FaceProjection
        Feet, their parameters, unit normals, unsigned distances and boundary flags.
    """
    from .face import Face

    face = reference if isinstance(reference, Face) else None
    surface = reference.surface if face is not None else reference
    dom = face_domain(surface, face.uv_bounds if face is not None else surface.bounds)
    grid = _SeedGrid(surface, dom)
    edges = _EdgeSamples(face, surface) if face is not None and face.is_trimmed else None
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    n = p.shape[0]
    uv, foot = np.empty((n, 2)), np.empty((n, 3))
    dist = np.empty(n)
    on_trim, conv = np.zeros(n, bool), np.zeros(n, bool)
    for a in range(0, n, _CHUNK):
        sl = slice(a, min(n, a + _CHUNK))
        uv[sl], foot[sl], dist[sl], on_trim[sl], conv[sl] = _closest_batch(surface, face, dom, grid, edges, p[sl])
        if progress is not None:
            progress(sl.stop, n, "closest points")
    normal = unit_normals_inside(surface, uv, dom)
    return FaceProjection(uv, foot, normal, dist, _at_box_edge(uv, dom) | on_trim, on_trim, conv)


def _at_box_edge(uv: np.ndarray, dom: _Domain) -> np.ndarray:
    """Parameters on an edge of the face's box in a direction where the face is not closed."""
    span = dom.hi - dom.lo
    return (~dom.wrap & ((uv <= dom.lo + 1e-12 * span) | (uv >= dom.hi - 1e-12 * span))).any(axis=1)


def _closest_batch(surface, face, dom: _Domain, grid: _SeedGrid, edges, p: np.ndarray):
    """:func:`closest_points` for one batch: surface feet from every basin's seed, those outside the
    trimming loops dropped, then the loops where they could be nearer."""
    rows, nodes, dist = _window(grid.tree, p, grid.reach)
    nodes = grid.nodes[nodes]
    first = np.r_[True, rows[1:] != rows[:-1]]  # each point's nearest node: always a seed
    d0 = dist[first][np.cumsum(first) - 1]
    near = first | (dist <= d0 + grid.node_reach[nodes])
    rows, nodes, dist, first = rows[near], nodes[near], dist[near], first[near]
    keep = first | _local_minima(p, rows, nodes, dist, grid.points, grid.neighbours)
    rows, nodes = rows[keep], nodes[keep]
    nv = grid.shape[1]
    seeds = np.stack([grid.us[nodes // nv], grid.vs[nodes % nv]], axis=1)
    uv, foot, conv = descend(surface, p[rows], seeds, dom)
    dist = np.linalg.norm(foot - p[rows], axis=1)
    if face is not None and face.is_trimmed:
        # a foot held on the box's edge is no interior foot: a point of the region there is on a loop
        dist = np.where(inside_face(face, uv, dom) & ~_at_box_edge(uv, dom), dist, np.inf)
    first = _best_per_row(rows, dist)
    uv, foot, dist, conv = uv[first], foot[first], dist[first], conv[first]
    on_trim = np.zeros(len(p), bool)
    if edges is not None:
        need, e_uv, e_foot, e_dist, e_conv = edges.closest(surface, p, dist)
        use = e_dist < dist[need]
        idx = need[use]
        uv[idx], foot[idx], dist[idx], conv[idx] = e_uv[use], e_foot[use], e_dist[use], e_conv[use]
        on_trim[idx] = True
    return uv, foot, dist, on_trim, conv


def inside_face(face, uv: np.ndarray, dom: _Domain | None = None) -> np.ndarray:
    """Parameter points inside the trimming loops, decided on polygons within 2e-5 mm of the loops on the
    surface (:func:`loop_polygons`). A point on the seam of a closed direction is tested a hair inside
    the box, where the loops' seam edges cannot make it ambiguous."""
    from .face import _points_in_polygons

    q = np.array(uv, float).reshape(-1, 2)
    if dom is not None:
        span = dom.hi - dom.lo
        for k in range(2):
            if dom.wrap[k]:
                q[:, k] = np.clip(q[:, k], dom.lo[k] + 1e-9 * span[k], dom.hi[k] - 1e-9 * span[k])
    return _points_in_polygons(q[:, 0], q[:, 1], loop_polygons(face))


def loop_polygons(face, tol: float = 2e-5) -> list:
    """The trimming loops as closed (u, v) polygons within ``tol`` mm of the loops' curves on the surface
    (:meth:`machsurf_cad.geometry.face.Face.trim_polygons`)."""
    return face.trim_polygons(tol)


def unit_normals_inside(surface: BSplineSurface, uv: np.ndarray, dom: _Domain) -> np.ndarray:
    """Unit ``su x sv`` at ``uv``; where it vanishes (a pole, a degenerate edge) the normal a little
    inside the face (towards the middle of its box), which is the limit normal there."""
    d = surface.derivatives(uv[:, 0], uv[:, 1], 1)
    n = np.cross(d.su, d.sv)
    ln = np.linalg.norm(n, axis=1)
    bad = ln <= 1e-12 * surface.scale**2
    centre = 0.5 * (dom.lo + dom.hi)
    for frac in (1e-7, 1e-5, 1e-3):
        if not bad.any():
            break
        q = uv[bad] + frac * (centre - uv[bad])
        db = surface.derivatives(q[:, 0], q[:, 1], 1)
        nb = np.cross(db.su, db.sv)
        n[bad] = nb
        ln[bad] = np.linalg.norm(nb, axis=1)
        bad = ln <= 1e-12 * surface.scale**2
    return n / np.where(ln > 0, ln, 1.0)[:, None]
