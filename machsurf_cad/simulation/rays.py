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
tracing on the whole body crawls along a ray that runs just outside the cylindrical side). A ray that
grazes the torus itself (one running just above a bull-nose's flat bottom, along a wall under the tool)
makes sphere tracing crawl too: where it has not converged the entry is solved exactly instead, as the
smallest root of the ray-torus quartic on which the torus distance vanishes (:func:`torus_quartic_entry`).
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
            args = (R_t, r, qp[cand], dp[cand], qz[cand], dz[cand], np.maximum(blo[cand], t0[cand]), stop[cand])
            tt, st = _trace_torus(*args, 10 * max_steps)
            slow = np.flatnonzero(st == 3)  # a grazing ray: the quartic's exact root instead
            if slow.size:
                tq, sq = torus_quartic_entry(*(x[slow] if np.ndim(x) else x for x in args))
                tt[slow], st[slow] = tq, sq
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


def torus_quartic_entry(R_t, r, qp, dp, qz, dz, t_start, t_end):
    """Entry of rays into the solid torus (ring radius ``R_t``, tube ``r``, centre ``r`` above the tip) by the
    exact quartic ``(|p|^2 + R_t^2 - r^2)^2 = 4 R_t^2 rho^2``: its real roots (companion-matrix eigenvalues,
    one Newton step on the torus distance) where that distance is below 1e-6 mm, the smallest in
    ``[t_start, t_end]``. ``qp, dp`` are the rays' start and direction across the axis, ``qz, dz`` along it.
    Returns ``(t, status)`` as :func:`ray_entry` (1 inside at ``t_start``, 3 where no root could be told)."""
    m = qp.shape[0]
    t0 = np.asarray(t_start, float)
    # centred on each ray's closest approach to the torus centre: better conditioned roots
    wz0 = qz - r
    a = np.einsum("ij,ij->i", dp, dp) + dz * dz
    tc = -(np.einsum("ij,ij->i", qp, dp) + wz0 * dz) / np.where(a > 0, a, 1.0)
    x0 = qp + tc[:, None] * dp
    z0 = wz0 + tc * dz
    A2, A1, A0 = np.einsum("ij,ij->i", dp, dp), 2.0 * np.einsum("ij,ij->i", x0, dp), np.einsum("ij,ij->i", x0, x0)
    b = A1 + 2.0 * z0 * dz
    c = A0 + z0 * z0 + R_t * R_t - r * r
    k4 = 4.0 * R_t * R_t
    coef = np.stack([a * a, 2 * a * b, b * b + 2 * a * c - k4 * A2, 2 * b * c - k4 * A1, c * c - k4 * A0], 1)
    comp = np.zeros((m, 4, 4))
    comp[:, 1:, :-1] = np.eye(3)
    comp[:, :, -1] = -(coef[:, :0:-1] / coef[:, :1])
    roots = np.linalg.eigvals(comp)
    s = roots.real
    ok = np.abs(roots.imag) <= 1e-4 * (1.0 + np.abs(s))

    def dist(sv):
        x = x0[:, None, :] + sv[..., None] * dp[:, None, :]
        rho = np.sqrt(np.einsum("ijk,ijk->ij", x, x))
        zz = z0[:, None] + sv * dz[:, None]
        return np.hypot(rho - R_t, zz) - r, rho, zz

    g, rho, zz = dist(s)
    with np.errstate(invalid="ignore", divide="ignore"):  # one Newton step on the distance (none at a tangency)
        x = x0[:, None, :] + s[..., None] * dp[:, None, :]
        drho = np.einsum("ijk,ik->ij", x, dp) / rho
        h = np.hypot(rho - R_t, zz)
        dg = ((rho - R_t) * drho + zz * dz[:, None]) / h
        step = np.where(np.abs(dg) > 1e-3, -g / dg, 0.0)
    s = s + np.where(np.isfinite(step) & (np.abs(step) < 1e-3), step, 0.0)
    g = dist(s)[0]
    t = s + tc[:, None]
    good = ok & (np.abs(g) <= 1e-6) & (t >= t0[:, None]) & (t <= np.asarray(t_end, float)[..., None])
    entry = np.where(good, t, np.inf).min(axis=1)
    status = np.where(np.isfinite(entry), 0, 2).astype(np.int8)
    inside = dist((t0 - tc)[:, None])[0][:, 0] <= 0.0
    status[inside] = 1
    entry[inside] = t0[inside]
    bad = ~np.all(np.isfinite(coef), axis=1) | (a <= 0)
    status[bad] = 3
    entry[bad] = t0[bad]
    return np.where(status == 2, np.inf, entry), status


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
