"""Batch runs on Dask: jobs files, a local cluster, an external scheduler and workers, a lost worker."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from conftest import ROOT, needs_kernel

import machsurf_cad as ms
from machsurf_cad.batchrun import BatchJob, parse_jobs, read_jobs
from machsurf_cad.batchrun.runner import prepare, run_on_worker

distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed (machsurf_cad[batch])")

PART = ROOT / "example_parts" / "bezier5_patch.step"
_VOLATILE = ("time_s", "files", "toolpath", "part", "out")


def _figures(rep):
    """A report without what legitimately differs between two runs (timings, paths)."""
    if isinstance(rep, dict):
        return {k: _figures(v) for k, v in rep.items() if k not in _VOLATILE and not k.endswith("_per_s")}
    if isinstance(rep, list):
        return [_figures(v) for v in rep]
    return rep


# ----------------------------------------------------------------------------- jobs files
@pytest.mark.parametrize(
    "data,words",
    [
        ({}, "'jobs' list"),
        ({"jobs": []}, "non-empty"),
        ({"jobs": [{"name": "a"}]}, "job 1 ('a'): missing field 'argv'"),
        ({"jobs": [{"name": "a", "argv": "reff"}]}, "job 1 ('a'): field 'argv' must be a list"),
        ({"jobs": [{"name": "a", "argv": ["reff"]}, {"name": "a", "argv": ["info"]}]}, "job 2 ('a'): duplicate"),
        ({"jobs": [{"name": "../x", "argv": ["info"]}]}, "names the output folder"),
        ({"jobs": [{"name": "a", "argv": ["info"], "cpu": 2}]}, "unknown field(s) cpu"),
        ({"jobs": [{"name": "a", "argv": [1, 2]}]}, "list of strings"),
    ],
)
def test_a_malformed_jobs_file_names_the_job_and_the_field(data, words):
    with pytest.raises(ms.InputError, match=None) as exc:
        parse_jobs(data, source="jobs.json")
    assert words in str(exc.value) and "\n" not in str(exc.value)


def test_jobs_files_in_json_and_toml_read_the_same(tmp_path):
    (tmp_path / "j.json").write_text(json.dumps({"jobs": [{"name": "r", "argv": ["reff", "--example", "bezier5"]}]}))
    (tmp_path / "j.toml").write_text('[[jobs]]\nname = "r"\nargv = ["reff", "--example", "bezier5"]\n')
    a, b = read_jobs(tmp_path / "j.json"), read_jobs(tmp_path / "j.toml")
    assert a == b and a[0].base_dir == str(tmp_path.resolve())
    (tmp_path / "bad.json").write_text("{nope")
    with pytest.raises(ms.InputError, match="bad.json: not valid JSON"):
        read_jobs(tmp_path / "bad.json")


def test_a_job_is_a_spec_or_a_command_line_not_both():
    spec = ms.ReffJob(example="bezier5", tool="ball:D=10")
    with pytest.raises(ms.InputError, match="spec or argv, not both"):
        BatchJob("r", ("reff",), spec=spec)
    with pytest.raises(ms.InputError, match="not the demo"):
        BatchJob("d", spec=ms.DemoJob())
    with pytest.raises(ms.InputError, match="non-empty list of strings"):
        BatchJob("e")
    from machsurf_cad.batchrun.runner import prepare

    assert prepare(BatchJob("r", spec=spec))[0] is spec


def test_a_job_command_line_is_parsed_as_the_cli_does_and_takes_no_output():
    with pytest.raises(ms.InputError, match="takes no -o"):
        prepare(BatchJob("a", ("reff", "--example", "bezier5", "--tool", "ball:D=10", "-o", "x")))
    with pytest.raises(ms.InputError, match="required: --tool"):
        prepare(BatchJob("a", ("reff", "--example", "bezier5")))
    with pytest.raises(ms.InputError, match="file not found"):
        prepare(BatchJob("a", ("info", "nowhere.step"), base_dir=str(ROOT)))
    flag = ("machining-surface", "--example", "bezier5", "--tool", "ball:D=10", "--toolpath")
    assert prepare(BatchJob("a", flag))[1] == {}  # machining-surface's --toolpath is a flag, not a file
    spec, inputs = prepare(BatchJob("a", ("info", "example_parts/bezier5_patch.step"), base_dir=str(ROOT)))
    assert spec.command == "info" and inputs["part"][0] == str(PART.resolve()) and len(inputs["part"][1]) == 64


@needs_kernel
def test_inputs_travel_as_bytes_where_the_worker_cannot_read_them(tmp_path):
    spec, inputs = prepare(BatchJob("a", ("info", str(PART))))
    moved = {"part": ("/nonexistent/elsewhere/bezier5_patch.step", inputs["part"][1])}
    assert run_on_worker("a", spec, moved)["status"] == "need-inputs"
    r = run_on_worker("a", spec, moved, {"part": PART.read_bytes()})
    assert r["status"] == "ok" and json.loads(r["files"]["report.json"])["n_faces"] == 1


def test_simulation_in_chunks_equals_one_run():
    """Each sample's result depends on no other sample: chunks give the same numbers to the last digit."""
    x = np.linspace(-4, 4, 41)
    tips = [np.stack([x, np.full_like(x, y), np.zeros_like(x)], 1) for y in (-1.5, 0.0, 1.5)]
    tp = ms.ToolPath.from_passes(tips, [np.tile([0.0, 0, 1], (41, 1))] * 3, cutter=ms.BallEndMill(6))
    plane = ms.geometry.builders.plane_patch((-3, -3, 0), (6, 0, 0), (0, 6, 0))
    one = ms.simulate(plane, tp, resolution=0.1)
    three = ms.simulate(plane, tp, resolution=0.1, chunks=3)
    assert np.array_equal(one.value, three.value) and np.array_equal(one.reached, three.reached)
    assert _figures(one.report()) == _figures(three.report())
    with pytest.raises(ms.InputError, match="chunks"):
        ms.simulate(plane, tp, resolution=0.1, chunks=0)


