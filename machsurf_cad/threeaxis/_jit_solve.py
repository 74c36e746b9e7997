"""Compiled (numba) local solves of the drop-cutter, one seed at a time: the face-interior ascent, the
ascent along a circle (the rim, or a circle where the profile's slope jumps), the search along a trimming
edge and the point below a pointed tip. Each is the scalar form of its numpy namesake in :mod:`.solves`
(same steps, safeguards and stopping rules), so the two paths agree to rounding.

``W = (D, Dn, Dm, Ed, cu, wk, ...)`` is per-query scratch: three (6, 3) derivative tables, a (9, 3) edge
table, a (3, 3) curve table and 480 floats (the kernel's ``W`` has the certificate's scratch after them).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._jit_geom import clamp_uv, edge_derivs, hyp, inside, isfin, nmax, nmin, norm3, nsign, prof, surf

ON_CIRCLE, PROBE_MM, PROBE_DIRECTIONS, PROBE_DROP, ON_CIRCLE_MM = 1e-9, 1e-3, 16, 1e-12, 1e-12  # as in solves


@njit(cache=True)
def enters_face(S, T, R, cx, cy, f, u, v, W):
    """``_enters_face`` on one contact (its point left in ``W[0][0]`` by the solve): inside the disc, or on its
    circle where a probe in one of 16 tangent directions lies on the face and closer to the axis."""
    rho = math.sqrt((W[0][0, 0] - cx) ** 2 + (W[0][0, 1] - cy) ** 2)
    if not (rho >= R * (1 - ON_CIRCLE)):
        return True
    D, wk = W[2], W[5]
    surf(S, f, u, v, 1, D, wk)
    su0, su1, su2, sv0, sv1, sv2 = D[1, 0], D[1, 1], D[1, 2], D[2, 0], D[2, 1], D[2, 2]
    E = su0 * su0 + su1 * su1 + su2 * su2
    F = su0 * sv0 + su1 * sv1 + su2 * sv2
    G = sv0 * sv0 + sv1 * sv1 + sv2 * sv2
    det = E * G - F * F
    if not (det > 1e-12 * max(E * G, 1e-300)):
        return True
    ln = math.sqrt(max(E, 1e-300))
    a0, a1, a2 = su0 / ln, su1 / ln, su2 / ln
    k = sv0 * a0 + sv1 * a1 + sv2 * a2
    b0, b1, b2 = sv0 - k * a0, sv1 - k * a1, sv2 - k * a2
    lb = max(math.sqrt(b0 * b0 + b1 * b1 + b2 * b2), 1e-300)
    b0, b1, b2 = b0 / lb, b1 / lb, b2 / lb
    limit = min(rho, R) - PROBE_DROP * R
    # the directions from the one nearest the axis (in plan) outwards: the first probe inward of the circle is
    # most often on the face, and the answer (any direction) does not depend on the order
    d0, d1 = cx - W[0][0, 0], cy - W[0][0, 1]
    near = int(round(math.atan2(d0 * b0 + d1 * b1, d0 * a0 + d1 * a1) / (2 * math.pi) * PROBE_DIRECTIONS))
    for n_ in range(PROBE_DIRECTIONS):
        i = (near + ((n_ + 1) // 2 if n_ % 2 else -(n_ // 2))) % PROBE_DIRECTIONS
        th = 2 * math.pi * i / PROBE_DIRECTIONS
        c_, s_ = PROBE_MM * math.cos(th), PROBE_MM * math.sin(th)
        e0, e1, e2 = c_ * a0 + s_ * b0, c_ * a1 + s_ * b1, c_ * a2 + s_ * b2
        pa = e0 * su0 + e1 * su1 + e2 * su2
        pb = e0 * sv0 + e1 * sv1 + e2 * sv2
        pu, pv = clamp_uv(S, f, u + (G * pa - F * pb) / det, v + (-F * pa + E * pb) / det)
        surf(S, f, pu, pv, 0, D, wk)
        if math.sqrt((D[0, 0] - cx) ** 2 + (D[0, 1] - cy) ** 2) < limit and inside(S, T, f, pu, pv):
            return True
    return False


@njit(cache=True, inline="always")
def g_derivs(PR, cx, cy, D, order):
    """``g = S_z - h(|S_xy - c|)`` with its (u, v) gradient and (order 2) Hessian (``_g_and_derivs``)."""
    dx, dy = D[0, 0] - cx, D[0, 1] - cy
    rho = hyp(dx, dy)
    h, h1, h2 = prof(PR, rho)
    g = D[0, 2] - h
    small = rho < 1e-9
    rs = 1.0 if small else rho
    B = h2 if small else h1 / rs
    A = 0.0 if small else (h2 - B) / rs**2
    gdx, gdy = B * dx, B * dy
    gu = D[1, 2] - (gdx * D[1, 0] + gdy * D[1, 1])
    gv = D[2, 2] - (gdx * D[2, 0] + gdy * D[2, 1])
    if order < 2:
        return g, gu, gv, 0.0, 0.0, 0.0
    du = dx * D[1, 0] + dy * D[1, 1]
    dv = dx * D[2, 0] + dy * D[2, 1]
    xuu = D[1, 0] * D[1, 0] + D[1, 1] * D[1, 1]
    xuv = D[1, 0] * D[2, 0] + D[1, 1] * D[2, 1]
    xvv = D[2, 0] * D[2, 0] + D[2, 1] * D[2, 1]
    Huu = D[3, 2] - (A * du * du + B * xuu) - (gdx * D[3, 0] + gdy * D[3, 1])
    Huv = D[4, 2] - (A * du * dv + B * xuv) - (gdx * D[4, 0] + gdy * D[4, 1])
    Hvv = D[5, 2] - (A * dv * dv + B * xvv) - (gdx * D[5, 0] + gdy * D[5, 1])
    return g, gu, gv, Huu, Huv, Hvv


@njit(cache=True, inline="always")
def _tan_len(D, a, b):
    return norm3(D[1, 0] * a + D[2, 0] * b, D[1, 1] * a + D[2, 1] * b, D[1, 2] * a + D[2, 2] * b)


@njit(cache=True)
def _off_poles(S, PR, cx, cy, f, u, v, W):
    """``_off_poles`` on one start: at a pole, the best of 16 starts just off it."""
    D, wk = W[0], W[5]
    surf(S, f, u, v, 1, D, wk)
    E = D[1, 0] ** 2 + D[1, 1] ** 2 + D[1, 2] ** 2
    G = D[2, 0] ** 2 + D[2, 1] ** 2 + D[2, 2] ** 2
    if not (min(E, G) <= 1e-14 * max(E, G)):
        return u, v
    ff = S[1]
    b0, b1, b2, b3 = ff[f, 8], ff[f, 9], ff[f, 10], ff[f, 11]
    along_v = G <= E
    off_u = u + 1e-4 * (b1 - b0) * nsign(0.5 * (b0 + b1) - u)
    off_v = v + 1e-4 * (b3 - b2) * nsign(0.5 * (b2 + b3) - v)
    best, bu, bv = -math.inf, u, v
    first = True
    for k in range(16):
        kk = (k + 0.5) / 16
        cu = off_u if along_v else b0 + kk * (b1 - b0)
        cv = b2 + kk * (b3 - b2) if along_v else off_v
        surf(S, f, cu, cv, 0, D, wk)
        g = D[0, 2] - prof(PR, hyp(D[0, 0] - cx, D[0, 1] - cy))[0]
        if not isfin(g):
            g = -math.inf
        if first or g > best:
            best, bu, bv, first = g, cu, cv, False
    return bu, bv


@njit(cache=True, inline="always")
def _up_curvature(Huu, Huv, Hvv, D, radius):
    disc = math.sqrt(max(0.25 * (Huu - Hvv) ** 2 + Huv * Huv, 0.0))
    lam = 0.5 * (Huu + Hvv) + disc
    if abs(Huv) > 1e-300:
        eu, ev = Huv, lam - Huu
    else:
        eu, ev = (1.0, 0.0) if Huu >= Hvv else (0.0, 1.0)
    k = radius / nmax(_tan_len(D, eu, ev), 1e-300)
    eu, ev = eu * k, ev * k
    quad = 0.5 * (Huu * eu * eu + 2 * Huv * eu * ev + Hvv * ev * ev)
    return eu, ev, quad if isfin(quad) else 0.0


@njit(cache=True, inline="always")
def _copy(dst, src):
    for i in range(6):
        for d in range(3):
            dst[i, d] = src[i, d]


@njit(cache=True, inline="always")
def _ascent_step(D, gu, gv, Huu, Huv, Hvv, radius, at_u, at_v):
    """The face ascent's step (``_ascent_step``): Newton where ``-H`` is positive definite, else steepest ascent
    on the surface as long as the trust radius, or along the largest upward curvature where that gains more;
    with ``u`` (``at_u``) or ``v`` (``at_v``) held, along the other parameter only."""
    if at_u:
        gu, Huv, Huu = 0.0, 0.0, -(1.0 + abs(Hvv))
    elif at_v:
        gv, Huv, Hvv = 0.0, 0.0, -(1.0 + abs(Huu))
    a, b, d_ = -Huu, -Huv, -Hvv
    det = a * d_ - b * b
    newton = (a > 0) and (det > 1e-14 * (a * a + d_ * d_ + b * b))
    du = dv = 0.0
    if newton:
        du = (d_ * gu - b * gv) / det
        dv = (-b * gu + a * gv) / det
    E = D[1, 0] ** 2 + D[1, 1] ** 2 + D[1, 2] ** 2
    F = 0.0 if at_u or at_v else D[1, 0] * D[2, 0] + D[1, 1] * D[2, 1] + D[1, 2] * D[2, 2]
    G = D[2, 0] ** 2 + D[2, 1] ** 2 + D[2, 2] ** 2
    dg = E * G - F * F
    regular = (dg > 1e-10 * E * G) and (min(E, G) > 1e-14 * max(E, G))
    if regular:
        au, av = (G * gu - F * gv) / dg, (-F * gu + E * gv) / dg
    else:
        au, av = gu, gv
    k = radius / nmax(_tan_len(D, au, av), 1e-300)
    if not newton:
        du, dv = au * k, av * k
    escape = False
    if not newton:
        eu, ev, quad = _up_curvature(Huu, Huv, Hvv, D, radius)
        escape = quad > abs(gu * au + gv * av) * k
        if escape:
            du, dv = eu, ev
    return du, dv, newton, escape


@njit(cache=True)
def face_newton(S, PR, sp, cx, cy, f, u, v, W, iters=40):
    """``_face_newton`` on one start: returns ``u, v, g`` with the point in ``W[0][0]``."""
    D, Dn, Dm, wk = W[0], W[1], W[2], W[5]
    u, v = _off_poles(S, PR, cx, cy, f, u, v, W)
    surf(S, f, u, v, 2, D, wk)
    g, gu, gv, Huu, Huv, Hvv = g_derivs(PR, cx, cy, D, 2)
    radius = 0.5 * sp
    if not isfin(g):
        return u, v, g
    fi, ff = S[0], S[1]
    for _ in range(iters):
        at_u = at_v = corner = False
        for attempt in range(2):
            du, dv, newton, escape = _ascent_step(D, gu, gv, Huu, Huv, Hvv, radius, at_u, at_v)
            if attempt == 1 or escape:
                break
            # a step out of the face's box on one side runs along that side instead (projected): a clamped
            # step crawls along it; out on both sides at a corner, no step of any length moves
            out_u = (not fi[f, 9]) and ((u <= ff[f, 8] and du < 0) or (u >= ff[f, 9] and du > 0))
            out_v = (not fi[f, 10]) and ((v <= ff[f, 10] and dv < 0) or (v >= ff[f, 11] and dv > 0))
            corner = out_u and out_v
            if out_u == out_v:
                break
            at_u, at_v = out_u, out_v
        if corner:
            break
        if du == 0.0 and dv == 0.0:  # a zero gradient and no upward curvature: every later step is this one
            break
        shrink = nmin(1.0, radius / nmax(_tan_len(D, du, dv), 1e-300))
        nu, nv = clamp_uv(S, f, u + du * shrink, v + dv * shrink)
        surf(S, f, nu, nv, 2, Dn, wk)
        gn, gun, gvn, Hun, Hwn, Hvn = g_derivs(PR, cx, cy, Dn, 2)
        if escape:  # the other side
            mu, mv = clamp_uv(S, f, u - du * shrink, v - dv * shrink)
            surf(S, f, mu, mv, 2, Dm, wk)
            gm, gum, gvm, Hum, Hwm, Hvm = g_derivs(PR, cx, cy, Dm, 2)
            gm_, gn_ = (-math.inf if gm != gm else gm), (-math.inf if gn != gn else gn)
            if gm_ > gn_:
                nu, nv, gn, gun, gvn, Hun, Hwn, Hvn = mu, mv, gm, gum, gvm, Hum, Hwm, Hvm
                _copy(Dn, Dm)
        moved = norm3(Dn[0, 0] - D[0, 0], Dn[0, 1] - D[0, 1], Dn[0, 2] - D[0, 2])
        rises = isfin(gn) and gn >= g - 1e-13 * (1 + abs(g))
        ok = rises and moved > 0
        if ok:
            u, v, g, gu, gv, Huu, Huv, Hvv = nu, nv, gn, gun, gvn, Hun, Hwn, Hvn
            _copy(D, Dn)
            radius = nmax(radius, 2 * moved)
        else:
            radius = 0.25 * radius
        if (ok and moved < 1e-11) or (rises and newton and moved == 0) or (not ok and radius < 1e-12):
            break
    return u, v, g


@njit(cache=True, inline="always")
def _circle_step(D, sp, R, cx, cy, rho):
    """The minimum-norm Newton step onto ``rho = R`` from the point of ``D`` (first derivatives), ``rho`` its
    distance from the axis; shortened to ``sp`` mm on the face. Returns ``du, dv``."""
    dx, dy = D[0, 0] - cx, D[0, 1] - cy
    ru = (dx * D[1, 0] + dy * D[1, 1]) / nmax(rho, 1e-300)
    rv = (dx * D[2, 0] + dy * D[2, 1]) / nmax(rho, 1e-300)
    n2 = ru * ru + rv * rv
    t = (R - rho) / n2 if n2 > 1e-300 else 0.0
    shrink = nmin(1.0, sp / nmax(_tan_len(D, t * ru, t * rv), 1e-300))
    if not isfin(shrink):
        shrink = 0.0
    return t * ru * shrink, t * rv * shrink


@njit(cache=True)
def project_circle(S, sp, R, cx, cy, f, u, v, n, W):
    """``_project_circle``: minimum-norm Newton steps onto ``rho = R``; returns ``u, v`` and whether it stopped
    on the circle (then ``W[0]`` holds the point and its first derivatives there)."""
    D, wk = W[0], W[5]
    for _ in range(n):
        surf(S, f, u, v, 1, D, wk)
        dx, dy = D[0, 0] - cx, D[0, 1] - cy
        rho = hyp(dx, dy)
        if abs(R - rho) <= ON_CIRCLE_MM * nmax(R, 1.0):  # on the circle: the further steps would not move
            return u, v, True
        du, dv = _circle_step(D, sp, R, cx, cy, rho)
        u, v = clamp_uv(S, f, u + du, v + dv)
    return u, v, False


@njit(cache=True)
def into_disc(S, sp, R, cx, cy, f, u, v, W, deeper, iters=16):
    """``_into_disc``: onto a circle just inside the rim, else (or ``deeper``: also from it) towards the face's
    point nearest the axis."""
    D, wk = W[0], W[5]
    target = R * (1 - 1e-3)
    stop = target * (1 - 1e-6) if deeper else target * (1 + 1e-9)
    u, v, _ = project_circle(S, sp, target, cx, cy, f, u, v, 6, W)
    for _ in range(iters):
        surf(S, f, u, v, 1, D, wk)
        dx, dy = D[0, 0] - cx, D[0, 1] - cy
        rho = hyp(dx, dy)
        if not (rho > stop):
            break
        a = D[1, 0] ** 2 + D[1, 1] ** 2
        b = D[1, 0] * D[2, 0] + D[1, 1] * D[2, 1]
        e = D[2, 0] ** 2 + D[2, 1] ** 2
        gu = dx * D[1, 0] + dy * D[1, 1]
        gv = dx * D[2, 0] + dy * D[2, 1]
        lm = 1e-9 * (a + e) + 1e-300
        det = (a + lm) * (e + lm) - b * b
        du = -((e + lm) * gu - b * gv) / det
        dv = -(-b * gu + (a + lm) * gv) / det
        k = nmin(1.0, sp / nmax(_tan_len(D, du, dv), 1e-300))
        if not isfin(k):
            k = 0.0
        moved = False
        for _half in range(8):
            nu, nv = clamp_uv(S, f, u + du * k, v + dv * k)
            surf(S, f, nu, nv, 0, D, wk)
            rn = hyp(D[0, 0] - cx, D[0, 1] - cy)
            if isfin(rn) and rn < rho - 1e-12:
                u, v, moved = nu, nv, True
                break
            k = 0.5 * k
        if not moved:
            break
    return u, v


@njit(cache=True, inline="always")
def _rim_terms(D, cx, cy, R):
    """At the point of ``D`` (second derivatives): its offset ``rho - R``, the gradient ``pu, pv`` of ``rho``
    (to first order in the offset), its square norm and the multiplier ``lam`` (the rise of z across the
    circle per mm of ``rho``)."""
    dx, dy = D[0, 0] - cx, D[0, 1] - cy
    pu = (dx * D[1, 0] + dy * D[1, 1]) / R
    pv = (dx * D[2, 0] + dy * D[2, 1]) / R
    n2 = pu * pu + pv * pv
    lam = (D[1, 2] * pu + D[2, 2] * pv) / n2 if n2 > 1e-300 else 0.0
    return hyp(dx, dy) - R, pu, pv, n2, lam


@njit(cache=True)
def rim_ascent(S, sp, R, h_R, cx, cy, f, u, v, W, iters=40):
    """``_rim_ascent``: the highest point of the face on ``rho = R`` near the start; returns ``u, v, g``
    (``-inf`` when it is not on the circle), the point in ``W[0][0]``.

    Each step is Newton's along the circle (within a trust radius) with its second-order correction across
    it, so that the point stays on the circle to third order; Newton steps onto the circle follow only while
    it is off by more than ``1e-9 R``. A step is kept when it does not lower the height the point would have
    on the circle (its z less ``lam`` times its offset), and the ascent stops on the circle (to
    ``ON_CIRCLE_MM``) where the next step would not move the point: one second-order evaluation a step near
    the top."""
    D, wk = W[0], W[5]
    tol = 1e-9 * max(R, 1.0)
    snap = ON_CIRCLE_MM * max(R, 1.0)
    u, v, _ = project_circle(S, sp, R, cx, cy, f, u, v, 6, W)
    surf(S, f, u, v, 2, D, wk)
    off, pu, pv, n2, lam = _rim_terms(D, cx, cy, R)
    z = D[0, 2] - lam * off if abs(off) <= tol else -math.inf
    radius = 2.0 * sp  # (the trust radius's start: 2 sample spacings, 10 % fewer evaluations than half of one)
    current = True
    for _ in range(iters):  # D holds the second derivatives at (u, v)
        pax, pay, paz = D[0, 0], D[0, 1], D[0, 2]
        dx, dy = pax - cx, pay - cy
        tu, tv = -pv, pu
        zt = D[1, 2] * tu + D[2, 2] * tv
        hz = D[3, 2] * tu * tu + 2 * D[4, 2] * tu * tv + D[5, 2] * tv * tv
        xtx, xty = D[1, 0] * tu + D[2, 0] * tv, D[1, 1] * tu + D[2, 1] * tv
        xttx = D[3, 0] * tu * tu + 2 * D[4, 0] * tu * tv + D[5, 0] * tv * tv
        xtty = D[3, 1] * tu * tu + 2 * D[4, 1] * tu * tv + D[5, 1] * tv * tv
        hphi = (xtx * xtx + xty * xty + dx * xttx + dy * xtty) / R
        Ltt = hz - lam * hphi
        tlen = _tan_len(D, tu, tv)
        if Ltt < -1e-300:
            s = -zt / Ltt
        else:
            s = nsign(zt) * radius / nmax(tlen, 1e-300)
        s = s * nmin(1.0, radius / nmax(abs(s) * tlen, 1e-300))
        if not isfin(s):
            s = 0.0
        if isfin(z) and Ltt < -1e-300 and abs(s) * tlen < 1e-12 and abs(off) <= snap:
            break  # the next step would not move the point
        c = (-off - 0.5 * s * s * hphi) / n2 if n2 > 1e-300 else 0.0  # across: onto the circle
        if not isfin(c):
            c = 0.0
        nu, nv = clamp_uv(S, f, u + s * tu + c * pu, v + s * tv + c * pv)
        surf(S, f, nu, nv, 2, D, wk)
        for _p in range(3):  # Newton steps onto the circle (``project_circle``'s, from this evaluation)
            rho = hyp(D[0, 0] - cx, D[0, 1] - cy)
            if abs(R - rho) <= tol:
                break
            du, dv = _circle_step(D, sp, R, cx, cy, rho)
            nu, nv = clamp_uv(S, f, nu + du, nv + dv)
            surf(S, f, nu, nv, 2, D, wk)
        off_n, pu_n, pv_n, n2_n, lam_n = _rim_terms(D, cx, cy, R)
        zn = D[0, 2] - lam_n * off_n if abs(off_n) <= tol else -math.inf
        acc = isfin(zn) and zn >= z - 1e-13 * (1 + abs(z))
        moved = norm3(D[0, 0] - pax, D[0, 1] - pay, D[0, 2] - paz)
        if acc:
            u, v, z = nu, nv, zn
            off, pu, pv, n2, lam = off_n, pu_n, pv_n, n2_n, lam_n
            radius = nmax(radius, 2 * moved)
        else:
            radius = 0.25 * radius
        current = acc
        if (acc and moved < 1e-11) or (not acc and radius < 1e-12):
            break
        if not acc:
            surf(S, f, u, v, 2, D, wk)
            current = True
    if current and abs(off) <= snap:
        z = D[0, 2]
    else:  # (stopped off the circle by more than ON_CIRCLE_MM, or on a rejected step: onto it from the point)
        u, v, _ = project_circle(S, sp, R, cx, cy, f, u, v, 3, W)
        surf(S, f, u, v, 0, D, wk)
        z = D[0, 2] if abs(hyp(D[0, 0] - cx, D[0, 1] - cy) - R) <= tol else -math.inf
    return u, v, (z - h_R) if isfin(z) else -math.inf


@njit(cache=True)
def tip_solve(S, cx, cy, f, u, v, W, iters=30):
    """``_tip_solve``: the face point below the axis; returns ``u, v, ok`` (point in ``W[0][0]``)."""
    D, wk = W[0], W[5]
    for _ in range(iters):
        surf(S, f, u, v, 1, D, wk)
        rx, ry = D[0, 0] - cx, D[0, 1] - cy
        a, b, c, d = D[1, 0], D[2, 0], D[1, 1], D[2, 1]
        det = a * d - b * c
        if abs(det) < 1e-300:
            det = 1e-300
        u, v = clamp_uv(S, f, u - (d * rx - b * ry) / det, v - (-c * rx + a * ry) / det)
    surf(S, f, u, v, 0, D, wk)
    return u, v, hyp(D[0, 0] - cx, D[0, 1] - cy) < 1e-9


# ----------------------------------------------------------------------------- trimming edges
@njit(cache=True, inline="always")
def edge_g(PR, cx, cy, Ed, order):
    """``g = z - h(rho)`` along an edge and (order >= 1, 2) its derivatives; returns g, rho, g1, r1, g2."""
    dx, dy = Ed[0, 0] - cx, Ed[0, 1] - cy
    rho = hyp(dx, dy)
    R = PR[1][0]
    h, h1, h2 = prof(PR, nmin(rho, R))
    g = Ed[0, 2] - h
    if order == 0:
        return g, rho, 0.0, 0.0, 0.0
    safe = nmax(rho, 1e-300)
    r1 = (dx * Ed[1, 0] + dy * Ed[1, 1]) / safe
    g1 = Ed[1, 2] - h1 * r1
    if order == 1:
        return g, rho, g1, r1, 0.0
    r2 = (Ed[1, 0] ** 2 + Ed[1, 1] ** 2 + dx * Ed[2, 0] + dy * Ed[2, 1] - r1 * r1) / safe
    return g, rho, g1, r1, Ed[2, 2] - h2 * r1 * r1 - h1 * r2


@njit(cache=True, inline="always")
def _newton_max(t, lo, hi, d1, d2):
    """One safeguarded Newton step towards a maximum of a function of ``t`` with derivatives ``d1``, ``d2``:
    the bracket ``[lo, hi]`` shrinks by the sign of ``d1``, Newton where the function is concave and the step
    stays inside, else bisection. Returns the new ``t``, the bracket and whether the step vanished."""
    if d1 > 0:
        lo = t
    if d1 < 0:
        hi = t
    newton = t - d1 / (d2 if d2 < 0 else -math.inf)
    t_new = newton if (d2 < 0 and lo < newton < hi) else 0.5 * (lo + hi)
    if d1 == 0:
        t_new = t
    return t_new, lo, hi, abs(t_new - t) <= 1e-15 * max(abs(t), 1.0)


WINDOW = 17
"""Samples of the edge search's window (two sample spacings either side of its seed)."""


