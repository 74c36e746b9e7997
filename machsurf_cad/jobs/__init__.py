"""One orchestration layer: a job spec in, a :class:`JobOutcome` (report, exit code, files) out.

The CLI, the demo, the FreeCAD workbench and the batch runner all call :func:`run_job`; the
CLI only turns arguments into a spec and prints.

Examples
--------
>>> from machsurf_cad.jobs import FlankJob, run_job
>>> import tempfile
>>> with tempfile.TemporaryDirectory() as d:
...     out = run_job(FlankJob(example="hypar", tool="cyl:D=20", setting="standard-distributed", render=False),
...                   d + "/flank")
>>> out.exit_code, round(out.report["interference"]["max_abs_mm"], 6)
(0, 1.339746)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..errors import InputError
from ..results import Progress
from ..typing import PathLike
from .base import EXIT_INPUT, EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, check_output_folder, quiet
from .specs import (
    SPECS,
    DemoJob,
    EnvelopeJob,
    FlankJob,
    InfoJob,
    InspectJob,
    JobSpec,
    MachiningSurfaceJob,
    Mill3Job,
    ReffJob,
    SimulateJob,
    VerifyJob,
)

_RUNNERS = {  # command -> (module, function); imported on first use (the kernel and pyvista stay lazy)
    "info": ("run_inspect", "run_info"),
    "inspect": ("run_inspect", "run_inspect"),
    "machining-surface": ("run_machining", "run_machining_surface"),
    "mill3": ("run_threeaxis", "run_three_axis"),
    "reff": ("run_reff", "run_reff"),
    "flank": ("run_flank", "run_flank"),
    "envelope": ("run_envelope", "run_envelope"),
    "verify": ("run_verify", "run_verify"),
    "simulate": ("run_simulate", "run_simulate"),
    "demo": ("run_demo", "run_demo"),
}


def _runner(spec: JobSpec) -> Callable:
    import importlib

    if not isinstance(spec, JobSpec) or spec.command not in _RUNNERS:
        raise InputError(f"run_job needs a job spec (InfoJob, MachiningSurfaceJob, ...), got {type(spec).__name__}")
    module, name = _RUNNERS[spec.command]
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


def run_job(spec: JobSpec, out: PathLike, *, say: Say = quiet, progress: Progress | None = None) -> JobOutcome:
    """Run one job and write its outputs into the folder ``out`` (staged: nothing half-written).

    Parameters
    ----------
    spec : JobSpec
        :class:`InfoJob`, :class:`InspectJob`, :class:`MachiningSurfaceJob`, :class:`Mill3Job`,
        :class:`ReffJob`, :class:`FlankJob`, :class:`EnvelopeJob`, :class:`VerifyJob`, :class:`SimulateJob`
        or :class:`DemoJob`.
    out : str or Path
        Output folder; ``report.json`` there holds every figure the job prints.
    say : callable, optional
        Receives each printed line (the CLI passes ``print``).
    progress : Progress, optional
        ``progress(done, total, message)`` for long stages.

    Returns
    -------
    JobOutcome
        ``exit_code`` 2 when a stated tolerance is not met, else 0.

    Raises
    ------
    MachsurfError
        Bad input (:class:`~machsurf_cad.errors.InputError`, exit code 1 at the CLI) or a tolerance
        the fit could not reach (:class:`~machsurf_cad.errors.ToleranceError`, exit code 2).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     out = run_job(ReffJob(example="bezier5", tool="ball:D=10", grid=8, render=False), d + "/reff")
    ...     files = out.files
    >>> out.exit_code, files, out.report["directions"][0]["r_eff_max_mm"]
    (0, ('report.json',), 5.0)
    """
    runner = _runner(spec)
    check_output_folder(out)  # before any work: a folder of the user's is refused, never replaced
    return runner(spec, Path(out), say, progress)


__all__ = [
    "VerifyJob",
    "SimulateJob",
    "run_job",
    "JobOutcome",
    "JobSpec",
    "InfoJob",
    "InspectJob",
    "MachiningSurfaceJob",
    "Mill3Job",
    "ReffJob",
    "FlankJob",
    "EnvelopeJob",
    "DemoJob",
    "SPECS",
    "Staging",
    "Say",
    "EXIT_OK",
    "EXIT_INPUT",
    "EXIT_TOLERANCE",
]
