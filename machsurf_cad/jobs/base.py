"""What every job shares: staged output folders, the outcome type, inputs from files or examples."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, MachsurfError
from ..results import write_json

Say = Callable[[str], None]
"""Where a job prints its figures (the CLI passes ``print``; the batch runner collects them)."""

EXIT_OK, EXIT_INPUT, EXIT_TOLERANCE = 0, 1, 2


def quiet(msg: str = "") -> None:
    """A :data:`Say` that prints nothing."""


REPORT = "report.json"

MANIFEST = ".machsurf-manifest.json"
"""The list of files a run wrote (relative paths, sizes, SHA-256), kept in its output folder: a folder is
replaced only when it holds exactly what its manifest lists."""


def _tree(folder: Path) -> tuple[dict[str, Path], list[str]]:
    """Files (relative POSIX path -> path) and other entries (symlinks, special files) under ``folder``."""
    files: dict[str, Path] = {}
    other: list[str] = []
    for root, dirs, names in os.walk(folder, followlinks=False):
        base = Path(root)
        for d in list(dirs):
            if (base / d).is_symlink():
                other.append((base / d).relative_to(folder).as_posix())
                dirs.remove(d)
        for n in names:
            p = base / n
            rel = p.relative_to(folder).as_posix()
            if p.is_symlink() or not p.is_file():
                other.append(rel)
            else:
                files[rel] = p
    return files, other


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_manifest(folder: Path) -> Path:
    """Write :data:`MANIFEST` listing every file under ``folder`` (size and SHA-256)."""
    files, _ = _tree(folder)
    entries = {rel: {"bytes": p.stat().st_size, "sha256": _digest(p)} for rel, p in sorted(files.items())}
    entries.pop(MANIFEST, None)
    doc = {"written_by": "machsurf_cad", "files": entries}
    (folder / MANIFEST).write_text(json.dumps(doc, indent=1) + "\n")
    return folder / MANIFEST


def foreign_files(folder: Path) -> list[str]:
    """What in ``folder`` an earlier machsurf run did not write, as relative paths (empty: the folder holds
    exactly one earlier run, unchanged, and may be replaced). A folder without a manifest is all foreign."""
    files, other = _tree(folder)
    try:
        listed = json.loads((folder / MANIFEST).read_text())["files"]
        if not isinstance(listed, dict):
            raise TypeError
    except (OSError, ValueError, KeyError, TypeError):
        return sorted(files) + sorted(other)
    foreign = sorted(other)
    for rel, p in sorted(files.items()):
        if rel == MANIFEST:
            continue
        entry = listed.get(rel)
        if not isinstance(entry, dict) or entry.get("bytes") != p.stat().st_size or entry.get("sha256") != _digest(p):
            foreign.append(rel)
    return foreign


def _legacy_run(folder: Path, files: list[str]) -> bool:
    """An output folder of machsurf before 0.3 (no manifest): its report.json lists every file there."""
    try:
        listed = json.loads((folder / REPORT).read_text()).get("files")
    except (OSError, ValueError, AttributeError):
        return False
    return isinstance(listed, list) and set(files) <= set(listed) | {REPORT}


def _shown(names: list[str]) -> str:
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def check_output_folder(out_dir) -> Path:
    """The real path of the output folder ``out_dir`` (symbolic links followed), or a one-line refusal.

    Refused: an existing file, the current folder or one holding it, and a folder holding anything an
    earlier machsurf run did not write (every file listed, unchanged, in its :data:`MANIFEST`; or, for
    folders of machsurf before 0.3, in its ``report.json``). :func:`~machsurf_cad.jobs.run_job` calls it
    before any work; :class:`Staging` again just before the swap.
    """
    shown = Path(out_dir)
    real = Path(os.path.realpath(out_dir))
    cwd = Path(os.getcwd())
    if real == cwd or real in cwd.parents:
        raise InputError(
            f"output folder {shown} is the current folder or holds it: give a new folder, e.g. -o out "
            "(machsurf replaces its output folder whole)"
        )
    if real.exists() and not real.is_dir():
        raise InputError(f"output folder {shown} is an existing file: choose another -o")
    if not real.is_dir():
        return real
    try:
        foreign = foreign_files(real)
        if foreign and not (real / MANIFEST).exists() and _legacy_run(real, foreign):
            foreign = []
    except OSError as exc:
        raise InputError(f"cannot read output folder {shown}: {exc.strerror or exc}") from None
    if foreign:
        raise InputError(
            f"output folder {shown} holds files machsurf did not write ({_shown(foreign)}): "
            "choose a new or empty folder (machsurf replaces only its own output folders)"
        )
    return real


class Staging:
    """Write outputs into a hidden sibling folder, then make it the output folder, whole.

    Use as a context manager: when the block ends normally the staged folder replaces ``out_dir``
    (an output folder holds exactly one run: files of an earlier run never mix with this one's);
    when it raises (including Ctrl-C or SIGTERM), the staged folder is removed and ``out_dir`` is
    left as it was. ``out_dir`` must be new, empty, or exactly an earlier machsurf run (every file
    in it listed, unchanged, in that run's :data:`MANIFEST`); anything else is refused in one line and
    never deleted - checked when the job starts and again just before the swap. A symbolic link is
    followed (the folder it points to is replaced, the link kept); the current folder or one holding
    it is refused. A write that fails (disk full, file too large, permissions) is reported in one
    line with nothing half-written.
    """

    def __init__(self, out_dir):
        self.shown = Path(out_dir)
        self.out_dir = check_output_folder(out_dir)
        try:
            self.out_dir.parent.mkdir(parents=True, exist_ok=True)
            self.dir = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.partial-", dir=str(self.out_dir.parent)))
        except OSError as exc:
            raise InputError(f"cannot write output folder {self.shown}: {exc.strerror or exc}") from None
        self.files: list[str] = []

    def path(self, name: str) -> Path:
        """Path of output ``name`` inside the staging folder (recorded in :attr:`files`)."""
        if name not in self.files:
            self.files.append(name)
        return self.dir / name

    def commit(self) -> Path:
        """Replace ``out_dir`` by the staged folder (an earlier run's folder is removed after the swap)."""
        check_output_folder(self.shown)  # the user may have put a file there while the job ran
        write_manifest(self.dir)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(self.dir, 0o777 & ~mask)  # mkdtemp's 0700 would hide the results from the user's group
        old = None
        # the swap is not interrupted: Ctrl-C or SIGTERM between its two renames would leave the earlier
        # run under a hidden name and no folder at all; a signal that arrives meanwhile is delivered after
        # it (the run is then complete: its folder holds every file and the manifest)
        blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
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
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.out_dir

    def abort(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> Staging:
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            try:
                self.commit()
                return False
            except BaseException as failed:
                self.abort()
                if isinstance(failed, OSError):
                    raise self._write_error(failed) from None
                raise
        self.abort()
        if isinstance(exc, OSError) and not isinstance(exc, MachsurfError):
            raise self._write_error(exc) from None
        return False

    def _write_error(self, exc: OSError) -> MachsurfError:
        """One line for a failed write (or read) of a file, naming it and the reason."""
        name = exc.filename or ""
        why = exc.strerror or str(exc)
        if not name or str(name).startswith(str(self.dir)) or str(name).startswith(str(self.out_dir)):
            return InputError(f"cannot write output folder {self.shown}: {why} (nothing written)")
        return InputError(f"cannot read {name}: {why}")


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

    return PostOptions(feed=spec.feed, plunge_feed=spec.plunge_feed, spindle=spec.spindle, tool_number=spec.tool_number)


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
    "check_output_folder",
    "MANIFEST",
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
