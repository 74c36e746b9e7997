"""An independent reference for the ball drop-cutter on trimmed faces, fast enough for 40,000-point grids.

Written apart from ``machsurf_cad.threeaxis``: it shares only the faces' evaluation, derivatives,
trimming test and size (:func:`machsurf_cad.gougecheck.face_size`, to space the samples). The tip of a
ball of radius R over the plan point q rests at the highest ``g(p) = p_z + sqrt(R^2 - |p_xy - q|^2) - R``
over the part's points p within R of q in plan. Here:

1. every face is sampled about ``spacing`` mm apart inside its trimming, every trimming curve (and an
   untrimmed face's parameter box) and every crease (an iso-parameter line where the surface is only C0,
   inside the trimming) ``edge_spacing`` mm apart;
2. per grid point, the best sample of each face and of each edge within R in plan;
3. each face's best sample climbs to its local maximum by Newton's method on the exact surface (exact first
   and second derivatives, steps accepted only uphill), kept when it ends inside the trimming and the disc;
   each edge's (and crease's) best sample by golden section between its two neighbours on the edge;
4. the height is the largest of all of these and of every sample (so never below a point of the part).
"""

from __future__ import annotations

import math

import numpy as np
from helpers import trimmed_grid
from scipy.spatial import cKDTree

from machsurf_cad.gougecheck import face_size


def _edges(face):
    """The face's boundary as parameter curves ``uv(t)`` on [0, 1]: its trimming curves, or its box."""
    out = []
    for loop in face.loops:
        for c in loop:
            t0, t1 = c.bounds
            out.append(lambda t, c=c, t0=t0, t1=t1: c.evaluate(t0 + (t1 - t0) * np.asarray(t)))
    if not out:
        u0, u1, v0, v1 = face.uv_bounds
        for a, b in (((u0, v0), (u1, v0)), ((u1, v0), (u1, v1)), ((u1, v1), (u0, v1)), ((u0, v1), (u0, v0))):
            a_, b_ = np.asarray(a, float), np.asarray(b, float)
            out.append(lambda t, a_=a_, b_=b_: a_ + np.asarray(t)[:, None] * (b_ - a_))
    return out


def _creases(face):
    """The face's C0 iso-parameter lines (interior knots of multiplicity at least the degree) as ``uv(t)``
    on [0, 1] across the whole parameter box (the samples outside the trimming are dropped)."""
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    out = []
    for knots, mults, p, fixed_u in ((s.knots_u, s.mults_u, s.degree_u, True),
                                     (s.knots_v, s.mults_v, s.degree_v, False)):  # fmt: skip
        vals, counts = np.asarray(knots, float), np.asarray(mults)
        for k in vals[1:-1][counts[1:-1] >= p]:
            if fixed_u and u0 < k < u1:
                out.append(lambda t, k=k: np.column_stack([np.full(np.size(t), k), v0 + (v1 - v0) * np.asarray(t)]))
            elif not fixed_u and v0 < k < v1:
                out.append(lambda t, k=k: np.column_stack([u0 + (u1 - u0) * np.asarray(t), np.full(np.size(t), k)]))
    return out


def chunks(tree, etree, xy, R: float, chunk: int, pairs: int) -> list[tuple[int, int]]:
    """``(start, end)`` runs of the plan points ``xy`` of at most ``chunk`` points and about ``pairs`` point-sample
    pairs within ``R`` (the face samples' ``tree`` and the edge samples' ``etree``)."""
    n = np.asarray(tree.query_ball_point(xy, R, return_length=True), float)
    n += np.asarray(etree.query_ball_point(xy, R, return_length=True), float)
    starts, total = [0], 0.0
    for k, c in enumerate(n.tolist()):
        if k > starts[-1] and (total + c > pairs or k - starts[-1] >= chunk):
            starts.append(k)
            total = 0.0
        total += c
    return list(zip(starts, starts[1:] + [xy.shape[0]]))


