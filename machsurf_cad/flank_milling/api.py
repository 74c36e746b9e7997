"""``flank()``: everything ``machsurf flank`` computes, as one result (mm, degrees, seconds)."""

from __future__ import annotations

import math  # noqa: F401  (used by the doctest)
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..cam.toolpath import ToolPath
from ..errors import InputError, ToleranceError
from ..results import Progress, Result
from ..typing import FaceLike, MapChunks, ToolLike
from .path import FlankPath
from .ruled import RuledSurface
from .settings import SETTINGS, Interference, NoAdmissibleSetting, Setting, interference, tool_setting

if TYPE_CHECKING:
    from ..geometry.face import Face

SettingKind = Literal["standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax"]
"""The tool settings: the paper's standard (tangent to C0, or Rubio's equal error at both directrices),
the bisector variant of the distributed one, optimum (three tangencies) and minimax (beyond the paper)."""


def setting_profiles(surface: RuledSurface, u_p: float, R: float, *, side: int = 1) -> dict:
    """The error along the rule (:class:`Interference`, the paper's figures 6 and 7) of every setting on
    one rule, or the reason (str) where a setting does not exist."""
    out: dict = {}
    for kind in SETTINGS:
        try:
            out[kind] = interference(surface, tool_setting(surface, u_p, R, kind, side=side))
        except NoAdmissibleSetting as exc:
            out[kind] = str(exc)
    return out


def compare_settings(surface: RuledSurface, u_p: float, R: float, *, side: int = 1, profiles=None) -> dict:
    """Max gouge / undercut (mm) of every setting on one rule; ``admissible: False`` where one does not exist."""
    out: dict[str, dict] = {}
    for kind, e in (profiles or setting_profiles(surface, u_p, R, side=side)).items():
        if isinstance(e, str):
            out[kind] = {"admissible": False, "reason": e}
        else:
            out[kind] = {"max_gouge_mm": e.max_gouge, "max_undercut_mm": e.max_undercut, "max_abs_mm": e.max_abs}
    return out


@dataclass(frozen=True, eq=False)
class FlankResult(Result):
    """Setting on one rule, its interference and every setting compared there; optionally the whole
    surface (settings, :class:`ToolPath`, certified envelope, nominal-vs-envelope deviation), the
    paper's parameter study and the radius range."""

    surface: RuledSurface
    cutter: Any
    rule: float
    u_p: float
    setting: Setting
    interference: Interference
    comparison: dict
    path: FlankPath | None = None
    toolpath: ToolPath | None = None
    envelope: Any = None
    envelope_deviation: Any = None
    study: dict | None = None
    radius_range: dict | None = None
    time_s: dict | None = None
    profiles: dict | None = None
    segment_envelopes: tuple = ()
    """Per continuous segment of the path: ``(segment, fit, deviation)``, or ``(segment, None, deviation,
    reason)`` where it has no envelope (fewer than 4 rules, or a folding motion whose envelope fit missed
    the tolerance): its deviation is then measured on the tool positions (None below 2 rules)."""
    smooth: dict | None = None
    """The smooth minimax path beside the rule-by-rule optima (``smooth``), see ``compare_with_rule_optima``."""
    cleared: Any = None
    """``whole`` with ``check_faces``: the rules lifted clear of the other faces or left out
    (:class:`~machsurf_cad.flank_milling.clear.ClearedFlank`); ``path`` is then the cleared path."""
    by_diameter: tuple = ()
    """Several tools: each one's share of the face, largest first
    (:class:`~machsurf_cad.flank_milling.tools.FlankToolPass`); ``path``, ``toolpath`` and ``cleared`` are
    those of the largest tool that machines any of it."""

    @property
    def R(self) -> float:
        return self.cutter.D / 2

    @property
    def whole_error_mm(self) -> float | None:
        """Largest gouge or undercut over the whole surface (mm), None without ``whole``."""
        return None if self.path is None else max(self.path.max_gouge, self.path.max_undercut)

    def report(self) -> dict:
        rep: dict = {
            "surface": self.surface.name,
            "tool": self.cutter.to_dict(),
            "R_mm": self.R,
            "rule": self.rule,
            "u_p": self.u_p,
            "setting": self.setting.report(),
            "interference": self.interference.report(),
            "all_settings_on_this_rule": self.comparison,
            "time_s": dict(self.time_s or {}),
        }
        if self.path is not None:
            rep["whole"] = {
                **self.path.report(),
                "toolpath": self.toolpath.report() if self.toolpath else None,
                "envelope_fit": self.envelope.report() if self.envelope is not None else None,
                "deviation_from_envelope": (
                    self.envelope_deviation.report() if self.envelope_deviation is not None else None
                ),
                "segments": [_segment_report(*x) for x in self.segment_envelopes],
                "clear_of_part": self.cleared.report() if self.cleared is not None else None,
            }
            if self.by_diameter:
                from .tools import left_out

                lo, hi = self.surface.u_range
                rep["whole"]["by_diameter"] = [p.report() for p in self.by_diameter]
                rep["whole"]["machined_fraction_all_tools"] = float(sum(p.machined_fraction for p in self.by_diameter))
                rep["whole"]["u_left_out"] = [list(r) for r in left_out(self.by_diameter, lo, hi)]
        if self.study is not None:
            rep["study"] = self.study
        if self.radius_range is not None:
            rep["radius_range"] = self.radius_range
        if self.smooth is not None:
            rep["smooth_minimax_vs_rule_optima"] = self.smooth
        return rep


