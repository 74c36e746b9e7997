"""The ``machsurf`` command line's arguments: the parser, and a command line to a job spec.

Shared by the command line (:mod:`machsurf_cad.cli`) and the batch runner (a batch job is a command
line); it imports neither, nor anything heavy (``machsurf --help`` stays fast).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import fields

from ._version import __version__
from .errors import InputError
from .jobs.base import EXIT_INPUT
from .jobs.specs import SPECS, JobSpec


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # bad usage is bad input: exit 1 with one line (the usage is one --help away)
        print(f"machsurf: error: {message} ({self.prog} --help lists the options)", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def _axis(text: str | None):
    if not text:
        return None
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise InputError("--axis must be x,y,z") from None
    if len(v) != 3:
        raise InputError("--axis must be x,y,z")
    return v


def _finite(text: str) -> float:
    """A finite number (``nan`` and ``inf`` are refused like any other non-number)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return v


def _lead(text: str):
    """``--lead``: degrees or ``auto``."""
    if text.strip().lower() == "auto":
        return "auto"
    try:
        return _finite(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"lead must be degrees or auto, got {text!r}") from None


def spec_of_args(args):
    """The job spec of the parsed arguments (options and spec fields share their names)."""
    cls = SPECS[args.command]
    kw = {f.name: getattr(args, f.name) for f in fields(cls) if hasattr(args, f.name)}
    for name in ("axis", "clearance_axis"):
        if name in kw:
            kw[name] = _axis(kw[name])
    return cls(**kw)


# ----------------------------------------------------------------------------- arguments
def _face_input(p, example_help: str, part_help: str = "STEP file (or use --example)") -> None:
    p.add_argument("part", nargs="?", help=part_help)
    p.add_argument("--example", help=example_help)
    p.add_argument("--face", type=int, default=0, help="face index (default 0)")


def _gouge(p, default: str) -> None:
    g = p.add_argument_group("tool-body check against every face of the part (before writing the path)")
    g.add_argument(
        "--gouge-tolerance",
        type=_finite,
        default=None if default == "--tolerance" else float(default),
        help=f"deepest the tool may go into the part, mm (default {default}); deeper: the path is not written, exit 2",
    )
    g.add_argument("--allow-gouge", action="store_true", help="write a gouging path anyway, gouges listed in report")
    g.add_argument(
        "--trim-gouges",
        action="store_true",
        help="keep only the clear stretches of a gouging path, relinked, rechecked",
    )


def _post(p) -> None:
    g = p.add_argument_group("tool-path output (APT CLDATA, CSV, JSON)")
    g.add_argument(
        "--clearance", type=_finite, default=5.0, help="approach/retract along the tool axis, mm (default 5)"
    )
    g.add_argument("--feed", type=_finite, default=1000.0, help="cutting feed, mm/min (default 1000)")
    g.add_argument("--plunge-feed", type=_finite, default=300.0, help="approach/retract feed, mm/min (default 300)")
    g.add_argument("--spindle", type=_finite, default=10000.0, help="spindle speed, rpm (default 10000)")
    g.add_argument("--tool-number", type=int, default=1, help="LOADTL tool number (default 1)")
    g.add_argument(
        "--simulate", action="store_true", help="simulate the written path on the part: scallops, gouges (exit 2)"
    )
    g.add_argument("--simulate-resolution", type=_finite, default=None, help="sample spacing of --simulate, mm")


