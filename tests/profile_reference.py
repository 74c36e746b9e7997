"""An independent reference for the flat and bull-nose drop-cutters on trimmed faces, fast enough for 40,000-point
grids.

Written apart from ``machsurf_cad.threeaxis``, like ``ball_reference.py`` (whose sampling of the trimming curves
and creases it reuses): it shares only the faces' evaluation, derivatives, trimming test and size. The lower
surface of a flat (``r = 0``) or bull-nose (corner radius ``0 < r < R``) end mill whose tip is at height H over
the plan point q is ``z = H + h(rho)``, rho the plan distance from q: ``h = 0`` for ``rho <= R - r``,
``h = r - sqrt(r^2 - (rho - R + r)^2)`` beyond. The tip rests at the highest ``g(p) = p_z - h(|p_xy - q|)`` over
the part's points p within R of q in plan. Here:

1. every face is sampled about ``spacing`` mm apart inside its trimming, every trimming curve (an untrimmed
   face's parameter box) and crease ``edge_spacing`` mm apart, as for the ball;
2. per grid point only the samples within a margin of its best one are kept (what refining can add: 3 sample
   spacings, and the rise of h over as much at the rim). Seeds: per grid point, face and sector of the disc (8)
   the best sample of the face or of its edges; per grid point and edge every sample at least as high as its
   neighbours on the edge (a neighbour outside the disc counts as -inf: the last sample before the edge leaves
   the disc is one);
3. a face's seed climbs to its local maximum of g by Newton's method on the exact surface (exact first and second
   derivatives, steps accepted only uphill, so inside the disc; a seed that cannot move where g curves up, as
   where a fillet meets its floor, again from a quarter of a sample cell off it); an edge's by golden section
   between its two neighbours on the edge (converging on the point where the edge leaves the disc when g rises
   up to it);
4. flat end only, the highest point on the rim circle ``c(t) = q + R (cos t, sin t)``: per grid point, face and
   sector (16) the best seed within 3 sample spacings of the rim is moved onto the circle (2-D Newton on (u, v)
   for the face point over c(t), also from a quarter cell off the seed, where the face may be vertical) and z(t)
   climbs to its maximum by Newton's method on t (exact dz/dt and d2z/dt2 through the implicit map, steps
   accepted only uphill). Faces vertical in plan have no such point (their top edges carry the contact); a rim
   maximum where the face's boundary crosses the circle is the edge's;
5. a refined point counts only inside the trimming; the height is the largest of all of these and of every
   sample, so never below a point of the part.
"""

from __future__ import annotations

import math

import numpy as np
from ball_reference import _creases, _edges, chunks
from helpers import trimmed_grid
from scipy.spatial import cKDTree

from machsurf_cad.gougecheck import face_size


def _h(rho, R: float, r: float):
    """The profile's rise ``h(rho)`` and its first two derivatives (``r = 0``: the flat end, h = 0)."""
    rho = np.asarray(rho, float)
    if r == 0:
        z = np.zeros_like(rho)
        return z, z, z
    x = np.maximum(rho - (R - r), 0.0)
    s2 = np.maximum(r * r - x * x, 0.0)
    w = np.sqrt(np.maximum(s2, 1e-30))
    return r - np.sqrt(s2), np.where(x > 0, x / w, 0.0), np.where(x > 0, r * r / w**3, 0.0)


def _g(P, q, R: float, r: float):
    rho = np.sqrt(np.sum((P[..., :2] - q) ** 2, axis=-1))
    return np.where(rho <= R, P[..., 2] - _h(np.minimum(rho, R), R, r)[0], -np.inf)


def _solve2(a, b, c, d, x, y):
    """``[[a, b], [c, d]]^-1 (x, y)`` elementwise (0 where singular) and the regular mask."""
    det = a * d - b * c
    ok = np.abs(det) > 1e-12 * (np.abs(a * d) + np.abs(b * c) + 1e-300)
    s = np.where(ok, det, 1.0)
    return np.where(ok, (d * x - b * y) / s, 0.0), np.where(ok, (a * y - c * x) / s, 0.0), ok


def _pairs(tree, xy, R):
    """All (point, sample) pairs within R in plan: point and sample indices, plan distance."""
    m = cKDTree(xy).sparse_distance_matrix(tree, R, output_type="ndarray")
    return m["i"], m["j"], m["v"]


def _best(keys, val):
    """Indices of the highest ``val`` per distinct key."""
    order = np.lexsort((-val, keys))
    return order[np.r_[True, keys[order][1:] != keys[order][:-1]]]


