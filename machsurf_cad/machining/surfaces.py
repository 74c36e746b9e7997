"""Guiding surface S1 and orientation surface S2 (Tournier, Duc, Lartigue, Contri, Table 1).

Lengths in mm, angles in degrees. ``n`` is the face's outward normal (into the tool), ``u``
the unit tool axis from a strategy, ``v = ((u x n)/|u x n|) x u`` the unit vector from the
torus centre-circle point K towards the tool axis (in the plane of u and n).

============  ============================  ===================================================
cutter        3-axis (u = fixed axis)       5-axis
============  ============================  ===================================================
ball, r=D/2   S1 = F + r n                  S1 = F + r n;        S2 = F + r n + L u
flat, R=D/2   S1 = F + R v                  S1 = F;              S2 = F + R v
bull (r,R_t)  S1 = F + r n + R_t v          S1 = F + r n;        S2 = F + r n + R_t v
============  ============================  ===================================================

For 5 axes a point of S1 and the point of S2 at the same (u, v) are the K and C_L of one
tool position; the axis is recovered as ``u = w x ((n x w)/|n x w|)`` with ``w = C_L - K``
(``(S2 - S1)/L`` for the ball). The 3-axis filleted point ``F + r n + R_t v`` is on the axis
in the plane of the torus centre circle, **r above the usual tool-tip cutter location**
``F + r n + R_t v - r u`` (ask for it with ``tip=True``); it is singular where the face normal
is parallel to the axis (the torus then touches along a circle).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from .. import checks
from ..approx import SurfaceFit, fit_surface
from ..checks import positive
from ..cutters import Cutter
from ..errors import DegenerateGeometryError, InputError
from ..geometry.bspline import BSplineSurface
from ..geometry.differential import local_properties_grid
from ..geometry.face import Face
from ..geometry.normals import unit_normals
from ..glossary import LoopPolicy, renamed
from ..results import Result
from ..typing import ArrayLike, FaceLike, PartLike, ProgressLike, StrategyLike, ToolLike, Vector3
from .bodycheck import gouging_placements
from .loops import LoopError, LoopReport, fold_mask, region_from_mask
from .strategies import AxisField, FixedAxis, IsoFeed, LeadTilt, LocalFrame, PlanesFeed, as_feed

_SIN_MIN_AXIS_TO_NORMAL = 1e-6  # |u x n| below this: v undefined (axis along the normal)
_MIN_AXIS_ELEVATION_DEG = 1.0  # the axis must stay this far above the tangent plane


_PURPOSE = "machining surfaces (Table 1)"


_THREE_AXIS_HINT = (
    "; the 3-axis surface point is singular at horizontal spots: the whole-part 3-axis engine (exact "
    "drop-cutter) handles them - `machsurf machining-surface PART --faces N --axes 3` or ms.raster"
)


def _as_face(face) -> Face:
    if isinstance(face, Face):
        return face
    if isinstance(face, BSplineSurface):
        return Face(face, name=face.name or "F")
    raise InputError("the nominal must be a Face or a BSplineSurface")


@dataclass(frozen=True)
class MachiningMaps:
    """The exact maps of Table 1 for one face, cutter, axis count and strategy (grid functions)."""

    face: Face
    cutter: Cutter
    axes: int
    strategy: Any
    axis_length: float
    tip: bool = False

    def __post_init__(self):
        if self.axes not in (3, 5):
            raise InputError("axes must be 3 or 5")
        self.cutter.end_mill_radii(_PURPOSE)

    # ------------------------------------------------------------------ exact local data
    def frame(self, us, vs) -> LocalFrame:
        us = np.asarray(us, dtype=float).ravel()
        vs = np.asarray(vs, dtype=float).ravel()
        U, V = np.meshgrid(us, vs, indexing="ij")
        d = self.face.surface.derivatives_grid(us, vs, 1)
        n = unit_normals(d.su, d.sv, self.face.surface.scale, U, V, surface=self.face.surface)
        if self.face.reversed:
            n = -n
        return LocalFrame(d.point, d.su, d.sv, n, U, V)

    def axis(self, frame: LocalFrame) -> np.ndarray:
        u = self.strategy.axis(frame)
        elev = np.einsum("...i,...i->...", u, frame.normal)
        low = elev < math.sin(math.radians(_MIN_AXIS_ELEVATION_DEG))
        if np.any(low):
            raise DegenerateGeometryError(
                f"the tool axis is within {_MIN_AXIS_ELEVATION_DEG:g} deg of the tangent plane (or below it) at "
                f"{int(low.sum())} point(s), e.g. xyz {np.round(frame.point[low][0], 3).tolist()}: the "
                + ("fixed axis cannot reach this face" if self.axes == 3 else "lead/tilt lays the tool on the surface"),
                {"uv": np.stack([frame.U[low], frame.V[low]], 1)[:20].tolist()},
            )
        return u

    def v_direction(self, u: np.ndarray, frame: LocalFrame) -> np.ndarray:
        c = np.cross(u, frame.normal)
        s = np.linalg.norm(c, axis=-1)
        bad = s < _SIN_MIN_AXIS_TO_NORMAL
        if np.any(bad):
            where = np.round(frame.point[bad][0], 3).tolist()
            raise DegenerateGeometryError(
                f"v = ((u x n)/|u x n|) x u is undefined where the tool axis is parallel to the face normal "
                f"({int(bad.sum())} sample(s), e.g. xyz {where}): the flat/torus end touches along a circle there"
                + ("; use a lead angle" if self.axes == 5 else _THREE_AXIS_HINT),
                {"uv": np.stack([frame.U[bad], frame.V[bad]], 1)[:20].tolist()},
            )
        return np.cross(c / s[..., None], u)

    # ------------------------------------------------------------------ Table 1
    def s1(self, us, vs) -> np.ndarray:
        """Guiding surface map on the grid ``us x vs`` (mm)."""
        em = self.cutter.end_mill_radii(_PURPOSE)
        r, Rt = em.r, em.R_t
        fr = self.frame(us, vs)
        if self.axes == 5:
            return fr.point + r * fr.normal
        u = self.axis(fr)
        if em.is_ball:
            x = fr.point + r * fr.normal
        else:
            x = fr.point + r * fr.normal + Rt * self.v_direction(u, fr)
        return x - r * u if self.tip else x

    def s2(self, us, vs) -> np.ndarray:
        """Orientation surface map on the grid (5-axis only), mm."""
        if self.axes != 5:
            raise InputError("3-axis machining has no orientation surface (the axis is fixed)")
        em = self.cutter.end_mill_radii(_PURPOSE)
        r, Rt = em.r, em.R_t
        fr = self.frame(us, vs)
        u = self.axis(fr)
        if em.is_ball:
            return fr.point + r * fr.normal + self.axis_length * u
        return fr.point + r * fr.normal + Rt * self.v_direction(u, fr)

    def check_axis_normal_singularities(self, n: int = 161) -> None:
        """Raise where the axis is parallel to the normal *between* samples (flat/bull maps need v).

        The direction of ``u x n`` in the plane normal to ``u`` winds once around such a point;
        a non-zero winding number around a grid cell finds it even when no sample hits it.
        """
        em = self.cutter.end_mill_radii(_PURPOSE)
        if em.is_ball or (self.axes == 5 and isinstance(self.strategy, LeadTilt) and self.strategy.lead != 0):
            return
        u0, u1, v0, v1 = self.face.uv_bounds
        us, vs = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
        fr = self.frame(us, vs)
        u = self.strategy.axis(fr)
        w = np.cross(u, fr.normal)
        ref = np.array([1.0, 0.0, 0.0]) if abs(np.mean(u[..., 0])) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = np.cross(u, ref)
        e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
        e2 = np.cross(u, e1)
        ang = np.arctan2(np.einsum("...i,...i->...", w, e2), np.einsum("...i,...i->...", w, e1))

        def wrap(a):
            return (a + np.pi) % (2 * np.pi) - np.pi

        wind = (
            wrap(ang[1:, :-1] - ang[:-1, :-1])
            + wrap(ang[1:, 1:] - ang[1:, :-1])
            + wrap(ang[:-1, 1:] - ang[1:, 1:])
            + wrap(ang[:-1, :-1] - ang[:-1, 1:])
        )
        cells = np.argwhere(np.abs(wind) > np.pi)
        if cells.size:
            i, j = cells[0]
            where = np.round(fr.point[i, j], 3).tolist()
            raise DegenerateGeometryError(
                f"the tool axis is parallel to the face normal near xyz {where} (u ~ {us[i]:.4g}, v ~ {vs[j]:.4g}; "
                f"{len(cells)} cell(s)): v = ((u x n)/|u x n|) x u is undefined there, the flat/torus end touches "
                "along a circle" + (_THREE_AXIS_HINT if self.axes == 3 else ""),
                {"uv": [[float(us[a]), float(vs[b])] for a, b in cells[:20]]},
            )

    def tool_axis(self, us, vs) -> np.ndarray:
        """Exact unit tool axis on the grid."""
        return self.axis(self.frame(us, vs))

    def tool_placements(self, us, vs) -> tuple[np.ndarray, np.ndarray]:
        """Exact tool tips (mm) and unit axes on the grid: the tip is ``r`` below the torus plane's axis
        point (5 axes: S2; 3 axes: S1 unless it is already at the tip) or the ball's centre."""
        em = self.cutter.end_mill_radii(_PURPOSE)
        axis = self.tool_axis(us, vs)
        if self.axes == 5:
            cl = self.s1(us, vs) if em.is_ball else self.s2(us, vs)
        else:
            cl = self.s1(us, vs)
            if self.tip:
                return cl, axis
        return cl - em.r * axis, axis


