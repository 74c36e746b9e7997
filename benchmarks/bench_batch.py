"""Batch runs on Dask (a LocalCluster of one process per core on this machine).

1. Eight machining-surface jobs with tool paths checked against the part (the example free-form,
   ball/bull/flat, 3 and 5 axes): one after the
   other in this process against ``machsurf_cad.batchrun`` on the local cluster (wall time, cluster start
   included).
2. One large simulation (the 5-axis ball path of bench_simulate, 10,200 positions on 1.07 M samples)
   in one run against 4 chunks of samples spread over the cluster (``simulate(map_chunks=dask_map(client))``);
   the figures must be equal.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

_TOOLS = [
    ("ball:D=10", 3, 0.0),
    ("ball:D=16", 3, 0.0),
    ("bull:D=16,r=3", 5, 10.0),
    ("bull:D=20,r=4", 5, 8.0),
    ("flat:D=10", 5, 5.0),
    ("flat:D=16", 5, 6.0),
    ("ball:D=10", 5, 0.0),
    ("bull:D=12,r=2", 5, 12.0),
]


def _jobs():
    from machsurf_cad.batchrun import BatchJob

    out = []
    for i, (tool, axes, lead) in enumerate(_TOOLS):
        argv = ["machining-surface", "--example", "bezier5", "--tool", tool, "--axes", str(axes), "--toolpath",
                "--stepover", "3", "--clearance", "60"]  # fmt: skip
        if axes == 5:
            argv += ["--lead", str(lead)]
        out.append(BatchJob(f"job{i}", tuple(argv)))
    return out


def batch_rows(quick=False):
    import os

    import machsurf_cad as ms
    from machsurf_cad.batchrun import dask_map
    from machsurf_cad.cliargs import spec_from_argv

    jobs = _jobs()[: 4 if quick else 8]
    rows = []
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        for j in jobs:
            ms.run_job(spec_from_argv(j.argv), Path(d) / "serial" / j.name)
        t_serial = time.perf_counter() - t
        t = time.perf_counter()
        res = ms.batch(jobs, Path(d) / "batch")
        t_batch = time.perf_counter() - t
        assert all(j.exit_code in (0, 2) for j in res.jobs), res.report()  # 2: a path refused (it gouges)
    per_job = [j.time_s for j in res.jobs]
    rows.append(
        {
            "name": f"batch: {len(jobs)} machining-surface jobs, {res.n_workers} workers",
            "n": len(jobs),
            "ours_s": t_batch,
            "ref_s": t_serial,
            "ref": "one after the other",
            "max_diff": 0.0,
            "per_job_s": per_job,
            "exit_codes": [j.exit_code for j in res.jobs],
            "n_cores": os.cpu_count(),
        }
    )
    # one large simulation in chunks over the cluster
    from distributed import Client, LocalCluster

    from .bench_simulate import _ball_path

    face = ms.example("bezier5")
    up = float(ms.local_properties(face, 0.5, 0.5).normal[2]) > 0
    F = ms.Face(face, name="bezier5", reversed=not up)
    tp, _ = _ball_path(face, n_pass=30 if quick else 100, n_pos=34 if quick else 100)
    res_mm = 0.4 if quick else 0.1
    t = time.perf_counter()
    one = ms.simulate(F, tp, resolution=res_mm, stock=2.0)
    t_one = time.perf_counter() - t
    with LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, dashboard_address=":0") as cluster:
        with Client(cluster) as client:
            t = time.perf_counter()
            split = ms.simulate(F, tp, resolution=res_mm, stock=2.0, chunks=4, map_chunks=dask_map(client))
            t_split = time.perf_counter() - t
    rows.append(
        {
            "name": f"simulate {tp.n_positions} pos x {one.points.shape[0]} samples in 4 chunks",
            "n": int(one.points.shape[0]),
            "ours_s": t_split,
            "ref_s": t_one,
            "ref": "one run, one process",
            "max_diff": float(np.abs(np.asarray(one.value) - np.asarray(split.value)).max()),
        }
    )
    return rows