def _as_ruled(surface, ruled_tolerance: float) -> RuledSurface:
    if isinstance(surface, RuledSurface):
        return surface
    from ..geometry.bspline import BSplineSurface
    from ..geometry.face import Face

    if isinstance(surface, Face):
        return RuledSurface.from_surface(surface.surface, tolerance=ruled_tolerance, name=surface.name)
    if isinstance(surface, BSplineSurface):
        return RuledSurface.from_surface(surface, tolerance=ruled_tolerance)
    raise InputError("flank milling needs a RuledSurface, a B-spline surface or a Face")


def flank(
    surface: RuledSurface | FaceLike,
    tool: ToolLike | float | Sequence[ToolLike | float],
    *,
    rule: float = 0.5,
    setting: SettingKind = "optimum",
    side: int = 1,
    whole: bool = False,
    tolerance: float = 0.01,
    envelope_tolerance: float = 1e-3,
    study: bool = False,
    radius_range: float | None = None,
    smooth: float | None = None,
    ruled_tolerance: float = 1e-6,
    clearance: float = 5.0,
    check_faces: Sequence[Face] | None = None,
    gouge_tolerance: float | None = None,
    progress: Progress | None = None,
    chunks: int = 1,
    map_chunks: MapChunks = None,
) -> FlankResult:
    """Flank milling of a ruled surface by a cylindrical cutter (Redonnet et al.), as ``machsurf flank``.

    Parameters
    ----------
    surface : RuledSurface, BSplineSurface or Face
        The ruled surface; a B-spline face is checked to be ruled within ``ruled_tolerance`` mm.
    tool : str, Cutter, float or a sequence of them
        A cylindrical cutter, ``"cyl:D=20"`` (a flat end mill), or a radius in mm. Several (with ``whole``
        and ``check_faces``): each stretch of the face by the largest that clears the part there
        (:mod:`~machsurf_cad.flank_milling.tools`, ``by_diameter``).
    rule : float
        Rule position as a fraction of the u range, in [0, 1].
    setting : {"standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax"}
        The tool setting.
    side : {1, -1}
        +1: tool on the side of ``S_u x S_v``.
    whole : bool
        Also the settings on the whole surface (step from ``tolerance`` mm), the tool path, the swept
        envelope fitted within ``envelope_tolerance`` mm and the nominal's deviation from it.
    study : bool
        Also the paper's parameter study (figs 9 and 10, hyperbolic paraboloid).
    radius_range : float, optional
        Also the smallest and largest tool radius keeping the whole surface within this many mm.
    smooth : float, optional
        Also (beyond the paper) the minimax path over the whole surface whose axis turns at most this
        many deg per mm between rules (0: 1.5 times the rules' own turn), compared with the
        rule-by-rule optima (:func:`~machsurf_cad.flank_milling.smooth.compare_with_rule_optima`).
    clearance : float
        Approach and retract distance along the axis of the tool path, mm.
    check_faces : list of Face, optional
        ``whole``: the part's other faces. Each rule's cylinder is lifted along its axis clear of them, and
        rules it cannot clear are left out and reported (:func:`~machsurf_cad.flank_milling.clear.clear_flank`).
    gouge_tolerance : float, optional
        How far a check face may lie inside the cylinder, mm (default ``tolerance``).
    progress : Progress, optional
        ``progress(done, total, message)`` along the whole surface.
    chunks, map_chunks : int, callable
        ``whole``: the rules in spans, run by ``map_chunks`` (see :func:`flank_path`).

    Returns
    -------
    FlankResult

    Raises
    ------
    InputError
        Not a cylindrical cutter, rule outside [0, 1], side not +-1, a non-ruled face; no rule of the face
        clears ``check_faces``.
    NoAdmissibleSetting
        The setting does not exist on that rule (e.g. the optimum beyond R = h_p / (2 sin alpha0)).

    Examples
    --------
    >>> from machsurf_cad import examples, flank
    >>> res = flank(examples.hypar_ruled(), "cyl:D=20", rule=0.5, setting="standard-distributed")
    >>> abs(res.interference.max_abs - 10 * (1 - math.cos(math.radians(30)))) < 1e-9  # R (1 - cos alpha0)
    True
    """
    from ..cutters import FlatEndMill

    t0 = time.perf_counter()
    given: list = list(tool) if isinstance(tool, (list, tuple)) else [tool]
    tools = sorted((_flank_cutter(t) for t in given), key=lambda c: -c.D)
    if not tools:
        raise InputError("flank milling needs a cylindrical cutter: cyl:D=..")
    cutter = tools[0]
    if len(tools) > 1 and not (whole and check_faces is not None):
        raise InputError(
            "several diameters are given out per stretch of the face against the part's other faces: "
            "give whole=True and check_faces (machsurf flank --whole on a STEP part)"
        )
    if not 0.0 <= rule <= 1.0:
        raise InputError(f"rule {rule:g} is outside [0, 1] (fraction of the u range)")
    if side not in (1, -1):
        raise InputError("side must be +1 or -1")
    if setting not in SETTINGS:
        raise InputError(f"unknown setting {setting!r}; use one of {', '.join(SETTINGS)}")
    surf = _as_ruled(surface, ruled_tolerance)
    R = cutter.D / 2
    lo, hi = surf.u_range
    u_p = lo + rule * (hi - lo)
    if whole:  # as the whole path does on this rule: Rubio's setting where the one asked for does not exist
        from .path import setting_or_fallback

        st = setting_or_fallback(surf, u_p, R, setting, side)
    else:
        st = tool_setting(surf, u_p, R, setting, side=side)
    times = {"setting_s": time.perf_counter() - t0}
    e = interference(surf, st)
    profiles = setting_profiles(surf, u_p, R, side=side)
    comparison = compare_settings(surf, u_p, R, side=side, profiles=profiles)
    path = tp = env = dev = None
    segment_envelopes: tuple = ()
    cleared = None
    passes: tuple = ()
    if whole:
        t1 = time.perf_counter()
        gtol = tolerance if gouge_tolerance is None else gouge_tolerance
        if len(tools) > 1:
            passes = _by_diameter(surf, tools, (setting, side, tolerance, progress, chunks, map_chunks),
                                  list(check_faces or []), gtol, clearance, _face_of(surface, surf))  # fmt: skip
            main = next(p for p in passes if p.path is not None)
            path, tp, cleared = main.path, main.toolpath, main.cleared
        else:
            path = _whole_path(surf, cutter, setting, side, tolerance, progress, chunks, map_chunks)
            body = FlatEndMill(cutter.D, max(cutter.length, path.length))
            if check_faces is not None:
                cleared = _cleared(path, check_faces, gtol)
                path = cleared.path
                tp = _linked(path, body, [*check_faces, _face_of(surface, surf)], clearance, gtol)
            else:
                tp = path.toolpath(body, clearance=clearance)
        env, dev, segment_envelopes = _segment_envelopes(path, envelope_tolerance)
        times["whole_s"] = time.perf_counter() - t1
    data = None
    if study:
        from .study import parameter_study

        t1 = time.perf_counter()
        data = parameter_study()
        times["study_s"] = time.perf_counter() - t1
    rr = None
    if radius_range is not None:
        from .path import radius_range as _radius_range

        t1 = time.perf_counter()
        rr = _radius_range(surf, radius_range, kind=setting, side=side)
        times["radius_range_s"] = time.perf_counter() - t1
    sm = None
    if smooth is not None:
        from .smooth import compare_with_rule_optima

        t1 = time.perf_counter()
        sm = compare_with_rule_optima(surf, R, side=side, n_rules=21, max_turn_rate=smooth or None)
        times["smooth_s"] = time.perf_counter() - t1
    times["total_s"] = time.perf_counter() - t0
    return FlankResult(
        surf, cutter, float(rule), float(u_p), st, e, comparison, path, tp, env, dev, data, rr, times, profiles,
        segment_envelopes, sm, cleared, passes,
    )  # fmt: skip


