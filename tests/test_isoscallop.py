"""Iso-scallop passes: spacing from the scallop height, confirmed by the cut simulation (mm)."""

import math

import pytest
from conftest import needs_kernel
from helpers import assert_close

import machsurf_cad as ms
from machsurf_cad.geometry import builders
from machsurf_cad.machining.isoscallop import iso_scallop_paths


def test_ball_on_a_plane_spacing_is_the_closed_form():
    R, h = 5.0, 0.01
    plane = ms.Face(builders.plane_patch((0, 0, 0), (40, 0, 0), (0, 30, 0)), name="plane")
    res = ms.machining_surface(plane, "ball:D=10", axes=3, tolerance=1e-4)
    tp = ms.tool_paths(res, scallop=h, chordal_tolerance=1e-3, clearance=20)  # the public door
    w = 2 * math.sqrt(2 * R * h - h * h)
    assert_close([tp.info["spacing_min_mm"], tp.info["spacing_max_mm"]], [w, w], 1e-6, "spacing")
    # the passes cover the plane: about width / w of them plus the two on the edges
    assert abs(tp.info["n_passes_planned"] - (math.ceil(40.0 / w) + 1)) <= 1
    sim = ms.simulate(plane, tp, resolution=0.1)
    assert h - 2e-4 < sim.max_scallop <= h + 1e-4 and sim.max_gouge < 1e-6


@pytest.mark.parametrize(
    "tool,axes,lead,resolution",
    [("ball:D=10", 3, 0.0, 0.3), ("bull:D=16,r=3", 5, 10.0, 0.3), ("flat:D=10", 5, 5.0, 0.5)],
)
@pytest.mark.slow
def test_simulation_confirms_the_scallop_on_a_free_form_face(tool, axes, lead, resolution):
    """``--scallop 0.01`` on the example free-form: the simulated max scallop is at most H plus the fit and
    chordal tolerances, and at least 0.006 (the planner uses its allowance); fewer passes than a constant
    spacing keeping the same scallop. The flat end mill's overruns past the face are shortened where they
    would gouge, not dropped: the face's corners keep their scallop (0.026 mm there when dropped)."""
    h, fit, chord = 0.01, 1e-4, 1e-3
    face = ms.example("bezier5")
    res = ms.machining_surface(face, tool, axes=axes, lead=lead, tolerance=fit)
    tp = iso_scallop_paths(res, scallop=h, chordal_tolerance=chord, clearance=60)
    assert tp.info["n_passes_planned"] <= tp.info["n_passes_constant_spacing"]
    sim = ms.simulate(ms.Face(face, name="f", reversed=res.nominal.reversed), tp, resolution=resolution)
    assert sim.reached.all()
    assert 0.006 <= sim.max_scallop <= h + fit + chord, sim.report()
    assert sim.max_gouge <= fit + chord


def test_a_scallop_the_tool_cannot_leave_is_refused():
    res = ms.machining_surface(ms.example("bezier5"), "ball:D=10", axes=3, tolerance=1e-3)
    with pytest.raises(ms.InputError, match="not smaller than the tool radius"):
        iso_scallop_paths(res, scallop=6.0)
    with pytest.raises(ms.InputError, match="> 0"):
        iso_scallop_paths(res, scallop=0.0)


@pytest.mark.slow
@needs_kernel
def test_machining_surface_command_with_scallop(tmp_path):
    import json

    from helpers import run

    out = tmp_path / "iso"
    r = run(
        "machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--axes", "3", "--toolpath",
        "--scallop", "0.02", "--chordal-tolerance", "0.002", "--clearance", "60", "--simulate", "--simulate-resolution",
        "0.5", "-o", out,
    )  # fmt: skip
    assert r.returncode == 0, r.stdout + r.stderr
    rep = json.loads((out / "report.json").read_text())
    info, sim = rep["toolpath"], rep["verify"]["simulate"]
    assert info["kind"] == "iso-scallop" and info["scallop_mm"] == 0.02
    assert 0.012 <= sim["max_scallop_mm"] <= 0.02 + 0.002 + 0.001 and not sim["gouged"]
    assert "iso-scallop passes for 0.02 mm" in r.stdout
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--toolpath", "--scallop", "7",
            "-o", tmp_path / "bad")  # fmt: skip
    assert r.returncode == 1 and "tool radius" in r.stderr and "Traceback" not in r.stderr
