"""Cutter profiles in the (rho, z) half-plane: segments, sphere families, exact distances (mm, degrees).

The geometry behind :mod:`machsurf_cad.cutters`: line and arc profile segments, the sphere-family
segments of the envelope paper, and the signed distance of half-plane points to a closed profile
region (exact for lines and arcs: distance to each segment; inside by the profile's height and width).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

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
        return sigma * self.radius + math.copysign(1.0, self.rho_c) * np.sqrt(self.rho_c**2 + (a - self.z_c) ** 2)

    def r_a(self, a) -> np.ndarray:
        """Derivative ``dr/da`` (dimensionless)."""
        a = np.asarray(a, dtype=float)
        if self.kind == "cone":
            return np.full_like(a, math.sin(math.radians(self.angle_deg)))
        if self.kind == "point":
            return np.zeros_like(a)
        return math.copysign(1.0, self.rho_c) * (a - self.z_c) / np.sqrt(self.rho_c**2 + (a - self.z_c) ** 2)

    def grazing_points(self, a) -> np.ndarray:
        """Profile points ``(rho, z)`` where the sphere at ``a`` touches the tool (not for "point")."""
        a = np.asarray(a, dtype=float)
        r = self.r(a)
        ra = self.r_a(a)
        # grazing circle: z = a - r r', rho = r sqrt(1 - r'^2)
        return np.stack([r * np.sqrt(np.clip(1 - ra * ra, 0, None)), a - r * ra], axis=-1)


def _segment_z_at(seg, rho: np.ndarray, lowest: bool) -> np.ndarray:
    """z of the segment at radius rho (inf where it does not reach rho)."""
    if isinstance(seg, LineSegment):
        lo, hi = min(seg.rho0, seg.rho1), max(seg.rho0, seg.rho1)
        if hi - lo < 1e-15:
            z = np.where(np.abs(rho - lo) <= 1e-12, min(seg.z0, seg.z1), np.inf)
            return z
        t = (rho - seg.rho0) / (seg.rho1 - seg.rho0)
        z = seg.z0 + t * (seg.z1 - seg.z0)
        return np.where((rho >= lo - 1e-12) & (rho <= hi + 1e-12), z, np.inf)
    pts = _arc_points_at_rho(seg, rho)
    return pts


def _arc_points_at_rho(seg, rho):
    dx = rho - seg.rho_c
    inside = np.abs(dx) <= seg.radius + 1e-12
    dz = np.sqrt(np.clip(seg.radius**2 - dx * dx, 0, None))
    best = np.full(rho.shape, np.inf)
    for sgn in (-1.0, 1.0):
        z = seg.z_c + sgn * dz
        ang = np.degrees(np.arctan2(z - seg.z_c, dx))
        ok = inside & _angle_in(ang, seg.start_deg, seg.end_deg)
        best = np.where(ok, np.minimum(best, z), best)
    return best


def _angle_in(ang, a0, a1):
    lo, hi = min(a0, a1), max(a0, a1)
    ang = np.asarray(ang)
    return (
        ((ang >= lo - 1e-9) & (ang <= hi + 1e-9))
        | ((ang + 360 >= lo - 1e-9) & (ang + 360 <= hi + 1e-9))
        | ((ang - 360 >= lo - 1e-9) & (ang - 360 <= hi + 1e-9))
    )


def _segment_rho_at(seg, h: np.ndarray) -> np.ndarray:
    if isinstance(seg, LineSegment):
        lo, hi = min(seg.z0, seg.z1), max(seg.z0, seg.z1)
        if hi - lo < 1e-15:
            return np.where(np.abs(h - lo) <= 1e-12, max(seg.rho0, seg.rho1), 0.0)
        t = (h - seg.z0) / (seg.z1 - seg.z0)
        r = seg.rho0 + t * (seg.rho1 - seg.rho0)
        return np.where((h >= lo - 1e-12) & (h <= hi + 1e-12), r, 0.0)
    dz = h - seg.z_c
    inside = np.abs(dz) <= seg.radius + 1e-12
    dr = np.sqrt(np.clip(seg.radius**2 - dz * dz, 0, None))
    best = np.zeros(h.shape)
    for sgn in (-1.0, 1.0):
        r = seg.rho_c + sgn * dr
        ang = np.degrees(np.arctan2(dz, sgn * dr))
        ok = inside & _angle_in(ang, seg.start_deg, seg.end_deg)
        best = np.where(ok, np.maximum(best, r), best)
    return best


def _segment_distance(seg, rho, z) -> np.ndarray:
    if isinstance(seg, LineSegment):
        a = np.array([seg.rho0, seg.z0])
        b = np.array([seg.rho1, seg.z1])
        ab = b - a
        L2 = float(ab @ ab)
        t = np.clip(((rho - a[0]) * ab[0] + (z - a[1]) * ab[1]) / L2, 0, 1) if L2 > 0 else np.zeros_like(rho)
        return np.hypot(rho - a[0] - t * ab[0], z - a[1] - t * ab[1])
    dx, dz = rho - seg.rho_c, z - seg.z_c
    ang = np.degrees(np.arctan2(dz, dx))
    on = _angle_in(ang, seg.start_deg, seg.end_deg)
    d_circle = np.abs(np.hypot(dx, dz) - seg.radius)
    ends = seg.points(2)
    d_end = np.minimum(np.hypot(rho - ends[0, 0], z - ends[0, 1]), np.hypot(rho - ends[1, 0], z - ends[1, 1]))
    return np.where(on, np.minimum(d_circle, d_end), d_end)


def rounded_core_distance(R_t: float, r: float, L: float, rho, z) -> np.ndarray:
    """Exact signed distance (mm, inside < 0) to the half-section of a flat (``r = 0``), bull-nose or
    ball (``R_t = 0``) end mill closed by its top at ``z = L >= r``: the rectangle ``[0, R_t] x [r, L]``
    grown by ``r`` (a Minkowski sum with a disc: its distance is the rectangle's minus ``r``), cut at
    ``z = L``. Equal to :func:`_region_distance` on the same profile (tested), a few times faster."""
    qx = rho - R_t
    below = r - z
    qz = np.maximum(below, z - L)
    box = np.hypot(np.maximum(qx, 0.0), np.maximum(qz, 0.0)) + np.minimum(np.maximum(qx, qz), 0.0)
    d = box - r
    # inside: the top plane may be nearer than the rounded side; above the top: to the top disc
    d = np.where(d < 0, np.maximum(d, z - L), d)
    return np.where(z > L, np.hypot(np.maximum(rho - R_t - r, 0.0), z - L), d)


def _region_distance(segs, rho, z) -> np.ndarray:
    """Signed distance to the half-section region bounded by ``segs`` and the axis (inside < 0)."""
    d = np.full(rho.shape, np.inf)
    for seg in segs:
        d = np.minimum(d, _segment_distance(seg, rho, z))
    # inside, exactly: above the lowest boundary at rho, within the width at z, below the top
    low = np.full(rho.shape, np.inf)
    wid = np.zeros(rho.shape)
    top = -np.inf
    for seg in segs:
        low = np.minimum(low, _segment_z_at(seg, rho, lowest=True))
        wid = np.maximum(wid, _segment_rho_at(seg, z))
        top = max(top, float(seg.points(2)[:, 1].max()))
    inside = (z > low) & (rho < wid) & (z < top)
    return np.where(inside, -d, d)


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


def lower_height(segs, rho) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The profile's lower surface ``h(rho)`` and its derivatives ``h'``, ``h''`` (mm, 1, 1/mm).

    ``h`` is the lowest profile height at radius ``rho`` (``inf`` where no segment reaches it), as
    :meth:`Cutter.height`; the derivatives are exact for the segment giving that height (lines: slope
    and 0; arcs: ``-+(rho - rho_c) / sqrt(r^2 - (rho - rho_c)^2)`` and ``r^2 / (...)^(3/2)``). They are
    clipped to ``+-1e8`` where an arc turns vertical (a ball's equator)."""
    rho = np.abs(np.asarray(rho, float))
    h = np.full(rho.shape, np.inf)
    h1 = np.zeros(rho.shape)
    h2 = np.zeros(rho.shape)
    for seg in segs:
        if isinstance(seg, LineSegment):
            if abs(seg.rho1 - seg.rho0) < 1e-15:
                continue  # a vertical side: the rim, not a height
            z = _segment_z_at(seg, rho, lowest=True)
            better = z < h
            h = np.where(better, z, h)
            h1 = np.where(better, (seg.z1 - seg.z0) / (seg.rho1 - seg.rho0), h1)
            h2 = np.where(better, 0.0, h2)
            continue
        dx = rho - seg.rho_c
        inside = np.abs(dx) <= seg.radius + 1e-12
        root = np.sqrt(np.clip(seg.radius**2 - dx * dx, 0, None))
        for sgn in (-1.0, 1.0):
            z = seg.z_c + sgn * root
            ang = np.degrees(np.arctan2(z - seg.z_c, dx))
            better = inside & _angle_in(ang, seg.start_deg, seg.end_deg) & (z < h)
            safe = np.maximum(root, 1e-8 * seg.radius)
            h = np.where(better, z, h)
            h1 = np.where(better, np.clip(-sgn * dx / safe, -1e8, 1e8), h1)
            h2 = np.where(better, np.clip(-sgn * seg.radius**2 / safe**3, -1e8, 1e8), h2)
    return h, h1, h2
