"""machsurf_cad: free-form surface machining geometry on the OpenCASCADE kernel.

Units: millimetres for lengths, degrees for angles, at every public boundary.

This flat namespace is the public API (after cadquery's ``func.py``): every entry point, job
spec and result type is importable from ``machsurf_cad``. The algorithms are numpy/scipy
only; :mod:`machsurf_cad.occ` is the single door to the kernel (cadquery/OCP) and
:mod:`machsurf_cad.viz` the single user of pyvista, both imported only when used.

Examples
--------
>>> import machsurf_cad as ms
>>> face = ms.example("bezier5")
>>> res = ms.machining_surface(face, "bull:D=28,r=4", axes=5, lead=20, tolerance=1e-3)
>>> res.s1_fit.max_error <= 1e-3
True
>>> tp = ms.tool_paths(res, stepover=10.0)
>>> tp.is_multiaxis, tp.cutter.spec()
(True, 'bull:D=28,r=4')
"""

from ._version import __version__
from .approx import SurfaceFit, fit_surface
from .batchrun import BatchJob, BatchJobResult, BatchResult, batch, read_jobs
from .cam import Move, PostOptions, ToolPath, read_apt, read_csv, write_apt, write_csv, write_json
from .cutters import (
    APTCutter,
    BallEndMill,
    BullNoseEndMill,
    ConicalCutter,
    Cutter,
    DrumCutter,
    EndMillRadii,
    FlatEndMill,
    Shank,
    cutter_from_apt,
    parse_cutter,
)
from .effradius import DirectionMap, ReffMaps, effective_radius, reff_maps, stepover
from .errors import DegenerateGeometryError, InputError, MachsurfError, ToleranceError
from .examples import EXAMPLES, example
from .flank_milling import (
    FlankPath,
    FlankResult,
    Interference,
    NoAdmissibleSetting,
    RuledSurface,
    Setting,
    compare_with_rule_optima,
    flank,
    flank_path,
    smooth_minimax_path,
)
from .geometry import BSplineCurve, BSplineSurface, builders, local_properties
from .geometry.face import Face
from .gougecheck import VerifyResult, verify
from .jobs import (
    DemoJob,
    EnvelopeJob,
    FlankJob,
    InfoJob,
    InspectJob,
    JobOutcome,
    JobSpec,
    MachiningSurfaceJob,
    ReffJob,
    SimulateJob,
    VerifyJob,
    run_job,
)
from .machining import (
    AxisField,
    FixedAxis,
    IsoFeed,
    LeadTilt,
    LoopError,
    MachiningSurface,
    PlanesFeed,
    machining_surface,
)
from .machining.toolpath import part_sphere, tool_paths
from .measure import DeviationResult, deviation, project_points
from .results import Progress
from .simulation import SimulationResult, simulate
from .sweep import Envelope, EnvelopeResult, Motion, PassChain, envelope
from .threeaxis import (
    Contact,
    Direction,
    DropCutterResult,
    Pattern,
    cl_surface,
    drop_cutter,
    raster,
    scallop_stepover,
    top_faces,
    waterline,
)

reff = reff_maps
"""Effective cutter radius and step-over maps over a face (the ``reff`` command); same as :func:`reff_maps`."""

__all__ = [
    # entry points
    "machining_surface",
    "drop_cutter",
    "raster",
    "waterline",
    "cl_surface",
    "top_faces",
    "scallop_stepover",
    "Contact",
    "Direction",
    "Pattern",
    "DropCutterResult",
    "tool_paths",
    "part_sphere",
    "reff",
    "reff_maps",
    "effective_radius",
    "stepover",
    "flank",
    "flank_path",
    "smooth_minimax_path",
    "compare_with_rule_optima",
    "envelope",
    "verify",
    "simulate",
    "batch",
    "read_jobs",
    "BatchJob",
    "BatchResult",
    "BatchJobResult",
    "deviation",
    "project_points",
    "fit_surface",
    "run_job",
    "example",
    "parse_cutter",
    "cutter_from_apt",
    "local_properties",
    "builders",
    # tool paths
    "ToolPath",
    "Move",
    "PostOptions",
    "write_apt",
    "write_csv",
    "write_json",
    "read_apt",
    "read_csv",
    # job specs and outcome
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
    "JobOutcome",
    # results
    "MachiningSurface",
    "ReffMaps",
    "DirectionMap",
    "FlankResult",
    "FlankPath",
    "Setting",
    "Interference",
    "VerifyResult",
    "SimulationResult",
    "EnvelopeResult",
    "PassChain",
    "Envelope",
    "DeviationResult",
    "SurfaceFit",
    # inputs and values
    "BSplineCurve",
    "BSplineSurface",
    "Face",
    "RuledSurface",
    "Motion",
    "EXAMPLES",
    "Cutter",
    "BallEndMill",
    "FlatEndMill",
    "BullNoseEndMill",
    "ConicalCutter",
    "DrumCutter",
    "APTCutter",
    "Shank",
    "EndMillRadii",
    "FixedAxis",
    "LeadTilt",
    "AxisField",
    "PlanesFeed",
    "IsoFeed",
    "Progress",
    # errors
    "MachsurfError",
    "InputError",
    "DegenerateGeometryError",
    "ToleranceError",
    "LoopError",
    "NoAdmissibleSetting",
    "__version__",
]


def __dir__():
    return sorted(__all__)