def recover_axis(k: np.ndarray, cl: np.ndarray, n: np.ndarray, *, ball_length: float | None = None) -> np.ndarray:
    """Tool axis from K (on S1), C_L (on S2) and the face normal: ``u = w x ((n x w)/|n x w|)``, ``w = C_L - K``.

    For the ball end mill (``ball_length`` given) the axis is ``(C_L - K) / |C_L - K|``. Raises
    :class:`DegenerateGeometryError` where the formula is undefined: ``w`` parallel to ``n``,
    i.e. the tool axis tangent to the surface.
    """
    w = np.asarray(cl, float) - np.asarray(k, float)
    if ball_length is not None:
        return w / np.linalg.norm(w, axis=-1, keepdims=True)
    c = np.cross(n, w)
    s = np.linalg.norm(c, axis=-1)
    wn = np.linalg.norm(w, axis=-1)
    bad = ~(s > 1e-9 * np.maximum(wn, 1e-300))
    if np.any(bad):
        raise DegenerateGeometryError(
            f"tool axis undefined at {int(bad.sum())} point(s): K->C_L is parallel to the face normal "
            "(axis tangent to the surface) or zero"
        )
    u = np.cross(w, c / s[..., None])
    return u / np.linalg.norm(u, axis=-1, keepdims=True)