def _flank_cutter(tool) -> Any:
    """The cylindrical cutter from a spec, a cutter or a radius (mm); anything else is refused."""
    from ..cutters import FlatEndMill
    from ..toolspec import parse_cutter

    cutter: Any
    if isinstance(tool, (int, float)):
        cutter = FlatEndMill(2.0 * float(tool))
    else:
        cutter = parse_cutter(tool) if isinstance(tool, str) else tool
        if not isinstance(cutter, FlatEndMill):
            raise InputError("flank milling needs a cylindrical cutter: cyl:D=.. (or flat:D=..)")
    return cutter


def _whole_path(surf: RuledSurface, cutter, setting, side, tolerance, progress, chunks, map_chunks):
    """The settings on the whole surface (:func:`flank_path`)."""
    from .path import flank_path

    return flank_path(
        surf, cutter.D / 2, setting, side=side, tolerance=tolerance, progress=progress, chunks=chunks,
        map_chunks=map_chunks,
    )  # fmt: skip


def _by_diameter(surf, tools, how, check_faces, gouge_tolerance, clearance, face) -> tuple:
    """Each stretch of the face by the largest tool that clears the part there (:mod:`.tools`); no tool
    machining any of it is an input error."""
    from ..cutters import FlatEndMill
    from .tools import by_diameter

    setting, side, tolerance, progress, chunks, map_chunks = how

    def link(path, c):
        body = FlatEndMill(c.D, max(c.length, path.length))
        return _linked(path, body, [*check_faces, face], clearance, gouge_tolerance)

    passes = by_diameter(
        surf, tools, lambda c: _whole_path(surf, c, setting, side, tolerance, progress, chunks, map_chunks),
        check_faces, gouge_tolerance=gouge_tolerance, link=link,
    )  # fmt: skip
    if all(p.path is None for p in passes):
        raise InputError(
            f"no rule of the face can be flank-milled clear of the other faces with any of "
            f"{', '.join(c.spec() for c in tools)}"
        )
    return passes


