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
    return OclBatch(points, triangles).drop(cutter, xy, z_min=z_min)


class OclBatch:
    """OpenCAMLib's ``BatchDropCutter`` on one mesh, set up apart from its runs, so that a benchmark times
    the drop-cutter alone (as machsurf's own face set and sample pool are prepared before its queries).

    ``OclBatch(points, triangles)`` builds the mesh (``STLSurf``); :meth:`prepare` a batch on it (its
    k-d tree, the cutter, the query points); :meth:`run` drops it and reads the heights."""

    def __init__(self, points, triangles):
        import opencamlib as ocl

        pts = np.asarray(points, float)
        tri = np.asarray(triangles, np.int64)
        if tri.size == 0:
            raise InputError("OpenCAMLib needs at least one triangle")
        self.surf = ocl.STLSurf()
        P = [ocl.Point(*map(float, p)) for p in pts]
        for a, b, c in tri:
            self.surf.addTriangle(ocl.Triangle(P[a], P[b], P[c]))
        self.z_low = float(pts[:, 2].min() - 1000.0)

    def prepare(self, cutter, xy, *, z_min: float | None = None):
        """A batch of the query points ``xy`` (mm) for ``cutter``, ready to :meth:`run`."""
        import opencamlib as ocl

        bdc = ocl.BatchDropCutter()
        bdc.setSTL(self.surf)
        tool = ocl_cutter(cutter)  # OpenCAMLib keeps a raw pointer: held with the batch until run() is done
        bdc.setCutter(tool)
        z0 = self.z_low if z_min is None else float(z_min)
        for x, y in np.asarray(xy, float):
            bdc.appendPoint(ocl.CLPoint(float(x), float(y), z0))
        return bdc, tool, z0

    @staticmethod
    def run(batch) -> np.ndarray:
        """Drop a prepared batch: the tip heights, NaN where the tool meets no triangle."""
        bdc, _tool, z0 = batch
        bdc.run()
        z = np.array([p.z for p in bdc.getCLPoints()])
        return np.where(z <= z0 + 1e-9, np.nan, z)

    def drop(self, cutter, xy, *, z_min: float | None = None) -> np.ndarray:
        """:meth:`prepare` and :meth:`run` in one."""
        return self.run(self.prepare(cutter, xy, z_min=z_min))
