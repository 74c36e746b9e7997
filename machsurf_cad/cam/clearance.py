"""Clearance surfaces that links travel on: a plane above the part (a fixed axis), a sphere or a cylinder
around it (the axis turning). A tool whose tip lies on the surface with its axis along the surface's outward
normal is wholly outside it (a ball's nearest point is its tip; a flat end's rim lies further out), so links
on it cannot meet a part inside; the moves out to it and back along a pass's axis are straight and are
checked by the tool-body check (:mod:`machsurf_cad.linking`).

A cylinder is ``(point, axis, radius, half_length)``: the part lies within ``radius - clearance`` of the
line through ``point`` along the unit ``axis``, and within ``half_length - clearance`` of ``point`` along it.
"""

from __future__ import annotations

import numpy as np


def exit_sphere(p, d, centre, radius):
    """Where the ray from ``p`` along unit ``d`` leaves the sphere (``p`` itself when outside already)."""
    w = p - centre
    b = float(w @ d)
    c = float(w @ w) - radius * radius
    if c >= 0 and b >= 0:
        return p
    lam = -b + np.sqrt(max(b * b - c, 0.0))
    return p + max(lam, 0.0) * d


def in_plane(p0, p1, a, height: float):
    """Rapid positions from ``p0`` (None at the path's start) up the fixed axis ``a`` to the plane
    ``x . a = height``, across it, and down towards ``p1`` (not included): (tips, axes)."""
    pts = [] if p0 is None else [np.asarray(p0, float)]
    pts.append(np.asarray(p1, float))
    up = [p + max(height - float(p @ a), 0.0) * a for p in pts]
    tips = np.array(up)
    return tips, np.repeat(np.asarray(a, float)[None, :], len(tips), axis=0)


def _arc(u0, u1, step_deg: float) -> np.ndarray:
    """Unit directions from ``u0`` to ``u1`` along the short great circle, at most ``step_deg`` apart."""
    ang = float(np.arccos(np.clip(u0 @ u1, -1.0, 1.0)))
    n = max(1, int(np.ceil(np.degrees(ang) / step_deg)))
    if ang < 1e-9:
        return np.repeat(u0[None, :], n + 1, axis=0)
    ortho = u1 - (u0 @ u1) * u0
    if np.linalg.norm(ortho) < 1e-12:  # opposite points: any great circle
        ortho = np.cross(u0, [1.0, 0.0, 0.0] if abs(u0[0]) < 0.9 else [0.0, 1.0, 0.0])
    ortho /= np.linalg.norm(ortho)
    th = np.linspace(0.0, ang, n + 1)
    return np.cos(th)[:, None] * u0 + np.sin(th)[:, None] * ortho


def beyond(axes, limit) -> np.ndarray:
    """Which ``axes`` lie more than ``limit = (machine_axis, degrees)`` from the machine's axis (all False
    without a limit): orientations a machine whose tilting axis stops there cannot take."""
    axes = np.atleast_2d(np.asarray(axes, float))
    if limit is None:
        return np.zeros(len(axes), bool)
    m = np.asarray(limit[0], float) / np.linalg.norm(limit[0])
    return axes @ m < np.cos(np.radians(float(limit[1]))) - 1e-12


def over_sphere(p0, a0, p1, a1, sphere, step_deg: float = 5.0, limit=None):
    """Rapid positions from ``p0`` (axis ``a0``) out along the axis to the sphere, over it along the great
    circle (axes radial, outward), back in along ``a1`` to ``p1``'s exit point: (tips, axes) without ``p1``.
    With a rotary ``limit`` (:func:`beyond`) a great circle that would turn the axis past it goes over the
    sphere's pole on the machine's axis instead (the angle to the pole then only falls and rises)."""
    centre = np.asarray(sphere[0], float)
    radius = float(sphere[1]) / np.cos(np.radians(step_deg / 2))  # the chords' sag kept outside
    q0 = exit_sphere(np.asarray(p0, float), np.asarray(a0, float), centre, radius)
    q1 = exit_sphere(np.asarray(p1, float), np.asarray(a1, float), centre, radius)
    u0, u1 = (q0 - centre) / np.linalg.norm(q0 - centre), (q1 - centre) / np.linalg.norm(q1 - centre)
    dirs = _arc(u0, u1, step_deg)
    if beyond(dirs, limit).any():
        m = np.asarray(limit[0], float) / np.linalg.norm(limit[0])
        dirs = np.vstack([_arc(u0, m, step_deg), _arc(m, u1, step_deg)[1:]])
    tips = np.vstack([q0, centre + radius * dirs, q1])
    axes = np.vstack([a0, dirs, a1])
    return tips, axes


