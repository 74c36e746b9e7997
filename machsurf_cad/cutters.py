"""Milling cutters as immutable values defined by their profile (lengths in mm, angles in degrees).

Vocabulary (after OpenCAMLib): a cutter is a surface of revolution about its axis ``z``;
the *tool tip* is the lowest point of the axis, at the origin of the tool frame. The
profile is a list of segments in the half plane ``(rho, z)``, ``rho >= 0`` the distance to
the axis, from the tip outwards and upwards.

Names, and how the papers call them
-----------------------------------
* ``D``   outer (cutting) diameter. The effective-radius paper calls ``D/2`` "R".
* ``r``   corner radius of a filleted (bull-nose, torus) cutter; ``r = D/2`` for a ball.
* ``R_t`` torus major radius, distance from the axis to the corner centre, ``R_t = D/2 - r``.
  The machining-surface paper (Tournier et al.) calls this "R".
* ``angle`` half taper angle of a conical cutter (degrees); positive widens towards the shank.

Sphere-family form (envelope paper, after Zhu et al. 2009)
---------------------------------------------------------
Every non-planar part of a rotational tool is the envelope of spheres with centres on the
axis ``q(a) = (0, 0, a)`` and radii ``r(a)``. :meth:`Cutter.sphere_family` returns it segment
by segment with ``r(a)`` and ``r'(a)``. Flat parts perpendicular to the axis (the bottom of a
flat or bull-nose end mill) are spheres of infinite radius and are not part of the family.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .errors import InputError


_AXIS_CUTOFF_DEG = 1.0
"""Sphere families of arcs stop where the profile normal is this close (degrees) to the axis."""


# ----------------------------------------------------------------------------- profile segments
@dataclass(frozen=True)
class LineSegment:
    """Straight profile segment from ``(rho0, z0)`` to ``(rho1, z1)`` (mm)."""

    rho0: float
    z0: float
    rho1: float
    z1: float

    def points(self, n: int) -> np.ndarray:
        s = np.linspace(0.0, 1.0, n)[:, None]
        return np.array([self.rho0, self.z0]) * (1 - s) + np.array([self.rho1, self.z1]) * s


@dataclass(frozen=True)
class ArcSegment:
    """Circular profile arc: centre ``(rho_c, z_c)``, radius, from ``start`` to ``end`` (degrees).

    ``convex`` is True when the tool material lies inside the circle (ball, torus corner,
    drum), False when it lies outside (concave "hyperbolic" profile).
    """

    rho_c: float
    z_c: float
    radius: float
    start_deg: float
    end_deg: float
    convex: bool = True

    def points(self, n: int) -> np.ndarray:
        a = np.radians(np.linspace(self.start_deg, self.end_deg, n))
        return np.stack([self.rho_c + self.radius * np.cos(a), self.z_c + self.radius * np.sin(a)], axis=1)


@dataclass(frozen=True)
class SphereFamilySegment:
    """Spheres centred at ``(0, 0, a)`` with radius ``r(a)`` for ``a`` in ``[a0, a1]`` (mm).

    ``kind`` is "cone" (``r(a) = r0 + (a - a0) sin(angle)``, includes the cylinder) or "arc"
    (``r(a) = sigma * radius + sign(rho_c) * sqrt(rho_c^2 + (a - z_c)^2)``) or "point"
    (a single sphere: ``a0 == a1``, e.g. a ball end).
    """

    kind: str
    a0: float
    a1: float
    r0: float = 0.0
    angle_deg: float = 0.0
    rho_c: float = 0.0
    z_c: float = 0.0
    radius: float = 0.0
    convex: bool = True

    def r(self, a) -> np.ndarray:
        a = np.asarray(a, dtype=float)
        if self.kind == "cone":
            return self.r0 + (a - self.a0) * math.sin(math.radians(self.angle_deg))
        if self.kind == "point":
            return np.full_like(a, self.radius)
        sigma = 1.0 if self.convex else -1.0
        return sigma * self.radius + math.copysign(1.0, self.rho_c) * np.sqrt(self.rho_c ** 2 + (a - self.z_c) ** 2)

    def r_a(self, a) -> np.ndarray:
        """Derivative ``dr/da`` (dimensionless)."""
        a = np.asarray(a, dtype=float)
        if self.kind == "cone":
            return np.full_like(a, math.sin(math.radians(self.angle_deg)))
        if self.kind == "point":
            return np.zeros_like(a)
        return math.copysign(1.0, self.rho_c) * (a - self.z_c) / np.sqrt(self.rho_c ** 2 + (a - self.z_c) ** 2)

    def grazing_points(self, a) -> np.ndarray:
        """Profile points ``(rho, z)`` where the sphere at ``a`` touches the tool (not for "point")."""
        a = np.asarray(a, dtype=float)
        r = self.r(a)
        ra = self.r_a(a)
        # grazing circle: z = a - r r', rho = r sqrt(1 - r'^2)
        return np.stack([r * np.sqrt(np.clip(1 - ra * ra, 0, None)), a - r * ra], axis=-1)


def _num(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"cutter parameter {name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise InputError(f"cutter parameter {name} must be finite, got {value!r}")
    return x


def _positive(name: str, value) -> float:
    x = _num(name, value)
    if not x > 0:
        raise InputError(f"cutter parameter {name} must be > 0 mm, got {value!r}")
    return x


# ----------------------------------------------------------------------------- cutters
class Cutter:
    """Base of all cutters (frozen dataclasses): ``D`` diameter and ``length`` cutting length (mm)."""

    D: float
    length: float
    kind = "cutter"

    @property
    def radius(self) -> float:
        """Outer radius ``D/2`` (mm); the effective-radius paper's "R"."""
        return self.D / 2

    def profile(self) -> list:
        raise NotImplementedError

    def sphere_family(self) -> list[SphereFamilySegment]:
        """Sphere-family segments covering every non-planar part of the profile."""
        out = []
        for seg in self.profile():
            out.extend(_family_of(seg))
        return out

    def profile_points(self, n_per_segment: int = 32) -> np.ndarray:
        """Polyline ``(rho, z)`` of the whole profile, tip to top (mm)."""
        pts = [seg.points(n_per_segment) for seg in self.profile()]
        return np.concatenate(pts)

    def spec(self) -> str:
        """Canonical CLI string, e.g. ``bull:D=20,r=4`` (parse it back with :func:`parse_cutter`)."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        d = {"kind": self.kind, "spec": self.spec()}
        d.update({k: getattr(self, k) for k in self.__dataclass_fields__})
        return d


def _family_of(seg) -> list[SphereFamilySegment]:
    if isinstance(seg, LineSegment):
        drho, dz = seg.rho1 - seg.rho0, seg.z1 - seg.z0
        if abs(dz) < 1e-15:
            return []  # flat part perpendicular to the axis: plane, not a sphere family
        phi = math.atan2(drho, dz)  # taper angle, positive when widening upwards
        a0 = seg.z0 + seg.rho0 * math.tan(phi)
        a1 = seg.z1 + seg.rho1 * math.tan(phi)
        return [SphereFamilySegment("cone", a0, a1, r0=seg.rho0 / math.cos(phi), angle_deg=math.degrees(phi))]
    if abs(seg.rho_c) < 1e-12:
        return [SphereFamilySegment("point", seg.z_c, seg.z_c, radius=seg.radius, z_c=seg.z_c)]
    ends = []
    cut = math.radians(_AXIS_CUTOFF_DEG)
    for t_end, t_other in ((seg.start_deg, seg.end_deg), (seg.end_deg, seg.start_deg)):
        t = math.radians(t_end)
        # where the profile normal is parallel to the axis the sphere centre runs off to
        # infinity: the family stops where the normal is _AXIS_CUTOFF_DEG off the axis
        d0 = math.asin(min(1.0, abs(math.cos(t))))
        if d0 < cut:
            t += math.copysign(cut - d0, t_other - t_end)
        ends.append(seg.z_c - seg.rho_c * math.tan(t))
    a0, a1 = min(ends), max(ends)
    return [SphereFamilySegment("arc", a0, a1, rho_c=seg.rho_c, z_c=seg.z_c, radius=seg.radius, convex=seg.convex)]


@dataclass(frozen=True)
class BallEndMill(Cutter):
    """Ball end mill: hemispherical end of radius ``D/2`` (mm) on a cylinder."""

    D: float
    length: float = 0.0

    kind = "ball"

    def __post_init__(self):
        _positive("D", self.D)
        object.__setattr__(self, "length", _length(self.length, self.D))

    @property
    def r(self) -> float:
        return self.D / 2

    @property
    def corner_radius(self) -> float:
        return self.D / 2

    def profile(self):
        R = self.D / 2
        return [ArcSegment(0.0, R, R, -90.0, 0.0), LineSegment(R, R, R, self.length)]

    def spec(self):
        return f"ball:D={self.D:g}"


@dataclass(frozen=True)
class FlatEndMill(Cutter):
    """Flat (square) end mill of diameter ``D`` (mm)."""

    D: float
    length: float = 0.0

    kind = "flat"

    def __post_init__(self):
        _positive("D", self.D)
        object.__setattr__(self, "length", _length(self.length, self.D))

    r = 0.0
    corner_radius = 0.0

    @property
    def R_t(self) -> float:
        return self.D / 2

    def profile(self):
        R = self.D / 2
        return [LineSegment(0.0, 0.0, R, 0.0), LineSegment(R, 0.0, R, self.length)]

    def spec(self):
        return f"flat:D={self.D:g}"


@dataclass(frozen=True)
class BullNoseEndMill(Cutter):
    """Filleted (bull-nose, torus) end mill: diameter ``D``, corner radius ``r`` (mm).

    ``R_t = D/2 - r`` is the torus major radius ("R" in the machining-surface paper); the
    effective-radius paper's "R" is ``D/2``.
    """

    D: float
    r: float
    length: float = 0.0

    kind = "bull"

    def __post_init__(self):
        _positive("D", self.D)
        _positive("r", self.r)
        if self.r > self.D / 2:
            raise InputError(f"cutter parameter r = {self.r:g} mm exceeds D/2 = {self.D / 2:g} mm")
        object.__setattr__(self, "length", _length(self.length, self.D))

    @property
    def R_t(self) -> float:
        return self.D / 2 - self.r

    @property
    def corner_radius(self) -> float:
        return self.r

    def profile(self):
        R, r = self.D / 2, self.r
        segs = []
        if self.R_t > 0:
            segs.append(LineSegment(0.0, 0.0, self.R_t, 0.0))
        segs += [ArcSegment(self.R_t, r, r, -90.0, 0.0), LineSegment(R, r, R, self.length)]
        return segs

    def spec(self):
        return f"bull:D={self.D:g},r={self.r:g}"


@dataclass(frozen=True)
class ConicalCutter(Cutter):
    """Tapered (conical) cutter: tip diameter ``D`` (mm), half taper ``angle`` (degrees).

    ``angle > 0`` widens towards the shank, ``angle < 0`` narrows (dovetail-like). The flat
    tip is at z = 0; the cone's sphere family starts at the real tip, ``a0 = (D/2) tan(angle)``
    (the envelope paper's ``a0 = 0`` would start below the tip plane).
    """

    D: float
    angle: float
    length: float = 0.0

    kind = "cone"

    def __post_init__(self):
        _positive("D", self.D)
        a = _num("angle", self.angle)
        if not -45.0 < a < 89.0:
            raise InputError(f"cutter parameter angle must be in (-45, 89) degrees, got {a:g}")
        object.__setattr__(self, "length", _length(self.length, self.D))
        top = self.D / 2 + self.length * math.tan(math.radians(a))
        if top <= 0:
            raise InputError("cone narrows to a point below its length: reduce angle or length")

    def profile(self):
        R = self.D / 2
        top = R + self.length * math.tan(math.radians(self.angle))
        return [LineSegment(0.0, 0.0, R, 0.0), LineSegment(R, 0.0, top, self.length)]

    def spec(self):
        return f"cone:D={self.D:g},angle={self.angle:g}"


@dataclass(frozen=True)
class DrumCutter(Cutter):
    """Drum (barrel) cutter: largest diameter ``D`` at mid height, profile arc radius ``R_p``.

    ``concave=True`` gives the "hyperbolic" shape of the envelope paper (smallest diameter
    ``D`` at mid height). Height ``length`` (mm), flat ends.
    """

    D: float
    R_p: float
    length: float = 0.0
    concave: bool = False

    kind = "drum"

    def __post_init__(self):
        _positive("D", self.D)
        _positive("R_p", self.R_p)
        object.__setattr__(self, "length", _length(self.length, self.D))
        h = self.length / 2
        if self.R_p <= h:
            raise InputError(f"cutter parameter R_p = {self.R_p:g} mm must exceed half the length {h:g} mm")
        if self._end_radius() <= 0:
            raise InputError("drum profile reaches the axis: increase D or R_p")

    def _end_radius(self) -> float:
        h = self.length / 2
        sag = self.R_p - math.sqrt(self.R_p ** 2 - h ** 2)
        return self.D / 2 - sag if not self.concave else self.D / 2 + sag

    def profile(self):
        R, h = self.D / 2, self.length / 2
        end = self._end_radius()
        half = math.degrees(math.asin(h / self.R_p))
        if self.concave:
            arc = ArcSegment(R + self.R_p, h, self.R_p, 180.0 + half, 180.0 - half, convex=False)
        else:
            arc = ArcSegment(R - self.R_p, h, self.R_p, -half, half, convex=True)
        return [LineSegment(0.0, 0.0, end, 0.0), arc, LineSegment(end, self.length, 0.0, self.length)]

    def spec(self):
        return f"{'barrel' if self.concave else 'drum'}:D={self.D:g},Rp={self.R_p:g},L={self.length:g}"


@dataclass(frozen=True)
class APTCutter(Cutter):
    """Generic APT 7-parameter cutter ``(D, r, e, f, alpha, beta, h)``.

    ``D`` diameter at the corner's outer tangent, ``r`` corner radius, ``e`` and ``f`` the
    radial and axial position of the corner centre (mm), ``alpha`` the bottom angle and
    ``beta`` the side taper (degrees), ``h`` the height (mm). Only the common "consistent"
    family is accepted: the corner arc joins the bottom line and the side line tangentially.
    """

    D: float
    r: float
    e: float
    f: float
    alpha: float
    beta: float
    h: float
    length: float = 0.0

    kind = "apt"

    def __post_init__(self):
        _positive("D", self.D)
        for name in ("r", "e", "f"):
            if _num(name, getattr(self, name)) < 0:
                raise InputError(f"cutter parameter {name} must be >= 0 mm")
        _positive("h", self.h)
        if not 0 <= _num("alpha", self.alpha) < 90 or not -45 < _num("beta", self.beta) < 90:
            raise InputError("cutter parameters alpha in [0, 90) and beta in (-45, 90) degrees")
        object.__setattr__(self, "length", self.h)
        if self.r > self.D / 2 + 1e-12:
            raise InputError(f"cutter parameter r = {self.r:g} mm exceeds D/2 = {self.D / 2:g} mm")

    def profile(self):
        al, be = math.radians(self.alpha), math.radians(self.beta)
        segs = []
        # corner arc from the bottom tangent (normal angle -90+alpha... ) to the side tangent
        a_start = -90.0 + self.alpha
        a_end = -self.beta
        p_start = (self.e + self.r * math.cos(math.radians(a_start)), self.f + self.r * math.sin(math.radians(a_start)))
        p_end = (self.e + self.r * math.cos(math.radians(a_end)), self.f + self.r * math.sin(math.radians(a_end)))
        # bottom line from the axis to the arc start with slope alpha
        z_axis = p_start[1] - p_start[0] * math.tan(al)
        segs.append(LineSegment(0.0, z_axis, *p_start))
        if self.r > 0:
            segs.append(ArcSegment(self.e, self.f, self.r, a_start, a_end))
        top_rho = p_end[0] + (self.h - p_end[1]) * math.tan(be)
        segs.append(LineSegment(*p_end, top_rho, self.h))
        return segs

    def spec(self):
        return (f"apt:D={self.D:g},r={self.r:g},e={self.e:g},f={self.f:g},alpha={self.alpha:g},"
                f"beta={self.beta:g},h={self.h:g}")


def _length(length, D) -> float:
    x = _num("length", length) if length else 0.0
    if x < 0:
        raise InputError("cutter parameter length must be >= 0 mm")
    return x if x > 0 else 3.0 * _num("D", D)


def end_mill_radii(cutter: Cutter, purpose: str) -> tuple[str, float, float]:
    """``(kind, r, R_t)`` of a ball, flat or bull-nose end mill: corner radius and torus major radius (mm).

    Other cutters raise :class:`InputError` saying what ``purpose`` needs them for.
    """
    if cutter.kind not in ("ball", "flat", "bull"):
        raise InputError(f"{purpose} are defined for ball, flat and bull-nose end mills, not {cutter.spec()}")
    r = cutter.corner_radius
    return cutter.kind, r, cutter.D / 2 - r


# ----------------------------------------------------------------------------- strings
_KINDS = {
    "ball": (BallEndMill, {"D": "D", "L": "length"}),
    "flat": (FlatEndMill, {"D": "D", "L": "length"}),
    "cyl": (FlatEndMill, {"D": "D", "L": "length"}),  # a cylindrical (flank) cutter is a flat end mill
    "bull": (BullNoseEndMill, {"D": "D", "r": "r", "L": "length"}),
    "torus": (BullNoseEndMill, {"D": "D", "r": "r", "L": "length"}),
    "cone": (ConicalCutter, {"D": "D", "angle": "angle", "L": "length"}),
    "drum": (DrumCutter, {"D": "D", "Rp": "R_p", "L": "length"}),
    "barrel": (DrumCutter, {"D": "D", "Rp": "R_p", "L": "length"}),
    "apt": (APTCutter, {"D": "D", "r": "r", "e": "e", "f": "f", "alpha": "alpha", "beta": "beta", "h": "h"}),
}


def parse_cutter(text: str) -> Cutter:
    """Cutter from its CLI string, e.g. ``ball:D=10``, ``bull:D=20,r=4``, ``cone:D=10,angle=6``.

    Raises :class:`InputError` with a one-line message for an unknown kind or bad parameter.

    Examples
    --------
    >>> parse_cutter("bull:D=20,r=4").R_t
    6.0
    """
    m = re.fullmatch(r"\s*([A-Za-z]+)\s*:(.*)", text or "")
    if not m:
        raise InputError(f"cutter string {text!r} is not of the form kind:K=V,... (e.g. ball:D=10)")
    kind, rest = m.group(1).lower(), m.group(2)
    if kind not in _KINDS:
        raise InputError(f"unknown cutter kind {kind!r}; known: {', '.join(sorted(_KINDS))}")
    cls, names = _KINDS[kind]
    kwargs = {}
    for part in filter(None, (p.strip() for p in rest.split(","))):
        if "=" not in part:
            raise InputError(f"cutter parameter {part!r} is not K=V")
        k, v = (s.strip() for s in part.split("=", 1))
        if k not in names:
            raise InputError(f"unknown parameter {k!r} for {kind} cutter; expected {', '.join(names)}")
        kwargs[names[k]] = _num(k, v)
    if kind == "barrel":
        kwargs["concave"] = True
    try:
        return cls(**kwargs)
    except TypeError:
        missing = [k for k, v in names.items() if v not in kwargs and v != "length"]
        raise InputError(f"{kind} cutter needs parameters: {', '.join(missing)}") from None
