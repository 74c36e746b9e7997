"""The command line: figures in the JSON report, exit codes 0/1/2, one-line errors, no partial output."""

import json

import numpy as np
import pytest
from conftest import ROOT, needs_kernel, needs_pyvista
from helpers import run, run_process

import machsurf_cad as ms

pytestmark = needs_kernel
BLOCK = ROOT / "example_parts" / "freeform_block.step"


def test_info_reports_every_face(tmp_path):
    r = run_process("info", BLOCK, "-o", tmp_path / "info")
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "info" / "report.json").read_text())
    assert rep["n_faces"] == 8 and f"{rep['n_faces']} face(s)" in r.stdout
    top = rep["faces"][0]
    assert top["name"] == "freeform_top" and top["trimmed"] and top["n_loops"] == 2
    assert f"{top['area_mm2']:.2f}" in r.stdout
    assert {f["source_type"] for f in rep["faces"]} == {"BSplineSurface", "Plane", "Cylinder"}


@needs_pyvista
def test_inspect_step_candidate_and_tolerance_exit_code(tmp_path):
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.occ import read_step_faces, write_step

    nominal = tmp_path / "nominal.step"
    top = read_step_faces(BLOCK)[0]
    write_step(nominal, [top])
    shifted = tmp_path / "shifted.step"
    s = top.surface
    write_step(shifted, [Face(s.with_poles(s.poles + [0, 0, 0.02]), top.loops, name="shifted")])
    ok = run("inspect", nominal, shifted, "--tolerance", "0.05", "--samples", "60", "-o", tmp_path / "ok")
    assert ok.returncode == 0, ok.stderr
    rep = json.loads((tmp_path / "ok" / "report.json").read_text())
    dev = rep["deviation"]
    # translating by 0.02 mm in z: the normal distance is 0.02 * n_z, at most 0.02 mm
    assert 0.018 < dev["max_abs_mm"] <= 0.02 + 1e-9
    assert f"{dev['max_abs_mm']:.6g}" in ok.stdout
    assert (tmp_path / "ok" / "deviation.png").stat().st_size > 10000
    bad = run_process(
        "inspect", nominal, shifted, "--tolerance", "0.01", "--samples", "40", "--no-render", "-o", tmp_path / "bad"
    )
    assert bad.returncode == 2 and "NOT met" in bad.stdout
    assert json.loads((tmp_path / "bad" / "report.json").read_text())["deviation"]["within_tolerance"] is False


def test_inspect_stl_candidate(tmp_path):
    from machsurf_cad.occ import read_step_faces, write_stl

    top = read_step_faces(BLOCK)[0]
    stl = write_stl(tmp_path / "top.stl", [top], linear_deflection=0.05)
    r = run("inspect", BLOCK, stl, "--no-render", "-o", tmp_path / "o")
    assert r.returncode == 0, r.stderr
    dev = json.loads((tmp_path / "o" / "report.json").read_text())["deviation"]
    assert dev["max_abs_mm"] < 0.05 * 1.2 and dev["n_points"] > 1000


@pytest.mark.parametrize("case", ["missing", "empty", "corrupt", "noface", "index", "suffix"])
def test_bad_input_one_line_exit_1_nothing_written(tmp_path, case):
    out = tmp_path / "out"
    (tmp_path / "empty.step").write_text("")
    (tmp_path / "corrupt.step").write_text("ISO-10303-21;\nHEADER;\ngarbage\n")
    args = {
        "missing": ("info", tmp_path / "nope.step"),
        "empty": ("info", tmp_path / "empty.step"),
        "corrupt": ("info", tmp_path / "corrupt.step"),
        "noface": ("inspect", BLOCK, tmp_path / "corrupt.step"),
        "index": ("inspect", BLOCK, BLOCK, "--face", "42"),
        "suffix": ("inspect", BLOCK, tmp_path / "cand.iges"),
    }[case]
    r = run_process(*args, "-o", out)
    assert r.returncode == 1
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("machsurf: error:"), r.stderr
    assert "Traceback" not in r.stderr
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.partial")]


