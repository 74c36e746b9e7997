"""Local solves of the exact drop-cutter on the NURBS faces: the cutter's lower surface ``h(rho)``, the
face-interior ascent, the ascent along the rim and along circles where the profile's slope jumps, the
search along trimming edges and the point below a pointed tip (see :mod:`.dropcutter`)."""

from __future__ import annotations

import math

import numpy as np

from ..cutter_profiles import ArcSegment, _angle_in, _segment_z_at, lower_height
from .faceset import FaceSet


# ----------------------------------------------------------------------------- evaluation helpers
def _surface_eval(fs: FaceSet, fid, u, v, order: int):
    """Point and derivatives of each point's face: arrays (m, 3) for P, Su, Sv (and Suu, Suv, Svv)."""
    return fs.atlas.derivatives(fid, u, v, order)


def _clamp_uv(fs: FaceSet, fid, u, v):
    """Parameters kept in each face's box: wrapped across a seam where the face closes on itself,
    clamped elsewhere."""
    b = fs.bounds[fid]
    cl = fs.closed[fid]
    pu = b[:, 1] - b[:, 0]
    pv = b[:, 3] - b[:, 2]
    u = np.where(cl[:, 0], b[:, 0] + np.mod(u - b[:, 0], np.where(cl[:, 0], pu, 1.0)), np.clip(u, b[:, 0], b[:, 1]))
    v = np.where(cl[:, 1], b[:, 2] + np.mod(v - b[:, 2], np.where(cl[:, 1], pv, 1.0)), np.clip(v, b[:, 2], b[:, 3]))
    return u, v


