"""Many B-spline surfaces evaluated together.

A drop-cutter solve moves thousands of points, each on its own face of a part, one Newton step at a
time; evaluating face by face costs a Python round per face and step. :class:`SurfaceAtlas` gathers
every face's power-basis patches (the same exact Taylor coefficients as
:meth:`BSplineSurface.derivatives` uses) in one table per degree pair, so a step evaluates all points
of all faces in one vectorised pass per degree pair: the same numbers, to rounding.
"""

from __future__ import annotations

import numpy as np

from .bspline import _POWER_MAX_DEGREE, _power_rows, _rational_surface_derivs, _wrap_period

_KEYS = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]


class _Group:
    """The patches of the surfaces of one degree pair, homogeneous (dimension 4)."""

    def __init__(self, surfaces, members):
        self.p, self.q = surfaces[members[0]].degree_u, surfaces[members[0]].degree_v
        p, q = self.p, self.q
        flats, ub, uh, vb, vh = [], [], [], [], []
        n = len(members)
        self.slot = {int(f): k for k, f in enumerate(members)}
        self.uoff, self.voff, self.poff = np.zeros(n, int), np.zeros(n, int), np.zeros(n, int)
        self.nsu, self.nsv = np.zeros(n, int), np.zeros(n, int)
        self.dom = np.zeros((n, 4))
        self.per = np.zeros((n, 2), bool)
        self.period = np.zeros((n, 4))
        nu_tot = nv_tot = np_tot = 0
        for k, f in enumerate(members):
            s = surfaces[f]
            tu, tv, hp = s._eval_data
            flat, mapu, mapv, hu, hv, nsv = s._power_data
            dim = hp.shape[2]
            blocks = flat.reshape(-1, p + 1, q + 1, dim)
            if dim == 3:  # w = 1: its Taylor coefficients are 1 then zeros
                w = np.zeros(blocks.shape[:3] + (1,))
                w[:, 0, 0, 0] = 1.0
                blocks = np.concatenate([blocks, w], axis=3)
            flats.append(blocks.reshape(blocks.shape[0], -1))
            su, sv = np.nonzero(mapu >= 0)[0], np.nonzero(mapv >= 0)[0]
            a_u, b_u = tu[p], tu[hp.shape[0]]
            a_v, b_v = tv[q], tv[hp.shape[1]]
            ub.append(k * 4 + (tu[su] - a_u) / (b_u - a_u))
            vb.append(k * 4 + (tv[sv] - a_v) / (b_v - a_v))
            uh.append(np.column_stack([tu[su], hu]))
            vh.append(np.column_stack([tv[sv], hv]))
            self.uoff[k], self.voff[k], self.poff[k] = nu_tot, nv_tot, np_tot
            self.nsu[k], self.nsv[k] = su.size, sv.size
            self.dom[k] = a_u, b_u, a_v, b_v
            self.per[k] = s.periodic_u, s.periodic_v
            self.period[k] = s.knots_u[0], s.knots_u[-1], s.knots_v[0], s.knots_v[-1]
            nu_tot += su.size
            nv_tot += sv.size
            np_tot += su.size * sv.size
        self.flat = np.ascontiguousarray(np.concatenate(flats))
        self.ukeys, self.vkeys = np.concatenate(ub), np.concatenate(vb)
        self.uh, self.vh = np.concatenate(uh), np.concatenate(vh)

    def homogeneous(self, k, u, v, order):
        """Homogeneous derivatives ``H[m, a, b, :]`` (a + b <= order) at ``(u, v)`` on slots ``k``."""
        p, q = self.p, self.q
        pu, pv = self.per[k, 0], self.per[k, 1]
        if pu.any():
            u = np.where(pu, _wrap_period(u, self.period[k, 0], self.period[k, 1]), u)
        if pv.any():
            v = np.where(pv, _wrap_period(v, self.period[k, 2], self.period[k, 3]), v)
        d = self.dom[k]
        with np.errstate(invalid="ignore"):
            xu = np.clip((u - d[:, 0]) / (d[:, 1] - d[:, 0]), 0.0, 1.0)
            xv = np.clip((v - d[:, 2]) / (d[:, 3] - d[:, 2]), 0.0, 1.0)
        gi = np.searchsorted(self.ukeys, k * 4 + xu, side="right") - 1
        gj = np.searchsorted(self.vkeys, k * 4 + xv, side="right") - 1
        gi = np.clip(gi, self.uoff[k], self.uoff[k] + self.nsu[k] - 1)
        gj = np.clip(gj, self.voff[k], self.voff[k] + self.nsv[k] - 1)
        hi, hj = self.uh[gi, 1], self.vh[gj, 1]
        s = (u - self.uh[gi, 0]) / hi
        t = (v - self.vh[gj, 0]) / hj
        pid = self.poff[k] + (gi - self.uoff[k]) * self.nsv[k] + (gj - self.voff[k])
        m = u.shape[0]
        rows_u = _power_rows(s, p, order, hi)
        rows_v = _power_rows(t, q, order, hj)
        g = np.take(self.flat, pid, axis=0).reshape(m, p + 1, (q + 1) * 4)
        a = np.matmul(rows_u, g).reshape(m, order + 1, q + 1, 4)
        h = np.empty((m, order + 1, order + 1, 4))
        for i in range(order + 1):
            for j in range(order + 1 - i):
                h[:, i, j] = np.einsum("mbd,mb->md", a[:, i], rows_v[:, j])
        return h


