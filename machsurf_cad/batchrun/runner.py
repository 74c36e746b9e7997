"""Batch runs on Dask's distributed scheduler: one task per job, each running :func:`~machsurf_cad.run_job`
on a worker exactly as the CLI would, outputs brought back into ``OUT/<name>/``.

Dask is imported here only (``pip install 'machsurf_cad[batch]'``).
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import os
import tempfile
import time
import uuid
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from ..errors import InputError, MachsurfError
from ..results import Result
from ..typing import PathLike, ProgressLike
from .jobsfile import BatchJob

PATH_FIELDS = ("part", "toolpath", "path", "nominal", "candidate")
_BLAS_THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""Job spec fields that name input files (sent to workers that cannot read them)."""


@dataclass(frozen=True, eq=False)
class BatchJobResult(Result):
    """One job of a batch: ``status`` ``"ok"`` or ``"error"``, the exit code its command line would have
    (0, 1 bad input, 2 a tolerance not met), its last message, time on the worker (s), the worker, the
    files written into ``OUT/<name>/`` and the job's own ``report.json`` (``figures``; empty on error)."""

    name: str
    status: str
    exit_code: int
    message: str
    time_s: float
    worker: str | None
    files: tuple = ()
    figures: dict = dataclasses.field(default_factory=dict, repr=False)
    attempts: int = 1

    def report(self) -> dict:
        return {
            "name": self.name,
            "status": self.status,
            "exit_code": self.exit_code,
            "message": self.message,
            "time_s": self.time_s,
            "worker": self.worker,
            "attempts": self.attempts,
            "files": list(self.files),
        }


@dataclass(frozen=True, eq=False)
class BatchResult(Result):
    """A whole batch: its jobs in the jobs file's order, the scheduler and workers used, wall time (s)."""

    jobs: tuple
    out_dir: str
    scheduler: str
    n_workers: int
    wall_time_s: float

    @property
    def exit_code(self) -> int:
        """0 when every job is ok; 2 when a job missed a tolerance; else 1."""
        codes = {j.exit_code for j in self.jobs}
        return 0 if codes <= {0} else (2 if 2 in codes else 1)

    def report(self) -> dict:
        n_ok = sum(j.status == "ok" for j in self.jobs)
        busy = sum(j.time_s for j in self.jobs)
        return {
            "n_jobs": len(self.jobs),
            "n_ok": n_ok,
            "n_error": len(self.jobs) - n_ok,
            "scheduler": self.scheduler,
            "n_workers": self.n_workers,
            "wall_time_s": self.wall_time_s,
            "job_time_sum_s": busy,
            "speed_up": busy / self.wall_time_s if self.wall_time_s > 0 else None,
            "exit_code": self.exit_code,
            "jobs": [j.report() for j in self.jobs],
        }


def _sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def prepare(job: BatchJob):
    """The job's spec (parsed as the CLI would) and its input files ``{field: (absolute path, sha256)}``."""
    from ..cliargs import spec_from_argv

    spec = job.spec if job.spec is not None else spec_from_argv(job.argv)
    inputs = {}
    for name in PATH_FIELDS:
        value = getattr(spec, name, None)
        if not value or not isinstance(value, str):  # machining-surface's toolpath is a flag
            continue
        p = Path(value)
        if not p.is_absolute():
            p = Path(job.base_dir or os.getcwd()) / p
        if not p.is_file():
            raise InputError(f"{name} {value}: file not found")
        inputs[name] = (str(p.resolve()), _sha256(p))
    return spec, inputs


