"""Hostile and conflicting inputs: a one-line refusal (exit 1, no traceback, nothing written), never a
traceback, a half-written folder, unbounded work or a silently wrong result."""

import json
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest
from conftest import ROOT, needs_kernel
from helpers import assert_points_close, run, run_process

BLOCK = ROOT / "example_parts" / "freeform_block.step"


def _refused(r, *words):
    assert r.returncode == 1, (r.returncode, r.stdout[-500:], r.stderr[-500:])
    lines = [ln for ln in r.stderr.splitlines() if ln.strip() and not ln.startswith("usage:")]
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])


def _no_partial(folder):
    assert not list(folder.parent.glob(f".{folder.name}.partial-*")), "a half-written staging folder was left"


@needs_kernel
def test_output_folder_that_is_a_file_or_unwritable(tmp_path):
    f = tmp_path / "afile"
    f.write_text("mine")
    _refused(run("info", BLOCK, "-o", f), "is an existing file")
    assert f.read_text() == "mine"
    _refused(run("info", BLOCK, "-o", "/proc/machsurf/x"), "cannot write output folder")
    other = tmp_path / "notours"
    other.mkdir()
    (other / "keep.txt").write_text("x")
    _refused(run("info", BLOCK, "-o", other), "holds files machsurf did not write (keep.txt)")
    assert (other / "keep.txt").is_file()


def test_reused_output_folder_holds_exactly_one_run(tmp_path):
    out = tmp_path / "ms"
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "ball:D=10",
        "--axes",
        "3",
        "--tolerance",
        "0.01",
        "--toolpath",
        "--stepover",
        "20",
        "--allow-gouge",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    assert (out / "toolpath.apt").is_file()
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=16,r=3",
        "--lead",
        "10",
        "--tolerance",
        "0.01",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr
    assert not (out / "toolpath.apt").exists()  # the earlier run's path is gone with its folder
    rep = json.loads((out / "report.json").read_text())
    assert sorted(p.name for p in out.iterdir()) == sorted(rep["files"] + [".machsurf-manifest.json"])
    _no_partial(out)


