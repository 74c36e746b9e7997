"""Batch runs of ``machsurf`` jobs on Dask (a local cluster or a running scheduler)."""

from .jobsfile import BatchJob, parse_jobs, read_jobs
from .runner import BatchJobResult, BatchResult, batch, dask_map, worker_map

__all__ = ["BatchJob", "BatchJobResult", "BatchResult", "batch", "dask_map", "parse_jobs", "read_jobs", "worker_map"]
