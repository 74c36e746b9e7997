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

import ast as _ast
import importlib as _importlib
from pathlib import Path as _Path
from typing import TYPE_CHECKING

from ._version import __version__

if TYPE_CHECKING:  # the names below, imported on first use by __getattr__ (``import machsurf_cad`` stays light)
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
    )
    from .effradius import DirectionMap, ReffMaps, effective_radius, reff_maps
    from .effradius import reff_maps as reff
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
        Mill3Job,
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
    from .machining.toolpath import part_cylinder, part_plane, part_sphere, tool_paths
    from .measure import DeviationResult, deviation, project_points
    from .pathcheck import PathCheck, check_toolpath
    from .results import Progress
    from .scallop import scallop_stepover, stepover
    from .simulation import SimulationResult, simulate
    from .sweep import Envelope, EnvelopeResult, Motion, PassChain, envelope
    from .threeaxis import (
        Contact,
        Direction,
        DropCutterResult,
        Mill3Result,
        Pattern,
        cl_surface,
        drop_cutter,
        mill3,
        raster,
        top_faces,
        trim_to_reach,
        waterline,
    )
    from .toolspec import cutter_from_apt, parse_cutter


def _lazy_names() -> dict[str, tuple[str, str]]:
    """``name -> (module, attribute)`` read from the ``TYPE_CHECKING`` imports above (one list of names)."""
    tree = _ast.parse(_Path(__file__).read_text())
    block = next(n for n in tree.body if isinstance(n, _ast.If) and getattr(n.test, "id", "") == "TYPE_CHECKING")
    out = {}
    for node in block.body:
        if isinstance(node, _ast.ImportFrom):
            for a in node.names:
                out[a.asname or a.name] = ("." * node.level + (node.module or ""), a.name)
    return out


_LAZY = _lazy_names()
_SUBMODULES = (
    "occ",
    "viz",
    "cam",
    "geometry",
    "jobs",
    "threeaxis",
    "machining",
    "flank_milling",
    "sweep",
    "simulation",
)


def __getattr__(name: str):
    """Import a public name (or the ``occ``/``viz`` doors and other subpackages) on first use (PEP 562)."""
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(_importlib.import_module(module, __name__), attr)
    elif name in _SUBMODULES:
        value = _importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'machsurf_cad' has no attribute {name!r}")
    globals()[name] = value
    return value


__all__ = [
    # entry points
    "machining_surface",
    "drop_cutter",
    "mill3",
    "Mill3Result",
    "check_toolpath",
    "PathCheck",
    "raster",
    "waterline",
    "cl_surface",
    "top_faces",
    "trim_to_reach",
    "scallop_stepover",
    "Contact",
    "Direction",
    "Pattern",
    "DropCutterResult",
    "tool_paths",
    "part_sphere",
    "part_plane",
    "part_cylinder",
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
    "Mill3Job",
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