@njit(cache=True, inline="always")
def _window(E, e, t0, dt, ts):
    """The edge search's window around ``t0``: its ``WINDOW`` parameters into ``ts``."""
    loop = E[0][e, 6] == 1  # a closed edge's window runs across its seam
    a = t0 - 2 * dt if loop else max(t0 - 2 * dt, E[1][e, 0])
    b = t0 + 2 * dt if loop else min(t0 + 2 * dt, E[1][e, 1])
    for k in range(WINDOW):
        ts[k] = a + (b - a) * (k / (WINDOW - 1))


@njit(cache=True, parallel=True, nogil=True)
def edge_windows(S, E, eid, et, edt, out):
    """The points of every edge sample's search window (``out[s, k]``): they do not depend on the query, so
    :func:`edge_search` reads them instead of evaluating the edge (the same numbers)."""
    for s in prange(eid.shape[0]):
        Ed, cu, wk = np.empty((9, 3)), np.empty((3, 3)), np.empty(480)
        ts = np.empty(WINDOW)
        _window(E, eid[s], et[s], edt[s], ts)
        for k in range(WINDOW):
            edge_derivs(S, E, eid[s], ts[k], 0, Ed, cu, wk)
            out[s, k, 0], out[s, k, 1], out[s, k, 2] = Ed[0, 0], Ed[0, 1], Ed[0, 2]