def test_usage_errors_exit_1():
    r = run("inspect")
    assert r.returncode == 1 and "Traceback" not in r.stderr
    r = run("frobnicate")
    assert r.returncode == 1
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=6", "--max-tilt", "nan")
    lines = [ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip()]
    assert r.returncode == 1 and len(lines) == 1 and "--max-tilt: must be a finite number" in lines[0], lines
    # a clearance larger than the part: a unit mistake, refused before any work
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=6", "--toolpath", "--clearance", "10000")
    assert r.returncode == 1 and r.stdout.strip() == "" and "larger than the part (144.8 mm" in r.stderr, r.stderr


@needs_pyvista
def test_machining_surface_command_with_toolpath(tmp_path):
    from machsurf_cad.occ import read_step_faces

    out = tmp_path / "ms"
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=28,r=4",
        "--axes",
        "5",
        "--strategy",
        "planes:x",
        "--lead",
        "20",
        "--tilt",
        "0",
        "--tolerance",
        "0.001",
        "--toolpath",
        "--stepover",
        "5",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr  # lead 20 deg: checked against the face, clean, written
    rep = json.loads((out / "report.json").read_text())
    assert rep["verify"]["clean"] and rep["verify"]["max_gouge_mm"] <= 0.01
    # lead 5 deg: R_t / sin(5) + r = 119 mm behind and beside the contact, tighter corners are cut: refused
    low = tmp_path / "low"
    args = [
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=28,r=4",
        "--lead",
        "5",
        "--tolerance",
        "0.001",
        "--toolpath",
        "--stepover",
        "5",
        "-o",
        low,
    ]
    r = run(*args)
    assert r.returncode == 2 and "tool path NOT written" in r.stdout, r.stderr
    assert not (low / "toolpath.apt").exists()
    v = json.loads((low / "report.json").read_text())["verify"]
    assert v["n_gouging_positions"] > 0 and v["max_gouge_mm"] > 0.3 and v["worst"][0]["face"] == "bezier5"
    r = run(*args, "--allow-gouge")
    assert r.returncode == 0 and (low / "toolpath.apt").is_file()  # written on request, gouges listed
    assert json.loads((low / "report.json").read_text())["verify"]["max_gouge_mm"] == pytest.approx(v["max_gouge_mm"])
    assert rep["S1"]["max_error_mm"] <= 0.001 and rep["S2"]["max_error_mm"] <= 0.001
    assert f"{rep['S1']['max_error_mm']:.3g}" in r.stdout
    assert rep["loops"]["found"] is False
    assert rep["alpha_max_deg_for_tolerance"] == pytest.approx(np.degrees(np.arctan(0.002 / 10)))
    assert rep["S1_deviation_map"]["max_abs_mm"] <= 0.001
    faces = read_step_faces(out / "machining_surface.step")
    assert [f.name for f in faces] == ["S1_guiding", "S2_orientation"]
    assert rep["toolpath"]["chordal_error_measured_mm"] <= 0.01
    apt = (out / "toolpath.apt").read_text()
    assert "CUTTER/28.0000,4.0000,10.0000,4.0000" in apt and "MULTAX/ON" in apt
    for name in ("S1_guiding.stl", "S2_orientation.stl", "deviation_S1.png", "toolpath.csv"):
        assert (out / name).is_file()


def test_machining_surface_command_errors(tmp_path):
    # loops: a ball bigger than the bowl -> one line, exit 1, nothing written
    out = tmp_path / "loop"
    r = run("machining-surface", BLOCK, "--face", "0", "--tool", "ball:D=600", "--lead", "10", "-o", out)
    assert r.returncode == 1 and "loop" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()
    # unreachable tolerance -> exit 2
    out = tmp_path / "tol"
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=28,r=4",
        "--lead",
        "20",
        "--tolerance",
        "1e-9",
        "--max-poles",
        "300",
        "-o",
        out,
    )
    assert r.returncode == 2 and "reached" in r.stderr
    assert not out.exists()
    # a cone is not a Table-1 cutter
    r = run("machining-surface", "--example", "bezier5", "--tool", "cone:D=10,angle=5", "--lead", "20", "-o", out)
    assert r.returncode == 1 and "Table 1" in r.stderr


