"""Hostile and conflicting inputs: a one-line refusal (exit 1, no traceback, nothing written), never a
traceback, a half-written folder, unbounded work or a silently wrong result."""

import json
import signal
import subprocess
import sys
import time

import pytest
from conftest import ROOT, needs_kernel
from helpers import run, run_process

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
        "--tol",
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
        "--tol",
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
            "--tol",
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
    r = run("inspect", BLOCK, BLOCK, "--samples", "2", "--no-render", "-o", o)
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
        "--seam-angle-tol",
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
