"""Compiled (numba) geometry of the drop-cutter kernel: surface and trimming-curve evaluation, the cutter's
lower surface ``h(rho)``, parameter clamping and the trimmed-region test, one point at a time.

Each function mirrors a numpy function of :mod:`.solves` (and :class:`~machsurf_cad.geometry.atlas.SurfaceAtlas`,
:func:`~machsurf_cad.cutter_profiles.lower_height`, :meth:`~machsurf_cad.geometry.face.Face.contains_uv`) on
one point, with the same formulas, so both paths give the same numbers to rounding. The packed arrays they
read are built by :mod:`.compiled`. ``np.minimum``/``np.maximum`` propagate NaN where Python's ``min``/``max``
would drop it: :func:`nmin`/:func:`nmax` keep numpy's behaviour.
"""

from __future__ import annotations

import math

from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

# surface table S = (fi, ff, ust, hu, vst, hv, coef)
#   fi[f] = p, q, nsu, nsv, uoff, voff, coff, periodic_u, periodic_v, closed_u, closed_v, trimmed, loop0, loop1,
#           rational
#   ff[f] = a_u, b_u, a_v, b_v (power-data domain), period u0, u1, v0, v1, face box u0, u1, v0, v1
# curve table E = (ei, ef, knots, poles): ei[e] = degree, koff, nk, poff, npoles, face; ef[e] = t0, t1
# trim table T = (tf, tl, start, seg, tb): per face its slabs of v (first, count; v0, where its bounds start in
#   tb, v1), each slab's polygon edges (seg rows u0, v0, u1, v1 of its edges, CSR by start); tb the slabs'
#   bounds
# profile PR = (segs, consts, pieces): segs[s] = kind (0 line, 1 arc), 5 numbers; consts = R, h_R, h_min, monotone,
#   lower_height at R (h, h1, h2) and at 0; pieces from compiled._pieces


def _borrow(context, builder, ty, value):
    if isinstance(ty, types.Array):
        ary = context.make_array(ty)(context, builder, value=value)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        ary.parent = cgutils.get_null_value(ary.parent.type)
        return ary._getvalue()
    if isinstance(ty, types.BaseTuple):
        items = [_borrow(context, builder, t, builder.extract_value(value, i)) for i, t in enumerate(ty)]
        return context.make_tuple(builder, ty, items)
    return value


@intrinsic
def borrowed(typingctx, x):
    """``x`` (an array, or a tuple of arrays and numbers) without reference counts: the same data, shape and
    strides with a null meminfo, so that passing it to a function costs no atomic increment and decrement
    (profiled: a quarter of the kernel's samples, and cache-line contention between the threads). Only for arrays
    the caller keeps alive (the kernel's arguments)."""

    def codegen(context, builder, sig, args):
        return _borrow(context, builder, sig.args[0], args[0])

    return x(x), codegen


@njit(cache=True)
def keep(x):
    """Nothing: a use of ``x`` that keeps the arrays whose borrowed views (:func:`borrowed`) run before it
    alive until here (numba releases a variable after its last use)."""
    return None


@njit(cache=True, inline="always")
def nmin(a, b):
    if a != a or b != b:
        return math.nan
    return a if a < b else b


@njit(cache=True, inline="always")
def nmax(a, b):
    if a != a or b != b:
        return math.nan
    return a if a > b else b


@njit(cache=True, inline="always")
def nsign(x):
    if x > 0:
        return 1.0
    if x < 0:
        return -1.0
    return 0.0 if x == 0 else math.nan


@njit(cache=True, inline="always")
def isfin(x):
    return not (math.isinf(x) or math.isnan(x))


@njit(cache=True, inline="always")
def _wrap(x, x0, x1):
    p = x1 - x0
    w = (x - x0) % p
    if w >= p:
        w = 0.0
    return x0 + w


