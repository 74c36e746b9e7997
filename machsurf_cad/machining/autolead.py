"""Gouge-free lead angles for a filleted end mill in 5 axes: ``machining_surface(..., lead="auto")`` (degrees, mm).

Second-order criterion at every contact: with lead ``lam`` and no tilt, the leaned bottom of a
filleted end mill rises away from the contact like a curve of radius ``R_eff(lam) = R_t / sin(lam) + r``
(across the feed this is relation (30) of the effective-radius paper with S = lam, alpha = 0; behind
the contact, along the feed, the same radius gives the rear-gouge threshold, checked against a brute
force in the tests). The tool does not cut beside or behind the contact when the surface curves less
than that in every direction:

* ``1 / R_eff(lam) >= k_max``, i.e. ``sin(lam) >= R_t / (1 / k_max - r)`` where the surface is concave
  for the tool (``k_max > 0``: its largest normal curvature towards the outward normal);
* ``1 / r >= k_max`` is needed whatever the lead (such points are reported as unreachable).

The smallest admissible lead per grid point, plus ``margin_deg``, and at least ``min_deg``, is then
raised to the smallest field that changes by at most ``rate_deg_per_mm`` per mm of surface (a
Lipschitz upper envelope: the axis never turns faster than that, and never below the local need),
blurred (Gaussian, 2 grid cells) and lifted by the most the blur removed anywhere, so that the
field is smooth (S2 follows the axis and must be fitted) and still above the need everywhere.
With ``check_faces`` the tool body is then checked (:func:`machsurf_cad.verify`) at a 61 x 61 grid of
placements against those faces; where it still gouges (its heel reaches farther than second order
sees), the need there and around is raised by ``bump_deg`` and the field rebuilt, up to
``max_rounds`` times. The written path is checked again as every path is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DegenerateGeometryError, InputError
from .strategies import LocalFrame


def concave_curvature(face, us, vs):
    """The largest normal curvature (1/mm) towards the face's outward normal (concave for the tool; OCCT's
    principal curvatures are signed towards su x sv) on the grid ``us x vs``, and the local properties."""
    from ..geometry.differential import local_properties_grid

    p = local_properties_grid(face.surface, us, vs)
    flip = -1.0 if face.reversed else 1.0
    return np.maximum(flip * p.k1, flip * p.k2), p


def minimum_lead(R_t: float, r: float, k_f, *, margin_deg: float = 0.0, min_deg: float = 0.0):
    """Smallest lead (degrees) with ``R_t / sin(lead) + r <= 1 / k_f``; NaN where none exists."""
    k_f = np.asarray(k_f, float)
    rho = np.where(k_f > 0, 1.0 / np.where(k_f > 0, k_f, 1.0), np.inf)
    room = rho - r
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(np.isinf(rho), 0.0, R_t / room)
    lead = np.where((room > 0) & (s <= 1.0), np.degrees(np.arcsin(np.clip(s, 0, 1))), np.nan)
    return np.maximum(lead + margin_deg, min_deg)


def lipschitz_envelope(field: np.ndarray, du_mm: np.ndarray, dv_mm: np.ndarray, rate: float, sweeps: int = 4):
    """The smallest grid function >= ``field`` whose change between neighbours is at most ``rate`` times
    their distance (mm): forward/backward sweeps along u and v (a chamfer distance transform)."""
    g = field.copy()
    for _ in range(sweeps):
        for i in range(1, g.shape[0]):
            g[i] = np.maximum(g[i], g[i - 1] - rate * du_mm[i - 1])
        for i in range(g.shape[0] - 2, -1, -1):
            g[i] = np.maximum(g[i], g[i + 1] - rate * du_mm[i])
        for j in range(1, g.shape[1]):
            g[:, j] = np.maximum(g[:, j], g[:, j - 1] - rate * dv_mm[:, j - 1])
        for j in range(g.shape[1] - 2, -1, -1):
            g[:, j] = np.maximum(g[:, j], g[:, j + 1] - rate * dv_mm[:, j])
    return g


@dataclass(frozen=True)
class LeadField:
    """5-axis axis with a lead that varies over the face (degrees on a (u, v) grid, bilinear), no tilt."""

    us: np.ndarray
    vs: np.ndarray
    lead_deg: np.ndarray
    feed: Any
    label: str = "automatic lead"
    info: dict | None = None

    def __post_init__(self) -> None:
        from scipy.interpolate import RegularGridInterpolator

        # built once: the fits evaluate the axis on every refinement grid
        interp = RegularGridInterpolator(
            (self.us, self.vs), self.lead_deg, method="cubic", bounds_error=False, fill_value=None
        )
        object.__setattr__(self, "_interp", interp)

    def lead_at(self, u, v) -> np.ndarray:
        return self._interp(np.stack([np.ravel(u), np.ravel(v)], -1)).reshape(np.shape(u))  # type: ignore[attr-defined]

    def axis(self, frame: LocalFrame) -> np.ndarray:
        f = self.feed.feed(frame)
        lt = np.radians(self.lead_at(frame.U, frame.V))[..., None]
        return np.cos(lt) * frame.normal + np.sin(lt) * f

    def describe(self) -> str:
        return (
            f"{self.label} {float(np.min(self.lead_deg)):.3g}..{float(np.max(self.lead_deg)):.3g} deg, "
            f"feed {self.feed.describe()}"
        )


def _smooth_field(need, du_mm, dv_mm, rate):
    """Rate-bounded envelope of the need, blurred and lifted back above it (see the module docstring)."""
    from scipy.ndimage import gaussian_filter

    env = lipschitz_envelope(need, du_mm, dv_mm, rate)
    blur = gaussian_filter(env, sigma=2.0, mode="nearest")
    return blur + max(0.0, float((env - blur).max()))


def auto_lead(
    face,
    cutter,
    feed,
    *,
    margin_deg: float = 1.0,
    min_deg: float = 0.0,
    rate_deg_per_mm: float = 2.0,
    grid: int = 61,
    check_faces=None,
    check_tolerance: float = 0.01,
    bump_deg: float = 1.0,
    max_rounds: int = 6,
    gouging=None,
) -> tuple[LeadField, dict]:
    """The gouge-free lead field of a bull-nose (or flat) end mill on ``face`` for ``feed`` (see module doc).

    Returns the field and a report: the lead range used, the local need's range, the rate bound, and
    the points where no lead avoids a local gouge (across-feed concavity tighter than r, or along the
    feed tighter than R_t + r). With ``check_faces``, ``gouging(field, us, vs, inside, check_faces,
    tolerance)`` gives the grid placements where the whole tool still gouges and how deep (the caller's
    body check: :func:`~machsurf_cad.machining.surfaces.lead_field_gouges`).
    """
    em = cutter.end_mill_radii("automatic lead")
    if em.is_ball:
        raise InputError("a ball end mill needs no lead against gouging: give a fixed lead")
    for name, x in (("margin_deg", margin_deg), ("min_deg", min_deg), ("rate_deg_per_mm", rate_deg_per_mm)):
        if not np.isfinite(x) or x < 0:
            raise InputError(f"{name} must be >= 0")
    u0, u1, v0, v1 = face.uv_bounds
    us, vs = np.linspace(u0, u1, grid), np.linspace(v0, v1, grid)
    U, V = np.meshgrid(us, vs, indexing="ij")
    k_max, p = concave_curvature(face, us, vs)
    need = minimum_lead(em.R_t, em.r, k_max, margin_deg=margin_deg, min_deg=min_deg)
    inside = face.contains_uv(U, V) if face.is_trimmed else np.ones(need.shape, bool)
    across = (em.r > 0) & (k_max * em.r > 1.0)
    bad = inside & (np.isnan(need) | across)
    need = np.where(np.isnan(need), 89.0, need)
    if np.any(bad):
        i = np.argwhere(bad)[0]
        raise DegenerateGeometryError(
            f"no lead avoids a local gouge at {int(bad.sum())} of {int(inside.sum())} grid point(s), e.g. (u, v) = "
            f"({us[i[0]]:.4g}, {vs[i[1]]:.4g}): the surface is concave tighter than the tool can follow "
            f"(R_t + r = {em.R_t + em.r:g} mm along the feed, r = {em.r:g} mm across)",
            {"uv": np.stack([U[bad], V[bad]], -1)[:20].tolist()},
        )
    du_mm = np.linalg.norm(np.diff(p.point, axis=0), axis=-1)
    dv_mm = np.linalg.norm(np.diff(p.point, axis=1), axis=-1)
    lead = _smooth_field(need, du_mm, dv_mm, rate_deg_per_mm)
    rounds = []
    if check_faces is not None:
        # the global body check on a grid of tool placements: where the tool still gouges (its rear
        # reaching farther than second order sees), raise the need and rebuild the field
        if gouging is None:
            raise InputError("auto_lead with check_faces needs the body check (gouging=...)")
        for _ in range(max_rounds):  # the placements on the lead grid itself: a gouge marks its own cell
            bad, depth = gouging(LeadField(us, vs, lead, feed), us, vs, inside, check_faces, check_tolerance)
            rounds.append({"gouging_placements": int(bad.sum()), "max_gouge_mm": float(depth.max())})
            if not bad.any():
                break
            for i, j in np.argwhere(bad):
                sl = (slice(max(0, i - 3), i + 4), slice(max(0, j - 3), j + 4))
                need[sl] = np.maximum(need[sl], lead[sl] + bump_deg)
            lead = _smooth_field(need, du_mm, dv_mm, rate_deg_per_mm)
    if np.max(lead) > 89.0:
        raise DegenerateGeometryError("the automatic lead would exceed 89 deg: the tool cannot follow this face")
    rep = {
        "lead_min_deg": float(lead[inside].min()),
        "lead_max_deg": float(lead[inside].max()),
        "local_need_max_deg": float(need[inside].max()),
        "margin_deg": margin_deg,
        "min_deg": min_deg,
        "rate_bound_deg_per_mm": rate_deg_per_mm,
        "grid": [grid, grid],
        "criterion": "R_t / sin(lead) + r <= 1 / k_max (largest concave curvature), r <= 1 / k_max",
        "body_check_rounds": rounds,
        "body_check_tolerance_mm": check_tolerance if check_faces is not None else None,
    }
    return LeadField(us, vs, lead, feed, info=rep), rep


__all__ = ["auto_lead", "minimum_lead", "concave_curvature", "lipschitz_envelope", "LeadField"]