@njit(cache=True)
def edge_search(S, E, PR, cx, cy, e, t0, dt, W, EW, s, iters=40):
    """``_edge_search`` on one seed (edge sample ``s``; ``EW`` its window's points from :func:`edge_windows`,
    or empty): returns ``g`` (``-inf`` where no point is in the disc), the point in ``W[3][0]``."""
    Ed, cu, wk = W[3], W[4], W[5]
    R = PR[1][0]
    n = WINDOW
    ts = wk[400:417]
    gs = wk[420:437]  # the samples' values, -inf outside the disc
    rs = wk[440:457]  # and their distances from the axis
    _window(E, e, t0, dt, ts)
    kbest = 0
    for k in range(n):
        if EW.shape[0] > 0:
            Ed[0, 0], Ed[0, 1], Ed[0, 2] = EW[s, k, 0], EW[s, k, 1], EW[s, k, 2]
        else:
            edge_derivs(S, E, e, ts[k], 0, Ed, cu, wk)
        g, rho, _, _, _ = edge_g(PR, cx, cy, Ed, 0)
        gs[k] = g if rho <= R else -math.inf
        rs[k] = rho
        if gs[k] > gs[kbest]:
            kbest = k
    if not isfin(gs[kbest]):  # ``_graze``: an edge grazing the disc between the samples
        kbest = _graze(S, E, PR, cx, cy, e, ts, gs, rs, W)
    if not isfin(gs[kbest]):
        edge_derivs(S, E, e, ts[kbest], 0, Ed, cu, wk)
        return -math.inf
    # from each of the (at most) three highest local maxima of the samples: an edge may rise to two maxima
    # within the window, the higher one not the best sample's
    best_g, bx, by, bz = -math.inf, math.nan, math.nan, math.nan
    taken = wk[460:463]
    for r in range(3):
        kr = -1
        for k in range(n):
            if not isfin(gs[k]) or (k > 0 and gs[k - 1] > gs[k]) or (k < n - 1 and gs[k + 1] > gs[k]):
                continue
            if (r > 0 and k == taken[0]) or (r > 1 and k == taken[1]):
                continue
            if kr < 0 or gs[k] > gs[kr]:
                kr = k
        if r == 0:
            kr = kbest
        if kr < 0:
            break
        taken[r] = kr
        g = _edge_from(S, E, PR, cx, cy, e, kr, ts, gs, W, iters)
        if g > best_g:
            best_g, bx, by, bz = g, Ed[0, 0], Ed[0, 1], Ed[0, 2]
    Ed[0, 0], Ed[0, 1], Ed[0, 2] = bx, by, bz
    return best_g


