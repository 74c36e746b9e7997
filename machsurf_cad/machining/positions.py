"""Tool positions on a machining surface at (u, v) of the nominal face: contact, S1, CL, tip and axis (mm).

Shared by the plane-section and iso-parametric passes (:mod:`.toolpath`) and the iso-scallop passes
(:mod:`.isoscallop`).
"""

from __future__ import annotations

import numpy as np

from ..geometry.normals import unit_normals
from .surfaces import MachiningSurface, recover_axis


def _positions(ms: MachiningSurface, uv: np.ndarray) -> dict:
    """Contact ``cc``, ``k`` (S1), ``cl``, ``tip`` and unit ``axis`` at ``uv``; ``axis_err`` (deg) measured
    against the exact axis on a sixteenth of the points (5 axes)."""
    em = ms.cutter.end_mill_radii("tool paths on machining surfaces")
    r = em.r
    F = ms.nominal.surface
    d = F.derivatives(uv[:, 0], uv[:, 1], 1)
    n = unit_normals(d.su, d.sv, F.scale)
    if ms.nominal.reversed:
        n = -n
    k = ms.s1.surface.evaluate(uv[:, 0], uv[:, 1])
    maps = ms.maps
    if ms.axes == 5:
        assert ms.s2 is not None  # 5 axes always have S2
        cl = ms.s2.surface.evaluate(uv[:, 0], uv[:, 1])
        axis = recover_axis(k, cl, n, ball_length=ms.axis_length if em.is_ball else None)
        if em.is_ball:
            cl = k  # the ball's CL is its centre; S2 only orients the axis
        # measured against the exact axis
        exact = np.stack([maps.tool_axis(np.array([a]), np.array([b]))[0, 0] for a, b in uv[:: max(1, len(uv) // 16)]])
        got = axis[:: max(1, len(uv) // 16)]
        axis_err = float(np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", exact, got), -1, 1))).max())
    else:
        axis = np.broadcast_to(np.asarray(ms.strategy.direction), k.shape).copy()
        cl = k + r * axis if ms.tip else k
        axis_err = 0.0
    tip = cl - r * axis
    return {"cc": d.point, "k": k, "cl": cl, "tip": tip, "axis": axis, "axis_err": axis_err}
