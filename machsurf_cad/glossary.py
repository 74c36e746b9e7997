"""One name per quantity: the vocabulary of every public argument, job spec field and CLI option.

Units follow one rule: lengths are millimetres and angles degrees at every public boundary, so an
argument's name carries no unit (``stepover``, ``lead``, ``clearance``). Quantities in other units
say theirs (``max_memory_mb``, ``timeout_s``), and so do the keys of every ``report()``
(``max_gouge_mm``). A CLI option is its job spec field with ``-`` for ``_``.

Every tolerance names what it bounds: ``tolerance`` (the fit of a certified surface, max norm on
points the fit never saw), ``chordal_tolerance`` (a tool path's chords from the exact positions),
``gouge_tolerance`` (how deep the tool body may go into the part), ``envelope_tolerance``,
``ruled_tolerance``, ``seam_angle_tolerance`` (degrees).

Names changed in 0.3.0 are in :data:`RENAMED`; the old ones still work with a
``DeprecationWarning`` until 0.4 (:func:`renamed`, :func:`renamed_fields`). ``python -m
machsurf_cad.glossary`` prints the table of :data:`TERMS` (docs/glossary.md).
"""

from __future__ import annotations

import functools
import warnings
from typing import Literal, NamedTuple

# ----------------------------------------------------------------------------- options (one Literal each)
Axes = Literal[3, 5]
"""Machine axes of a machining surface: 3 (fixed axis, also 3+2) or 5 (lead and tilt)."""
LoopPolicy = Literal["error", "flag", "trim"]
"""What to do when an offset surface has loops: refuse, report them, or trim them away."""
Continuity = Literal["g0", "g1"]
"""Continuity between adjacent swept-envelope passes."""
SettingKind = Literal["standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax"]
"""How a flank-milling cylinder is placed on a rule (Redonnet et al., Rubio)."""
RasterPattern = Literal["raster", "waterline"]
"""3-axis tool-path pattern (:class:`machsurf_cad.Pattern` is the enum)."""
RasterDirection = Literal["zigzag", "one-way"]
"""Order of raster lines (:class:`machsurf_cad.Direction` is the enum)."""
DropEngine = Literal["auto", "compiled", "numpy"]
"""How the drop-cutter runs: the compiled kernel (numba), the numpy reference, or the kernel where numba is
installed and the faces' degrees are at most 7 (``auto``). Both give the same heights."""


class Term(NamedTuple):
    """One quantity: its unit (empty when it has none) and meaning."""

    unit: str
    meaning: str