def _inside(fs: FaceSet, fid, u, v) -> np.ndarray:
    ok = np.zeros(u.shape[0], bool)
    for f in np.unique(fid):
        sel = np.nonzero(fid == f)[0]
        face = fs.faces[f]
        u0, u1, v0, v1 = face.uv_bounds
        tol = 1e-12 * max(u1 - u0, v1 - v0, 1.0)
        ok[sel] = face.contains_uv(u[sel], v[sel]) if face.is_trimmed else (
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
        slopes = lower_height(self.segs, np.linspace(0.0, self.R, 2049))[1]
        # sine of the steepest profile slope inside the rim: the face is tangent to the profile
        # there only where it is at most this steep (0 for a flat end mill: flat spots only)
        self.max_tilt = float(np.sin(np.arctan(np.abs(slopes).max())))
        self.monotone = bool(np.all(np.diff(table) >= -1e-12))
        # radii inside the rim where the slope of h jumps: (radius, h) of each such circle
        self.kinks = []
        ends = sorted({round(float(x), 12) for seg in self.segs for x in seg.points(2)[:, 0]})
        for rk in ends:
            if 1e-9 < rk < self.R * (1 - 1e-9):
                _, sl, _ = lower_height(self.segs, np.array([rk - 1e-7, rk + 1e-7]))
                if abs(sl[1] - sl[0]) > 1e-6:
                    self.kinks.append((rk, float(self(np.array([rk]))[0][0])))
        self.h_min = float(table.min())

    def radius_of_slope(self, slope) -> np.ndarray:
        """Radius where the lower profile's slope ``h'`` first reaches ``slope`` (a tangent: the tool touches a
        surface of that slope there); the rim where it never does."""
        if not hasattr(self, "_slope_table"):
            rho = np.linspace(0.0, self.R, 4097)
            h1 = lower_height(self.segs, rho)[1]
            h1 = np.maximum.accumulate(np.where(np.isfinite(h1), h1, np.inf))
            self._slope_table = (h1, rho)
        h1, rho = self._slope_table
        s = np.asarray(slope, float)
        i = np.clip(np.searchsorted(h1, s, side="left"), 1, rho.size - 1)
        lo, hi = h1[i - 1], h1[i]
        w = np.where(np.isfinite(hi) & (hi > lo), (s - lo) / np.where(hi > lo, hi - lo, 1.0), 1.0)
        return np.where(s <= h1[0], 0.0, rho[i - 1] + np.clip(w, 0.0, 1.0) * (rho[i] - rho[i - 1]))

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

    def height(self, rho) -> np.ndarray:
        """``h`` alone, the first of :meth:`__call__`'s results, to the bit: on each piece of ``[0, R]`` where one
        segment (one branch of an arc) is the lowest its formula, without ``lower_height``'s search over the
        segments and its arcs' angles (within a margin of a piece's inner ends, and for a profile
        whose pieces do not match ``lower_height`` everywhere, ``lower_height`` itself). The scallop planner's
        swept surfaces evaluate it millions of times, on a few hundred radii a call."""
        rho = np.asarray(rho, float)
        x = np.abs(np.minimum(rho, self.R))
        tb = self._pieces()
        margin = self._piece_margin
        h = np.full(x.shape, np.nan)
        for lo, hi, kind, a, b, c, d in tb:
            on = (x > lo + margin) & (x < hi - margin)
            h[on] = _piece_h(kind, a, b, c, d, x[on])
        rest = np.isnan(h)
        if rest.any():
            xr = x[rest]
            hr = np.where(xr == self.R, self._h_ends[1], np.where(xr == 0.0, self._h_ends[0], np.nan))
            left = np.isnan(hr)
            if left.any():
                hr[left] = lower_height(self.segs, xr[left])[0]
            h[rest] = hr
        return np.where(rho <= self.R * (1 + 1e-12), np.where(np.isfinite(h), h, self.h_R), np.inf)

    def _pieces(self) -> np.ndarray:
        """Rows ``lo, hi, kind (0 line, 1 arc branch, -1 none), a, b, c, d`` (a line's ``rho0, z0, rho1, z1``; an
        arc's ``rho_c, z_c, radius**2, branch``): the pieces between the segments' ends and their arcs'
        extremes, each with its lowest segment, checked against ``lower_height`` on 64 points of every piece
        and at its margin's edges (to the bit); none where a piece does not match (segments crossing inside
        it). The margin is ``PIECE_MARGIN_MM``, or 1e-10 of the largest arc's radius (``lower_height`` lets an
        arc run 1e-9 degrees past its ends: 1.7e-11 of its radius)."""
        table: np.ndarray | None = getattr(self, "_piece_table", None)
        if table is not None:
            return table
        ends = [0.0, self.R]
        radii = [0.0]
        for seg in self.segs:
            if isinstance(seg, ArcSegment):
                c, r = seg.rho_c, seg.radius
                ends += [c - r, c + r] + [c + r * math.cos(math.radians(a)) for a in (seg.start_deg, seg.end_deg)]
                radii.append(abs(r))
            else:
                ends += [seg.rho0, seg.rho1]
        margin = max(PIECE_MARGIN_MM, 1e-10 * max(radii))
        cuts = np.unique(np.clip(np.array(ends, float), 0.0, self.R))
        rows = []
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            if hi - lo > 4 * margin:
                rows.append((lo, hi, *_lowest_piece(self.segs, 0.5 * (lo + hi))))
        tb = np.array(rows, float).reshape(-1, 7)
        for lo, hi, kind, a, b, c, d in tb:
            inner = np.nextafter([lo + margin, hi - margin], [hi, lo])  # the first and last radii a piece takes
            x = np.r_[inner, np.linspace(lo + 2 * margin, hi - 2 * margin, 64)]
            if not np.array_equal(_piece_h(kind, a, b, c, d, x), lower_height(self.segs, x)[0]):
                tb = np.zeros((0, 7))
                break
        self._h_ends = lower_height(self.segs, np.array([0.0, self.R]))[0]
        self._piece_margin = margin
        self._piece_table = tb
        return tb


PIECE_MARGIN_MM = 1e-9
"""Within this distance of a profile piece's ends (at least; :meth:`_Profile._pieces`) :meth:`_Profile.height`
runs ``lower_height`` itself."""


def _piece_h(kind, a, b, c, d, x):
    """``h`` at ``x`` on a profile piece (:meth:`_Profile._pieces`): ``lower_height``'s formulas."""
    if kind == 0.0:
        return b + (x - a) / (c - a) * (d - b)
    if kind == 1.0:  # c: the radius squared as lower_height squares it
        return b + d * np.sqrt(np.clip(c - (x - a) * (x - a), 0, None))
    return np.full(np.shape(x), np.inf)


def _lowest_piece(segs, x: float) -> tuple:
    """The segment (an arc's branch) lowest at ``x`` as a piece's ``kind, a, b, c, d`` (``lower_height``'s
    order: the first of equal heights); ``-1`` where none reaches ``x``."""
    best, out = math.inf, (-1.0, 0.0, 0.0, 0.0, 0.0)
    for seg in segs:
        if isinstance(seg, ArcSegment):
            dx = x - seg.rho_c
            root = math.sqrt(max(seg.radius**2 - dx * dx, 0.0))
            for sgn in (-1.0, 1.0):
                z = seg.z_c + sgn * root
                ang = np.array([math.degrees(math.atan2(z - seg.z_c, dx))])
                if abs(dx) <= seg.radius + 1e-12 and _angle_in(ang, seg.start_deg, seg.end_deg)[0] and z < best:
                    best, out = z, (1.0, seg.rho_c, seg.z_c, seg.radius**2, sgn)
        elif abs(seg.rho1 - seg.rho0) >= 1e-15:
            z = float(_segment_z_at(seg, np.array([x]), lowest=True)[0])
            if z < best:
                best, out = z, (0.0, seg.rho0, seg.z0, seg.rho1, seg.z1)
    return out


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
def _up_curvature(Huu, Huv, Hvv, Su, Sv, radius):
    """Unit-length (``radius`` mm on the surface) parameter step along the eigenvector of the largest
    eigenvalue of the (u, v) Hessian, and the second-order gain ``e^T H e / 2`` along it (mm)."""
    tr = Huu + Hvv
    disc = np.sqrt(np.maximum(0.25 * (Huu - Hvv) ** 2 + Huv * Huv, 0.0))
    lam = 0.5 * tr + disc
    eu = np.where(np.abs(Huv) > 1e-300, Huv, np.where(Huu >= Hvv, 1.0, 0.0))
    ev = np.where(np.abs(Huv) > 1e-300, lam - Huu, np.where(Huu >= Hvv, 0.0, 1.0))
    ln = np.linalg.norm(Su * eu[:, None] + Sv * ev[:, None], axis=1)
    k = radius / np.maximum(ln, 1e-300)
    eu, ev = eu * k, ev * k
    quad = 0.5 * (Huu * eu * eu + 2 * Huv * eu * ev + Hvv * ev * ev)
    return eu, ev, np.where(np.isfinite(quad), quad, 0.0)


def _off_poles(fs, prof, c, fid, u, v, n: int = 16):
    """Starts at a pole (a box side collapsed to a point, where one tangent vanishes) moved just off it,
    at the best of ``n`` directions around it: at the pole the parameter of the collapsed side says
    nothing about the direction, and ascent may need to cross the pole."""
    _, Su, Sv = _surface_eval(fs, fid, u, v, 1)
    E = np.einsum("ij,ij->i", Su, Su)
    G = np.einsum("ij,ij->i", Sv, Sv)
    pole = np.nonzero(np.minimum(E, G) <= 1e-14 * np.maximum(E, G))[0]
    if pole.size == 0:
        return u, v
    b = fs.bounds[fid[pole]]
    along_v = G[pole] <= E[pole]  # Sv vanishes: the side u = const is the pole, v runs around it
    mid_u = 0.5 * (b[:, 0] + b[:, 1])
    mid_v = 0.5 * (b[:, 2] + b[:, 3])
    off_u = u[pole] + 1e-4 * (b[:, 1] - b[:, 0]) * np.sign(mid_u - u[pole])
    off_v = v[pole] + 1e-4 * (b[:, 3] - b[:, 2]) * np.sign(mid_v - v[pole])
    k = (np.arange(n) + 0.5) / n
    cu = np.where(along_v[:, None], off_u[:, None], b[:, 0:1] + k * (b[:, 1:2] - b[:, 0:1]))
    cv = np.where(along_v[:, None], b[:, 2:3] + k * (b[:, 3:4] - b[:, 2:3]), off_v[:, None])
    f = np.repeat(fid[pole], n)
    P = _surface_eval(fs, f, cu.ravel(), cv.ravel(), 0)[0]
    rho = np.hypot(*(P[:, :2] - np.repeat(c[pole], n, axis=0)).T)
    g = (P[:, 2] - prof(rho)[0]).reshape(-1, n)
    g = np.where(np.isfinite(g), g, -np.inf)
    j = np.argmax(g, axis=1)
    r = np.arange(pole.size)
    u[pole], v[pole] = cu[r, j], cv[r, j]
    return u, v


def _put(dst, at, src, sel) -> None:
    """``d[at] = s[sel]`` for each pair of arrays (a solver's state taken from its trial)."""
    for d, s in zip(dst, src):
        d[at] = s[sel]


def _ascent_step(Su, Sv, gu, gv, Huu, Huv, Hvv, radius, at_u, at_v):
    """The face ascent's step: Newton where ``-H`` is positive definite, else steepest ascent on the surface
    (first fundamental form) as long as the trust radius, or along the largest upward curvature where that
    gains more (at a minimum or saddle of g, a fillet's foot or a valley, the gradient step crawls); with
    ``u`` (``at_u``) or ``v`` (``at_v``) held, along the other parameter only. Returns ``du, dv, newton,
    escape`` (an escape is tried to both sides)."""
    held = at_u | at_v
    gu, gv = np.where(at_u, 0.0, gu), np.where(at_v, 0.0, gv)
    Huu, Huv, Hvv = (np.where(at_u, -(1.0 + np.abs(Hvv)), Huu), np.where(held, 0.0, Huv),
                     np.where(at_v, -(1.0 + np.abs(Huu)), Hvv))  # fmt: skip
    a, b, d_ = -Huu, -Huv, -Hvv  # M = -H: Newton where it is positive definite
    det = a * d_ - b * b
    newton = (a > 0) & (det > 1e-14 * (a * a + d_ * d_ + b * b))
    det = np.where(newton, det, 1.0)
    du = np.where(newton, (d_ * gu - b * gv) / det, 0.0)
    dv = np.where(newton, (-b * gu + a * gv) / det, 0.0)
    E = np.einsum("ij,ij->i", Su, Su)
    F = np.where(held, 0.0, np.einsum("ij,ij->i", Su, Sv))
    G = np.einsum("ij,ij->i", Sv, Sv)
    dg = E * G - F * F
    # near a pole or a collapsed edge (one tangent vanishing): the parameter gradient instead
    regular = (dg > 1e-10 * E * G) & (np.minimum(E, G) > 1e-14 * np.maximum(E, G))
    dg = np.where(regular, dg, 1.0)
    au = np.where(regular, (G * gu - F * gv) / dg, gu)
    av = np.where(regular, (-F * gu + E * gv) / dg, gv)
    alen = np.linalg.norm(Su * au[:, None] + Sv * av[:, None], axis=1)
    k = radius / np.maximum(alen, 1e-300)
    du = np.where(newton, du, au * k)
    dv = np.where(newton, dv, av * k)
    eu, ev, quad = _up_curvature(Huu, Huv, Hvv, Su, Sv, radius)
    escape = ~newton & (quad > np.abs(gu * au + gv * av) * k)
    return np.where(escape, eu, du), np.where(escape, ev, dv), newton, escape


def _face_newton(fs, prof, c, fid, u, v, iters: int = 40):
    """Maximise ``g`` from ``(u, v)``: damped Newton (Hessian shifted to negative definite) with a trust
    region in mm; steps that do not increase ``g`` or leave the tool's disc are refused."""
    u, v = _off_poles(fs, prof, c, fid, u.copy(), v.copy())
    D = _surface_eval(fs, fid, u, v, 2)
    g, gu, gv, H = _g_and_derivs(prof, c, *D)
    radius = np.full(u.shape, 0.5 * fs.spacing)
    active = np.isfinite(g)
    for _ in range(iters):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        Su, Sv = D[1][idx], D[2][idx]
        Hi = (H[0][idx], H[1][idx], H[2][idx])
        no = np.zeros(idx.size, bool)
        du, dv, newton, escape = _ascent_step(Su, Sv, gu[idx], gv[idx], *Hi, radius[idx], no, no)
        # a step out of the face's box on one side runs along that side instead (projected): a clamped step
        # crawls along it; out on both sides at a corner, no step of any length moves
        b_, cl = fs.bounds[fid[idx]], fs.closed[fid[idx]]
        out_u = ~cl[:, 0] & (((u[idx] <= b_[:, 0]) & (du < 0)) | ((u[idx] >= b_[:, 1]) & (du > 0))) & ~escape
        out_v = ~cl[:, 1] & (((v[idx] <= b_[:, 2]) & (dv < 0)) | ((v[idx] >= b_[:, 3]) & (dv > 0))) & ~escape
        one = out_u ^ out_v
        if one.any():
            p_ = _ascent_step(Su, Sv, gu[idx], gv[idx], *Hi, radius[idx], out_u & one, out_v & one)
            du, dv, newton, escape = (np.where(one, a_, b) for a_, b in zip(p_, (du, dv, newton, escape)))
        corner = out_u & out_v
        if corner.any():
            active[idx[corner]] = False
            kept = (idx, du, dv, newton, escape, Su, Sv)
            idx, du, dv, newton, escape, Su, Sv = (x[~corner] for x in kept)
            if idx.size == 0:
                break
        step = np.linalg.norm(Su * du[:, None] + Sv * dv[:, None], axis=1)
        shrink = np.minimum(1.0, radius[idx] / np.maximum(step, 1e-300))
        nu, nv = _clamp_uv(fs, fid[idx], u[idx] + du * shrink, v[idx] + dv * shrink)
        Dn = _surface_eval(fs, fid[idx], nu, nv, 2)
        gn, gun, gvn, Hn = _g_and_derivs(prof, c[idx], *Dn)
        e_ = np.nonzero(escape)[0]
        if e_.size:  # the other side
            mu_, mv_ = _clamp_uv(fs, fid[idx[e_]], u[idx[e_]] - du[e_] * shrink[e_], v[idx[e_]] - dv[e_] * shrink[e_])
            Dm = _surface_eval(fs, fid[idx[e_]], mu_, mv_, 2)
            gm, gum, gvm, Hm = _g_and_derivs(prof, c[idx[e_]], *Dm)
            better = np.nan_to_num(gm, nan=-np.inf) > np.nan_to_num(gn[e_], nan=-np.inf)
            _put([nu, nv, gn, gun, gvn, *Dn, *Hn], e_[better], [mu_, mv_, gm, gum, gvm, *Dm, *Hm], better)
        moved = np.linalg.norm(Dn[0] - D[0][idx], axis=1)  # a step clamped at the box may not move
        rises = np.isfinite(gn) & (gn >= g[idx] - 1e-13 * (1 + np.abs(g[idx])))
        ok = rises & (moved > 0)
        _put([u, v, g, gu, gv, *D, *H], idx[ok], [nu, nv, gn, gun, gvn, *Dn, *Hn], ok)
        radius[idx] = np.where(ok, np.maximum(radius[idx], 2 * moved), 0.25 * radius[idx])
        done = (ok & (moved < 1e-11)) | (rises & newton & (moved == 0)) | (~ok & (radius[idx] < 1e-12))
        # a zero step (zero gradient, no upward curvature: a horizontal plane under a flat end) repeats itself
        done |= (du == 0) & (dv == 0)
        active[idx[done]] = False
    return u, v, g, D[0]


def _rim_newton(fs, prof, c, fid, u, v, iters: int = 40, radius: float | None = None, h_at: float | None = None):
    """The highest point of a face on the circle ``|S_xy - c| = R``, near ``(u, v)``: projected Newton
    ascent along the circle (steps along the constraint's tangent, Newton where the Lagrangian's second
    derivative along it is negative, else a trust-radius step uphill, each followed by a projection
    onto the circle; steps that do not rise are refused and the radius shrinks)."""
    R = prof.R if radius is None else float(radius)
    h_R = prof.h_R if h_at is None else float(h_at)
    with np.errstate(all="ignore"):
        return _rim_ascent(fs, R, h_R, c, fid, u, v, iters)


def _circle_step(fs, P, Su, Sv, c, R):
    """The minimum-norm Newton step onto ``rho = R`` from each point ``P`` (first derivatives ``Su, Sv``),
    shortened to the sample spacing on the face: ``du, dv`` and the points' distances ``rho`` from the axis."""
    d = P[:, :2] - c
    rho = np.hypot(d[:, 0], d[:, 1])
    ru = np.einsum("ij,ij->i", d, Su[:, :2]) / np.maximum(rho, 1e-300)
    rv = np.einsum("ij,ij->i", d, Sv[:, :2]) / np.maximum(rho, 1e-300)
    n2 = ru * ru + rv * rv
    t = np.where(n2 > 1e-300, (R - rho) / np.where(n2 > 1e-300, n2, 1.0), 0.0)
    t = np.where(np.abs(R - rho) <= _ON_CIRCLE_MM * max(R, 1.0), 0.0, t)  # on the circle: stays there
    step = np.linalg.norm(Su * (t * ru)[:, None] + Sv * (t * rv)[:, None], axis=1)
    shrink = np.minimum(1.0, fs.spacing / np.maximum(step, 1e-300))
    shrink = np.where(np.isfinite(shrink), shrink, 0.0)
    return t * ru * shrink, t * rv * shrink, rho


def _project_circle(fs, R, c, fid, u, v, n: int = 4):
    """Minimum-norm Newton steps onto ``rho = R``; returns (u, v)."""
    for _ in range(n):
        P, Su, Sv = _surface_eval(fs, fid, u, v, 1)[:3]
        du, dv, _ = _circle_step(fs, P, Su, Sv, c, R)
        u, v = _clamp_uv(fs, fid, u + du, v + dv)
    return u, v


def _into_disc(fs, R, c, fid, u, v, deeper: bool = False, iters: int = 16):
    """Starts moved onto a circle just inside the rim (``rho = R (1 - 1e-3)``: a ball's profile turns
    vertical at the rim, where Newton would crawl), and where the face does not reach that circle near
    the start, to its point nearest the axis (damped Gauss-Newton on ``|S_xy - c|^2``, halving steps
    that do not get closer): a face that only grazes the disc (a sliver under the rim, e.g. the
    vertical foot of a boss's round under a bull-nose's corner) has its feasible starts there. Starts
    that cannot get inside stay where the descent ends. ``deeper``: the descent also from the circle (a second
    start for the face's maximum: from the circle, Newton may end on a lower local maximum near the rim)."""
    target = R * (1 - 1e-3)
    stop = target * (1 - 1e-6) if deeper else target * (1 + 1e-9)  # whether on the circle: never rounding's call
    u, v = _project_circle(fs, target, c, fid, u, v, 6)
    active = np.ones(u.shape, bool)
    for _ in range(iters):
        a_ = np.nonzero(active)[0]
        if a_.size == 0:
            break
        P, Su, Sv = _surface_eval(fs, fid[a_], u[a_], v[a_], 1)
        d = P[:, :2] - c[a_]
        rho = np.hypot(d[:, 0], d[:, 1])
        active[a_[~(rho > stop)]] = False
        xu, xv = Su[:, :2], Sv[:, :2]
        a = np.einsum("ij,ij->i", xu, xu)
        b = np.einsum("ij,ij->i", xu, xv)
        e = np.einsum("ij,ij->i", xv, xv)
        gu = np.einsum("ij,ij->i", d, xu)
        gv = np.einsum("ij,ij->i", d, xv)
        lm = 1e-9 * (a + e) + 1e-300  # Levenberg damping: a tangent with no plan component
        det = (a + lm) * (e + lm) - b * b
        du = -((e + lm) * gu - b * gv) / det
        dv = -(-b * gu + (a + lm) * gv) / det
        step = np.linalg.norm(Su * du[:, None] + Sv * dv[:, None], axis=1)
        k = np.minimum(1.0, fs.spacing / np.maximum(step, 1e-300))
        k = np.where(np.isfinite(k), k, 0.0)
        moved = np.zeros(a_.size, bool)
        for _half in range(8):
            nu, nv = _clamp_uv(fs, fid[a_], u[a_] + du * k, v[a_] + dv * k)
            rn = np.hypot(*(_surface_eval(fs, fid[a_], nu, nv, 0)[0][:, :2] - c[a_]).T)
            ok = active[a_] & ~moved & np.isfinite(rn) & (rn < rho - 1e-12)
            u[a_[ok]], v[a_[ok]] = nu[ok], nv[ok]
            moved |= ok
            k = 0.5 * k
        active[a_[~moved]] = False
    return u, v


def _rim_terms(D, c, R):
    """At the points of ``D`` (second derivatives): their offsets ``rho - R``, the gradients ``pu, pv`` of
    ``rho`` (to first order in the offset), their square norms and the multipliers ``lam`` (the rise of z
    across the circle per mm of ``rho``)."""
    P, Su, Sv = D[0], D[1], D[2]
    d = P[:, :2] - c
    pu = np.einsum("ij,ij->i", d, Su[:, :2]) / R
    pv = np.einsum("ij,ij->i", d, Sv[:, :2]) / R
    n2 = pu * pu + pv * pv
    ok = n2 > 1e-300
    lam = np.where(ok, (Su[:, 2] * pu + Sv[:, 2] * pv) / np.where(ok, n2, 1.0), 0.0)
    return np.hypot(d[:, 0], d[:, 1]) - R, pu, pv, n2, lam


def _rim_ascent(fs, R, h_R, c, fid, u, v, iters):
    """The highest point of each row's face on ``rho = R`` near its start (see :func:`._jit_solve.rim_ascent`:
    Newton along the circle with its second-order correction across it, Newton steps onto it while the point
    is off by more than ``1e-9 R``, steps kept when the height the point would have on the circle does not
    fall, a row stopping on the circle where its next step would not move it)."""
    tol = 1e-9 * max(R, 1.0)
    snap = _ON_CIRCLE_MM * max(R, 1.0)
    u, v = _project_circle(fs, R, c, fid, u.copy(), v.copy(), 6)
    D = list(_surface_eval(fs, fid, u, v, 2))  # the kept points' second derivatives, per row
    off, pu, pv, n2, lam = _rim_terms(D, c, R)
    z = np.where(np.abs(off) <= tol, D[0][:, 2] - lam * off, -np.inf)
    radius = np.full(u.shape, 2.0 * fs.spacing)  # (as the kernel's: 2 sample spacings)
    active = np.ones(u.shape, bool)
    for _ in range(iters):
        a_ = np.nonzero(active)[0]
        if a_.size == 0:
            break
        Pa, Su, Sv, Suu, Suv, Svv = (X[a_] for X in D)
        d = Pa[:, :2] - c[a_]
        tu, tv = -pv[a_], pu[a_]  # tangent of the circle on the face
        zt = Su[:, 2] * tu + Sv[:, 2] * tv
        hz = Suu[:, 2] * tu * tu + 2 * Suv[:, 2] * tu * tv + Svv[:, 2] * tv * tv
        xt = Su[:, :2] * tu[:, None] + Sv[:, :2] * tv[:, None]
        xtt = Suu[:, :2] * (tu * tu)[:, None] + 2 * Suv[:, :2] * (tu * tv)[:, None] + Svv[:, :2] * (tv * tv)[:, None]
        hphi = (np.einsum("ij,ij->i", xt, xt) + np.einsum("ij,ij->i", d, xtt)) / R
        Ltt = hz - lam[a_] * hphi
        tlen = np.linalg.norm(Su * tu[:, None] + Sv * tv[:, None], axis=1)
        newton = Ltt < -1e-300
        s = np.where(newton, -zt / np.where(newton, Ltt, -1.0), np.sign(zt) * radius[a_] / np.maximum(tlen, 1e-300))
        step = np.abs(s) * tlen
        s = s * np.minimum(1.0, radius[a_] / np.maximum(step, 1e-300))
        s = np.where(np.isfinite(s), s, 0.0)
        top = np.isfinite(z[a_]) & newton & (np.abs(s) * tlen < 1e-12) & (np.abs(off[a_]) <= snap)
        active[a_[top]] = False  # the next step would not move the point
        go = ~top
        b_, s, tu, tv, Pa, hphi = a_[go], s[go], tu[go], tv[go], Pa[go], hphi[go]
        if b_.size == 0:
            break
        ok = n2[b_] > 1e-300
        cc = np.where(ok, (-off[b_] - 0.5 * s * s * hphi) / np.where(ok, n2[b_], 1.0), 0.0)  # onto the circle
        cc = np.where(np.isfinite(cc), cc, 0.0)
        nu, nv = _clamp_uv(fs, fid[b_], u[b_] + s * tu + cc * pu[b_], v[b_] + s * tv + cc * pv[b_])
        Dn = list(_surface_eval(fs, fid[b_], nu, nv, 2))
        for _p in range(3):  # Newton steps onto the circle while off it by more than tol
            rho = np.hypot(Dn[0][:, 0] - c[b_, 0], Dn[0][:, 1] - c[b_, 1])
            far = np.nonzero(np.abs(R - rho) > tol)[0]
            if far.size == 0:
                break
            du, dv, _ = _circle_step(fs, Dn[0][far], Dn[1][far], Dn[2][far], c[b_[far]], R)
            nu[far], nv[far] = _clamp_uv(fs, fid[b_[far]], nu[far] + du, nv[far] + dv)
            for X, Y in zip(Dn, _surface_eval(fs, fid[b_[far]], nu[far], nv[far], 2)):
                X[far] = Y
        off_n, pu_n, pv_n, n2_n, lam_n = _rim_terms(Dn, c[b_], R)
        zn = np.where(np.abs(off_n) <= tol, Dn[0][:, 2] - lam_n * off_n, -np.inf)
        acc = np.isfinite(zn) & (zn >= z[b_] - 1e-13 * (1 + np.abs(z[b_])))
        moved = np.linalg.norm(Dn[0] - Pa, axis=1)
        ia = b_[acc]
        u[ia], v[ia], z[ia] = nu[acc], nv[acc], zn[acc]
        off[ia], pu[ia], pv[ia], n2[ia], lam[ia] = off_n[acc], pu_n[acc], pv_n[acc], n2_n[acc], lam_n[acc]
        for X, Y in zip(D, Dn):
            X[ia] = Y[acc]
        radius[b_] = np.where(acc, np.maximum(radius[b_], 2 * moved), 0.25 * radius[b_])
        done = (acc & (moved < 1e-11)) | (~acc & (radius[b_] < 1e-12))
        active[b_[done]] = False
    P = D[0].copy()
    z = P[:, 2].copy()
    away = np.nonzero(np.abs(off) > snap)[0]  # stopped off the circle by more than ON_CIRCLE_MM: onto it
    if away.size:
        u[away], v[away] = _project_circle(fs, R, c[away], fid[away], u[away], v[away], 3)
        P[away] = _surface_eval(fs, fid[away], u[away], v[away], 0)[0]
        on = np.abs(np.hypot(*(P[away, :2] - c[away]).T) - R) <= tol
        z[away] = np.where(on, P[away, 2], -np.inf)
    return u, v, np.where(np.isfinite(z), z - h_R, -np.inf), P


def _edge_points(fs, eid, t):
    """Surface points of edge parameters ``t`` (each on its own edge ``eid``)."""
    return _edge_derivs(fs, eid, t, 0)[0]


def _edge_derivs(fs, eid, t, order: int):
    """Point of each edge parameter on its face, and its first (and second) derivatives in ``t``:
    ``P' = Su u' + Sv v'``, ``P'' = Suu u'^2 + 2 Suv u' v' + Svv v'^2 + Su u'' + Sv v''``."""
    m = t.size
    uv = np.empty((m, 3, 2))
    loop = fs.edge_loop
    for e in np.unique(eid):
        sel = np.nonzero(eid == e)[0]
        te = t[sel]
        if loop[e]:  # a closed edge: its parameter runs on across the seam
            lo, hi = fs.edges[e].bounds
            te = lo + np.mod(te - lo, hi - lo)
        uv[sel, : order + 1] = fs.edges[e].derivatives(te, order)
    fid = fs.edge_face[eid]
    if order == 0:
        return (_surface_eval(fs, fid, uv[:, 0, 0], uv[:, 0, 1], 0)[0],)
    d = _surface_eval(fs, fid, uv[:, 0, 0], uv[:, 0, 1], order)
    P, Su, Sv = d[0], d[1], d[2]
    du, dv = uv[:, 1, 0:1], uv[:, 1, 1:2]
    P1 = Su * du + Sv * dv
    if order == 1:
        return P, P1
    Suu, Suv, Svv = d[3], d[4], d[5]
    ddu, ddv = uv[:, 2, 0:1], uv[:, 2, 1:2]
    P2 = Suu * du * du + 2 * Suv * du * dv + Svv * dv * dv + Su * ddu + Sv * ddv
    return P, P1, P2


def _edge_g(prof, c, P, P1=None, P2=None):
    """``g = z - h(rho)`` along an edge and its first two derivatives in ``t`` (where ``rho > 0``)."""
    d = P[:, :2] - c
    rho = np.hypot(d[:, 0], d[:, 1])
    h, h1, h2 = prof(np.minimum(rho, prof.R))
    g = P[:, 2] - h
    if P1 is None:
        return g, rho
    safe = np.maximum(rho, 1e-300)
    r1 = np.einsum("ij,ij->i", d, P1[:, :2]) / safe
    g1 = P1[:, 2] - h1 * r1
    if P2 is None:
        return g, rho, g1, r1
    r2 = (np.einsum("ij,ij->i", P1[:, :2], P1[:, :2]) + np.einsum("ij,ij->i", d, P2[:, :2]) - r1 * r1) / safe
    g2 = P2[:, 2] - h2 * r1 * r1 - h1 * r2
    return g, rho, g1, r1, g2


_EDGE_SAMPLES = 17


def _newton_max(t, lo, hi, d1, d2):
    """One safeguarded Newton step per row towards a maximum of a function of ``t`` with derivatives ``d1``,
    ``d2``: the bracket ``[lo, hi]`` shrinks by the sign of ``d1``, Newton where the function is concave and
    the step stays inside, else bisection. Returns the new ``t``, the bracket and whether the step vanished."""
    lo = np.where(d1 > 0, t, lo)
    hi = np.where(d1 < 0, t, hi)
    newton = t - d1 / np.where(d2 < 0, d2, -np.inf)
    t_new = np.where((d2 < 0) & (newton > lo) & (newton < hi), newton, 0.5 * (lo + hi))
    t_new = np.where(d1 == 0, t, t_new)
    return t_new, lo, hi, np.abs(t_new - t) <= 1e-15 * np.maximum(np.abs(t), 1.0)


def _edge_search(fs, prof, c, eid, t0, dt, iters: int = 40):
    """Maximise ``g = z - h(rho)`` along an edge near ``t0`` within the tool's disc, on ``[t0 - 2 dt, t0 +
    2 dt]`` within the edge: the best of 17 samples brackets the maximum, then a safeguarded Newton on
    ``g'(t) = 0`` with exact derivatives (the bracket shrinks by the sign of ``g'``; a bisection step when
    Newton leaves it), and where the maximum sits on the tool's circle, Newton on ``rho(t) = R`` within
    the bracket. Returns the value (``-inf`` where no point of the interval is in the disc) and the point."""
    a, b = fs.on_edge(eid, t0 - 2 * dt), fs.on_edge(eid, t0 + 2 * dt)  # a closed edge's runs across its seam
    R = prof.R
    m = t0.size
    n = _EDGE_SAMPLES
    ts = a[:, None] + (b - a)[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    P = _edge_points(fs, np.repeat(eid, n), ts.ravel())
    g_s, rho = _edge_g(prof, np.repeat(c, n, axis=0), P)
    g_s = np.where(rho <= R, g_s, -np.inf).reshape(m, n)  # the samples' values, -inf outside the disc
    _graze(fs, prof, c, eid, ts, g_s, rho.reshape(m, n))
    # from each of the (at most) three highest local maxima of the samples (the first: the best sample): an
    # edge may rise to two maxima within the window, the higher one not the best sample's
    fin = np.isfinite(g_s)
    left = np.concatenate([np.full((m, 1), -np.inf), g_s[:, :-1]], axis=1)
    right = np.concatenate([g_s[:, 1:], np.full((m, 1), -np.inf)], axis=1)
    local = fin & ~(left > g_s) & ~(right > g_s)
    k = np.argmax(g_s, axis=1)
    score = np.where(local, g_s, -np.inf)
    g = np.full(m, -np.inf)
    P = _edge_points(fs, eid, ts[np.arange(m), k])
    rows = np.nonzero(fin[np.arange(m), k])[0]
    for r in range(3):
        if r > 0:  # the next highest local maximum not taken yet (ties: the first)
            score[np.arange(m), k] = -np.inf
            k = np.argmax(score, axis=1)
            rows = np.nonzero(np.isfinite(score[np.arange(m), k]))[0]
        if rows.size == 0:
            break
        gr, Pr = _edge_from(fs, prof, c[rows], eid[rows], ts[rows], g_s[rows], k[rows], iters)
        better = gr > g[rows]
        g[rows[better]], P[rows[better]] = gr[better], Pr[better]
    return g, P


def _edge_from(fs, prof, c, eid, ts, g_s, k, iters: int):
    """The edge search's safeguarded Newton on ``g'(t) = 0`` from sample ``k`` of each row (bracketed by its
    neighbours; a row stops when its step vanishes, so its answer does not depend on the others), onto the
    tool's circle where it ends outside the disc; ``g`` where the part enters the disc there (else ``-inf``)
    and the point."""
    m, n = ts.shape
    R = prof.R
    lo = ts[np.arange(m), np.maximum(k - 1, 0)]
    hi = ts[np.arange(m), np.minimum(k + 1, n - 1)]
    t = ts[np.arange(m), k].copy()
    tried = np.zeros(m, np.int64)  # the bracket's ends tried as its maximum: 1 lo, 2 hi
    act = np.arange(m)
    for _ in range(iters):
        if act.size == 0:
            break
        ta, la, ha = t[act], lo[act], hi[act]
        Pk, P1, P2 = _edge_derivs(fs, eid[act], ta, 2)
        ga, _, g1, _, g2 = _edge_g(prof, c[act], Pk, P1, P2)
        t_new, la, ha, conv = _newton_max(ta, la, ha, g1, g2)
        lo[act], hi[act] = la, ha
        # a bisection towards an end not tried yet: the end may be the bracket's maximum (an edge rising
        # out of the disc); there in one step instead of the bisection's fifty
        with np.errstate(divide="ignore", invalid="ignore"):
            newton_in = (g2 < 0) & (ta - g1 / g2 > la) & (ta - g1 / g2 < ha)
        side = np.where(newton_in, 0, np.where(g1 > 0, 2, 1))
        probe = np.nonzero(~conv & (side > 0) & ((tried[act] & side) == 0))[0]
        if probe.size:
            rows = act[probe]
            tried[rows] |= side[probe]
            end = np.where(side[probe] == 2, ha[probe], la[probe])
            Pe, Pe1 = _edge_derivs(fs, eid[rows], end, 1)
            ge, _, ge1, _ = _edge_g(prof, c[rows], Pe, Pe1)
            top = (ge >= ga[probe]) & np.where(side[probe] == 2, ge1 >= 0, ge1 <= 0)
            t_new[probe[top]] = end[top]
            conv[probe[top]] = True
        t[act] = t_new
        act = act[~conv]
    # the maximum outside the disc: the best point is on the circle, between the last point inside
    # and the first outside (Newton on rho(t) = R, kept in that bracket)
    P = _edge_points(fs, eid, t)
    g, rho = _edge_g(prof, c, P)
    out = rho > R
    if out.any():
        t = _onto_circle(fs, prof, c, eid, t, ts, g_s, out)
        P = _edge_points(fs, eid, t)
        g, rho = _edge_g(prof, c, P)
    ok = rho <= R * (1 + 1e-11)  # looser than _onto_circle's 1e-12: its point, evaluated again, stays in
    ok &= _enters_edge(fs, R, c, eid, t, rho)
    return np.where(ok, g, -np.inf), P


_ON_CIRCLE = 1e-9
"""A contact within this (relative to R) of the tool's circle is on it: it counts only where the part enters the
open disc next to it (:func:`_enters_face`, :func:`_enters_edge`)."""
_ON_CIRCLE_MM = 1e-12
"""A projection onto a circle of radius R stops within this times max(R, 1 mm) of it (its further Newton steps
would move the point by less than rounding in the coordinates)."""
_PROBE_MM = 1e-3
_PROBE_DIRECTIONS = 16
_PROBE_DROP = 1e-12
"""How much closer to the axis (relative to R) a probe must be than the contact to show that the part enters."""


def _enters_face(fs, R, c, fid, u, v, P) -> np.ndarray:
    """Whether each face contact has face points strictly inside the tool's disc next to it: True inside the
    disc; on its circle only where a probe :data:`_PROBE_MM` away on the face, in one of 16 directions of the
    tangent plane, lies on the trimmed face and closer to the axis (the face crosses the circle, or curves
    into the disc like a fillet tangent to a wall). A face that only touches the circle from outside (a
    plane wall exactly ``R`` from the axis, a step's edge at the rim) touches the tool's side without
    entering it: the tool may go lower (the drop-cutter is the lowest height at which the tool does not
    enter the part). ``P`` holds the contacts' points."""
    ok = np.ones(u.shape[0], bool)
    rho = np.sqrt((P[:, 0] - c[:, 0]) ** 2 + (P[:, 1] - c[:, 1]) ** 2)
    on = np.nonzero(rho >= R * (1 - _ON_CIRCLE))[0]
    if on.size == 0:
        return ok
    _, Su, Sv = _surface_eval(fs, fid[on], u[on], v[on], 1)
    rho = rho[on]
    E, F, G = (np.einsum("ij,ij->i", a, b) for a, b in ((Su, Su), (Su, Sv), (Sv, Sv)))
    det = E * G - F * F
    regular = det > 1e-12 * np.maximum(E * G, 1e-300)
    det = np.where(regular, det, 1.0)
    # an orthonormal tangent frame (t1 along Su) and the parameter steps of its directions
    t1 = Su / np.sqrt(np.maximum(E, 1e-300))[:, None]
    t2 = Sv - np.einsum("ij,ij->i", Sv, t1)[:, None] * t1
    t2 /= np.maximum(np.linalg.norm(t2, axis=1), 1e-300)[:, None]
    n = _PROBE_DIRECTIONS
    th = 2 * np.pi * np.arange(n) / n
    e = _PROBE_MM * (np.cos(th)[None, :, None] * t1[:, None, :] + np.sin(th)[None, :, None] * t2[:, None, :])
    a, b = np.einsum("mkd,md->mk", e, Su), np.einsum("mkd,md->mk", e, Sv)
    du = (G[:, None] * a - F[:, None] * b) / det[:, None]
    dv = (-F[:, None] * a + E[:, None] * b) / det[:, None]
    f = np.repeat(fid[on], n)
    pu, pv = _clamp_uv(fs, f, np.repeat(u[on], n) + du.ravel(), np.repeat(v[on], n) + dv.ravel())
    Q = _surface_eval(fs, f, pu, pv, 0)[0]
    cc = np.repeat(c[on], n, axis=0)
    rq = np.sqrt((Q[:, 0] - cc[:, 0]) ** 2 + (Q[:, 1] - cc[:, 1]) ** 2)
    closer = (rq < np.minimum(np.repeat(rho, n), R) - _PROBE_DROP * R) & _inside(fs, f, pu, pv)
    ok[on] = closer.reshape(-1, n).any(axis=1) | ~regular  # a pole or a degenerate tangent plane: kept
    return ok


def _enters_edge(fs, R, c, eid, t, rho) -> np.ndarray:
    """As :func:`_enters_face` for edge contacts: on the circle only where a probe :data:`_PROBE_MM` along the
    edge, on either side, lies closer to the axis."""
    ok = np.ones(t.shape[0], bool)
    on = np.nonzero(np.nan_to_num(rho, nan=0.0) >= R * (1 - _ON_CIRCLE))[0]
    if on.size == 0:
        return ok
    P, P1 = _edge_derivs(fs, eid[on], t[on], 1)
    r0 = np.sqrt((P[:, 0] - c[on, 0]) ** 2 + (P[:, 1] - c[on, 1]) ** 2)
    step = _PROBE_MM / np.maximum(np.linalg.norm(P1, axis=1), 1e-300)
    closer = np.zeros(on.size, bool)
    for sgn in (-1.0, 1.0):
        Q = _edge_points(fs, eid[on], fs.on_edge(eid[on], t[on] + sgn * step))
        rq = np.sqrt((Q[:, 0] - c[on, 0]) ** 2 + (Q[:, 1] - c[on, 1]) ** 2)
        closer |= rq < np.minimum(r0, R) - _PROBE_DROP * R
    ok[on] = closer
    return ok


def _graze(fs, prof, c, eid, ts, g, rho, iters: int = 40) -> None:
    """Rows with no sample inside the disc: the edge point nearest the axis between the samples around the
    nearest one (safeguarded Newton on ``d rho^2 / dt = 0``); where it lies inside the disc (an edge that
    grazes the disc between samples: a blade's tip edge 0.4 um inside the rim lifts a ball by 26 mm) it
    replaces that sample in ``ts`` and ``g`` (in place)."""
    R = prof.R
    rows = np.nonzero(~np.isfinite(g).any(axis=1))[0]
    if rows.size == 0:
        return
    n = ts.shape[1]
    k = np.argmin(np.nan_to_num(rho[rows], nan=np.inf), axis=1)
    lo, hi = ts[rows, np.maximum(k - 1, 0)], ts[rows, np.minimum(k + 1, n - 1)]
    t = ts[rows, k].copy()
    act = np.arange(rows.size)
    for _ in range(iters):
        if act.size == 0:
            break
        ta, la, ha = t[act], lo[act], hi[act]
        P, P1, P2 = _edge_derivs(fs, eid[rows[act]], ta, 2)
        d = P[:, :2] - c[rows[act]]
        r1 = np.einsum("ij,ij->i", d, P1[:, :2])  # half the derivatives of rho^2: a maximum of -rho^2
        r2 = np.einsum("ij,ij->i", P1[:, :2], P1[:, :2]) + np.einsum("ij,ij->i", d, P2[:, :2])
        t[act], lo[act], hi[act], conv = _newton_max(ta, la, ha, -r1, -r2)
        act = act[~conv]
    P = _edge_points(fs, eid[rows], t)
    gt, rt = _edge_g(prof, c[rows], P)
    hit = np.nonzero(rt <= R)[0]
    ts[rows[hit], k[hit]] = t[hit]
    g[rows[hit], k[hit]] = gt[hit]


def _onto_circle(fs, prof, c, eid, t, ts, g, out, iters: int = 40):
    """For the rows ``out`` (whose maximum ``t`` lies outside the disc), the edge point on the tool's
    circle nearest ``t`` on the side of the disc: Newton on ``rho(t) - R`` safeguarded by the bracket
    between the nearest sample inside the disc (finite ``g``) and ``t``."""
    R = prof.R
    idx = np.nonzero(out)[0]
    dist = np.where(np.isfinite(g[idx]), np.abs(ts[idx] - t[idx, None]), np.inf)
    t_in = ts[idx, np.argmin(dist, axis=1)]
    t_out = t[idx].copy()
    x = 0.5 * (t_in + t_out)
    act = np.arange(idx.size)  # rows still moving (each stops on its own)
    for _ in range(iters):
        if act.size == 0:
            break
        xa, ti, to = x[act], t_in[act], t_out[act]
        P, P1 = _edge_derivs(fs, eid[idx[act]], xa, 1)
        _, rho, _, r1 = _edge_g(prof, c[idx[act]], P, P1)
        f = rho - R  # inside: within the disc (rho <= R (1 + 1e-12); the edge search accepts up to 1e-11)
        ti = np.where(f <= 1e-12 * R, xa, ti)
        to = np.where(f > 1e-12 * R, xa, to)
        newton = xa - f / np.where(r1 != 0, r1, np.inf)
        lo, hi = np.minimum(ti, to), np.maximum(ti, to)
        x_new = np.where((newton > lo) & (newton < hi), newton, 0.5 * (ti + to))
        conv = np.abs(x_new - xa) <= 1e-15 * np.maximum(np.abs(xa), 1.0)
        conv |= np.abs(f) <= 1e-12 * R  # on the circle
        t_in[act], t_out[act] = ti, to
        x[act] = np.where(conv, xa, x_new)
        act = act[~conv]
    t = t.copy()
    t[idx] = t_in  # the last parameter inside the disc (within the bracket's width of the circle)
    return t


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
