"""What the jobs read: the part's faces, a tool-path file and its cutter, shank and holder texts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import InputError
from .base import Say


def shank(text: str | None, what: str):
    """``D=..,L=..`` (mm) as a :class:`~machsurf_cad.cutters.Shank`."""
    if not text:
        return None
    from ..cutters import Shank

    kw = {}
    for part in text.split(","):
        k, _, v = part.partition("=")
        k = k.strip().upper()
        if k not in ("D", "L") or not v.strip():
            raise InputError(f"--{what} must be D=..,L=.. (mm), got {text!r}")
        try:
            kw[k] = float(v)
        except ValueError:
            raise InputError(f"--{what} {k} must be a number, got {v!r}") from None
    if set(kw) != {"D", "L"}:
        raise InputError(f"--{what} needs D and L (mm), got {text!r}")
    return Shank(kw["D"], kw["L"])


def cutter_with_body(tool: str, shank_text: str | None, holder_text: str | None):
    """The cutter of ``tool`` with the shank and holder texts (``D=..,L=..``); a holder narrower than the
    shank it grips is refused."""
    import dataclasses

    from ..toolspec import parse_cutter

    cutter = parse_cutter(tool)
    if not (shank_text or holder_text):
        return cutter
    s, h = shank(shank_text, "shank"), shank(holder_text, "holder")
    grip = s.diameter if s is not None else cutter.D
    if h is not None and h.diameter < grip:
        raise InputError(
            f"--holder D={h.diameter:g} mm is narrower than the {'shank' if s is not None else 'tool'} it holds "
            f"(D={grip:g} mm): give the holder's own diameter"
        )
    return dataclasses.replace(cutter, shank=s, holder=h)  # type: ignore[type-var]


def check_clearance(clearance: float, faces) -> None:
    """Refuse a clearance larger than the part itself (its poles' bounding box diagonal): a unit mistake,
    and links that high make the path and its check needlessly long."""
    from ..machining.toolpath import part_sphere

    size = 2.0 * part_sphere(faces, 0.0)[1]
    if clearance > max(size, 1.0):
        raise InputError(
            f"clearance {clearance:g} mm is larger than the part ({size:.4g} mm across its bounding box): "
            "check the units (mm)"
        )


def part_faces(part: str, faces: str = "all"):
    """Faces of a STEP part: ``all`` or a comma list of indices."""
    from ..occ import read_step_faces

    if faces.strip().lower() == "all":
        return read_step_faces(part)
    try:
        idx = [int(x) for x in faces.split(",") if x.strip()]
    except ValueError:
        raise InputError(f"--faces must be all or indices like 0,3,5; got {faces!r}") from None
    return read_step_faces(part, idx)


def body_faces(faces, index: int):
    """The faces of the body (solid) that face ``index`` bounds: a STEP assembly's other bodies are other parts.
    All of them when the face bounds no solid or the file holds one."""
    body = next((f.body for f in faces if f.index == index), -1)
    return [f for f in faces if f.body == body] if body >= 0 else list(faces)


def read_toolpath_file(path: Path):
    """A tool path from our CSV or an APT CLDATA file, by its suffix."""
    from ..cam import read_apt, read_csv

    suffix = path.suffix.lower()
    if not path.is_file():
        raise InputError(f"tool path file not found: {path}")
    if suffix == ".csv":
        return read_csv(path)
    if suffix in (".apt", ".cls", ".cl", ".aptsource", ".txt"):
        return read_apt(path)
    raise InputError(f"tool path must be .csv (ours) or APT CLDATA (.apt, .cls, .cl), got {path.name}")


def toolpath_and_cutter(toolpath: str, tool: str | None, say: Say):
    """The tool path file and its cutter: ``tool`` (a cutter string) wins over the file's CUTTER, with a
    warning when they disagree; one of them must exist."""
    from ..toolspec import parse_cutter

    path = Path(toolpath)
    tp = read_toolpath_file(path)
    cutter: Any = parse_cutter(tool) if tool else tp.cutter
    if cutter is None:
        raise InputError(f"{path.name} names no usable CUTTER: give --tool")
    for note in tp.info.get("assumed") or []:
        say(f"note: {path.name} does not say it: assumed {note}")
    if tool and tp.cutter is not None and tp.cutter.apt_parameters() != cutter.apt_parameters():
        say(f"warning: {path.name} names the tool {tp.cutter.spec()}, --tool says {cutter.spec()}: using --tool")
    return path, tp, cutter


__all__ = ["body_faces", "part_faces", "read_toolpath_file", "toolpath_and_cutter", "shank"]