def test_verification_in_chunks_equals_one_run():
    """Each placement's check depends on no other: chunks of placements give the same figures."""
    plane = ms.geometry.builders.plane_patch()  # z = 0, 100 x 100 mm
    x = np.linspace(10, 90, 60)
    tips = [np.stack([x, np.full_like(x, y), np.where(x > 50, -0.03, 0.0)], 1) for y in (30.0, 50.0, 70.0)]
    tp = ms.ToolPath.from_passes(tips, [np.tile([0.1, 0, 1], (60, 1))] * 3, cutter=ms.BullNoseEndMill(10, 2))
    one = ms.verify(plane, tp, gouge_tolerance=0.01)
    four = ms.verify(plane, tp, gouge_tolerance=0.01, chunks=4)
    for name in ("cut_distance", "holder_distance", "worst_face", "status", "sample_depth"):
        assert np.array_equal(getattr(one, name), getattr(four, name)), name
    assert np.array_equal(one.worst_xyz, four.worst_xyz, equal_nan=True)
    assert _figures(one.report()) == _figures(four.report()) and one.max_gouge > 0.02


def test_reff_maps_in_direction_groups_equal_one_run():
    face = ms.example("bezier5")
    one = ms.reff_maps(face, "bull:D=16,r=3", directions="all", grid=24, scallop=0.01)
    five = ms.reff_maps(face, "bull:D=16,r=3", directions="all", grid=24, scallop=0.01, chunks=5)
    assert len(one.directions) == 36 and np.array_equal(one.best_theta_deg, five.best_theta_deg)
    for a, b in zip(one.directions, five.directions):
        assert a.theta_deg == b.theta_deg and np.array_equal(a.r_eff, b.r_eff, equal_nan=True)
    assert _figures(one.report()) == _figures(five.report())


@pytest.mark.parametrize("kind", ["optimum", "standard-distributed"])
def test_flank_rules_in_spans_equal_one_run(kind):
    """Each span of rules starts from the settings a single run has there: the same rules and figures."""
    from machsurf_cad.flank_milling import flank_path

    surf = ms.examples.liu_ruled()
    one = flank_path(surf, 10.0, kind, tolerance=0.005)
    four = flank_path(surf, 10.0, kind, tolerance=0.005, chunks=4)
    assert len(one.settings) > 20 and np.array_equal(one.u, four.u)
    assert np.array_equal(one.tip, four.tip) and np.array_equal(one.axis, four.axis)
    assert _figures(one.report()) == _figures(four.report())