@njit(cache=True)
def _edge_from(S, E, PR, cx, cy, e, k0, ts, gs, W, iters):
    """The edge search's safeguarded Newton from sample ``k0`` (bracketed by its neighbours), onto the tool's
    circle where it ends outside the disc; ``g`` where the part enters the disc there, else ``-inf``; the point
    in ``W[3][0]``."""
    Ed, cu, wk = W[3], W[4], W[5]
    R = PR[1][0]
    n = ts.shape[0]
    lo, hi = ts[max(k0 - 1, 0)], ts[min(k0 + 1, n - 1)]
    t = ts[k0]
    tried = 0  # the bracket's ends tried as its maximum: 1 lo, 2 hi
    for _ in range(iters):
        edge_derivs(S, E, e, t, 2, Ed, cu, wk)
        g, _, g1, _, g2 = edge_g(PR, cx, cy, Ed, 2)
        t_new, lo, hi, conv = _newton_max(t, lo, hi, g1, g2)
        if conv:
            t = t_new
            break
        side = 0 if (g2 < 0 and lo < t - g1 / g2 < hi) else (2 if g1 > 0 else 1)
        if side > 0 and not (tried & side):  # a bisection towards an end: the end may be the maximum
            tried |= side
            end = hi if side == 2 else lo
            edge_derivs(S, E, e, end, 1, Ed, cu, wk)
            ge, _, ge1, _, _ = edge_g(PR, cx, cy, Ed, 1)
            if ge >= g and (ge1 >= 0 if side == 2 else ge1 <= 0):
                t = end  # (the old bisection's limit, there in one step)
                break
        t = t_new
    edge_derivs(S, E, e, t, 0, Ed, cu, wk)
    g, rho, _, _, _ = edge_g(PR, cx, cy, Ed, 0)
    if rho > R:
        t = _onto_circle(S, E, PR, cx, cy, e, t, ts, gs, W)
        edge_derivs(S, E, e, t, 0, Ed, cu, wk)
        g, rho, _, _, _ = edge_g(PR, cx, cy, Ed, 0)
    if rho <= R * (1 + 1e-11) and _enters_edge(S, E, R, cx, cy, e, t, W):
        return g
    return -math.inf


