"""Exact entry of rays into ball, flat and bull-nose end mill bodies (mm).

The cutting part of these tools is a rectangle ``[0, R_t] x [r, L]`` of the half-section grown by a
disc of radius ``r`` and cut at the top ``z = L`` (see
:func:`~machsurf_cad.cutter_profiles.rounded_core_distance`). With ``L >= 2 r`` it is the union of
three pieces whose ray intersections are closed forms or nearly so:

* the cylinder ``rho <= R_t + r``, ``r <= z <= L`` (the side);
* the cylinder ``rho <= R_t``, ``0 <= z <= L`` (the core; absent for a ball);
* the torus of ring radius ``R_t`` and tube ``r`` (a sphere for a ball, absent for a flat end mill).

Cylinders and spheres are intervals of a quadratic and a slab (exact); the torus is sphere-traced on
its own exact distance, which stays fast because its surface curves away from a grazing ray (sphere
tracing on the whole body crawls along a ray that runs just outside the cylindrical side).
"""

from __future__ import annotations

import numpy as np

_CONVERGED_MM = 1e-7


def ray_core(cutter) -> tuple[float, float, float] | None:
    """``(R_t, r, L)`` where :func:`ray_entry` applies to ``cutter`` (ball, flat, bull with ``L >= 2 r``)."""
    core = cutter._rounded_core()
    if core is None:
        return None
    R_t, r, L = core
    return core if (r == 0.0 or L >= 2.0 * r) else None


def _quadratic_interval(a, b, c):
    """Interval of ``t`` with ``a t^2 + b t + c <= 0`` (``a >= 0``); empty as ``lo > hi``."""
    lo = np.full(c.shape, np.inf)
    hi = np.full(c.shape, -np.inf)
    flat = a <= 1e-24
    lo = np.where(flat & (c <= 0), -np.inf, lo)
    hi = np.where(flat & (c <= 0), np.inf, hi)
    disc = b * b - 4.0 * a * c
    ok = ~flat & (disc >= 0)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    qq = -0.5 * (b + np.where(b >= 0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(ok, qq / np.where(ok, a, 1.0), np.inf)
        t2 = np.where(ok & (qq != 0), c / np.where(qq != 0, qq, 1.0), t1)
    lo = np.where(ok, np.minimum(t1, t2), lo)
    hi = np.where(ok, np.maximum(t1, t2), hi)
    return lo, hi


def _slab_interval(qz, dz, za, zb):
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = (za - qz) / dz
        tb = (zb - qz) / dz
    par = np.abs(dz) <= 1e-300
    inside = (qz >= za) & (qz <= zb)
    lo = np.where(par, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
    hi = np.where(par, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
    return lo, hi


def _cylinder(qp, dp, qz, dz, radius, za, zb):
    a = np.einsum("ij,ij->i", dp, dp)
    b = 2.0 * np.einsum("ij,ij->i", qp, dp)
    c = np.einsum("ij,ij->i", qp, qp) - radius * radius
    lo1, hi1 = _quadratic_interval(a, b, c)
    lo2, hi2 = _slab_interval(qz, dz, za, zb)
    return np.maximum(lo1, lo2), np.minimum(hi1, hi2)


def ray_entry(core, P, N, T, A, t_start, t_end: float, max_steps: int = 60):
    """Entry of each ray ``P + t N`` (``t`` from ``t_start`` to ``t_end``) into the body ``core`` =
    ``(R_t, r, L)`` placed at tips ``T`` with unit axes ``A``; the same contract as
    :func:`~machsurf_cad.simulation.nbuffer.march`: ``(t, status)``, status 0 entered at ``t``, 1 inside
    at ``t_start``, 2 no entry before ``t_end`` (``t = inf``), 3 the torus march did not converge (``t`` a
    lower bound)."""
    R_t, r, L = core
    m = P.shape[0]
    t0 = np.array(t_start, float, copy=True) if np.ndim(t_start) else np.full(m, float(t_start))
    q = P - T
    qz = np.einsum("ij,ij->i", q, A)
    dz = np.einsum("ij,ij->i", N, A)
    qp = q - qz[:, None] * A
    dp = N - dz[:, None] * A
    pieces = [_cylinder(qp, dp, qz, dz, R_t + r, r, L)] if r > 0 else []
    if R_t > 0:
        pieces.append(_cylinder(qp, dp, qz, dz, R_t, 0.0, L))
    if r > 0 and R_t == 0:  # the ball's sphere
        w = q - r * A
        pieces.append(
            _quadratic_interval(np.ones(m), 2.0 * np.einsum("ij,ij->i", w, N), np.einsum("ij,ij->i", w, w) - r * r)
        )
    entry = np.full(m, np.inf)
    inside = np.zeros(m, bool)
    for lo, hi in pieces:
        hit = (lo <= hi) & (hi >= t0) & (lo <= t_end)
        inside |= hit & (lo <= t0)
        entry = np.where(hit, np.minimum(entry, np.maximum(lo, t0)), entry)
    status = np.where(inside, 1, np.where(np.isfinite(entry), 0, 2)).astype(np.int8)
    if r > 0 and R_t > 0:  # the torus: sphere tracing on its distance, inside the bounding cylinder only
        blo, bhi = _cylinder(qp, dp, qz, dz, R_t + r, 0.0, 2.0 * r)
        stop = np.minimum(entry, t_end)
        cand = np.flatnonzero(~inside & (blo <= bhi) & (bhi >= t0) & (blo <= stop))
        if cand.size:
            tt, st = _trace_torus(R_t, r, qp[cand], dp[cand], qz[cand], dz[cand], np.maximum(blo[cand], t0[cand]),
                                  stop[cand], 10 * max_steps)  # fmt: skip
            st = np.where((st == 1) & (blo[cand] > t0[cand]), 0, st)  # inside where the bound starts: enters there
            better = (st != 2) & (tt < entry[cand])
            idx = cand[better]
            entry[idx] = tt[better]
            status[idx] = st[better]
    return np.where(status == 2, np.inf, entry), status


def _trace_torus(R_t, r, qp, dp, qz, dz, t, stop, max_steps):
    def dist(i, tt):
        x = qp[i] + tt[:, None] * dp[i]
        rho = np.sqrt(np.einsum("ij,ij->i", x, x))
        return np.hypot(rho - R_t, qz[i] + tt * dz[i] - r) - r

    return sphere_trace(dist, t, stop, max_steps)


def sphere_trace(dist, t_start: np.ndarray, t_end, max_steps: int):
    """March rays by their distance to a body: ``dist(indices, t)`` is a lower bound of the distance of
    those rays' points at ``t`` (exact for a signed distance), so no step passes through the body.
    Returns ``(t, status)`` as :func:`ray_entry` (``t_end`` a number or one per ray)."""
    t = np.array(t_start, float, copy=True)
    stop = np.broadcast_to(np.asarray(t_end, float), t.shape)
    status = np.full(t.shape, 3, np.int8)
    act = np.arange(t.size)
    g = dist(act, t)
    status[g <= 0] = 1
    act = act[g > 0]
    g = g[g > 0]
    for _ in range(max_steps):
        if act.size == 0:
            break
        done = g < _CONVERGED_MM
        status[act[done]] = 0
        t[act[done]] += np.maximum(g[done], 0.0)
        act, g = act[~done], g[~done]
        t[act] += g
        out = t[act] > stop[act]
        status[act[out]] = 2
        act = act[~out]
        if act.size == 0:
            break
        g = dist(act, t[act])
    return np.where(status == 2, np.inf, t), status