# ----------------------------------------------------------------------------- on a cluster
@pytest.fixture(scope="module")
def toolpath_csv(tmp_path_factory):
    out = tmp_path_factory.mktemp("tp") / "ms"
    ms.run_job(
        ms.MachiningSurfaceJob(part=str(PART), tool="ball:D=10", axes=3, toolpath=True, stepover=4.0),
        out,
    )
    return out / "toolpath.csv"


@needs_kernel
def test_local_cluster_runs_every_job_like_the_cli_and_reports_the_bad_one(tmp_path, toolpath_csv):
    argvs = {
        "reff": [
            "reff",
            "--example",
            "bezier5",
            "--tool",
            "bull:D=16,r=3",
            "--grid",
            "12",
            "--direction",
            "all",
            "--chunks",
            "3",
            "--no-render",
        ],  # fmt: skip
        "surface": ["machining-surface", str(PART), "--tool", "ball:D=10", "--axes", "3"],
        "sim": [
            "simulate",
            str(PART),
            "--toolpath",
            str(toolpath_csv),
            "--tool",
            "ball:D=10",
            "--resolution",
            "0.8",
            "--chunks",
            "3",
            "--no-render",
        ],  # fmt: skip
        "check": [
            "verify",
            str(PART),
            "--toolpath",
            str(toolpath_csv),
            "--tool",
            "ball:D=10",
            "--chunks",
            "3",
            "--no-render",
        ],  # fmt: skip
        "bad-face": ["machining-surface", str(PART), "--face", "9", "--tool", "ball:D=10"],
        "flank": ["flank", "--example", "liu", "--tool", "cyl:D=20", "--whole", "--chunks", "3", "--no-render"],
    }
    jobs = [BatchJob(k, tuple(v)) for k, v in argvs.items()]
    # from Python a job is its spec (the same job as the command line's, no argv)
    jobs[1] = BatchJob("surface", spec=ms.MachiningSurfaceJob(part=str(PART), tool="ball:D=10", axes=3))
    res = ms.batch(jobs, tmp_path / "b", workers=2)
    by = {j.name: j for j in res.jobs}
    assert [j.name for j in res.jobs] == list(argvs) and res.n_workers == 2
    assert by["bad-face"].status == "error" and by["bad-face"].exit_code == 1 and "face" in by["bad-face"].message
    assert all(by[k].status == "ok" and by[k].worker is not None for k in ("reff", "surface", "sim", "check"))
    # the flank path misses its 0.01 mm on Liu's surface with R 10: exit 2, its outputs written
    assert by["flank"].exit_code == 2 and "NOT met" in by["flank"].message and "envelope.step" in by["flank"].files
    assert res.exit_code == 2  # a job missed a tolerance
    rep = json.loads((tmp_path / "b" / "batch_report.json").read_text())
    assert rep["n_ok"] == 4 and rep["n_error"] == 2 and rep["jobs"][4]["name"] == "bad-face"
    rows = (tmp_path / "b" / "batch_figures.csv").read_text().splitlines()
    assert len(rows) == 7 and rows[0].startswith("name,status,exit_code,time_s,worker")
    assert not (tmp_path / "b" / "bad-face").exists()  # a failed job writes nothing
    # the same figures as direct runs (reff, simulation and check split in 3 over the cluster, direct in one)
    direct_argv = {k: [a for a in argvs[k] if a not in ("--chunks", "3")] for k in ("sim", "check", "reff", "flank")}
    for name in ("reff", "surface", "sim", "check", "flank"):
        from machsurf_cad.cliargs import spec_from_argv

        d = ms.run_job(spec_from_argv(direct_argv.get(name, argvs[name])), tmp_path / "direct" / name)
        got = json.loads((tmp_path / "b" / name / "report.json").read_text())
        assert _figures(got) == _figures(d.report), name
    # an earlier batch is kept unless --overwrite
    with pytest.raises(ms.InputError, match="earlier batch"):
        ms.batch(jobs[:1], tmp_path / "b", workers=1)
    assert ms.batch(jobs[:1], tmp_path / "b", workers=1, overwrite=True).exit_code == 0
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        ".machsurf-manifest.json", "batch_figures.csv", "batch_report.json", "reff", "report.json"
    ]  # fmt: skip


