"""One validation of the numbers users pass, with the same limits in every command (mm, degrees)."""

from __future__ import annotations

import math

from .errors import InputError

LEAD_LIMIT_DEG = 89.0
"""Largest |lead|: at 90 deg the axis lies in the tangent plane."""
TILT_LIMIT_DEG = 180.0
"""Largest |tilt| (a turn about the normal; beyond it, say the angle modulo 360)."""


def finite(name: str, value) -> float:
    """``value`` as a finite float, or a one-line :class:`InputError` naming it."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise InputError(f"{name} must be finite, got {value!r}")
    return x


def positive(name: str, value, unit: str = "mm") -> float:
    """``value`` as a finite float > 0."""
    x = finite(name, value)
    if not x > 0:
        raise InputError(f"{name} must be > 0{' ' + unit if unit else ''}, got {value!r}")
    return x


def lead_tilt(lead, tilt, *, axes: int = 5) -> tuple[float, float]:
    """Lead and tilt angles (degrees), checked the same way everywhere.

    |lead| <= 89 deg (at 90 the tool lies on the surface), |tilt| <= 180 deg; with 3 axes both must
    be 0 (the axis is fixed: a lead or tilt would be silently ignored).
    """
    lt, tl = finite("lead angle (deg)", lead), finite("tilt angle (deg)", tilt)
    if axes == 3 and (lt != 0.0 or tl != 0.0):
        raise InputError("lead and tilt apply to 5 axes; with 3 axes give a fixed --axis instead")
    if abs(lt) > LEAD_LIMIT_DEG:
        raise InputError(
            f"lead angle {lt:g} deg puts the axis at or below the tangent plane "
            f"(|lead| must be <= {LEAD_LIMIT_DEG:g} deg)"
        )
    if abs(tl) > TILT_LIMIT_DEG:
        raise InputError(f"tilt angle {tl:g} deg is outside [-{TILT_LIMIT_DEG:g}, {TILT_LIMIT_DEG:g}] deg")
    return lt, tl


__all__ = ["finite", "positive", "lead_tilt", "LEAD_LIMIT_DEG", "TILT_LIMIT_DEG"]