DEPRECATED_OPTIONS: dict[str, dict[str, str]] = {
    "inspect": {"--tol": "--tolerance", "--max-memory": "--max-memory-mb"},
    "machining-surface": {"--tol": "--tolerance", "--chordal": "--chordal-tolerance",
                          "--gouge-tol": "--gouge-tolerance", "--grid": "--grid-step"},
    "mill3": {"--tol": "--tolerance", "--chordal": "--chordal-tolerance", "--gouge-tol": "--gouge-tolerance",
              "--grid": "--grid-step"},
    "reff": {"--max-memory": "--max-memory-mb"},
    "flank": {"--tol": "--tolerance", "--envelope-tol": "--envelope-tolerance", "--gouge-tol": "--gouge-tolerance",
              "--fit-ruled": "--ruled-tolerance"},
    "envelope": {"--tol": "--tolerance", "--chordal": "--chordal-tolerance", "--gouge-tol": "--gouge-tolerance",
                 "--seam-angle-tol": "--seam-angle-tolerance"},
    "verify": {"--tol": "--gouge-tolerance", "--step-deg": "--angle-step"},
    "simulate": {"--tol": "--gouge-tolerance"},
}  # fmt: skip
"""Options renamed in 0.3.0 (the glossary), by command: still accepted until 0.4 with a one-line note."""


def modernise_argv(argv, note=None) -> list[str]:
    """``argv`` with the old option names of its command replaced by the new ones; ``note(line)`` is told
    of each."""
    argv = [str(a) for a in argv]
    command = next((a for a in argv if not a.startswith("-")), None)
    old = DEPRECATED_OPTIONS.get(command or "", {})
    out = []
    for a in argv:
        name, eq, value = a.partition("=")
        if name in old:
            if note is not None:
                note(f"note: {name} is now {old[name]} (the old name goes in 0.4)")
            a = old[name] + eq + value
        out.append(a)
    return out


class _StrictParser(_Parser):
    def error(self, message):  # a batch job's command line: the message only, the batch goes on
        raise InputError(message)


def spec_from_argv(argv) -> JobSpec:
    """The job spec of one command line without ``-o`` (what :func:`machsurf_cad.batch` runs).

    Raises :class:`~machsurf_cad.errors.InputError` with the parser's one-line message on bad usage.
    """
    argv = [str(a) for a in argv]
    if any(a in ("-o", "--out") or a.startswith("--out=") for a in argv):
        raise InputError("a batch job's command line takes no -o: the batch writes OUT/<name>/")
    if argv[:1] in (["batch"], ["demo"]):
        raise InputError(f"'{argv[0]}' cannot run as a batch job")
    args = build_parser(_StrictParser).parse_args(modernise_argv(argv))
    if not getattr(args, "command", None):
        raise InputError("empty command line")
    return spec_of_args(args)


def build_parser(parser_class=None) -> argparse.ArgumentParser:
    parser_class = parser_class or _Parser
    p = parser_class(prog="machsurf", description="Free-form surface machining geometry (mm, degrees).")
    p.add_argument("--version", action="version", version=f"machsurf_cad {__version__}")
    sub = p.add_subparsers(dest="command", parser_class=parser_class)
    _demo_parser(sub)
    _info_parser(sub)
    _inspect_parser(sub)
    _machining_surface_parser(sub)
    _mill3_parser(sub)
    _reff_parser(sub)
    _flank_parser(sub)
    _verify_parser(sub)
    _simulate_parser(sub)
    _envelope_parser(sub)
    _batch_parser(sub)
    return p


def _demo_parser(sub) -> None:
    """``machsurf demo``: the main job on the embedded example part."""
    d = sub.add_parser("demo", help="main job on the embedded example part: STEP, STL, deviation map, report")
    d.add_argument("-o", "--out", default="out/demo", help="output folder (default: out/demo)")


def _info_parser(sub) -> None:
    """``machsurf info``: the faces of a STEP part."""
    i = sub.add_parser("info", help="faces of a STEP part: types, degrees, bounds, areas")
    i.add_argument("part", help="STEP file")
    i.add_argument("-o", "--out", default="out/info", help="folder for report.json (default: out/info)")