def test_an_unreachable_scheduler_is_a_clear_error_within_the_timeout(tmp_path):
    t = time.perf_counter()
    with pytest.raises(ms.InputError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        ms.batch([{"name": "r", "argv": ["reff", "--example", "bezier5", "--tool", "ball:D=10"]}], tmp_path / "o",
                 scheduler="tcp://127.0.0.1:9", timeout_s=2)  # fmt: skip
    assert time.perf_counter() - t < 15
    assert not (tmp_path / "o").exists()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask(*args):
    exe = os.path.join(os.path.dirname(sys.executable), "dask")
    return subprocess.Popen(
        [exe, *args], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
    )  # fmt: skip


@needs_kernel
@pytest.mark.slow  # the local cluster's test stays in the fast tier
def test_external_scheduler_and_workers_survive_a_killed_worker(tmp_path):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1; one worker is killed while the
    batch runs: every job still completes (Dask moves the lost worker's jobs), with the direct figures."""
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")]
    try:
        time.sleep(2.0)
        with pytest.raises(ms.InputError, match="has no worker after 1 s"):  # not waiting for ever
            ms.batch([BatchJob("r", ("reff", "--example", "bezier5", "--tool", "ball:D=10"))], tmp_path / "none",
                     scheduler=addr, timeout_s=1)  # fmt: skip
        for name in ("wa", "wb"):
            # no nanny: the worker keeps this process's BLAS threads (a nanny sets one: last digits differ)
            procs.append(_dask("worker", addr, "--nthreads", "1", "--no-nanny", "--name", name,
                               "--no-dashboard", "--death-timeout", "60"))  # fmt: skip
        client = distributed.Client(addr, timeout="60s")
        client.wait_for_workers(2, timeout=60)
        client.close()
        jobs = [
            BatchJob(f"s{i}", ("machining-surface", "--example", "bezier5", "--tool", f"ball:D={8 + i}", "--axes", "3"))
            for i in range(6)
        ]
        box = {}
        th = threading.Thread(target=lambda: box.update(res=ms.batch(jobs, tmp_path / "ext", scheduler=addr)))
        th.start()
        time.sleep(4.0)  # both workers busy: kill one of them (its process group)
        os.killpg(procs[1].pid, signal.SIGKILL)
        assert procs[1].wait(timeout=10) is not None  # worker "wa" is gone mid-batch
        th.join(timeout=600)
        res = box["res"]
        assert res.exit_code == 0 and all(j.status == "ok" for j in res.jobs), res.report()
        assert {j.worker for j in res.jobs} <= {"wa", "wb"} and "wb" in {j.worker for j in res.jobs}
        d = ms.run_job(__import__("machsurf_cad.cliargs").cliargs.spec_from_argv(jobs[0].argv), tmp_path / "direct")
        got = json.loads((tmp_path / "ext" / "s0" / "report.json").read_text())
        assert _figures(got) == _figures(d.report)
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_batch_command_line(tmp_path):
    from helpers import run

    jobs = tmp_path / "jobs.json"
    jobs.write_text(json.dumps({"jobs": [
        {"name": "r1", "argv": ["reff", "--example", "bezier5", "--tool", "ball:D=10", "--grid", "8", "--no-render"]},
        {"name": "r2", "argv": ["reff", "--example", "bezier5", "--tool", "bull:D=10,r=2", "--grid", "8",
                                "--no-render"]},
    ]}))  # fmt: skip
    with pytest.raises(ms.InputError, match="non-empty list of BatchJob"):
        ms.batch([], tmp_path / "none")
    r = run("batch", jobs, "-o", tmp_path / "out", "--workers", "1")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "2 of 2 job(s) ok" in r.stdout
    rep = json.loads((tmp_path / "out" / "batch_report.json").read_text())
    assert [j["status"] for j in rep["jobs"]] == ["ok", "ok"] and rep["n_workers"] == 1
    ball = json.loads((tmp_path / "out" / "r1" / "report.json").read_text())["directions"][0]
    assert ball["r_eff_min_mm"] == ball["r_eff_max_mm"] == 5.0  # a ball's effective radius is R everywhere
    jobs.write_text(json.dumps({"jobs": [{"name": "r1", "argv": ["reff"]}, {"name": "r1", "argv": ["reff"]}]}))
    r = run("batch", jobs, "-o", tmp_path / "out2")
    assert r.returncode == 1 and r.stderr.strip().count("\n") == 0 and "job 2 ('r1'): duplicate" in r.stderr