def test_degenerate_surface_is_a_one_line_error(tmp_path):
    from machsurf_cad.geometry import builders
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.occ import write_step

    # a cone with its tip inside the face: the normal has no limit there
    tri = builders.revolve_profile(ms.BSplineCurve(1, [0, 1], [2, 2], [[30.0, 0.0], [0.0, 30.0]]), 300.0)
    try:
        path = write_step(tmp_path / "tri.step", [Face(tri, name="tri")])
    except Exception as exc:  # the kernel may refuse the degenerate face already: that is a clear error too
        assert "not valid" in str(exc)
        return
    out = tmp_path / "o"
    r = run("machining-surface", path, "--tool", "ball:D=10", "--lead", "10", "-o", out)
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "no limit normal" in r.stderr or "not valid" in r.stderr
    assert not out.exists()


@needs_pyvista
def test_reff_command_report_and_maps(tmp_path):
    out = tmp_path / "reff"
    r = run(
        "reff",
        "--example",
        "blade",
        "--tool",
        "bull:D=10,r=2",
        "--compare",
        "ball",
        "--direction=-45,0,45,90",
        "--grid",
        "64",
        "--scallop",
        "0.01",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    assert [d["theta_deg"] for d in rep["directions"]] == [-45, 0, 45, 90]
    for d in rep["directions"]:
        assert 2.0 - 1e-9 <= d["r_eff_min_mm"] <= d["r_eff_mean_mm"] <= d["r_eff_max_mm"]
        assert 0.0 <= d["area_fraction_torus_beats_ball"] <= 1.0
        assert d["stepover_ratio_mean"] == pytest.approx(d["stepover_mean_mm"] / d["stepover_ball_mean_mm"])
        assert f"{d['r_eff_mean_mm']:.4g}" in r.stdout
    assert sum(rep["best_direction"]["histogram_deg"].values()) == 64 * 64
    for name in ("reff_thetam45.png", "reff_theta90.vtp", "best_direction.png"):
        assert (out / name).is_file()
    import pyvista as pv

    # the .vtp holds true values (only colours clip at 2R = 10 mm): its max is the report's max
    for d in rep["directions"]:
        tag = f"{d['theta_deg']:g}".replace("-", "m")
        arr = np.asarray(pv.read(out / f"reff_theta{tag}.vtp").point_data["R_eff [mm]"])
        assert abs(np.nanmax(arr[np.isfinite(arr)]) - d["r_eff_max_mm"]) <= 1e-9 * d["r_eff_max_mm"]
    assert max(d["r_eff_max_mm"] for d in rep["directions"]) > 10.0  # beyond the colour range somewhere


def test_reff_command_bad_input(tmp_path):
    r = run("reff", "--example", "blade", "--tool", "bull:D=10,r=2", "--direction", "0.785,1.571", "-o", tmp_path / "a")
    assert r.returncode == 1 and "radians" in r.stderr and "Traceback" not in r.stderr
    r = run("reff", "--example", "blade", "--tool", "bull:D=10,r=2", "--scallop", "7", "-o", tmp_path / "b")
    assert r.returncode == 1 and "scallop" in r.stderr
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@needs_pyvista
def test_flank_command(tmp_path):
    out = tmp_path / "flank"
    r = run(
        "flank",
        "--example",
        "liu",
        "--tool",
        "cyl:D=20",
        "--rule",
        "0.5",
        "--setting",
        "optimum",
        "--side",
        "+1",
        "--whole",
        "--tolerance",
        "0.5",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    st, e = rep["setting"], rep["interference"]
    assert st["kind"] == "optimum" and abs(st["h0_mm"] + st["h1_mm"] - st["h_p_mm"]) < 1e-9
    assert f"{st['gamma_deg']:.6f}" in r.stdout and f"{e['max_gouge_mm']:.6g}" in r.stdout
    assert e["max_abs_mm"] < 0.05
    w = rep["whole"]
    assert w["envelope_fit"]["max_error_mm"] <= 1e-3 and w["n_rules"] >= 9
    assert w["deviation_from_envelope"]["max_abs_mm"] < 0.5
    rows = (out / "toolpath.csv").read_text().splitlines()
    assert (
        len(rows) == 1 + w["n_rules"] + 2
    )  # header, one cut position per rule, approach from and retract to clearance
    apt = (out / "toolpath.apt").read_text().splitlines()
    assert sum(ln.startswith("GOTO/") for ln in apt) == w["n_rules"] + 2
    assert "CUTTER/20.0000,0.0000,10.0000,0.0000,0.0000,0.0000," in "\n".join(apt)  # same convention as every tool
    from machsurf_cad import Move, read_apt

    tp = read_apt(out / "toolpath.apt")
    assert [Move(m).name for m in tp.move[[0, 1, 2, -1]]] == ["RAPID", "APPROACH", "CUT", "RETRACT"]
    # a flank tool lies along the surface: it approaches and leaves 5 mm sideways (normal to its axis)
    for a, b in ((0, 1), (-1, -2)):
        w = tp.tip[a] - tp.tip[b]
        assert abs(np.linalg.norm(w) - 5.0) < 2e-5 and abs(w @ tp.axis[b]) < 2e-5
    assert rep["whole"]["verify"]["clean"] and rep["whole"]["verify"]["n_collisions"] == 0
    for name in ("envelope.step", "envelope.stl", "deviation.png"):
        assert (out / name).is_file()
    # the whole surface is not within 0.01 mm with R = 10: exit 2, outputs still written
    r = run(
        "flank", "--example", "liu", "--tool", "cyl:D=20", "--whole", "--tolerance", "0.01", "-o", tmp_path / "tight"
    )
    assert r.returncode == 2 and "NOT met" in r.stdout


def test_flank_command_bad_input(tmp_path):
    r = run("flank", "--example", "hypar", "--rule", "1.5", "-o", tmp_path / "a")
    assert r.returncode == 1 and "outside [0, 1]" in r.stderr
    r = run("flank", "--example", "hypar", "--tool", "cyl:D=200", "--setting", "optimum", "-o", tmp_path / "b")
    assert r.returncode == 1 and "no admissible" in r.stderr
    r = run("flank", ROOT / "example_parts" / "bezier5_patch.step", "-o", tmp_path / "c")
    assert r.returncode == 1 and "not a ruled surface" in r.stderr
    r = run("flank", "--example", "hypar", "--tool", "ball:D=10", "-o", tmp_path / "d")
    assert r.returncode == 1 and "cylindrical" in r.stderr
    # a clearance larger than the part: a unit mistake, as for the other commands (the example hypar is
    # 100 x 100 x 20 mm: its poles' box 141.4 mm across)
    r = run("flank", "--example", "hypar", "--whole", "--clearance", "5000", "-o", tmp_path / "e")
    assert r.returncode == 1 and "clearance 5000 mm is larger than the part" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not any((tmp_path / x).exists() for x in "abcde")


def test_a_holder_narrower_than_its_shank_is_refused_and_the_body_applies_to_one_faces_path(tmp_path):
    """--shank/--holder give the whole tool to every path's check, the 5-axis and 3+2 paths of one face
    included (tilt away clears the holder too); a holder narrower than what it holds is one line."""
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=6", "--toolpath",
            "--shank", "D=6,L=20", "--holder", "D=4,L=30", "-o", tmp_path / "a")  # fmt: skip
    assert r.returncode == 1 and "--holder D=4 mm is narrower than the shank it holds (D=6 mm)" in r.stderr
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=6", "--shank", "D=6,L=20",
            "-o", tmp_path / "b")  # fmt: skip
    assert r.returncode == 1 and "--shank applies to a tool path: add --toolpath" in r.stderr
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=6", "--axes", "3", "--toolpath",
            "--stepover", "6", "--shank", "D=6,L=20", "--holder", "D=30,L=40", "-o", tmp_path / "c")  # fmt: skip
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "c" / "report.json").read_text())
    assert rep["tool"]["shank"] == [6.0, 20.0] and rep["tool"]["holder"] == [30.0, 40.0]
    # the check measured the holder: 40 mm of D30 standing 18 + 20 mm above the tip over a face that rises
    # less than that under it
    assert rep["verify"]["clean"] and 0.0 < rep["verify"]["min_clearance_mm"] < 40.0