def _inspect_parser(sub) -> None:
    """``machsurf inspect``: a candidate's deviation from a nominal face."""
    n = sub.add_parser("inspect", help="deviation of a candidate (STEP face or STL) from a nominal STEP face")
    n.add_argument("nominal", help="nominal STEP file")
    n.add_argument("candidate", help="candidate STEP (.step/.stp) or mesh (.stl)")
    n.add_argument("--face", type=int, default=0, help="face index in the nominal file (default 0)")
    n.add_argument("--candidate-face", type=int, default=None, help="face index in a candidate STEP (default: --face)")
    n.add_argument(
        "--tolerance", type=_finite, default=None, help="tolerance, max |deviation| in mm (exit 2 if not met)"
    )
    n.add_argument("--samples", type=int, default=200, help="grid samples per direction on a STEP candidate")
    n.add_argument("--no-render", dest="render", action="store_false", help="skip the PNG/VTP (numbers only)")
    n.add_argument("--max-memory-mb", type=_finite, default=4096.0, help="memory budget, MB: bigger work is refused")
    n.add_argument("-o", "--out", default="out/inspect", help="output folder (default: out/inspect)")


def _machining_surface_parser(sub) -> None:
    """``machsurf machining-surface``: S1 and S2 of a face, and their tool path."""
    m = sub.add_parser("machining-surface", help="guiding S1 and orientation S2 surfaces of a face (Table 1)")
    _face_input(m, "example surface instead of a STEP: bezier5, blade, hypar, liu, eq18")
    m.add_argument("--tool", required=True, help="ball:D=..|flat:D=..|bull:D=..,r=.. (mm)")
    m.add_argument("--axes", type=int, default=5, help="3 or 5 (default 5)")
    m.add_argument("--strategy", default="planes:x", help="planes:x|y|z|a,b,c or iso:u|v (default planes:x)")
    m.add_argument("--lead", type=_lead, default=0.0, help="lead angle Omega_t, degrees, or auto (5 axes)")
    m.add_argument("--lead-margin", type=_finite, default=1.0, help="--lead auto: degrees above the local need")
    m.add_argument("--lead-min", type=_finite, default=0.0, help="--lead auto: smallest lead, degrees")
    m.add_argument("--lead-rate", type=_finite, default=2.0, help="--lead auto: largest lead change, deg per mm")
    m.add_argument("--tilt", type=_finite, default=0.0, help="tilt angle Omega_n, degrees (5 axes)")
    m.add_argument("--max-lead", type=_finite, default=None,
                   help="5 axes, tilt away: largest lead the axis may take to clear the part, degrees")  # fmt: skip
    m.add_argument("--max-tilt", type=_finite, default=None,
                   help="5 axes, tilt away: largest tilt either side the axis may take to clear the part, degrees; "
                   "what no orientation clears is cut out of the path")  # fmt: skip
    m.add_argument("--max-axis-angle", type=_finite, default=None,
                   help="the machine's rotary limit: largest angle of the tool axis from +Z, degrees (a head's B "
                   "or a table's A range); positions past it are cut out, links kept within it")  # fmt: skip
    m.add_argument("--axis", default=None, help="fixed axis x,y,z for 3 axes / 3+2 (default 0,0,1)")
    m.add_argument("--clearance-surface", choices=["auto", "plane", "sphere", "cylinder"], default="auto",
                   help="--toolpath: what links between passes travel on (default auto: a plane above the part for "
                   "a fixed axis, else a cylinder about a long part, else a sphere)")  # fmt: skip
    m.add_argument("--clearance-axis", default=None,
                   help="--clearance-surface cylinder: its axis x,y,z (default the part's longest side)")  # fmt: skip
    m.add_argument("--tip", action="store_true", help="3 axes: S1 at the tool tip instead of the torus plane")
    m.add_argument("--tolerance", type=_finite, default=1e-3, help="fit tolerance, max-norm mm (default 0.001)")
    m.add_argument("--degree", type=int, default=3, help="fit degree in u and v (default 3)")
    m.add_argument("--max-poles", type=int, default=40000, help="pole budget per surface (default 40000)")
    m.add_argument(
        "--loops",
        choices=["error", "flag", "trim"],
        default="error",
        help="on loops: error (default), flag (export and report) or trim (cut interior regions away)",
    )
    m.add_argument(
        "--stl-deflection",
        type=_finite,
        default=None,
        help="STL linear deflection, mm (default 0.01; larger where a face would need over 2 million triangles)",
    )
    m.add_argument("--toolpath", action="store_true", help="also write the tool path (CSV, APT CLDATA, JSON)")
    m.add_argument("--stepover", type=_finite, default=None, help="distance between passes, mm (default 2)")
    m.add_argument(
        "--scallop",
        type=_finite,
        default=None,
        metavar="H",
        help="instead of --stepover: iso-scallop passes leaving H mm between neighbours (spacing on the surface)",
    )
    m.add_argument(
        "--overrun",
        type=_finite,
        default=None,
        help="with --scallop: passes run on past the face's edges, mm (default R)",
    )
    m.add_argument(
        "--chordal-tolerance",
        type=_finite,
        default=0.005,
        help="chordal tolerance of the positions, mm (default 0.005)",
    )
    _whole_part_group(m)
    _gouge(m, "0.01")
    _post(m)
    m.add_argument("-o", "--out", default="out/machining_surface", help="output folder")


