"""One validation of the numbers users pass, with the same limits in every command (mm, degrees)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .errors import InputError

if TYPE_CHECKING:
    import numpy as np

    from .cutters import Cutter

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


def index(name: str, value, *, low: int = 0) -> int:
    """``value`` as an integer index >= ``low`` (a bool or a fractional number is refused, not rounded)."""
    if isinstance(value, bool) or not (isinstance(value, (int, float)) or hasattr(value, "__index__")):
        raise InputError(f"{name} must be an integer, got {value!r}")
    if isinstance(value, float) and not value.is_integer():
        raise InputError(f"{name} must be an integer, got {value!r}")
    i = int(value)
    if i < low:
        raise InputError(f"{name} must be >= {low}, got {value!r}")
    return i


def tool(value, name: str = "tool") -> Cutter:
    """A :class:`~machsurf_cad.cutters.Cutter`, from itself or its string (``ball:D=10``)."""
    from .cutters import Cutter
    from .toolspec import parse_cutter

    if isinstance(value, Cutter):
        return value
    if isinstance(value, str):
        return parse_cutter(value)
    raise InputError(f"{name} must be a Cutter or a cutter string like ball:D=10, got {type(value).__name__}")


def toolpath(value, name: str = "toolpath"):
    """``value`` if it is a :class:`~machsurf_cad.cam.ToolPath`, else a one-line error."""
    from .cam.toolpath import ToolPath

    if not isinstance(value, ToolPath):
        raise InputError(
            f"{name} must be a ToolPath (ms.read_apt, ms.read_csv, ms.tool_paths ...), got {type(value).__name__}"
        )
    return value


def points(name: str, value, dim: int) -> np.ndarray:
    """``value`` as a float array of shape (n, dim) (any array whose last axis has ``dim`` values)."""
    import numpy as np

    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be an array of numbers of shape (n, {dim})") from None
    if a.ndim == 0 or a.shape[-1] != dim:
        raise InputError(f"{name} must have shape (n, {dim}), got {a.shape}")
    return a.reshape(-1, dim)


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


__all__ = ["finite", "positive", "index", "tool", "toolpath", "points", "lead_tilt", "LEAD_LIMIT_DEG", "TILT_LIMIT_DEG"]