@njit(cache=True, inline="always")
def _span(keys, off, n, x):
    """Largest k in [0, n) with keys[off + k] <= x (0 below the first)."""
    if n <= 1 or x < keys[off + 1]:
        return 0
    hi = n - 1
    if x >= keys[off + hi]:
        return hi
    lo = 0
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if keys[off + mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, inline="always")
def _poly_sums(coef, base, p, q, order, n_out, out, wk):
    """:func:`surf`'s sums on a polynomial piece (power rows in ``wk``): first over v into ``wk[72:]``, then over
    u into ``out``. Inlined, so that a call with constant degrees has loops the compiler unrolls."""
    for a in range(p + 1):
        for kv in range(order + 1):
            x0 = x1 = x2 = 0.0
            for b in range(q + 1):
                w = wk[24 + 8 * kv + b]
                cb = base + (a * (q + 1) + b) * 4
                x0 += w * coef[cb]
                x1 += w * coef[cb + 1]
                x2 += w * coef[cb + 2]
            o = 72 + (a * 3 + kv) * 4
            wk[o], wk[o + 1], wk[o + 2] = x0, x1, x2
    for k in range(n_out):
        ku = 0 if k == 0 or k == 2 or k == 5 else (1 if k == 1 or k == 4 else 2)
        kv = 0 if k == 0 or k == 1 or k == 3 else (1 if k == 2 or k == 4 else 2)
        x0 = x1 = x2 = 0.0
        for a in range(p + 1):
            w = wk[8 * ku + a]
            o = 72 + (a * 3 + kv) * 4
            x0 += w * wk[o]
            x1 += w * wk[o + 1]
            x2 += w * wk[o + 2]
        out[k, 0], out[k, 1], out[k, 2] = x0, x1, x2


@njit(cache=True)
def surf(S, f, u, v, order, out, wk):
    """Point and derivatives of face ``f`` at ``(u, v)`` into ``out`` rows P, Su, Sv, Suu, Suv, Svv (as many
    as ``order`` asks); ``wk`` is scratch of 168 floats."""
    fi, ff, ust, hu, vst, hv, coef = S
    p, q = fi[f, 0], fi[f, 1]
    if fi[f, 7]:
        u = _wrap(u, ff[f, 4], ff[f, 5])
    if fi[f, 8]:
        v = _wrap(v, ff[f, 6], ff[f, 7])
    uo, vo = fi[f, 4], fi[f, 5]
    i = _span(ust, uo, fi[f, 2], u)
    j = _span(vst, vo, fi[f, 3], v)
    h1, h2 = hu[uo + i], hv[vo + j]
    s = (u - ust[uo + i]) / h1
    t = (v - vst[vo + j]) / h2
    # power rows: wk[0:8] x^a, wk[8:16] d/du, wk[16:24] d2/du2; the same for v at 24
    for a in range(24 + 24):
        wk[a] = 0.0
    wk[0] = 1.0
    for a in range(1, p + 1):
        wk[a] = wk[a - 1] * s
    wk[24] = 1.0
    for b in range(1, q + 1):
        wk[24 + b] = wk[24 + b - 1] * t
    if order >= 1:
        for a in range(1, p + 1):
            wk[8 + a] = wk[a - 1] * a / h1
        for b in range(1, q + 1):
            wk[32 + b] = wk[24 + b - 1] * b / h2
    if order >= 2:
        for a in range(2, p + 1):
            wk[16 + a] = wk[a - 2] * (a * (a - 1)) / (h1 * h1)
        for b in range(2, q + 1):
            wk[40 + b] = wk[24 + b - 2] * (b * (b - 1)) / (h2 * h2)
    # A[a, kv, :] = sum_b rv[kv, b] C[a, b, :] at wk[72:168], then H[ku, kv] = sum_a ru[ku, a] A[a, kv]
    base = fi[f, 6] + (i * fi[f, 3] + j) * (p + 1) * (q + 1) * 4
    n_out = 1 if order == 0 else (3 if order == 1 else 6)
    if fi[f, 14] == 0:  # polynomial: the weights' sums are 1 and 0, the division below the same numbers
        if p == 3 and q == 3:  # bicubic (most faces): the same sums with constant bounds, unrolled by the compiler
            _poly_sums(coef, base, 3, 3, order, n_out, out, wk)
        else:
            _poly_sums(coef, base, p, q, order, n_out, out, wk)
        return
    for a in range(p + 1):
        for kv in range(order + 1):
            x0 = x1 = x2 = x3 = 0.0
            for b in range(q + 1):
                w = wk[24 + 8 * kv + b]
                cb = base + (a * (q + 1) + b) * 4
                x0 += w * coef[cb]
                x1 += w * coef[cb + 1]
                x2 += w * coef[cb + 2]
                x3 += w * coef[cb + 3]
            o = 72 + (a * 3 + kv) * 4
            wk[o], wk[o + 1], wk[o + 2], wk[o + 3] = x0, x1, x2, x3
    for k in range(n_out):
        ku = 0 if k == 0 or k == 2 or k == 5 else (1 if k == 1 or k == 4 else 2)
        kv = 0 if k == 0 or k == 1 or k == 3 else (1 if k == 2 or k == 4 else 2)
        x0 = x1 = x2 = x3 = 0.0
        for a in range(p + 1):
            w = wk[8 * ku + a]
            o = 72 + (a * 3 + kv) * 4
            x0 += w * wk[o]
            x1 += w * wk[o + 1]
            x2 += w * wk[o + 2]
            x3 += w * wk[o + 3]
        wk[48 + 4 * k], wk[49 + 4 * k], wk[50 + 4 * k], wk[51 + 4 * k] = x0, x1, x2, x3
    # rational: The NURBS Book A4.4 (keys 0:(0,0) 1:(1,0) 2:(0,1) 3:(2,0) 4:(1,1) 5:(0,2))
    w0 = wk[48 + 3]
    for d in range(3):
        out[0, d] = wk[48 + d] / w0
    if order >= 1:
        w10, w01 = wk[48 + 7], wk[48 + 11]
        for d in range(3):
            out[1, d] = (wk[52 + d] - w10 * out[0, d]) / w0
            out[2, d] = (wk[56 + d] - w01 * out[0, d]) / w0
        if order >= 2:
            w20, w11, w02 = wk[48 + 15], wk[48 + 19], wk[48 + 23]
            for d in range(3):
                out[3, d] = (wk[60 + d] - 2 * w10 * out[1, d] - w20 * out[0, d]) / w0
                out[5, d] = (wk[68 + d] - 2 * w01 * out[2, d] - w02 * out[0, d]) / w0
                out[4, d] = (wk[64 + d] - w10 * out[2, d] - w01 * out[1, d] - w11 * out[0, d]) / w0


