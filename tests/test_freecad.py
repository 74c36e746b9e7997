"""The FreeCAD workbench, headless (FreeCADCmd) and in the GUI under Xvfb, with FreeCAD's own Python.

FreeCADCmd exits 0 even on an uncaught exception, so the scripts write every figure to a JSON file
and these tests read it. The add-on is installed the way a user installs it: linked into the Mod
folder of a throwaway $HOME.
"""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import HAS_OCP, ROOT

FREECADCMD = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
FREECAD = shutil.which("freecad") or shutil.which("FreeCAD")
XVFB = shutil.which("xvfb-run")

IN_CI = os.environ.get("CI", "").lower() == "true"  # CI installs FreeCAD and xvfb: there these tests must run

pytestmark = pytest.mark.skipif(
    FREECADCMD is None and not IN_CI, reason="FreeCAD is not installed (apt-get install freecad)"
)


# numba's kernel for FreeCAD's Python (Debian's python3-numba, when installed): one cache for every test, each of
# which has its own $HOME (the add-on keeps the cache under $HOME), compiled once before the first test
NUMBA_CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "machsurf_cad" / "freecad-numba"


@pytest.fixture(scope="session", autouse=True)
def _kernel_compiled_once(tmp_path_factory):
    """The drop-cutter kernel compiled (or loaded) in FreeCAD's Python before any test times a recompute; the
    two test workers take turns (a lock), the second loads what the first compiled."""
    if FREECADCMD is None:
        return
    import fcntl

    NUMBA_CACHE.mkdir(parents=True, exist_ok=True)
    script = tmp_path_factory.mktemp("numba") / "warm.py"
    script.write_text(
        "import os, sys\n"
        f"sys.path.insert(0, {str(ROOT)!r})\n"
        "from machsurf_cad.threeaxis import compiled\n"
        "compiled.available() and compiled.build_error()\n"
        "os._exit(0)\n"
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=str(NUMBA_CACHE))
    env.pop("PYTHONPATH", None)
    with open(NUMBA_CACHE / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        # (Debian's numba 0.56 takes 13-14 min of one core for the kernel on the development machine at its
        # slowest, measured in the eighteenth session: 776 s for the seventeenth session's code, 846 s for this)
        subprocess.run([FREECADCMD, str(script)], env=env, timeout=2400, stdin=subprocess.DEVNULL,
                       capture_output=True)  # fmt: skip


def _home(tmp_path):
    mod = tmp_path / "home" / ".local" / "share" / "FreeCAD" / "Mod"
    mod.mkdir(parents=True)
    (mod / "machsurf_cad").symlink_to(
        ROOT
    )  # as `make workbench-install` does: the root package.xml points to workbench/
    return tmp_path / "home"


def _run(cmd, tmp_path, script, timeout=600, **extra_env):
    """``script`` run by FreeCAD (``cmd``) with its own $HOME; its result dict (``ok`` asserted). A script that
    has not finished 30 s before ``timeout`` dumps every thread's Python stack (fcscript's watchdog) and exits:
    the failure then says where it stood, and what FreeCAD printed."""
    assert None not in cmd, f"missing program in {cmd} (CI installs freecad and xvfb)"
    out = tmp_path / "result.json"
    hang = tmp_path / "hang_traceback.txt"
    env = dict(
        os.environ,
        HOME=str(_home(tmp_path)),
        MACHSURF_FC_OUT=str(out),
        MACHSURF_ROOT=str(ROOT),
        MACHSURF_FC_WATCHDOG_S=str(max(timeout - 30, 10)),
        QTWEBENGINE_DISABLE_SANDBOX="1",
        NUMBA_CACHE_DIR=str(NUMBA_CACHE),
        **extra_env,
    )
    env.pop("PYTHONPATH", None)  # FreeCAD's Python must not pick up the venv's packages
    try:
        proc = subprocess.run(
            cmd + [str(ROOT / "tests" / "freecad" / script)],
            cwd=tmp_path,
            env=env,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
        printed = (proc.stdout or "")[-2000:] + (proc.stderr or "")[-2000:]
    except subprocess.TimeoutExpired as e:
        printed = f"timed out after {timeout} s; " + str(e.stderr or "")[-2000:]
    if not out.is_file():
        stacks = hang.read_text()[-6000:] if hang.is_file() else "(no watchdog dump)"
        pytest.fail(f"the FreeCAD script wrote no result; its threads' stacks:\n{stacks}\nprinted:\n{printed}")
    res = json.loads(out.read_text())
    assert res["ok"], res.get("error")
    return res


def test_features_recompute_headless(tmp_path):
    r = _run([FREECADCMD], tmp_path, "headless_check.py")
    assert r["no_ocp_in_process"]  # machsurf_cad's numpy core only: no cadquery/OCP in FreeCAD's process
    rc = r["recompute"]
    assert rc["valid"] and rc["status"] == "ok" and rc["n_faces"] == 2
    assert 0 < rc["max_s1"] <= 1e-3 and 0 < rc["max_s2"] <= 1e-3
    cmp = r["compare_direct"]
    assert cmp["max_dev"] < 1e-9  # the feature's faces equal machsurf_cad's direct result
    assert cmp["wires"] == [2, 2]  # trimmed like the nominal face (outer loop + hole)
    assert rc["max_s1"] == pytest.approx(cmp["direct_max_s1"], rel=1e-9)
    ct = r["change_tool"]
    assert ct["valid"] and ct["report_tool"] == "ball:D=10" and ct["max_s1"] != rc["max_s1"]
    of = r["other_features"]
    assert of["reff_valid"] and 2.0 <= of["reff_mean"]
    assert of["env_valid"] and of["env_faces"] == 2 and of["env_gap"] < 1e-3
    q = r["quantities"]  # lengths and angles are quantities: units shown, micrometres kept
    assert (
        q["half_micron"] == 0.0005
        and q["tol_text"] == "500.00 nm"
        and q["mm_text"] == "1.00 µm"
        and q["lead_text"].startswith("10")
    )
    assert q["types"] == ["App::PropertyLength", "App::PropertyAngle", "App::PropertyLength", "App::PropertyAngle"]
    assert q["migrated"] == ["App::PropertyLength", 0.002, "App::PropertyAngle", 7.5]
    ax = r["axes_int"]  # Axes = 3 from a script works; 4 is one line; a 0.3 enumeration comes back as 3
    assert ax["type"] == "App::PropertyIntegerConstraint" and ax["value"] == 3 and ax["status"] == "ok"
    assert ax["four_status"] == "error: Axes must be 3 or 5, got 4"
    assert ax["migrated"] == ["App::PropertyIntegerConstraint", 3] and ax["factory"] == 3
    it = r["invalid_tool"]  # nothing of the previous recompute survives an error
    assert it["shape_null"] and it["max_s1"] == 0.0 and it["report"] == "" and it["poles"] == ""
    assert it["status"].startswith("error: ") and "\n" not in it["status"]
    bad = r["bad_input"]
    assert bad["edge_shape_null"] and bad["edge_status"].startswith("error: ") and "not a face" in bad["edge_status"]
    assert bad["planar_valid"] and bad["planar_faces"] == 2  # a plane is converted to NURBS and machined
    assert bad["tight_shape_null"] and "did not reach" in bad["tight_status"]
    ro = r["reopen"]
    assert ro["valid"] and ro["proxy"] == "MachiningSurfaceFeature" and ro["n_faces"] == 2
    assert ro["max_s1"] == pytest.approx(rc["max_s1"], rel=1e-9)
    # onDocumentRestored migrates a document saved without a property: it comes back with its default
    assert ro["loops"] == "error" and ro["loops_enum"] == ["error", "flag", "trim"]
    assert ro["proxy_module"] == "freecad.machsurf.app.features"
    pr = r["preferences"]  # defaults of new features and tool names from the preferences
    assert pr["tolerance"] == 0.002 and pr["grid"] == 40 and pr["status"] == "ok" and pr["tool"] == "bull:D=16,r=3"
    assert pr["unknown_status"].startswith("error: tool 'bull99' is not in the tool library")
    ds = r["deleted_source"]
    assert ds["shape_null"] and ds["max_s1"] == 0.0 and "deleted" in ds["status"] and ds["n_objects"] >= 5


@pytest.mark.slow
def test_faces_with_holes_convert_exactly(tmp_path):
    """Inner wires (circle, ellipse, closed spline; planar and on a cylinder; the block's bottom) survive
    the round trip FreeCAD -> machsurf_cad -> FreeCAD: same wires, a valid face of the same meshed area,
    points in the holes outside the core's face and points in the material inside; a machining surface
    of the plate keeps the hole."""
    import math

    r = _run([FREECADCMD], tmp_path, "holes_check.py")
    for name in ("round_hole", "three_holes", "pierced_cylinder", "block_bottom"):
        c = r[name]
        assert c["wires"] == c["loops"] == c["back_wires"] >= 2 and c["back_valid"], (name, c)
        assert abs(c["back_area"] - c["area"]) <= 1e-5 * c["area"], (name, c)
        assert not any(c["hole_points_inside"]) and all(c["material_points_inside"]), (name, c)
    assert r["three_holes"]["wires"] == 4 and r["pierced_cylinder"]["wires"] == 3
    # the plate: 100 x 80 less a D20 hole (meshed at 1 um: the polygon in the hole adds < 0.01 mm2)
    assert r["round_hole"]["back_area"] == pytest.approx(8000 - 100 * math.pi, abs=0.01)
    assert r["feature"]["valid"] and r["feature"]["wires"] == [2]
    g = r["gapped_loop"]  # a loop whose sides miss by 3e-5 mm (CATIA's) is closed: a valid 60 x 40 face
    assert g["valid"] and g["closed"] and g["wires"] == 1 and g["area"] == pytest.approx(2400.0, abs=0.01)


@pytest.mark.slow
def test_cam_operation_in_a_path_job(tmp_path):
    """A CamOperation on the block's free-form top: added to a Path Job created for the part, its tool from
    the Job's ToolController (the default 5 mm end mill), clean against every face of the block; one G1
    per non-rapid position, equal to the CSV machsurf writes for the same path within 1e-6 mm; the
    bull-nose ToolBit's FlatRadius mapped to the corner radius; a Job without tools: one line, no path."""
    r = _run([FREECADCMD], tmp_path, "camop_check.py")
    op, c, m = r["op"], r["csv"], r["mapping"]
    assert op["status"] == "ok" and op["in_job"] and op["verdict"].startswith("clean")
    assert op["tool"] == "flat:D=5" and op["tc_diameter"] == 5.0 and 0 <= op["max_gouge"] <= 0.01
    assert op["n_g1"] == c["rows"] > 500 and op["cut_points"] >= c["cut_rows"] > 500 and op["n_g0"] >= 2
    # safe G-code: up to the clearance height (above the stock), across at it, then machsurf's path; back up
    sm = r["safe_moves"]
    assert not sm["status_after_make"].startswith("error"), sm["status_after_make"]
    z_clear = sm["first"][0]["Z"]
    assert z_clear >= sm["stock_top"] + 5.0 - 1e-9 and set(sm["first"][0]) == {"Z"}
    assert sm["first"][1]["Z"] == z_clear and sm["first"][1]["X"] == sm["path_first"]["X"]
    assert sm["first"][1]["B"] == sm["path_first"]["B"] and sm["first"][1]["C"] == sm["path_first"]["C"]
    assert set(sm["last"]) == {"Z"} and sm["last"]["Z"] >= z_clear
    assert c["max_dev"] is not None and c["max_dev"] < 1e-6
    assert m["bull"] == "bull:D=10,r=2,L=20" and m["ball"] == "ball:D=6"
    assert m["chamfer"] == "cone:D=2,angle=45,L=5"  # flat tip 2 FlatRadius, half of 90 deg, up to D 12
    assert "pointed tip is not supported" in m["pointed_vbit"] and "'drill' is not supported" in m["drill"]
    mm = r["mismatch"]  # a Tool text against the controller: refused by both names, nothing written
    assert mm["status"].startswith("error: Tool 'ball:D=6' disagrees with the ToolController") and "flat:D=5" in mm[
        "status"] and mm["n_commands"] == 0  # fmt: skip
    assert mm["agreeing_status"] == "ok"
    ps = r["path_simulator"]  # FreeCAD's simulator runs every move: material removed, the part still inside
    assert ps["applied"] == op["n_g1"] + op["n_g0"]
    assert ps["part_volume"] < ps["left_volume"] < ps["stock_volume"] - 10_000
    nt = r["no_tool"]
    assert nt["status"].startswith("error: no tool") and nt["n_commands"] == 0 and nt["cut_points"] == 0
    # 5 axes: every move is machsurf's (tips exact, axes back from B/C within 1e-12), the path clean
    f5 = r["five_axis"]
    assert f5["status"] == "ok" and f5["verdict"].startswith("clean") and f5["tool"] == "ball:D=6"
    assert f5["n_moves"] == f5["n_direct"] > 400 and f5["cut_points"] == f5["direct_cut"]
    assert f5["tip_dev"] < 1e-9 and f5["axis_dev"] < 1e-12 and 0 < f5["max_b"] < 90
    assert 0 < f5["surface_error"] <= 1e-3
    assert f5["tool_change"] == [["M6", {"T": 1.0}], ["M3", {"S": 10000.0}]] and f5["tool_change_before_moves"]
    apt = r["apt"]  # the APT beside it (machsurf's writer, 5 decimals): same positions and axes
    assert apt["n"] == f5["n_direct"] and apt["tip_dev"] <= 5e-6 and apt["axis_dev"] < 1e-9
    assert apt["feed_line"].startswith("FEDRAT/")
    tr = r["trim"]  # a gouging 5-axis path: refused; cut down and relinked; or tilted away, then cut down
    assert tr["refused"]["status"].startswith("error: the path gouges the part") and tr["refused"]["n_moves"] == 0
    t = tr["trimmed"]
    assert t["status"] == "ok" and t["verdict"].startswith("trimmed, then clean"), t
    assert t["independent_clean"] and t["max_gouge"] <= 0.01 and 0.5 <= t["area"] < 1.0, t
    t = tr["tilted"]  # raising the lead where the face is concave: clean, or nearly so and trimmed
    assert t["status"] == "ok" and t["verdict"].startswith(("clean", "trimmed, then clean")), t
    assert t["independent_clean"] and t["max_gouge"] <= 0.01
    assert t["area"] is None or t["area"] >= tr["trimmed"]["area"]
    bad = r["bad_input"]  # every bad value: one line, an empty path; restored, the operation recovers
    assert len(bad["cases"]) == 7
    for case, b in bad["cases"].items():
        assert b["status"].startswith("error: ") and "\n" not in b["status"], case
        assert b["n_commands"] == 0 and b["cut_points"] == 0, case
    assert bad["recovered"] == "ok" and bad["n_g1"] > 400 and bad["objects_same"]
    fl = r["flank"]  # flank milling: machsurf's path, its gouge (the setting's own) within the tolerance given
    assert fl["status"] == "ok" and fl["verdict"].startswith("clean") and fl["n_moves"] == fl["n_direct"] > 10
    assert fl["tip_dev"] < 1e-9 and fl["direct_rule_gouge"] <= fl["max_gouge"] <= 0.5
    assert r["flank_ball"]["status"].startswith("error: flank milling needs a flat end mill")
    assert r["flank_ball"]["n_commands"] == 0
    sim = r["simulation"]  # the material left, mapped: its largest value is MaxScallop; over the limit: a warning
    assert sim["status"].startswith("warning: the path leaves up to") and sim["n_g1"] == op["n_g1"]
    assert sim["map_max"] == pytest.approx(sim["max_scallop"], abs=1e-12) and 0.05 < sim["max_scallop"] < 2.5
    assert sim["map_min"] >= -0.01 and 30_000 < sim["n_values"] < 50_000 and sim["n_quads"] > 30_000
    assert sim["title"].startswith("material left, machined region [mm]")


@pytest.mark.slow
def test_colour_maps_migrations_cancel(tmp_path):
    r = _run([FREECADCMD], tmp_path, "maps_check.py")
    d = r["deviation_map"]  # the guiding surface's deviation: machsurf_cad's own map, point for point
    assert d["status"] == "ok" and d["n_points"] > 10_000 and d["n_quads"] > 10_000 and d["quads_in_range"]
    assert d["max_point_gap"] == 0.0 and d["max_value_diff"] == 0.0 and d["max_abs"] == d["direct_max_abs"]
    assert 0 < d["max_abs"] <= 1e-3 and d["range"] == [-1e-3, 1e-3] and d["marks"] == [-1e-3, 1e-3]
    assert d["diverging"] and d["title"] == "guiding surface deviation [mm]"
    e = r["reff_map"]  # R_eff over the face: the feature's min/max, reff_maps' min/max, the map's range
    assert e["status"] == "ok" and e["min"] == e["direct_min"] == e["prop_min"] == e["range"][0]
    assert e["max"] == e["direct_max"] == e["prop_max"] == e["range"][1]
    assert e["min"] == pytest.approx(2.0, abs=1e-6)  # the corner radius r: the torus's smallest R_eff
    so = r["stepover_map"]
    assert so["min"] == so["direct_min"] and so["max"] == so["direct_max"] and 0 < so["min"] < so["max"]
    assert "0.01 mm scallop" in so["title"]
    ws = r["stepover_without_scallop"]
    assert ws["status"].startswith("error: the step-over map needs a scallop height") and ws["n_values"] == 0
    assert e["memory_64"] == "about 3 MB" and r["memory_1024"] == "about 682 MB"
    em = r["envelope_map"]  # each pass's fit against its exact envelope, on points off the fit's samples
    assert em["status"] == "ok" and em["n"] == 2 * 64 * 64 and 0 < em["max_abs"] <= 1e-3
    assert em["marks"] == [-1e-3, 1e-3] and em["title"] == "envelope fit deviation [mm]"
    fm = r["flank_map"]  # the band the interference is measured on: its lowest value is the setting's gouge
    assert fm["status"] == "ok" and fm["n"] > 3000 and fm["undercut"] == 0.0
    assert fm["min"] == pytest.approx(-fm["gouge"], rel=5e-3) and fm["min"] >= -fm["gouge"] - 1e-9
    assert fm["gouge"] == pytest.approx(0.11852, abs=5e-5)  # the paper's optimum on the hyperbolic paraboloid
    c = r["colours"]
    assert c["div_mid"] == [0.87, 0.87, 0.87] and c["div_low"][2] > c["div_low"][0] and c["div_high"][0] > 0.7
    assert c["clipped"] == c["seq_high"] and c["norm_div"] == [0.0, 0.5, 0.75] and c["norm_seq"] == [0, 0.5, 1]
    mg = r["migration"]  # paper vocabulary of 0.2 documents renamed, values kept
    assert mg["rule"] == 0.25 and mg["side"] == "opposite side" and mg["pass_turn"] == 4.0 and not mg["old_gone"]
    assert mg["guiding_error_prop"] and mg["map_props"]
    k = r["cancel"]  # Esc on the progress bar: the recompute stops, nothing of the previous one survives
    assert k["before"]["valid"] and k["before"]["n_values"] > 0 and k["before"]["error"] > 0
    assert k["status"] == "error: cancelled by the user" and k["shape_null"] and k["error"] == 0.0
    assert k["n_values"] == 0 and k["calls"] == 2 and k["proxy_same"]


def test_an_addon_manager_clone_loads_and_recomputes(tmp_path):
    """The repository cloned into the Mod folder (as the Addon Manager does, no link to workbench/): the
    root package.xml points FreeCAD to the workbench, which finds the core beside it; a feature recomputes."""
    files = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert "package.xml" in files and "LICENSE" in files
    home = tmp_path / "home"
    clone = home / ".local" / "share" / "FreeCAD" / "Mod" / "machsurf_cad"
    for f in files:
        if (ROOT / f).is_file():
            (clone / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, clone / f)
    out = tmp_path / "result.json"
    env = dict(os.environ, HOME=str(home), MACHSURF_FC_OUT=str(out), MACHSURF_ROOT=str(ROOT))
    env.pop("PYTHONPATH", None)
    assert FREECADCMD is not None, "CI installs freecad"
    subprocess.run([FREECADCMD, str(ROOT / "tests" / "freecad" / "addon_check.py")], cwd=tmp_path, env=env,
                   timeout=600, stdin=subprocess.DEVNULL, capture_output=True)  # fmt: skip
    r = json.loads(out.read_text())
    assert r["ok"], r.get("error")
    assert r["features_file"].startswith(str(clone)) and r["core_file"].startswith(str(clone))
    assert r["status"] == "ok" and r["faces"] == 2 and 0 < r["max_s1"] <= 1e-3


@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_gui_command_on_a_selected_face(tmp_path):
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "gui_check.py")
    assert r["workbench"] == "MachsurfWorkbench"
    assert r["valid"] and r["faces"] == 2 and 0 < r["max_s1"] <= 1e-3
    # colours follow the measured error over the tolerance: red share = error / tolerance (blue = within)
    assert r["colours"][0][0] == pytest.approx(r["max_s1"] / 1e-3, abs=1e-6)
    assert all(0 <= c[0] <= 1 and abs(c[0] + c[2] - 1) < 1e-6 for c in r["colours"])
    assert r["step_bytes"] > 10000 and r["step_names"] == ["S1_guiding", "S2_orientation"]
    assert r["panel"]["untouched"] == 0.001 and r["panel"]["typed"] == 0.0005 and r["panel"]["status"] == "ok"
    assert r["reopened_view"] == {"before": "NoneType", "after": "ViewProvider"}
    assert r["preferences_ui"] == ["defaultGrid", "defaultTolerance", "toolLibrary"]
    assert r["preferences"]["icon_saturated"] > 20  # the page's icon is the workbench's, not FreeCAD's black cross
    cmds = r["commands"]  # one icon per command, and tooltips that explain rather than repeat the menu text
    assert len(cmds) == 6 and len({c["pixmap"] for c in cmds.values()}) == 6
    assert all(os.path.isfile(c["pixmap"]) and len(c["tip"]) > len(c["menu"]) + 40 for c in cmds.values())
    import numpy as np
    from PIL import Image

    img = np.asarray(Image.open(r["png"]).convert("RGB"))
    assert img.shape[:2] == (900, 1200) and len(np.unique(img.reshape(-1, 3), axis=0)) > 100


@pytest.mark.slow
@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_a_cam_programmers_steps_with_clicks_and_keys(tmp_path):
    """The face picked, the CAM operation's toolbar button clicked (a Job and its tool made, the raster computed
    and checked clean), the task panel opened from the tree, a step-over typed and OK clicked: recomputed with
    fewer positions, clean. Each step captured as the screen shows it (docs/freecad_step_*.png)."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "steps_check.py")
    assert r["selected"] == [["Face1"]] and r["ops_made"] == 1
    first, second = r["first"], r["second"]
    assert first["status"] == "ok" and first["verdict"].startswith("clean") and first["in_job"]
    assert first["tool"] == "flat:D=5" and first["stepover"] == 2.0 and 0 < first["max_gouge"] <= 0.01
    assert r["panel_open"]
    assert second["status"] == "ok" and second["verdict"].startswith("clean") and second["stepover"] == 3.0
    assert 0 < second["cut_points"] < first["cut_points"]
    import numpy as np
    from PIL import Image

    assert len(r["shots"]) == 4
    for png in r["shots"]:  # the whole window: tree, property view and the 3D view's shading
        img = np.asarray(Image.open(png).convert("RGB"))
        assert img.shape[0] > 1000 and img.shape[1] > 1400 and len(np.unique(img.reshape(-1, 3), axis=0)) > 500


@pytest.mark.skipif(not HAS_OCP, reason="cadquery-ocp is needed to write the STEP files")
def test_freecad_imports_every_multi_face_step_we_write(tmp_path):
    """FreeCAD 0.20 crashed (SIGSEGV) on our multi-face STEP files (OCCT's assembly structure): each file
    the project writes must import, with every face, under the product name we give it."""
    import machsurf_cad as ms
    from machsurf_cad.occ import write_step

    res = ms.machining_surface(ms.example("bezier5"), "bull:D=28,r=4", lead=20, tolerance=1e-3)
    env = ms.envelope("cone:D=10,angle=10", ms.example("sine", "motion"), passes=3)
    fl = ms.flank(ms.example("liu", "ruled"), "cyl:D=20", whole=True, tolerance=0.5)
    files = {
        "machining_surface.step": [f for f in res.faces()],
        "envelopes.step": [ms.Face(f.surface, name=e.name) for e, f in zip(env.chain.passes, env.chain.fits)],
        "envelope.step": [ms.Face(fl.envelope.surface, name="flank_envelope")],
    }
    paths = [write_step(tmp_path / name, faces, author="QA") for name, faces in files.items()]
    r = _run([FREECADCMD], tmp_path, "import_check.py", MACHSURF_STEP_FILES=os.pathsep.join(map(str, paths)))
    for name, faces in files.items():
        got = r["files"][name]
        assert got["faces"] == len(faces), (name, got)
        assert name[: -len(".step")] in got["labels"], got["labels"]  # the product carries our name
        assert not any("Open CASCADE" in lab for lab in got["labels"])


@pytest.mark.slow
@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_colour_maps_with_legends_in_the_3d_view(tmp_path):
    """Screenshots of every feature's map (looked at: tmp_path/map_*.png): the guiding surface's deviation, R_eff,
    the material a path leaves, the envelope fit's deviation, the distance from a ruled face to the flank tool.
    The numbers behind them are test_colour_maps_migrations_cancel's; here: the map is what the view shows
    (default mode "Map"; beside the path and the placed cylinder), the legend's unlit bar has the scale's end
    colours, the map fills part of the view, and after an error the view holds nothing."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "gui_maps_check.py")
    for name, s in r["shots"].items():
        assert s["status"] == "ok" and s["n_values"] > 1000, name
        assert s["mode"] == ("beside" if name in ("scallop", "flank") else "Map"), name
        assert max(s["legend_end_colour_error"]) < 0.02, name  # the legend's ends: the scale's colours
        assert 0.05 < s["map_pixel_fraction"] < 0.6, name  # the coloured map fills part of the view
    assert r["shots"]["deviation"]["title"] == "guiding surface deviation [mm]"
    import re

    for name, s in r["shots"].items():  # one number format per legend (no 0.001 beside 5.00e-04)
        numbers = [x for t in s["legend_texts"] for x in re.findall(r"-?\d+\.?\d*(?:e-?\d+)?", t)
                   if t != s["title"]]  # fmt: skip
        assert numbers and not any("e" in x for x in numbers), (name, s["legend_texts"])
        assert len({len(x.split(".")[1]) if "." in x else 0 for x in numbers}) == 1, (name, s["legend_texts"])
        assert s["range_mark_editor_modes"] == [["Hidden"], ["Hidden"]], name  # the editor showed [-0.00, 0.00]
    assert r["shots"]["reff"]["title"] == "effective cutter radius [mm]"
    ae = r["after_error"]
    assert ae["status"].startswith("error: tool 'nonsense'") and ae["n_values"] == 0 and ae["children"] == 0


@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
@pytest.mark.slow  # the panel test types into the add-on's own fields in the fast tier
def test_tolerances_typed_in_the_property_editor_keep_every_digit(tmp_path):
    """Issue 29 item 1: keys typed into FreeCAD's own property editor (its QuantitySpinBox rounds a length to
    2 decimals in mm when it stores it): 0.5 um and 0.0005 mm come back as 0.0005 mm on a machining surface
    and on a CAM operation; 1e-7 mm (shown as 0.00 mm) and a non-length are refused, the value before kept."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "property_edit_check.py")
    t = r["typed"]
    assert all(t[k]["editor"] == "Gui::QuantitySpinBox" for k in t)  # FreeCAD's own editor, not ours
    assert t["0.5 um"]["stored_mm"] == 0.0005 and t["0.5 um"]["shown"] == "500.00 nm"
    assert t["0.0005 mm"]["stored_mm"] == 0.0005 and t["2.5 um"]["stored_mm"] == 0.0025
    assert t["0.0000001 mm"]["stored_mm"] == 0.001 and t["3 deg"]["stored_mm"] == 0.001  # refused, kept
    assert r["status_after"] == "ok"
    c = r["camop"]
    assert c["ChordalTolerance"][1] == 0.0005 and c["SurfaceTolerance"][1] == 0.0005
    assert c["StepOver"][1] == 2.345 and c["Lead"][1] == 12.5


@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_cam_operation_task_panel_edited_with_keys_and_mouse(tmp_path):
    """Issue 29 item 8: the CAM operation's task panel (opened as a double-click does) holds its fields grouped
    as the property editor groups them, only the groups its pattern uses; the pattern chosen with the arrow
    keys, 0.5 um and 40 deg typed, a check box clicked and OK clicked store exactly those values and nothing
    else (the picture: tmp_path/freecad_cam_panel.png, looked at)."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "panel_check.py")
    assert r["raster_groups"] == ["Accuracy", "Cutter", "Linking", "Simulation", "Strategy"]
    assert not r["raster_stepdown_visible"]
    assert r["five_groups"] == ["5-axis", "Accuracy", "Cutter", "Linking", "Simulation", "Strategy"]
    assert r["stored"] == {"Pattern": "5-axis surface", "ChordalTolerance": 0.0005, "MaxLead": 40.0,
                           "TrimGouges": True, "GougeTolerance": 0.01, "StepOver": 2.0}  # fmt: skip
    assert r["panel_closed"]


@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_recomputes_keep_the_gui_live_and_esc_cancels_them(tmp_path):
    """Issue 29 item 5: a CAM raster (numpy drop-cutter in FreeCAD's Python, a minute or more to its end)
    runs off the GUI thread: a 100 ms Qt timer beside it fires with gaps under 0.5 s, FreeCAD's progress bar
    moves, Esc (a key event to the main window) ends the recompute within a second with one line and no path;
    a machining surface recomputed to its end keeps the timer firing (the gap includes writing its result)."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "responsive_check.py")
    c = r["cancelled"]
    assert c["status"] == "error: cancelled by the user" and c["n_commands"] == 0
    assert c["esc_to_end_s"] < 1.0 and c["seconds"] < 6.0  # stopped within a second (0.3 s here), not run out
    assert c["max_gap_s"] < 0.5 and c["ticks"] >= 15  # events handled while it ran
    assert any(v > 0 for v in c["bar_values"])  # FreeCAD's progress bar moved
    f = r["finished"]
    assert f["status"] == "ok" and f["faces"] == 2 and 0 < f["error"] <= 1e-5
    assert f["max_gap_s"] < 1.0


@pytest.mark.slow
def test_two_operations_posted_by_freecads_posts_are_clean(tmp_path):
    """Issue 29 item 7: a Job with two machsurf operations posted through FreeCAD's linuxcnc and grbl
    post-processors; every G0/G1 of the G-code read back (modal coordinates) and checked by the tool-body
    check against every face of the block: no gouge, no collision, the first and last moves above the part,
    no rapid across x or y below the part's top, one tool change (the Job's ToolController)."""
    r = _run([FREECADCMD], tmp_path, "post_check.py")
    assert all(o["status"] == "ok" and o["verdict"].startswith("clean") for o in r["ops"])
    for name in ("linuxcnc", "grbl"):
        p = r["posted"][name]
        assert p["moves"] > 1000 and p["rapids"] >= 4, name
        assert p["clean"] and p["collisions"] == 0 and p["gouging_positions"] == 0 and p["max_gouge"] <= 0.01, name
        assert p["first_move_z_above_part"] and p["last_move_z_above_part"] and p["low_xy_rapids"] == 0, name
        assert p["m6"] == 1, name


@pytest.mark.skipif((FREECAD is None or XVFB is None) and not IN_CI, reason="FreeCAD GUI or xvfb-run is not installed")
def test_five_axis_paths_are_previewed_right(tmp_path):
    """Issue 29 item 6: FreeCAD 0.20 draws B/C words as rotations (swirls beside the part). A 5-axis operation
    draws its tips as one polyline and its axes as lines (coloured by the body check's distance) and cuts
    FreeCAD's own drawing down to the last command; a 3-axis operation keeps FreeCAD's drawing, no preview
    (the picture: tmp_path/freecad_5axis_preview.png, looked at: white cutting lines on the face, red
    links and axes above it)."""
    r = _run([XVFB, "-a", "-s", "-screen 0 1600x1200x24", FREECAD], tmp_path, "preview_check.py")
    f = r["five"]
    assert f["status"] == "ok" and f["n_tips"] == f["n_moves"] > f["n_g1"] > 400
    assert f["tips_vs_moves_mm"] < 1e-9  # the preview's tips are the path's own moves, one by one
    assert f["n_line_sets"] == 2 and f["polyline_vertices"] == f["n_tips"] and 300 <= f["axis_lines"] <= 400
    assert -f["gouge_tolerance"] <= f["min_distance"] <= 0.0 < f["max_distance"]  # touching cuts, clear links
    start, count, n = f["freecad_shows"]
    assert count == 1 and start == n - 1
    t = r["three"]
    assert t["status"] == "ok" and t["n_tips"] == 0 and t["freecad_shows"] == [0, 0]
    assert r["red_pixels"] > 100  # the links and axes drawn (red: clear by a millimetre and more)


@pytest.mark.slow
def test_cam_operation_defaults_are_clean_with_freecads_stock_tools(tmp_path):
    """Issue 29 item 2: the raster at the operation's default settings (chordal tolerance 0.005 mm, below the
    gouge tolerance 0.01 mm) is clean on the block with FreeCAD's stock 5 mm end mill, 6 mm ball end and
    6 mm bull nose (whose FlatRadius 1.5 mm is a corner radius of 1.5 mm); the stock chamfer and V-bit map
    to machsurf's cone (tip diameter, half the included angle)."""
    r = _run([FREECADCMD], tmp_path, "stock_tools_check.py")
    assert r["defaults"] == {"chordal": 0.005, "gouge": 0.01}
    tools = {"5mm_Endmill": "flat:D=5", "6mm_Ball_End": "ball:D=6", "6mm_Bullnose": "bull:D=6,r=1.5"}
    for name, spec in tools.items():
        s = r["stock"][name]
        assert s["status"] == "ok" and s["verdict"].startswith("clean") and s["tool"].startswith(spec), (name, s)
        assert 0 < s["max_gouge"] <= 0.01 and s["cut_points"] > 1000, name
    assert r["45degree_chamfer"].startswith("cone:D=5,angle=22.5,L=")
    assert r["60degree_Vbit"].startswith("cone:D=1,angle=30,L=")