@dataclass(frozen=True, eq=False)
class MachiningSurface(Result):
    """S1 (and S2 for 5 axes) as certified B-spline faces, trimmed like the nominal face.

    Attributes hold the fitted faces, their fits (with measured errors), the loop report and
    the measured tool-axis error. Lengths in mm, angles in degrees.
    """

    nominal: Face
    cutter: Cutter
    axes: int
    strategy: Any
    tolerance: float
    s1: Face
    s1_fit: SurfaceFit
    s2: Face | None
    s2_fit: SurfaceFit | None
    loops: LoopReport
    axis_length: float
    tip: bool
    axis_error_deg: float | None = None
    alpha_max_deg_tolerance: float | None = None
    alpha_max_deg_measured: float | None = None
    timings: dict = field(default_factory=dict)

    @property
    def maps(self) -> MachiningMaps:
        return MachiningMaps(self.nominal, self.cutter, self.axes, self.strategy, self.axis_length, self.tip)

    def faces(self) -> list[Face]:
        return [self.s1] + ([self.s2] if self.s2 is not None else [])

    def report(self) -> dict:
        em = self.cutter.end_mill_radii(_PURPOSE)
        r, Rt = em.r, em.R_t
        out = {
            "trimmed_holes": max(0, len(self.s1.loops) - max(1, len(self.nominal.loops))) if self.loops.found else 0,
            "tool": self.cutter.to_dict(),
            "tool_kind": self.cutter.kind,
            "r_mm": r,
            "R_t_mm": Rt,
            "axes": self.axes,
            "strategy": self.strategy.describe(),
            "auto_lead": getattr(self.strategy, "info", None),
            "tolerance_mm": self.tolerance,
            "tip_location": self.tip,
            "axis_length_mm": self.axis_length if em.is_ball else None,
            "S1": {"name": self.s1.name, **self.s1_fit.report()},
            "S2": None if (self.s2 is None or self.s2_fit is None) else {"name": self.s2.name, **self.s2_fit.report()},
            "loops": self.loops.report(),
            "alpha_max_deg_for_tolerance": self.alpha_max_deg_tolerance,
            "alpha_max_deg_for_measured_errors": self.alpha_max_deg_measured,
            "axis_error_deg_measured": self.axis_error_deg,
            "time_s": self.timings,
        }
        return out


