"""Effective cutter radius and step-over maps (lengths in mm, angles in degrees).

Effective radius of a cutter moving in translation, at the cutter-contact point, in the plane
normal to the feed (after "Study of the effective cutter radius for end milling of free-form
surfaces using a torus milling cutter", relation (30)):

    R_eff = (R - r) cos^2(alpha) / (sin(S) * Q) + r,   Q = cos^2(alpha) + sin^2(alpha) cos^2(S)

* ``R`` the cutter's outer radius ``D/2`` (the paper's "R"), ``r`` its corner radius, so
  ``R - r = R_t`` the torus major radius;
* ``S`` the slope: angle between the tool axis and the surface normal at the contact point;
* ``alpha`` the angle between the steepest-slope direction and the feed direction, both
  projected on the plane normal to the tool axis.

``Q`` is the paper's ``1 - sin^2(alpha) sin^2(S)`` written without its cancellation when both
angles approach 90 degrees. Special cases, handled explicitly: ``S = 0`` (flat spot, horizontal
feed): infinite, reported as ``inf`` and counted; ``alpha = +-90 deg``: ``r``; ``S = 90 deg``
(vertical feed): ``R`` (for ``alpha != 90 deg``). Ball end mill: ``R`` everywhere. Flat end mill:
the torus with ``r = 0``, i.e. ``R / sin(phi)`` for a feed along the steepest slope.

Step-over from scallop height: :mod:`machsurf_cad.scallop`.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from scipy.special import cosdg, sindg

from .chunking import split_map
from .cutters import Cutter
from .errors import DegenerateGeometryError, InputError
from .geometry.bspline import BSplineSurface
from .geometry.face import Face
from .geometry.normals import unit_normals
from .glossary import renamed
from .results import Result
from .scallop import stepover
from .toolspec import parse_cutter
from .typing import ArrayLike, FaceLike, MapChunks, ToolLike

_S_FLAT_DEG = 1e-9  # slopes below this are a flat spot: R_eff is infinite


_PURPOSE = "effective radius maps"


def _check_angles(name: str, deg) -> np.ndarray:
    a = np.asarray(deg, dtype=float)
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite degrees")
    return a


@renamed(cutter="tool", slope_deg="slope", alpha_deg="alpha")
def effective_radius(tool: ToolLike, slope: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """Effective radius (mm) of a cutter for slope ``S`` and angle ``alpha`` (degrees), vectorised.

    Parameters
    ----------
    tool : Cutter or str
        Ball, flat or bull-nose end mill (mm).
    slope : float or array_like
        Slope S of the surface: angle between its normal and the tool axis, degrees.
    alpha : float or array_like
        Angle between the steepest slope and the feed, projected normal to the axis, degrees.

    Returns
    -------
    ndarray
        Relation (30), ``R_t cos^2 a / (sin S (cos^2 a + sin^2 a cos^2 S)) + r`` (mm); ``inf`` at
        flat spots (``S = 0``, horizontal feed) for flat and bull-nose cutters.

    Raises
    ------
    InputError
        Angles outside [-360, 360] (radians given by mistake), not an end mill.

    Examples
    --------
    >>> float(effective_radius("bull:D=10,r=2", 30.0, 0.0))  # R_t / sin(S) + r
    8.0
    >>> float(effective_radius("bull:D=10,r=2", 30.0, 90.0))
    2.0
    >>> float(effective_radius("ball:D=10", 30.0, 45.0))
    5.0
    """
    c = parse_cutter(tool) if isinstance(tool, str) else tool
    em = c.end_mill_radii(_PURPOSE)
    R, r = em.R, em.r
    S = _check_angles("slope", slope)
    al = _check_angles("alpha", alpha)
    S, al = np.broadcast_arrays(S, al)
    if em.is_ball:
        return np.full(S.shape, R)
    # sines and cosines of angles in degrees, exact near multiples of 90 deg (no pi/2 rounding)
    sS, cS = sindg(S), cosdg(S)
    ca, sa = cosdg(al), sindg(al)
    ca2 = ca * ca
    q = ca2 + sa * sa * cS * cS  # = 1 - sin^2(alpha) sin^2(S), without cancellation
    flat = np.abs(S) < _S_FLAT_DEG
    perp = ca2 < 1e-30  # alpha = +-90 deg exactly (in floating point)
    num = (R - r) * ca2
    den = np.abs(sS) * q
    with np.errstate(divide="ignore", invalid="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf) + r
    val = np.where(perp, r, val)
    val = np.where(flat & ~perp, np.inf, val)
    return val


# ----------------------------------------------------------------------------- maps
@dataclass(frozen=True, eq=False)
class DirectionMap(Result):
    """Maps for one machining direction ``theta_deg`` (feed projection angle with machine X)."""

    theta_deg: float
    slope_deg: np.ndarray
    alpha_deg: np.ndarray
    r_eff: np.ndarray
    rho: np.ndarray
    stepover: np.ndarray | None
    stepover_ball: np.ndarray | None
    reachable: np.ndarray | None
    unreachable: np.ndarray | None = None
    stepover_surface: np.ndarray | None = None
    stepover_surface_ball: np.ndarray | None = None

    def figures(self, inside: np.ndarray, weights: np.ndarray, R_ball: float) -> dict:
        unreach = self.unreachable if self.unreachable is not None else np.zeros(inside.shape, bool)
        w_all = weights * inside
        total = float(w_all.sum())
        n_in = int(inside.sum())
        facing = self.slope_deg >= 90.0 - 1e-9
        head = {
            "theta_deg": self.theta_deg,
            "unreachable_fraction": float(w_all[unreach].sum() / total) if total > 0 else 0.0,
            "n_unreachable_samples": int(np.count_nonzero(unreach & inside)),
            "n_facing_away_samples": int(np.count_nonzero(facing & inside)),
            "n_samples": n_in,
        }
        inside = inside & ~unreach  # the scores below are over the samples the tool can reach
        w = weights * inside
        if not inside.any():
            return {
                **head,
                "r_eff_min_mm": None,
                "r_eff_max_mm": None,
                "r_eff_mean_mm": None,
                "n_infinite_r_eff": 0,
                "area_fraction_torus_beats_ball": None,
            }
        fin = np.isfinite(self.r_eff) & inside
        out = {
            **head,
            "r_eff_min_mm": float(self.r_eff[fin].min()) if fin.any() else None,
            "r_eff_max_mm": float(self.r_eff[fin].max()) if fin.any() else None,
            "r_eff_mean_mm": float(np.average(self.r_eff[fin], weights=w[fin])) if fin.any() else None,
            "n_infinite_r_eff": int(np.count_nonzero(~np.isfinite(self.r_eff) & inside)),
            "area_fraction_torus_beats_ball": float(w[(self.r_eff > R_ball) & inside].sum() / w.sum()),
        }
        if self.stepover is not None:
            ok = np.isfinite(self.stepover) & np.isfinite(self.stepover_ball) & inside
            so, sb = self.stepover[ok], self.stepover_ball[ok]
            ss = self.stepover_surface[ok] if self.stepover_surface is not None else so
            ssb = self.stepover_surface_ball[ok] if self.stepover_surface_ball is not None else sb
            out.update(
                {
                    "stepover_mean_mm": float(np.average(so, weights=w[ok])) if ok.any() else None,
                    "stepover_ball_mean_mm": float(np.average(sb, weights=w[ok])) if ok.any() else None,
                    "stepover_surface_mean_mm": float(np.average(ss, weights=w[ok])) if ok.any() else None,
                    "stepover_surface_ball_mean_mm": float(np.average(ssb, weights=w[ok])) if ok.any() else None,
                    "stepover_surface_min_mm": float(ss.min()) if ok.any() else None,
                    "n_unreachable": int(np.count_nonzero(~self.reachable & inside)),
                    "n_infinite_stepover": int(np.count_nonzero(np.isinf(self.stepover) & inside)),
                }
            )
            if ok.any():
                out["stepover_ratio_mean"] = out["stepover_mean_mm"] / out["stepover_ball_mean_mm"]
        return out


@dataclass(frozen=True, eq=False)
class ReffMaps(Result):
    """Effective-radius maps over a face on a ``grid x grid`` parameter grid (mm, degrees)."""

    face: Face
    cutter: Cutter
    compare: Cutter | None
    axes: int
    lead_deg: float
    tilt_deg: float
    scallop: float | None
    us: np.ndarray
    vs: np.ndarray
    points: np.ndarray
    inside: np.ndarray
    area_weights: np.ndarray
    directions: tuple
    best_theta_deg: np.ndarray | None
    best_value: np.ndarray | None
    time_s: float
    timings: dict = field(default_factory=dict)

    @property
    def R_ball(self) -> float:
        return self.compare.D / 2 if self.compare is not None else self.cutter.D / 2

    def report(self) -> dict:
        em = self.cutter.end_mill_radii(_PURPOSE)
        R, r = em.R, em.r
        rep = {
            "tool": self.cutter.to_dict(),
            "compare": None if self.compare is None else self.compare.to_dict(),
            "R_mm": R,
            "r_mm": r,
            "R_t_mm": R - r,
            "axes": self.axes,
            "lead_deg": self.lead_deg,
            "tilt_deg": self.tilt_deg,
            "scallop_mm": self.scallop,
            "grid": [int(self.us.size), int(self.vs.size)],
            "directions": [d.figures(self.inside, self.area_weights, self.R_ball) for d in self.directions],
            "time_s": {**self.timings, "total_s": self.time_s},
        }
        if self.best_theta_deg is not None:
            vals = self.best_theta_deg[self.inside]
            rep["best_direction"] = {
                "criterion": "stepover" if self.scallop else "r_eff",
                "histogram_deg": {
                    f"{t.theta_deg:g}": int(np.count_nonzero(np.isclose(vals, t.theta_deg))) for t in self.directions
                },
            }
        return rep


def _as_face(face) -> Face:
    if isinstance(face, Face):
        return face
    if isinstance(face, BSplineSurface):
        return Face(face, name=face.name)
    raise InputError("the face must be a Face or a BSplineSurface")


def parse_directions(text) -> list[float]:
    """Directions in degrees from ``"45"``, ``"-45,0,45,90"`` or ``"all"`` (0..175 by 5 degrees).

    Values beyond 360 degrees in magnitude are refused: a direction in radians by mistake
    would be (1.57 'degrees' is allowed; 6.28 with several values below 2 pi is flagged).
    """
    if isinstance(text, (int, float)):
        vals = [float(text)]
    elif isinstance(text, str) and text.strip().lower() == "all":
        return [float(x) for x in range(0, 180, 5)]
    elif isinstance(text, str):
        try:
            vals = [float(x) for x in text.replace(" ", "").split(",") if x]
        except ValueError:
            raise InputError(f"directions must be numbers in degrees or 'all', got {text!r}") from None
    else:
        vals = [float(x) for x in text]
    if not vals:
        raise InputError("give at least one direction (degrees)")
    for v in vals:
        if not math.isfinite(v) or abs(v) > 360.0:
            raise InputError(f"direction {v:g} is not an angle in degrees (|theta| <= 360)")
    if len(vals) > 1 and all(abs(v) <= 2 * math.pi for v in vals) and any(0 < abs(v) < 1 for v in vals):
        raise InputError(f"directions {vals} look like radians: give degrees (e.g. 45, not 0.785)")
    return vals


def reff_maps(
    face: FaceLike,
    tool: ToolLike,
    *,
    directions: float | str | Iterable[float] = (0.0,),
    grid: int = 256,
    compare: ToolLike | None = "ball",
    scallop: float | None = None,
    axes: int = 3,
    lead: float = 0.0,
    tilt: float = 0.0,
    max_memory_mb: float = 4096.0,
    chunks: int = 1,
    map_chunks: MapChunks = None,
) -> ReffMaps:
    """Effective radius (and step-over) maps of ``tool`` over a face, for machining directions.

    Parameters
    ----------
    face : Face or BSplineSurface
        Outward normal into the tool.
    tool : Cutter or str
        Torus (``bull:D=10,r=2``), flat or ball cutter; mm.
    directions : sequence of float or str
        Machining directions theta (degrees): angle of the feed's projection on the machine XY
        plane with X. ``"all"`` is 0..175 by 5 (alpha and alpha + 180 give the same value).
    grid : int
        Samples per parameter direction, at tile centres (the paper used 256).
    compare : str or Cutter or None
        Reference cutter (default a ball of the same diameter).
    scallop : float, optional
        Scallop height (mm) for the step-over maps.
    axes, lead, tilt : int, float, float
        3: axis z. 5: the axis is leaned by ``lead`` towards the feed and turned by ``tilt``
        about the normal (conventions of :mod:`machsurf_cad.machining.strategies`); S and alpha
        are then measured in the tool frame.
    max_memory_mb : float
        Work-size bound: a grid and set of directions needing more memory is refused with the estimate.
    chunks : int
        Split the directions into this many groups (each direction's map depends on no other: the
        figures are the same to the last digit).
    map_chunks : callable, optional
        ``map``-like callable running the groups (e.g. :func:`machsurf_cad.batchrun.dask_map`).

    Returns
    -------
    ReffMaps
        Per direction: slope, alpha, R_eff (and step-overs) on the grid; the best direction
        when there are several; ``report()`` with min/mean/max R_eff, area fractions, ratios.

    Raises
    ------
    InputError
        Not a ball/flat/bull-nose cutter, directions given in radians, a scallop not below R.

    Examples
    --------
    >>> from machsurf_cad import examples
    >>> m = reff_maps(examples.bezier5_patch(), "ball:D=10", grid=16)
    >>> float(m.directions[0].r_eff.min()), float(m.directions[0].r_eff.max())  # a ball: R everywhere
    (5.0, 5.0)
    """
    t0 = time.perf_counter()
    timings = {}
    face = _as_face(face)
    cutter, comp, lead, tilt, grid, dirs = _reff_inputs(
        tool, compare, axes, lead, tilt, grid, directions, max_memory_mb, scallop
    )
    u0, u1, v0, v1 = face.uv_bounds
    us = u0 + (u1 - u0) * (np.arange(grid) + 0.5) / grid  # tile centres
    vs = v0 + (v1 - v0) * (np.arange(grid) + 0.5) / grid
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = face.contains_uv(U, V) if face.is_trimmed else np.ones(U.shape, bool)
    t = time.perf_counter()
    d = face.surface.derivatives_grid(us, vs, 2)  # the curvature across the feed decides reachability
    timings["evaluate_s"] = time.perf_counter() - t
    n = _outward_normals(face, d, us, vs, U, V, inside)
    area = np.linalg.norm(np.cross(d.su, d.sv), axis=-1)
    forms = _Forms(d, n, True)
    t = time.perf_counter()
    job = functools.partial(_direction_maps, fm=forms, cutter=cutter, comp=comp, scallop=scallop, axes=axes,
                            lead=lead, tilt=tilt, inside=inside)  # fmt: skip
    maps = [m for group in split_map(job, [np.asarray(dirs, float)], chunks, map_chunks) for m in group]
    timings["maps_s"] = time.perf_counter() - t
    best_t, best_v = _best_direction(maps, dirs, scallop)
    return ReffMaps(
        face,
        cutter,
        comp,
        axes,
        float(lead),
        float(tilt),
        scallop,
        us,
        vs,
        d.point,
        inside,
        area,
        tuple(maps),
        best_t,
        best_v,
        time.perf_counter() - t0,
        timings,
    )


def _reff_inputs(tool, compare, axes, lead, tilt, grid, directions, max_memory_mb, scallop):
    """Check :func:`reff_maps`' options: the cutter and reference cutter, lead and tilt, grid and directions."""
    from . import checks

    cutter = checks.tool(tool)
    R = cutter.end_mill_radii(_PURPOSE).R
    comp = None
    if compare is not None:
        comp = parse_cutter(f"ball:D={cutter.D:g}") if compare == "ball" else checks.tool(compare, "compare")
        comp.end_mill_radii(_PURPOSE)
    if axes not in (3, 5):
        raise InputError("axes must be 3 or 5")
    from .checks import lead_tilt

    lead, tilt = lead_tilt(lead, tilt, axes=axes)
    grid = checks.index("grid", grid)
    if not 2 <= grid <= 4096:
        raise InputError("grid must be between 2 and 4096")
    dirs = parse_directions(directions)
    # work-size bound: about 20 float64 arrays per grid point shared, 10 more per direction
    need = grid * grid * 8 * (20 + 10 * len(dirs)) / 2**20
    if need > max_memory_mb:
        raise InputError(
            f"grid {grid} with {len(dirs)} direction(s) needs about {need / 1024:.3g} GiB, over the "
            f"{max_memory_mb / 1024:.3g} GiB budget: reduce --grid or the directions"
        )
    if scallop is not None and not scallop > 0:
        raise InputError("scallop height must be > 0 mm")
    if scallop is not None and scallop >= min(R, comp.D / 2 if comp else R):
        raise InputError(f"scallop height {scallop:g} mm is larger than the tool radius")
    return cutter, comp, lead, tilt, grid, dirs