def _cleared(path, check_faces, gouge_tolerance: float):
    """The path lifted clear of ``check_faces`` (:func:`.clear.clear_flank`); no rule kept is an input error."""
    from .clear import clear_flank

    res = clear_flank(path, list(check_faces), gouge_tolerance=gouge_tolerance)
    if res.path is None:
        raise InputError(
            f"no rule of the face can be flank-milled clear of the other faces: the cylinder enters them up to "
            f"{max(r['deepest_intrusion_mm'] for r in res.rules_left_out):.3g} mm on every rule"
        )
    return res


LEAD_MM = 0.5
"""How far off the flank face a segment starts and ends (sideways, away from the face): the links then run
along the tool axis without touching it."""


def _face_of(surface, surf: RuledSurface):
    """The flank face as a :class:`Face` (the one given, or the ruled surface's B-spline)."""
    from ..geometry.face import Face

    if isinstance(surface, Face):
        return surface
    return Face(surf.to_bspline().surface, name=surf.name)


def _linked(path: FlankPath, cutter, part, clearance: float, gouge_tolerance: float) -> ToolPath:
    """The path's continuous segments joined by links the tool-body check finds clear of ``part``
    (:func:`~machsurf_cad.linking.link_runs`): out along the tool axis, over the clearance surface where a
    direct link would cross the part."""
    from ..linking import link_runs
    from .path import leave_direction

    cc = path.contact_points
    away = np.array([leave_direction(s) for s in path.settings])
    runs = []
    for sl in path.segment_slices():  # each segment entered and left sideways, LEAD_MM off the face
        t, a, c, w = path.tip[sl], path.axis[sl], cc[sl], away[sl]
        runs.append((np.concatenate([t[:1] + LEAD_MM * w[:1], t, t[-1:] + LEAD_MM * w[-1:]]),
                     np.concatenate([a[:1], a, a[-1:]]), np.concatenate([np.full((1, 3), np.nan), c,
                                                                         np.full((1, 3), np.nan)])))  # fmt: skip
    return link_runs(runs, part, cutter, clearance=clearance, gouge_tolerance=gouge_tolerance,
                     name=f"flank_{path.kind}", info={"setting": path.kind, "n_rules": len(path.settings)})  # fmt: skip