_MM, _DEG = "mm", "deg"
TERMS: dict[str, Term] = {
    # inputs: parts, faces, tools
    "part": Term("", "the part: a STEP file path, or its faces"),
    "faces": Term("", "faces to machine or check: Face/BSplineSurface list, or all | top | indices"),
    "face": Term("", "one face: a Face, a BSplineSurface, or its index in the part"),
    "check_faces": Term("", "faces the tool body must not cut into (rest | all | none | indices)"),
    "example": Term("", "name of an embedded example part or motion"),
    "tool": Term("", "the cutter: a Cutter, or its text ball:D=10, bull:D=16,r=3, ..."),
    "shank": Term("", "shank cylinder above the cutting length (D=..,L=..)"),
    "holder": Term("", "holder cylinder above the shank (D=..,L=..)"),
    "toolpath": Term("", "a ToolPath, or a tool-path file (our CSV, APT CLDATA)"),
    "surface": Term("", "the surface worked on (B-spline, ruled, or a MachiningSurface)"),
    "nominal": Term("", "the reference face a candidate is measured against"),
    "candidate": Term("", "what is measured: a STEP face or an STL mesh"),
    "candidate_face": Term("", "face index in a candidate STEP"),
    "reference": Term("", "the exact surface a deviation is measured from"),
    "motion": Term("", "a tool motion: tip and axis along a parameter"),
    "path": Term("", "a file path (output, or a JSON motion)"),
    "points": Term(_MM, "points in space, (n, 3)"),
    "xy": Term(_MM, "query points in the tool frame, (n, 2)"),
    "axis": Term("", "fixed tool axis x, y, z (3 axes and 3+2)"),
    "axis_field": Term("", "an axis field along the surface (FixedAxis, LeadTilt, AxisField)"),
    "face_set": Term("", "a prepared drop-cutter face set, reused across calls"),
    "text": Term("", "a cutter's text"),
    "params": Term("", "an APT CUTTER statement's numbers"),
    "name": Term("", "a name"),
    "view": Term("", "which view of an example: surface | ruled | motion"),
    "jobs": Term("", "job specs, command lines, or a jobs file"),
    "spec": Term("", "a job spec"),
    # machining parameters
    "axes": Term("", "3 or 5"),
    "strategy": Term("", "pass layout: planes:x|y|z|a,b,c or iso:u|v"),
    "lead": Term(_DEG, "lead angle Omega_t (or auto)"),
    "tilt": Term(_DEG, "tilt angle Omega_n"),
    "lead_margin": Term(_DEG, "lead auto: degrees above the local need"),
    "lead_min": Term(_DEG, "lead auto: smallest lead"),
    "lead_rate": Term("deg/mm", "lead auto: largest lead change per mm of path"),
    "lead_check_faces": Term("", "lead auto: faces the tool body is checked against"),
    "max_lead": Term(_DEG, "tilt away: largest lead the axis may take to clear the part"),
    "max_tilt": Term(_DEG, "tilt away: largest tilt either side the axis may take to clear the part"),
    "max_axis_angle": Term(_DEG, "the machine's rotary limit: largest angle of the tool axis from the machine axis"),
    "machine_axis": Term("", "the machine's reference axis (spindle at zero tilt), x, y, z; +Z by default"),
    "tip": Term("", "3 axes: the guiding surface at the tool tip instead of the torus plane"),
    "stepover": Term(_MM, "distance between adjacent passes"),
    "scallop": Term(_MM, "cusp height left between adjacent passes"),
    "overrun": Term(_MM, "iso-scallop passes run on past the face's edges"),
    "stepdown": Term(_MM, "waterline: distance between levels"),
    "angle": Term(_DEG, "raster direction in the plane"),
    "theta": Term(_DEG, "direction in the tangent plane / rotation of the next axis"),
    "slope": Term(_DEG, "surface slope from the tool axis"),
    "alpha": Term(_DEG, "feed direction angle / cone half angle"),
    "direction": Term("", "raster line order (zigzag | one-way), or a direction in degrees"),
    "directions": Term(_DEG, "machining directions theta"),
    "pattern": Term("", "raster | waterline"),
    "zigzag": Term("", "alternate the pass direction"),
    "clearance": Term(
        _MM, "distance the whole tool, holder included, keeps from the part on rapids; approach and retract length"
    ),
    "safe_sphere": Term("", "a sphere around the part that links travel on"),
    "safe_plane": Term(_MM, "height along the fixed axis of a plane above the part that links travel in"),
    "safe_cylinder": Term("", "a cylinder around the part that links travel on (point, axis, radius, half length)"),
    "clearance_surface": Term("", "what links travel on: auto | plane | sphere | cylinder"),
    "clearance_axis": Term("", "axis of a clearance cylinder, x, y, z (default the part's longest side)"),
    "extent": Term(_MM, "plan rectangle of a 3-axis pattern, (xmin, xmax, ymin, ymax)"),
    "z_min": Term(_MM, "waterline: lowest level"),
    "grid": Term("", "samples per parameter direction (a count)"),
    "grid_step": Term(_MM, "spacing of a plan grid of heights"),
    "sample_step": Term(_MM, "spacing of the drop-cutter samples along a line"),
    "seed_spacing": Term(_MM, "spacing of seed samples on faces and edges"),
    "step": Term(_MM, "largest tip step between checked placements"),
    "angle_step": Term(_DEG, "largest axis step between checked placements"),
    "spacing": Term(_MM, "part sample spacing"),
    "resolution": Term(_MM, "nominal sample spacing of a simulation"),
    "depth": Term(_MM, "deepest gouge measured"),
    "stock": Term(_MM, "thickest material measured"),
    "motion_step": Term(_MM, "placement spacing along a motion"),
    "heights": Term(_MM, "material heights whose area fractions are reported"),
    "side": Term("", "+1 or -1: which side of the surface the tool is on"),
    "rule": Term("", "rule position, fraction of the u range [0, 1]"),
    "setting": Term("", "flank setting kind (standard-tangent | ... | optimum | minimax)"),
    "whole": Term("", "flank: settings over the whole surface"),
    "radius": Term(_MM, "tool radius"),
    "radius_range": Term(_MM, "flank: tolerance within which the smallest and largest radius are found"),
    "smooth": Term("deg/mm", "flank: axis turn bound of the smooth minimax path (0: default)"),
    "max_turn_rate": Term("deg/mm", "largest axis turn per mm of path"),
    "study": Term("", "flank: the paper's parameter study"),
    "n_rules": Term("", "number of rules"),
    "max_rules": Term("", "largest number of rules"),
    "min_rules": Term("", "smallest number of rules"),
    "n_v": Term("", "samples along each rule"),
    "overhang": Term(_MM, "tool length beyond the surface's directrices"),
    "passes": Term("", "number of passes"),
    "max_passes": Term("", "largest number of passes"),
    "continuity": Term("", "g0 | g1"),
    "theta_scan": Term("", "scan the admissible theta range"),
    "compare": Term("", "reference cutter or comparison to report"),
    "kw": Term("", "options passed on"),
    "func": Term("", "a function of the surface parameters"),
    "direction_vector": Term("", "a direction x, y, z"),
    "plane_normal": Term("", "normal of the pass planes"),
    "feed": Term("mm/min", "cutting feed"),
    "plunge_feed": Term("mm/min", "approach and retract feed"),
    "spindle": Term("rpm", "spindle speed"),
    "tool_number": Term("", "LOADTL tool number"),
    "partno": Term("", "PARTNO text"),
    "options": Term("", "post-processor options (PostOptions)"),
    "simulate": Term("", "simulate the written path"),
    "simulate_resolution": Term(_MM, "sample spacing of the simulation"),
    "render": Term("", "write pictures"),
    "allow_gouge": Term("", "write a gouging path anyway, gouges reported"),
    "trim_gouges": Term("", "keep only the clear stretches of a gouging path, relinked"),
    "fit_ruled": Term(_MM, "accept a non-ruled face within this distance"),
    "loops": Term("", "error | flag | trim"),
    "cl_surface": Term("", "also fit the certified height field of the tool positions"),
    "stl_deflection": Term(_MM, "STL linear deflection"),
    "degree": Term("", "B-spline degree"),
    "max_poles": Term("", "pole budget of a fit"),
    "axis_length": Term(_MM, "length of the axis vectors drawn on S2"),
    "loop_grid": Term("", "samples per direction of the loop check"),
    # tolerances, each naming its measure
    "tolerance": Term(_MM, "max-norm error of a certified fit, on points the fit never saw"),
    "chordal_tolerance": Term(_MM, "a tool path's chords from the exact positions"),
    "gouge_tolerance": Term(_MM, "deepest the tool body may go into the part"),
    "envelope_tolerance": Term(_MM, "fit tolerance of a swept envelope"),
    "ruled_tolerance": Term(_MM, "accept a non-ruled face within this distance"),
    "seam_angle_tolerance": Term(_DEG, "G1 is claimed only when pass seams meet within this normal angle"),
    "uv_tolerance": Term("", "parameter-space convergence of a projection"),
    "on_gouge": Term("", "what the body check does with a gouging path: refuse | trim | allow"),
    "r_eff": Term(_MM, "effective cutter radius in the feed direction"),
    "rho": Term(_MM, "normal curvature radius of the surface across the feed"),
    "argv": Term("", "a command line without the program name"),
    "base_dir": Term("", "folder relative paths of a job are read from"),
    "label": Term("", "a name shown in reports"),
    "min_fraction": Term("", "smallest fraction of a face visible along the axis"),
    # numerics, memory, scheduling
    "samples": Term("", "samples per direction"),
    "max_samples": Term("", "memory budget in samples"),
    "seed_samples": Term("", "seed samples per direction"),
    "check_grid": Term("", "check samples per span"),
    "max_iter": Term("", "largest number of iterations"),
    "initial_spans": Term("", "spans of the first fit"),
    "bounds": Term("", "parameter box"),
    "breaks": Term("", "forced knots"),
    "f": Term("", "the function fitted (fit_surface); APT f, the corner centre height in mm (APTCutter)"),
    "u": Term("", "surface parameter u"),
    "v": Term("", "surface parameter v"),
    "check": Term("", "verify the result"),
    "triangles": Term("", "a mesh's triangles"),
    "max_memory_mb": Term("MB", "memory budget: bigger work is refused"),
    "batch_size": Term("", "queries per vectorised batch (bounds memory)"),
    "engine": Term("", "the drop-cutter's engine: compiled kernel or numpy reference (DropEngine)"),
    "chunks": Term("", "split the work into this many chunks"),
    "map_chunks": Term("", "a map function for the chunks (Dask)"),
    "out": Term("", "output folder"),
    "scheduler": Term("", "Dask scheduler address"),
    "workers": Term("", "local worker processes"),
    "retries": Term("", "runs again of a failed task"),
    "overwrite": Term("", "replace an earlier run"),
    "timeout_s": Term("s", "time to reach the scheduler"),
    "say": Term("", "a function printing one line"),
    "progress": Term("", "a progress callback (Progress)"),
    "jumps": Term("", "positions with no motion into them: separate stretches checked in one call"),
    # cutter geometry (OpenCAMLib/APT vocabulary)
    "D": Term(_MM, "cutter diameter"),
    "r": Term(_MM, "corner radius"),
    "e": Term(_MM, "APT e: corner centre distance from the axis"),
    "beta": Term(_DEG, "APT beta: side angle"),
    "h": Term(_MM, "APT h: height"),
    "R_p": Term(_MM, "drum profile radius"),
    "concave": Term("", "concave drum profile"),
    "length": Term(_MM, "cutting length"),
    "diameter": Term(_MM, "cylinder diameter"),
}