def _outward_normals(face: Face, d, us, vs, U, V, inside) -> np.ndarray:
    """The face's outward unit normals on the grid; a singular point inside the face is refused."""
    n = unit_normals(d.su, d.sv, face.surface.scale, U, V, check=False)
    bad = ~np.isfinite(n).all(axis=-1) & inside
    if np.any(bad):
        i = np.argwhere(bad)[0]
        raise DegenerateGeometryError(
            f"surface normal undefined at {int(bad.sum())} sample(s), e.g. (u, v) = ({U[tuple(i)]:.4g}, "
            f"{V[tuple(i)]:.4g}): singular point",
            {"uv": np.stack([U[bad], V[bad]], 1)[:20].tolist()},
        )
    _check_singular(face, us, vs, n, inside)
    if face.reversed:
        n = -n
    return n


def _best_direction(maps: list, dirs, scallop):
    """Several directions: per grid point the direction with the largest step-over (or R_eff) and that value."""
    best_t = best_v = None
    if len(maps) > 1:
        crit = np.stack([m.stepover if scallop is not None else m.r_eff for m in maps])
        crit = np.where(np.isnan(crit) | np.stack([m.unreachable for m in maps]), -np.inf, crit)
        idx = np.argmax(crit, axis=0)
        best_t = np.asarray(dirs)[idx]
        best_v = np.take_along_axis(crit, idx[None], 0)[0]
    return best_t, best_v


