"""Job specs: one frozen dataclass per command, built from CLI arguments or from Python (mm, degrees).

A spec holds exactly what a command line holds (file paths, example names, cutter strings,
numbers), so it can be written to JSON, sent to another process and run there by
:func:`machsurf_cad.run_job`. Field names are the CLI's option names with ``-`` as ``_``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import get_args

from ..checks import positive
from ..errors import InputError
from ..glossary import Continuity, LoopPolicy, RasterDirection, RasterPattern, SettingKind, renamed_fields


def _positive(name: str, v, allow_none: bool = False) -> None:
    if v is None and allow_none:
        return
    positive(name, v, "")


def _one_input(part, example, other: str = "a STEP file") -> None:
    if part and example:
        raise InputError(f"give either {other} or --example, not both")


def _choice(name: str, v, choices) -> None:
    if v not in choices:
        raise InputError(f"{name} must be one of {', '.join(map(str, choices))}, got {v!r}")


@dataclass(frozen=True)
class _Post:
    """Tool-path output options shared by the path-writing jobs."""

    clearance: float = 5.0
    feed: float = 1000.0
    plunge_feed: float = 300.0
    spindle: float = 10000.0
    tool_number: int = 1
    simulate: bool = False
    simulate_resolution: float | None = None

    def _check_post(self) -> None:
        for n in ("clearance", "feed", "plunge_feed", "spindle"):
            _positive(n, getattr(self, n))
        _positive("simulate_resolution (mm)", self.simulate_resolution, allow_none=True)
        if int(self.tool_number) < 1:
            raise InputError("tool_number must be >= 1")


@dataclass(frozen=True)
class JobSpec:
    """Base of job specs; ``command`` is the CLI command name."""

    command = ""

    def to_dict(self) -> dict:
        return {"command": self.command, **asdict(self)}

    @classmethod
    def from_mapping(cls, data: dict) -> JobSpec:
        """Build from a mapping with these field names (unknown keys are an error)."""
        names = {f.name for f in fields(cls)} | set(getattr(cls, "__renamed__", {}))
        unknown = set(data) - names - {"command"}
        if unknown:
            raise InputError(f"{cls.command}: unknown option(s) {', '.join(sorted(unknown))}")
        return cls(**{k: v for k, v in data.items() if k in names})


@dataclass(frozen=True)
class InfoJob(JobSpec):
    """Every face of a STEP part: types, degrees, poles, trimming, areas, uv bounds."""

    part: str = ""
    command = "info"

    def __post_init__(self) -> None:
        if not self.part:
            raise InputError("info needs a STEP file")


@renamed_fields(tol="tolerance", max_memory="max_memory_mb")
@dataclass(frozen=True)
class InspectJob(JobSpec):
    """Signed deviation of a candidate (STEP face or STL) from a nominal STEP face."""

    nominal: str = ""
    candidate: str = ""
    face: int = 0
    candidate_face: int | None = None
    tolerance: float | None = None
    samples: int = 200
    render: bool = True
    max_memory_mb: float = 4096.0
    command = "inspect"

    def __post_init__(self) -> None:
        _positive("tolerance (mm)", self.tolerance, allow_none=True)
        _positive("max_memory_mb (MB)", self.max_memory_mb)
        if int(self.samples) < 2:
            raise InputError("samples must be >= 2")


@renamed_fields(tol="tolerance", chordal="chordal_tolerance", gouge_tol="gouge_tolerance", grid="grid_step")
@dataclass(frozen=True)
class MachiningSurfaceJob(_Post, JobSpec):
    """Guiding S1 and orientation S2 surfaces (Table 1 of Tournier et al.) and optionally a tool path."""

    part: str | None = None
    example: str | None = None
    face: int = 0
    tool: str = "ball:D=10"
    axes: int = 5
    strategy: str = "planes:x"
    lead: float | str = 0.0
    tilt: float = 0.0
    axis: tuple | None = None
    lead_margin: float = 1.0
    lead_min: float = 0.0
    lead_rate: float = 2.0
    max_lead: float | None = None
    """Tilt away (5 axes): largest lead, degrees (with ``max_tilt``; :mod:`machsurf_cad.machining.avoid`)."""
    max_tilt: float | None = None
    """Tilt away (5 axes): largest tilt either side, degrees; what no orientation clears is cut out."""
    max_axis_angle: float | None = None
    """The machine's rotary limit: largest angle of the tool axis from +Z, degrees (a head's B or a table's A
    range, C turning freely); positions past it are cut out, links kept within it."""
    tip: bool = False
    tolerance: float = 1e-3
    degree: int = 3
    max_poles: int = 40000
    loops: LoopPolicy = "error"
    stl_deflection: float | None = None
    """STL chordal deflection, mm (default 0.01, larger on faces that would need over 2 million triangles)."""
    toolpath: bool = False
    clearance_surface: str = "auto"
    """What links travel on: auto (plane for a fixed axis, cylinder about a long part, else sphere), plane,
    sphere, cylinder."""
    clearance_axis: tuple | None = None
    """The clearance cylinder's axis (default the part's longest side)."""
    stepover: float | None = None
    """Distance between passes, mm (default 2; not with ``scallop``)."""
    chordal_tolerance: float = 0.005
    scallop: float | None = None
    overrun: float | None = None
    gouge_tolerance: float = 0.01
    allow_gouge: bool = False
    trim_gouges: bool = False
    faces: str | None = None
    check_faces: str = "rest"
    pattern: str = "raster"
    angle: float = 0.0
    direction: str = "zigzag"
    stepdown: float | None = None
    grid_step: float | None = None
    cl_surface: bool = False
    shank: str | None = None
    holder: str | None = None
    command = "machining-surface"

    def __post_init__(self) -> None:
        _one_input(self.part, self.example)
        _choice("axes", self.axes, (3, 5))
        if self.faces is not None and self.axes != 3:
            raise InputError("--faces (exact drop-cutter on several faces) needs --axes 3")
        if self.faces is not None and not str(self.faces).strip():
            raise InputError("--faces names no face: give all, top or indices like 0,3")
        self._check_combinations()
        _choice("pattern", self.pattern, ("raster", "waterline"))
        _choice("direction", self.direction, ("zigzag", "one-way"))
        _positive("stepdown (mm)", self.stepdown, allow_none=True)
        _positive("grid_step (mm)", self.grid_step, allow_none=True)
        _choice("loops", self.loops, ("error", "flag", "trim"))
        _positive("scallop (mm)", self.scallop, allow_none=True)
        if self.overrun is not None and not self.overrun >= 0:
            raise InputError(f"overrun must be >= 0 mm, got {self.overrun!r}")
        for n in ("tolerance", "chordal_tolerance"):
            _positive(n + " (mm)", getattr(self, n))
        _positive("stl_deflection (mm)", self.stl_deflection, allow_none=True)
        _positive("stepover (mm)", self.stepover, allow_none=True)
        if not (isinstance(self.max_poles, int) and self.max_poles >= 16):
            raise InputError(f"max_poles must be an integer >= 16, got {self.max_poles!r}")
        if self.axis is not None and len(self.axis) != 3:
            raise InputError("axis must be x,y,z")
        _choice("clearance_surface", self.clearance_surface, ("auto", "plane", "sphere", "cylinder"))
        if self.clearance_axis is not None and self.clearance_surface not in ("auto", "cylinder"):
            raise InputError("--clearance-axis is the axis of a clearance cylinder: use --clearance-surface cylinder")
        if self.clearance_axis is not None and not (
            len(self.clearance_axis) == 3 and 0 < sum(x * x for x in self.clearance_axis) < float("inf")
        ):
            raise InputError(f"--clearance-axis must be a non-zero x,y,z, got {self.clearance_axis!r}")
        if self.clearance_surface == "plane" and self.axes == 5:
            raise InputError("a clearance plane needs a fixed tool axis (--axes 3): use sphere or cylinder")
        self._check_tilt_away()
        self._check_post()

    @property
    def tilt_away(self) -> bool:
        return self.max_lead is not None or self.max_tilt is not None

    def _check_tilt_away(self) -> None:
        x = self.max_axis_angle
        if x is not None and not (isinstance(x, (int, float)) and 0.0 < x <= 180.0):
            raise InputError(f"--max-axis-angle must be within 0..180 degrees (from +Z), got {x!r}")
        if x is not None and not self.toolpath:
            raise InputError("--max-axis-angle applies to a tool path: add --toolpath")
        for name in ("max_lead", "max_tilt"):
            x = getattr(self, name)
            if x is not None and not (isinstance(x, (int, float)) and 0.0 <= x <= 90.0):
                raise InputError(f"--{name.replace('_', '-')} must be within 0..90 degrees, got {x!r}")
        if not self.tilt_away:
            return
        if self.axes != 5:
            raise InputError("--max-lead and --max-tilt turn a 5-axis axis away from the part: use --axes 5")
        if self.lead == "auto":
            raise InputError("--max-lead/--max-tilt start from a given lead: give --lead in degrees, not auto")
        if self.max_lead is not None and self.max_lead < float(self.lead):
            raise InputError(f"--max-lead ({self.max_lead:g} deg) is below --lead ({float(self.lead):g} deg)")

    def _check_combinations(self) -> None:
        """Refuse options that the chosen route would ignore (each names what it needs)."""
        if self.scallop is not None and self.stepover is not None:
            raise InputError("give --stepover or --scallop, not both (--scallop sets the distance between passes)")
        if (self.scallop is not None or self.stepover is not None) and not self.toolpath:
            raise InputError(
                f"--{'scallop' if self.scallop is not None else 'stepover'} applies to a tool path: add --toolpath"
            )
        if not self.toolpath:
            path_only = [
                name for name, value, default in (
                    ("--chordal-tolerance", self.chordal_tolerance, 0.005),
                    ("--gouge-tolerance", self.gouge_tolerance, 0.01),
                    ("--allow-gouge", self.allow_gouge, False), ("--trim-gouges", self.trim_gouges, False),
                    ("--clearance", self.clearance, 5.0), ("--feed", self.feed, 1000.0),
                    ("--clearance-surface", self.clearance_surface, "auto"),
                    ("--clearance-axis", self.clearance_axis, None),
                    ("--plunge-feed", self.plunge_feed, 300.0), ("--spindle", self.spindle, 10000.0),
                    ("--tool-number", self.tool_number, 1), ("--simulate", self.simulate, False),
                    ("--simulate-resolution", self.simulate_resolution, None),
                    ("--shank", self.shank, None), ("--holder", self.holder, None),
                ) if value != default
            ]  # fmt: skip
            if path_only:
                raise InputError(f"{path_only[0]} applies to a tool path: add --toolpath")
        if self.overrun is not None and self.scallop is None:
            raise InputError("--overrun applies to iso-scallop passes: add --scallop")
        if self.lead != "auto" and (self.lead_margin, self.lead_min, self.lead_rate) != (1.0, 0.0, 2.0):
            raise InputError("--lead-margin, --lead-min and --lead-rate apply to --lead auto")
        if self.faces is None:  # the options of the whole-part 3-axis engine
            given = [
                name for name, value, default in (
                    ("--pattern", self.pattern, "raster"), ("--angle", self.angle, 0.0),
                    ("--direction", self.direction, "zigzag"), ("--stepdown", self.stepdown, None),
                    ("--grid-step", self.grid_step, None), ("--cl-surface", self.cl_surface, False),
                ) if value != default
            ]  # fmt: skip
            if given:
                raise InputError(f"{given[0]} applies to the whole-part 3-axis engine: add --faces (e.g. --faces top)")
            if self.check_faces not in ("rest", "body"):
                raise InputError(
                    "--check-faces of one face is rest (every other face of the file) or body (the faces of the "
                    f"solid it bounds); face lists need --faces, got {self.check_faces!r}"
                )

    @property
    def stepover_or_default(self) -> float:
        """The distance between passes, mm (2 when neither it nor ``scallop`` is given)."""
        return 2.0 if self.stepover is None else float(self.stepover)

    def to_mill3(self) -> Mill3Job:
        """The :class:`Mill3Job` of a ``--faces`` invocation (the whole-part engine's own spec)."""
        same = {f.name for f in fields(Mill3Job)} & {f.name for f in fields(self)}
        kw = {n: getattr(self, n) for n in same if n not in ("faces", "toolpath", "cl_surface")}
        return Mill3Job(
            **kw, faces=str(self.faces), toolpath=bool(self.toolpath), cl_surface=self.cl_surface or not self.toolpath
        )


@dataclass(frozen=True)
class Mill3Job(_Post, JobSpec):
    """3-axis (and 3+2) tool paths on a whole part: the exact drop-cutter on the B-rep, any cutter.

    Machines ``faces`` (top: the faces seen along the axis, all, or indices) while the tool body keeps
    out of ``check_faces`` (rest of the part by default); the path is checked against every face of the
    part before it is written.
    """

    part: str | None = None
    example: str | None = None
    tool: str = "ball:D=10"
    faces: str = "top"
    check_faces: str = "rest"
    axis: tuple | None = None
    pattern: RasterPattern = "raster"
    stepover: float | None = None
    """Distance between raster lines (waterline: between levels unless ``stepdown``), mm (default 2)."""
    scallop: float | None = None
    angle: float = 0.0
    direction: RasterDirection = "zigzag"
    stepdown: float | None = None
    grid_step: float | None = None
    chordal_tolerance: float = 0.005
    toolpath: bool = True
    cl_surface: bool = False
    tolerance: float = 1e-3
    """Fit tolerance of the CL surface (``cl_surface``), max norm on unseen points, mm."""
    degree: int = 3
    max_poles: int = 40000
    shank: str | None = None
    holder: str | None = None
    gouge_tolerance: float = 0.01
    allow_gouge: bool = False
    trim_gouges: bool = False
    command = "mill3"

    def __post_init__(self) -> None:
        _one_input(self.part, self.example)
        if not str(self.faces).strip():
            raise InputError("--faces names no face: give all, top or indices like 0,3")
        _choice("pattern", self.pattern, get_args(RasterPattern))
        _choice("direction", self.direction, get_args(RasterDirection))
        if self.scallop is not None and self.stepover is not None:
            raise InputError("give --stepover or --scallop, not both (--scallop sets the distance between passes)")
        for n in ("stepover", "scallop", "stepdown", "grid_step"):
            _positive(n + " (mm)", getattr(self, n), allow_none=True)
        for n in ("chordal_tolerance", "tolerance", "gouge_tolerance"):
            _positive(n + " (mm)", getattr(self, n))
        if not (isinstance(self.max_poles, int) and self.max_poles >= 16):
            raise InputError(f"max_poles must be an integer >= 16, got {self.max_poles!r}")
        if self.axis is not None and len(self.axis) != 3:
            raise InputError("axis must be x,y,z")
        if not (self.toolpath or self.cl_surface):
            raise InputError("nothing to do: give a tool path (the default) or --cl-surface")
        self._check_post()


@renamed_fields(max_memory="max_memory_mb")
@dataclass(frozen=True)
class ReffJob(JobSpec):
    """Effective cutter radius (relation (30)) and step-over (31) maps over a face."""

    part: str | None = None
    example: str | None = None
    face: int = 0
    tool: str = "bull:D=10,r=2"
    compare: str = "ball"
    direction: str = "0"
    grid: int = 256
    scallop: float | None = None
    axes: int = 3
    lead: float = 0.0
    tilt: float = 0.0
    render: bool = True
    max_memory_mb: float = 4096.0
    chunks: int = 1
    command = "reff"

    def __post_init__(self) -> None:
        _one_input(self.part, self.example)
        _choice("axes", self.axes, (3, 5))
        _positive("scallop (mm)", self.scallop, allow_none=True)
        if int(self.chunks) < 1:
            raise InputError(f"chunks must be >= 1, got {self.chunks}")


@renamed_fields(
    tol="tolerance", envelope_tol="envelope_tolerance", gouge_tol="gouge_tolerance", fit_ruled="ruled_tolerance"
)
@dataclass(frozen=True)
class FlankJob(_Post, JobSpec):
    """Flank milling settings of a cylindrical cutter on a ruled surface (Redonnet et al.)."""

    part: str | None = None
    example: str | None = None
    face: int = 0
    ruled_tolerance: float | None = None
    tool: str | tuple = "cyl:D=20"
    """A cylindrical cutter, or several (``--whole`` on a STEP part: the largest that clears per stretch)."""
    rule: float = 0.5
    setting: SettingKind = "optimum"
    side: int = 1
    whole: bool = False
    tolerance: float = 0.01
    envelope_tolerance: float = 1e-3
    study: bool = False
    radius_range: float | None = None
    smooth: float | None = None
    """Smooth minimax path compared with the rule optima: axis turn bound in deg/mm (0: the default bound)."""
    chunks: int = 1
    render: bool = True
    gouge_tolerance: float | None = None
    allow_gouge: bool = False
    trim_gouges: bool = False
    check_faces: str = "rest"
    """``--whole`` on a STEP part: the faces the cylinder is lifted clear of (rest of the part, none, indices)."""
    command = "flank"

    def __post_init__(self) -> None:
        _one_input(self.part, self.example)
        _choice("setting", self.setting, get_args(SettingKind))
        _choice("side", self.side, (1, -1))
        if not 0.0 <= self.rule <= 1.0:
            raise InputError(f"rule {self.rule:g} is outside [0, 1] (fraction of the u range)")
        _positive("tolerance (mm)", self.tolerance)
        _positive("envelope_tolerance (mm)", self.envelope_tolerance)
        _positive("radius_range (mm)", self.radius_range, allow_none=True)
        if self.smooth is not None and not (isinstance(self.smooth, (int, float)) and self.smooth >= 0):
            raise InputError(f"smooth must be an axis turn bound >= 0 deg/mm (0: the default), got {self.smooth!r}")
        _positive("ruled_tolerance (mm)", self.ruled_tolerance, allow_none=True)
        if isinstance(self.tool, (list, tuple)):
            tools = tuple(str(t) for t in self.tool)
            if not tools:
                raise InputError("--tool names no cutter")
            object.__setattr__(self, "tool", tools[0] if len(tools) == 1 else tools)
        if isinstance(self.tool, tuple) and not (self.whole and self.part):
            raise InputError("several --tool diameters are given out against the part's faces: add --whole and "
                             "give a STEP part")  # fmt: skip
        if int(self.chunks) < 1:
            raise InputError(f"chunks must be >= 1, got {self.chunks}")
        self._check_post()


@renamed_fields(
    tol="tolerance", chordal="chordal_tolerance", gouge_tol="gouge_tolerance", seam_angle_tol="seam_angle_tolerance"
)
@dataclass(frozen=True)
class EnvelopeJob(_Post, JobSpec):
    """Swept envelopes of a rotational tool and G1/G0 adjacent passes (Aranda Bassegoda, eq. (21))."""

    tool: str = "cyl:D=10"
    path: str | None = None
    example: str | None = None
    part: str | None = None
    gouge_tolerance: float = 0.01
    allow_gouge: bool = False
    trim_gouges: bool = False
    passes: int = 2
    continuity: Continuity = "g1"
    theta: str = "0"
    side: int = 1
    tolerance: float = 1e-3
    seam_angle_tolerance: float = 0.05
    theta_scan: bool = True
    render: bool = True
    chordal_tolerance: float = 0.01
    command = "envelope"

    def __post_init__(self) -> None:
        _one_input(self.path, self.example, "--path")
        _choice("continuity", self.continuity, ("g0", "g1"))
        _choice("side", self.side, (1, -1))
        if int(self.passes) < 1:
            raise InputError("passes must be >= 1")
        _positive("tolerance (mm)", self.tolerance)
        _positive("chordal_tolerance (mm)", self.chordal_tolerance)
        _positive("seam_angle_tolerance (deg)", self.seam_angle_tolerance)
        self._check_post()

    def thetas(self) -> list[float]:
        try:
            th = [float(x) for x in str(self.theta).split(",")]
        except ValueError:
            raise InputError(f"theta must be degrees, e.g. 0 or 0,15,-10; got {self.theta!r}") from None
        for t in th:
            if not -180 < t < 180:
                raise InputError(f"theta {t:g} deg is outside (-180, 180)")
        if len(th) not in (1, max(int(self.passes) - 1, 1)):
            raise InputError(
                f"--theta needs one angle, or one per new pass ({int(self.passes) - 1} for {self.passes} passes); "
                f"got {len(th)}"
            )
        return th


@renamed_fields(tol="gouge_tolerance", step_deg="angle_step")
@dataclass(frozen=True)
class VerifyJob(JobSpec):
    """Gouges and collisions of a tool path's tool body against every face of a part."""

    part: str = ""
    toolpath: str = ""
    tool: str | None = None
    shank: str | None = None
    holder: str | None = None
    faces: str = "all"
    gouge_tolerance: float = 0.01
    step: float | None = None
    angle_step: float = 1.0
    spacing: float | None = None
    chunks: int = 1
    render: bool = True
    command = "verify"

    def __post_init__(self) -> None:
        if not self.part or not self.toolpath:
            raise InputError("verify needs a STEP part and --toolpath")
        _positive("gouge_tolerance (mm)", self.gouge_tolerance)
        _positive("step (mm)", self.step, allow_none=True)
        _positive("angle_step (deg)", self.angle_step)
        _positive("spacing (mm)", self.spacing, allow_none=True)
        if int(self.chunks) < 1:
            raise InputError(f"chunks must be >= 1, got {self.chunks}")


@renamed_fields(tol="gouge_tolerance")
@dataclass(frozen=True)
class SimulateJob(JobSpec):
    """What a tool path leaves on the part: the N-buffer cut simulation (scallops and gouges)."""

    part: str = ""
    toolpath: str = ""
    tool: str | None = None
    faces: str = "all"
    resolution: float | None = None
    gouge_tolerance: float = 0.01
    depth: float = 1.0
    stock: float = 1.0
    motion_step: float | None = None
    heights: str = "0.001,0.002,0.005,0.01,0.02,0.05,0.1"
    max_samples: int = 10_000_000
    chunks: int = 1
    render: bool = True
    command = "simulate"

    def __post_init__(self) -> None:
        if not self.part or not self.toolpath:
            raise InputError("simulate needs a STEP part and --toolpath")
        _positive("resolution (mm)", self.resolution, allow_none=True)
        _positive("gouge_tolerance (mm)", self.gouge_tolerance)
        _positive("depth (mm)", self.depth)
        _positive("stock (mm)", self.stock)
        _positive("motion_step (mm)", self.motion_step, allow_none=True)
        if int(self.max_samples) < 1:
            raise InputError("max_samples must be >= 1")
        if int(self.chunks) < 1:
            raise InputError(f"chunks must be >= 1, got {self.chunks}")
        self.height_values()

    def height_values(self) -> tuple:
        try:
            hs = tuple(float(x) for x in str(self.heights).split(",") if x.strip())
        except ValueError:
            raise InputError(f"--heights must be numbers in mm like 0.005,0.01; got {self.heights!r}") from None
        for h in hs:
            _positive("each height (mm)", h)
        return hs


@dataclass(frozen=True)
class DemoJob(JobSpec):
    """The main job on the embedded example part (``make demo``)."""

    command = "demo"


SPECS: dict[str, type[JobSpec]] = {
    c.command: c
    for c in (
        InfoJob,
        InspectJob,
        MachiningSurfaceJob,
        Mill3Job,
        ReffJob,
        FlankJob,
        EnvelopeJob,
        VerifyJob,
        SimulateJob,
        DemoJob,
    )
}
"""Spec type by command name."""

__all__ = [
    "JobSpec",
    "InfoJob",
    "InspectJob",
    "MachiningSurfaceJob",
    "ReffJob",
    "FlankJob",
    "EnvelopeJob",
    "VerifyJob",
    "SimulateJob",
    "DemoJob",
    "SPECS",
    "Mill3Job",
]