def _whole_part_group(m) -> None:
    """``machining-surface --axes 3`` on whole parts: the exact drop-cutter options."""
    t = m.add_argument_group("3 axes on whole parts: exact drop-cutter on several faces (with --axes 3)")
    t.add_argument(
        "--faces", default=None, help="faces to machine: all | top (seen along the axis) | 0,3,5 (instead of --face)"
    )
    t.add_argument(
        "--check-faces",
        default="rest",
        help="faces the tool must not cut into: rest (default: every other face of the file) | body (with --face: "
        "only the solid it bounds, the file's other solids being other parts) | all | none | 1,2 (with --faces)",
    )
    t.add_argument("--pattern", choices=["raster", "waterline"], default="raster", help="tool-path pattern")
    t.add_argument("--angle", type=_finite, default=0.0, help="raster direction in the plane, degrees (default 0)")
    t.add_argument("--direction", choices=["zigzag", "one-way"], default="zigzag", help="raster line order")
    t.add_argument("--stepdown", type=_finite, default=None, help="waterline: distance between levels, mm")
    t.add_argument("--grid-step", type=_finite, default=None, help="waterline / CL surface: plan grid of heights, mm")
    t.add_argument(
        "--cl-surface", action="store_true", help="also fit the certified height-field B-spline of the tool positions"
    )
    t.add_argument(
        "--shank", default=None, help="shank above the cutting length, D=..,L=.. (mm): checked for collisions"
    )
    t.add_argument("--holder", default=None, help="holder above the shank, D=..,L=.. (mm): checked for collisions")


def _reff_parser(sub) -> None:
    """``machsurf reff``: effective radius and step-over maps."""
    e = sub.add_parser("reff", help="effective cutter radius and step-over maps over a face")
    _face_input(e, "example surface instead of a STEP: blade, bezier5, ...")
    e.add_argument("--tool", required=True, help="bull:D=..,r=.. | flat:D=.. | ball:D=.. (mm)")
    e.add_argument("--compare", default="ball", help="reference cutter: ball (same D, default), a cutter string, none")
    e.add_argument("--direction", default="0", help="machining direction(s) theta in degrees: 45 | -45,0,45,90 | all")
    e.add_argument("--grid", type=int, default=256, help="samples per parameter direction (default 256)")
    e.add_argument("--scallop", type=_finite, default=None, help="scallop height, mm: adds step-over maps")
    e.add_argument("--axes", type=int, default=3, help="3 (axis z, default) or 5 (lead/tilt)")
    e.add_argument("--lead", type=_finite, default=0.0, help="lead angle, degrees (5 axes)")
    e.add_argument("--tilt", type=_finite, default=0.0, help="tilt angle, degrees (5 axes)")
    e.add_argument("--no-render", dest="render", action="store_false", help="numbers only")
    e.add_argument("--max-memory-mb", type=_finite, default=4096.0, help="memory budget, MB: bigger work is refused")
    e.add_argument(
        "--chunks", type=int, default=1, help="split the directions into N groups (over the cluster in a batch)"
    )
    e.add_argument("-o", "--out", default="out/reff", help="output folder")