def run_on_worker(name: str, spec, inputs: dict, payload: dict | None = None) -> dict:
    """Run one job where this function is called (a Dask worker): inputs by path when this machine
    holds the same files (same sha256), else from ``payload`` (their bytes), else ask for them
    (``status`` ``"need-inputs"``). Returns the outcome and the output files' bytes."""
    from ..jobs import run_job

    worker = _worker_name()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="machsurf-batch-") as tmp:
        local = {}
        for field, (path, digest) in inputs.items():
            if payload is not None and field in payload:
                q = Path(tmp) / "inputs" / field / Path(path).name
                q.parent.mkdir(parents=True)
                q.write_bytes(payload[field])
                local[field] = str(q)
            elif Path(path).is_file() and _sha256(path) == digest:
                local[field] = path
            else:
                return {"status": "need-inputs", "worker": worker}
        spec = dataclasses.replace(spec, **local)
        lines: list[str] = []
        out = Path(tmp) / "out"
        try:
            outcome = run_job(spec, out, say=lines.append)
            code = outcome.exit_code
            # a job that missed a tolerance: its last word says which
            message = (
                "" if code == 0 else next((ln for ln in reversed(lines) if ln and not ln.startswith("outputs")), "")
            )
        except MachsurfError as exc:
            code, message = exc.exit_code, str(exc)
        except Exception as exc:  # an unexpected failure is this job's error, never the batch's
            code, message = 1, f"{type(exc).__name__}: {exc}"
        files = {}
        if out.is_dir():
            for f in sorted(out.rglob("*")):
                if f.is_file():
                    files[f.relative_to(out).as_posix()] = f.read_bytes()
    return {
        "status": "ok" if code == 0 else "error",
        "exit_code": int(code),
        "message": message,
        "time_s": time.perf_counter() - t0,
        "worker": worker,
        "files": files,
    }


def dask_map(client):
    """A ``map``-like callable running its calls as tasks on ``client``'s cluster, results in order
    (for :func:`~machsurf_cad.simulate`'s ``map_chunks``)."""

    def _map(fn, *iterables):
        args = [client.scatter(list(it)) for it in iterables]  # large chunks travel once, not in the graph
        return client.gather(client.map(fn, *args, pure=False))

    return _map


def worker_map():
    """On a Dask worker (a batch job): a ``map`` that spreads its calls over the same cluster (the job's
    task waits outside the worker's thread pool meanwhile); elsewhere ``None`` (run here)."""
    try:
        from distributed import get_worker, worker_client

        get_worker()
    except (ImportError, ValueError):
        return None

    def _map(fn, *iterables):
        with worker_client() as client:
            args = [client.scatter(list(it)) for it in iterables]
            return client.gather(client.map(fn, *args, pure=False))

    return _map


def chunk_map(chunks: int):
    """The ``map_chunks`` of a job split in ``chunks``: over the Dask cluster when the job runs on a
    worker (a batch), else ``None`` (the chunks run one after the other)."""
    return worker_map() if int(chunks) > 1 else None


def _worker_name() -> str | None:
    try:
        from distributed import get_worker

        w = get_worker()
        return str(w.name if w.name is not None else w.address)
    except (ImportError, ValueError):
        return None


def _connect(Client, scheduler: str, timeout_s: float):
    """A Dask client of ``scheduler`` within ``timeout_s`` (in a thread: a server that is no Dask scheduler,
    e.g. one that answers HTTP, can keep the handshake waiting or announce an absurd message size)."""
    import threading

    box: dict = {}

    def connect():
        try:
            box["client"] = Client(scheduler, timeout=f"{timeout_s}s")
        except BaseException as exc:  # reported below, in the caller's thread
            box["error"] = exc

    t = threading.Thread(target=connect, daemon=True, name="machsurf-dask-connect")
    t.start()
    t.join(timeout_s + 2.0)
    if t.is_alive() or "error" in box:
        exc = box.get("error")
        why = f"{type(exc).__name__}: {exc}" if exc is not None else "no answer"
        if isinstance(exc, MemoryError):
            why = "it does not answer as a Dask scheduler"
        raise InputError(f"cannot reach the Dask scheduler at {scheduler} within {timeout_s:g} s: {why}"[:400])
    return box["client"]


