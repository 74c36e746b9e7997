"""The 3-axis machining surface of whole parts: the exact drop-cutter heights as a certified
height-field B-spline (tool tips over the plan box), for any cutter, flat spots and creases included.

The fit is the shared certified engine (:func:`machsurf_cad.approx.fit_surface`): knots are refined
where the error measured against the exact drop-cutter on points the fit never used exceeds the
tolerance; where the tool positions crease (the contact jumps between faces or regions) the refinement
concentrates along the crease. Plan points with no face under the tool are filled with the lowest
height found (their share is reported).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..approx import SurfaceFit, fit_surface
from ..errors import InputError
from ..glossary import renamed
from ..results import Progress
from ..typing import FacesLike, ToolLike, Vector3
from .dropcutter import drop_cutter, machining_face_set


@renamed(cutter="tool", tolerance_mm="tolerance", seed_spacing_mm="seed_spacing")
def cl_surface(
    faces: FacesLike,
    tool: ToolLike,
    *,
    check_faces: FacesLike = (),
    tolerance: float,
    axis: Vector3 = (0.0, 0.0, 1.0),
    extent: Sequence[float] | None = None,
    degree: int = 3,
    max_poles: int = 40000,
    seed_spacing: float | None = None,
    progress: Progress | None = None,
) -> tuple[SurfaceFit, dict]:
    """Certified height-field B-spline of the tool tips over the machined faces' plan box.

    Returns the fit (its ``max_error`` measured against the exact drop-cutter at unseen points, mm) and
    figures: the plan box, the share of the box with no face under the tool. Raises
    :class:`~machsurf_cad.errors.ToleranceError` (with the error reached) when the pole budget ends
    first.
    """
    if not (tolerance > 0 and math.isfinite(tolerance)):
        raise InputError(f"tolerance must be > 0 mm, got {tolerance}")
    fs, box = machining_face_set(faces, check_faces, tool, axis=axis, seed_spacing=seed_spacing,
                                 what="the CL surface")  # fmt: skip
    extent = box if extent is None else extent
    frame = fs.frame
    stats = {"n_evaluated": 0, "n_without_face": 0}
    floor: list[float] = []

    def f(us, vs):
        X, Y = np.meshgrid(us, vs, indexing="ij")
        r = drop_cutter(None, tool, np.column_stack([X.ravel(), Y.ravel()]), face_set=fs)
        z = r.height
        miss = ~np.isfinite(z)
        stats["n_evaluated"] += int(z.size)
        stats["n_without_face"] += int(miss.sum())
        if not floor:
            if miss.all():
                raise InputError("no face lies under the tool anywhere in the plan box")
            floor.append(float(np.nanmin(z)))
        z = np.where(miss, floor[0], z)
        P = np.stack([X, Y, z.reshape(X.shape)], axis=-1)
        return P @ frame

    fit = fit_surface(
        f,
        extent,
        tolerance=tolerance,
        degree=(degree, degree),
        max_poles=max_poles,
        name="cl_surface",
        progress=progress,
    )
    info = {
        "extent_mm": [float(e) for e in extent],
        "share_without_face": stats["n_without_face"] / max(1, stats["n_evaluated"]),
        "n_drop_cutter_evaluations": stats["n_evaluated"],
    }
    return fit, info
