"""Compiled (numba) certificate of a flat end's rim contact: a box of the face's parameters in which no point
inside the tool's disc is higher than the contact.

At a rim contact ``p*`` of a flat end (the highest point of the face on the circle ``rho = R``, where the
face rises outwards) the Lagrangian ``L = z + mu (R^2 - rho^2) / 2`` with the contact's multiplier
``mu >= 0`` has zero gradient, and ``z <= L`` at every point with ``rho <= R``. On one polynomial piece
(knot span pair) of a non-rational face, ``L`` is a polynomial in the span's coordinates; expanded about the
contact and scaled to a box ``|ds| <= rs, |dt| <= rt`` (``x = ds / rs``, ``y = dt / rt``):

    L - L* <= g r - lam r^2 + K r^3 <= g^2 / (4 (lam - K)),  r = max(|x|, |y|) <= 1,

where ``g`` is the sum of the linear coefficients' magnitudes (zero at the contact but for rounding), ``lam``
the least eigenvalue of minus the quadratic part and ``K`` the sum of the magnitudes of every coefficient of
degree three and more. When ``K < lam`` (asked with a margin: ``K < 7 lam / 8``) every point of the face in the
box and in the disc is at most ``L* + g^2 / (4 (lam - K))`` high: exact arithmetic on the piece's
coefficients, no sampling. The drop-cutter then leaves out the seed samples whose whole grid neighbourhood
lies in the box (they bound nothing above the contact), which ends the local solves that would climb back to
the same contact from a neighbouring sector.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._jit_geom import _span, hyp

CERT_SLACK = 5e-11
"""A box is kept only when the height it certifies exceeds the contact's by at most this (mm): less than the
drop-cutter's tie margin, so a seed left out can raise the height by no more than a tie does."""


@njit(cache=True, inline="always")
def _taylor_pq(coef, base, p, q, s0, t0, out, tmp):
    """The piece's Taylor coefficients about ``(s0, t0)`` (x, y, z of the power-basis block at ``base``) into
    ``out[3, 8, 8]`` (``tmp``: scratch of the same shape)."""
    for d in range(3):  # along u: sum_i C[i, b] binom(i, a) s0^(i - a)
        for b in range(q + 1):
            for a in range(p + 1):
                acc = 0.0
                for i in range(p, a - 1, -1):
                    acc = acc * s0 + coef[base + (i * (q + 1) + b) * 4 + d] * _BINOM[i, a]
                tmp[d, a, b] = acc
        for a in range(p + 1):
            for b in range(q + 1):
                acc = 0.0
                for j in range(q, b - 1, -1):
                    acc = acc * t0 + tmp[d, a, j] * _BINOM[j, b]
                out[d, a, b] = acc


@njit(cache=True)
def _taylor(coef, base, p, q, s0, t0, out, tmp):
    """:func:`_taylor_pq`, a bicubic piece's with its degrees as constants (the loops unrolled)."""
    if p == 3 and q == 3:
        _taylor_pq(coef, base, 3, 3, s0, t0, out, tmp)
    else:
        _taylor_pq(coef, base, p, q, s0, t0, out, tmp)


def _pascal(n):
    out = np.zeros((n, n))
    for i in range(n):
        out[i, 0] = 1.0
        for k in range(1, i + 1):
            out[i, k] = out[i - 1, k - 1] + out[i - 1, k]
    return out


CERT_SCRATCH = 842
"""Floats of :func:`rim_certificate`'s scratch: the Taylor coefficients and their scratch (2 x 3 x 8 x 8) and
the Lagrangian's coefficients of the contact's piece and of a neighbouring one (15 x 15 each), and per side of
the box its knot line's distance and whether the box grows across it."""

_BINOM = _pascal(8)
"""Binomial coefficients ``binom(n, k)`` for n < 8 (the power basis's degrees: at most 7)."""


