"""Compiled (numba) drop-cutter query: the branch and bound of :func:`.dropcutter._drop_chunk` for one
query point at a time, in parallel over the points.

The seeds, groups, bounds and phases are those of the numpy path (see its docstring): per query, the pool
samples within ``R + spacing`` of the axis (a plan grid instead of the k-d tree), the best sample as a lower
bound, per (face, sector) group the best face seed, rim seeds and per (edge, sector, inside) the edge seeds;
phase 1 solves the best face and rim seed, phase 2 every seed whose group bound still reaches the best
height found, then up to four rounds of further face seeds and the circles where the profile's slope jumps.
The local solves are the scalar forms in :mod:`._jit_solve`. Unlike the numpy path, the kernel drops the
gathered samples whose every bound is below the height a sample inside the disc already lifts the tool to
(:func:`_prune`), and skips a face or rim seed when the fine cells (:mod:`.cells`) of its group bound it
below the best height: the same answer with about half the local solves. When the first phase ends on a
flat end's rim contact, its certificate (:mod:`._jit_cert`: a parameter box in which no point inside the
disc is higher) leaves out of every bound the seed samples and fine samples whose grid neighbourhoods lie in
the box, so the other sectors' seeds no longer climb back to the same contact.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._jit_cert import CERT_SCRATCH, boxed, rim_certificate
from ._jit_geom import borrowed, hyp, inside, isfin, keep, norm3, prof, prof_floor, surf
from ._jit_solve import ON_CIRCLE, edge_search, enters_face, face_newton, into_disc, rim_ascent, tip_solve

FACE, RIM, EDGE, TIP, SAMPLE = 1, 2, 3, 4, 5

BOUND_TIE = 1e-10
"""Phase 2 solves a seed only when its group's bound is above the best height by more than this (mm): a bound
that only ties the best (a flat end on a horizontal floor: the floor's edges and rim at the floor's height)
cannot raise it by more (the numpy path's ``_BOUND_TIE_MM``)."""

KERNEL_SOURCES = "6cb2c16c3106aa88"
""":func:`.compiled.kernel_stamp` of the callees' sources: changing them changes this file, so that numba's
cache (keyed by this file's stamp) compiles the kernel again (checked by a test)."""


@njit(cache=True)
def _add(best, bp, g, kind, f, x, y, z, e=-1):
    """Keep the highest value (a bare sample ranks 1e-12 relative below a solved contact of equal value);
    ``best`` = (rank, height, kind, face, found, edge or -1)."""
    if not isfin(g):
        return
    rank = g - (1e-12 * (1 + abs(g)) if kind == SAMPLE else 0.0)
    if best[4] == 0.0 or rank > best[0]:
        best[0], best[1], best[2], best[3], best[4], best[5] = rank, g, kind, f, 1.0, e
        bp[0], bp[1], bp[2] = x, y, z


@njit(cache=True, inline="always")
def _beats(best, g):
    """Whether a solved contact of value ``g`` would enter ``best`` (:func:`_add`): the trimming and circle
    tests of a contact that cannot are skipped."""
    return isfin(g) and (best[4] == 0.0 or g > best[0])


@njit(cache=True)
def _solve(kind, j, cx, cy, S, E, T, PR, SM, K, W, best, bp, rk, hk):
    """One local solve of ``kind`` (FACE, RIM, EDGE) from pool sample ``j``; the candidate into ``best``."""
    pf, puv = SM[1], SM[2]
    R, sp = K[0], K[1]
    f = pf[j]
    u0, v0 = puv[j, 0], puv[j, 1]
    D = W[0]
    if kind == FACE:
        surf(S, f, u0, v0, 0, D, W[5])
        n_starts = 1
        ua, va = u0, v0
        if hyp(D[0, 0] - cx, D[0, 1] - cy) > R * (1 - 1e-3):  # as _solve: onto the circle, and further in
            ua, va = into_disc(S, sp, R, cx, cy, f, u0, v0, W, False)
            n_starts = 2
        for s in range(n_starts):
            us, vs = (ua, va) if s == 0 else into_disc(S, sp, R, cx, cy, f, u0, v0, W, True)
            u, v, g = face_newton(S, PR, sp, cx, cy, f, us, vs, W)
            if _beats(best, g) and inside(S, T, f, u, v) and enters_face(S, T, R, cx, cy, f, u, v, W):
                _add(best, bp, g, FACE, f, D[0, 0], D[0, 1], D[0, 2])
        u0, v0 = ua, va
        if K[4] > 0:
            u, v, ok = tip_solve(S, cx, cy, f, u0, v0, W)
            g = D[0, 2] - K[7]
            if ok and _beats(best, g) and inside(S, T, f, u, v):
                _add(best, bp, g, TIP, f, D[0, 0], D[0, 1], D[0, 2])
    elif kind == RIM:
        u, v, g = rim_ascent(S, sp, rk, hk, cx, cy, f, u0, v0, W)
        if _beats(best, g) and inside(S, T, f, u, v) and enters_face(S, T, R, cx, cy, f, u, v, W):
            _add(best, bp, g, RIM, f, D[0, 0], D[0, 1], D[0, 2])
            best[6], best[7] = u, v  # (the rim certificate's start)
    else:
        k = j - SM[3]
        g = edge_search(S, E, PR, cx, cy, SM[4][k], SM[5][k], SM[6][k], W, SM[18], k)
        Ed = W[3]
        _add(best, bp, g, EDGE, f, Ed[0, 0], Ed[0, 1], Ed[0, 2], SM[4][k])


@njit(cache=True, inline="always")
def _column(i, j0, j1, cx, cy, rq, x0, y0, cs):
    """The cells ``j0..j1`` of grid column ``i`` that reach within ``rq`` of ``(cx, cy)``: a sample of the column
    within ``rq`` lies within the disc's half chord at the column's nearest x (widened by 1e-6 ``rq``, far more
    than a rounding of the sample's column or distance can move it there)."""
    dx = max(0.0, x0 + i * cs - cx, cx - (x0 + (i + 1) * cs))
    if dx > rq * (1 + 1e-9):
        return 1, 0
    h = math.sqrt(max(rq * rq - dx * dx, 0.0)) + 1e-6 * rq
    return max(j0, int(math.floor((cy - h - y0) / cs))), min(j1, int(math.floor((cy + h - y0) / cs)))


@njit(cache=True)
def _gather(cx, cy, rq, xyz, G, h_R, h_min, inner):
    """Pool samples within ``rq`` of ``(cx, cy)`` in plan (the grid's cells that reach the disc): indices and
    distances, in the grid's order (cell by cell, each cell's by pool index). With ``h_R`` (a profile that rises to its
    rim; else NaN), ``h_min`` and ``inner = R (1 - ON_CIRCLE)``, a cell is read from its highest ``top`` down
    only while that reaches :func:`_prune`'s ``low`` of the samples read so far (which only grows). The rest
    would be pruned and raise no ``low`` (``top`` is at least z), so :func:`_prune` keeps the same samples."""
    meta, dims, start, items, top = G
    x0, y0, cs = meta[0], meta[1], meta[2]
    nx, ny = dims[0], dims[1]
    i0 = max(int(math.floor((cx - rq - x0) / cs)), 0)
    i1 = min(int(math.floor((cx + rq - x0) / cs)), nx - 1)
    j0 = max(int(math.floor((cy - rq - y0) / cs)), 0)
    j1 = min(int(math.floor((cy + rq - y0) / cs)), ny - 1)
    count = 0
    for i in range(i0, i1 + 1):
        a, b = _column(i, j0, j1, cx, cy, rq, x0, y0, cs)
        count += start[i * ny + b + 1] - start[i * ny + a] if b >= a else 0
    idx = np.empty(max(count, 0), np.int64)
    rr = np.empty(max(count, 0))
    rising = h_R == h_R
    lowz = -math.inf  # _prune's: the highest z - h_R strictly inside the disc
    low = -math.inf  # and its low
    m = 0
    for i in range(i0, i1 + 1):
        a, b = _column(i, j0, j1, cx, cy, rq, x0, y0, cs)
        for c in range(i * ny + a, i * ny + b + 1):
            m0 = m
            for k in range(start[c], start[c + 1]):
                if top[k] < low:  # (so are the rest of the cell's)
                    break
                jj = items[k]
                dx, dy = xyz[jj, 0] - cx, xyz[jj, 1] - cy
                rho = math.sqrt(dx * dx + dy * dy)
                if rho <= rq:
                    idx[m] = jj
                    rr[m] = rho
                    m += 1
                    z = xyz[jj, 2] - h_R
                    if rising and rho < inner and z > lowz:  # (a NaN sample raises nothing)
                        lowz = z
                        low = lowz + (h_min - 1e-9)
            for a in range(m0 + 1, m):  # the cell's samples by pool index (insertion sort: a few)
                ja, ra = idx[a], rr[a]
                b = a - 1
                while b >= m0 and idx[b] > ja:
                    idx[b + 1], rr[b + 1] = idx[b], rr[b]
                    b -= 1
                idx[b + 1], rr[b + 1] = ja, ra
    return idx[:m], rr[:m]


@njit(cache=True)
def _prune(idx, rr, SM, K, PR):
    """The gathered samples without those whose every bound is below a height the tool is known to reach: a
    sample strictly inside the disc lifts the tool to at least ``z - h(R)`` (a profile that rises to its
    rim), and a sample whose ``z + rise`` (face or edge) less the profile's lowest point ``h_min`` (below
    zero for a tip under the reference point) is below that, less 1e-9 mm, can neither bound nor seed a
    higher contact. The order of the rest is kept. On stacked faces (a propeller's blades one above the
    other, a mould's floors and walls below its top) most of the gathered samples go."""
    m = idx.shape[0]
    if m == 0 or PR[1][3] == 0.0:  # a profile that does not rise to its rim: no such height
        return idx, rr
    xyz, rise, erise, n_int = SM[0], SM[8], SM[17], SM[3]
    R, h_R, h_min = K[0], K[3], PR[1][2]
    low = -math.inf
    for k in range(m):
        z = xyz[idx[k], 2] - h_R
        if rr[k] < R * (1 - ON_CIRCLE) and z > low:  # (a NaN sample raises nothing)
            low = z
    low += h_min - 1e-9  # a sample is kept when z + rise - h_min reaches the known height (less 1e-9 mm)
    n = 0
    for k in range(m):
        j = idx[k]
        r = rise[j] if j < n_int else max(rise[j], erise[j - n_int])
        if xyz[j, 2] + r >= low:
            idx[n], rr[n] = j, rr[k]
            n += 1
    return idx[:n], rr[:n]


@njit(cache=True)
def _group_best(n_groups, key, score, sel, idx):
    """Per group the candidate of highest ``score`` among ``sel`` (on ties the smallest pool index ``idx``, as
    the numpy path's ``_best_per``); -1 where none."""
    return _group_best_into(np.empty(n_groups, np.int64), key, score, sel, idx)


@njit(cache=True)
def _group_best_into(out, key, score, sel, idx):
    """:func:`_group_best` into ``out`` (its groups)."""
    out[:] = -1
    for k in range(key.shape[0]):
        if sel[k]:
            _pick(out, key[k], k, score, idx)
    return out


@njit(cache=True, inline="always")
def _pick(out, g, k, score, idx):
    """Candidate ``k`` into group ``g`` of ``out`` where it beats the group's: the higher ``score``, on ties the
    smaller pool index ``idx`` (the numpy path's ``_best_per``)."""
    o = out[g]
    if o < 0 or score[k] > score[o] or (score[k] == score[o] and idx[k] < idx[o]):
        out[g] = k


@njit(cache=True)
def _bounds(fb, rb, eb, gk, ek, ub, rim_ub, e_ub, is_e, free):
    """The groups' face and rim bounds over the samples ``free`` (all where ``free`` is empty) and the edge
    groups' bounds over the edge samples: per group the largest of each, in one pass."""
    fb[:] = -math.inf
    rb[:] = -math.inf
    eb[:] = -math.inf
    every = free.shape[0] == 0
    for k in range(gk.shape[0]):
        if every or free[k]:
            g = gk[k]
            if ub[k] > fb[g]:
                fb[g] = ub[k]
            if rim_ub[k] > rb[g]:
                rb[g] = rim_ub[k]
        if is_e[k] and e_ub[k] > eb[ek[k]]:
            eb[ek[k]] = e_ub[k]


@njit(cache=True)
def _best_of(score, sel, idx):
    """``_group_best`` of one group holding every candidate: the index of the highest ``score`` among ``sel``
    (ties: the smallest ``idx``), -1 where none."""
    out = -1
    for k in range(score.shape[0]):
        if sel[k] and (out < 0 or score[k] > score[out] or (score[k] == score[out] and idx[k] < idx[out])):
            out = k
    return out


@njit(cache=True)
def _candidates(cx, cy, idx, rr, PR, SM, K):
    """Per pool sample in reach of the query: value ``z - h(rho)``, z, ``-rho``, the bounds of its face
    (``ub``), rim (``rim_ub``) and edge (``e_ub``) neighbourhoods, inside the disc, an edge sample, its
    (face, sector) group and (edge, sector, inside) group, and the numbers of faces and edges met."""
    xyz, pf, n_int = SM[0], SM[1], SM[3]
    cov, rise, ecov = SM[7], SM[8], SM[10]
    R, h_R = K[0], K[3]
    m = idx.shape[0]
    # four allocations instead of twelve (each costs about as much as a sample's bounds)
    maps = np.full(int(K[5]) + int(K[6]), -1, np.int64)
    fmap, emap = maps[: int(K[5])], maps[int(K[5]) :]
    nl = ne = 0
    F = np.empty((6, m))
    val, zz, negr, ub, rim_ub, e_ub = F[0], F[1], F[2], F[3], F[4], F[5]
    e_ub[:] = -math.inf
    level = PR[1][2] == h_R  # (a flat end: h = h_R on the whole disc, no profile call in the loop)
    B = np.empty((2, m), np.bool_)
    feas, is_e = B[0], B[1]
    I_ = np.zeros((2, m), np.int64)
    gk, ek = I_[0], I_[1]
    for k in range(m):
        j = idx[k]
        rho = rr[k]
        z = xyz[j, 2]
        zz[k], negr[k] = z, -rho
        val[k] = z - (h_R if level else prof(PR, min(rho, R))[0])
        feas[k] = rho <= R
        dx, dy = xyz[j, 0] - cx, xyz[j, 1] - cy
        sector = 0  # the centre, else the quadrant (as the numpy path's _seeds)
        if not (rho < 0.5 * R):
            sector = (1 if dx < 0 else 2) if dy < 0 else (3 if dx > 0 else 4)
        f = pf[j]
        if fmap[f] < 0:
            fmap[f] = nl
            nl += 1
        gk[k] = fmap[f] * 5 + sector
        reach = rho - cov[j]
        ub[k] = z + rise[j] - (h_R if level else prof_floor(PR, reach)) if reach <= R else -math.inf
        rim_ub[k] = z + rise[j] - h_R if abs(rho - R) <= cov[j] else -math.inf
        is_e[k] = j >= n_int
        if is_e[k]:
            e = SM[4][j - n_int]
            if emap[e] < 0:
                emap[e] = ne
                ne += 1
            ek[k] = (emap[e] * 5 + sector) * 2 + (1 if feas[k] else 0)
            ec = ecov[j - n_int]
            if rho - ec <= R:
                e_ub[k] = z + SM[17][j - n_int] - (h_R if level else prof_floor(PR, rho - ec))
    return val, zz, negr, ub, rim_ub, e_ub, feas, is_e, gk, ek, nl, ne


@njit(cache=True)
def _seed_sets(idx, rr, val, zz, negr, feas, is_e, gk, ek, ng, n_eg, SM, K, P, out):
    """Face seeds (per group the best sample inside the disc, an edge sample where the face has none, else
    the sample nearest the disc within its cover radius outside it; none steeper than the profile), rim
    seeds (the highest near the rim inside, the nearest outside) and edge seeds, as masks (into ``out``, 3 x m;
    ``P``: scratch of ``5 ng + 2 n_eg``)."""
    cov, tilt = SM[7], SM[9]
    R, max_tilt = K[0], K[2]
    m = idx.shape[0]
    # the seven picks' groups in one pass (each group's pick as _group_best_into's: the samples in their
    # order, the highest score, ties to the smallest pool index)
    P[:] = -1
    e0 = 5 * ng
    for k in range(m):
        c = cov[idx[k]]
        f_, e_, g = feas[k], is_e[k], gk[k]
        if f_:
            _pick(P, g if not e_ else ng + g, k, val, idx)
            if rr[k] >= R - c:  # near the rim inside
                _pick(P, 3 * ng + g, k, zz, idx)
        else:
            if rr[k] - c <= R:  # outside the disc, within the cover
                _pick(P, 2 * ng + g, k, negr, idx)
            if rr[k] <= R + c:  # near the rim outside
                _pick(P, 4 * ng + g, k, negr, idx)
        if e_:
            if f_:
                _pick(P, e0 + ek[k], k, val, idx)
            else:
                _pick(P, e0 + n_eg + ek[k], k, negr, idx)
    seed, s2, s3 = P[:ng], P[ng : 2 * ng], P[2 * ng : 3 * ng]
    out[:] = False
    is_seed, rseed, eseed = out[:m], out[m : 2 * m], out[2 * m :]
    for g in range(ng):
        s = seed[g] if seed[g] >= 0 else (s2[g] if s2[g] >= 0 else s3[g])
        if s >= 0 and tilt[idx[s]] <= max_tilt + 1e-9:
            is_seed[s] = True
    for i in range(3 * ng, e0):
        if P[i] >= 0:
            rseed[P[i]] = True
    for i in range(e0, e0 + 2 * n_eg):
        if P[i] >= 0:
            eseed[P[i]] = True
    return is_seed, rseed, eseed


@njit(cache=True)
def _query(cx, cy, S, E, T, PR, SM, G, K, kinks, best, bp, W):
    """The tip height at one query point: ``best`` = (rank, height, kind, face, found), ``bp`` the contact;
    ``W`` the solves' scratch (:mod:`._jit_solve`: nothing in it is read before it is written)."""
    # every array passed on is borrowed (no reference counting: a quarter of the samples, profiled): the
    # arguments are kept alive by the caller, the arrays made here by ``keep`` at the end
    S, E, T, PR, SM, G, K, kinks, best, bp, W = borrowed((S, E, T, PR, SM, G, K, kinks, best, bp, W))
    xyz, pf = SM[0], SM[1]
    R, h_R = K[0], K[3]
    best[4] = 0.0
    got = _gather(cx, cy, K[8], xyz, G, h_R if PR[1][3] != 0.0 else math.nan, PR[1][2], R * (1 - ON_CIRCLE))
    idx, rr = borrowed(got)
    idx, rr = _prune(idx, rr, SM, K, PR)
    m = idx.shape[0]
    if m == 0:
        return
    cand = _candidates(cx, cy, idx, rr, PR, SM, K)
    val, zz, negr, ub, rim_ub, e_ub, feas, is_e, gk, ek, nl, ne = borrowed(cand)
    ng, n_eg = nl * 5, ne * 10
    # the best sample inside the disc (not on its circle: see enters_face) is a lower bound (_best_of's rule)
    b0 = -1
    for k in range(m):
        if rr[k] < R * (1 - ON_CIRCLE) and (b0 < 0 or val[k] > val[b0] or (val[k] == val[b0] and idx[k] < idx[b0])):
            b0 = k
    if b0 >= 0:
        j = idx[b0]
        _add(best, bp, val[b0], SAMPLE, pf[j], xyz[j, 0], xyz[j, 1], xyz[j, 2])
    # the query's scratch in one allocation per type: floats (the groups' face, rim and edge bounds, the
    # cells' face and rim bounds (NaN: not computed), the certificate, phase 2's seed bounds), integers (the
    # seed picks, phase 2's seeds and group index, a round's sample) and flags (the seed masks, the samples the
    # certificate leaves, the rounds' tried and selected)
    nb, n_pk = 2 * ng + n_eg, 5 * ng + 2 * n_eg
    fl_ = np.empty(nb + 2 * m + 5 + 3 * m)
    in_ = np.empty(n_pk + 3 * m + 2 * ng + 1 + m + 1, np.int64)
    bl_ = np.empty(8 * m, np.bool_)
    fl, ii, bb = borrowed((fl_, in_, bl_))
    seeds = _seed_sets(idx, rr, val, zz, negr, feas, is_e, gk, ek, ng, n_eg, SM, K, ii[:n_pk], bb[: 3 * m])
    is_seed, rseed, eseed = seeds
    bounds = (fl[:ng], fl[ng : 2 * ng], fl[2 * ng : nb])
    _bounds(bounds[0], bounds[1], bounds[2], gk, ek, ub, rim_ub, e_ub, is_e, is_e[:0])
    # phase 1: the best face seed and the highest rim seed
    f1 = _best_of(val, is_seed, idx)
    r1 = _best_of(zz, rseed, idx)
    if f1 >= 0:
        _solve(FACE, idx[f1], cx, cy, S, E, T, PR, SM, K, W, best, bp, R, h_R)
    if r1 >= 0 and (best[4] == 0 or bounds[1][gk[r1]] > best[1] + BOUND_TIE):  # (a ball's rim: seldom)
        _solve(RIM, idx[r1], cx, cy, S, E, T, PR, SM, K, W, best, bp, R, h_R)
    # CB: the cells' face and rim bounds, the certificate (a flat end's rim contact: the seed samples whose
    # neighbourhoods it covers bound nothing more), then phase 2's seeds, their bounds and its group index, and
    # the rounds' flags and sample
    cb = fl[nb:]
    cb[: 2 * m] = math.nan
    i2 = n_pk + 3 * m
    CB = (cb[:m], cb[m : 2 * m], cb[2 * m : 2 * m + 5], ii[n_pk:i2], cb[2 * m + 5 :], ii[i2 : i2 + 2 * ng + 1 + m],
          bb[4 * m : 6 * m], ii[i2 + 2 * ng + 1 + m :], bb[6 * m : 8 * m])  # fmt: skip
    CB[2][:] = -1.0
    cert = CB[2]
    if K[10] > 0 and K[9] > 0 and best[4] > 0 and best[2] == RIM:
        if rim_certificate(S, int(best[3]), best[6], best[7], cx, cy, R, best[1] + h_R, cert[1:], W[6]):
            cert[0] = best[3]
            free = bb[3 * m : 4 * m]
            for k in range(m):
                free[k] = not _covered(k, idx, SM, cert)
                if is_e[k] and e_ub[k] > -math.inf and _edge_covered(k, idx, SM, cert):
                    e_ub[k] = -math.inf  # (its edge's points in the box: no higher than the contact)
            _bounds(bounds[0], bounds[1], bounds[2], gk, ek, ub, rim_ub, e_ub, is_e, free)
    _phase2(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, seeds, bounds, gk, ek, f1, r1, CB)
    low = _more_rounds(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, is_seed, feas, is_e, ub, gk, ng, CB)
    _more_edge_rounds(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, e_ub, eseed, is_e, ek, n_eg, CB[8])
    for kk in range(kinks.shape[0]):
        _kink_rounds(kinks[kk, 0], kinks[kk, 1], low, cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, zz, gk, ng)
    keep((got, cand, fl_, in_, bl_))


@njit(cache=True, inline="always")
def _covered(k, idx, SM, cert):
    """Whether pool sample ``idx[k]`` has its grid neighbourhood in the certified box (a sample on an edge of the
    face: the parameter box of its edge step, :attr:`.cells.FineCells.steps`)."""
    j = idx[k]
    f = SM[1][j]
    if f != cert[0]:
        return False
    a = 0 if j < SM[3] else 4
    steps = SM[20]
    return boxed(cert, f, SM[2][j, 0], SM[2][j, 1], steps[f, a] * (1 + 1e-9), steps[f, a + 1] * (1 + 1e-9))


@njit(cache=True)
def _edge_covered(k, idx, SM, cert):
    """Whether the edge points that edge sample ``idx[k]`` bounds (those between its neighbours on its edge) lie
    in the certified box: the neighbours' and its own parameters a seed step inside it (the edge's ends: two)."""
    j = idx[k]
    f = SM[1][j]
    if f != cert[0]:
        return False
    n_int, puv, eid, steps = SM[3], SM[2], SM[4], SM[20]
    du, dv = steps[f, 0] * (1 + 1e-9), steps[f, 1] * (1 + 1e-9)
    e = eid[j - n_int]
    for nb in (j - 1, j + 1):
        if nb < n_int or nb >= puv.shape[0] or eid[nb - n_int] != e:
            if not boxed(cert, f, puv[j, 0], puv[j, 1], 2 * du, 2 * dv):
                return False
        elif not boxed(cert, f, puv[nb, 0], puv[nb, 1], du, dv):
            return False
    return boxed(cert, f, puv[j, 0], puv[j, 1], du, dv)


@njit(cache=True)
def _kink_rounds(rk, hk, low, cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, zz, gk, ng):
    """``_kink_solves`` for one kink circle: per group, inside the circle and outside it apart, the highest near
    sample whose bound reaches ``low``, then rounds of the untried ones whose bound beats the best height."""
    cov, rise = SM[7], SM[8]
    m = idx.shape[0]
    near = np.empty(m, np.bool_)
    bound = np.empty(m)
    key = np.empty(m, np.int64)
    for k in range(m):
        j = idx[k]
        near[k] = abs(rr[k] - rk) <= cov[j]
        bound[k] = zz[k] + rise[j] - hk
        key[k] = gk[k] * 2 + (1 if rr[k] < rk else 0)
    tried = np.zeros(m, np.bool_)
    sel = np.empty(m, np.bool_)
    for k in range(m):
        sel[k] = near[k] and bound[k] >= low
    seeds = _group_best(2 * ng, key, zz, sel, idx)
    for _ in range(5):
        any_ = False
        for s in seeds:
            if s >= 0:
                any_ = True
                tried[s] = True
                _solve(RIM, idx[s], cx, cy, S, E, T, PR, SM, K, W, best, bp, rk, hk)
        if not any_:
            break
        top = best[1] if best[4] > 0 else -math.inf
        for k in range(m):
            sel[k] = near[k] and not tried[k] and bound[k] > top + 1e-7
        seeds = _group_best(2 * ng, key, bound, sel, idx)


@njit(cache=True)
def _phase2(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, seeds, bounds, gk, ek, f1, r1, CB):
    """Every seed whose group bound reaches the best height of phase 1 (face seeds in the found contact's own
    basin skipped), highest bound first; a seed whose bound falls below a height found meanwhile cannot
    raise it and is skipped, and so is a face or rim seed whose group's cells (:func:`_group_cells`) cannot."""
    xyz, pf, cov = SM[0], SM[1], SM[7]
    R, h_R = K[0], K[3]
    is_seed, rseed, eseed = seeds
    fb, rb, eb = bounds
    m = idx.shape[0]
    low = best[1] + BOUND_TIE if best[4] > 0 else -math.inf
    solved = best[4] > 0 and best[2] == FACE
    c_face = best[3]
    p1x, p1y, p1z = bp[0], bp[1], bp[2]
    tk, tb = CB[3], CB[4]  # (3 m each)
    nt = 0
    for k in range(m):
        if is_seed[k] and k != f1 and fb[gk[k]] > low:
            j = idx[k]
            own = solved and pf[j] == c_face
            own = own and norm3(xyz[j, 0] - p1x, xyz[j, 1] - p1y, xyz[j, 2] - p1z) <= 2 * cov[j]
            if not own:
                tk[nt], tb[nt] = k, fb[gk[k]]
                nt += 1
        if rseed[k] and k != r1 and rb[gk[k]] > low:
            tk[nt], tb[nt] = m + k, rb[gk[k]]
            nt += 1
        if eseed[k] and eb[ek[k]] > low:
            tk[nt], tb[nt] = 2 * m + k, eb[ek[k]]
            nt += 1
    for a in range(1, nt):  # highest bound first, ties in their order (a stable insertion sort: a few)
        ka, ba = tk[a], tb[a]
        b = a - 1
        while b >= 0 and tb[b] < ba:
            tk[b + 1], tb[b + 1] = tk[b], tb[b]
            b -= 1
        tk[b + 1], tb[b + 1] = ka, ba
    if nt == 0:
        return
    GI = _group_index(fb.shape[0], gk, CB[5])
    for i in range(nt):
        if best[4] > 0 and tb[i] <= best[1] + BOUND_TIE:
            break
        kind, k = FACE + tk[i] // m, tk[i] % m
        if kind != EDGE and best[4] > 0 and K[9] > 0:
            low = best[1] + BOUND_TIE
            if _group_cells(gk[k], kind - FACE, low, cx, cy, idx, rr, GI, PR, SM, K, CB) <= low:
                continue
        _solve(kind, idx[k], cx, cy, S, E, T, PR, SM, K, W, best, bp, R, h_R)


@njit(cache=True)
def _more_rounds(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, rr, tried0, feas, is_e, ub, gk, ng, CB):
    """``_more_face_rounds``: the untried sample of highest bound per group, away from the best contact,
    while a bound (and its cell's) beats the best height; returns the best height before the last round."""
    xyz, pf, cov, tilt = SM[0], SM[1], SM[7], SM[9]
    m = idx.shape[0]
    tried, sel = CB[6][:m], CB[6][m:]
    tried[:] = tried0
    one = CB[7]
    low = -math.inf
    for _ in range(4):
        low = best[1] if best[4] > 0 else -math.inf
        sel[:] = False
        any_ = False
        for k in range(m):
            j = idx[k]
            if tried[k] or is_e[k] or not feas[k] or tilt[j] > K[2] + 1e-9 or not (ub[k] > low + 1e-7):
                continue
            far = best[4] == 0 or best[2] != FACE or pf[j] != best[3]
            far = far or norm3(xyz[j, 0] - bp[0], xyz[j, 1] - bp[1], xyz[j, 2] - bp[2]) > cov[j]
            if K[9] > 0 and far:
                one[0] = k
            if far and (K[9] == 0 or _cells(one, 0, 1, 0, low + 1e-7, cx, cy, idx, rr, PR, SM, K, CB) > low + 1e-7):
                sel[k] = True
                any_ = True
        if not any_:
            break
        for s in _group_best(ng, gk, ub, sel, idx):
            if s >= 0:
                tried[s] = True
                _solve(FACE, idx[s], cx, cy, S, E, T, PR, SM, K, W, best, bp, K[0], K[3])
    return low


@njit(cache=True)
def _more_edge_rounds(cx, cy, S, E, T, PR, SM, K, W, best, bp, idx, e_ub, eseed, is_e, ek, n_eg, scratch):
    """``_more_edge_rounds``: the untried edge sample of highest bound per group, away from the best contact
    on its own edge, while a bound beats the best height (``scratch``: 2 m flags)."""
    xyz, n_int, ecov = SM[0], SM[3], SM[10]
    m = idx.shape[0]
    tried, sel = scratch[:m], scratch[m:]
    tried[:] = eseed
    for _ in range(4):
        low = best[1] if best[4] > 0 else -math.inf
        sel[:] = False
        any_ = False
        for k in range(m):
            if tried[k] or not is_e[k] or not (e_ub[k] > low + 1e-7):
                continue
            j = idx[k]
            near = best[4] > 0 and best[5] == SM[4][j - n_int]
            near = near and norm3(xyz[j, 0] - bp[0], xyz[j, 1] - bp[1], xyz[j, 2] - bp[2]) <= 2 * ecov[j - n_int]
            if not near:
                sel[k] = True
                any_ = True
        if not any_:
            break
        for s in _group_best(n_eg, ek, e_ub, sel, idx):
            if s >= 0:
                tried[s] = True
                _solve(EDGE, idx[s], cx, cy, S, E, T, PR, SM, K, W, best, bp, K[0], K[3])


@njit(cache=True)
def _cells(order, i0, i1, which, low, cx, cy, idx, rr, PR, SM, K, CB):
    """The largest face (``which`` 0) or rim (1) bound of the cells (:mod:`.cells`) of pool samples
    ``idx[order[i0:i1]]`` at the query, stopping at the first that reaches ``low``. A cell's bound is the
    bound of the whole cell when that is below ``low``, else the largest over its fine samples (computed once
    per query and sample, kept in ``CB``). The arrays are taken out of their tuples once for all the cells
    (each take and each call costs a reference count)."""
    R, h_R = K[0], K[3]
    pf, start, cxyz, crise, ccov, rad, top = SM[1], SM[11], SM[12], SM[13], SM[14], SM[15], SM[16]
    cuv, steps = SM[19], SM[20]
    CBf, CBr, cert = CB[0], CB[1], CB[2]
    level = PR[1][2] == h_R  # (a flat end: the floor is h_R everywhere, no profile call in the loop)
    out = CBf if which == 0 else CBr
    best = -math.inf
    for i in range(i0, i1):
        k = order[i]
        if not math.isnan(out[k]):
            best = max(best, out[k])
            if best >= low:
                break
            continue
        j = idx[k]
        if not (top[j] > -math.inf):
            continue
        rho = rr[k]
        if which == 0:
            rough = top[j] - (h_R if level else prof_floor(PR, rho - rad[j])) if rho - rad[j] <= R else -math.inf
        else:
            rough = top[j] - h_R if abs(rho - R) <= rad[j] else -math.inf
        if rough < low:
            best = max(best, rough)
            continue
        f = pf[j]
        certified = cert[0] == f
        du, dv = steps[f, 6] * (1 + 1e-9), steps[f, 7] * (1 + 1e-9)  # (a fine sample may lie on an edge)
        fb = rb = -math.inf
        for c in range(start[j], start[j + 1]):
            if certified and boxed(cert, f, cuv[c, 0], cuv[c, 1], du, dv):
                continue
            ex, ey = cxyz[c, 0] - cx, cxyz[c, 1] - cy
            r = math.sqrt(ex * ex + ey * ey)  # (a bound with a cover's margin: not libm's hypot, 3 % of the time)
            t = cxyz[c, 2] + crise[c]
            if r - ccov[c] <= R:
                fb = max(fb, t - (h_R if level else prof_floor(PR, r - ccov[c])))
            if abs(r - R) <= ccov[c]:
                rb = max(rb, t - h_R)
        CBf[k], CBr[k] = fb, rb
        best = max(best, out[k])
        if best >= low:
            break
    return best


@njit(cache=True)
def _group_index(ng, gk, buf):
    """The samples of each group in their order: ``order[start[g]:start[g + 1]]`` (a counting sort; ``buf``:
    scratch of ``2 ng + 1 + m``)."""
    m = gk.shape[0]
    buf[:] = 0  # start, the fill pointers and order
    start, fill, order = buf[: ng + 1], buf[ng + 1 : 2 * ng + 1], buf[2 * ng + 1 :]
    for k in range(m):
        start[gk[k] + 1] += 1
    for g in range(ng):
        start[g + 1] += start[g]
    fill[:] = start[:-1]
    for k in range(m):
        order[fill[gk[k]]] = k
        fill[gk[k]] += 1
    return order, start


@njit(cache=True)
def _group_cells(g, which, low, cx, cy, idx, rr, GI, PR, SM, K, CB):
    """The largest face (``which`` 0) or rim (1) cell bound of group ``g``'s samples (``GI``: see
    :func:`_group_index`; stops at the first that reaches ``low``)."""
    order, start = GI
    return _cells(order, start[g], start[g + 1], which, low, cx, cy, idx, rr, PR, SM, K, CB)


@njit(cache=True, parallel=True, nogil=True)
def drop_batch(C, S, E, T, PR, SM, G, K, kinks, height, kind, face, point, chunk):
    """Heights of the query points ``C`` (n, 2) into the output arrays, in parallel over chunks of ``chunk``
    points (each chunk's scratch made once for its points; every point's answer is its own)."""
    n = C.shape[0]
    for ci in prange((n + chunk - 1) // chunk):
        best = np.zeros(8)
        bp = np.zeros(3)
        W = (np.empty((6, 3)), np.empty((6, 3)), np.empty((6, 3)), np.empty((9, 3)), np.empty((3, 3)), np.empty(480),
             np.empty(CERT_SCRATCH))  # fmt: skip
        for q in range(ci * chunk, min(n, (ci + 1) * chunk)):
            best[:] = 0.0
            _query(C[q, 0], C[q, 1], S, E, T, PR, SM, G, K, kinks, best, bp, W)
            if best[4] > 0:
                height[q] = best[1]
                kind[q] = int(best[2])
                face[q] = int(best[3])
                point[q, 0], point[q, 1], point[q, 2] = bp[0], bp[1], bp[2]
            else:
                height[q] = math.nan
                kind[q] = 0
                face[q] = -1
                point[q, 0] = point[q, 1] = point[q, 2] = math.nan