def _check_singular(face: Face, us, vs, n, inside) -> None:
    """Raise where the normal is undefined on the domain's edges (collapsed edge) or jumps by more
    than 60 degrees between neighbouring samples (a singular point inside)."""
    u0, u1, v0, v1 = face.uv_bounds
    s = face.surface
    edges = [
        (np.full(vs.size, u0), vs),
        (np.full(vs.size, u1), vs),
        (us, np.full(us.size, v0)),
        (us, np.full(us.size, v1)),
    ]
    for eu, ev in edges:
        nn = s.normals(eu, ev, check=False)
        bad = ~np.isfinite(nn).all(axis=-1)
        if face.is_trimmed:
            bad &= face.contains_uv(eu, ev)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise DegenerateGeometryError(
                f"surface normal undefined at {int(bad.sum())} point(s) of the domain's edge, e.g. (u, v) = "
                f"({eu[i]:.4g}, {ev[i]:.4g}): collapsed edge (singular point)",
                {"uv": np.stack([eu[bad], ev[bad]], 1)[:20].tolist()},
            )
    cos_lim = math.cos(math.radians(60.0))
    for axis in (0, 1):
        a = np.take(n, np.arange(n.shape[axis] - 1), axis=axis)
        b = np.take(n, np.arange(1, n.shape[axis]), axis=axis)
        ok = np.take(inside, np.arange(n.shape[axis] - 1), axis=axis) & np.take(
            inside, np.arange(1, n.shape[axis]), axis=axis
        )
        jump = (_dot(a, b) < cos_lim) & ok
        if np.any(jump):
            i, j = np.argwhere(jump)[0]
            raise DegenerateGeometryError(
                f"the surface normal turns by more than 60 deg between neighbouring samples near (u, v) = "
                f"({us[i]:.4g}, {vs[j]:.4g}): singular point or crease; refine the grid or split the face"
            )