def _flank_parser(sub) -> None:
    """``machsurf flank``: flank milling of a ruled surface."""
    f = sub.add_parser("flank", help="flank milling settings of a cylindrical cutter on a ruled surface")
    _face_input(f, "eq18 | hypar | liu (the paper's surfaces, exact)", "STEP file with a ruled face (or use --example)")
    f.add_argument("--ruled-tolerance", type=_finite, default=None, help="accept a non-ruled face within this many mm")
    f.add_argument("--tool", nargs="+", default=["cyl:D=20"],
                   help="cylindrical cutter, e.g. cyl:D=80 (mm); several (--whole on a STEP part): each stretch of "
                   "the face by the largest that clears the part there")  # fmt: skip
    f.add_argument("--rule", type=_finite, default=0.5, help="rule position as a fraction of the u range [0, 1]")
    f.add_argument(
        "--setting",
        default="optimum",
        choices=["standard-tangent", "standard-distributed", "standard-bisector", "optimum", "minimax"],
        help="standard-distributed: Rubio's equal error at both directrices; standard-bisector: offset along the "
        "bisector of the end normals",
    )
    f.add_argument("--side", type=int, default=1, help="+1: tool on the side of S_u x S_v, -1: the other")
    f.add_argument("--whole", action="store_true", help="settings on the whole surface: tool path, envelope, map")
    f.add_argument(
        "--tolerance", type=_finite, default=0.01, help="whole-surface tolerance and rule step criterion, mm"
    )
    f.add_argument("--envelope-tolerance", type=_finite, default=1e-3, help="envelope fit tolerance, mm")
    f.add_argument("--study", action="store_true", help="the paper's parameter study plots (figs 9 and 10)")
    f.add_argument(
        "--radius-range",
        type=_finite,
        default=None,
        metavar="TOL",
        help="smallest and largest R keeping the whole surface within TOL mm",
    )
    f.add_argument(
        "--smooth",
        dest="smooth",
        type=_finite,
        nargs="?",
        const=0.0,
        default=None,
        metavar="DEG_PER_MM",
        help="beyond the paper: a minimax path over the whole surface whose axis turns at most DEG_PER_MM per mm "
        "(default 1.5x the rules' own turn), compared with the rule-by-rule optima",
    )
    f.add_argument(
        "--chunks", type=int, default=1, help="--whole: split the rules into N spans (over the cluster in a batch)"
    )
    f.add_argument(
        "--check-faces",
        default="rest",
        help="--whole on a STEP part: faces the cylinder is lifted clear of (rules it cannot clear are left out): "
        "rest (default: every other face) | body (the solid the face bounds) | none | 1,2",
    )
    f.add_argument("--no-render", dest="render", action="store_false", help="numbers and files, no pictures")
    _gouge(f, "--tolerance")
    _post(f)
    f.add_argument("-o", "--out", default="out/flank", help="output folder")


def _verify_parser(sub) -> None:
    """``machsurf verify``: tool-body gouges and collisions of a tool path."""
    w = sub.add_parser("verify", help="tool-body gouges and collisions of a tool path against every face of a part")
    w.add_argument("part", help="STEP file of the part")
    w.add_argument("--toolpath", required=True, help="tool path: our CSV, or APT CLDATA (.apt, .cls)")
    w.add_argument("--tool", default=None, help="cutter, e.g. bull:D=16,r=3 (default: the APT file's CUTTER)")
    w.add_argument("--shank", default=None, help="shank cylinder above the cutting length: D=..,L=.. (mm)")
    w.add_argument("--holder", default=None, help="holder cylinder above the shank: D=..,L=.. (mm)")
    w.add_argument("--faces", default="all", help="faces to check: all (default) or indices 0,3,5")
    w.add_argument(
        "--gouge-tolerance", type=_finite, default=0.01, help="gouge / collision tolerance, mm (default 0.01)"
    )
    w.add_argument(
        "--step",
        type=_finite,
        default=None,
        help="largest tip step along each move, mm (default min(1, sqrt(4 rho tol)): what the motion between two "
        "placements can cut deeper stays below gouge-tolerance/2, reported as motion_bound_mm)",
    )
    w.add_argument("--angle-step", type=_finite, default=1.0, help="largest axis step along each move, deg (default 1)")
    w.add_argument("--spacing", type=_finite, default=None, help="part sample spacing, mm (default min(1, D/8))")
    w.add_argument(
        "--chunks", type=int, default=1, help="split the placements into N chunks (over the cluster in a batch)"
    )
    w.add_argument("--no-render", dest="render", action="store_false", help="numbers only")
    w.add_argument("-o", "--out", default="out/verify", help="output folder")