RENAMED: dict[str, str] = {
    "cutter": "tool",
    "tol": "tolerance (verify, simulate: gouge_tolerance)",
    "chordal": "chordal_tolerance",
    "gouge_tol": "gouge_tolerance",
    "envelope_tol": "envelope_tolerance",
    "seam_angle_tol": "seam_angle_tolerance",
    "max_memory": "max_memory_mb",
    "step_deg": "angle_step",
    "step_mm": "step",
    "spacing_mm": "spacing",
    "clearance_mm": "clearance",
    "stepover_mm": "stepover",
    "scallop_mm": "scallop",
    "angle_deg": "angle",
    "theta_deg": "theta",
    "slope_deg": "slope",
    "alpha_deg": "alpha",
    "chordal_tolerance_mm": "chordal_tolerance",
    "tolerance_mm": "tolerance (cl_surface)",
    "verify_tolerance_mm": "gouge_tolerance",
    "seed_spacing_mm": "seed_spacing",
    "sample_step_mm": "sample_step",
    "stepdown_mm": "stepdown",
    "grid_mm": "grid_step",
    "z_min_mm": "z_min",
    "lead_margin_deg": "lead_margin",
    "lead_min_deg": "lead_min",
    "lead_rate_deg_per_mm": "lead_rate",
    "max_turn_deg_per_mm": "max_turn_rate",
    "face_set_": "face_set",
    "chunk": "batch_size",
    "uv_tol": "uv_tolerance",
    "R": "radius (flank_path, smooth_minimax_path, compare_with_rule_optima)",
    "kind": "setting (flank_path)",
    "ms": "surface",
    "tp": "toolpath",
    "feed_mm_min": "feed",
    "plunge_mm_min": "plunge_feed",
    "spindle_rpm": "spindle",
}
"""Old name -> new name, for the names changed in 0.3.0 (still accepted with a warning until 0.4)."""


