"""``simulate()``: what a tool path leaves on the part, by the N-buffer method (mm, degrees, seconds)."""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..cam.toolpath import ToolPath
from ..chunking import check_chunks, split_map
from ..errors import InputError
from ..geometry.face import Face
from ..geometry.normals import unit_normals
from ..glossary import renamed
from ..gougecheck import _faces, face_size, motion_radius
from ..results import Progress, Result
from ..typing import MapChunks, PartLike, ToolLike
from .nbuffer import motion_poses, nbuffer
from .region import machined_region, sample_curvature

DEFAULT_HEIGHTS_MM = (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1)
"""Heights (mm) whose exceeded area fraction the report lists."""

BYTES_PER_SAMPLE = 400
"""Memory the simulation needs per nominal sample (points, normals, results, k-d tree, pairs), bytes."""


@dataclass(frozen=True, eq=False)
class SimulationResult(Result):
    """Per nominal sample: the signed thickness left (mm: + material left along the outward normal,
    - gouge: the depth of the nominal point inside the swept cutting body), whether any placement
    reached it, whether it was measured, whether it lies in the machined region, and the figures of the run.

    The material-left figures (``max_scallop``, ``mean_scallop``, ``fraction_above``) are those of the
    **machined region** (under a pass or between two: :mod:`~machsurf_cad.simulation.region`); the
    unmachined **border** around the passes is reported apart (:meth:`border`). Gouges count everywhere.
    A sample that is not ``measured`` (a ray that did not converge could still cut it deeper) counts in
    neither. ``normal_value`` keeps the thickness along the normal also below the nominal (at a convex edge
    it runs under the neighbouring face: not a gouge depth). ``area`` is each sample's share of the
    sampled area (mm^2, a quarter of each grid quad it is a corner of): the areas and area fractions of
    the regions add up to the sampled area; the means are taken over the quads wholly in a region.

    ``quads`` (k, 4) indexes the samples of each face's parameter grid whose four corners lie on the
    trimmed face, for maps."""

    toolpath: ToolPath
    cutter: Any
    points: np.ndarray
    normals: np.ndarray
    face: np.ndarray
    value: np.ndarray
    reached: np.ndarray
    clamped: np.ndarray
    quads: np.ndarray
    face_names: tuple
    resolution_mm: float
    depth_mm: float
    stock_mm: float
    tolerance_mm: float
    motion_step_mm: float
    motion_bound_smooth_mm: float | None
    motion_residual_mm: float
    heights_mm: tuple
    n_placements: int
    n_pairs: int
    n_marched: int
    n_unconverged: int
    time_s: dict
    measured: np.ndarray | None = None
    machined: np.ndarray | None = None
    normal_value: np.ndarray | None = None
    area: np.ndarray | None = None
    n_unconverged_motion: int = 0

    def __post_init__(self) -> None:
        n = self.points.shape[0]
        for name, default in (("measured", True), ("machined", True)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.full(n, default))
        if self.normal_value is None:
            object.__setattr__(self, "normal_value", self.value)
        if self.area is None:
            object.__setattr__(self, "area", np.ones(n))
        super().__post_init__()

    @property
    def areas(self) -> np.ndarray:
        """Area (mm^2) each sample stands for (set in ``__post_init__`` when not given)."""
        assert self.area is not None
        return self.area

    @property
    def known(self) -> np.ndarray:
        """Reached and measured samples."""
        return self.reached & self.measured

    @property
    def in_region(self) -> np.ndarray:
        """Reached, measured samples of the machined region."""
        return self.known & self.machined

    @property
    def on_border(self) -> np.ndarray:
        """Reached, measured samples outside the machined region."""
        return self.known & ~self.machined

    @property
    def scallop(self) -> np.ndarray:
        """Material left (mm, >= 0) at reached measured samples (both regions), 0 where gouged, NaN elsewhere."""
        return np.where(self.known, np.maximum(self.value, 0.0), np.nan)

    @property
    def max_scallop(self) -> float:
        """Most material left in the machined region (mm); NaN where it is empty."""
        v = self.value[self.in_region]
        return float(max(v.max(), 0.0)) if v.size else float("nan")

    @property
    def mean_scallop(self) -> float:
        """Mean material left over the machined region (mm): :meth:`region_mean`."""
        return self.region_mean(np.maximum(self.value, 0.0), self.in_region)

    def region_mean(self, v: np.ndarray, sel: np.ndarray) -> float:
        """Mean of ``v`` over the area of the grid quads whose four corners are all in ``sel`` (each quad's
        corner average: the trapezoidal rule, exact to second order in the sample spacing); the plain mean of
        ``v[sel]`` where no quad lies wholly in it; NaN where ``sel`` is empty."""
        if not sel.any():
            return float("nan")
        q = np.asarray(self.quads, int)
        q = q[sel[q].all(axis=1)] if q.size else q
        if q.size == 0:
            return float(v[sel].mean())
        P = self.points
        a = 0.5 * np.linalg.norm(np.cross(P[q[:, 2]] - P[q[:, 0]], P[q[:, 3]] - P[q[:, 1]]), axis=1)
        return float((a * v[q].mean(axis=1)).sum() / a.sum()) if a.sum() > 0 else float(v[sel].mean())

    @property
    def max_gouge(self) -> float:
        """Deepest cut below the nominal over every measured sample (mm, >= 0): the depth of the nominal point
        inside the swept cutting body."""
        v = self.value[self.known]
        return float(max(-v.min(), 0.0)) if v.size else 0.0

    @property
    def gouged(self) -> bool:
        return self.max_gouge > self.tolerance_mm

    def fraction_above(self, h: float, where: np.ndarray | None = None) -> float:
        """Area fraction (0..1) of the machined region (or of ``where``) with more than ``h`` mm left."""
        sel = self.in_region if where is None else where
        a = self.area[sel]
        return float(a[self.value[sel] > h].sum() / a.sum()) if a.sum() > 0 else 0.0

    def border(self) -> dict:
        """The unmachined border: samples, area (mm^2) and its fraction of the sampled area, material left."""
        b = self.on_border
        v = self.value[b]
        total = float(self.areas.sum())
        return {
            "n_samples": int(b.sum()),
            "area_mm2": float(self.areas[b].sum()),
            "area_fraction": float(self.areas[b].sum()) / total if total > 0 else 0.0,
            "max_material_mm": float(max(v.max(), 0.0)) if v.size else None,
            "mean_material_mm": self.region_mean(np.maximum(self.value, 0.0), b),
            "max_gouge_mm": float(max(-v.min(), 0.0)) if v.size else 0.0,
            "fraction_above_mm": {f"{h:g}": self.fraction_above(h, b) for h in self.heights_mm},
        }

    def not_measured(self, n_where: int = 20) -> dict:
        """Samples a ray that did not converge leaves unknown: counts per face and where (the first few)."""
        bad = ~self.measured
        idx = np.flatnonzero(bad)
        faces, counts = np.unique(self.face[idx], return_counts=True)
        return {
            "n_samples": int(idx.size),
            "n_rays": int(self.n_unconverged),
            "n_motion_probes": int(self.n_unconverged_motion),
            "per_face": [
                {"face": int(f), "name": self.face_names[int(f)], "n_samples": int(c)} for f, c in zip(faces, counts)
            ],
            "where_xyz_mm": self.points[idx[:n_where]].tolist(),
        }

    def report(self) -> dict:
        n = int(self.points.shape[0])
        nr = int(self.reached.sum())
        t = float(self.time_s.get("total_s", float("nan")))
        v = self.value[self.in_region]
        total = float(self.areas.sum())
        known = self.value[self.known]
        return {
            "n_samples": n,
            "resolution_mm": self.resolution_mm,
            "n_faces": len(self.face_names),
            "n_positions": int(self.toolpath.n_positions),
            "n_placements": self.n_placements,
            "reached_fraction": nr / n if n else 0.0,
            "not_reached_fraction": 1.0 - nr / n if n else 0.0,
            "max_scallop_mm": self.max_scallop,
            "mean_scallop_mm": self.mean_scallop,
            "median_scallop_mm": float(np.median(np.maximum(v, 0.0))) if v.size else float("nan"),
            "machined_region": {
                "n_samples": int(self.in_region.sum()),
                "area_mm2": float(self.area[self.in_region].sum()),
                "area_fraction": float(self.area[self.in_region].sum()) / total if total > 0 else 0.0,
            },
            "border": self.border(),
            "not_measured": self.not_measured(),
            "max_gouge_mm": self.max_gouge,
            "gouge_tolerance_mm": self.tolerance_mm,
            "gouged": self.gouged,
            "n_gouged_samples": int((known < -self.tolerance_mm).sum()),
            "gouge_deeper_than_depth": bool(self.max_gouge > self.depth_mm),
            "fraction_above_mm": {f"{h:g}": self.fraction_above(h) for h in self.heights_mm},
            "depth_mm": self.depth_mm,
            "stock_mm": self.stock_mm,
            "motion_step_mm": self.motion_step_mm,
            "motion_bound_smooth_mm": self.motion_bound_smooth_mm,
            "motion_residual_mm": self.motion_residual_mm,
            "n_pairs": self.n_pairs,
            "n_marched": self.n_marched,
            "n_unconverged": self.n_unconverged,
            "samples_x_positions_per_s": n * self.n_placements / t if t > 0 else None,
            "tool": self.cutter.spec(),
            "faces": self.per_face(),
            "time_s": dict(self.time_s),
        }

    def per_face(self) -> list[dict]:
        """Per face: samples, reached and machined fractions, material left in the machined region and on the
        border, max gouge (mm), samples not measured."""
        out = []
        for i, name in enumerate(self.face_names):
            sel = self.face == i
            r = sel & self.known
            v = self.value[r]
            vm = self.value[sel & self.in_region]
            vb = self.value[sel & self.on_border]
            out.append(
                {
                    "face": i,
                    "name": name,
                    "n_samples": int(sel.sum()),
                    "reached_fraction": float((sel & self.reached).sum() / max(1, sel.sum())),
                    "machined_fraction": float((sel & self.in_region).sum() / max(1, sel.sum())),
                    "max_scallop_mm": float(max(vm.max(), 0.0)) if vm.size else None,
                    "mean_scallop_mm": float(np.maximum(vm, 0.0).mean()) if vm.size else None,
                    "border_max_material_mm": float(max(vb.max(), 0.0)) if vb.size else None,
                    "max_gouge_mm": float(max(-v.min(), 0.0)) if v.size else 0.0,
                    "n_not_measured": int((sel & ~self.measured).sum()),
                }
            )
        return out


