"""The tool body placed by the exact machining maps on a grid, each placement checked against faces (mm).

Used by the loop detection of 3-axis bull and flat end mills and by the automatic lead's body check.
"""

from __future__ import annotations

import numpy as np


def gouging_placements(maps, us, vs, inside, faces, *, tolerance: float):
    """The tool placed by the exact maps at every grid point inside the face, each checked alone against
    ``faces`` (:func:`machsurf_cad.verify`): grid masks of the gouging placements and their depths (mm),
    and the tips (mm)."""
    from ..cam.toolpath import Move, ToolPath
    from ..gougecheck import GOUGE, verify

    tips, axes = maps.tool_placements(us, vs)
    bad = np.zeros(inside.shape, bool)
    depth = np.zeros(inside.shape)
    sel = np.nonzero(inside.ravel())[0]
    if sel.size:
        tp = ToolPath(
            tips.reshape(-1, 3)[sel],
            axes.reshape(-1, 3)[sel],
            np.full(sel.size, Move.CUT),
            np.arange(sel.size),
            cutter=maps.cutter,
        )
        res = verify(faces, tp, gouge_tolerance=tolerance, step=1e9, angle_step=180.0)  # each placement alone
        bad.ravel()[sel] = res.status == GOUGE
        depth.ravel()[sel] = res.gouge_depth
    return bad, depth, tips


__all__ = ["gouging_placements"]