def _cylinder(cyl):
    c, w = np.asarray(cyl[0], float), np.asarray(cyl[1], float)
    return c, w / np.linalg.norm(w), float(cyl[2]), float(cyl[3])


def exit_cylinder(p, d, cyl, radius: float | None = None) -> np.ndarray:
    """Where the ray from ``p`` along unit ``d`` reaches the cylinder (``radius`` instead of its own when
    given): ``(1, 3)``; a ray that would pass an end first (an axis along the cylinder's) goes to that end's
    plane and then out at right angles to the axis: ``(2, 3)`` (a tool beyond an end is clear of the part).
    ``p`` itself when outside already."""
    c, w, rc, h = _cylinder(cyl)
    rc = rc if radius is None else float(radius)
    p, d = np.asarray(p, float), np.asarray(d, float)
    q = p - c
    s, dw = float(q @ w), float(d @ w)
    rho, dp = q - s * w, d - dw * w
    a, b, cc = float(dp @ dp), float(rho @ dp), float(rho @ rho) - rc * rc
    if cc >= 0 and b >= 0:
        return p[None, :]
    lam = (-b + np.sqrt(max(b * b - a * cc, 0.0))) / a if a > 1e-12 else np.inf
    if abs(s + lam * dw) <= h:
        return (p + max(lam, 0.0) * d)[None, :]
    if abs(s) >= h and s * dw >= 0:  # beyond an end already, moving away from it
        e = p
    else:  # out of the end's plane first
        e = p + max(((h if dw > 0 else -h) - s) / dw, 0.0) * d
    r = (e - c) - float((e - c) @ w) * w
    nr = float(np.linalg.norm(r))
    if nr < 1e-9:  # on the axis: any direction at right angles to it
        r = np.cross(w, [1.0, 0.0, 0.0] if abs(w[0]) < 0.9 else [0.0, 1.0, 0.0])
        nr = float(np.linalg.norm(r))
    return np.vstack([e, e + (rc - min(nr, rc)) * r / nr])


def _turn(r0, r1, w, step_deg: float) -> np.ndarray:
    """Unit directions at right angles to ``w`` from ``r0`` to ``r1`` the short way round it, at most
    ``step_deg`` apart."""
    ang = float(np.arctan2(np.cross(r0, r1) @ w, r0 @ r1))
    n = max(1, int(np.ceil(abs(np.degrees(ang)) / step_deg)))
    th = np.linspace(0.0, ang, n + 1)[:, None]
    return np.cos(th) * r0 + np.sin(th) * np.cross(w, r0)


def over_cylinder(p0, a0, p1, a1, cyl, step_deg: float = 5.0, limit=None):
    """Rapid positions from ``p0`` (axis ``a0``) out along the axis to the cylinder, over it along a helix
    (turning at most ``step_deg`` per step, axes at right angles to the cylinder's axis, outward), back in
    along ``a1`` to ``p1``'s exit point: (tips, axes) without ``p1``. With a rotary ``limit``
    (:func:`beyond`) a helix that would turn the axis past it goes round over the side nearest the machine's
    axis instead."""
    c, w, rc, _ = _cylinder(cyl)
    radius = rc / np.cos(np.radians(step_deg / 2))  # the chords' sag kept outside
    q0 = exit_cylinder(p0, a0, cyl, radius)
    q1 = exit_cylinder(p1, a1, cyl, radius)
    e0, e1 = q0[-1] - c, q1[-1] - c
    s0, s1 = float(e0 @ w), float(e1 @ w)
    r0, r1 = e0 - s0 * w, e1 - s1 * w
    r0, r1 = r0 / np.linalg.norm(r0), r1 / np.linalg.norm(r1)
    dirs = _turn(r0, r1, w, step_deg)
    if beyond(dirs, limit).any():
        m = np.asarray(limit[0], float)
        m = m - (m @ w) * w
        if np.linalg.norm(m) > 1e-9:
            m /= np.linalg.norm(m)
            dirs = np.vstack([_turn(r0, m, w, step_deg), _turn(m, r1, w, step_deg)[1:]])
    along = np.linspace(s0, s1, len(dirs))[:, None] * w
    tips = np.vstack([q0, c + along + radius * dirs, q1[::-1]])
    axes = np.vstack([np.tile(a0, (len(q0), 1)), dirs, np.tile(a1, (len(q1), 1))])
    return tips, axes


def on_cylinder(tips: np.ndarray, cyl) -> np.ndarray:
    """Which tips lie on or outside the cylinder, or beyond one of its ends."""
    c, w, rc, h = _cylinder(cyl)
    q = np.asarray(tips, float) - c
    s = q @ w
    rho = np.linalg.norm(q - s[:, None] * w, axis=1)
    return (rho >= rc - 1e-9) | (np.abs(s) >= h - 1e-9)