@needs_pyvista
def test_envelope_command(tmp_path):
    from machsurf_cad.occ import read_step_faces

    out = tmp_path / "env"
    r = run(
        "envelope",
        "--tool",
        "cone:D=10,angle=10",
        "--example",
        "sine",
        "--passes",
        "3",
        "--continuity",
        "g1",
        "--theta",
        "0",
        "--tolerance",
        "0.001",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    assert len(rep["passes"]) == 3 and len(rep["seams"]) == 2
    for p in rep["passes"]:
        assert p["fit"]["max_error_mm"] <= 0.001
    for s in rep["seams"]:
        assert s["exact"]["max_gap_mm"] < 1e-6 and s["exact"]["max_normal_angle_deg"] < 1e-4
        assert f"{s['exact']['max_gap_mm']:.3g}" in r.stdout
    assert 0 < rep["max_theta_deg"] < 90
    assert [f.name for f in read_step_faces(out / "envelopes.step")] == ["pass_1", "pass_2", "pass_3"]
    assert (out / "zebra.png").stat().st_size > 10000 and (out / "envelopes.stl").is_file()


def test_envelope_command_bad_input(tmp_path):
    bad = tmp_path / "path.json"
    bad.write_text('{"points": [[0,0,0],[1,0,0],[1,0,0],[2,0,0],[3,0,0]]}')
    r = run("envelope", "--tool", "cyl:D=10", "--path", bad, "-o", tmp_path / "a")
    assert r.returncode == 1 and "cusp" in r.stderr
    bad.write_text('{"points": [[0,0,0],[1,0,0],[2,1,0],[3,0,0]], "axis": [0, 0, 0]}')
    r = run("envelope", "--tool", "cyl:D=10", "--path", bad, "-o", tmp_path / "b")
    assert r.returncode == 1 and "zero-length axis" in r.stderr
    r = run("envelope", "--tool", "cone:D=10,angle=10", "--theta", "250", "-o", tmp_path / "c")
    assert r.returncode == 1 and "theta" in r.stderr
    r = run("envelope", "--tool", "cone:D=10,angle=10", "--theta", "120", "--passes", "2", "-o", tmp_path / "d")
    assert r.returncode == 1 and ("folds back" in r.stderr or "no real envelope" in r.stderr)
    assert not any((tmp_path / x).exists() for x in "abcd")


def test_lead_auto_reports_its_range_and_the_global_check_still_decides(tmp_path):
    out = tmp_path / "auto"
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=28,r=4",
        "--lead",
        "auto",
        "--tolerance",
        "0.001",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    al = json.loads((out / "report.json").read_text())["auto_lead"]
    assert 0 < al["lead_min_deg"] <= al["local_need_max_deg"] <= al["lead_max_deg"] < 89
    assert f"automatic lead: {al['lead_min_deg']:.3f}" in r.stdout
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--lead", "auto", "-o", tmp_path / "b")
    assert r.returncode == 1 and "a ball end mill needs no lead" in r.stderr
    r = run(
        "machining-surface", "--example", "bezier5", "--tool", "bull:D=28,r=4", "--lead", "soon", "-o", tmp_path / "c"
    )
    assert r.returncode == 1 and "lead must be degrees or auto" in r.stderr


def test_links_over_a_chosen_clearance_cylinder(tmp_path):
    """--clearance-surface cylinder --clearance-axis: the report names the cylinder (radius = the poles'
    farthest distance from the axis + clearance), the path is clean; options that cannot hold are one line."""
    base = ["machining-surface", "--example", "hypar", "--tool", "ball:D=10", "--axes", "5", "--toolpath"]
    out = tmp_path / "cyl"
    r = run(*base, "--stepover", 10, "--clearance-surface", "cylinder", "--clearance-axis", "0,0,1", "-o", out)
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    cs, poles = rep["clearance_surface"], np.asarray(ms.example("hypar").poles).reshape(-1, 3)
    c = 0.5 * (poles.min(axis=0) + poles.max(axis=0))
    assert cs["kind"] == "cylinder" and cs["axis"] == [0.0, 0.0, 1.0]
    assert cs["radius_mm"] == pytest.approx(np.hypot(*(poles[:, :2] - c[:2]).T).max() + 5.0, abs=1e-9)
    assert rep["verify"]["clean"] and rep["toolpath"]["link_length_mm"] > 0
    for extra, msg in (
        (["--clearance-surface", "plane"], "needs a fixed tool axis"),
        (["--clearance-surface", "sphere", "--clearance-axis", "0,0,1"], "axis of a clearance cylinder"),
        (["--clearance-surface", "cylinder", "--clearance-axis", "0,0,0"], "non-zero x,y,z"),
    ):
        r = run(*base, *extra, "-o", tmp_path / "bad")
        assert r.returncode == 1 and msg in r.stderr and r.stderr.count("\n") == 1, r.stderr
        assert not (tmp_path / "bad").exists()


def test_rotary_limit_cuts_out_what_the_machine_cannot_reach(tmp_path):
    """--max-axis-angle 80 on the hypar (its normals lean up to 90 deg from +Z): the positions past 80 deg are
    cut out and said, every written axis is within 80 deg of +Z, the rest is clean; bad limits are one line."""
    base = ["machining-surface", "--example", "hypar", "--tool", "ball:D=10", "--axes", "5"]
    out = tmp_path / "lim"
    r = run(*base, "--toolpath", "--stepover", 10, "--max-axis-angle", 80, "-o", out)
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    tp = ms.read_csv(out / "toolpath.csv")
    planned = rep["toolpath"]["n_positions"]
    assert 0 < rep["verify"]["n_positions_beyond_axis_limit"] < planned and rep["verify"]["verdict"] == "trimmed"
    assert np.degrees(np.arccos(np.clip(tp.axis[:, 2], -1, 1))).max() <= 80.0 + 1e-9
    assert rep["verify"]["trimmed"]["recheck"]["clean"] and 0.1 < rep["machined_area_fraction"] < 0.9
    for extra, msg in ((["--toolpath", "--max-axis-angle", 0], "0..180"), (["--toolpath", "--max-axis-angle", 200],
                       "0..180"), (["--max-axis-angle", 80], "add --toolpath")):  # fmt: skip
        r = run(*base, *extra, "-o", tmp_path / "bad")
        assert r.returncode == 1 and msg in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_several_flank_diameters_need_the_part(tmp_path):
    """Several --tool diameters are given out against a STEP part's faces: without --whole and a part, one line."""
    for extra in ([], ["--whole"]):
        r = run("flank", "--example", "hypar", "--tool", "cyl:D=20", "cyl:D=10", *extra, "-o", tmp_path / "x")
        assert r.returncode == 1 and "add --whole and give a STEP part" in r.stderr and r.stderr.count("\n") == 1
    r = run("flank", "--example", "hypar", "--tool", "cyl:D=20", "--no-render", "-o", tmp_path / "one")
    assert r.returncode == 0, r.stderr  # one diameter through the same option: that tool, R = 10
    rep = json.loads((tmp_path / "one" / "report.json").read_text())
    assert rep["R_mm"] == 10.0 and "by_diameter" not in (rep.get("whole") or {})
