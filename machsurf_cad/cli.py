"""The ``machsurf`` command line (also ``python -m machsurf_cad``): arguments to a job spec, nothing more.

Exit codes: 0 success, 1 bad input (one-line message, no traceback), 2 a tolerance not met.
Every command writes ``report.json`` with each figure it prints; lengths in mm, angles in
degrees. The work is done by :func:`machsurf_cad.run_job` (outputs staged: a failed command
leaves nothing half-written). The arguments are :mod:`machsurf_cad.cliargs`'.
"""

from __future__ import annotations

import sys

from .cliargs import build_parser, modernise_argv
from .cliargs import spec_of_args as _spec
from .errors import MachsurfError
from .jobs.base import EXIT_INPUT


def _say(msg: str = "") -> None:
    try:
        print(msg, flush=True)
    except BrokenPipeError:  # `machsurf info part.step | head`: keep working, stop printing
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _run_batch(args) -> int:
    from .batchrun import batch, read_jobs
    from .progress import Bar

    jobs = read_jobs(args.jobs)
    with Bar("batch jobs", len(jobs)) as bar:
        res = batch(
            jobs,
            args.out,
            scheduler=args.scheduler,
            workers=args.workers,
            retries=args.retries,
            overwrite=args.overwrite,
            timeout_s=args.timeout,
            say=_say,
            progress=bar,
        )
    rep = res.report()
    _say(
        f"{rep['n_ok']} of {rep['n_jobs']} job(s) ok in {rep['wall_time_s']:.1f} s on {rep['n_workers']} worker(s) "
        f"(jobs' own time {rep['job_time_sum_s']:.1f} s); outputs in {args.out}/: batch_report.json, "
        "batch_figures.csv, <name>/"
    )
    return res.exit_code


_BAR_TITLES = {
    "inspect": "measuring deviation",
    "machining-surface": "fitting S1/S2",
    "mill3": "drop-cutter",
    "flank": "settings along the surface",
    "demo": "measuring the STL",
    "verify": "checking the tool body",
    "simulate": "simulating the cut",
}


def run(argv=None) -> int:
    """Parse ``argv`` and run the command (signal handlers are :func:`machsurf_cad._start.main`'s)."""
    parser = build_parser()
    argv = modernise_argv(sys.argv[1:] if argv is None else argv, lambda line: print(line, file=sys.stderr))
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return EXIT_INPUT
    from .progress import Bar

    try:
        if args.command == "batch":
            return _run_batch(args)
        spec = _spec(args)
        if args.command == "machining-surface" and getattr(args, "faces", None) is not None:
            _say("note: `machsurf mill3` is the whole-part 3-axis command (machining-surface --faces still works)")
        with Bar(_BAR_TITLES.get(args.command, args.command)) as bar:
            from .jobs import run_job

            return run_job(spec, args.out, say=_say, progress=bar).exit_code
    except MachsurfError as exc:
        print(f"machsurf: error: {exc}", file=sys.stderr)
        return exc.exit_code