@njit(cache=True)
def _curve_uv(E, e, x, order, cu, wk):
    """``(u, v)`` of trimming curve ``e`` at ``x`` and its derivatives into ``cu`` rows 0..order
    (The NURBS Book A2.3 on the flat knots, rational by A4.2); ``wk`` scratch of 200 floats."""
    ei, ef, knots, poles = E
    p, ko, nk, po, npol = ei[e, 0], ei[e, 1], ei[e, 2], ei[e, 3], ei[e, 4]
    n = npol
    # span: clip(searchsorted(t, x, right) - 1, p, n - 1)
    lo, hi = 0, nk
    while lo < hi:
        mid = (lo + hi) // 2
        if knots[ko + mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    sp = lo - 1
    if sp < p:
        sp = p
    if sp > n - 1:
        sp = n - 1
    # ndu (p+1)x(p+1) at wk[0:], left/right at wk[100:], ders at wk[140:] (3 x (p+1))
    P1 = p + 1
    for a in range(P1 * P1):
        wk[a] = 0.0
    wk[0] = 1.0
    for j in range(1, p + 1):
        wk[100 + j] = x - knots[ko + sp + 1 - j]
        wk[120 + j] = knots[ko + sp + j] - x
        saved = 0.0
        for r in range(j):
            wk[j * P1 + r] = wk[120 + r + 1] + wk[100 + j - r]
            temp = wk[r * P1 + j - 1] / wk[j * P1 + r]
            wk[r * P1 + j] = saved + wk[120 + r + 1] * temp
            saved = wk[100 + j - r] * temp
        wk[j * P1 + j] = saved
    for a in range(140, 140 + 3 * P1):
        wk[a] = 0.0
    for j in range(P1):
        wk[140 + j] = wk[j * P1 + p]
    nd = order if order < p else p
    if nd > 0:
        # a[2][p+1] at wk[170:]
        for r in range(P1):
            s1, s2 = 0, 1
            for a in range(2 * P1):
                wk[170 + a] = 0.0
            wk[170] = 1.0
            for k in range(1, nd + 1):
                d = 0.0
                rk, pk = r - k, p - k
                if r >= k:
                    wk[170 + s2 * P1] = wk[170 + s1 * P1] / wk[(pk + 1) * P1 + rk]
                    d = wk[170 + s2 * P1] * wk[rk * P1 + pk]
                j1 = 1 if rk >= -1 else -rk
                j2 = k - 1 if r - 1 <= pk else p - r
                for j in range(j1, j2 + 1):
                    wk[170 + s2 * P1 + j] = (wk[170 + s1 * P1 + j] - wk[170 + s1 * P1 + j - 1]) / wk[
                        (pk + 1) * P1 + rk + j
                    ]
                    d += wk[170 + s2 * P1 + j] * wk[(rk + j) * P1 + pk]
                if r <= pk:
                    wk[170 + s2 * P1 + k] = -wk[170 + s1 * P1 + k - 1] / wk[(pk + 1) * P1 + r]
                    d += wk[170 + s2 * P1 + k] * wk[r * P1 + pk]
                wk[140 + k * P1 + r] = d
                s1, s2 = s2, s1
        fac = float(p)
        for k in range(1, nd + 1):
            for j in range(P1):
                wk[140 + k * P1 + j] *= fac
            fac *= p - k
    # homogeneous (u w, v w, w) derivatives, then rational
    for k in range(order + 1):
        a0 = a1 = a2 = 0.0
        for j in range(P1):
            b = wk[140 + k * P1 + j]
            row = po + sp - p + j
            a0 += b * poles[row, 0]
            a1 += b * poles[row, 1]
            a2 += b * poles[row, 2]
        cu[k, 0], cu[k, 1], cu[k, 2] = a0, a1, a2
    w0 = cu[0, 2]
    cu[0, 0] /= w0
    cu[0, 1] /= w0
    if order >= 1:
        w1 = cu[1, 2]
        cu[1, 0] = (cu[1, 0] - w1 * cu[0, 0]) / w0
        cu[1, 1] = (cu[1, 1] - w1 * cu[0, 1]) / w0
        if order >= 2:
            w2 = cu[2, 2]
            cu[2, 0] = (cu[2, 0] - 2 * w1 * cu[1, 0] - w2 * cu[0, 0]) / w0
            cu[2, 1] = (cu[2, 1] - 2 * w1 * cu[1, 1] - w2 * cu[0, 1]) / w0


@njit(cache=True)
def edge_derivs(S, E, e, x, order, out, cu, wk):
    """Surface point of edge ``e`` at ``x`` into ``out[0]`` and its first (second) derivatives in ``x`` into
    ``out[1]`` (``out[2]``); ``out`` rows 3.. are scratch for the surface's derivatives. A closed edge's
    parameter runs on across its seam."""
    if E[0][e, 6] == 1:
        lo, hi = E[1][e, 0], E[1][e, 1]
        x = lo + (x - lo) % (hi - lo)
    _curve_uv(E, e, x, order, cu, wk)
    f = E[0][e, 5]
    # surface derivatives into out[3:9] via a view
    sd = out[3:9]
    surf(S, f, cu[0, 0], cu[0, 1], order, sd, wk[200:])
    for d in range(3):
        out[0, d] = sd[0, d]
    if order >= 1:
        du, dv = cu[1, 0], cu[1, 1]
        for d in range(3):
            out[1, d] = sd[1, d] * du + sd[2, d] * dv
        if order >= 2:
            ddu, ddv = cu[2, 0], cu[2, 1]
            for d in range(3):
                out[2, d] = (
                    sd[3, d] * du * du + 2 * sd[4, d] * du * dv + sd[5, d] * dv * dv + sd[1, d] * ddu + sd[2, d] * ddv
                )


# ----------------------------------------------------------------------------- the cutter's lower surface
@njit(cache=True)
def _angle_in(ang, a0, a1):
    lo, hi = min(a0, a1), max(a0, a1)
    for sh in (0.0, 360.0, -360.0):
        if ang + sh >= lo - 1e-9 and ang + sh <= hi + 1e-9:
            return True
    return False


@njit(cache=True)
def lower_height(segs, rho):
    """``h, h', h''`` of the lowest profile segment at ``rho`` (:func:`~machsurf_cad.cutter_profiles.lower_height`)."""
    h, h1, h2, _, _ = lowest_segment(segs, rho)
    return h, h1, h2


@njit(cache=True)
def lowest_segment(segs, rho):
    """:func:`lower_height` with the row of ``segs`` it takes and the arc's branch (-1 lower, 1 upper, 0 a
    line; row -1 where no segment reaches ``rho``)."""
    rho = abs(rho)
    h, h1, h2 = math.inf, 0.0, 0.0
    who, branch = -1, 0.0
    for s in range(segs.shape[0]):
        if segs[s, 0] == 0.0:
            r0, z0, r1, z1 = segs[s, 1], segs[s, 2], segs[s, 3], segs[s, 4]
            if abs(r1 - r0) < 1e-15:
                continue
            lo, hi = min(r0, r1), max(r0, r1)
            if rho >= lo - 1e-12 and rho <= hi + 1e-12:
                z = z0 + (rho - r0) / (r1 - r0) * (z1 - z0)
                if z < h:
                    h, h1, h2 = z, (z1 - z0) / (r1 - r0), 0.0
                    who, branch = s, 0.0
            continue
        rc, zc, r, a0, a1 = segs[s, 1], segs[s, 2], segs[s, 3], segs[s, 4], segs[s, 5]
        dx = rho - rc
        if abs(dx) > r + 1e-12:
            continue
        root = math.sqrt(max(r * r - dx * dx, 0.0))
        for sgn in (-1.0, 1.0):
            z = zc + sgn * root
            if z < h and _angle_in(math.degrees(math.atan2(z - zc, dx)), a0, a1):
                safe = max(root, 1e-8 * r)
                h = z
                h1 = min(max(-sgn * dx / safe, -1e8), 1e8)
                h2 = min(max(-sgn * r * r / safe**3, -1e8), 1e8)
                who, branch = s, sgn
    return h, h1, h2, who, branch


@njit(cache=True, inline="always")
def piece_height(tb, rho):
    """``lower_height`` from the profile's pieces (:func:`.compiled._pieces`): ``h, h', h''`` and whether
    ``rho`` lies inside a piece (more than :data:`PIECE_MARGIN` from its ends; else the caller runs
    ``lower_height``). The same formulas as ``lower_height`` for the segment that is lowest on the piece, so
    the same numbers, without its search over the segments and their arcs' angles."""
    for i in range(tb.shape[0]):
        if rho > tb[i, 0] + PIECE_MARGIN and rho < tb[i, 1] - PIECE_MARGIN:
            kind = tb[i, 2]
            if kind == 0.0:
                r0, z0, r1, z1 = tb[i, 3], tb[i, 4], tb[i, 5], tb[i, 6]
                return z0 + (rho - r0) / (r1 - r0) * (z1 - z0), (z1 - z0) / (r1 - r0), 0.0, True
            if kind == 1.0:
                rc, zc, r, sgn = tb[i, 3], tb[i, 4], tb[i, 5], tb[i, 6]
                dx = rho - rc
                root = math.sqrt(max(r * r - dx * dx, 0.0))
                safe = max(root, 1e-8 * r)
                h1 = min(max(-sgn * dx / safe, -1e8), 1e8)
                return zc + sgn * root, h1, min(max(-sgn * r * r / safe**3, -1e8), 1e8), True
            return math.inf, 0.0, 0.0, True
    return math.inf, 0.0, 0.0, False


PIECE_MARGIN = 1e-9
"""Within this distance (mm) of a piece's ends the profile is evaluated by ``lower_height`` itself."""


@njit(cache=True, inline="always")
def prof(PR, rho):
    """The profile's ``h, h', h''`` at ``rho``: ``inf`` beyond the rim, ``h(R)`` where no segment reaches
    (``_Profile.__call__``)."""
    segs, k, tb = PR
    R = k[0]
    x = nmin(rho, R)
    if x == R:  # lower_height at the rim and at the axis, computed once (compiled._profile)
        h, h1, h2, ok = k[4], k[5], k[6], True
    elif x == 0.0:
        h, h1, h2, ok = k[7], k[8], k[9], True
    else:
        h, h1, h2, ok = piece_height(tb, abs(x))
    if not ok:
        h, h1, h2 = lower_height(segs, x)
    if rho <= R * (1 + 1e-12):
        if not isfin(h):
            h = k[1]
    else:
        h = math.inf
    return h, h1, h2


@njit(cache=True, inline="always")
def prof_floor(PR, rho):
    """A lower bound of ``h`` on ``[rho, R]`` (``_Profile.floor``); ``h_min`` itself where the profile is not
    monotone or is level from its lowest point to the rim (a flat end: ``h_min == h_R``)."""
    k = PR[1]
    if k[3] == 0.0 or k[2] == k[1]:
        return k[2]
    return prof(PR, min(max(rho, 0.0), k[0]))[0]


# ----------------------------------------------------------------------------- parameters and trims
@njit(cache=True, inline="always")
def clamp_uv(S, f, u, v):
    """``_clamp_uv``: wrapped across a closed face's seam, clamped to the face's box elsewhere."""
    fi, ff = S[0], S[1]
    u0, u1, v0, v1 = ff[f, 8], ff[f, 9], ff[f, 10], ff[f, 11]
    if fi[f, 9]:
        pu = u1 - u0
        u = u0 + ((u - u0) % pu)
    else:
        u = min(max(u, u0), u1)
    if fi[f, 10]:
        pv = v1 - v0
        v = v0 + ((v - v0) % pv)
    else:
        v = min(max(v, v0), v1)
    return u, v


@njit(cache=True)
def inside(S, T, f, u, v):
    """``_inside``: the face's box (untrimmed) or the even-odd rule on its trimming polygons."""
    fi, ff = S[0], S[1]
    if not (u == u and v == v):
        return False
    if fi[f, 11] == 0:
        u0, u1, v0, v1 = ff[f, 8], ff[f, 9], ff[f, 10], ff[f, 11]
        tol = 1e-12 * max(u1 - u0, v1 - v0, 1.0)
        return u >= u0 - tol and u <= u1 + tol and v >= v0 - tol and v <= v1 + tol
    tf, tl, start, seg, tb = T
    s0, ns = tf[f, 0], tf[f, 1]
    if not (v > tl[f, 0] and v <= tl[f, 2]):
        return False
    b0 = int(tl[f, 1])
    lo, hi = 0, ns - 1  # the slab (b_k, b_k+1] of v: the first k with b_k+1 >= v
    while lo < hi:
        mid = (lo + hi) // 2
        if tb[b0 + mid + 1] >= v:
            hi = mid
        else:
            lo = mid + 1
    k = lo
    flip = False
    for i in range(start[s0 + k], start[s0 + k + 1]):
        x0, y0, x1, y1 = seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3]
        if y0 == y1:
            continue
        if min(y0, y1) < v <= max(y0, y1):  # as _points_in_polygons: lo < v <= hi
            xint = x0 + (v - y0) * (x1 - x0) / (y1 - y0)
            if u < xint:
                flip = not flip
    return flip


@njit(cache=True, inline="always")
def hyp(x, y):
    """``hypot(x, y)`` for the kernel's plan distances (mm, far from overflow): the square root of the sum of
    squares, within two units in the last place of libm's ``hypot`` (which the numpy path's ``np.hypot`` calls)
    and a third of its cost (profiled: 3 % of the kernel's time in ``hypot``)."""
    return math.sqrt(x * x + y * y)


@njit(cache=True, inline="always")
def norm3(x, y, z):
    return math.sqrt(x * x + y * y + z * z)