@njit(cache=True)
def _piece_base(fi, f, i, j, coef):
    """The coefficient block of face ``f``'s piece ``(i, j)``, or -1 when the piece is rational."""
    p, q = fi[f, 0], fi[f, 1]
    base = fi[f, 6] + (i * fi[f, 3] + j) * (p + 1) * (q + 1) * 4
    for a in range(p + 1):
        for b in range(q + 1):
            if coef[base + (a * (q + 1) + b) * 4 + 3] != (1.0 if a == 0 and b == 0 else 0.0):
                return -1
    return base


@njit(cache=True)
def _lagrangian(p, q, T, mu, R, L):
    """:func:`_lagrangian_pq`, a bicubic piece's with its degrees as constants (the loops unrolled)."""
    if p == 3 and q == 3:
        _lagrangian_pq(3, 3, T, mu, R, L)
    else:
        _lagrangian_pq(p, q, T, mu, R, L)


@njit(cache=True, inline="always")
def _lagrangian_pq(p, q, T, mu, R, L):
    """The Lagrangian's coefficients ``L`` (15 x 15; ``[:2p + 1, :2q + 1]`` written) from the Taylor coefficients
    ``T`` (x, y less the axis, z) and the multiplier ``mu``. The product ``x^2 + y^2`` sums each pair of
    coefficients once (twice the product) and each coefficient's square."""
    X, Y, Z = T[0], T[1], T[2]
    L[: 2 * p + 1, : 2 * q + 1] = 0.0
    h = 0.5 * mu
    for a in range(p + 1):
        for b in range(q + 1):
            xa, ya = X[a, b], Y[a, b]
            L[a, b] += Z[a, b]
            L[2 * a, 2 * b] -= h * (xa * xa + ya * ya)
            for b2 in range(b + 1, q + 1):  # the pairs after (a, b): the rest of its row, then the next rows
                L[2 * a, b + b2] -= mu * (xa * X[a, b2] + ya * Y[a, b2])
            for a2 in range(a + 1, p + 1):
                for b2 in range(q + 1):
                    L[a + a2, b + b2] -= mu * (xa * X[a2, b2] + ya * Y[a2, b2])
    L[0, 0] += h * R * R


@njit(cache=True)
def _terms(L, p, q, rs, rt):
    """On the box ``|ds| <= rs, |dt| <= rt``: the linear terms' sum ``g``, ``lam``, ``K`` and the coefficients'
    magnitude sum (see the module docstring)."""
    g = abs(L[1, 0]) * rs + abs(L[0, 1]) * rt
    A, B, C = L[2, 0] * rs * rs, L[1, 1] * rs * rt, L[0, 2] * rt * rt
    lam = -(0.5 * (A + C) + math.sqrt(0.25 * (A - C) ** 2 + 0.25 * B * B))
    K = size = 0.0
    ra = 1.0
    for a in range(2 * p + 1):
        c_ = ra  # rs^a rt^b by running products
        for b in range(2 * q + 1):
            c = abs(L[a, b]) * c_
            c_ *= rt
            size += c
            if a + b >= 3:
                K += c
        ra *= rs
    return g, lam, K, size


@njit(cache=True, inline="always")
def _top(a, c, lo):
    """The top of ``a w - c w^2`` over ``lo <= w <= 1`` (``c > 0``)."""
    w = min(max(a / (2 * c), lo), 1.0)
    return a * w - c * w * w