def _warn(where: str, old: str, new: str) -> None:
    warnings.warn(f"{where}: {old}= is now {new}= (the old name goes in 0.4)", DeprecationWarning, stacklevel=4)


def _rename_kwargs(where: str, mapping: dict[str, str], kwargs: dict) -> dict:
    from .errors import InputError

    for old, new in mapping.items():
        if old in kwargs:
            if new in kwargs:
                raise InputError(f"{where}: give {new}= only ({old}= is its old name)")
            _warn(where, old, new)
            kwargs[new] = kwargs.pop(old)
    return kwargs


def renamed(**old_to_new: str):
    """Decorator: keyword arguments under their old names still work, with a DeprecationWarning.

    The signature (``inspect.signature``) shows the new names only.

    Examples
    --------
    >>> @renamed(tol="tolerance")
    ... def fit(*, tolerance=1.0):
    ...     return tolerance
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     fit(tol=0.5), w[0].category.__name__
    (0.5, 'DeprecationWarning')
    """

    def deco(func):
        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            return func(*args, **_rename_kwargs(func.__name__ + "()", old_to_new, kwargs))

        wrapper.__renamed__ = dict(old_to_new)  # type: ignore[attr-defined]
        return wrapper

    return deco


def renamed_fields(**old_to_new: str):
    """Class decorator (outside ``@dataclass``): old field names still work in the constructor."""

    def deco(cls):
        init = cls.__init__

        @functools.wraps(init)
        def __init__(self, *args, **kwargs):
            init(self, *args, **_rename_kwargs(cls.__name__, old_to_new, kwargs))

        cls.__init__ = __init__
        cls.__renamed__ = {**getattr(cls, "__renamed__", {}), **old_to_new}
        return cls

    return deco


def table() -> str:
    """The glossary as a Markdown table (docs/glossary.md)."""
    rows = ["| name | unit | meaning |", "|---|---|---|"]
    rows += [
        f"| `{k}` | {t.unit or '-'} | {t.meaning.replace('|', '&#124;')} |"
        for k, t in sorted(TERMS.items(), key=lambda kv: kv[0].lower())
    ]
    old = ["", "Renamed in 0.3.0 (the old names work with a warning until 0.4):", ""]
    old += ["| old | new |", "|---|---|"] + [f"| `{a}` | `{b}` |" for a, b in sorted(RENAMED.items())]
    return "\n".join(rows + old) + "\n"


if __name__ == "__main__":  # pragma: no cover
    print(table(), end="")
