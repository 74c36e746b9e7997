"""Example tool motions (mm) for swept envelopes."""

from __future__ import annotations

import numpy as np

from ..sweep.core import Motion


def sine_motion() -> Motion:
    """Tip along a 100 mm sine-wave path in the XY plane, axis turning from (0, -0.2, 1) to (0.3, 0.1, 1)."""
    return Motion.interpolated_axis(
        lambda t: np.stack([100 * np.asarray(t), 20 * np.sin(np.pi * np.asarray(t)), 0 * np.asarray(t)], -1),
        (0.0, -0.2, 1.0),
        (0.3, 0.1, 1.0),
        label="sine path, turning axis",
    )


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