class ProfileReference:
    """The part sampled once; :meth:`heights` for any grid of plan points and flat or bull-nose cutter."""

    def __init__(self, faces, spacing: float = 0.15, edge_spacing: float = 0.01):
        self.faces = list(faces)
        P, F, U, V, cell, duv = [], [], [], [], [], []
        for i, f in enumerate(self.faces):
            lengths = face_size(f)
            u, v = trimmed_grid(f, lengths, spacing, 2, 6000)
            P.append(f.surface.evaluate(u, v))
            F, U, V = F + [np.full(u.size, i)], U + [u], V + [v]
            u0, u1, v0, v1 = f.uv_bounds  # the largest diagonal of the sample grid's cells, mm
            nu, nv = (int(np.clip(math.ceil(x / spacing) + 1, 2, 6000)) for x in lengths)
            duv.append(((u1 - u0) / (nu - 1), (v1 - v0) / (nv - 1)))
            G = f.surface.evaluate_grid(np.linspace(u0, u1, nu), np.linspace(v0, v1, nv))
            cell.append(max(np.linalg.norm(G[1:, 1:] - G[:-1, :-1], axis=-1).max(),
                            np.linalg.norm(G[1:, :-1] - G[:-1, 1:], axis=-1).max()))  # fmt: skip
        self.P, self.F, self.U, self.V = (np.concatenate(x) for x in (P, F, U, V))
        self.cell, self.duv = np.asarray(cell), np.asarray(duv)
        E, EI, ET, EF, EU, EV, step, dts = ([] for _ in range(8))
        self.edge_fn, self.edge_face, self.crease = [], [], []
        for i, f in enumerate(self.faces):
            for fn, crease in [(fn, False) for fn in _edges(f)] + [(fn, True) for fn in _creases(f)]:
                uv = fn(np.linspace(0, 1, 65))
                L = float(np.linalg.norm(np.diff(f.surface.evaluate(uv[:, 0], uv[:, 1]), axis=0), axis=1).sum())
                n = max(2, int(math.ceil(L / edge_spacing)) + 1)
                t = np.linspace(0, 1, n)
                uv = fn(t)
                pts = f.surface.evaluate(uv[:, 0], uv[:, 1])
                keep = f.contains_uv(uv[:, 0], uv[:, 1]) if crease and f.is_trimmed else np.ones(n, bool)
                E.append(pts[keep])
                EI.append(np.full(int(keep.sum()), len(self.edge_fn)))
                ET.append(t[keep])
                EF, EU, EV = EF + [np.full(int(keep.sum()), i)], EU + [uv[keep, 0]], EV + [uv[keep, 1]]
                step.append(float(np.linalg.norm(np.diff(pts, axis=0), axis=1).max()))
                self.edge_fn.append(fn)
                self.edge_face.append(i)
                dts.append(1.0 / (n - 1))
                self.crease.append(crease)
        self.E, self.EI, self.ET, self.EF, self.EU, self.EV = (np.concatenate(x) for x in (E, EI, ET, EF, EU, EV))
        self.edge_step, self.edge_dt = np.asarray(step), np.asarray(dts)
        self.tree = cKDTree(self.P[:, :2])
        self.etree = cKDTree(self.E[:, :2])

    def _newton(self, fi, u, v, q, R, r, iters: int = 40, retry: bool = True):
        """Each seed climbs to its local maximum of g on the face (uphill steps only); -inf if it ends outside
        the trimming."""
        f = self.faces[fi]
        s = f.surface
        u0, u1, v0, v1 = f.uv_bounds
        u, v = np.array(u, float), np.array(v, float)
        best = _g(s.evaluate(u, v), q, R, r)
        ever, curved = np.zeros(u.size, bool), np.zeros(u.size, bool)
        act = np.arange(u.size)
        for it in range(iters):
            if act.size == 0:
                break
            d, qa = s.derivatives(u[act], v[act], order=2), q[act]
            dxy = d.point[:, :2] - qa
            rho = np.maximum(np.sqrt(np.sum(dxy**2, axis=1)), 1e-12)
            _, h1, h2 = _h(rho, R, r)
            xu, xv = d.su[:, :2], d.sv[:, :2]
            ru, rv = np.sum(dxy * xu, 1) / rho, np.sum(dxy * xv, 1) / rho
            ruu = (np.sum(xu * xu, 1) + np.sum(dxy * d.suu[:, :2], 1) - ru * ru) / rho
            ruv = (np.sum(xu * xv, 1) + np.sum(dxy * d.suv[:, :2], 1) - ru * rv) / rho
            rvv = (np.sum(xv * xv, 1) + np.sum(dxy * d.svv[:, :2], 1) - rv * rv) / rho
            gu, gv = d.su[:, 2] - h1 * ru, d.sv[:, 2] - h1 * rv
            huu = d.suu[:, 2] - h2 * ru * ru - h1 * ruu
            huv = d.suv[:, 2] - h2 * ru * rv - h1 * ruv
            hvv = d.svv[:, 2] - h2 * rv * rv - h1 * rvv
            if it == 0:  # g curves up somewhere across a cell: a seed at a stationary point may be no maximum
                A, B, C = huu * self.duv[fi, 0] ** 2, huv * self.duv[fi].prod(), hvv * self.duv[fi, 1] ** 2
                curved = (A + C) / 2 + np.hypot((A - C) / 2, B) > 1e-12
            det = huu * hvv - huv * huv
            newton = (det > 0) & (huu < 0)
            safe = np.where(newton, det, 1.0)
            su_, sv_ = -(hvv * gu - huv * gv) / safe, -(huu * gv - huv * gu) / safe
            # where g is not locally concave: a step up the gradient, 1/50 of the domain long
            gn = np.hypot(gu * (u1 - u0), gv * (v1 - v0)) + 1e-300
            step_u = np.where(newton, su_, gu * (u1 - u0) ** 2 / gn / 50)
            step_v = np.where(newton, sv_, gv * (v1 - v0) ** 2 / gn / 50)
            moved = np.zeros(act.size, bool)
            idx, lam = np.flatnonzero(np.hypot(step_u / (u1 - u0), step_v / (v1 - v0)) > 1e-14), 1.0
            for _half in range(20):  # uphill only: halve the step until g rises
                if idx.size == 0:
                    break
                k = act[idx]
                un = np.clip(u[k] + lam * step_u[idx], u0, u1)
                vn = np.clip(v[k] + lam * step_v[idx], v0, v1)
                val = _g(s.evaluate(un, vn), q[k], R, r)
                up = val > best[k]
                u[k[up]], v[k[up]], best[k[up]] = un[up], vn[up], val[up]
                moved[idx[up]] = True
                idx, lam = idx[~up], lam / 2
            ever[act[moved]] = True
            act = act[moved]
        inside = f.contains_uv(u, v) if f.is_trimmed else np.ones(u.size, bool)
        best = np.where(inside, best, -np.inf)
        k = np.flatnonzero(~ever & curved)
        if retry and k.size:  # e.g. a seed where a fillet meets its floor: from a quarter cell off it
            du, dv = self.duv[fi] / 4
            uu = np.concatenate([np.clip(u[k] + a * du, u0, u1) for a in (1, -1, 0, 0)])
            vv = np.concatenate([np.clip(v[k] + b * dv, v0, v1) for b in (0, 0, 1, -1)])
            more = self._newton(fi, uu, vv, np.tile(q[k], (4, 1)), R, r, iters, False).reshape(4, -1).max(axis=0)
            best[k] = np.maximum(best[k], more)
        return best

    @staticmethod
    def _onto(s, box, u, v, q, R, t, iters: int = 10):
        """The face point over ``q + R (cos t, sin t)`` by 2-D Newton from (u, v): u, v and whether it is there."""
        c = q + R * np.column_stack([np.cos(t), np.sin(t)])
        for _ in range(iters):
            d = s.derivatives(u, v, order=1)
            e = d.point[:, :2] - c
            if np.all(np.abs(e) < 1e-12):
                break
            du, dv, _ = _solve2(d.su[:, 0], d.sv[:, 0], d.su[:, 1], d.sv[:, 1], -e[:, 0], -e[:, 1])
            u, v = np.clip(u + du, box[0], box[1]), np.clip(v + dv, box[2], box[3])
        return u, v, np.linalg.norm(s.evaluate(u, v)[:, :2] - c, axis=1) < 1e-11

    def _rim(self, fi, u, v, q, R, iters: int = 40):
        """Flat end: from each seed, the highest point of the face on the rim circle near it (-inf if none)."""
        f = self.faces[fi]
        s, box = f.surface, f.uv_bounds
        p = s.evaluate(u, v)
        t = np.arctan2(p[:, 1] - q[:, 1], p[:, 0] - q[:, 0])
        z = np.full(u.size, -np.inf)
        du, dv = self.duv[fi] / 4  # also from a quarter cell off the seed (a seed where the face is vertical)
        for a, b in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)):
            un, vn, ok = self._onto(s, box, np.clip(u + a * du, *box[:2]), np.clip(v + b * dv, *box[2:]), q, R, t)
            zn = np.where(ok, s.evaluate(un, vn)[:, 2], -np.inf)
            up = zn > z
            u, v, z = np.where(up, un, u), np.where(up, vn, v), np.where(up, zn, z)
        act = np.flatnonzero(np.isfinite(z))
        for _ in range(iters):
            if act.size == 0:
                break
            d = s.derivatives(u[act], v[act], order=2)
            ta = t[act]
            c1x, c1y, c2x, c2y = -R * np.sin(ta), R * np.cos(ta), -R * np.cos(ta), -R * np.sin(ta)
            a, b, c, e = d.su[:, 0], d.sv[:, 0], d.su[:, 1], d.sv[:, 1]
            up, vp, reg = _solve2(a, b, c, e, c1x, c1y)  # (u', v') along the circle
            B = d.suu * (up * up)[:, None] + 2 * d.suv * (up * vp)[:, None] + d.svv * (vp * vp)[:, None]
            upp, vpp, _ = _solve2(a, b, c, e, c2x - B[:, 0], c2y - B[:, 1])
            z1 = d.su[:, 2] * up + d.sv[:, 2] * vp
            z2 = B[:, 2] + d.su[:, 2] * upp + d.sv[:, 2] * vpp
            newton = z2 < 0
            step = np.where(newton, -z1 / np.where(newton, z2, -1.0), np.where(z1 < 0, -0.02, 0.02))
            step = np.where(reg, np.clip(step, -0.3, 0.3), 0.0)
            moved = np.zeros(act.size, bool)
            idx, lam = np.flatnonzero(np.abs(step) > 1e-11), 1.0  # converged below
            for _half in range(12):  # uphill only: halve the step until z rises
                k = act[idx]
                un, vn, okn = self._onto(s, box, u[k], v[k], q[k], R, t[k] + lam * step[idx], iters=6)
                zn = s.evaluate(un, vn)[:, 2]
                upm = okn & (zn > z[k])
                kk = k[upm]
                u[kk], v[kk], z[kk], t[kk] = un[upm], vn[upm], zn[upm], t[kk] + lam * step[idx[upm]]
                moved[idx[upm]] = True
                lam, idx = lam / 2, idx[~upm]
                if idx.size == 0:
                    break
            act = act[moved]
        inside = f.contains_uv(u, v) if f.is_trimmed else np.ones(u.size, bool)
        return np.where(inside, z, -np.inf)

    def _golden(self, e, t_lo, t_hi, q, R, r, iters: int = 64):
        """The best value of g found by golden section on the edge ``e`` between ``t_lo`` and ``t_hi``."""
        f = self.faces[self.edge_face[e]]
        fn = self.edge_fn[e]

        def g(t):
            uv = fn(t)
            return _g(f.surface.evaluate(uv[:, 0], uv[:, 1]), q, R, r)

        a, b = t_lo.copy(), t_hi.copy()
        k = (math.sqrt(5) - 1) / 2
        c, d = b - k * (b - a), a + k * (b - a)
        gc, gd = g(c), g(d)
        best, tb = np.maximum(gc, gd), np.where(gc >= gd, c, d)
        for _ in range(iters):
            left = gc >= gd
            b = np.where(left, d, b)
            a = np.where(left, a, c)
            c2, d2 = b - k * (b - a), a + k * (b - a)
            c, d = np.where(left, c2, d), np.where(left, c, d2)
            tn = np.where(left, c, d)
            gnew = g(tn)
            gc, gd = np.where(left, gnew, gd), np.where(left, gc, gnew)
            better = gnew > best
            best, tb = np.where(better, gnew, best), np.where(better, tn, tb)
        if self.crease[e] and f.is_trimmed:  # a crease's point counts only inside the trimming
            uv = fn(tb)
            best = np.where(f.contains_uv(uv[:, 0], uv[:, 1]), best, -np.inf)
        return best

    def heights(self, xy, R: float, r: float = 0.0, chunk: int = 4000, pairs: int = 10_000_000) -> np.ndarray:
        """Tip heights of a flat (``r = 0``) or bull-nose (corner radius ``r``) end mill of radius ``R`` over the
        plan points ``xy`` (NaN where no face is within R), in chunks of at most ``chunk`` points and about
        ``pairs`` point-sample pairs."""
        if not 0 <= r < R:
            raise ValueError(f"need 0 <= r < R, got R = {R}, r = {r}")
        xy = np.asarray(xy, float).reshape(-1, 2)
        out = np.full(xy.shape[0], -np.inf)
        for a, b in chunks(self.tree, self.etree, xy, R, chunk, pairs):
            out[a:b] = self._chunk(xy[a:b], float(R), float(r))
        return np.where(np.isfinite(out), out, np.nan)

    def _chunk(self, q, R, r):
        h = np.full(q.shape[0], -np.inf)
        qi, si, rho_f = _pairs(self.tree, q, R)
        val = self.P[si, 2] - _h(rho_f, R, r)[0]
        np.maximum.at(h, qi, val)
        qe, se, rho_e = _pairs(self.etree, q, R)
        vale = self.E[se, 2] - _h(rho_e, R, r)[0]
        np.maximum.at(h, qe, vale)
        # what refining can add to a sample (3 sample spacings, and the rise of h over as much at the rim)
        margin = 3 * self.cell + r - _h(R - 3 * self.cell, R, r)[0]  # h(R) = r
        em = 3 * self.edge_step + r - _h(R - 3 * self.edge_step, R, r)[0]
        k = val >= h[qi] - margin[self.F[si]]
        qi, si, rho_f, val = qi[k], si[k], rho_f[k], val[k]
        k = vale >= h[qe] - np.maximum(margin[self.EF[se]], em[self.EI[se]])
        qe, se, rho_e, vale = qe[k], se[k], rho_e[k], vale[k]
        # seeds on the faces: their samples and the edges' samples
        sq, fi, val = np.r_[qi, qe], np.r_[self.F[si], self.EF[se]], np.r_[val, vale]
        su, sv, rho = np.r_[self.U[si], self.EU[se]], np.r_[self.V[si], self.EV[se]], np.r_[rho_f, rho_e]
        dxy = np.r_[self.P[si, :2], self.E[se, :2]] - q[sq]
        ang = np.arctan2(dxy[:, 1], dxy[:, 0]) + math.pi
        # the best seed per point, face and sector of the disc climbs to its maximum of g (flat: also on the rim)
        for nsec, rim in ((8, False), (16, True)) if r == 0 else ((8, False),):
            sec = np.minimum((ang * nsec / (2 * math.pi)).astype(np.int64), nsec - 1)
            keys = (sq.astype(np.int64) * len(self.faces) + fi) * nsec + sec
            pool = np.flatnonzero(rho >= R - 3 * self.cell[fi]) if rim else np.arange(sq.size)
            sel = pool[_best(keys[pool], val[pool])]
            sel = sel[val[sel] >= h[sq[sel]] - margin[fi[sel]]]
            for f_id in np.unique(fi[sel]):
                k = sel[fi[sel] == f_id]
                uu, vv, qq = su[k], sv[k], q[sq[k]]
                res = self._rim(f_id, uu, vv, qq, R) if rim else self._newton(f_id, uu, vv, qq, R, r)
                np.maximum.at(h, sq[k], res)
        # edges: each sample at least as high as its neighbours on the edge, by golden section around it (a
        # neighbour outside the disc or far below the best is -inf)
        if qe.size:
            order = np.lexsort((se, qe))
            qe, se, vale = qe[order], se[order], vale[order]
            ei = self.EI[se]
            nb = (qe[1:] == qe[:-1]) & (se[1:] == se[:-1] + 1) & (ei[1:] == ei[:-1])
            nb &= np.abs(self.ET[se[1:]] - self.ET[se[:-1]] - self.edge_dt[ei[1:]]) < 0.5 * self.edge_dt[ei[1:]]
            prev = np.r_[-np.inf, np.where(nb, vale[:-1], -np.inf)]
            nxt = np.r_[np.where(nb, vale[1:], -np.inf), -np.inf]
            cand = np.flatnonzero((vale > prev + 1e-10) & (vale >= nxt - 1e-10) & (vale >= h[qe] - em[ei]))
            for e in np.unique(ei[cand]):
                k = cand[ei[cand] == e]
                t, dt = self.ET[se[k]], self.edge_dt[e]
                res = self._golden(e, np.maximum(t - dt, 0.0), np.minimum(t + dt, 1.0), q[qe[k]], R, r)
                np.maximum.at(h, qe[k], res)
        return h