def _client(scheduler: str | None, workers: int | None, timeout_s: float):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("batch runs need Dask: pip install 'machsurf_cad[batch]'") from None
    if scheduler:
        client = _connect(Client, scheduler, float(timeout_s))
        try:  # a scheduler without workers would keep the jobs waiting for ever
            client.wait_for_workers(1, timeout=float(timeout_s))
        except (OSError, TimeoutError) as exc:
            client.close()
            raise InputError(f"the Dask scheduler at {scheduler} has no worker after {timeout_s:g} s: {exc}") from None
        return client, None
    import logging

    n = int(workers) if workers is not None else (os.cpu_count() or 1)
    if n < 1:
        raise InputError(f"workers must be >= 1, got {workers}")
    # Dask starts workers with one BLAS thread; a least-squares fit then rounds differently in the last
    # digit from the same job run by the CLI: keep the threads a plain process has
    # (set before the worker processes start: BLAS reads them when it loads)
    import dask

    key = "distributed.nanny.pre-spawn-environ"
    blas = {k: os.environ.get(k, str(os.cpu_count() or 1)) for k in _BLAS_THREADS}
    with dask.config.set({key: {**dask.config.get(key, {}), **blas}}):
        cluster = LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
        )
    return Client(cluster), cluster


def batch(
    jobs: Iterable[BatchJob | dict[str, Any]],
    out: PathLike = "out/batch",
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 2,
    overwrite: bool = False,
    timeout_s: float = 10.0,
    say: Callable[[str], object] | None = None,
    progress: ProgressLike = None,
) -> BatchResult:
    """Run ``jobs`` (:class:`BatchJob`) on Dask and write ``OUT/<name>/`` per job, ``batch_report.json``
    (also as ``report.json``) and ``batch_figures.csv``.

    Parameters
    ----------
    jobs : sequence of BatchJob or of dict
        From :func:`read_jobs`, built in Python (``BatchJob(name, spec=ms.Mill3Job(...))``), or mappings
        ``{"name": ..., "argv": [...]}``; names unique.
    out : str or Path
        Output folder (default ``out/batch``; written whole when the batch ends; an earlier batch there
        needs ``overwrite``).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:port``); default a ``LocalCluster`` of
        ``workers`` processes (one per core).
    retries : int
        Times a job is run again after its task failed (Dask also moves the jobs of a lost worker to
        the others, up to its ``allowed-failures``).
    timeout_s : float
        Time to reach ``scheduler`` before giving up (s).

    Returns
    -------
    BatchResult
        Every job's status, exit code, message, time and worker; a failing job never stops the others.
    """
    from ..jobs import Staging
    from ..results import write_json

    say = say or (lambda msg="": None)
    jobs = tuple(jobs)
    if jobs and all(isinstance(j, dict) for j in jobs):  # {"name": ..., "argv": [...]} as in a jobs file
        from .jobsfile import parse_jobs

        jobs = parse_jobs({"jobs": list(jobs)}, source="batch()")
    if not jobs or not all(isinstance(j, BatchJob) for j in jobs):
        raise InputError("batch() needs a non-empty list of BatchJob (or of {'name': ..., 'argv': [...]})")
    jobs = cast("tuple[BatchJob, ...]", jobs)  # every one checked above (the type checker cannot see it)
    names = [j.name for j in jobs]
    if len(set(names)) != len(names):
        raise InputError("duplicate job names: " + ", ".join(sorted({n for n in names if names.count(n) > 1})))
    taken = sorted(set(names) & {"report.json", "batch_report.json", "batch_figures.csv", ".machsurf-manifest.json"})
    if taken:
        raise InputError(f"job name {taken[0]!r} is a file the batch writes in its output folder: rename the job")
    if workers is not None and not (isinstance(workers, int) and workers >= 1):
        raise InputError(f"workers must be an integer >= 1, got {workers!r}")
    if not (isinstance(timeout_s, (int, float)) and 0 < timeout_s < 1e6):
        raise InputError(f"timeout_s must be > 0 s, got {timeout_s!r}")
    if int(retries) < 0:
        raise InputError(f"retries must be >= 0, got {retries}")
    out = Path(out)
    if (out / "batch_report.json").is_file() and not overwrite:
        raise InputError(f"{out} holds an earlier batch: choose another -o or pass --overwrite")
    t0 = time.perf_counter()
    results: dict[str, BatchJobResult] = {}
    ready = []
    for job in jobs:
        try:
            ready.append((job, *prepare(job)))
        except MachsurfError as exc:
            results[job.name] = BatchJobResult(job.name, "error", exc.exit_code, str(exc), 0.0, None)
    with Staging(out) as st:
        client, cluster = _client(scheduler, workers, timeout_s)
        try:
            n_workers = len(client.scheduler_info().get("workers", {}))
            say(f"batch: {len(jobs)} job(s) on {n_workers} Dask worker(s) ({scheduler or 'local cluster'})")
            _run(client, ready, st.dir, results, int(retries), say, progress, len(jobs))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        res = BatchResult(
            tuple(results[j.name] for j in jobs), str(out), scheduler or "local", n_workers, time.perf_counter() - t0
        )
        rep = res.report()
        rep["units"] = {"length": "mm", "angle": "deg", "time": "s"}
        write_json(st.path("batch_report.json"), rep)
        write_json(st.path("report.json"), {**rep, "command": "batch"})
        write_figures_csv(st.path("batch_figures.csv"), res.jobs)
    return res