def sample_areas(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Each sample's share of the sampled area (mm^2): a quarter of every grid quad it is a corner of (the
    quad's area as half the cross product of its diagonals)."""
    out = np.zeros(P.shape[0])
    if Q.size:
        q = np.asarray(Q, int)
        a = 0.5 * np.linalg.norm(np.cross(P[q[:, 2]] - P[q[:, 0]], P[q[:, 3]] - P[q[:, 1]]), axis=1)
        np.add.at(out, q.ravel(), np.repeat(0.25 * a, 4))
    return out


def _face_size(face: Face) -> tuple[float, float]:
    lu, lv = face_size(face)
    return max(lu, 1e-9), max(lv, 1e-9)


def sample_faces(faces, resolution: float, *, max_samples: int):
    """Trim-aware parameter grids about ``resolution`` mm apart with outward unit normals.

    Returns points, normals, face index per sample, and the quads of each grid (sample indices)."""
    sizes = [_face_size(f) for f in faces]
    need = sum((math.ceil(lu / resolution) + 1) * (math.ceil(lv / resolution) + 1) for lu, lv in sizes)
    if need > max_samples:
        raise InputError(
            f"resolution {resolution:g} mm needs about {need:,} samples ({need * BYTES_PER_SAMPLE / 2**30:.1f} GiB), "
            f"more than the budget of {max_samples:,} ({max_samples * BYTES_PER_SAMPLE / 2**30:.1f} GiB): use "
            f"--resolution {resolution * math.sqrt(need / max_samples):.3g} or more"
        )
    P, Nn, F, Q = [], [], [], []
    base = 0
    for i, (face, (lu, lv)) in enumerate(zip(faces, sizes)):
        s = face.surface
        u0, u1, v0, v1 = face.uv_bounds
        nu = int(max(3, math.ceil(lu / resolution) + 1))
        nv = int(max(3, math.ceil(lv / resolution) + 1))
        us, vs = np.linspace(u0, u1, nu), np.linspace(v0, v1, nv)
        d = s.derivatives_grid(us, vs, 1)
        U, V = np.meshgrid(us, vs, indexing="ij")
        n = unit_normals(d.su, d.sv, s.scale, U, V, check=False, surface=s)
        if face.reversed:
            n = -n
        keep = face.contains_uv(U.ravel(), V.ravel()) if face.is_trimmed else np.ones(U.size, bool)
        keep &= np.all(np.isfinite(n.reshape(-1, 3)), axis=1)
        idx = np.full(U.size, -1)
        idx[keep] = base + np.arange(int(keep.sum()))
        g = idx.reshape(nu, nv)
        q = np.stack([g[:-1, :-1], g[1:, :-1], g[1:, 1:], g[:-1, 1:]], axis=-1).reshape(-1, 4)
        Q.append(q[(q >= 0).all(axis=1)])
        P.append(d.point.reshape(-1, 3)[keep])
        Nn.append(n.reshape(-1, 3)[keep])
        F.append(np.full(int(keep.sum()), i))
        base += int(keep.sum())
    return np.concatenate(P), np.concatenate(Nn), np.concatenate(F), np.concatenate(Q)


@renamed(cutter="tool", tolerance="gouge_tolerance")
def simulate(
    part: PartLike,
    toolpath: ToolPath,
    tool: ToolLike | None = None,
    *,
    resolution: float | None = None,
    gouge_tolerance: float = 0.01,
    depth: float = 1.0,
    stock: float = 1.0,
    motion_step: float | None = None,
    heights: tuple = DEFAULT_HEIGHTS_MM,
    max_samples: int = 10_000_000,
    chunks: int = 1,
    map_chunks: MapChunks = None,
    progress: Progress | None = None,
) -> SimulationResult:
    """Simulate the cut of a tool path on the nominal faces (N-buffer) and measure what it leaves.

    The material left is reported for the machined region (under the cutting passes and between
    adjacent ones, :mod:`~machsurf_cad.simulation.region`) and, apart, for the unmachined border around
    them (``report()["border"]``); gouges are the depth of the nominal point inside the swept cutting
    body, the figure :func:`~machsurf_cad.verify` measures. Samples a ray that did not converge leaves
    unknown are not measured: counted and located (``report()["not_measured"]``), in no figure.

    Parameters
    ----------
    part : Face, BSplineSurface or sequence of them
        The faces to simulate (trimmed regions respected); outward normals from the faces.
    toolpath : ToolPath
        Every move is simulated (the tool removes material whatever the move kind).
    tool : Cutter, optional
        The tool; the path's own cutter when not given. Its cutting part cuts (shank and holder
        collisions are :func:`~machsurf_cad.verify`'s).
    resolution : float, optional
        Distance between nominal samples, mm; default: about 200,000 samples over the faces.
    gouge_tolerance : float
        A cut deeper than this below the nominal is a gouge (mm).
    depth, stock : float
        Length of each sample's blade inside and outside the part, mm: a placement is looked for within
        them; material thicker than ``stock`` is not reached. A gouge's depth (inside the swept body)
        is measured whatever ``depth``; ``clamped`` flags a cut along the normal beyond it.
    motion_step : float, optional
        Largest move of any point of the cutting part between simulated placements, mm (the motion
        between them is then refined); default: the tool radius / 10.
    heights : tuple of float
        Heights (mm) whose exceeded area fractions are reported (of the machined region; of the border
        apart).
    max_samples : int
        Memory budget in samples (about 400 bytes each); a finer resolution is refused with its size.
    chunks : int
        Split the samples into this many chunks, simulated independently (each sample's result does
        not depend on the others: the figures are the same to the last digit).
    map_chunks : callable, optional
        ``map``-like callable running the chunks, e.g. over a Dask cluster
        (:func:`machsurf_cad.batchrun.dask_map`); default: one after the other here.
    progress : Progress, optional

    Returns
    -------
    SimulationResult

    Raises
    ------
    InputError
        No cutter, a resolution, depth or stock not > 0, a resolution over the memory budget, a path
        that never touches the faces ("no contact").

    Examples
    --------
    A ball end mill R = 5 mm on the plane z = 0, two passes 2 mm apart: the scallop is
    ``R - sqrt(R^2 - s^2/4)``.

    >>> import numpy as np
    >>> from machsurf_cad import BallEndMill, ToolPath, simulate
    >>> from machsurf_cad.geometry.builders import plane_patch
    >>> x = np.linspace(-3, 3, 31)
    >>> tips = [np.stack([x, np.full_like(x, y), np.zeros_like(x)], 1) for y in (-1.0, 1.0)]
    >>> tp = ToolPath.from_passes(tips, [np.tile([0.0, 0, 1], (31, 1))] * 2, cutter=BallEndMill(10))
    >>> res = simulate(plane_patch((-1, -1, 0), (2, 0, 0), (0, 2, 0)), tp, resolution=0.05)
    >>> round(res.max_scallop, 4), round(5 - (25 - 1) ** 0.5, 4)
    (0.101, 0.101)
    """
    t0 = time.perf_counter()
    from .. import checks

    toolpath = checks.toolpath(toolpath)
    c = checks.tool(tool) if tool is not None else toolpath.cutter
    if c is None:
        raise InputError("simulate needs the tool: the path carries no cutter (give --tool)")
    resolution = None if resolution is None else checks.positive("resolution", resolution)
    motion_step = None if motion_step is None else checks.positive("motion step", motion_step)
    gouge_tolerance = checks.positive("tolerance", gouge_tolerance)
    for name, val in (("depth", depth), ("stock", stock)):
        if checks.positive(name, val) > 10 * float(c.D):  # the rays march through it: kilometres march for ever
            raise InputError(f"{name} {val:g} mm is more than 10 times the tool's diameter ({c.D:g} mm)")
    faces = _faces(part, "simulate")
    if resolution is None:
        area = sum(a * b for a, b in map(_face_size, faces))
        resolution = max(math.sqrt(area / 200_000), 1e-3)
    R = float(c.max_radius())
    step = motion_step if motion_step is not None else 0.1 * R
    P, N, F, Q = sample_faces(faces, resolution, max_samples=max_samples)
    t1 = time.perf_counter()
    T, A, _ = motion_poses(toolpath.tip, toolpath.axis, step, float(c.length))
    rho = motion_radius(c)
    smooth = not _has_sharp_corner(c)
    # how much lower the swept motion can cut than its sampled placements: the sagitta of the smallest
    # profile radius over a step (no sharp corner), else half a step (a corner sweeping across)
    margin = step * step / (8 * rho) if smooth else 0.5 * step
    kw: dict[str, Any] = {"depth": depth, "stock": stock, "margin": margin, "sharp": not smooth}
    if check_chunks(chunks) == 1:
        kw["progress"] = progress
    out = _merge_chunks(split_map(functools.partial(_nbuffer_chunk, c, T, A, kw), [P, N], chunks, map_chunks))
    t2 = time.perf_counter()
    if not out["reached"].any():
        raise InputError(
            f"no contact: no tool placement comes within {stock:g} mm of the {len(faces)} face(s) "
            "(wrong part, faces or tool path?)"
        )
    machined = machined_region(
        c, toolpath, P, N, out["reached"], depth=depth, stock=stock, touch=gouge_tolerance,
        curvature=sample_curvature(P, N, Q),
    )  # fmt: skip
    t3 = time.perf_counter()
    times = {"sampling_s": t1 - t0, "simulation_s": t2 - t1, "region_s": t3 - t2, "total_s": t3 - t0}
    figures = dict(
        resolution_mm=float(resolution),
        depth_mm=float(depth),
        stock_mm=float(stock),
        tolerance_mm=float(gouge_tolerance),
        motion_step_mm=step,
        motion_bound_smooth_mm=step * step / (8 * rho) if smooth else None,
        heights_mm=tuple(float(h) for h in heights),
        n_placements=int(T.shape[0]),
        time_s=times,
    )
    return _result(toolpath, c, faces, (P, N, F, Q), out, machined, figures)


def _result(toolpath, cutter, faces, samples, out: dict, machined, figures: dict) -> SimulationResult:
    """The :class:`SimulationResult` of a run: samples ``(P, N, F, Q)``, the merged N-buffer output, the
    machined region and the run's figures."""
    P, N, F, Q = samples
    return SimulationResult(
        toolpath=toolpath,
        cutter=cutter,
        points=P,
        normals=N,
        face=F,
        value=out["t"],
        reached=out["reached"],
        clamped=out["clamped"],
        quads=Q,
        face_names=tuple(f.name or f"face_{i}" for i, f in enumerate(faces)),
        motion_residual_mm=out["motion_residual_mm"],
        n_pairs=out["n_pairs"],
        n_marched=out["n_marched"],
        n_unconverged=out["n_unconverged"],
        measured=out["measured"],
        machined=machined,
        normal_value=out["t_normal"],
        area=sample_areas(P, Q),
        n_unconverged_motion=out["n_unconverged_motion"],
        **figures,
    )


def _nbuffer_chunk(cutter, T, A, kw, P, N) -> dict:
    """One chunk of samples (module level: it travels to other processes)."""
    return nbuffer(cutter, P, N, T, A, **kw)


def _merge_chunks(parts: list) -> dict:
    if len(parts) == 1:
        return parts[0]
    keys = ("t", "t_normal", "reached", "measured", "clamped", "pose")
    out: dict[str, Any] = {k: np.concatenate([p[k] for p in parts]) for k in keys}
    for k in ("n_pairs", "n_marched", "n_refined", "n_unconverged", "n_unconverged_motion"):
        out[k] = int(sum(p[k] for p in parts))
    out["motion_residual_mm"] = float(max(p["motion_residual_mm"] for p in parts))
    return out


def _has_sharp_corner(cutter) -> bool:
    """True when two cutting profile segments meet at an angle (a flat end mill's rim, a cone tip)."""
    segs = cutter.profile()
    tang = []
    for seg in segs:
        p = seg.points(2001)
        tang.append((p[1] - p[0], p[-1] - p[-2]))
    for (_, end), (start, _) in zip(tang[:-1], tang[1:]):
        a = end / np.linalg.norm(end)
        b = start / np.linalg.norm(start)
        if a @ b < math.cos(math.radians(1.0)):
            return True
    return False


__all__ = ["simulate", "SimulationResult", "sample_faces", "sample_areas", "DEFAULT_HEIGHTS_MM"]
