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
degree three and more. When ``K < lam`` (asked with a margin: ``K < lam / 2``) every point of the face in the
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


@njit(cache=True)
def _taylor(coef, base, p, q, s0, t0, out, tmp):
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


def _pascal(n):
    out = np.zeros((n, n))
    for i in range(n):
        out[i, 0] = 1.0
        for k in range(1, i + 1):
            out[i, k] = out[i - 1, k - 1] + out[i - 1, k]
    return out


CERT_SCRATCH = 609
"""Floats of :func:`rim_certificate`'s scratch: the Taylor coefficients and their scratch (2 x 3 x 8 x 8) and
the Lagrangian's coefficients (15 x 15)."""

_BINOM = _pascal(8)
"""Binomial coefficients ``binom(n, k)`` for n < 8 (the power basis's degrees: at most 7)."""


@njit(cache=True)
def rim_certificate(S, f, u, v, cx, cy, R, z, out, ws=None):
    """The parameter box of face ``f`` about its flat-end rim contact ``(u, v)`` (height ``z``, tool axis at
    ``(cx, cy)``, radius ``R``) in which no point in the disc is above ``z + CERT_SLACK``: ``out[0:4]`` = u
    from, u to, v from, v to. Returns whether one was found (a non-rational, non-periodic face whose rim
    function is concave enough there: tried on boxes of ``2 R``, ``R``, ``R / 2`` and ``R / 4`` mm in plan).
    ``ws``: scratch of at least ``CERT_SCRATCH`` floats (else made here)."""
    fi, ff, ust, hu, vst, hv, coef = S
    if fi[f, 7] or fi[f, 8]:
        return False
    p, q = fi[f, 0], fi[f, 1]
    uo, vo, nsu, nsv = fi[f, 4], fi[f, 5], fi[f, 2], fi[f, 3]
    i = _span(ust, uo, nsu, u)
    j = _span(vst, vo, nsv, v)
    h1, h2 = hu[uo + i], hv[vo + j]
    base = fi[f, 6] + (i * nsv + j) * (p + 1) * (q + 1) * 4
    for a in range(p + 1):  # a rational piece: no certificate
        for b in range(q + 1):
            if coef[base + (a * (q + 1) + b) * 4 + 3] != (1.0 if a == 0 and b == 0 else 0.0):
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
    L = ws[384:609].reshape((15, 15))
    L[: 2 * p + 1, : 2 * q + 1] = 0.0  # (the part read below)
    for a in range(p + 1):
        for b in range(q + 1):
            L[a, b] += Z[a, b]
            for a2 in range(p + 1):
                for b2 in range(q + 1):
                    L[a + a2, b + b2] -= 0.5 * mu * (X[a, b] * X[a2, b2] + Y[a, b] * Y[a2, b2])
    L[0, 0] += 0.5 * mu * R * R
    su, sv = hyp(X[1, 0], Y[1, 0]), hyp(X[0, 1], Y[0, 1])  # plan speeds per unit of the span's coordinates
    if not (su > 0 and sv > 0):
        return False
    for attempt in range(4):
        r_mm = 2 * R / (1 << attempt)
        rs, rt = r_mm / su, r_mm / sv
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
        if not (lam > 0 and K < 0.5 * lam):
            continue
        # L* above z, the linear terms' rise and the coefficients' rounding (1e-14 of their sum)
        e = max(L[0, 0] - z, 0.0) + g * g / (4 * (lam - K)) + 1e-14 * size
        if not (e <= CERT_SLACK):
            continue
        lo_u = -math.inf if i == 0 else ust[uo + i]  # the end pieces run on beyond the knots (extrapolated)
        hi_u = math.inf if i == nsu - 1 else ust[uo + i] + h1
        lo_v = -math.inf if j == 0 else vst[vo + j]
        hi_v = math.inf if j == nsv - 1 else vst[vo + j] + h2
        out[0], out[1] = max(u - rs * h1, lo_u), min(u + rs * h1, hi_u)
        out[2], out[3] = max(v - rt * h2, lo_v), min(v + rt * h2, hi_v)
        return True
    return False


@njit(cache=True, inline="always")
def boxed(cert, f, u, v, du, dv):
    """Whether the parameter box ``u +- du, v +- dv`` of face ``f`` lies in the certified box ``cert`` (face,
    u from, u to, v from, v to; face -1: none)."""
    return f == cert[0] and u - du >= cert[1] and u + du <= cert[2] and v - dv >= cert[3] and v + dv <= cert[4]
