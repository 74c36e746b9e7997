"""One vocabulary: every public argument, job spec field and CLI option is a glossary term (issue 26)."""

from __future__ import annotations

import dataclasses
import inspect
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad.cliargs import DEPRECATED_OPTIONS, build_parser, modernise_argv
from machsurf_cad.glossary import RENAMED, TERMS, table

ROOT = Path(__file__).resolve().parents[1]
INPUT_TYPES = (
    "BallEndMill", "FlatEndMill", "BullNoseEndMill", "ConicalCutter", "DrumCutter", "APTCutter", "Shank",
    "PostOptions", "FixedAxis", "LeadTilt", "AxisField", "PlanesFeed", "IsoFeed", "BatchJob",
)  # fmt: skip
"""Classes users build as inputs (results and data types, whose fields are outputs, are not scanned)."""


def _public_parameters():
    for name in ms.__all__:
        obj = getattr(ms, name)
        if inspect.isclass(obj):
            if (issubclass(obj, ms.JobSpec) and obj is not ms.JobSpec) or name in INPUT_TYPES:
                yield name, [f.name for f in dataclasses.fields(obj)]
        elif inspect.isfunction(obj):
            sig = inspect.signature(obj)
            yield name, [p.name for p in sig.parameters.values() if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)]


def test_every_public_parameter_and_spec_field_is_a_glossary_term():
    unknown, retired = [], []
    for name, params in _public_parameters():
        unknown += [f"{name}({p})" for p in params if p not in TERMS]
        retired += [f"{name}({p})" for p in params if p in RENAMED and p not in TERMS]
    assert not unknown, f"not in machsurf_cad.glossary.TERMS: {unknown}"
    assert not retired, f"retired names still in a signature: {retired}"
    n = sum(len(p) for _, p in _public_parameters())
    assert n > 400  # the scan saw the API, not an empty list


def test_every_cli_option_is_its_spec_field_and_a_glossary_term():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    skip = {"help", "out", "command", "version", "jobs", "scheduler", "workers", "retries", "timeout"}
    for command, p in sub.choices.items():
        for a in p._actions:
            if a.dest in skip:
                continue
            assert a.dest in TERMS, f"machsurf {command}: option {a.option_strings or a.dest} -> {a.dest}"
            if a.option_strings:
                assert f"--{a.dest.replace('_', '-')}" in a.option_strings or a.dest in (
                    "render",
                    "toolpath",
                    "theta_scan",
                )
        spec = ms.jobs.SPECS.get(command)
        if spec is not None and command != "demo":
            fields = {f.name for f in dataclasses.fields(spec)}
            dests = {a.dest for a in p._actions} - skip
            assert dests <= fields, f"{command}: options without a spec field: {dests - fields}"


def test_glossary_page_is_the_table():
    assert (ROOT / "docs" / "glossary.md").read_text().split("\n", 2)[2] == table()


def test_old_argument_names_still_work_with_a_warning():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        r = ms.effective_radius("bull:D=10,r=2", slope_deg=30.0, alpha_deg=0.0)
        job = ms.VerifyJob(part="p.step", toolpath="t.csv", tol=0.02, step_deg=2.0)
        opts = ms.PostOptions(feed_mm_min=1500)
    new = ms.effective_radius("bull:D=10,r=2", slope=30.0, alpha=0.0)
    assert float(r) == float(new)
    assert (job.gouge_tolerance, job.angle_step, opts.feed) == (0.02, 2.0, 1500)
    msgs = [str(x.message) for x in w if x.category is DeprecationWarning]
    assert any("slope_deg= is now slope=" in m for m in msgs)
    assert any("tol= is now gouge_tolerance=" in m for m in msgs)
    assert any("feed_mm_min= is now feed=" in m for m in msgs)
    with pytest.raises(ms.InputError, match="give gouge_tolerance= only"):
        ms.VerifyJob(part="p.step", toolpath="t.csv", tol=0.02, gouge_tolerance=0.03)


def test_old_cli_options_are_rewritten_per_command_with_a_note():
    notes = []
    argv = modernise_argv(["verify", "p.step", "--toolpath", "t.csv", "--tol", "0.02", "--step-deg=2"], notes.append)
    assert argv[-2:] == ["--gouge-tolerance", "0.02", "--angle-step=2"][-2:] and "--gouge-tolerance" in argv
    assert argv[-1] == "--angle-step=2"
    assert modernise_argv(["flank", "--tol", "0.1"]) == ["flank", "--tolerance", "0.1"]
    assert modernise_argv(["reff", "--grid", "8"]) == ["reff", "--grid", "8"]  # a count there: not renamed
    assert len(notes) == 2 and notes[0].startswith("note: --tol is now --gouge-tolerance")
    for command, old in DEPRECATED_OPTIONS.items():
        assert set(old.values()) <= {s for a in _sub(command)._actions for s in a.option_strings}, command


def _sub(command):
    parser = build_parser()
    return next(a for a in parser._actions if a.dest == "command").choices[command]


def test_an_old_option_on_the_command_line_works_and_says_so(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "machsurf_cad", "reff", "--example", "bezier5", "--tool", "ball:D=10", "--grid", "8",
         "--no-render", "--max-memory", "512", "-o", str(tmp_path / "r")],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "note: --max-memory is now --max-memory-mb" in r.stderr


def test_scallop_relations_have_one_home_and_one_argument_order():
    from machsurf_cad import scallop

    assert ms.stepover is scallop.stepover and ms.scallop_stepover is scallop.scallop_stepover
    # the flat-floor step of a ball equals relation (31) on a plane with R_eff = R (two circles, exact)
    d, _ = ms.stepover(0.01, 5.0, np.inf)
    assert abs(ms.scallop_stepover(0.01, "ball:D=10") - float(d)) < 1e-12
    assert abs(float(scallop.spacing_for_scallop(0.01, 5.0, 0.0)) - float(d)) < 1e-12
    assert abs(float(scallop.scallop_height(float(d), 5.0, 0.0)) - 0.01) < 1e-12
    with pytest.warns(DeprecationWarning, match="is now scallop_stepover"):
        old = ms.scallop_stepover("ball:D=10", 0.01)
    assert old == ms.scallop_stepover(0.01, "ball:D=10")


def test_every_command_line_in_the_docs_parses():
    """Each `machsurf ...` command printed in README.md and docs/*.md (not the synopses with [ | ...]) is a
    valid command line of this version: no retired option, no option that does not exist."""
    import re
    import shlex

    parser = build_parser()
    found, bad = 0, []
    docs = sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts)
    for page in [ROOT / "README.md", *docs, ROOT / "workbench" / "README.md"]:
        text = page.read_text()
        lines = re.findall(r"`(machsurf [^`]+)`", text) + re.findall(r"^(machsurf [^\n`#]+)", text, flags=re.M)
        for line in lines:
            if any(ch in line for ch in "[]|<>") or "..." in line or line.startswith("machsurf run"):
                continue
            argv = [a for a in shlex.split(line)[1:] if a != "\\"]
            if (
                len(argv) < 2
                or (len(argv) == 2 and argv[1].startswith("--"))
                or argv[0] not in {a for act in parser._actions if act.dest == "command" for a in act.choices}
            ):
                continue  # a command's name in a sentence
            if modernise_argv(argv) != argv:
                bad.append(f"{page.name}: retired option in `{line}`")
            try:
                parser.parse_args(argv)
            except SystemExit:
                bad.append(f"{page.name}: `{line}` does not parse")
            found += 1
    assert not bad, bad
    assert found >= 6  # the README's chained examples and the guide's