def _run(client, ready, stage_dir: Path, results: dict, retries: int, say, progress, total: int) -> None:
    from distributed import as_completed

    def submit(job, spec, inputs, payload=None):
        key = f"machsurf-{job.name}-{uuid.uuid4().hex[:8]}"
        return client.submit(run_on_worker, job.name, spec, inputs, payload, key=key, pure=False, retries=retries)

    futures = {}
    for job, spec, inputs in ready:
        futures[submit(job, spec, inputs)] = (job, spec, inputs, 1)
    done = len(results)
    if progress is not None:
        progress(done, total, "batch")
    queue = as_completed(list(futures))
    for fut in queue:
        job, spec, inputs, attempt = futures.pop(fut)
        try:
            r = fut.result()
        except Exception as exc:  # the task itself failed: retries spent, or its workers kept dying
            r = {"status": "error", "exit_code": 1, "message": f"{type(exc).__name__}: {exc}", "time_s": 0.0,
                 "worker": None, "files": {}}  # fmt: skip
        if r["status"] == "need-inputs":  # this worker cannot read the inputs: send their bytes
            payload = {f: Path(p).read_bytes() for f, (p, _d) in inputs.items()}
            nf = submit(job, spec, inputs, payload)
            futures[nf] = (job, spec, inputs, attempt)
            queue.add(nf)
            continue
        figures = {}
        folder = stage_dir / job.name
        for rel, data in r["files"].items():
            q = folder / rel
            q.parent.mkdir(parents=True, exist_ok=True)
            q.write_bytes(data)
            if rel == "report.json":
                import json

                figures = json.loads(data)
        results[job.name] = BatchJobResult(
            job.name, r["status"], r["exit_code"], r["message"], r["time_s"], r["worker"],
            tuple(sorted(r["files"])), figures, attempt,
        )  # fmt: skip
        done += 1
        say(f"  {job.name}: {r['status']} (exit {r['exit_code']}, {r['time_s']:.2f} s on {r['worker']})"
            + (f": {r['message']}" if r["status"] != "ok" else ""))  # fmt: skip
        if progress is not None:
            progress(done, total, job.name)


def _scalars(d: dict, prefix: str = "", depth: int = 0):
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, bool) or v is None:
            continue
        if isinstance(v, (int, float)):
            yield key, v
        elif isinstance(v, dict) and depth < 2:
            yield from _scalars(v, key + ".", depth + 1)


def write_figures_csv(path, jobs) -> Path:
    """One row per job: name, status, exit code, time, worker and every number of its report (dotted keys)."""
    rows = []
    keys: list[str] = []
    for j in jobs:
        fig = dict(_scalars({k: v for k, v in j.figures.items() if k not in ("exit_code", "units", "files")}))
        rows.append((j, fig))
        keys.extend(k for k in fig if k not in keys)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["name", "status", "exit_code", "time_s", "worker", *keys])
        for j, fig in rows:
            w.writerow(
                [j.name, j.status, j.exit_code, f"{j.time_s:.3f}", j.worker or "", *[fig.get(k, "") for k in keys]]
            )
    return Path(path)
