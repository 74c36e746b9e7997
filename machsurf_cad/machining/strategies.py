"""Tool-axis strategies: the unit tool axis u(xi1, xi2) over a face (angles in degrees).

Local frame at the cutter-contact point C_C (after Tournier et al.): ``n`` the face's outward
normal (out of the material, into the tool), ``f`` the feed direction (tangent, given by the
machining strategy), ``t = f x n``.

Sign conventions
----------------
* **Lead** ``Omega_t`` (rotation about ``t``): positive leans the axis *towards the feed
  direction*: ``u = cos(lead) n + sin(lead) f`` before the tilt. (As a right-handed rotation
  about ``t`` this is an angle of ``-lead``.)
* **Tilt** ``Omega_n`` (rotation about ``n``, applied second): right-handed about ``n``, turning
  the leaning part from ``f`` towards ``n x f = -t``. With ``lead = 0`` the tilt has no effect
  (the axis is ``n``), as in the paper.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..glossary import renamed_fields


def _unit(v, what="vector") -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n == 0:
        raise InputError(f"{what} must be a non-zero finite vector")
    return v / n


def _normalize(a: np.ndarray) -> np.ndarray:
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


@dataclass(frozen=True)
class LocalFrame:
    """Exact local data of the nominal face on a parameter grid (outward normal ``n``)."""

    point: np.ndarray
    su: np.ndarray
    sv: np.ndarray
    normal: np.ndarray
    U: np.ndarray
    V: np.ndarray


# ----------------------------------------------------------------------------- feed directions
@dataclass(frozen=True)
class PlanesFeed:
    """Feed along parallel planes of normal ``plane_normal``: ``f = (n x N) / |n x N|``.

    ``planes:x`` (normal x, planes parallel to yOz as in the paper's example) feeds along +y
    on a surface facing +z.
    """

    plane_normal: tuple

    def __post_init__(self):
        object.__setattr__(self, "plane_normal", tuple(_unit(self.plane_normal, "plane normal")))

    def feed(self, frame: LocalFrame) -> np.ndarray:
        f = np.cross(frame.normal, np.asarray(self.plane_normal))
        bad = np.linalg.norm(f, axis=-1) < 1e-9
        if np.any(bad):
            raise InputError(
                "the guiding planes are tangent to the face somewhere (normal parallel to the "
                "plane normal): choose another plane direction"
            )
        return _normalize(f)

    def describe(self) -> str:
        return "planes normal to ({:.4g}, {:.4g}, {:.4g})".format(*self.plane_normal)


@dataclass(frozen=True)
class IsoFeed:
    """Feed along the iso-parametric direction ``"u"`` (v constant) or ``"v"``."""

    direction: str = "u"

    def __post_init__(self):
        if self.direction not in ("u", "v"):
            raise InputError("iso-parametric feed direction must be 'u' or 'v'")

    def feed(self, frame: LocalFrame) -> np.ndarray:
        d = frame.su if self.direction == "u" else frame.sv
        # tangent already; remove round-off normal part
        d = d - np.einsum("...i,...i->...", d, frame.normal)[..., None] * frame.normal
        return _normalize(d)

    def describe(self) -> str:
        return f"iso-parametric along {self.direction}"


# ----------------------------------------------------------------------------- axis strategies
@dataclass(frozen=True)
class FixedAxis:
    """Fixed tool axis (3-axis: z; 3+2: any direction), unit vector."""

    direction: tuple = (0.0, 0.0, 1.0)
    feed: Any = None

    def __post_init__(self):
        object.__setattr__(self, "direction", tuple(_unit(self.direction, "tool axis")))

    def axis(self, frame: LocalFrame) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.direction), frame.normal.shape).copy()

    def describe(self) -> str:
        return "fixed axis ({:.4g}, {:.4g}, {:.4g})".format(*self.direction)


@renamed_fields(lead_deg="lead", tilt_deg="tilt")
@dataclass(frozen=True)
class LeadTilt:
    """5-axis axis from lead ``Omega_t`` and tilt ``Omega_n`` (degrees) in the local frame.

    See the module docstring for the sign conventions.
    """

    lead: float
    tilt: float
    feed: Any

    def __post_init__(self):
        from ..checks import lead_tilt

        lead, tilt = lead_tilt(self.lead, self.tilt)
        object.__setattr__(self, "lead", lead)
        object.__setattr__(self, "tilt", tilt)

    def axis(self, frame: LocalFrame) -> np.ndarray:
        f = self.feed.feed(frame)
        n = frame.normal
        lt, tn = np.radians(self.lead), np.radians(self.tilt)
        lean = np.cos(tn) * f + np.sin(tn) * np.cross(n, f)
        return np.cos(lt) * n + np.sin(lt) * lean

    def describe(self) -> str:
        return f"lead {self.lead:g} deg, tilt {self.tilt:g} deg, feed {self.feed.describe()}"


@dataclass(frozen=True)
class AxisField:
    """Axis given by the caller: ``func(u, v) -> (..., 3)`` (normalised here), broadcast over arrays."""

    func: Callable
    feed: Any = None
    label: str = "axis field"

    def axis(self, frame: LocalFrame) -> np.ndarray:
        a = np.asarray(self.func(frame.U, frame.V), dtype=float)
        if a.shape != frame.normal.shape or not np.all(np.isfinite(a)):
            raise InputError("the axis field must return finite vectors of shape (..., 3)")
        norm = np.linalg.norm(a, axis=-1, keepdims=True)
        if np.any(norm == 0):
            raise InputError("the axis field returned a zero vector")
        return a / norm

    def describe(self) -> str:
        return self.label

    @classmethod
    def from_grid(cls, axes, bounds, label: str = "axis field (grid)") -> AxisField:
        """Axis field from unit vectors on a uniform (nu, nv) grid over ``bounds``, interpolated bicubically."""
        from ..geometry.builders import interpolate_grid

        a = np.asarray(axes, dtype=float)
        if a.ndim != 3 or a.shape[2] != 3 or min(a.shape[:2]) < 4:
            raise InputError("grid axis field must have shape (nu >= 4, nv >= 4, 3)")
        u0, u1, v0, v1 = bounds
        surf = interpolate_grid(a, 3, 3, np.linspace(u0, u1, a.shape[0]), np.linspace(v0, v1, a.shape[1]))
        return cls(lambda u, v: surf.evaluate(u, v), None, label)


def as_feed(strategy):
    """The feed of ``strategy``: a :class:`PlanesFeed` or :class:`IsoFeed`, or its text (:func:`parse_strategy`)."""
    if isinstance(strategy, str):
        return parse_strategy(strategy)
    if isinstance(strategy, (PlanesFeed, IsoFeed)):
        return strategy
    raise InputError(f"strategy must be text like planes:x or iso:u, or a PlanesFeed/IsoFeed; got {strategy!r}")


def parse_strategy(text: str):
    """Feed from its CLI form: ``planes:x|y|z|a,b,c`` or ``iso:u|iso:v``."""
    kind, _, arg = (text or "").partition(":")
    kind = kind.strip().lower()
    if kind == "planes":
        axes = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}
        if arg.strip().lower() in axes:
            return PlanesFeed(axes[arg.strip().lower()])
        try:
            vec = [float(x) for x in arg.split(",")]
        except ValueError:
            vec = []
        if len(vec) != 3:
            raise InputError(f"strategy {text!r}: planes needs x, y, z or a normal a,b,c")
        return PlanesFeed(tuple(vec))
    if kind == "iso":
        return IsoFeed(arg.strip().lower() or "u")
    raise InputError(f"unknown strategy {text!r}: use planes:x|y|z|a,b,c or iso:u|v")
