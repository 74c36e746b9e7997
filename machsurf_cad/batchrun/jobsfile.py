"""Batch jobs: a name and a job spec (from Python) or one ``machsurf`` command line (JSON or TOML files) each."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError
from ..typing import PathLike

if TYPE_CHECKING:
    from ..jobs.specs import JobSpec

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")


@dataclass(frozen=True)
class BatchJob:
    """One batch job: ``name`` (its output folder ``OUT/<name>/``) and what to run, either ``spec`` (a job
    spec built in Python, e.g. ``ms.Mill3Job(part=..., tool=...)``) or ``argv`` (a ``machsurf`` command line
    without ``-o``, as a jobs file holds it). Relative input paths are read from ``base_dir`` (the jobs
    file's folder) when given, else from the current folder.

    Examples
    --------
    >>> BatchJob("reff-ball", ("reff", "--example", "bezier5", "--tool", "ball:D=10")).argv[0]
    'reff'
    >>> from machsurf_cad.jobs import ReffJob
    >>> BatchJob("reff-ball", spec=ReffJob(example="bezier5", tool="ball:D=10")).spec.command
    'reff'
    """

    name: str
    argv: tuple = ()
    base_dir: str | None = None
    spec: JobSpec | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise InputError(
                f"job name {self.name!r}: letters, digits, '.', '_' or '-' (it names the output folder), "
                "up to 100 characters"
            )
        if self.spec is not None:
            from ..jobs.specs import DemoJob, JobSpec

            if not isinstance(self.spec, JobSpec) or isinstance(self.spec, DemoJob):
                raise InputError(f"job {self.name!r}: spec must be a job spec (not the demo), got {self.spec!r}")
            if self.argv:
                raise InputError(f"job {self.name!r}: give spec or argv, not both")
            return
        if isinstance(self.argv, str) or not all(isinstance(a, str) for a in self.argv) or not self.argv:
            raise InputError(f"job {self.name!r}: field 'argv' must be a non-empty list of strings (or give spec)")
        object.__setattr__(self, "argv", tuple(self.argv))


def parse_jobs(data, *, base_dir: str | None = None, source: str = "jobs") -> tuple[BatchJob, ...]:
    """Batch jobs from a mapping ``{"jobs": [{"name": ..., "argv": [...]}, ...]}``; every problem names
    the job (its number from 1 and its name) and the field."""
    if not isinstance(data, dict) or "jobs" not in data:
        raise InputError(f"{source}: expected an object with a 'jobs' list")
    extra = set(data) - {"jobs"}
    if extra:
        raise InputError(f"{source}: unknown top-level field(s) {', '.join(sorted(extra))}")
    raw = data["jobs"]
    if not isinstance(raw, list) or not raw:
        raise InputError(f"{source}: 'jobs' must be a non-empty list")
    jobs: list[BatchJob] = []
    seen: dict[str, int] = {}
    for i, item in enumerate(raw, 1):
        where = f"{source}: job {i}"
        if not isinstance(item, dict):
            raise InputError(f"{where}: expected an object with 'name' and 'argv'")
        if "name" in item:
            where += f" ({item['name']!r})"
        for key in ("name", "argv"):
            if key not in item:
                raise InputError(f"{where}: missing field '{key}'")
        unknown = set(item) - {"name", "argv"}
        if unknown:
            raise InputError(f"{where}: unknown field(s) {', '.join(sorted(unknown))}")
        if not isinstance(item["argv"], list):
            raise InputError(f"{where}: field 'argv' must be a list of strings (a command line without -o)")
        try:
            job = BatchJob(item["name"], tuple(item["argv"]), base_dir)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
        if job.name in seen:
            raise InputError(f"{where}: duplicate name (job {seen[job.name]} has it too)")
        seen[job.name] = i
        jobs.append(job)
    return tuple(jobs)


def read_jobs(path: PathLike) -> tuple[BatchJob, ...]:
    """Read a jobs file: JSON (``.json``) or TOML (``.toml``: ``[[jobs]]`` tables with ``name`` and
    ``argv``). Relative input paths in the command lines are taken from the file's folder."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"jobs file {p} not found")
    text = p.read_text(encoding="utf-8", errors="replace")
    try:
        if p.suffix.lower() == ".toml":
            import tomllib

            data = tomllib.loads(text)
        else:
            data = json.loads(text)
    except (ValueError, UnicodeError) as exc:
        raise InputError(f"{p.name}: not valid {'TOML' if p.suffix.lower() == '.toml' else 'JSON'}: {exc}") from None
    return parse_jobs(data, base_dir=str(p.resolve().parent), source=p.name)