@njit(cache=True)
def _graze(S, E, PR, cx, cy, e, ts, gs, rs, W, iters=40):
    """``_graze`` on one edge (samples ``ts``, their distances ``rs`` from the axis): the point nearest the axis
    between the samples around the nearest one; inside the disc it replaces that sample (``ts``, ``gs``).
    Returns the index of the sample to start from."""
    Ed, cu, wk = W[3], W[4], W[5]
    R = PR[1][0]
    n = ts.shape[0]
    k, best = 0, math.inf
    for i in range(n):
        if rs[i] < best:
            k, best = i, rs[i]
    lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, n - 1)]
    t = ts[k]
    for _ in range(iters):
        edge_derivs(S, E, e, t, 2, Ed, cu, wk)
        dx, dy = Ed[0, 0] - cx, Ed[0, 1] - cy
        r1 = dx * Ed[1, 0] + dy * Ed[1, 1]  # half the derivatives of rho^2: a maximum of -rho^2
        r2 = Ed[1, 0] ** 2 + Ed[1, 1] ** 2 + dx * Ed[2, 0] + dy * Ed[2, 1]
        t, lo, hi, conv = _newton_max(t, lo, hi, -r1, -r2)
        if conv:
            break
    edge_derivs(S, E, e, t, 0, Ed, cu, wk)
    g, rho, _, _, _ = edge_g(PR, cx, cy, Ed, 0)
    if rho <= R:
        ts[k], gs[k] = t, g
    return k