def _resolve_strategy(axes, strategy, lead, tilt, axis, axis_field):
    if axis_field is not None:
        if axes != 5:
            raise InputError("an axis field needs axes=5")
        feed = as_feed(strategy)
        return axis_field if isinstance(axis_field, AxisField) else AxisField(axis_field, feed)
    feed = as_feed(strategy)
    if axes == 3:
        from ..checks import lead_tilt

        lead_tilt(lead, tilt, axes=3)  # refuses a lead or tilt that 3 axes would ignore
        return FixedAxis(axis if axis is not None else (0.0, 0.0, 1.0), feed)
    if axis is not None:
        raise InputError("a fixed axis with axes=5 is 3+2 machining: use axes=3 with axis=...")
    return LeadTilt(lead, tilt, feed)


def lead_field_gouges(face, cutter, field, us, vs, inside, check_faces, tolerance):
    """Where the whole tool gouges ``check_faces`` at the placements of a lead ``field`` on the grid
    ``us x vs`` (``inside``: the grid points on the face), and how deep (mm): the body check
    :func:`~machsurf_cad.machining.autolead.auto_lead` raises its lead with."""
    maps = MachiningMaps(face, cutter, 5, field, cutter.D, False)
    bad, depth, _ = gouging_placements(maps, us, vs, inside, check_faces, tolerance=tolerance)
    return bad, depth