class SurfaceAtlas:
    """Exact points and derivatives of many B-spline surfaces at scattered ``(surface, u, v)``.

    Parameters
    ----------
    surfaces : sequence of BSplineSurface

    Examples
    --------
    >>> import numpy as np
    >>> from machsurf_cad.geometry import builders
    >>> a, b = builders.plane_patch(), builders.sphere_patch(10.0, (0.0, 90.0), 360.0)
    >>> atlas = SurfaceAtlas([a, b])
    >>> fid, u, v = np.array([0, 1]), np.array([0.3, 0.2]), np.array([0.6, 0.7])
    >>> P = atlas.derivatives(fid, u, v, 0)[0]
    >>> bool(np.allclose(P[1], b.derivatives(u[1:], v[1:], 0).point[0], atol=1e-12))
    True
    """

    def __init__(self, surfaces):
        self.surfaces = tuple(surfaces)
        pairs: dict = {}
        self._loose = []
        for f, s in enumerate(self.surfaces):
            if s.degree_u <= _POWER_MAX_DEGREE and s.degree_v <= _POWER_MAX_DEGREE:
                pairs.setdefault((s.degree_u, s.degree_v), []).append(f)
            else:
                self._loose.append(f)
        self._groups = [_Group(self.surfaces, m) for m in pairs.values()]
        n = len(self.surfaces)
        self._group_of = np.full(n, -1)
        self._slot_of = np.zeros(n, int)
        for gi, g in enumerate(self._groups):
            for f, k in g.slot.items():
                self._group_of[f], self._slot_of[f] = gi, k

    def derivatives(self, fid, u, v, order: int) -> list:
        """Point, then (order >= 1) ``Su``, ``Sv``, then (order 2) ``Suu``, ``Suv``, ``Svv``: arrays (m, 3)."""
        fid = np.asarray(fid, int)
        u, v = np.asarray(u, float), np.asarray(v, float)
        m = u.shape[0]
        keys = _KEYS[: {0: 1, 1: 3, 2: 6}[order]]
        out = [np.empty((m, 3)) for _ in keys]
        grp = self._group_of[fid] if m else np.zeros(0, int)
        for gi, g in enumerate(self._groups):
            sel = np.nonzero(grp == gi)[0]
            if sel.size == 0:
                continue
            d = _rational_surface_derivs(g.homogeneous(self._slot_of[fid[sel]], u[sel], v[sel], order), order)
            for o, (a, b) in zip(out, keys):
                o[sel] = d[:, a, b]
        for f in self._loose:
            sel = np.nonzero(fid == f)[0]
            if sel.size:
                d = self.surfaces[f].derivatives(u[sel], v[sel], order)
                for o, p in zip(out, [d.point, d.su, d.sv, d.suu, d.suv, d.svv]):
                    o[sel] = p
        return out
