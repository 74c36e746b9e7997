"""Loop (self-intersection) detection on offset-type machining surfaces (lengths in mm).

* **local**: the offset distance reaches a concave principal radius of curvature,
  ``r * kappa >= 1`` (kappa signed against the outward normal, positive where the face
  bends towards the tool).
* **fold**: the exact map's Jacobian turns over, ``(X_u x X_v) . n <= 0``: the surface
  folds back on itself (this is how the local loop of any map shows, S2 included).
* **global**: a point of S1 = F + r n lies closer to F than r: the ball/corner centre
  would gouge the face somewhere else.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import MachsurfError
from ..results import Result


@dataclass(frozen=True, eq=False)
class LoopRegion(Result):
    """A set of flagged parameter samples: where, how many, how bad."""

    kind: str
    surface: str
    n_samples: int
    uv_box: tuple
    xyz_box: tuple
    worst_uv: tuple
    worst_xyz: tuple
    worst_value: float
    uv: np.ndarray
    xyz: np.ndarray

    def describe(self) -> str:
        u0, u1, v0, v1 = self.uv_box
        return (
            f"{self.kind} loop on {self.surface}: {self.n_samples} sample(s) in u [{u0:.4g}, {u1:.4g}] x "
            f"v [{v0:.4g}, {v1:.4g}], worst at xyz ({', '.join(f'{x:.3f}' for x in self.worst_xyz)}) mm"
        )

    def report(self) -> dict:
        return {
            "kind": self.kind,
            "surface": self.surface,
            "n_samples": self.n_samples,
            "uv_box": list(self.uv_box),
            "xyz_box": [list(self.xyz_box[0]), list(self.xyz_box[1])],
            "worst_uv": list(self.worst_uv),
            "worst_xyz": list(self.worst_xyz),
            "worst_value": self.worst_value,
        }


@dataclass(frozen=True, eq=False)
class LoopReport(Result):
    regions: tuple
    grid: tuple
    mask: np.ndarray | None = None
    us: np.ndarray | None = None
    vs: np.ndarray | None = None

    @property
    def found(self) -> bool:
        return len(self.regions) > 0

    def report(self) -> dict:
        return {"found": self.found, "grid": list(self.grid), "regions": [r.report() for r in self.regions]}


class LoopError(MachsurfError):
    """The machining surface has loops: exporting it would let the tool gouge."""

    exit_code = 1

    def __init__(self, message: str, loops: LoopReport):
        super().__init__(message)
        self.loops = loops


def region_from_mask(kind: str, surface: str, mask: np.ndarray, U, V, xyz, value) -> LoopRegion | None:
    """Summarise flagged grid samples (``mask``) as one region; ``value`` ranks their badness."""
    if not np.any(mask):
        return None
    uu, vv, pts, val = U[mask], V[mask], xyz[mask], value[mask]
    w = int(np.argmax(val))
    return LoopRegion(
        kind,
        surface,
        int(mask.sum()),
        (float(uu.min()), float(uu.max()), float(vv.min()), float(vv.max())),
        (pts.min(axis=0).tolist(), pts.max(axis=0).tolist()),
        (float(uu[w]), float(vv[w])),
        tuple(float(x) for x in pts[w]),
        float(val[w]),
        np.stack([uu, vv], 1),
        pts,
    )


def fold_mask(X: np.ndarray, us: np.ndarray, vs: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the grid map ``X`` (nu, nv, 3) turns over relative to ``n``: returns (mask, -J)."""
    xu = np.gradient(X, us, axis=0)
    xv = np.gradient(X, vs, axis=1)
    j = np.einsum("...i,...i->...", np.cross(xu, xv), n)
    scale = np.linalg.norm(xu, axis=-1) * np.linalg.norm(xv, axis=-1)
    jn = j / np.where(scale > 0, scale, 1.0)
    return jn <= 0.0, -jn


def hole_loops(report: LoopReport, margin_cells: int = 2):
    """Closed parameter-space polylines around the flagged samples (one per connected region),
    grown by ``margin_cells`` grid cells, as degree-1 closed 2-D B-spline loops.

    Raises :class:`LoopError` when a region reaches the face's parameter boundary: cutting it
    would need a boolean with the outer loop, which is not done here.
    """
    import contourpy

    from ..geometry.bspline import BSplineCurve

    m = np.asarray(report.mask, bool)
    grown = m.copy()
    for _ in range(margin_cells):
        g = grown.copy()
        g[1:, :] |= grown[:-1, :]
        g[:-1, :] |= grown[1:, :]
        g[:, 1:] |= grown[:, :-1]
        g[:, :-1] |= grown[:, 1:]
        grown = g
    if grown[0, :].any() or grown[-1, :].any() or grown[:, 0].any() or grown[:, -1].any():
        raise LoopError(
            "a loop region reaches the edge of the face: it cannot be trimmed away as a hole; "
            "use loops='flag' or a smaller tool",
            report,
        )
    gen = contourpy.contour_generator(x=report.vs, y=report.us, z=grown.astype(float), line_type="Separate")
    loops = []
    for line in gen.lines(0.5):
        uv = np.stack([line[:, 1], line[:, 0]], 1)
        if np.linalg.norm(uv[0] - uv[-1]) > 1e-12:
            uv = np.vstack([uv, uv[:1]])
        n = uv.shape[0]
        knots = np.arange(n, dtype=float)
        mults = np.ones(n, dtype=int)
        mults[0] = mults[-1] = 2
        loops.append((BSplineCurve(1, knots, mults, uv),))
    return loops