@renamed(lead_margin_deg="lead_margin", lead_min_deg="lead_min", lead_rate_deg_per_mm="lead_rate")
def machining_surface(
    face: FaceLike,
    tool: ToolLike,
    *,
    axes: int = 5,
    strategy: StrategyLike = "planes:x",
    lead: float | Literal["auto"] = 0.0,
    tilt: float = 0.0,
    axis: Vector3 | None = None,
    axis_field: Callable[[np.ndarray, np.ndarray], ArrayLike] | AxisField | None = None,
    tolerance: float = 1e-3,
    lead_margin: float = 1.0,
    lead_min: float = 0.0,
    lead_rate: float = 2.0,
    lead_check_faces: PartLike | None = None,
    degree: Sequence[int] = (3, 3),
    max_poles: int = 40000,
    loops: LoopPolicy = "error",
    axis_length: float | None = None,
    tip: bool = False,
    loop_grid: int = 121,
    progress: ProgressLike = None,
) -> MachiningSurface:
    """Guiding surface S1 and orientation surface S2 of a face, as certified B-spline faces.

    Parameters
    ----------
    face : Face or BSplineSurface
        Nominal face F; its outward normal points into the tool. S1/S2 keep its (u, v)
        parameterisation and trimming.
    tool : Cutter or str
        Ball, flat or bull-nose end mill (e.g. ``"bull:D=28,r=4"``), mm.
    axes : 3 or 5
        3: fixed axis ``axis`` (default z; any direction for 3+2); 5: lead/tilt or axis field.
    strategy : str or feed object
        Feed direction: ``"planes:x"`` (planes parallel to yOz), ``"planes:a,b,c"``, ``"iso:u"``.
    lead, tilt : float
        Lead ``Omega_t`` and tilt ``Omega_n`` in degrees (5 axes); conventions in
        :mod:`machsurf_cad.machining.strategies`. ``lead="auto"``: per point the smallest lead free
        of local gouging plus ``lead_margin``, at least ``lead_min``, changing by at most
        ``lead_rate`` per mm, raised where the tool body still gouges ``lead_check_faces``
        (default: the face itself) at a grid of placements (:mod:`machsurf_cad.machining.autolead`;
        reported as ``auto_lead``); a fixed lead is checked by the tool-body check, never changed.
    axis_field : callable or AxisField, optional
        Tool axis ``func(u, v) -> (..., 3)`` given by the caller (5 axes).
    tolerance : float
        Max-norm fit tolerance in mm, for S1 and S2 each (measured on unseen points).
    loops : {"error", "flag", "trim"}
        What to do when loops are found: raise :class:`LoopError` naming the regions
        (default), return the surfaces with the regions in the report, or trim them away
        (a hole around each region, grown by two loop-grid cells; regions touching the face's
        edge are refused).
    axis_length : float, optional
        ``L`` of the 5-axis ball orientation surface ``S2 = F + r n + L u`` (default D), mm.
    tip : bool
        3 axes only: S1 at the tool tip (``... - r u``) instead of the torus-centre plane.
    progress : callable, optional
        :data:`~machsurf_cad.results.Progress`, passed to :func:`~machsurf_cad.approx.fit_surface`.

    Returns
    -------
    MachiningSurface
        S1 (and S2 in 5 axes) as trimmed faces with their fits (errors measured on unseen
        points), the loop report, alpha_max and the measured axis error; ``report()`` for the figures.

    Raises
    ------
    InputError
        Not a ball, flat or bull-nose end mill, bad axes/strategy/angles.
    LoopError
        Loops found with ``loops="error"`` (the regions are named).
    DegenerateGeometryError
        Zero normals, or a 3-axis filleted point where the normal is parallel to the axis.
    ToleranceError
        The pole budget ran out before the tolerance (the error reached is in the message).

    Examples
    --------
    >>> from machsurf_cad import examples
    >>> ms = machining_surface(examples.bezier5_patch(), "bull:D=28,r=4", lead=20, tolerance=1e-3)
    >>> ms.s1_fit.max_error <= 1e-3 and ms.s2_fit.max_error <= 1e-3, ms.loops.found
    (True, False)
    """
    if loops not in ("error", "flag", "trim"):
        raise InputError("loops must be 'error', 'flag' or 'trim'")
    if tip and axes != 3:
        raise InputError("tip=True is for 3-axis machining (5-axis S1 is the offset F + r n)")
    cutter = checks.tool(tool)
    positive("tolerance (mm)", tolerance)
    em = cutter.end_mill_radii(_PURPOSE)
    face = _as_face(face)
    if isinstance(lead, str):
        lead_options = (lead, lead_margin, lead_min, lead_rate, lead_check_faces)
        strat = _auto_lead_strategy(face, cutter, axes, strategy, tilt, axis, axis_field, *lead_options)
    else:
        strat = _resolve_strategy(axes, strategy, lead, tilt, axis, axis_field)
    L = float(axis_length) if axis_length is not None else cutter.D
    if not L > 0:
        raise InputError("axis length must be > 0 mm")
    maps = MachiningMaps(face, cutter, axes, strat, L, tip)
    maps.check_axis_normal_singularities()
    t0 = time.perf_counter()
    timings = {}
    # loops first: they are cheap to find, and a looped map is also hard to fit
    report = detect_loops(maps, loop_grid)
    timings["loops_s"] = time.perf_counter() - t0
    if report.found and loops == "error":
        raise LoopError(
            "machining surface has loops (the tool would gouge): "
            + "; ".join(r_.describe() for r_ in report.regions)
            + ". Use a smaller corner radius, another strategy, or loops='flag' to export anyway",
            report,
        )
    s1_fit, s2_fit = _fit_s1_s2(maps, axes, tolerance, degree, max_poles, progress, timings)
    trimmed = _trim_loops(face, report) if report.found and loops == "trim" else face
    s1 = trimmed.with_surface(s1_fit.surface, "S1_guiding")
    s2 = trimmed.with_surface(s2_fit.surface, "S2_orientation") if s2_fit is not None else None
    axis_err = a_tol = a_meas = None
    if axes == 5:
        assert s2_fit is not None  # 5 axes always fit S2
        axis_err, a_tol, a_meas = _axis_figures(maps, s1_fit, s2_fit, em, L, tolerance)
    timings["total_s"] = time.perf_counter() - t0
    return MachiningSurface(
        face,
        cutter,
        axes,
        strat,
        float(tolerance),
        s1,
        s1_fit,
        s2,
        s2_fit,
        report,
        L,
        tip,
        axis_err,
        a_tol,
        a_meas,
        timings,
    )


