"""The JSON path format of ``machsurf envelope --path`` (tip points in mm, optional axes)."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import InputError
from .core import Motion


def load_path(path) -> Motion:
    """A motion from JSON: ``{"points": [[x, y, z], ...], "axes": [[i, j, k], ...]}`` (axes optional,
    or ``"axis": [i, j, k]`` constant); tip points in mm, interpolated by a cubic B-spline."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"path file not found: {p}")
    try:
        d = json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"path file {p} is not valid JSON: {exc.msg if hasattr(exc, 'msg') else exc}") from None
    if not isinstance(d, dict) or "points" not in d:
        raise InputError(f"path file {p} needs a 'points' list")
    return Motion.from_points(d["points"], d.get("axes"), d.get("axis", (0.0, 0.0, 1.0)), label=p.name)