def _dot(a, b):
    """Row-wise dot product of (..., 3) arrays (faster than einsum on large grids)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


class _Forms:
    """What every direction needs, computed once per face: normal, first and second forms."""

    def __init__(self, d, n, second: bool):
        self.d, self.n = d, n
        self.E, self.F, self.G = _dot(d.su, d.su), _dot(d.su, d.sv), _dot(d.sv, d.sv)
        self.det = self.E * self.G - self.F * self.F
        if second:
            self.L, self.M, self.N = _dot(d.suu, n), _dot(d.suv, n), _dot(d.svv, n)


def _direction_maps(thetas, *, fm, cutter, comp, scallop, axes, lead, tilt, inside) -> list:
    """Maps of a group of directions (module level: groups travel to workers)."""
    return [_direction_map(float(th), fm, cutter, comp, scallop, axes, lead, tilt, inside) for th in thetas]


def _direction_map(theta, fm: _Forms, cutter, comp, scallop, axes, lead, tilt, inside) -> DirectionMap:
    th = math.radians(theta)
    n = fm.n
    nz = n[..., 2]
    vertical = ~(np.abs(nz) > 1e-12)
    if axes == 5 and np.any(vertical & inside):
        raise DegenerateGeometryError(
            f"the face has vertical spots (normal horizontal) at {int((vertical & inside).sum())} "
            "sample(s): a feed direction by its XY projection is undefined there"
        )
    # 3 axes: a spot whose normal is horizontal or faces away from +Z cannot be reached (counted below)
    # feed: the tangent direction whose projection on XY is along theta
    ct, st = math.cos(th), math.sin(th)
    with np.errstate(divide="ignore", invalid="ignore"):
        fz = -(n[..., 0] * ct + n[..., 1] * st) / np.where(vertical, 1.0, nz)
    fnorm = np.sqrt(1.0 + fz * fz)
    f = np.empty(n.shape)
    f[..., 0] = ct / fnorm
    f[..., 1] = st / fnorm
    f[..., 2] = fz / fnorm
    if axes == 3:
        # u = z: S from n_z, and the projections on XY are direct
        cosS = np.clip(nz, -1.0, 1.0)
        sinS = np.hypot(n[..., 0], n[..., 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            cos_a = np.abs(n[..., 0] * ct + n[..., 1] * st) / sinS
    else:
        lt, tn = math.radians(lead), math.radians(tilt)
        u = math.cos(lt) * n + math.sin(lt) * (math.cos(tn) * f + math.sin(tn) * np.cross(n, f))
        cosS = np.clip(_dot(u, n), -1.0, 1.0)
        n_perp = n - cosS[..., None] * u
        f_perp = f - _dot(f, u)[..., None] * u
        sinS = np.sqrt(_dot(n_perp, n_perp))
        with np.errstate(invalid="ignore", divide="ignore"):
            cos_a = np.abs(_dot(n_perp, f_perp)) / (sinS * np.sqrt(_dot(f_perp, f_perp)))
    cos_a = np.where(sinS > 1e-15, np.clip(cos_a, 0.0, 1.0), 1.0)  # flat spot: alpha immaterial (R_eff inf)
    S = np.degrees(np.arctan2(sinS, cosS))
    alpha = np.degrees(np.arccos(cos_a))
    r_eff = effective_radius(cutter, S, alpha)
    # normal section across the feed: direction t = f x n; rho signed positive where convex
    t_dir = np.cross(f, n)
    a, b = _dot(t_dir, fm.d.su), _dot(t_dir, fm.d.sv)
    with np.errstate(divide="ignore", invalid="ignore"):
        du = (fm.G * a - fm.F * b) / fm.det
        dv = (fm.E * b - fm.F * a) / fm.det
        II = fm.L * du * du + 2 * fm.M * du * dv + fm.N * dv * dv
        I_ = fm.E * du * du + 2 * fm.F * du * dv + fm.G * dv * dv
        kn = II / I_  # positive: bends towards the tool (concave)
        rho = np.where(np.abs(kn) > 1e-14, -1.0 / kn, np.inf)
    # unreachable: facing away from the axis (3 axes), or a concave section tighter than the tool across it
    unreach = (rho < 0) & (-rho <= np.where(np.isfinite(r_eff), r_eff, np.inf))
    if axes == 3:
        unreach |= vertical | (nz < 0)
    unreach &= inside
    so = sob = reach = ss = ssb = None
    if scallop is not None:
        from .scallop import spacing_for_scallop

        with np.errstate(invalid="ignore"):
            so, reach = stepover(scallop, np.where(unreach, np.nan, r_eff), rho)
            rb = (comp or cutter).D / 2
            sob, _ = stepover(scallop, np.full(S.shape, rb), rho)
            kappa = np.where(np.isfinite(rho), 1.0 / np.where(np.isfinite(rho), rho, 1.0), 0.0)
            ss = np.where(np.isinf(r_eff), np.inf, spacing_for_scallop(scallop, r_eff, kappa))
            ssb = spacing_for_scallop(scallop, rb, kappa)
        unreach |= ~reach & inside
        for arr in (so, ss):
            arr[unreach] = np.nan
    r_eff = np.where(unreach, np.nan, r_eff)
    return DirectionMap(float(theta), S, alpha, r_eff, rho, so, sob, reach, unreach, ss, ssb)


reff = reff_maps
"""Alias of :func:`reff_maps`, named like the ``machsurf reff`` command."""

__all__ = ["effective_radius", "stepover", "reff_maps", "reff", "ReffMaps", "DirectionMap", "parse_directions"]