def _auto_lead_strategy(
    face, cutter, axes, strategy, tilt, axis, axis_field, lead, lead_margin, lead_min, lead_rate, lead_check_faces
):
    """The ``lead="auto"`` lead field (:func:`~machsurf_cad.machining.autolead.auto_lead`), its options checked."""
    if lead != "auto":
        raise InputError(f"lead must be degrees or 'auto', got {lead!r}")
    if axes != 5 or axis is not None or axis_field is not None or tilt:
        raise InputError("lead='auto' is a 5-axis lead field without tilt, fixed axis or axis field")
    from .autolead import auto_lead

    feed = as_feed(strategy)
    strat, _ = auto_lead(
        face,
        cutter,
        feed,
        margin_deg=lead_margin,
        min_deg=lead_min,
        rate_deg_per_mm=lead_rate,
        check_faces=[face] if lead_check_faces is None else lead_check_faces,
        gouging=functools.partial(lead_field_gouges, face, cutter),
    )
    return strat


def _fit_s1_s2(maps: MachiningMaps, axes, tolerance, degree, max_poles, progress, timings: dict):
    """Fit S1 (and S2 in 5 axes) within ``tolerance``, each fit's time added to ``timings``."""
    face = maps.face
    bounds = face.uv_bounds
    t1 = time.perf_counter()
    brk = derived_breaks(face.surface, degree, derivative_loss=1)
    fit = functools.partial(
        fit_surface, tolerance=tolerance, degree=degree, max_poles=max_poles, breaks=brk, progress=progress
    )
    s1_fit = fit(maps.s1, bounds, name="S1_guiding")
    timings["fit_S1_s"] = time.perf_counter() - t1
    s2_fit = None
    if axes == 5:
        t2 = time.perf_counter()
        s2_fit = fit(maps.s2, bounds, name="S2_orientation")
        timings["fit_S2_s"] = time.perf_counter() - t2
    return s1_fit, s2_fit


def _trim_loops(face: Face, report: LoopReport) -> Face:
    """The face with a hole around each loop region (``loops="trim"``)."""
    from .loops import hole_loops

    outer = face.loops or (_box_loop(face.uv_bounds),)
    return Face(
        face.surface,
        tuple(outer) + tuple(hole_loops(report)),
        face.name,
        face.index,
        face.reversed,
        face.source_type,
        face.uv_bounds,
        face.area,
    )


def _axis_figures(maps: MachiningMaps, s1_fit, s2_fit, em, L: float, tolerance: float):
    """5 axes: the measured axis error and the axis angle error the tolerance and the measured errors allow (deg)."""
    axis_err = _measured_axis_error(maps, s1_fit.surface, s2_fit.surface, em.is_ball, L)
    lever = L if em.is_ball else em.R_t
    a_tol = math.degrees(math.atan(2 * tolerance / lever))
    a_meas = math.degrees(math.atan((s1_fit.max_error + s2_fit.max_error) / lever))
    return axis_err, a_tol, a_meas