def test_conflicting_and_malformed_arguments(tmp_path):
    o = tmp_path / "o"
    _refused(run("machining-surface", BLOCK, "--example", "bezier5", "--tool", "ball:D=10", "-o", o), "not both")
    _refused(run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10,D=12", "-o", o), "given twice")
    _refused(
        run(
            "machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--axes", "3", "--axis", "1,2", "-o", o
        ),
        "x,y,z",
    )
    _refused(
        run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--axes", "3", "--lead", "10", "-o", o),
        "lead and tilt apply to 5 axes",
    )
    _refused(
        run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--tilt", "1e6", "-o", o), "tilt angle"
    )
    _refused(
        run("reff", "--example", "blade", "--tool", "bull:D=10,r=2", "--axes", "5", "--lead", "90", "-o", o),
        "|lead| must be <= 89",
    )
    _refused(run("envelope", "--tool", "cyl:D=10", "--passes", "2", "--theta", "0,15,30", "-o", o), "one per new pass")
    assert not o.exists()


def test_work_size_is_bounded_before_the_work(tmp_path):
    o = tmp_path / "o"
    _refused(
        run(
            "machining-surface",
            "--example",
            "bezier5",
            "--tool",
            "ball:D=10",
            "--axes",
            "3",
            "--tolerance",
            "0.01",
            "--toolpath",
            "--stepover",
            "1e-4",
            "-o",
            o,
        ),
        "passes over this face",
        "--stepover >=",
    )
    _refused(
        run("reff", "--example", "blade", "--tool", "bull:D=10,r=2", "--grid", "4096", "--direction", "all", "-o", o),
        "GiB, over the",
    )
    assert not o.exists()


@needs_kernel
def test_inspect_sample_counts(tmp_path):
    o = tmp_path / "o"
    _refused(run("inspect", BLOCK, BLOCK, "--samples", "1", "-o", o), "samples must be >= 2")
    _refused(run("inspect", BLOCK, BLOCK, "--samples", "100000", "-o", o), "GiB, over the", "at most")
    _refused(run("inspect", BLOCK, BLOCK, "--samples", "2", "-o", o), "none of its 2 x 2 samples lies inside")
    r = run("inspect", BLOCK, BLOCK, "--samples", "3", "--no-render", "-o", o)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize(
    "body,words",
    [
        ('{"points": [[0,0,0],[1,0,0],[2,1,NaN],[3,0,0]]}', "finite"),
        ('{"points": [[0,0,0],[1,0,0],[2,1,Infinity],[3,0,0]]}', "finite"),
        ('{"points": [[0,0,0],[1,0],[2,1,0],[3,0,0]]}', "rows of equal length"),
        ('{"points": [[0,0,0],["a",0,0],[2,1,0],[3,0,0]]}', "numbers"),
        ('{"points": [[0,0,0],[1,0,0],[2,1,0],[3,0,0]], "axis": [0, 1]}', "3 components"),
    ],
)
def test_envelope_path_files(tmp_path, body, words):
    f = tmp_path / "path.json"
    f.write_text(body)
    _refused(run("envelope", "--tool", "cyl:D=10", "--path", f, "-o", tmp_path / "o"), words)


def test_user_path_gets_exact_derivatives_and_measured_g1(tmp_path):
    import numpy as np

    t = np.linspace(0, 1, 12)
    f = tmp_path / "sine.json"
    f.write_text(json.dumps({"points": np.stack([100 * t, 20 * np.sin(np.pi * t), 0 * t], 1).tolist()}))
    out = tmp_path / "env"
    r = run(
        "envelope",
        "--tool",
        "cone:D=10,angle=10",
        "--path",
        f,
        "--passes",
        "2",
        "--no-render",
        "--no-theta-scan",
        "-o",
        out,
    )
    assert r.returncode == 0, r.stderr  # it exited 1 before ("S_a and S_t are parallel ... t = -0.0002")
    chk = json.loads((out / "report.json").read_text())["seams_measured_on_written_faces"]
    assert chk["achieved"] == "G1" and chk["max_normal_angle_deg"] <= 0.05
    # an impossible G1 limit: exit 2, said, and the files are still written
    r = run(
        "envelope",
        "--tool",
        "cone:D=10,angle=10",
        "--path",
        f,
        "--passes",
        "2",
        "--no-render",
        "--no-theta-scan",
        "--seam-angle-tolerance",
        "1e-9",
        "-o",
        tmp_path / "env2",
    )
    assert r.returncode == 2 and "G1 NOT met" in r.stdout and (tmp_path / "env2" / "envelopes.step").is_file()


@needs_kernel
def test_reff_on_a_horizontal_plane_says_na(tmp_path):
    r = run(
        "reff",
        BLOCK,
        "--face",
        "2",
        "--tool",
        "bull:D=10,r=2",
        "--scallop",
        "0.01",
        "--grid",
        "16",
        "--no-render",
        "-o",
        tmp_path / "o",
    )
    assert r.returncode == 0, r.stderr
    # the block's face 2 is its bottom: it faces away from +Z, so a 3-axis tool reaches none of it (it used to
    # print "infinite R_eff" figures for it)
    assert "R_eff min n/a" in r.stdout and "unreachable 100.0% of the area" in r.stdout


@needs_kernel
def test_broken_pipe_and_sigterm(tmp_path):
    env_cmd = [sys.executable, "-m", "machsurf_cad", "info", str(BLOCK), "-o", str(tmp_path / "i")]
    p1 = subprocess.Popen(env_cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    p1.stdout.readline()
    p1.stdout.close()  # like `| head -1`
    err = p1.stderr.read().decode()
    assert p1.wait(60) == 0 and "Traceback" not in err
    assert (tmp_path / "i" / "report.json").is_file()  # the job finished and wrote its report
    cmd = [
        sys.executable,
        "-m",
        "machsurf_cad",
        "envelope",
        "--tool",
        "cone:D=10,angle=10",
        "--example",
        "helix",
        "--passes",
        "3",
        "--continuity",
        "g0",
        "-o",
        str(tmp_path / "big"),
    ]  # about 10 s, little memory
    p2 = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    time.sleep(3.0)
    p2.send_signal(signal.SIGTERM)
    rc = p2.wait(60)
    assert rc == 143 and b"terminated" in p2.stderr.read()
    assert not (tmp_path / "big").exists()
    _no_partial(tmp_path / "big")
    p3 = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    time.sleep(3.0)
    t = time.perf_counter()
    p3.send_signal(signal.SIGINT)  # Ctrl-C: acts within a second, exit 130, nothing written
    assert p3.wait(60) == 130 and time.perf_counter() - t < 2.0
    assert b"interrupted" in p3.stderr.read() and not (tmp_path / "big").exists()
    _no_partial(tmp_path / "big")


def test_api_refusals():
    import numpy as np

    import machsurf_cad as ms

    s = ms.example("bezier5")
    with pytest.raises(ms.InputError, match="outside the surface's domain"):
        ms.local_properties(s, 1.5, 0.5)
    with pytest.raises(ms.InputError, match="tolerance must be > 0"):
        ms.deviation(s, s, samples=5, tolerance=-1)
    with pytest.raises(ms.InputError, match="tolerance must be finite"):
        ms.deviation(s, s, samples=5, tolerance=float("nan"))
    assert np.isfinite(ms.local_properties(s, 1.0, 0.0).normal).all()  # the closed domain is fine


def test_subprocess_exit_codes_stay_honest(tmp_path):
    r = run_process("machining-surface", "--example", "bezier5", "--tool", "ball:D=10,D=12", "-o", tmp_path / "o")
    _refused(r, "given twice")


# ----------------------------------------------------------------------------- issue 25: trust
def _strict(text: str):
    """JSON as RFC 8259 has it: NaN and Infinity refused."""

    def no(c):
        raise ValueError(f"not strict JSON: {c}")

    return json.loads(text, parse_constant=no)


def _plane_path(tmp_path, **kw):
    """A small clean 3-axis path on the bezier5 example (and the face)."""
    import machsurf_cad as ms

    face = ms.example("bezier5")
    res = ms.machining_surface(face, "ball:D=10", axes=3, tolerance=1e-2)
    return face, ms.tool_paths(res, stepover=20.0, **kw)


@needs_kernel
def test_a_users_file_beside_an_old_report_is_never_deleted(tmp_path):
    out = tmp_path / "F"
    assert run("info", BLOCK, "-o", out).returncode == 0
    (out / "thesis.txt").write_text("three years of work")
    r = run("info", BLOCK, "-o", out)
    _refused(r, "holds files machsurf did not write (thesis.txt)")
    assert r.stdout == ""  # refused before any work
    assert (out / "thesis.txt").read_text() == "three years of work" and (out / "report.json").is_file()
    (out / "thesis.txt").unlink()
    (out / "report.json").write_text((out / "report.json").read_text() + " ")  # edited by the user: theirs now
    _refused(run("info", BLOCK, "-o", out), "(report.json)")
    _no_partial(out)


@needs_kernel
def test_output_folder_dot_symlink_and_a_failed_write(tmp_path):
    work = tmp_path / "w"
    work.mkdir()
    (work / "keep.txt").write_text("x")
    r = run_process("info", BLOCK, "-o", ".", cwd=work)
    _refused(r, "is the current folder")
    assert sorted(p.name for p in work.iterdir()) == ["keep.txt"]
    real = tmp_path / "real"
    assert run("info", BLOCK, "-o", real).returncode == 0
    link = tmp_path / "link"
    link.symlink_to(real)
    assert run("info", BLOCK, "-o", link).returncode == 0
    assert link.is_symlink() and (real / "report.json").is_file()  # the folder replaced, the link kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "real", "w"]  # no .old-* or .partial-* left
    # a write that fails (a file-size limit: the same error path as a full disk) is one line, nothing written
    import resource

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))

    r = subprocess.run([sys.executable, "-m", "machsurf_cad", "info", str(BLOCK), "-o", str(tmp_path / "big")],
                       capture_output=True, text=True, preexec_fn=limit, stdin=subprocess.DEVNULL, timeout=300,
                       env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
    _refused(r, "cannot write output folder", "File too large")
    assert not (tmp_path / "big").exists()
    _no_partial(tmp_path / "big")


def test_foreign_cldata_is_read_as_a_cam_system_reads_it(tmp_path):
    import machsurf_cad as ms

    nx = tmp_path / "nx.cls"  # NX: 6-value GOTOs without MULTAX, TLDATA, PAINT, END-OF-PATH
    nx.write_text("TOOL PATH/FIXED_CONTOUR,TOOL,BALL10\nTLDATA/MILL,10.0000,5.0000,75.0000,0.0000,0.0000\n"
                  "MSYS/0.0,0.0,0.0,1.0,0.0,0.0,0.0,1.0,0.0\nPAINT/PATH\nFEDRAT/MMPM,250.0\n"
                  "GOTO/10.0,0.0,5.0,0.0,0.6,0.8\nGOTO/20.0,0.0,5.0,0.0,0.6,0.8\nEND-OF-PATH\n")  # fmt: skip
    tp = ms.read_apt(nx)
    assert_points_close(tp.axis, [[0, 0.6, 0.8]] * 2, atol=1e-15)  # not +Z
    assert tp.cutter == ms.BallEndMill(10, 75.0) and tp.feed[1] == 250.0
    catia = tmp_path / "catia.aptsource"  # CATIA: spaces, TLAXIS for 3-value GOTOs, a non-identity MSYS
    catia.write_text("$$ CATIA\nPARTNO/PART1\nMULTAX\nUNITS/MM\nINTOL/0.01\n"
                     "CUTTER/  10.000000,   5.000000,   0.000000,   5.000000,   0.000000,   0.000000,  50.000000\n"
                     "TLAXIS/ 0.000000, 1.000000, 0.000000\nRAPID\nGOTO  /   1.00000,   2.00000,   3.00000\n"
                     "GOTO  /   4.00000,   2.00000,   3.00000\nMSYS/10,0,0,0,1,0,-1,0,0\n"
                     "GOTO/1,0,0\nFINI\n")  # fmt: skip
    tp = ms.read_apt(catia)
    assert_points_close(tp.axis[:2], [[0, 1.0, 0]] * 2, atol=0)  # TLAXIS/0,1,0 honoured, not +Z
    assert_points_close(tp.tip[2], [10.0, 1.0, 0.0], atol=1e-12)  # MSYS: origin + x axis (0, 1, 0)
    assert_points_close(tp.axis[2], [-1.0, 0, 0], atol=1e-12)  # the axis turned with the frame
    fusion = tmp_path / "fusion.apt"  # Fusion-style: PPRINT, word-first FEDRAT, MULTAX/ON, an unknown statement
    fusion.write_text(
        "PARTNO 'P'\nUNITS/MM\nMULTAX/ON\nCUTTER/6,0,3,0,0,0,20\nPPRINT/'OP1'\nSPINDL/RPM,5000,CLW\n"
        "RAPID\nGOTO/0,0,10,0,0,1\nFEDRAT/MMPM,800\nGOTO/0,0,0,0,0,1\nGOTO/5,0,0,0,0,1\nWOBBLE/3\nFINI\n"
    )
    with pytest.warns(UserWarning, match="WOBBLE x1"):
        tp = ms.read_apt(fusion)
    assert tp.cutter == ms.FlatEndMill(6, 20.0) and tp.info["skipped_statements"] == {"WOBBLE": 1}
    for bad, words in (("CUTTER/1e6,3,5,3,0,0,30", "d = 2(e + r) = 16"), ("CUTTER/10,0,50,0,0,0,50", "inconsistent"),
                       ("TRACUT/1,0,0,5,0,1,0,0,0,0,1,0", "TRACUT changes the tool path's geometry"),
                       ("GOTO/1,2", "3 or 6 values"), ("UNITS/FURLONG", "unknown units")):  # fmt: skip
        f = tmp_path / "bad.apt"
        f.write_text(f"UNITS/MM\n{bad}\nGOTO/0,0,0\nFINI\n")
        with pytest.raises(ms.InputError, match=re.escape(words)):
            ms.read_apt(f)
    with pytest.raises(ms.InputError, match="is not a text file"):
        (tmp_path / "g.apt").write_bytes(bytes(range(256)) * 4)
        ms.read_apt(tmp_path / "g.apt")


def test_spreadsheet_csv_and_our_csv_carrying_its_tool(tmp_path):
    import machsurf_cad as ms

    face, tp = _plane_path(tmp_path)
    ours = ms.write_csv(tmp_path / "ours.csv", tp)
    back = ms.read_csv(ours)
    assert back.cutter == ms.BallEndMill(10) and back.info["assumed"] == []
    assert_points_close(back.tip, tp.tip, atol=1e-6)  # 6 decimals per coordinate
    # a spreadsheet's: BOM, CRLF, ';' with decimal commas, other column order, no move or pass
    (tmp_path / "s.csv").write_bytes(
        "\ufeffK;J;I;Z;Y;X;tool\r\n1;0;0;3,5;2;1,25;bull:D=16,r=3\r\n1;0;0;3,5;2;2,25;bull:D=16,r=3\r\n".encode()
    )
    s = ms.read_csv(tmp_path / "s.csv")
    assert_points_close(s.tip, [[1.25, 2, 3.5], [2.25, 2, 3.5]], atol=0)
    assert s.cutter == ms.BullNoseEndMill(16, 3)  # the tool cell keeps its comma
    assert s.n_passes == 1 and "every move a cut (no move column)" in s.info["assumed"]
    (tmp_path / "u.csv").write_text("tip_z,tip_y,tip_x\n3,2,1\n", encoding="utf-16")
    u = ms.read_csv(tmp_path / "u.csv")
    assert_points_close(u.tip, [[1, 2, 3]], atol=0) and "axis +Z (no i,j,k columns)" in u.info["assumed"]
    for text, words in (("a,b\n1,2\n", "no tip columns"), ("x,y,z,i,j\n1,2,3,0,0\n", "only i, j"),
                        ("x,y,z\n1,,3\n", "row 1 has an empty"),
                        ("x,y,z,i,j,k\n1,2,3,0,0,0\n", "zero tool axis")):  # fmt: skip
        (tmp_path / "b.csv").write_text(text)
        with pytest.raises(ms.InputError, match=re.escape(words)):
            ms.read_csv(tmp_path / "b.csv")


@needs_kernel
def test_verify_and_simulate_read_the_tool_from_our_csv(tmp_path):
    import machsurf_cad as ms

    face, tp = _plane_path(tmp_path)
    csv = ms.write_csv(tmp_path / "p.csv", tp)
    ms.occ.write_step(tmp_path / "part.step", [ms.Face(face)])
    r = run("simulate", tmp_path / "part.step", "--toolpath", csv, "--resolution", "1", "-o", tmp_path / "s")
    assert r.returncode in (0, 2) and "names no usable CUTTER" not in r.stderr, r.stderr
    assert _strict((tmp_path / "s" / "report.json").read_text())["tool"]["kind"] == "ball"


def test_reports_are_strict_json():
    import math

    import numpy as np

    from machsurf_cad.results import strict_json

    doc = {"a_mm": float("nan"), "b": [np.inf, 1.5, np.float64("-inf")], "c": np.array([np.nan, 2.0])}
    assert _strict(strict_json(doc)) == {"a_mm": None, "b": [None, 1.5, None], "c": [None, 2.0]}
    assert not math.isnan(_strict(strict_json({"x": np.float32(2.5)}))["x"])


@pytest.mark.parametrize("delay", [0.25, 0.4, 0.8, 1.2])
def test_ctrl_c_and_sigterm_during_start_up(tmp_path, delay):
    for sig, code, word in ((signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")):
        p = subprocess.Popen([sys.executable, "-m", "machsurf_cad", "machining-surface", "--example", "bezier5",
                              "--tool", "ball:D=10", "--axes", "3", "--tolerance", "0.01", "-o", str(tmp_path / "o")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL,
                             env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
        time.sleep(delay)
        p.send_signal(sig)
        out, err = p.communicate(timeout=60)
        if p.returncode == 0:  # finished before the signal: nothing to check at this delay
            continue
        assert p.returncode == code and "Traceback" not in err and word in err, (delay, p.returncode, err[-800:])
        # nothing written, or (the signal arrived during the folder swap, which defers it) the whole run
        o = tmp_path / "o"
        assert not o.exists() or json.loads((o / ".machsurf-manifest.json").read_text())["files"], delay
        shutil.rmtree(o, ignore_errors=True)


@pytest.mark.parametrize(
    "argv, words",
    [
        (
            [
                "machining-surface",
                "--example",
                "bezier5",
                "--tool",
                "ball:D=10",
                "--axes",
                "3",
                "--faces",
                "",
                "--toolpath",
            ],
            "names no face",
        ),
        (
            [
                "machining-surface",
                "--example",
                "bezier5",
                "--tool",
                "ball:D=10",
                "--toolpath",
                "--stepover",
                "7",
                "--scallop",
                "0.01",
            ],
            "not both",
        ),
        (["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--scallop", "0.01"], "add --toolpath"),
        (
            [
                "machining-surface",
                "--example",
                "bezier5",
                "--tool",
                "ball:D=10",
                "--axes",
                "5",
                "--pattern",
                "waterline",
            ],
            "add --faces",
        ),
        (["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--angle", "nan"], "finite number"),
        (["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--feed", "900"], "--feed applies to"),
        (["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--lead-rate", "3"], "--lead auto"),
        (
            ["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--shank", "D=10,L=40"],
            "add --toolpath",
        ),
        (["machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--tolerance", "inf"], "finite number"),
    ],
)
def test_ignored_option_combinations_are_refused(tmp_path, argv, words):
    r = run(*argv, "-o", tmp_path / "o")
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert words in r.stderr
    assert not (tmp_path / "o").exists()


def test_batch_workers_zero_and_a_job_named_like_the_batch_report(tmp_path):
    import machsurf_cad as ms

    job = {"name": "r", "argv": ["reff", "--example", "bezier5", "--tool", "ball:D=10", "--grid", "8"]}
    with pytest.raises(ms.InputError, match="workers must be an integer >= 1, got 0"):
        ms.batch([job], tmp_path / "b", workers=0)
    with pytest.raises(ms.InputError, match="'report.json' is a file the batch writes"):
        ms.batch([{**job, "name": "report.json"}], tmp_path / "b", workers=1)
    assert not (tmp_path / "b").exists()


def _wrong_types():
    import numpy as np

    import machsurf_cad as ms

    face = ms.example("bezier5")
    res = ms.machining_surface(face, "ball:D=10", axes=3, tolerance=1e-2)
    tp = ms.tool_paths(res, stepover=20.0)
    return {
        "machining_surface strategy=42": lambda: ms.machining_surface(face, "ball:D=10", axes=3, strategy=42),
        "machining_surface tool=123": lambda: ms.machining_surface(face, 123),
        "machining_surface tolerance='a'": lambda: ms.machining_surface(face, "ball:D=10", tolerance="a"),
        "verify toolpath=None": lambda: ms.verify(face, None),
        "simulate resolution='abc'": lambda: ms.simulate(face, tp, resolution="abc"),
        "simulate toolpath=None": lambda: ms.simulate(face, None),
        "drop_cutter xy='abc'": lambda: ms.drop_cutter([face], ms.BallEndMill(10), "abc"),
        "raster stepover='a'": lambda: ms.raster([face], "ball:D=10", stepover="a"),
        "raster stepover=1e-4": lambda: ms.raster([face], "ball:D=10", stepover=1e-4),
        "tool_paths ms='x'": lambda: ms.tool_paths("x", stepover=1),
        "tool_paths stepover='a'": lambda: ms.tool_paths(res, stepover="a"),
        "reff tool=42": lambda: ms.reff(face, 42),
        "reff grid='a'": lambda: ms.reff(face, "ball:D=10", grid="a"),
        "envelope motion=None": lambda: ms.envelope("cyl:D=10", None),
        "parse_cutter 1": lambda: ms.parse_cutter(1),
        "cutter_from_apt [10, 20]": lambda: ms.cutter_from_apt([10, 20]),
        "write_apt None": lambda: ms.write_apt("/nonexistent/x.apt", None),
        "write_csv 'a'": lambda: ms.write_csv("/nonexistent/x.csv", "a"),
        "read_apt None": lambda: ms.read_apt(None),
        "run_job 'x'": lambda: ms.run_job("x", "/nonexistent/o"),
        "Face(None)": lambda: ms.Face(None),
        "top_faces None": lambda: ms.top_faces(None),
        "local_properties None": lambda: ms.local_properties(None, 0, 0),
        "drop_cutter 0 points": lambda: ms.drop_cutter([face], "ball:D=10", np.zeros((0, 3))),
    }


def test_the_public_api_refuses_wrong_types_in_one_line():
    import machsurf_cad as ms

    for what, call in _wrong_types().items():
        with pytest.raises(ms.InputError) as e:
            call()
        assert "\n" not in str(e.value), what


def test_a_raster_that_would_run_for_hours_is_refused_with_its_figure():
    import machsurf_cad as ms

    t = time.perf_counter()
    with pytest.raises(ms.InputError, match=r"needs about .* drop-cutter points .* give a larger step-over"):
        ms.raster([ms.example("bezier5")], "ball:D=10", stepover=1e-4)
    face, tp = _plane_path(None)
    with pytest.raises(ms.InputError, match=r"every 1e-06 mm needs .* tool placements .* give a larger motion step"):
        ms.simulate(face, tp, motion_step=1e-6)  # asked for 52 GiB before
    with pytest.raises(ms.InputError, match=r"needs .* tool placements .* give a larger step"):
        ms.verify(face, tp, step=1e-5)
    with pytest.raises(ms.InputError, match="more than 10 times the part's size"):
        ms.drop_cutter([face], "ball:D=1e6", [[0.0, 0.0]])
    assert time.perf_counter() - t < 30


@needs_kernel
def test_a_face_no_tool_position_can_touch_is_refused_by_name(tmp_path):
    import cadquery as cq

    cq.exporters.export(cq.Workplane().box(40, 30, 20), str(tmp_path / "box.step"))
    faces = {}
    for i in range(6):
        faces[i] = run("machining-surface", tmp_path / "box.step", "--faces", i, "--axes", "3", "--tool", "ball:D=10",
                       "--toolpath", "--stepover", "5", "-o", tmp_path / f"o{i}")  # fmt: skip
    bottom = [i for i, r in faces.items() if "faces away from +Z" in r.stderr]
    walls = [i for i, r in faces.items() if "parallel to the tool axis" in r.stderr]
    top = [i for i, r in faces.items() if r.returncode == 0]
    assert len(bottom) == 1 and len(walls) == 4 and len(top) == 1, {i: r.stderr for i, r in faces.items()}
    _refused(faces[bottom[0]], f"face {bottom[0]} faces away from +Z")


def test_a_large_gouge_tolerance_is_not_a_clearance_the_rapids_must_keep(tmp_path):
    out = tmp_path / "f"
    r = run(
        "flank", "--example", "hypar", "--tool", "cyl:D=20", "--whole", "--tolerance", "1e3", "--no-render", "-o", out
    )
    assert r.returncode == 0, r.stdout[-800:] + r.stderr
    v = _strict((out / "report.json").read_text())["whole"]["verify"]
    assert v["n_collisions"] == 0 and v["clearance_mm"] == 0.01 and v["min_clearance_mm"] > 4.4
    assert (out / "toolpath.apt").is_file() and "mm into" not in r.stdout


def test_mill3_is_the_whole_part_three_axis_command_and_the_old_route_notes_it(tmp_path):
    r = run("mill3", "--example", "bezier5", "--tool", "ball:D=10", "--stepover", "10", "-o", tmp_path / "m")
    assert r.returncode == 0, r.stderr
    rep = _strict((tmp_path / "m" / "report.json").read_text())
    assert rep["verify"]["clean"] and rep["toolpath"]["n_passes"] == 11 and rep["faces_machined"] == [0]
    old = run("machining-surface", "--example", "bezier5", "--faces", "top", "--axes", "3", "--tool", "ball:D=10",
              "--toolpath", "--stepover", "10", "-o", tmp_path / "o")  # fmt: skip
    assert old.returncode == 0 and "note: `machsurf mill3` is the whole-part 3-axis command" in old.stdout
    assert (tmp_path / "o" / "toolpath.csv").read_text() == (tmp_path / "m" / "toolpath.csv").read_text()


@pytest.mark.slow
@needs_kernel
def test_sigterm_stops_a_long_stl_meshing_at_once(tmp_path):
    p = subprocess.Popen([sys.executable, "-m", "machsurf_cad", "machining-surface", "--example", "blade", "--tool",
                          "ball:D=10", "--axes", "3", "--tolerance", "0.01", "--stl-deflection", "0.0002", "-o",
                          str(tmp_path / "o")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         stdin=subprocess.DEVNULL,
                         env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
    deadline = time.time() + 120
    while "loops: none" not in (line := p.stdout.readline()) and time.time() < deadline:  # the fit is done
        assert line or p.poll() is None, p.stderr.read()
    time.sleep(3)  # inside OCCT's meshing of about 0.7 million triangles (about 20 s)
    t = time.perf_counter()
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143 and time.perf_counter() - t < 3, (p.returncode, err)
    assert err.strip() == "machsurf: terminated (nothing written)" and not (tmp_path / "o").exists()
    _no_partial(tmp_path / "o")


def test_a_scheduler_that_answers_http_is_refused_within_the_timeout(tmp_path):
    import http.server
    import threading

    import machsurf_cad as ms

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    srv.daemon_threads = True  # a handler waiting on the Dask client's bytes must not hold the shutdown
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        t = time.perf_counter()
        with pytest.raises(ms.InputError, match="cannot reach the Dask scheduler"):
            ms.batch([{"name": "r", "argv": ["reff", "--example", "bezier5", "--tool", "ball:D=10"]}], tmp_path / "b",
                     scheduler=f"tcp://127.0.0.1:{srv.server_address[1]}", timeout_s=2)  # fmt: skip
        assert time.perf_counter() - t < 10  # --timeout 3 was ignored for 60 s; a 3 EiB MemoryError before
    finally:
        srv.shutdown()
    assert not (tmp_path / "b").exists()


def test_an_iso_scallop_of_a_nanometre_is_refused_after_the_first_step(tmp_path):
    t = time.perf_counter()
    r = run("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--tolerance", "0.01", "--toolpath",
            "--scallop", "1e-9", "-o", tmp_path / "o")  # fmt: skip
    _refused(r, "needs about", "passes on this face", "give a larger scallop height")
    assert time.perf_counter() - t < 30  # 104 s before
