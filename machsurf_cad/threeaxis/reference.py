"""OpenCAMLib's drop-cutter on a triangle mesh: the open 3-axis reference the exact drop-cutter is
compared with (tests and benchmarks). Needs ``pip install opencamlib`` (Python 3.11 wheels)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def has_opencamlib() -> bool:
    """True when OpenCAMLib can be imported."""
    try:
        import opencamlib  # noqa: F401
    except ImportError:
        return False
    return True


def ocl_cutter(cutter):
    """The OpenCAMLib cutter of a ball, flat or bull-nose end mill (same D, r and length)."""
    import opencamlib as ocl

    radii = cutter.end_mill_radii("OpenCAMLib's cutters")
    length = float(cutter.length)
    if radii.is_ball:
        return ocl.BallCutter(float(cutter.D), length)
    if radii.is_flat:
        return ocl.CylCutter(float(cutter.D), length)
    return ocl.BullCutter(float(cutter.D), float(radii.r), length)


def ocl_drop_cutter(points, triangles, cutter, xy, *, z_min: float | None = None) -> np.ndarray:
    """Tip heights of OpenCAMLib's ``BatchDropCutter`` on the mesh ``(points, triangles)`` at ``xy`` (mm).

    Points where the tool meets no triangle stay at ``z_min`` (default: below the mesh) and are
    returned as NaN."""
    import opencamlib as ocl

    pts = np.asarray(points, float)
    tri = np.asarray(triangles, np.int64)
    if tri.size == 0:
        raise InputError("OpenCAMLib needs at least one triangle")
    surf = ocl.STLSurf()
    P = [ocl.Point(*map(float, p)) for p in pts]
    for a, b, c in tri:
        surf.addTriangle(ocl.Triangle(P[a], P[b], P[c]))
    bdc = ocl.BatchDropCutter()
    bdc.setSTL(surf)
    tool = ocl_cutter(cutter)  # OpenCAMLib keeps a raw pointer: hold the object until run() is done
    bdc.setCutter(tool)
    z0 = float(pts[:, 2].min() - 1000.0) if z_min is None else float(z_min)
    for x, y in np.asarray(xy, float):
        bdc.appendPoint(ocl.CLPoint(float(x), float(y), z0))
    bdc.run()
    z = np.array([p.z for p in bdc.getCLPoints()])
    del tool, surf
    return np.where(z <= z0 + 1e-9, np.nan, z)