def _segment_envelopes(path, envelope_tolerance: float):
    """One envelope per continuous segment of the path and its deviation; those of the longest segment."""
    from .path import envelope_deviation, envelope_surface, positions_deviation

    segs = []
    for seg in path.segments():  # one envelope per continuous segment (a jump has no envelope)
        fit = None
        if len(seg.settings) < 4:
            why = f"{len(seg.settings)} rule(s): too short for an envelope"
        else:
            try:
                fit = envelope_surface(seg, tolerance=envelope_tolerance)
            except ToleranceError as exc:  # the motion folds its envelope: measured on the positions
                why = f"swept envelope not fitted ({exc})"
        if fit is not None:
            segs.append((seg, fit, envelope_deviation(seg, fit.surface)))
        else:
            segs.append((seg, None, positions_deviation(seg) if len(seg.settings) >= 2 else None, why))
    # envelope and map of the longest segment with an envelope (else of the longest segment)
    main = max([x for x in segs if x[1] is not None] or segs, key=lambda x: len(x[0].settings))
    return main[1], main[2], tuple(segs)


def _segment_report(seg, fit, dev, why: str = "") -> dict:
    rep = {
        "u_range": [float(seg.u[0]), float(seg.u[-1])],
        "n_rules": len(seg.settings),
        "max_gouge_mm": seg.max_gouge,
        "max_undercut_mm": seg.max_undercut,
    }
    if fit is None:
        rep["no_envelope"] = why
    else:
        rep["envelope_fit_max_error_mm"] = fit.max_error
    rep["deviation_max_abs_mm"] = None if dev is None else dev.max_abs
    rep["deviation_measured_to"] = "envelope" if fit is not None else ("tool positions" if dev is not None else None)
    return rep


def mean_normal(surface: RuledSurface, side: int = 1) -> np.ndarray:
    """The surface's mean unit normal on the tool side (for views along it)."""
    lo, hi = surface.u_range
    n = surface.normal(np.linspace(lo, hi, 9), np.full(9, 0.5)).mean(axis=0) * side
    return n / np.linalg.norm(n)


__all__ = ["flank", "FlankResult", "compare_settings", "setting_profiles", "SettingKind", "mean_normal"]