class BallReference:
    """The part sampled once; :meth:`heights` for any grid of plan points."""

    def __init__(self, faces, spacing: float = 0.15, edge_spacing: float = 0.01):
        self.faces = list(faces)
        P, F, U, V = [], [], [], []
        for i, f in enumerate(self.faces):
            u, v = trimmed_grid(f, face_size(f), spacing, 2, 6000)
            P.append(f.surface.evaluate(u, v))
            F.append(np.full(u.size, i))
            U.append(u)
            V.append(v)
        self.P, self.F, self.U, self.V = (np.concatenate(x) for x in (P, F, U, V))
        E, EI, ET, self.edge_fn, self.edge_face, self.edge_dt = [], [], [], [], [], []
        self.crease: list[bool] = []
        for i, f in enumerate(self.faces):
            for fn, crease in [(fn, False) for fn in _edges(f)] + [(fn, True) for fn in _creases(f)]:
                t = np.linspace(0, 1, 65)
                uv = fn(t)
                L = float(np.linalg.norm(np.diff(f.surface.evaluate(uv[:, 0], uv[:, 1]), axis=0), axis=1).sum())
                n = max(2, int(math.ceil(L / edge_spacing)) + 1)
                t = np.linspace(0, 1, n)
                uv = fn(t)
                keep = f.contains_uv(uv[:, 0], uv[:, 1]) if crease and f.is_trimmed else np.ones(n, bool)
                E.append(f.surface.evaluate(uv[keep, 0], uv[keep, 1]))
                EI.append(np.full(int(keep.sum()), len(self.edge_fn)))
                ET.append(t[keep])
                self.edge_fn.append(fn)
                self.edge_face.append(i)
                self.edge_dt.append(1.0 / (n - 1))
                self.crease.append(crease)
        self.E, self.EI, self.ET = np.concatenate(E), np.concatenate(EI), np.concatenate(ET)
        self.tree = cKDTree(self.P[:, :2])
        self.etree = cKDTree(self.E[:, :2])

    @staticmethod
    def _g(P, q, R):
        r2 = np.sum((P[..., :2] - q) ** 2, axis=-1)
        return np.where(r2 <= R * R, P[..., 2] + np.sqrt(np.maximum(R * R - r2, 0.0)) - R, -np.inf)

    def _best(self, tree, pts, group, xy, R):
        """Per grid point and group (face or edge), the best sample: (point index, sample index, value)."""
        qi, si = [], []
        for k, lst in enumerate(tree.query_ball_point(xy, R)):
            if lst:
                qi.append(np.full(len(lst), k))
                si.append(np.asarray(lst))
        if not qi:
            return np.empty(0, int), np.empty(0, int), np.empty(0)
        qi, si = np.concatenate(qi), np.concatenate(si)
        val = self._g(pts[si], xy[qi], R)
        order = np.lexsort((-val, group[si], qi))
        qi, si, val = qi[order], si[order], val[order]
        first = np.r_[True, (qi[1:] != qi[:-1]) | (group[si][1:] != group[si][:-1])]
        return qi[first], si[first], val[first]

    def _newton(self, f, u, v, q, R, iters: int = 30):
        s = f.surface
        u0, u1, v0, v1 = f.uv_bounds
        best = self._g(s.evaluate(u, v), q, R)
        for _ in range(iters):
            d = s.derivatives(u, v, order=2)
            dxy = d.point[:, :2] - q
            w = np.sqrt(np.maximum(R * R - np.sum(dxy**2, axis=1), 1e-30))
            su, sv, suu, suv, svv = d.su, d.sv, d.suu, d.suv, d.svv
            wu = -np.sum(dxy * su[:, :2], axis=1) / w
            wv = -np.sum(dxy * sv[:, :2], axis=1) / w
            gu, gv = su[:, 2] + wu, sv[:, 2] + wv
            huu = suu[:, 2] - (np.sum(su[:, :2] ** 2, 1) + np.sum(dxy * suu[:, :2], 1)) / w - wu * wu / w
            huv = suv[:, 2] - (np.sum(su[:, :2] * sv[:, :2], 1) + np.sum(dxy * suv[:, :2], 1)) / w - wu * wv / w
            hvv = svv[:, 2] - (np.sum(sv[:, :2] ** 2, 1) + np.sum(dxy * svv[:, :2], 1)) / w - wv * wv / w
            det = huu * hvv - huv * huv
            newton = (det > 0) & (huu < 0)
            safe = np.where(newton, det, 1.0)
            su_, sv_ = -(hvv * gu - huv * gv) / safe, -(huu * gv - huv * gu) / safe
            # where the value is not locally concave: a step up the gradient, 1/50 of the domain long
            gn = np.hypot(gu * (u1 - u0), gv * (v1 - v0)) + 1e-300
            step_u = np.where(newton, su_, gu * (u1 - u0) ** 2 / gn / 50)
            step_v = np.where(newton, sv_, gv * (v1 - v0) ** 2 / gn / 50)
            moved = np.zeros(u.size, bool)
            lam = np.ones(u.size)
            for _half in range(12):  # uphill only: halve the step until the value rises
                un = np.clip(u + lam * step_u, u0, u1)
                vn = np.clip(v + lam * step_v, v0, v1)
                val = self._g(s.evaluate(un, vn), q, R)
                up = (val > best) & ~moved
                u, v, best = np.where(up, un, u), np.where(up, vn, v), np.where(up, val, best)
                moved |= up
                lam = np.where(moved, lam, lam / 2)
                if moved.all():
                    break
            if not moved.any():
                break
        inside = f.contains_uv(u, v) if f.is_trimmed else np.ones(u.size, bool)
        return np.where(inside, best, -np.inf)

    def _golden(self, e, t_lo, t_hi, q, R, iters: int = 60):
        f = self.faces[self.edge_face[e]]
        fn = self.edge_fn[e]

        def g(t):
            uv = fn(t)
            return self._g(f.surface.evaluate(uv[:, 0], uv[:, 1]), q, R)

        a, b = t_lo.copy(), t_hi.copy()
        r = (math.sqrt(5) - 1) / 2
        c, d = b - r * (b - a), a + r * (b - a)
        gc, gd = g(c), g(d)
        for _ in range(iters):
            left = gc >= gd
            b = np.where(left, d, b)
            a = np.where(left, a, c)
            c2, d2 = b - r * (b - a), a + r * (b - a)
            c, d = np.where(left, c2, d), np.where(left, c, d2)
            gnew = g(np.where(left, c, d))
            gc, gd = np.where(left, gnew, gd), np.where(left, gc, gnew)
        best, t = np.maximum(gc, gd), np.where(gc >= gd, c, d)
        if self.crease[e] and f.is_trimmed:  # a crease's point counts only inside the trimming
            uv = fn(t)
            best = np.where(f.contains_uv(uv[:, 0], uv[:, 1]), best, -np.inf)
        return best

    def heights(self, xy, R: float, chunk: int = 2000, pairs: int = 4_000_000) -> np.ndarray:
        """Tip heights of a ball of radius ``R`` over the plan points ``xy`` (NaN where no face is within R), in
        chunks of at most ``chunk`` points and about ``pairs`` point-sample pairs (steep faces stack many
        samples under one point in plan)."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        out = np.full(xy.shape[0], -np.inf)
        for a, b in chunks(self.tree, self.etree, xy, R, chunk, pairs):
            q = xy[a:b]
            h = np.full(q.shape[0], -np.inf)
            qi, si, val = self._best(self.tree, self.P, self.F, q, R)
            np.maximum.at(h, qi, val)
            for fi in np.unique(self.F[si]):
                k = self.F[si] == fi
                np.maximum.at(h, qi[k], self._newton(self.faces[fi], self.U[si[k]], self.V[si[k]], q[qi[k]], R))
            qe, se, vale = self._best(self.etree, self.E, self.EI, q, R)
            np.maximum.at(h, qe, vale)
            for e in np.unique(self.EI[se]):
                k = self.EI[se] == e
                t = self.ET[se[k]]
                dt = self.edge_dt[e]
                np.maximum.at(h, qe[k], self._golden(e, np.maximum(t - dt, 0.0), np.minimum(t + dt, 1.0), q[qe[k]], R))
            out[a:b] = h
        return np.where(np.isfinite(out), out, np.nan)