@njit(cache=True)
def _enters_edge(S, E, R, cx, cy, e, t, W):
    """``_enters_edge`` on one contact (the point of ``t`` left in ``W[3][0]``)."""
    Ed, cu, wk = W[3], W[4], W[5]
    edge_derivs(S, E, e, t, 1, Ed, cu, wk)
    r0 = math.sqrt((Ed[0, 0] - cx) ** 2 + (Ed[0, 1] - cy) ** 2)
    ok = True
    if r0 >= R * (1 - ON_CIRCLE):
        step = PROBE_MM / nmax(norm3(Ed[1, 0], Ed[1, 1], Ed[1, 2]), 1e-300)
        ok = False
        for sgn in (-1.0, 1.0):
            tq = t + sgn * step
            edge_derivs(S, E, e, tq if E[0][e, 6] == 1 else min(max(tq, E[1][e, 0]), E[1][e, 1]), 0, Ed, cu, wk)
            if math.sqrt((Ed[0, 0] - cx) ** 2 + (Ed[0, 1] - cy) ** 2) < min(r0, R) - PROBE_DROP * R:
                ok = True
    edge_derivs(S, E, e, t, 0, Ed, cu, wk)
    return ok


@njit(cache=True)
def _onto_circle(S, E, PR, cx, cy, e, t, ts, gs, W, iters=40):
    """``_onto_circle``: the last edge parameter inside the disc between the nearest sample inside (finite
    ``gs``) and ``t``."""
    Ed, cu, wk = W[3], W[4], W[5]
    R = PR[1][0]
    best, t_in = math.inf, ts[0]
    for k in range(ts.shape[0]):
        if isfin(gs[k]) and abs(ts[k] - t) < best:
            best, t_in = abs(ts[k] - t), ts[k]
    t_out = t
    x = 0.5 * (t_in + t_out)
    for _ in range(iters):
        edge_derivs(S, E, e, x, 1, Ed, cu, wk)
        _, rho, _, r1, _ = edge_g(PR, cx, cy, Ed, 1)
        fx = rho - R  # inside: within the disc as the edge search accepts it
        if fx <= 1e-12 * R:
            t_in = x
            if fx >= -1e-12 * R:
                break  # on the circle
        if fx > 1e-12 * R:
            t_out = x
        newton = x - fx / (r1 if r1 != 0 else math.inf)
        lo, hi = min(t_in, t_out), max(t_in, t_out)
        x_new = newton if lo < newton < hi else 0.5 * (t_in + t_out)
        if abs(x_new - x) <= 1e-15 * max(abs(x), 1.0):
            break
        x = x_new
    return t_in
