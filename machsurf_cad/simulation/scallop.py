"""Scallop height between adjacent passes and the spacing that leaves a given height (mm).

In the section across the feed the tool is a circle of radius ``rho`` (its effective radius there:
the ball radius, or relation (30) for a torus: ``r + R_t / sin(lead)`` on a plane) touching the
surface's normal section, a circle of radius ``1/kappa`` (``kappa > 0`` convex, ``< 0`` concave,
``0`` a plane). Two tool circles whose contacts lie ``w`` apart along the surface leave a cusp whose
height above the surface is exact for these circles (the circle-circle construction; on a plane
``h = rho - sqrt(rho^2 - w^2/4)``).
"""

from __future__ import annotations

import numpy as np

_PLANE = 1e-9


def scallop_height(w, rho, kappa=0.0) -> np.ndarray:
    """Cusp height (mm) between two tool circles of radius ``rho`` (mm) whose contacts lie ``w`` mm apart
    along a surface section of curvature ``kappa`` (1/mm; > 0 convex, < 0 concave). NaN where the
    circles no longer meet above the surface (``w`` too large, or a concave section tighter than the tool)."""
    w, rho, kappa = np.broadcast_arrays(*(np.asarray(x, float) for x in (w, rho, kappa)))
    out = np.full(w.shape, np.nan)
    flat = np.abs(kappa) < _PLANE
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(flat, rho - np.sqrt(rho * rho - 0.25 * w * w), out)
        Rs = 1.0 / np.where(flat, 1.0, kappa)
        a = np.abs(Rs)
        half = 0.5 * w / a  # half the angle between the two contacts, seen from the section's centre
        convex = kappa > 0
        D = np.where(convex, a + rho, a - rho)  # centre of the section to each tool circle's centre
        disc = rho * rho - (D * np.sin(half)) ** 2
        # centre of the section to the cusp: the crossing of the tool circles on the surface's side
        d = D * np.cos(half) + np.where(convex, -1.0, 1.0) * np.sqrt(disc)
        h = np.where(convex, d - a, a - d)
        ok = ~flat & (disc >= 0) & (D > 0)
        out = np.where(ok, h, out)
    return out


def spacing_for_scallop(h, rho, kappa=0.0) -> np.ndarray:
    """Distance along the surface (mm) between adjacent contacts that leaves the cusp height ``h`` (mm):
    the inverse of :func:`scallop_height`. NaN where no spacing leaves ``h`` (``h`` above what the tool can
    leave: ``h >= rho`` on a plane)."""
    h, rho, kappa = np.broadcast_arrays(*(np.asarray(x, float) for x in (h, rho, kappa)))
    out = np.full(h.shape, np.nan)
    flat = np.abs(kappa) < _PLANE
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(flat & (h < rho), 2.0 * np.sqrt(np.maximum(2.0 * rho * h - h * h, 0.0)), out)
        a = np.abs(1.0 / np.where(flat, 1.0, kappa))
        convex = kappa > 0
        D = np.where(convex, a + rho, a - rho)
        d = np.where(convex, a + h, a - h)
        c = (D * D + d * d - rho * rho) / (2.0 * D * d)  # law of cosines in the triangle centre, tool, cusp
        ok = ~flat & (D > 0) & (d > 0) & (np.abs(c) <= 1.0)
        out = np.where(ok, 2.0 * a * np.arccos(np.clip(c, -1.0, 1.0)), out)
    return out


__all__ = ["scallop_height", "spacing_for_scallop"]