def _simulate_parser(sub) -> None:
    """``machsurf simulate``: what a tool path leaves on the part."""
    s = sub.add_parser("simulate", help="what a tool path leaves on the part: scallops and gouges (N-buffer)")
    s.add_argument("part", help="STEP file of the part")
    s.add_argument("--toolpath", required=True, help="tool path: our CSV, or APT CLDATA (.apt, .cls)")
    s.add_argument("--tool", default=None, help="cutter, e.g. ball:D=10 (default: the APT file's CUTTER)")
    s.add_argument("--faces", default="all", help="faces to simulate: all (default) or indices 0,3,5")
    s.add_argument(
        "--resolution", type=_finite, default=None, help="nominal sample spacing, mm (default ~200k samples)"
    )
    s.add_argument(
        "--gouge-tolerance",
        type=_finite,
        default=0.01,
        help="a cut deeper than this is a gouge, mm (default 0.01); exit 2",
    )
    s.add_argument("--depth", type=_finite, default=1.0, help="deepest gouge measured, mm (default 1)")
    s.add_argument("--stock", type=_finite, default=1.0, help="thickest material measured, mm (default 1)")
    s.add_argument(
        "--motion-step", type=_finite, default=None, help="placement spacing on the motion, mm (default R/10)"
    )
    s.add_argument("--heights", default="0.001,0.002,0.005,0.01,0.02,0.05,0.1", help="area fractions above these, mm")
    s.add_argument("--max-samples", type=int, default=10_000_000, help="memory budget in samples (~400 B each)")
    s.add_argument(
        "--chunks", type=int, default=1, help="split the samples into N chunks (spread over the cluster in a batch)"
    )
    s.add_argument("--no-render", dest="render", action="store_false", help="numbers and VTP-free report only")
    s.add_argument("-o", "--out", default="out/simulate", help="output folder")


def _envelope_parser(sub) -> None:
    """``machsurf envelope``: swept envelopes and adjacent passes."""
    v = sub.add_parser("envelope", help="swept envelopes of a rotational tool and G1/G0 adjacent passes")
    v.add_argument(
        "--tool",
        required=True,
        help="cyl:D=.. | cone:D=..,angle=.. | drum:D=..,Rp=..,L=.. | barrel:... | ball:D=.. (mm, degrees)",
    )
    v.add_argument("--path", help="JSON path file: {points: [[x,y,z]...], axes: [[i,j,k]...]} (tip points, mm)")
    v.add_argument("--example", help="example motion instead of --path: sine (default), line, helix")
    v.add_argument("--part", default=None, help="STEP part the passes are for: the tool path is checked against it")
    v.add_argument("--passes", type=int, default=2, help="number of passes (default 2)")
    v.add_argument("--continuity", choices=["g0", "g1"], default="g1", help="between passes (default g1)")
    v.add_argument("--theta", default="0", help="rotation of each next axis about n1, degrees (one, or one per seam)")
    v.add_argument("--side", type=int, default=1, help="envelope sheet: +1 (side of S_a x S_t) or -1")
    v.add_argument("--tolerance", type=_finite, default=1e-3, help="fit tolerance per pass, mm (default 0.001)")
    v.add_argument(
        "--chordal-tolerance",
        type=_finite,
        default=0.01,
        help="chordal tolerance of the tool path, mm (default 0.01)",
    )
    v.add_argument(
        "--seam-angle-tolerance",
        type=_finite,
        default=0.05,
        help="G1 is claimed only when the written faces meet within this normal angle, deg (default 0.05); else exit 2",
    )
    v.add_argument(
        "--no-theta-scan", dest="theta_scan", action="store_false", help="skip the scan of the admissible theta range"
    )
    v.add_argument("--no-render", dest="render", action="store_false", help="skip the zebra picture")
    _gouge(v, "0.01")
    _post(v)
    v.add_argument("-o", "--out", default="out/envelope", help="output folder")


