"""The public namespace: every entry point works twice and after importing its submodule; results are
frozen with read-only arrays; one progress signature; report keys carry their units."""

import dataclasses
import importlib
import math
import pkgutil

import numpy as np
import pytest
from helpers import assert_close

import machsurf_cad as ms


def _calls():
    """One small call per entry point, each with a number to check (mm, degrees)."""
    bez = ms.example("bezier5")
    hyp = ms.example("hypar", "ruled")
    return {
        "machining_surface": lambda: ms.machining_surface(bez, "ball:D=10", axes=3, tolerance=1e-2).s1_fit.max_error,
        "reff": lambda: float(ms.reff(bez, "bull:D=10,r=2", grid=16).directions[0].r_eff.min()),
        "reff_maps": lambda: float(ms.reff_maps(bez, "ball:D=10", grid=8).directions[0].r_eff.max()),
        "effective_radius": lambda: float(ms.effective_radius("bull:D=10,r=2", 90.0, 0.0)),
        "stepover": lambda: float(ms.stepover(0.01, 5.0, np.inf)[0]),
        "flank": lambda: ms.flank(hyp, "cyl:D=20", setting="standard-distributed").interference.max_abs,
        "envelope": lambda: ms.envelope("cyl:D=10", ms.example("line", "motion")).chain.fits[0].max_error,
        "deviation": lambda: ms.deviation(bez, bez.with_poles(bez.poles + [0, 0, 0.5]), samples=12).max_abs,
        "parse_cutter": lambda: ms.parse_cutter("bull:D=20,r=4").torus_radius,
        "example": lambda: ms.example("liu", "ruled").u_range[1],
    }


EXPECTED = {
    "effective_radius": 10.0 / 2 - 2 + 2,  # feed along the steepest slope (alpha = 0) on a vertical wall: R_t + r
    "stepover": 2 * math.sqrt(0.01 * (2 * 5.0 - 0.01)),  # flat surface: 2 sqrt(h (2 R_eff - h))
    "flank": 10.0 * (1 - math.cos(math.radians(30.0))),  # standard distributed on the hypar: R (1 - cos alpha0)
    "parse_cutter": 6.0,
    "example": 23.014,
    "reff_maps": 5.0,  # a ball's effective radius is its radius everywhere
}


@pytest.mark.parametrize("name", sorted(_calls()))
def test_entry_point_twice_and_after_importing_its_submodule(name):
    call = _calls()[name]
    first = call()
    for mod in (
        "machsurf_cad.flank_milling",
        "machsurf_cad.sweep",
        "machsurf_cad.measure",
        "machsurf_cad.effradius",
        "machsurf_cad.machining",
        "machsurf_cad.examples",
        "machsurf_cad.cutters",
    ):
        importlib.import_module(mod)
    second = call()
    assert callable(getattr(ms, name)) and first == second
    if name in EXPECTED:
        assert_close(first, EXPECTED[name], 1e-9, name)
    if name in ("machining_surface", "envelope"):
        assert first <= 1e-2
    if name == "deviation":  # a patch lifted by 0.5 mm along z: normal distance <= 0.5, = 0.5 where flat
        assert 0.4 < first <= 0.5 + 1e-9


def test_namespace_lists_every_entry_point_and_no_name_shadows_a_subpackage():
    names = set(dir(ms))
    for n in (
        "machining_surface",
        "tool_paths",
        "reff",
        "flank",
        "envelope",
        "deviation",
        "run_job",
        "ToolPath",
        "write_apt",
        "read_apt",
        "FlankResult",
        "EnvelopeResult",
        "MachiningSurface",
        "DeviationResult",
    ):
        assert n in names and n in ms.__all__
    subs = {m.name for m in pkgutil.iter_modules(ms.__path__)}
    for n in ms.__all__:
        if n in subs:  # a public name may only be the submodule itself (like ``builders``), never a function
            assert getattr(ms, n) is importlib.import_module(f"machsurf_cad.{n}"), n
    assert {"flank", "envelope", "deviation", "reff"}.isdisjoint(subs)


def test_results_are_frozen_read_only_and_compare_by_identity():
    d = ms.deviation(ms.example("bezier5"), ms.example("bezier5"), samples=10)
    with pytest.raises(ValueError):
        d.signed[0] = 99.0  # read-only: the statistics cannot go stale
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.tolerance = 1.0
    assert d == d and d != ms.deviation(ms.example("bezier5"), ms.example("bezier5"), samples=10)
    assert isinstance(hash(d), int)  # hashable by identity (eq=False), never by array value
    tp = ms.tool_paths(ms.machining_surface(ms.example("bezier5"), "ball:D=10", axes=3, tolerance=1e-2), stepover=20)
    assert not tp.tip.flags.writeable and not tp.extras["uv"].flags.writeable


def test_reports_carry_units_and_one_timing_convention():
    bez = ms.example("bezier5")
    res = ms.machining_surface(bez, "bull:D=28,r=4", axes=5, lead=20, tolerance=1e-3)
    rep = res.report()
    assert set(rep["time_s"]) >= {"loops_s", "fit_S1_s", "fit_S2_s", "total_s"}
    assert all(k.endswith("_s") for k in rep["time_s"])
    dev = ms.deviation(bez, bez, samples=10).report()
    assert {"max_abs_mm", "rms_mm", "mean_mm", "worst_xyz_mm", "tolerance_mm"} <= set(dev)
    maps = ms.reff_maps(bez, "bull:D=10,r=2", grid=8).report()
    assert all(k.endswith("_s") for k in maps["time_s"]) and "total_s" in maps["time_s"]
    fl = ms.flank(ms.example("liu", "ruled"), "cyl:D=20").report()
    assert all(k.endswith("_s") for k in fl["time_s"]) and "total_s" in fl["time_s"]


def test_one_progress_signature():
    calls = []

    def progress(done, total, message):
        calls.append((done, total, message))

    bez = ms.example("bezier5")
    ms.deviation(bez, bez, samples=30, progress=progress)
    ms.machining_surface(bez, "ball:D=10", axes=3, tolerance=1e-4, progress=progress)
    ms.flank(ms.example("liu", "ruled"), "cyl:D=20", whole=True, tolerance=0.5, progress=progress)
    kinds = {m.split()[1] if m[:1].isdigit() else m for _, _, m in calls}
    assert {"closest points", "poles,", "settings along the surface"} <= kinds
    assert all(isinstance(d, int) and (t is None or isinstance(t, int)) for d, t, _ in calls)


def test_job_specs_validate_and_round_trip_through_a_mapping():
    spec = ms.FlankJob(example="liu", tool="cyl:D=20", whole=True, tolerance=0.5)
    again = ms.FlankJob.from_mapping({k: v for k, v in spec.to_dict().items() if k != "command"})
    assert again == spec and spec.to_dict()["command"] == "flank"
    with pytest.raises(ms.InputError, match="setting must be one of"):
        ms.FlankJob(example="liu", setting="best")
    with pytest.raises(ms.InputError, match="unknown option"):
        ms.FlankJob.from_mapping({"example": "liu", "radius": 3})
    with pytest.raises(ms.InputError, match="loops must be one of"):
        ms.MachiningSurfaceJob(example="bezier5", loops="ignore")