@njit(cache=True)
def _neighbour(S, f, i, j, u, v, cx, cy, mu, R, z, du, dv, eu, ev, ru, rv, T, L):
    """Whether piece ``(i, j)`` of face ``f``, next to the contact's across the knot line of u (``eu``: -1 or
    +1, the side; 0: the same u span), of v (``ev``) or of both (a diagonal piece), has no point in the box
    ``u +- du, v +- dv`` and in the disc above ``z + CERT_SLACK``. Its polynomial, expanded about the contact
    (outside the piece) with the contact's multiplier and scaled to the box (``x = ds / rs``, ``y = dt /
    rt``), satisfies

        L - L0 <= a_x x + a_y y - (lam - K) (x^2 + y^2)

    (the quadratic part is at most ``-lam (x^2 + y^2)`` and the rest at most ``K r^3 <= K (x^2 + y^2)``),
    whose top is the sum of two concave parabolas' tops: over ``|x| <= 1`` along a span the contact's piece
    shares, over ``ru <= w <= 1`` (``w = eu x``, the knot line ``ru`` box units from the contact) across one.
    A piece that falls away from its knot line is bounded by its value there, where it meets the contact's."""
    fi, ff, ust, hu, vst, hv, coef = S
    p, q = fi[f, 0], fi[f, 1]
    base = _piece_base(fi, f, i, j, coef)
    if base < 0:
        return False
    h1, h2 = hu[fi[f, 4] + i], hv[fi[f, 5] + j]
    _taylor(coef, base, p, q, (u - ust[fi[f, 4] + i]) / h1, (v - vst[fi[f, 5] + j]) / h2, T[0], T[1])
    T[0, 0, 0, 0] -= cx
    T[0, 1, 0, 0] -= cy
    _lagrangian(p, q, T[0], mu, R, L)
    rs, rt = du / h1, dv / h2
    g, lam, K, size = _terms(L, p, q, rs, rt)
    if not (lam > 0 and K < 0.875 * lam):
        return False
    c = lam - K
    ax, ay = L[1, 0] * rs, L[0, 1] * rt
    tx = _top(eu * ax, c, ru) if eu != 0 else _top(abs(ax), c, 0.0)
    ty = _top(ev * ay, c, rv) if ev != 0 else _top(abs(ay), c, 0.0)
    return L[0, 0] - z + tx + ty + 1e-14 * size <= CERT_SLACK


