"""What every job shares: staged output folders, the outcome type, inputs from files or examples."""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from ..results import write_json

Say = Callable[[str], None]
"""Where a job prints its figures (the CLI passes ``print``; the batch runner collects them)."""

EXIT_OK, EXIT_INPUT, EXIT_TOLERANCE = 0, 1, 2


def quiet(msg: str = "") -> None:
    """A :data:`Say` that prints nothing."""


REPORT = "report.json"


class Staging:
    """Write outputs into a hidden sibling folder, then make it the output folder, whole.

    Use as a context manager: when the block ends normally the staged folder replaces ``out_dir``
    (an output folder holds exactly one run: files of an earlier run never mix with this one's);
    when it raises (including Ctrl-C or SIGTERM), the staged folder is removed and ``out_dir`` is
    left as it was. ``out_dir`` must be new, empty, or an earlier machsurf output folder (it holds a
    ``report.json``); anything else is refused rather than deleted.
    """

    def __init__(self, out_dir):
        self.out_dir = Path(out_dir)
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise InputError(f"output folder {self.out_dir} is an existing file: choose another -o")
        if self.out_dir.is_dir() and any(self.out_dir.iterdir()) and not (self.out_dir / REPORT).is_file():
            raise InputError(
                f"output folder {self.out_dir} is not empty and holds no machsurf report.json: "
                "choose a new or empty folder (machsurf replaces its own output folders whole)"
            )
        try:
            self.out_dir.parent.mkdir(parents=True, exist_ok=True)
            self.dir = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.partial-", dir=str(self.out_dir.parent)))
        except OSError as exc:
            raise InputError(f"cannot write output folder {self.out_dir}: {exc.strerror or exc}") from None
        self.files: list[str] = []

    def path(self, name: str) -> Path:
        """Path of output ``name`` inside the staging folder (recorded in :attr:`files`)."""
        if name not in self.files:
            self.files.append(name)
        return self.dir / name

    def commit(self) -> Path:
        """Replace ``out_dir`` by the staged folder (an earlier run's folder is removed after the swap)."""
        old = None
        if self.out_dir.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.old-", dir=str(self.out_dir.parent)))
            old.rmdir()
            self.out_dir.rename(old)
        try:
            self.dir.rename(self.out_dir)
        except OSError:
            if old is not None:
                old.rename(self.out_dir)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.out_dir

    def abort(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> Staging:
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.commit()
        else:
            self.abort()
        return False


@dataclass(frozen=True, eq=False)
class JobOutcome:
    """What a job returns: its JSON report (every figure it printed), exit code and files written.

    ``exit_code`` is 0, or 2 when a stated tolerance, gouge or scallop limit is not met (bad input
    raises :class:`~machsurf_cad.errors.InputError` instead, exit code 1 at the CLI).
    """

    command: str
    report: dict
    exit_code: int = EXIT_OK
    files: tuple = ()
    out_dir: Path | None = None
    result: object = field(default=None, repr=False)


def finish(st: Staging, command: str, report: dict, exit_code: int = EXIT_OK, result=None) -> JobOutcome:
    """Write ``report.json`` (with the file list) into the staging folder and build the outcome."""
    report["command"] = command
    report["units"] = {"length": "mm", "angle": "deg", "time": "s"}
    files = [f for f in st.files if f != "report.json"] + ["report.json"]
    report["files"] = files
    report["exit_code"] = exit_code
    write_json(st.path("report.json"), report)
    return JobOutcome(command, report, exit_code, tuple(files), st.out_dir, result)


def step_face(part: str | None, face: int):
    """Face ``face`` of the STEP file ``part``, or a one-line error."""
    if not part:
        raise InputError("give a STEP file or an example")
    from ..occ import read_step_face

    return read_step_face(part, face)


def face_input(part: str | None, example: str | None, face: int):
    """``(Face, description)`` from a STEP file's face or a named example surface."""
    from ..geometry.face import Face

    if example:
        from ..examples import example as build

        s = build(example, "surface")
        return Face(s, name=s.name or example), f"example {example}"
    f = step_face(part, face)
    return f, f"face {f.index} '{f.name}' of {part}"


def post_options(spec):
    """:class:`~machsurf_cad.cam.PostOptions` from a job spec's feed fields."""
    from ..cam import PostOptions

    return PostOptions(
        feed_mm_min=spec.feed, plunge_mm_min=spec.plunge_feed, spindle_rpm=spec.spindle, tool_number=spec.tool_number
    )


def write_toolpath(st: Staging, tp, spec, stem: str = "toolpath") -> list[str]:
    """The tool path as CSV, APT CLDATA and JSON through the one writer."""
    from ..cam import write_apt, write_csv
    from ..cam import write_json as write_tp_json

    write_csv(st.path(f"{stem}.csv"), tp)
    write_apt(st.path(f"{stem}.apt"), tp, post_options(spec))
    write_tp_json(st.path(f"{stem}.json"), tp)
    return [f"{stem}.csv", f"{stem}.apt", f"{stem}.json"]


__all__ = [
    "Say",
    "quiet",
    "Staging",
    "JobOutcome",
    "finish",
    "face_input",
    "step_face",
    "post_options",
    "write_toolpath",
    "EXIT_OK",
    "EXIT_INPUT",
    "EXIT_TOLERANCE",
]
