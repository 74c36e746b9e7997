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
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .cutter_profiles import (
    ArcSegment,
    LineSegment,
    SphereFamilySegment,
    _family_of,
    _region_distance,
    _segment_rho_at,
    _segment_z_at,
    rounded_core_distance,
)
from .errors import InputError


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
@dataclass(frozen=True)
class Shank:
    """A plain cylinder above the cutting part (shank) or above the shank (holder), mm."""

    diameter: float
    length: float

    def __post_init__(self):
        _positive("shank/holder diameter", self.diameter)
        _positive("shank/holder length", self.length)


class EndMillRadii(NamedTuple):
    """Radii of a ball, flat or bull-nose end mill (mm): the one radius helper.

    ``r`` corner radius, ``R_t = D/2 - r`` torus major radius (the machining-surface paper's
    "R"), ``R = D/2`` outer radius (the effective-radius paper's "R").
    """

    r: float
    R_t: float
    R: float

    @property
    def is_ball(self) -> bool:
        """True for a ball end mill (R_t = 0)."""
        return self.R_t == 0.0

    @property
    def is_flat(self) -> bool:
        """True for a flat end mill (r = 0)."""
        return self.r == 0.0


class Cutter:
    """Base of all cutters (frozen dataclasses): ``D`` diameter and ``length`` cutting length (mm).

    The shared vocabulary (after OpenCAMLib's ``height(r)``, ``width(h)``, ``offsetCutter(d)``)
    is methods here, computed from the profile: :meth:`height`, :meth:`width`, :meth:`offset`,
    :meth:`signed_distance`, :meth:`apt_parameters`, :meth:`end_mill_radii`; optional
    ``shank`` and ``holder`` cylinders extend the body upwards.
    """

    D: float
    length: float
    shank: Shank | None
    holder: Shank | None
    kind = "cutter"

    @property
    def radius(self) -> float:
        """Outer radius ``D/2`` (mm); the effective-radius paper's "R"."""
        return self.D / 2

    @property
    def corner_radius(self) -> float:
        """Corner radius r (mm); 0 where the cutter has no corner arc."""
        return 0.0

    @property
    def torus_radius(self) -> float:
        """Distance from the axis to the corner centre ``R_t = D/2 - r`` (mm)."""
        return self.D / 2 - self.corner_radius

    def profile(self) -> list:
        raise NotImplementedError

    def sphere_family(self) -> list[SphereFamilySegment]:
        """Sphere-family segments covering every non-planar part of the profile."""
        out = []
        for seg in self.profile():
            out.extend(_family_of(seg))
        return out

    def sweep_segment(self) -> SphereFamilySegment:
        """The sphere-family segment that sweeps a flank envelope: the side (cylinder or cone)."""
        return self.sphere_family()[-1]

    def profile_points(self, n_per_segment: int = 32) -> np.ndarray:
        """Polyline ``(rho, z)`` of the whole profile, tip to top (mm)."""
        pts = [seg.points(n_per_segment) for seg in self.profile()]
        return np.concatenate(pts)

    def spec(self) -> str:
        """Canonical CLI string, e.g. ``bull:D=20,r=4`` (parse it back with :func:`parse_cutter`)."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        d: dict = {"kind": self.kind, "spec": self.spec()}
        for k in self.__dataclass_fields__:  # type: ignore[attr-defined]
            v = getattr(self, k)
            d[k] = None if v is None else (v if not isinstance(v, Shank) else [v.diameter, v.length])
        return d

    # ------------------------------------------------------------------ shared vocabulary
    def end_mill_radii(self, purpose: str) -> EndMillRadii:
        """``(r, R_t, R)`` of a ball, flat or bull-nose end mill (mm).

        Other cutters raise :class:`InputError` saying what ``purpose`` needs them for.
        """
        raise InputError(f"{purpose} are defined for ball, flat and bull-nose end mills, not {self.spec()}")

    def height(self, rho) -> np.ndarray:
        """Height of the tool's lower surface above the tip at distance ``rho`` from the axis (mm).

        ``inf`` beyond the tool's largest radius (OpenCAMLib's ``height(r)``).

        >>> BullNoseEndMill(20, 4).height([0.0, 6.0, 10.0]).round(12).tolist()
        [0.0, 0.0, 4.0]
        """
        rho = np.abs(np.asarray(rho, float))
        out = np.full(rho.shape, np.inf)
        for seg in self.profile():
            out = np.minimum(out, _segment_z_at(seg, rho, lowest=True))
        return out

    def width(self, h) -> np.ndarray:
        """Radius of the tool at height ``h`` above the tip (mm); 0 outside ``[0, length]``
        (OpenCAMLib's ``width(h)``).

        >>> BallEndMill(10).width([0.0, 5.0]).round(12).tolist()
        [0.0, 5.0]
        """
        h = np.asarray(h, float)
        out = np.zeros(h.shape)
        for seg in self.profile():
            out = np.maximum(out, _segment_rho_at(seg, h))
        return out

    def offset(self, d: float) -> Cutter:
        """The cutter grown by ``d`` mm normal to its surface (OpenCAMLib's ``offsetCutter``):
        ball D -> ball D + 2d, flat D -> bull (D + 2d, r = d), bull (D, r) -> bull (D + 2d, r + d)."""
        raise InputError(f"the offset of {self.spec()} is not a cutter of this library (ball, flat or bull only)")

    def apt_parameters(self) -> tuple[float, float, float, float, float, float, float]:
        """The APT 7 parameters ``(d, r, e, f, alpha, beta, h)``: diameter, corner radius, radial
        and axial position of the corner centre (mm), bottom and side angles (degrees), height (mm).
        One convention for every tool: a flat end mill is ``(D, 0, D/2, 0, 0, 0, h)``."""
        raise NotImplementedError

    def body_parts(self) -> list[tuple[float, float, float]]:
        """The cylinders above the cutting part: ``(radius, z_bottom, z_top)`` of shank and holder (mm)."""
        out = []
        z = self.length
        for part in (self.shank, self.holder):
            if part is not None:
                out.append((part.diameter / 2, z, z + part.length))
                z += part.length
        return out

    def signed_distance(self, points, *, tip=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)) -> np.ndarray:
        """Signed distance (mm) of 3-D points to the tool body placed with its tip at ``tip`` and unit
        ``axis`` (tip towards shank): negative inside the body, positive outside.

        The body is the profile revolved about the axis and closed by its top, plus the shank and
        holder cylinders. Exact for line and arc profiles (distances to each segment).

        >>> float(BallEndMill(10).signed_distance([[0.0, 0.0, -1.0]])[0])
        1.0
        >>> float(FlatEndMill(10).signed_distance([[0.0, 0.0, 1.0]])[0])
        -1.0
        """
        p = np.asarray(points, float).reshape(-1, 3) - np.asarray(tip, float)
        a = np.asarray(axis, float)
        a = a / np.linalg.norm(a)
        z = p @ a
        rho = np.linalg.norm(p - z[:, None] * a, axis=1)
        d = _region_distance(self._outline(), rho, z)
        for R_, z0, z1 in self.body_parts():
            box = [LineSegment(0.0, z0, R_, z0), LineSegment(R_, z0, R_, z1), LineSegment(R_, z1, 0.0, z1)]
            d = np.minimum(d, _region_distance(box, rho, z))
        return d.reshape(np.shape(points)[:-1])

    def cutting_distance_rz(self, rho, z) -> np.ndarray:
        """Signed distance (mm) of half-plane points ``(rho, z)`` (tool frame) to the cutting part's body
        (the revolved profile closed by its top): negative inside."""
        rho = np.asarray(rho, float)
        z = np.asarray(z, float)
        core = self._rounded_core()
        if core is not None:
            return rounded_core_distance(*core, rho, z)
        return _region_distance(self._outline(), rho, z)

    def _rounded_core(self) -> tuple[float, float, float] | None:
        """``(R_t, r, length)`` where the cutting part is a rectangle grown by a disc of radius ``r``
        (ball, flat, bull-nose with ``length >= r``), else None."""
        return None

    def holder_distance_rz(self, rho, z) -> np.ndarray:
        """Signed distance (mm) of ``(rho, z)`` to the shank and holder cylinders (``inf`` without them)."""
        rho = np.asarray(rho, float)
        z = np.asarray(z, float)
        d = np.full(np.broadcast_shapes(rho.shape, z.shape), np.inf)
        for R_, z0, z1 in self.body_parts():
            box = [LineSegment(0.0, z0, R_, z0), LineSegment(R_, z0, R_, z1), LineSegment(R_, z1, 0.0, z1)]
            d = np.minimum(d, _region_distance(box, rho, z))
        return d

    def max_radius(self) -> float:
        """Largest radius of the whole body (cutting part, shank, holder), mm."""
        r = float(self.profile_points(16)[:, 0].max())
        return max([r] + [p[0] for p in self.body_parts()])

    def body_length(self) -> float:
        """Height of the whole body above the tip (cutting length plus shank and holder), mm."""
        parts = self.body_parts()
        return parts[-1][2] if parts else float(self.length)

    def _outline(self) -> list:
        """The closed half-section boundary without the axis: profile and top cap."""
        segs = list(self.profile())
        last = segs[-1]
        end = last.points(2)[-1]
        if end[0] > 1e-12:
            segs.append(LineSegment(float(end[0]), float(end[1]), 0.0, float(end[1])))
        return segs


@dataclass(frozen=True)
class BallEndMill(Cutter):
    """Ball end mill: hemispherical end of radius ``D/2`` (mm) on a cylinder."""

    D: float
    length: float = 0.0

    shank: Shank | None = None
    holder: Shank | None = None

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

    def end_mill_radii(self, purpose: str) -> EndMillRadii:
        return EndMillRadii(self.D / 2, 0.0, self.D / 2)

    def offset(self, d: float) -> Cutter:
        return BallEndMill(self.D + 2 * _num("d", d), self.length, self.shank, self.holder)

    def apt_parameters(self):
        R = self.D / 2
        return (self.D, R, 0.0, R, 0.0, 0.0, self.length)

    def sweep_segment(self) -> SphereFamilySegment:
        return self.sphere_family()[0]  # the ball's single sphere

    def profile(self):
        R = self.D / 2
        return [ArcSegment(0.0, R, R, -90.0, 0.0), LineSegment(R, R, R, self.length)]

    def _rounded_core(self):
        return (0.0, self.D / 2, self.length) if self.length >= self.D / 2 else None

    def spec(self):
        return f"ball:D={self.D:g}"


@dataclass(frozen=True)
class FlatEndMill(Cutter):
    """Flat (square) end mill of diameter ``D`` (mm)."""

    D: float
    length: float = 0.0

    shank: Shank | None = None
    holder: Shank | None = None

    kind = "flat"

    def __post_init__(self):
        _positive("D", self.D)
        object.__setattr__(self, "length", _length(self.length, self.D))

    r = 0.0

    @property
    def R_t(self) -> float:
        return self.D / 2

    def end_mill_radii(self, purpose: str) -> EndMillRadii:
        return EndMillRadii(0.0, self.D / 2, self.D / 2)

    def offset(self, d: float) -> Cutter:
        d = _num("d", d)
        return BullNoseEndMill(self.D + 2 * d, d, self.length, self.shank, self.holder) if d > 0 else self

    def apt_parameters(self):
        return (self.D, 0.0, self.D / 2, 0.0, 0.0, 0.0, self.length)

    def profile(self):
        R = self.D / 2
        return [LineSegment(0.0, 0.0, R, 0.0), LineSegment(R, 0.0, R, self.length)]

    def _rounded_core(self):
        return (self.D / 2, 0.0, self.length)

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

    shank: Shank | None = None
    holder: Shank | None = None

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

    def end_mill_radii(self, purpose: str) -> EndMillRadii:
        return EndMillRadii(self.r, self.D / 2 - self.r, self.D / 2)

    def offset(self, d: float) -> Cutter:
        d = _num("d", d)
        return BullNoseEndMill(self.D + 2 * d, self.r + d, self.length, self.shank, self.holder)

    def apt_parameters(self):
        return (self.D, self.r, self.D / 2 - self.r, self.r, 0.0, 0.0, self.length)

    def profile(self):
        R, r = self.D / 2, self.r
        segs = []
        if self.R_t > 0:
            segs.append(LineSegment(0.0, 0.0, self.R_t, 0.0))
        segs += [ArcSegment(self.R_t, r, r, -90.0, 0.0), LineSegment(R, r, R, self.length)]
        return segs

    def _rounded_core(self):
        return (self.R_t, self.r, self.length) if self.length >= self.r else None

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

    shank: Shank | None = None
    holder: Shank | None = None

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

    def apt_parameters(self):
        return (self.D, 0.0, self.D / 2, 0.0, 0.0, float(self.angle), self.length)

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

    shank: Shank | None = None
    holder: Shank | None = None

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
        sag = self.R_p - math.sqrt(self.R_p**2 - h**2)
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

    def sweep_segment(self) -> SphereFamilySegment:
        return next(sg for sg in self.sphere_family() if sg.kind == "arc")

    def apt_parameters(self):
        """APT has no drum: the arc as the corner ``(D, R_p, D/2 - R_p, L/2, 0, 0, L)`` (e < 0 for a drum)."""
        sign = -1.0 if self.concave else 1.0
        return (self.D, self.R_p, self.D / 2 - sign * self.R_p, self.length / 2, 0.0, 0.0, self.length)

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

    shank: Shank | None = None
    holder: Shank | None = None

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

    @property
    def corner_radius(self) -> float:
        return self.r

    def apt_parameters(self):
        return (self.D, self.r, self.e, self.f, self.alpha, self.beta, self.h)

    def spec(self):
        return (
            f"apt:D={self.D:g},r={self.r:g},e={self.e:g},f={self.f:g},alpha={self.alpha:g},"
            f"beta={self.beta:g},h={self.h:g}"
        )


def _length(length, D) -> float:
    x = _num("length", length) if length else 0.0
    if x < 0:
        raise InputError("cutter parameter length must be >= 0 mm")
    return x if x > 0 else 3.0 * _num("D", D)