def derived_breaks(surface: BSplineSurface, degree=(3, 3), derivative_loss: int = 1):
    """Interior knots of ``surface`` with the multiplicities a fit of a map built from its
    ``derivative_loss``-th derivatives needs: the map is C^(k - loss) where the surface is C^k,
    so a fit of degree p gets multiplicity ``p - (k - loss)`` there (at least 1)."""
    out = []
    for knots, mults, deg, p in (
        (surface.knots_u, surface.mults_u, surface.degree_u, degree[0]),
        (surface.knots_v, surface.mults_v, surface.degree_v, degree[1]),
    ):
        k_in = knots[1:-1]
        cont = deg - mults[1:-1] - derivative_loss
        m = np.clip(p - cont, 1, p)
        out.append((k_in, m))
    return tuple(out)


def fit_deviation(ms: MachiningSurface, which: str = "S1", samples: int = 150):
    """Deviation map of a fitted machining surface against its exact map (mm).

    Sampled on a grid shifted off the fit's samples, inside the trimmed face; signed along
    the face's outward normal. Returns a :class:`~machsurf_cad.measure.DeviationResult`.
    """
    from ..measure import DeviationResult, deviation_stats

    maps = ms.maps
    fit = ms.s1_fit if which == "S1" else ms.s2_fit
    if fit is None:
        raise InputError(f"{which} was not built")
    u0, u1, v0, v1 = ms.nominal.uv_bounds
    shift = (np.arange(samples) + 0.3819660112501051) / samples
    us, vs = u0 + (u1 - u0) * shift, v0 + (v1 - v0) * shift
    exact = maps.s1(us, vs) if which == "S1" else maps.s2(us, vs)
    got = fit.surface.evaluate_grid(us, vs)
    n = maps.frame(us, vs).normal
    diff = got - exact
    signed = np.linalg.norm(diff, axis=-1) * np.where(np.einsum("...i,...i->...", diff, n) < 0, -1.0, 1.0)
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = ms.s1.contains_uv(U, V)  # S1's trimming: the nominal's, plus any loop holes cut away
    pts, ref = got.reshape(-1, 3), exact.reshape(-1, 3)
    sg = signed.ravel()
    uv = np.stack([U.ravel(), V.ravel()], 1)
    grid_points = grid_index = None
    if ms.s1.is_trimmed:
        keep = inside.ravel()
        grid_points, grid_index = pts, np.nonzero(keep)[0]
        pts, ref, sg, uv = pts[keep], ref[keep], sg[keep], uv[keep]
    stats = deviation_stats(sg, pts, uv)
    return DeviationResult(
        pts,
        sg,
        uv,
        ref,
        np.zeros(len(sg), bool),
        (samples, samples),
        None,
        ms.tolerance,
        stats,
        grid_points,
        grid_index,
    )


def _measured_axis_error(maps: MachiningMaps, s1: BSplineSurface, s2: BSplineSurface, is_ball: bool, L: float) -> float:
    """Largest angle (deg) between the axis recovered from the fitted S1/S2 and the exact axis."""
    u0, u1, v0, v1 = maps.face.uv_bounds
    fr_u = np.linspace(u0, u1, 41)[:-1] + (u1 - u0) / 82
    fr_v = np.linspace(v0, v1, 41)[:-1] + (v1 - v0) / 82
    fr = maps.frame(fr_u, fr_v)
    exact = maps.axis(fr)
    k = s1.evaluate_grid(fr_u, fr_v)
    cl = s2.evaluate_grid(fr_u, fr_v)
    got = recover_axis(k, cl, fr.normal, ball_length=L if is_ball else None)
    cosang = np.clip(np.einsum("...i,...i->...", got, exact), -1, 1)
    return float(np.degrees(np.arccos(cosang)).max())


