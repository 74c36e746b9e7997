"""Exact drop-cutter on the B-rep: the lowest tool position above ``(x, y)`` that touches no face.

For a tool whose axis is +z (the :class:`~machsurf_cad.threeaxis.faceset.FaceSet` frame) and whose lower
surface is ``z = tip_z + h(rho)`` (:func:`~machsurf_cad.cutter_profiles.lower_height`, out to the profile's
largest radius ``R``), the tip height at ``c = (x, y)`` is

    tip_z(c) = max over part points p with |p_xy - c| <= R of  p_z - h(|p_xy - c|).

The maximum is reached at one of these contacts, each found by a local solve on the exact NURBS:

* ``FACE``: inside a face, where ``g(u, v) = S_z - h(|S_xy - c|)`` is stationary (damped Newton with a
  trust region; it also finds flat spots under a flat bottom, ``h' = 0``);
* ``RIM``: the profile's outer circle ``rho = R`` on a face (Newton on the Lagrange system of
  ``max S_z`` subject to ``|S_xy - c| = R``): walls, steep faces, a flat end mill's edge;
* ``EDGE``: on a trimming edge or at a vertex (golden-section search along the edge's exact curve, cut
  back to the circle where the maximum lies outside it);
* ``TIP``: the point below a pointed tip (profiles with ``h'(0) > 0``);
* ``SAMPLE``: a seed sample itself, when no refinement beats it (counted in the report).

Seeds come from a k-d tree over the face and edge samples in plan; per query the best sample of each
face and edge in five sectors of the disc (centre, four quadrants) seeds the solves. Every candidate
is a point of the part inside the disc, so the result never lies above the exact value; it equals it
when a seed lies in the basin of the highest contact (checked against brute force and OpenCAMLib in
the tests).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from scipy.spatial import cKDTree

from ..cutter_profiles import lower_height
from ..errors import InputError
from ..results import Progress, Result
from .faceset import FaceSet, face_set


class Contact(IntEnum):
    """Where the tool touches the part at a CL point (OpenCAMLib's CC types, for any profile)."""

    NONE = 0
    """No face under the tool: the height is NaN."""
    FACE = 1
    """The profile tangent to a face's interior (includes flat spots under a flat bottom)."""
    RIM = 2
    """The profile's outer circle on a face (walls, steep faces)."""
    EDGE = 3
    """A trimming edge or vertex of a face."""
    TIP = 4
    """The point below a pointed tip."""
    SAMPLE = 5
    """A seed sample (no refinement beat it)."""


@dataclass(frozen=True, eq=False)
class DropCutterResult(Result):
    """Exact drop-cutter heights at query points (mm).

    Attributes
    ----------
    xy : ndarray (n, 2)
        Query points in the tool frame (``x`` along ``frame[0]``, ``y`` along ``frame[1]``).
    height : ndarray (n,)
        Tip height along the axis (tool frame z), NaN where no face lies under the tool.
    tip : ndarray (n, 3)
        CL points (tool tips) in world coordinates.
    contact : ndarray (n, 3)
        The contact (CC) points in world coordinates.
    face : ndarray (n,)
        Index of the contact face in the given faces (-1: none).
    kind : ndarray (n,)
        :class:`Contact` of each point.
    axis : ndarray (3,)
        Tool axis (world, unit).
    frame : ndarray (3, 3)
        World -> tool frame rotation (rows e1, e2, axis).
    cutter : str
        The cutter's spec.
    time_s : dict
        Stage timings (seconds).
    """

    xy: np.ndarray
    height: np.ndarray
    tip: np.ndarray
    contact: np.ndarray
    face: np.ndarray
    kind: np.ndarray
    axis: np.ndarray
    frame: np.ndarray
    cutter: str
    time_s: dict

    @property
    def n_points(self) -> int:
        return int(self.height.shape[0])

    def report(self) -> dict:
        kinds = {k.name.lower(): int(np.count_nonzero(self.kind == k)) for k in Contact}
        ok = np.isfinite(self.height)
        return {
            "cutter": self.cutter,
            "n_points": self.n_points,
            "n_without_face": int((~ok).sum()),
            "contacts": kinds,
            "height_min_mm": float(self.height[ok].min()) if ok.any() else None,
            "height_max_mm": float(self.height[ok].max()) if ok.any() else None,
            "axis": [float(a) for a in self.axis],
            "time_s": dict(self.time_s),
        }


# ----------------------------------------------------------------------------- evaluation helpers
def _surface_eval(fs: FaceSet, fid, u, v, order: int):
    """Point and derivatives of each point's face: arrays (m, 3) for P, Su, Sv (and Suu, Suv, Svv)."""
    m = u.shape[0]
    keys = 1 if order == 0 else (3 if order == 1 else 6)
    out = [np.empty((m, 3)) for _ in range(keys)]
    for f in np.unique(fid):
        sel = np.nonzero(fid == f)[0]
        d = fs.faces[f].surface.derivatives(u[sel], v[sel], order)
        parts = [d.point, d.su, d.sv, d.suu, d.suv, d.svv][:keys]
        for o, p in zip(out, parts):
            o[sel] = p
    return out


def _clamp_uv(fs: FaceSet, fid, u, v):
    b = np.array([fs.faces[f].uv_bounds for f in range(len(fs.faces))])[fid]
    return np.clip(u, b[:, 0], b[:, 1]), np.clip(v, b[:, 2], b[:, 3])


def _inside(fs: FaceSet, fid, u, v) -> np.ndarray:
    ok = np.zeros(u.shape[0], bool)
    for f in np.unique(fid):
        sel = np.nonzero(fid == f)[0]
        face = fs.faces[f]
        u0, u1, v0, v1 = face.uv_bounds
        tol = 1e-12 * max(u1 - u0, v1 - v0, 1.0)
        ok[sel] = face.contains_uv(u[sel], v[sel], n_per_curve=1024) if face.is_trimmed else (
            (u[sel] >= u0 - tol) & (u[sel] <= u1 + tol) & (v[sel] >= v0 - tol) & (v[sel] <= v1 + tol)
        )  # fmt: skip
    return ok


class _Profile:
    """``h``, ``h'``, ``h''`` of the cutter's lower surface out to its largest radius."""

    def __init__(self, cutter):
        self.segs = cutter.profile()
        pts = cutter.profile_points(64)
        self.R = float(pts[:, 0].max())
        self.h_R = float(lower_height(self.segs, np.array([self.R]))[0][0])
        if not math.isfinite(self.h_R):  # a vertical side only: its foot
            self.h_R = float(pts[np.argmax(pts[:, 0]), 1])
        _, h1, _ = lower_height(self.segs, np.array([0.0]))
        self.pointed = bool(abs(h1[0]) > 1e-9)
        table = self(np.linspace(0.0, self.R, 2049))[0]
        self.monotone = bool(np.all(np.diff(table) >= -1e-12))
        self.h_min = float(table.min())

    def floor(self, rho) -> np.ndarray:
        """A lower bound of ``h`` on ``[rho, R]`` (``h(max(rho, 0))`` for a profile rising outwards)."""
        rho = np.asarray(rho, float)
        if not self.monotone:
            return np.full(rho.shape, self.h_min)
        return self(np.clip(rho, 0.0, self.R))[0]

    def __call__(self, rho):
        rho = np.asarray(rho, float)
        h, h1, h2 = lower_height(self.segs, np.minimum(rho, self.R))
        h = np.where(rho <= self.R * (1 + 1e-12), np.where(np.isfinite(h), h, self.h_R), np.inf)
        return h, h1, h2


def _g_and_derivs(prof: _Profile, c, P, Su, Sv, Suu=None, Suv=None, Svv=None):
    """``g = S_z - h(|S_xy - c|)`` with its (u, v) gradient and Hessian."""
    d = P[:, :2] - c
    rho = np.hypot(d[:, 0], d[:, 1])
    h, h1, h2 = prof(rho)
    g = P[:, 2] - h
    small = rho < 1e-9
    rs = np.where(small, 1.0, rho)
    B = np.where(small, h2, h1 / rs)  # h'/rho -> h''(0) at the axis
    A = np.where(small, 0.0, (h2 - B) / rs**2)
    gd = B[:, None] * d
    xu, xv = Su[:, :2], Sv[:, :2]
    gu = Su[:, 2] - np.einsum("ij,ij->i", gd, xu)
    gv = Sv[:, 2] - np.einsum("ij,ij->i", gd, xv)
    if Suu is None:
        return g, gu, gv, None
    du = np.einsum("ij,ij->i", d, xu)
    dv = np.einsum("ij,ij->i", d, xv)
    Huu = Suu[:, 2] - (A * du * du + B * np.einsum("ij,ij->i", xu, xu)) - np.einsum("ij,ij->i", gd, Suu[:, :2])
    Huv = Suv[:, 2] - (A * du * dv + B * np.einsum("ij,ij->i", xu, xv)) - np.einsum("ij,ij->i", gd, Suv[:, :2])
    Hvv = Svv[:, 2] - (A * dv * dv + B * np.einsum("ij,ij->i", xv, xv)) - np.einsum("ij,ij->i", gd, Svv[:, :2])
    return g, gu, gv, (Huu, Huv, Hvv)


# ----------------------------------------------------------------------------- local solves
def _face_newton(fs, prof, c, fid, u, v, iters: int = 40):
    """Maximise ``g`` from ``(u, v)``: damped Newton (Hessian shifted to negative definite) with a trust
    region in mm; steps that do not increase ``g`` or leave the tool's disc are refused."""
    u, v = u.copy(), v.copy()
    D = _surface_eval(fs, fid, u, v, 2)
    g, gu, gv, H = _g_and_derivs(prof, c, *D)
    radius = np.full(u.shape, 0.5 * fs.spacing)
    active = np.isfinite(g)
    for _ in range(iters):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        Huu, Huv, Hvv = (h[idx] for h in H)
        a, b, d_ = -Huu, -Huv, -Hvv  # M = -H: Newton where it is positive definite
        det = a * d_ - b * b
        newton = (a > 0) & (det > 1e-14 * (a * a + d_ * d_ + b * b))
        det = np.where(newton, det, 1.0)
        du = np.where(newton, (d_ * gu[idx] - b * gv[idx]) / det, 0.0)
        dv = np.where(newton, (-b * gu[idx] + a * gv[idx]) / det, 0.0)
        Su, Sv = D[1][idx], D[2][idx]
        # elsewhere steepest ascent on the surface (first fundamental form), as long as the trust radius
        E = np.einsum("ij,ij->i", Su, Su)
        F = np.einsum("ij,ij->i", Su, Sv)
        G = np.einsum("ij,ij->i", Sv, Sv)
        dg = E * G - F * F
        # near a pole or a collapsed edge (one tangent vanishing): the parameter gradient instead
        regular = (dg > 1e-10 * E * G) & (np.minimum(E, G) > 1e-14 * np.maximum(E, G))
        dg = np.where(regular, dg, 1.0)
        au = np.where(regular, (G * gu[idx] - F * gv[idx]) / dg, gu[idx])
        av = np.where(regular, (-F * gu[idx] + E * gv[idx]) / dg, gv[idx])
        alen = np.linalg.norm(Su * au[:, None] + Sv * av[:, None], axis=1)
        k = radius[idx] / np.maximum(alen, 1e-300)
        du = np.where(newton, du, au * k)
        dv = np.where(newton, dv, av * k)
        step = np.linalg.norm(Su * du[:, None] + Sv * dv[:, None], axis=1)
        shrink = np.minimum(1.0, radius[idx] / np.maximum(step, 1e-300))
        nu, nv = _clamp_uv(fs, fid[idx], u[idx] + du * shrink, v[idx] + dv * shrink)
        Dn = _surface_eval(fs, fid[idx], nu, nv, 2)
        gn, gun, gvn, Hn = _g_and_derivs(prof, c[idx], *Dn)
        ok = np.isfinite(gn) & (gn >= g[idx] - 1e-13 * (1 + np.abs(g[idx])))
        acc = idx[ok]
        u[acc], v[acc], g[acc], gu[acc], gv[acc] = nu[ok], nv[ok], gn[ok], gun[ok], gvn[ok]
        for k in range(6):
            D[k][acc] = Dn[k][ok]
        for k in range(3):
            H[k][acc] = Hn[k][ok]
        moved = step * shrink
        radius[idx] = np.where(ok, np.maximum(radius[idx], 2 * moved), 0.25 * radius[idx])
        done = (ok & (moved < 1e-11)) | (~ok & (radius[idx] < 1e-12))
        active[idx[done]] = False
    return u, v, g, D[0]


def _rim_newton(fs, prof, c, fid, u, v, iters: int = 30):
    """Stationary points of ``S_z`` on the circle ``|S_xy - c| = R`` (Newton on the Lagrange system)."""
    with np.errstate(all="ignore"):
        return _rim_newton_raw(fs, prof, c, fid, u, v, iters)


def _rim_newton_raw(fs, prof, c, fid, u, v, iters):
    R = prof.R
    u, v = u.copy(), v.copy()
    lam = np.zeros(u.shape)
    fresh = True
    active = np.ones(u.shape, bool)
    for _ in range(iters):
        a_ = np.nonzero(active)[0]
        if a_.size == 0:
            break
        P, Su, Sv, Suu, Suv, Svv = _surface_eval(fs, fid[a_], u[a_], v[a_], 2)
        d = P[:, :2] - c[a_]
        phi = (np.einsum("ij,ij->i", d, d) - R * R) / (2 * R)
        pu = np.einsum("ij,ij->i", d, Su[:, :2]) / R
        pv = np.einsum("ij,ij->i", d, Sv[:, :2]) / R
        if fresh:
            lam = (Su[:, 2] * pu + Sv[:, 2] * pv) / (pu * pu + pv * pv + 1e-300)
            fresh = False
        la = lam[a_]
        Luu = Suu[:, 2] - la * (np.einsum("ij,ij->i", Su[:, :2], Su[:, :2]) + np.einsum("ij,ij->i", d, Suu[:, :2])) / R
        Luv = Suv[:, 2] - la * (np.einsum("ij,ij->i", Su[:, :2], Sv[:, :2]) + np.einsum("ij,ij->i", d, Suv[:, :2])) / R
        Lvv = Svv[:, 2] - la * (np.einsum("ij,ij->i", Sv[:, :2], Sv[:, :2]) + np.einsum("ij,ij->i", d, Svv[:, :2])) / R
        K = np.zeros((a_.size, 3, 3))
        K[:, 0, 0], K[:, 0, 1], K[:, 1, 0], K[:, 1, 1] = Luu, Luv, Luv, Lvv
        K[:, 0, 2] = K[:, 2, 0] = -pu
        K[:, 1, 2] = K[:, 2, 1] = -pv
        rhs = np.stack([-(Su[:, 2] - la * pu), -(Sv[:, 2] - la * pv), phi], axis=1)
        bad = ~np.all(np.isfinite(K.reshape(-1, 9)), axis=1) | ~np.all(np.isfinite(rhs), axis=1)
        K[bad] = np.eye(3)
        rhs[bad] = 0.0
        bad = np.abs(np.linalg.det(K)) < 1e-300
        K[bad] = np.eye(3)
        rhs[bad] = 0.0
        x = np.linalg.solve(K, rhs[:, :, None])[:, :, 0]
        step = np.linalg.norm(Su * x[:, :1] + Sv * x[:, 1:2], axis=1)
        shrink = np.minimum(1.0, 0.5 * fs.spacing / np.maximum(step, 1e-300))
        u[a_], v[a_] = _clamp_uv(fs, fid[a_], u[a_] + x[:, 0] * shrink, v[a_] + x[:, 1] * shrink)
        lam[a_] = la + x[:, 2] * shrink
        active[a_[(step * shrink < 1e-11) | ~np.isfinite(step)]] = False
    P = _surface_eval(fs, fid, u, v, 0)[0]
    d = P[:, :2] - c
    rho = np.hypot(d[:, 0], d[:, 1])
    ok = np.isfinite(rho) & (np.abs(rho - R) <= 1e-9 * max(R, 1.0))
    return u, v, np.where(ok, P[:, 2] - prof.h_R, -np.inf), P


def _edge_points(fs, eid, t):
    """Surface points of edge parameters ``t`` (each on its own edge ``eid``)."""
    uv = np.empty((t.size, 2))
    for e in np.unique(eid):
        sel = np.nonzero(eid == e)[0]
        uv[sel] = fs.edges[e].evaluate(t[sel])
    fid = fs.edge_face[eid]
    return _surface_eval(fs, fid, uv[:, 0], uv[:, 1], 0)[0]


def _edge_search(fs, prof, c, eid, t0, dt, iters: int = 30):
    """Maximise ``g`` along an edge near ``t0`` (golden section on ``[t0 - 2 dt, t0 + 2 dt]`` within the
    edge) with the part outside the tool's disc penalised steeply; a maximum found just outside the
    circle is moved onto it (Newton on ``rho(t) = R``). Returns the value (``-inf`` if no feasible point
    was reached) and the point."""
    lo_b = np.array([e.bounds[0] for e in fs.edges])[eid]
    hi_b = np.array([e.bounds[1] for e in fs.edges])[eid]
    a, b = np.maximum(t0 - 2 * dt, lo_b), np.minimum(t0 + 2 * dt, hi_b)
    R = prof.R

    def f(t):
        P = _edge_points(fs, eid, t)
        rho = np.hypot(*(P[:, :2] - c).T)
        return P[:, 2] - prof(np.minimum(rho, R))[0] - 1e6 * np.maximum(rho - R, 0.0), rho, P

    gr = (math.sqrt(5) - 1) / 2
    x1, x2 = b - gr * (b - a), a + gr * (b - a)
    f1, f2 = f(x1)[0], f(x2)[0]
    for _ in range(iters):
        left = f1 >= f2
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
        x2n = np.where(left, x1, a + gr * (b - a))
        x1n = np.where(left, b - gr * (b - a), x2)
        fn = f(np.where(left, x1n, x2n))[0]
        f1, f2 = np.where(left, fn, f2), np.where(left, f1, fn)
        x1, x2 = x1n, x2n
    t = np.clip(0.5 * (a + b), lo_b, hi_b)
    for _ in range(4):  # onto the circle where the maximum sits just outside it
        _, rho, _ = f(t)
        out = rho > R
        if not out.any():
            break
        e = 1e-7 * np.maximum(dt, 1e-12)
        rp = f(np.clip(t + e, lo_b, hi_b))[1]
        rm = f(np.clip(t - e, lo_b, hi_b))[1]
        slope = (rp - rm) / (np.clip(t + e, lo_b, hi_b) - np.clip(t - e, lo_b, hi_b))
        step = np.where(out & (np.abs(slope) > 0), (rho - R) * (1 + 1e-9) / np.where(slope == 0, 1, slope), 0.0)
        t = np.clip(t - step, lo_b, hi_b)
    g, rho, P = f(t)
    return np.where(rho <= R * (1 + 1e-12), g, -np.inf), P


def _tip_solve(fs, c, fid, u, v, iters: int = 30):
    """The face point straight below the axis: Newton on ``S_xy(u, v) = c``."""
    for _ in range(iters):
        P, Su, Sv = _surface_eval(fs, fid, u, v, 1)
        r = P[:, :2] - c
        a, b, cc, d = Su[:, 0], Sv[:, 0], Su[:, 1], Sv[:, 1]
        det = a * d - b * cc
        det = np.where(np.abs(det) < 1e-300, 1e-300, det)
        du = -(d * r[:, 0] - b * r[:, 1]) / det
        dv = -(-cc * r[:, 0] + a * r[:, 1]) / det
        u, v = _clamp_uv(fs, fid, u + du, v + dv)
    P = _surface_eval(fs, fid, u, v, 0)[0]
    ok = np.hypot(*(P[:, :2] - c).T) < 1e-9
    return u, v, ok, P


# ----------------------------------------------------------------------------- the query
def _seeds(fs: FaceSet, prof: _Profile, C: np.ndarray):
    """Pairs (query, sample) within the tool's disc (plus a margin), the best feasible sample per query,
    and per (query, face or edge, sector) the best sample as a seed."""
    n_int = fs.sample_xyz.shape[0]
    margin = fs.spacing
    qtree = cKDTree(C)
    sdm = qtree.sparse_distance_matrix(fs.tree, prof.R + margin, output_type="ndarray")
    qi = sdm["i"].astype(np.int64)
    sj = sdm["j"].astype(np.int64)
    rho = sdm["v"]
    xyz = np.where((sj < n_int)[:, None], fs.sample_xyz[np.minimum(sj, n_int - 1)], fs.edge_xyz[np.maximum(sj - n_int, 0)])
    h = prof(np.minimum(rho, prof.R))[0]
    val = xyz[:, 2] - h
    feasible = rho <= prof.R
    d = xyz[:, :2] - C[qi]
    sector = np.where(rho < 0.5 * prof.R, 0, 1 + ((np.arctan2(d[:, 1], d[:, 0]) + math.pi) // (math.pi / 2)).astype(int).clip(0, 3))
    is_edge = sj >= n_int
    group = np.where(is_edge, len(fs.faces) + fs.edge_id[np.maximum(sj - n_int, 0)], fs.sample_face[np.minimum(sj, n_int - 1)])
    return qi, sj, rho, xyz, val, feasible, sector, is_edge, group


def _best_per(key, val):
    """Index of the largest ``val`` per distinct ``key`` (first of each group after a sort)."""
    if key.size == 0:
        return np.zeros(0, int)
    order = np.lexsort((-val, key))
    k = key[order]
    first = np.ones(k.size, bool)
    first[1:] = k[1:] != k[:-1]
    return order[first]


class _Candidates:
    """Contact candidates of a chunk: query, value (tip height), kind, face, point."""

    def __init__(self):
        self.parts: list = []

    def add(self, q, g, kind, fid, P, ok=None):
        if ok is None:
            ok = np.isfinite(g)
        self.parts.append((q[ok], g[ok], np.full(int(ok.sum()), kind), fid[ok], P[ok]))

    def best(self, m: int):
        q, v, k, f, p = (np.concatenate([pt[i] for pt in self.parts]) for i in range(5))
        win = _best_per(q, v)
        height = np.full(m, np.nan)
        kind = np.zeros(m, np.int8)
        face = np.full(m, -1)
        point = np.full((m, 3), np.nan)
        height[q[win]], kind[q[win]], face[q[win]], point[q[win]] = v[win], k[win], f[win], p[win]
        return height, kind, face, point


def _solve_seeds(fs, prof, C, cand: _Candidates, q, sj, rho0, is_edge):
    """Local solves from seed samples: face and rim solves from face samples, and from edge samples of
    a face with no face sample among the seeds of that query (a sliver between its last grid row and
    its boundary); edge searches from edge samples."""
    n_int = fs.sample_xyz.shape[0]
    ke = np.where(is_edge, sj - n_int, 0)
    ks = np.where(is_edge, 0, sj)
    fid = np.where(is_edge, fs.edge_face[fs.edge_id[ke]], fs.sample_face[ks])
    u0 = np.where(is_edge, fs.edge_uv[ke, 0], fs.sample_uv[ks, 0])
    v0 = np.where(is_edge, fs.edge_uv[ke, 1], fs.sample_uv[ks, 1])
    inside_face = ~is_edge & (rho0 <= prof.R)
    has_face_seed = np.isin(q * len(fs.faces) + fid, (q * len(fs.faces) + fid)[inside_face])
    solve = ~is_edge | ~has_face_seed
    e = np.nonzero(is_edge)[0]
    if e.size:
        k = ke[e]
        eid = fs.edge_id[k]
        g, P = _edge_search(fs, prof, C[q[e]], eid, fs.edge_t[k], fs.edge_dt[k])
        cand.add(q[e], g, Contact.EDGE, fs.edge_face[eid], P)
    q, fid, u0, v0, rho0 = q[solve], fid[solve], u0[solve], v0[solve], rho0[solve]
    if q.size == 0:
        return
    c = C[q]
    u, v, g, P = _face_newton(fs, prof, c, fid, u0, v0)
    cand.add(q, g, Contact.FACE, fid, P, np.isfinite(g) & _inside(fs, fid, u, v))
    near_rim = np.nonzero(rho0 > min(0.5 * prof.R, prof.R - 2 * fs.spacing))[0]
    if near_rim.size:
        r_ = near_rim
        u, v, g, P = _rim_newton(fs, prof, c[r_], fid[r_], u0[r_], v0[r_])
        cand.add(q[r_], g, Contact.RIM, fid[r_], P, np.isfinite(g) & _inside(fs, fid[r_], u, v))
    if prof.pointed:
        u, v, ok, P = _tip_solve(fs, c, fid, u0.copy(), v0.copy())
        g = P[:, 2] - prof(np.zeros(P.shape[0]))[0]
        cand.add(q, g, Contact.TIP, fid, P, ok & _inside(fs, fid, u, v))

def _drop_chunk(fs: FaceSet, prof: _Profile, C: np.ndarray):
    """Branch and bound over seed groups: the best sample is a lower bound of the tip height; each
    sample bounds from above what its neighbourhood can reach (``z + rise - h(rho - cover)``); the best
    group is solved first, then every group whose bound still beats the best solved contact."""
    m = C.shape[0]
    qi, sj, rho, xyz, val, feasible, sector, is_edge, group = _seeds(fs, prof, C)
    n_int = fs.sample_xyz.shape[0]
    cand = _Candidates()
    fe = np.nonzero(feasible)[0]
    best = fe[_best_per(qi[fe], val[fe])]
    face_of = np.where(is_edge, fs.edge_face[fs.edge_id[np.maximum(sj - n_int, 0)]], fs.sample_face[np.minimum(sj, n_int - 1)])
    cand.add(qi[best], val[best], Contact.SAMPLE, face_of[best], xyz[best])
    if best.size == 0:
        return cand.best(m)
    low = np.full(m, -np.inf)
    low[qi[best]] = val[best]
    cover = fs.cover[sj]
    reach = rho - cover
    ub = np.where(reach <= prof.R, xyz[:, 2] + fs.rise[sj] - prof.floor(reach), -np.inf)
    n_groups = len(fs.faces) + len(fs.edges)
    key = (qi * n_groups + group) * 5 + sector
    seed = _best_per(key, val)
    # phase 1: the group of each query's best sample value
    first = seed[_best_per(qi[seed], val[seed])]
    _solve_seeds(fs, prof, C, cand, qi[first], sj[first], rho[first], is_edge[first])
    h1, k1, f1, p1 = cand.best(m)
    solved = (k1 == Contact.FACE) | (k1 == Contact.RIM)
    # phase 2: samples whose bound still beats the contact found, except on the contact's own face
    # within two cover radii of it (the contact's own neighbourhood), seed their groups' best samples
    pq = p1[qi]
    near = solved[qi] & ~is_edge & (face_of == f1[qi]) & (np.linalg.norm(xyz - pq, axis=1) <= 2 * cover)
    open_ = (ub >= np.nan_to_num(h1[qi], nan=-np.inf) - 1e-9) & ~near
    if open_.any():
        o = np.nonzero(open_)[0]
        rest = o[_best_per(key[o], val[o])]
        _solve_seeds(fs, prof, C, cand, qi[rest], sj[rest], rho[rest], is_edge[rest])
    return cand.best(m)


def default_seed_spacing(cutter) -> float:
    """Seed sample spacing (mm): a third of the tool radius, within [0.2, 2] mm."""
    return float(np.clip(cutter.radius / 3, 0.2, 2.0))


def drop_cutter(
    faces,
    cutter,
    xy,
    *,
    axis=(0.0, 0.0, 1.0),
    seed_spacing_mm: float | None = None,
    face_set_: FaceSet | None = None,
    chunk: int = 2048,
    progress: Progress | None = None,
) -> DropCutterResult:
    """Exact drop-cutter heights of ``cutter`` on ``faces`` at the points ``xy`` (module docstring).

    Parameters
    ----------
    faces : sequence of Face or BSplineSurface
        The faces the tool must not cut into (trimmed regions respected).
    cutter : Cutter
        Any profile cutter (ball, flat, bull, cone, drum, APT).
    xy : array_like (n, 2)
        Query points in the tool frame (for ``axis = +z``: world x, y), mm.
    axis : 3-vector
        Fixed tool axis (3+2 machining); queries and heights are in its frame
        (:func:`~machsurf_cad.threeaxis.faceset.axis_frame`).
    seed_spacing_mm : float, optional
        Seed sample spacing on faces and edges (default :func:`default_seed_spacing`). Contacts are
        solved on the exact surfaces; a smaller spacing only seeds more local solves.
    face_set_ : FaceSet, optional
        A prepared face set (reused across calls with the same faces, axis and spacing).
    chunk : int
        Queries per vectorised batch (bounds memory).
    progress : Progress, optional
        ``progress(done, total, message)`` over the queries.

    Returns
    -------
    DropCutterResult

    Examples
    --------
    >>> from machsurf_cad import BallEndMill, builders, drop_cutter
    >>> plane = builders.plane_patch((-20, -20, 0), (40, 0, 0), (0, 40, 0))
    >>> r = drop_cutter([plane], BallEndMill(10), [[0.0, 0.0]])
    >>> round(float(r.height[0]), 9)
    0.0
    """
    t0 = time.perf_counter()
    xy = np.asarray(xy, float)
    if xy.ndim != 2 or xy.shape[1] != 2 or not np.all(np.isfinite(xy)):
        raise InputError("drop-cutter query points must be a finite (n, 2) array of x, y in mm")
    spacing = default_seed_spacing(cutter) if seed_spacing_mm is None else float(seed_spacing_mm)
    fs = face_set_ if face_set_ is not None else face_set(faces, axis=axis, spacing=spacing)
    t1 = time.perf_counter()
    prof = _Profile(cutter)
    n = xy.shape[0]
    height = np.full(n, np.nan)
    kind = np.zeros(n, np.int8)
    face = np.full(n, -1)
    point = np.full((n, 3), np.nan)
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        height[s:e], kind[s:e], face[s:e], point[s:e] = _drop_chunk(fs, prof, xy[s:e])
        if progress is not None:
            progress(e, n, "drop-cutter")
    t2 = time.perf_counter()
    tip_f = np.column_stack([xy, height])
    return DropCutterResult(
        xy,
        height,
        fs.to_world(tip_f),
        fs.to_world(point),
        face,
        kind,
        fs.frame[2].copy(),
        fs.frame.copy(),
        cutter.spec(),
        {"prepare_s": t1 - t0, "drop_s": t2 - t1},
    )