@njit(cache=True)
def rim_certificate(S, f, u, v, cx, cy, R, z, out, ws=None):
    """The parameter box of face ``f`` about its flat-end rim contact ``(u, v)`` (height ``z``, tool axis at
    ``(cx, cy)``, radius ``R``) in which no point in the disc is above ``z + CERT_SLACK``: ``out[0:4]`` = u
    from, u to, v from, v to. Returns whether one was found (a non-rational, non-periodic face whose rim
    function is concave enough there: tried on boxes reaching ``2 R`` mm in plan from the contact (the disc's
    far side), then each 0.7 of the one before, down to about ``R / 4``). The box found on the contact's
    piece stops at its knot lines; it goes on across each into the neighbouring piece when that piece
    certifies (:func:`_neighbour`), and across a u and a v knot line both only when the diagonal piece between
    them does too (else across the u one only). ``ws``: scratch of at least ``CERT_SCRATCH`` floats (else made
    here)."""
    fi, ff, ust, hu, vst, hv, coef = S
    if fi[f, 7] or fi[f, 8]:
        return False
    p, q = fi[f, 0], fi[f, 1]
    uo, vo, nsu, nsv = fi[f, 4], fi[f, 5], fi[f, 2], fi[f, 3]
    i = _span(ust, uo, nsu, u)
    j = _span(vst, vo, nsv, v)
    h1, h2 = hu[uo + i], hv[vo + j]
    base = _piece_base(fi, f, i, j, coef)
    if base < 0:  # a rational piece: no certificate
        return False
    if ws is None:
        ws = np.empty(CERT_SCRATCH)
    # the Taylor coefficients and _taylor's scratch (only their [:p + 1, :q + 1] are written and read)
    T = ws[:384].reshape((2, 3, 8, 8))
    _taylor(coef, base, p, q, (u - ust[uo + i]) / h1, (v - vst[vo + j]) / h2, T[0], T[1])
    X, Y, Z = T[0, 0], T[0, 1], T[0, 2]
    X[0, 0] -= cx
    Y[0, 0] -= cy
    # the multiplier: the least-squares fit of grad z = mu grad (rho^2 / 2) at the contact
    gx = X[0, 0] * X[1, 0] + Y[0, 0] * Y[1, 0]
    gy = X[0, 0] * X[0, 1] + Y[0, 0] * Y[0, 1]
    gg = gx * gx + gy * gy
    if not (gg > 0):
        return False
    mu = (Z[1, 0] * gx + Z[0, 1] * gy) / gg
    if not (mu > 0):
        return False
    su, sv = hyp(X[1, 0], Y[1, 0]), hyp(X[0, 1], Y[0, 1])  # plan speeds per unit of the span's coordinates
    if not (su > 0 and sv > 0):
        return False
    L = ws[384:609].reshape((15, 15))
    _lagrangian(p, q, T[0], mu, R, L)
    r_mm = 2 * R / 0.7
    for _attempt in range(7):
        r_mm *= 0.7
        rs, rt = r_mm / su, r_mm / sv
        g, lam, K, size = _terms(L, p, q, rs, rt)
        if not (lam > 0 and K < 0.875 * lam):
            continue
        # L* above z, the linear terms' rise and the coefficients' rounding (1e-14 of their sum)
        e = max(L[0, 0] - z, 0.0) + g * g / (4 * (lam - K)) + 1e-14 * size
        if not (e <= CERT_SLACK):
            continue
        du, dv = rs * h1, rt * h2
        lo_u = -math.inf if i == 0 else ust[uo + i]  # the end pieces run on beyond the knots (extrapolated)
        hi_u = math.inf if i == nsu - 1 else ust[uo + i] + h1
        lo_v = -math.inf if j == 0 else vst[vo + j]
        hi_v = math.inf if j == nsv - 1 else vst[vo + j] + h2
        out[0], out[1] = max(u - du, lo_u), min(u + du, hi_u)
        out[2], out[3] = max(v - dv, lo_v), min(v + dv, hi_v)
        Ln = ws[609:834].reshape((15, 15))
        # the pieces across the knot lines the box reaches: each side's, then the diagonal ones between two
        # sides that certify (a diagonal that does not takes back its v side: the box stays on pieces)
        near, grow = ws[834:838], ws[838:842]  # the knot line's distance from the contact in box units; 1.0: grown
        grow[:] = 0.0
        for side in range(4):
            k = (i - 1 if side == 0 else i + 1) if side < 2 else (j - 1 if side == 2 else j + 1)
            half = du if side < 2 else dv
            near[side] = abs(out[side] - (u if side < 2 else v)) / half
            if not (0 <= k < (nsu if side < 2 else nsv)) or near[side] >= 1.0:  # (the box does not reach it)
                continue
            e = -1 if side == 0 or side == 2 else 1
            if side < 2:
                grow[side] = _neighbour(S, f, k, j, u, v, cx, cy, mu, R, z, du, dv, e, 0, near[side], 0.0, T, Ln)
            else:
                grow[side] = _neighbour(S, f, i, k, u, v, cx, cy, mu, R, z, du, dv, 0, e, 0.0, near[side], T, Ln)
        for su_ in range(2):
            for sv_ in range(2, 4):
                if grow[su_] > 0 and grow[sv_] > 0:
                    eu, ev = (-1 if su_ == 0 else 1), (-1 if sv_ == 2 else 1)
                    ru, rv = near[su_], near[sv_]
                    if not _neighbour(S, f, i + eu, j + ev, u, v, cx, cy, mu, R, z, du, dv, eu, ev, ru, rv, T, Ln):
                        grow[sv_] = 0.0
        for side in range(4):
            if grow[side] > 0:
                k = (i - 1 if side == 0 else i + 1) if side < 2 else (j - 1 if side == 2 else j + 1)
                n_k = nsu if side < 2 else nsv
                at = u if side < 2 else v
                half = du if side < 2 else dv
                lo_k = ust[uo + k] if side < 2 else vst[vo + k]  # the neighbour's knots (the end ones: none)
                hi_k = lo_k + (hu[uo + k] if side < 2 else hv[vo + k])
                if side == 0 or side == 2:
                    out[side] = max(at - half, -math.inf if k == 0 else lo_k)
                else:
                    out[side] = min(at + half, math.inf if k == n_k - 1 else hi_k)
        return True
    return False


@njit(cache=True, inline="always")
def boxed(cert, f, u, v, du, dv):
    """Whether the parameter box ``u +- du, v +- dv`` of face ``f`` lies in the certified box ``cert`` (face,
    u from, u to, v from, v to; face -1: none)."""
    return f == cert[0] and u - du >= cert[1] and u + du <= cert[2] and v - dv >= cert[3] and v + dv <= cert[4]