def detect_loops(maps: MachiningMaps, n: int = 121) -> LoopReport:
    """Local, fold and global loops of S1 (and S2) on an n x n grid inside the trimmed face."""
    face = maps.face
    em = maps.cutter.end_mill_radii(_PURPOSE)
    r = em.r
    u0, u1, v0, v1 = face.uv_bounds
    us, vs = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = face.contains_uv(U, V)
    fr = maps.frame(us, vs)
    regions = []
    # local: r * kappa >= 1 with kappa the concave principal curvature (outward normal)
    if r > 0:
        props = local_properties_grid(face.surface, us, vs)
        sign = -1.0 if face.reversed else 1.0
        kappa = np.maximum(sign * props.k1, sign * props.k2)
        mask = inside & (r * kappa >= 1.0)
        reg = region_from_mask("local", "S1", mask, U, V, fr.point, r * kappa)
        if reg is not None:
            regions.append(reg)
    # fold of each exact map
    n_param = -fr.normal if face.reversed else fr.normal  # orientation of su x sv, the maps' own
    x1 = maps.s1(us, vs)
    m1, val1 = fold_mask(x1, us, vs, n_param)
    reg = region_from_mask("fold", "S1", inside & m1 & ~_near_edge(n), U, V, x1, val1)
    if reg is not None and not any(rg.kind == "local" for rg in regions):
        regions.append(reg)
    if maps.axes == 5:
        x2 = maps.s2(us, vs)
        m2, val2 = fold_mask(x2, us, vs, n_param)
        reg = region_from_mask("fold", "S2", inside & m2 & ~_near_edge(n), U, V, x2, val2)
        if reg is not None:
            regions.append(reg)
    # global: offset points closer to F than r (S1 = F + r n only)
    if r > 0 and (maps.axes == 5 or em.is_ball):
        from ..measure import project_points

        offs = fr.point + r * fr.normal
        proj = project_points(face.surface, offs[inside])
        dist = np.full(U.shape, np.inf)
        d_in = np.linalg.norm(offs[inside] - proj.foot, axis=1)
        foot_in_face = face.contains_uv(proj.uv[:, 0], proj.uv[:, 1]) if face.is_trimmed else np.ones(d_in.size, bool)
        d_in = np.where(foot_in_face, d_in, np.inf)
        dist[inside] = d_in
        slack = max(1e-6 * r, 1e-9)
        mask = dist < r - slack
        reg = region_from_mask("global", "S1", mask, U, V, offs, r - np.where(np.isfinite(dist), dist, r))
        if reg is not None:
            regions.append(reg)
    # global, 3 axes with a flat or bull-nose end mill: the whole tool body at each placement against
    # the face (the offset test above only sees the corner's centre; a tilted or wide bottom cuts
    # elsewhere, e.g. in a channel narrower than the tool)
    if maps.axes == 3 and not em.is_ball:
        us2, vs2 = us[::2], vs[::2]
        bad, depth, tips = gouging_placements(maps, us2, vs2, inside[::2, ::2], [face], tolerance=1e-3)
        reg = region_from_mask("global", "S1", bad, *np.meshgrid(us2, vs2, indexing="ij"), tips, depth)
        if reg is not None:
            regions.append(reg)
    mask = np.zeros((n, n), bool)
    for rg in regions:
        iu = np.clip(np.round((rg.uv[:, 0] - u0) / (u1 - u0) * (n - 1)).astype(int), 0, n - 1)
        iv = np.clip(np.round((rg.uv[:, 1] - v0) / (v1 - v0) * (n - 1)).astype(int), 0, n - 1)
        mask[iu, iv] = True
    return LoopReport(tuple(regions), (n, n), mask, us, vs)


def _box_loop(bounds):
    """The parameter box as a closed loop of four straight 2-D segments."""
    from ..geometry.builders import line_segment

    u0, u1, v0, v1 = bounds
    c = [(u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)]
    return tuple(line_segment(a, b) for a, b in zip(c[:-1], c[1:]))


def _near_edge(n: int) -> np.ndarray:
    """One-sample border where one-sided differences make the fold test unreliable."""
    m = np.zeros((n, n), bool)
    m[0, :] = m[-1, :] = m[:, 0] = m[:, -1] = True
    return m


__all__ = [
    "machining_surface",
    "MachiningSurface",
    "MachiningMaps",
    "recover_axis",
    "detect_loops",
    "LoopError",
    "FixedAxis",
    "LeadTilt",
    "AxisField",
    "PlanesFeed",
    "IsoFeed",
]
