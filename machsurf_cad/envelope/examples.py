"""Example tool motions (mm) and the JSON path format."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from .core import Motion


def sine_motion() -> Motion:
    """Tip along a 100 mm sine-wave path in the XY plane, axis turning from (0, -0.2, 1) to (0.3, 0.1, 1)."""
    return Motion.interpolated_axis(
        lambda t: np.stack([100 * np.asarray(t), 20 * np.sin(np.pi * np.asarray(t)), 0 * np.asarray(t)], -1),
        (0.0, -0.2, 1.0), (0.3, 0.1, 1.0), label="sine path, turning axis")


def line_motion() -> Motion:
    """Straight 100 mm path along X, axis Z."""
    return Motion.line((0, 0, 0), (100, 0, 0), (0, 0, 1), label="straight line, axis z")


def helix_motion() -> Motion:
    """Quarter helix of radius 60 mm, pitch 40 mm, axis tilted 15 deg towards the helix axis."""
    def tip(t):
        t = np.asarray(t) * np.pi / 2
        return np.stack([60 * np.cos(t), 60 * np.sin(t), 40 * t / (2 * np.pi)], -1)

    def axis(t):
        t = np.asarray(t) * np.pi / 2
        s = np.sin(np.radians(15))
        return np.stack([-s * np.cos(t), -s * np.sin(t), np.full(t.shape, np.cos(np.radians(15)))], -1)

    return Motion(tip, axis, (0.0, 1.0), "quarter helix")


EXAMPLES = {"sine": sine_motion, "line": line_motion, "helix": helix_motion}


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
