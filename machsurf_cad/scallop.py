"""Scallop height and step-over: one home for the relations every planner and measure uses (mm).

* :func:`stepover`: relation (31) of the effective-radius paper (re-derived): the distance between adjacent tool
  centres for a scallop height, an effective radius and the surface's signed normal radius (reff maps).
* :func:`scallop_height` and its inverse :func:`spacing_for_scallop`: the circle-circle construction
  along the surface (iso-scallop passes, reff step-over maps, the simulation's checks).
* :func:`scallop_stepover`: the flat-floor step of a cutter's corner arc plus its flat bottom (the
  first guess of the 3-axis scallop planner).

Step-over from scallop height (relation (31), re-derived from the triangle O, C, H; the
extracted text lost a square root and a factor): two tool circles of radius ``R_eff`` tangent
to a surface circle of signed radius ``rho``, scallop height ``h`` at their intersection:

    d = sqrt(h (2 R_eff - h) (2 rho + h) (2 rho + 2 R_eff + h)) / |rho + h|

``d`` is the distance between adjacent tool centres (passes) in the plane normal to the feed.
Sign of ``rho``: **positive for a convex surface** (the tool outside the surface circle),
negative for a concave one, ``inf`` for flat, where ``d = 2 sqrt(h (2 R_eff - h))``. Where a
concave radius is not larger than ``R_eff + h/2`` the cutter cannot reach: NaN with a mask.

In :func:`scallop_height` the tool is a circle of radius ``rho`` (its effective radius across the feed)
touching the surface's normal section, a circle of radius ``1/kappa`` (``kappa > 0`` convex, ``< 0``
concave, ``0`` a plane); two tool circles whose contacts lie ``w`` apart along the surface leave a cusp
whose height above the surface is exact for these circles (on a plane ``h = rho - sqrt(rho^2 - w^2/4)``).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .errors import InputError
from .typing import ArrayLike, ToolLike


def stepover(scallop: float, r_eff: ArrayLike, rho: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Distance between adjacent passes (mm) for scallop height ``scallop`` (mm).

    Parameters
    ----------
    scallop : float
        Scallop height h, mm (> 0).
    r_eff : float or array_like
        Effective cutter radius, mm.
    rho : float or array_like
        Signed radius of the surface's normal section in the plane normal to the feed (mm):
        positive convex, negative concave, ``inf`` flat.

    Returns
    -------
    d : ndarray
        ``sqrt(h (2 R_eff - h)(2 rho + h)(2 rho + 2 R_eff + h)) / |rho + h|`` (relation (31)
        re-derived), mm; NaN where the cutter cannot reach (concave radius not larger than
        ``R_eff + h/2``); infinite for an infinite ``R_eff`` (flat spot).
    reachable : ndarray of bool
        False where ``d`` is NaN.

    Examples
    --------
    >>> d, ok = stepover(0.01, 5.0, np.inf)
    >>> round(float(d), 9) == round(2 * math.sqrt(0.01 * (10 - 0.01)), 9)
    True
    """
    h = float(scallop)
    if not h > 0:
        raise InputError("scallop height must be > 0 mm")
    R, rho = np.broadcast_arrays(np.asarray(r_eff, dtype=float), np.asarray(rho, dtype=float))
    if np.any(np.isfinite(R) & (h >= 2 * R)):
        raise InputError(
            f"scallop height {h:g} mm is not smaller than the effective diameter (min 2 R_eff = "
            f"{2 * float(np.nanmin(R)):g} mm)"
        )
    flat = ~np.isfinite(rho)
    rr = np.where(flat, 1.0, rho)
    with np.errstate(invalid="ignore", divide="ignore"):
        prod = h * (2 * R - h) * (2 * rr + h) * (2 * rr + 2 * R + h)
        d_curved = np.sqrt(prod) / np.abs(rr + h)
        d_flat = 2 * np.sqrt(h * (2 * R - h))
    d = np.where(flat, d_flat, d_curved)
    reach = flat | (rho > 0) | (-rho > R + h / 2)
    infinite_r = ~np.isfinite(R)
    d = np.where(infinite_r, np.inf, d)
    d = np.where(reach | infinite_r, d, np.nan)
    return d, reach | infinite_r


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


def scallop_stepover(scallop: float, tool: ToolLike) -> float:
    """Step-over (mm) leaving a cusp of ``scallop`` mm between two passes of the cutter's smallest
    corner arc on a flat floor, ``2 sqrt(2 r H - H^2)`` (ball: ``r = D/2``). The flat bottom of a
    bull-nose adds ``2 R_t``; a flat end mill has no arc and is refused (its scallop on slopes depends on
    the slope, not on a radius).

    The arguments come in the order of :func:`stepover` (scallop first); the order of 0.2
    (``scallop_stepover(tool, scallop)``) still works with a DeprecationWarning until 0.4.

    Examples
    --------
    >>> round(scallop_stepover(0.01, "ball:D=10"), 6)
    0.632139
    >>> round(scallop_stepover(0.01, "bull:D=10,r=2"), 6)  # the arc's 0.4 mm plus the 6 mm flat bottom
    6.3995
    """
    from . import checks

    if not isinstance(scallop, (int, float, np.floating, np.integer)):
        warnings.warn(
            "scallop_stepover(tool, scallop) is now scallop_stepover(scallop, tool) (the old order goes in 0.4)",
            DeprecationWarning,
            stacklevel=2,
        )
        scallop, tool = tool, scallop  # type: ignore[assignment]
    cutter = checks.tool(tool)
    if not scallop > 0:
        raise InputError(f"scallop must be > 0 mm, got {scallop}")
    r = float(cutter.corner_radius)
    if r <= 0:
        raise InputError(f"a scallop height needs a cutter with a corner radius, not {cutter.spec()}: give --stepover")
    h = min(float(scallop), r)
    return 2 * math.sqrt(2 * r * h - h * h) + 2 * float(cutter.torus_radius if r < cutter.radius else 0.0)


__all__ = ["stepover", "scallop_height", "spacing_for_scallop", "scallop_stepover"]
