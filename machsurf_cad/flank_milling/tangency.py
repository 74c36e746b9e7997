"""The three-tangency system of the optimum flank setting, solved from many starts at once (mm, radians).

A candidate setting is ``(h0, gamma)``: the axis ``Q + t a`` with ``Q = P0 + h0 z1 + R y1`` and
``a = cos(gamma) z1 + sin(gamma) x1`` (the rule touches the cylinder at ``M2 = P0 + h0 z1``). It is a
three-tangency setting when the distance from each directrix to the axis has a local minimum equal
to ``R``. Every start runs its own Newton iteration on ``(h0, gamma)``, with the contact points found
by Newton on ``u`` at each step; all starts advance together as numpy arrays (the optimum search
runs 20 starts: one vectorised pass instead of 20 Python loops).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Contacts:
    """Local minima of the distance from a directrix to each of several axes."""

    u: np.ndarray
    dist: np.ndarray
    point: np.ndarray
    slope: np.ndarray  # d(dist^2)/du at u: zero at a true tangency
    ok: np.ndarray


def _perp(w, a):
    return w - np.einsum("ij,ij->i", w, a)[:, None] * a


def _newton_u(directrix, q, a, u, lo, hi, iters):
    """Newton on u from ``u`` (rows); returns ``(u, ok, d)`` with ``d`` the directrix's derivatives at
    the last iterate when every row converged (steps below 1e-13 of the range), else None."""
    ok = np.ones(u.shape, bool)
    scale = max(1.0, abs(hi - lo))
    d = None
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for _ in range(iters):
            d = directrix(u, 2)
            w = _perp(d[:, 0] - q, a)
            d1 = _perp(d[:, 1], a)
            g = 2 * np.einsum("ij,ij->i", w, d[:, 1])
            h = 2 * (np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", w, d[:, 2]))
            ok &= (h > 0) & np.isfinite(g)
            step = np.where(ok, g / np.where(h > 0, h, 1.0), 0.0)
            u_new = np.clip(u - step, lo, hi)
            done = np.abs(u_new - u) < 1e-13 * scale
            u = u_new
            if np.all(done | ~ok):
                return u, ok, d
    return u, ok, None


def contact_points(directrix, q, a, u_start, u_range, *, iters: int = 40, n_samples: int = 129) -> Contacts:
    """Local minima over ``u`` in ``u_range`` of the distance from ``directrix`` to the axes ``(q[i], a[i])``.

    Newton from ``u_start[i]``; where it fails (a concave stretch of the distance, or outside a
    directrix's domain) it starts again from the closest of ``n_samples`` samples over the range."""
    lo, hi = u_range
    q = np.atleast_2d(np.asarray(q, float))
    a = np.atleast_2d(np.asarray(a, float))
    u, ok, d = _newton_u(directrix, q, a, np.clip(np.asarray(u_start, float).copy(), lo, hi), lo, hi, iters)
    if not ok.all():
        d = None
        f = np.nonzero(~ok)[0]
        us = np.linspace(lo, hi, n_samples)
        with np.errstate(invalid="ignore"):
            C = directrix(us, 0)[:, 0]
            W = C[None, :, :] - q[f, None, :]
            W = W - np.einsum("ijk,ik->ij", W, a[f])[..., None] * a[f, None, :]
            D = np.linalg.norm(W, axis=-1)
        has = np.any(np.isfinite(D), axis=1)
        f = f[has]
        if f.size:
            start = us[np.nanargmin(D[has], axis=1)]
            u[f], ok[f], _ = _newton_u(directrix, q[f], a[f], start, lo, hi, iters)
    with np.errstate(invalid="ignore"):
        if d is None:  # else: the last Newton evaluation, within 1e-13 of the range of u
            d = directrix(u, 1)
        w = _perp(d[:, 0] - q, a)
        dist = np.linalg.norm(w, axis=1)
        slope = 2 * np.einsum("ij,ij->i", w, d[:, 1])
    ok &= np.all(np.isfinite(w), axis=1)
    return Contacts(u, dist, d[:, 0], slope, ok)


def axes(frame, R: float, h0, gamma):
    """Axis points and unit directions of the settings ``(h0, gamma)`` (phi = 0), arrays."""
    h0 = np.asarray(h0, float)
    gamma = np.asarray(gamma, float)
    q = frame.p0 + h0[:, None] * frame.z1 + R * frame.y1
    a = np.cos(gamma)[:, None] * frame.z1 + np.sin(gamma)[:, None] * frame.x1
    return q, a


@dataclass(frozen=True)
class Solutions:
    """Converged three-tangency settings (one row per start that converged)."""

    h0: np.ndarray
    gamma: np.ndarray
    c0: Contacts
    c1: Contacts


def solve(surface, frame, R: float, starts, u_range, *, warm=None, iters: int = 30) -> Solutions:
    """Newton on ``(h0, gamma)`` from every start ``(h0 / h_p, gamma)`` at once, with the analytic
    Jacobian (at a tangency the distance is stationary in u, so its derivatives in ``h0`` and ``gamma``
    are those at fixed contact points). A start is dropped when its step leaves the rule's length or
    a radian, or gamma passes 1.5 rad, or a contact point is lost; the rest stop at ``|dist - R| <
    1e-12 R``. ``warm``: contact parameters ``(u0, u1)`` to start the contact search from (default the
    rule's ``u``)."""
    X = np.atleast_2d(np.asarray(starts, float))
    n = X.shape[0]
    lo, hi = u_range
    span = surface.u_range[1] - surface.u_range[0]
    h0 = X[:, 0] * frame.h_p
    gam = X[:, 1].copy()
    u0 = np.full(n, frame.u_p if warm is None else warm[0], float)
    u1 = np.full(n, frame.u_p if warm is None else warm[1], float)
    active = np.ones(n, bool)
    conv = np.zeros(n, bool)
    # the contacts of each converged start, per directrix: u, distance, point, slope
    cu, cd, cs = np.full((2, n), np.nan), np.full((2, n), np.nan), np.full((2, n), np.nan)
    cp = np.full((2, n, 3), np.nan)
    for _ in range(iters):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        q, a = axes(frame, R, h0[idx], gam[idx])
        r0 = contact_points(surface.c0, q, a, u0[idx], (lo, hi))
        r1 = contact_points(surface.c1, q, a, u1[idx], (lo, hi))
        fail = ~(r0.ok & r1.ok)
        near = ~fail & (np.abs(r0.u - frame.u_p) < 0.5 * span) & (np.abs(r1.u - frame.u_p) < 0.5 * span)
        u0[idx[near]], u1[idx[near]] = r0.u[near], r1.u[near]
        F0, F1 = r0.dist - R, r1.dist - R
        done = ~fail & (np.maximum(np.abs(F0), np.abs(F1)) < 1e-12 * R)
        for k, r in enumerate((r0, r1)):
            cu[k, idx[done]], cd[k, idx[done]] = r.u[done], r.dist[done]
            cs[k, idx[done]], cp[k, idx[done]] = r.slope[done], r.point[done]
        conv[idx[done]] = True
        active[idx[done | fail]] = False
        go = ~(done | fail)
        if not go.any():
            continue
        da = -np.sin(gam[idx])[:, None] * frame.z1 + np.cos(gam[idx])[:, None] * frame.x1
        J = np.empty((idx.size, 2, 2))
        with np.errstate(invalid="ignore", divide="ignore"):
            for k, r in enumerate((r0, r1)):
                w = r.point - q
                wa = np.einsum("ij,ij->i", w, a)
                wp = w - wa[:, None] * a
                nh = wp / np.linalg.norm(wp, axis=1)[:, None]
                J[:, k, 0] = -(nh @ frame.z1)
                J[:, k, 1] = -wa * np.einsum("ij,ij->i", nh, da)
            det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
            s0 = (J[:, 1, 1] * F0 - J[:, 0, 1] * F1) / det
            s1 = (-J[:, 1, 0] * F0 + J[:, 0, 0] * F1) / det
        bad = ~(np.isfinite(s0) & np.isfinite(s1)) | (np.abs(s0) > frame.h_p) | (np.abs(s1) > 1.0)
        step = go & ~bad
        h0[idx[step]] -= s0[step]
        gam[idx[step]] -= s1[step]
        bad |= ~(np.isfinite(h0[idx]) & np.isfinite(gam[idx])) | (np.abs(gam[idx]) > 1.5)
        active[idx[go & bad]] = False
    rows = np.nonzero(conv)[0]
    c0, c1 = (Contacts(cu[k, rows], cd[k, rows], cp[k, rows], cs[k, rows], np.ones(rows.size, bool)) for k in (0, 1))
    return Solutions(h0[rows], gam[rows], c0, c1)