def _mill3_parser(sub) -> None:
    w = sub.add_parser(
        "mill3", help="3-axis tool paths on a whole part: exact drop-cutter on its faces (raster or waterline)"
    )
    w.add_argument("part", nargs="?", help="STEP file of the part (or use --example)")
    w.add_argument("--example", help="example surface instead of a STEP: bezier5, blade, ...")
    w.add_argument("--tool", required=True, help="any cutter: ball:D=.., flat:D=.., bull:D=..,r=.., cone:... (mm)")
    w.add_argument("--faces", default="top", help="faces to machine: top (default: seen along the axis) | all | 0,3,5")
    w.add_argument(
        "--check-faces", default="rest", help="faces the tool must not cut into: rest (default) | all | none"
    )
    w.add_argument("--axis", default=None, help="fixed tool axis x,y,z (3+2; default 0,0,1)")
    w.add_argument("--pattern", choices=["raster", "waterline"], default="raster", help="tool-path pattern")
    w.add_argument("--stepover", type=_finite, default=None, help="distance between raster lines, mm (default 2)")
    w.add_argument("--scallop", type=_finite, default=None, metavar="H", help="instead of --stepover: cusp height H mm")
    w.add_argument("--angle", type=_finite, default=0.0, help="raster direction in the plane, degrees (default 0)")
    w.add_argument("--direction", choices=["zigzag", "one-way"], default="zigzag", help="raster line order")
    w.add_argument("--stepdown", type=_finite, default=None, help="waterline: distance between levels, mm")
    w.add_argument("--grid-step", type=_finite, default=None, help="waterline: plan grid of heights, mm")
    w.add_argument("--chordal-tolerance", type=_finite, default=0.005, help="chordal tolerance of the positions, mm")
    w.add_argument("--cl-surface", action="store_true", help="also fit the certified height field of the positions")
    w.add_argument("--no-toolpath", dest="toolpath", action="store_false", help="with --cl-surface: no tool path")
    w.add_argument(
        "--tolerance", type=_finite, default=1e-3, help="CL surface fit tolerance, max-norm mm (default 0.001)"
    )
    w.add_argument("--degree", type=int, default=3, help="CL surface degree (default 3)")
    w.add_argument("--max-poles", type=int, default=40000, help="CL surface pole budget (default 40000)")
    w.add_argument("--shank", default=None, help="shank above the cutting length, D=..,L=.. (mm)")
    w.add_argument("--holder", default=None, help="holder above the shank, D=..,L=.. (mm)")
    _gouge(w, "0.01")
    _post(w)
    w.add_argument("-o", "--out", default="out/mill3", help="output folder")


def _batch_parser(sub) -> None:
    b = sub.add_parser("batch", help="run many jobs (one command line each) on Dask: a local cluster or a scheduler")
    b.add_argument("jobs", help='jobs file: JSON {"jobs": [{"name": ..., "argv": [command line without -o]}]} or TOML')
    b.add_argument("--scheduler", default=None, help="address of a running Dask scheduler, tcp://host:port")
    b.add_argument("--workers", type=int, default=None, help="local cluster: worker processes (default one per core)")
    b.add_argument("--retries", type=int, default=2, help="runs again of a job whose task failed (default 2)")
    b.add_argument("--timeout", type=_finite, default=10.0, help="time to reach --scheduler, s (default 10)")
    b.add_argument("--overwrite", action="store_true", help="replace an earlier batch in the output folder")
    b.add_argument("-o", "--out", default="out/batch", help="output folder: <name>/ per job, batch_report.json")
