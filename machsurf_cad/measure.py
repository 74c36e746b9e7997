"""Signed deviation of a candidate (surface, mesh or point set) from a reference surface.

The distance of each candidate point is measured to its closest point on the reference face,
trimming honoured (:func:`~machsurf_cad.geometry.closest.closest_points`: every basin of the
distance seeded from a grid of surface samples and refined by Newton's method, feet outside the
trimming loops dropped, the loops' 3-D curves searched too; closed directions are searched across
their seam). The sign is that of
``(p - foot) . n``, ``n`` the reference's outward normal (``su x sv`` for a surface; the
face's outward normal for a :class:`~machsurf_cad.geometry.face.Face`). All lengths in mm.

Examples
--------
>>> from machsurf_cad.geometry import builders
>>> plane = builders.plane_patch()
>>> lifted = builders.plane_patch(origin=(0, 0, 0.5))
>>> d = deviation(plane, lifted, samples=20)
>>> round(d.max_abs, 12), round(d.mean, 12)
(0.5, 0.5)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from .errors import InputError
from .geometry.bspline import BSplineSurface
from .geometry.closest import closest_points, inside_face
from .geometry.face import Face
from .glossary import renamed
from .results import Result
from .typing import ArrayLike, FaceLike, ProgressLike


@dataclass(frozen=True, eq=False)
class Projection(Result):
    """Closest points on a surface: parameters ``uv`` (n, 2), ``foot`` (n, 3), ``normal`` (n, 3)."""

    uv: np.ndarray
    foot: np.ndarray
    normal: np.ndarray
    on_boundary: np.ndarray
    converged: np.ndarray


@dataclass(frozen=True, eq=False)
class DeviationResult(Result):
    """Signed distances (mm) of candidate points to a reference and their statistics.

    ``signed[i]`` is the distance of ``points[i]`` to the reference, positive on the side of
    the reference normal. ``grid_shape`` is set when the points come from a surface grid
    (rows along u); ``triangles`` when they come from a mesh. For a trimmed surface the
    measured points are the grid points inside the face: ``grid_points`` holds the whole
    grid and ``grid_index`` the positions of ``points`` in it (for drawing).
    """

    points: np.ndarray
    signed: np.ndarray
    foot_uv: np.ndarray
    foot: np.ndarray
    on_boundary: np.ndarray
    grid_shape: tuple | None = None
    triangles: np.ndarray | None = None
    tolerance: float | None = None
    stats: dict = field(default_factory=dict)
    grid_points: np.ndarray | None = None
    grid_index: np.ndarray | None = None
    outside_trim: np.ndarray | None = None
    """For a trimmed reference face: True where the candidate point's closest surface point lies
    outside the trimmed region, so it was measured to the face's boundary edges instead."""

    @property
    def max_abs(self) -> float:
        return self.stats["max_abs"]

    @property
    def mean(self) -> float:
        return self.stats["mean"]

    @property
    def within_tolerance(self) -> bool | None:
        """True/False when a tolerance was given (max abs deviation <= tolerance), else None."""
        if self.tolerance is None:
            return None
        return self.max_abs <= self.tolerance

    def report(self) -> dict:
        """JSON-ready figures with unit-suffixed keys (``max_abs_mm``, ``rms_mm``, ``worst_xyz_mm``...)."""
        out = {(k + "_mm" if k in _MM_KEYS else k): v for k, v in self.stats.items()}
        out["tolerance_mm"] = self.tolerance
        out["within_tolerance"] = self.within_tolerance
        return out


_BYTES_PER_POINT = 1024  # measured peak of projection + statistics + map per candidate point, rounded up

_MM_KEYS = {
    "max_abs",
    "max",
    "min",
    "mean",
    "mean_abs",
    "rms",
    "p50_abs",
    "p95_abs",
    "p99_abs",
    "worst_xyz",
    "worst_signed",
}


@renamed(uv_tol="uv_tolerance")
def project_points(
    surface: BSplineSurface,
    points: ArrayLike,
    *,
    seed_samples: int | None = None,
    max_iter: int = 50,
    uv_tolerance: float = 1e-14,
    progress: ProgressLike = None,
) -> Projection:
    """Closest points on ``surface`` (inside its parameter box) of many 3-D points.

    Newton's method on ``|S(u, v) - p|^2`` from the nearest of ``seed_samples^2`` reference
    samples (default: 6 per knot span, at least 64 per direction), with an active set for
    the box bounds so feet on the boundary are exact too.

    Parameters
    ----------
    surface : BSplineSurface
        The surface (mm).
    points : array_like (n, 3)
        Points to project, mm.
    progress : Progress, optional
        ``progress(done, total, message)`` after each chunk of points.

    Returns
    -------
    Projection
        ``uv``, ``foot``, unit ``normal`` at the foot, ``on_boundary`` and ``converged`` per point.

    Examples
    --------
    >>> from machsurf_cad.geometry import builders
    >>> pr = project_points(builders.plane_patch(), [[30.0, 40.0, 7.0]])
    >>> pr.uv.round(12).tolist(), pr.foot.round(12).tolist()
    ([[0.3, 0.4]], [[30.0, 40.0, 0.0]])
    """
    from .checks import points as _points

    p = _points("points", points, 3)
    if not np.all(np.isfinite(p)):
        raise InputError("candidate points must be finite")
    u0, u1, v0, v1 = surface.bounds
    if seed_samples is None:
        nu = int(np.clip(6 * (surface.knots_u.size - 1) * surface.degree_u, 64, 400))
        nv = int(np.clip(6 * (surface.knots_v.size - 1) * surface.degree_v, 64, 400))
    else:
        nu = nv = int(seed_samples)
    us, vs = np.linspace(u0, u1, nu), np.linspace(v0, v1, nv)
    grid = surface.evaluate_grid(us, vs).reshape(-1, 3)
    _, idx = cKDTree(grid).query(p)
    uv = np.stack([us[idx // nv], vs[idx % nv]], axis=1)
    chunk = 1 << 16
    if p.shape[0] > chunk:
        parts = []
        for a in range(0, p.shape[0], chunk):
            parts.append(_newton(surface, p[a : a + chunk], uv[a : a + chunk].copy(), max_iter, uv_tolerance))
            if progress is not None:
                progress(min(p.shape[0], a + chunk), p.shape[0], "closest points")
        return Projection(
            *(
                np.concatenate([getattr(q, k) for q in parts])
                for k in ("uv", "foot", "normal", "on_boundary", "converged")
            )
        )
    res = _newton(surface, p, uv, max_iter, uv_tolerance)
    if progress is not None:
        progress(p.shape[0], p.shape[0], "closest points")
    return res


def _newton(surface: BSplineSurface, p: np.ndarray, uv: np.ndarray, max_iter: int, uv_tol: float) -> Projection:
    """Box-constrained Newton iterations from the seeds ``uv`` (see :func:`project_points`)."""
    u0, u1, v0, v1 = surface.bounds
    lo = np.array([u0, v0])
    hi = np.array([u1, v1])
    span = hi - lo
    active = np.ones(p.shape[0], dtype=bool)
    converged = np.zeros(p.shape[0], dtype=bool)
    for _ in range(max_iter):
        if not active.any():
            break
        ia = np.nonzero(active)[0]
        d = surface.derivatives(uv[ia, 0], uv[ia, 1], 2)
        r = d.point - p[ia]
        g = np.stack([np.einsum("ij,ij->i", d.su, r), np.einsum("ij,ij->i", d.sv, r)], axis=1)
        huu = np.einsum("ij,ij->i", d.su, d.su) + np.einsum("ij,ij->i", d.suu, r)
        huv = np.einsum("ij,ij->i", d.su, d.sv) + np.einsum("ij,ij->i", d.suv, r)
        hvv = np.einsum("ij,ij->i", d.sv, d.sv) + np.einsum("ij,ij->i", d.svv, r)
        det = huu * hvv - huv * huv
        # fall back to Gauss-Newton where the Hessian is not positive definite
        gn = ~((huu > 0) & (det > 0))
        if gn.any():
            huu = np.where(gn, np.einsum("ij,ij->i", d.su, d.su), huu)
            huv = np.where(gn, np.einsum("ij,ij->i", d.su, d.sv), huv)
            hvv = np.where(gn, np.einsum("ij,ij->i", d.sv, d.sv), hvv)
            det = huu * hvv - huv * huv
        cur = uv[ia]
        # active set: a coordinate on its bound whose descent direction points outward stays put
        at_lo = cur <= lo + 1e-15 * span
        at_hi = cur >= hi - 1e-15 * span
        fix = (at_lo & (g > 0)) | (at_hi & (g < 0))
        step = np.empty_like(cur)
        safe_det = np.where(det != 0, det, 1.0)
        step[:, 0] = (hvv * g[:, 0] - huv * g[:, 1]) / safe_det
        step[:, 1] = (huu * g[:, 1] - huv * g[:, 0]) / safe_det
        only_u = fix[:, 1] & ~fix[:, 0]
        only_v = fix[:, 0] & ~fix[:, 1]
        both = fix[:, 0] & fix[:, 1]
        step[only_u, 0] = g[only_u, 0] / np.where(huu[only_u] != 0, huu[only_u], 1.0)
        step[only_u, 1] = 0.0
        step[only_v, 1] = g[only_v, 1] / np.where(hvv[only_v] != 0, hvv[only_v], 1.0)
        step[only_v, 0] = 0.0
        step[both] = 0.0
        # limit steps to a quarter of the domain to stay in the basin of the seed
        lim = 0.25 * span
        step = np.clip(step, -lim, lim)
        new = np.clip(cur - step, lo, hi)
        moved = np.abs(new - cur).max(axis=1)
        uv[ia] = new
        done = moved <= uv_tol * span.max()
        converged[ia[done]] = True
        active[ia[done]] = False
    d = surface.derivatives(uv[:, 0], uv[:, 1], 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    on_b = np.any((uv <= lo + 1e-12 * span) | (uv >= hi - 1e-12 * span), axis=1)
    return Projection(uv, d.point, n, on_b, converged)


def deviation(
    reference: FaceLike,
    candidate: FaceLike | ArrayLike,
    *,
    samples: int = 200,
    tolerance: float | None = None,
    triangles: ArrayLike | None = None,
    progress: ProgressLike = None,
    max_memory_mb: float = 4096.0,
) -> DeviationResult:
    """Signed deviation of ``candidate`` from ``reference`` (mm).

    Parameters
    ----------
    reference : BSplineSurface or Face
        The surface measured against. For a :class:`Face` the sign follows the face's
        outward normal (flipped when the face is reversed). Feet are the closest points of
        the trimmed face: on the surface where that lies inside the trimmed region, else on
        its boundary edges (those points are flagged in ``outside_trim`` and counted in the
        report as ``n_outside_trimmed_region``).
    candidate : BSplineSurface, Face or array_like (n, 3)
        A surface (sampled on a ``samples`` x ``samples`` grid, trimming honoured for a
        Face) or points, e.g. mesh vertices.
    samples : int
        Grid size per direction when the candidate is a surface.
    tolerance : float, optional
        Max-norm tolerance in mm; reported as within/outside and drawn as a band on maps.
    triangles : array_like, optional
        Mesh connectivity of candidate points (kept for rendering).
    progress : callable, optional
        :data:`~machsurf_cad.results.Progress` called after each chunk of projected points.
    max_memory_mb : float
        Work-size bound: a candidate whose measurement would need more memory (about 1 kB per
        point) is refused with the memory it would need.

    Returns
    -------
    DeviationResult
        Signed distances (+ on the side of the reference's outward normal), closest points and
        statistics (``report()``: ``max_abs_mm``, ``rms_mm``, worst point in xyz and uv...).

    Raises
    ------
    InputError
        Empty candidate, wrong point array shape, non-finite points.

    Examples
    --------
    >>> from machsurf_cad.geometry import builders
    >>> d = deviation(builders.plane_patch(), builders.plane_patch(origin=(0, 0, -0.2)), samples=5)
    >>> round(d.stats["min"], 12), d.within_tolerance
    (-0.2, None)
    """
    from .checks import positive

    if tolerance is not None:
        tolerance = positive("tolerance", tolerance)
    if isinstance(candidate, (BSplineSurface, Face)):
        if int(samples) < 2:
            raise InputError(f"samples must be >= 2 per direction, got {samples}")
        need = samples * samples * _BYTES_PER_POINT / 2**20
        positive("max_memory_mb", max_memory_mb, "MB")
        if need > max_memory_mb:
            raise InputError(
                f"samples = {samples} ({samples * samples} points) needs about {need / 1024:.3g} GiB, over the "
                f"{max_memory_mb / 1024:.3g} GiB budget: reduce --samples "
                f"(at most {int((max_memory_mb * 2**20 / _BYTES_PER_POINT) ** 0.5)})"
            )
    ref_surface = reference.surface if isinstance(reference, Face) else reference
    flip = -1.0 if isinstance(reference, Face) and reference.reversed else 1.0
    if not isinstance(ref_surface, BSplineSurface):
        raise InputError("reference must be a BSplineSurface or Face")
    grid_shape = None
    grid_points = grid_index = None
    if isinstance(candidate, (BSplineSurface, Face)):
        cs = candidate.surface if isinstance(candidate, Face) else candidate
        u0, u1, v0, v1 = candidate.uv_bounds if isinstance(candidate, Face) else cs.bounds
        us, vs = np.linspace(u0, u1, samples), np.linspace(v0, v1, samples)
        pts = cs.evaluate_grid(us, vs).reshape(-1, 3)
        grid_shape = (samples, samples)
        if isinstance(candidate, Face) and candidate.is_trimmed:
            uu, vv = np.meshgrid(us, vs, indexing="ij")
            keep = inside_face(candidate, np.stack([uu.ravel(), vv.ravel()], axis=1))  # polygons to 2e-5 mm
            grid_points, grid_index = pts, np.nonzero(keep)[0]
            pts = pts[keep]
    else:
        from .checks import points

        pts = points("candidate (a surface, a Face or points (n, 3))", candidate, 3)
    if pts.shape[0] == 0:
        more = f": none of its {samples} x {samples} samples lies inside its trimming loops; give more samples"
        raise InputError("candidate has no points to measure" + (more if grid_shape is not None else ""))
    # the closest point of the (trimmed) face: every basin of |S - p| searched, feet outside the
    # trimming loops dropped, the loops' 3-D curves searched where they could be nearer
    cp = closest_points(reference, pts, progress=progress)
    proj = Projection(cp.uv, cp.foot, cp.normal, cp.on_boundary, cp.converged)
    outside = cp.on_trim if isinstance(reference, Face) and reference.is_trimmed else None
    signed = signed_distances(pts, proj, flip)
    stats = deviation_stats(signed, pts, proj.uv, proj.on_boundary, proj.converged)
    if outside is not None:
        stats["n_outside_trimmed_region"] = int(outside.sum())
        stats["max_abs_outside_trimmed_region"] = float(np.abs(signed[outside]).max()) if outside.any() else 0.0
    return DeviationResult(
        pts,
        signed,
        proj.uv,
        proj.foot,
        proj.on_boundary,
        grid_shape,
        None if triangles is None else np.asarray(triangles),
        tolerance,
        stats,
        grid_points,
        grid_index,
        outside,
    )


def signed_distances(pts: np.ndarray, proj: Projection, flip: float = 1.0) -> np.ndarray:
    """Euclidean distance to the foot, signed by the side of the reference normal.

    Inside the domain the foot is orthogonal and this equals ``(p - foot) . n``; where the
    foot is on the boundary (candidate overhangs the reference) it is the true distance
    to the boundary point, not its normal component.
    """
    diff = pts - proj.foot
    side = np.einsum("ij,ij->i", diff, proj.normal)
    dist = np.linalg.norm(diff, axis=1)
    return flip * np.where(side < 0, -dist, dist)


def deviation_stats(signed: np.ndarray, pts: np.ndarray, uv: np.ndarray, on_boundary=None, converged=None) -> dict:
    """max/min/mean/RMS/percentiles of signed deviations and the worst location (mm)."""
    a = np.abs(signed)
    w = int(np.argmax(a))
    out = {
        "n_points": int(signed.size),
        "max_abs": float(a[w]),
        "max": float(signed.max()),
        "min": float(signed.min()),
        "mean": float(signed.mean()),
        "mean_abs": float(a.mean()),
        "rms": float(np.sqrt(np.mean(signed**2))),
        "p50_abs": float(np.percentile(a, 50)),
        "p95_abs": float(np.percentile(a, 95)),
        "p99_abs": float(np.percentile(a, 99)),
        "worst_xyz": pts[w].tolist(),
        "worst_uv": uv[w].tolist(),
        "worst_signed": float(signed[w]),
    }
    if on_boundary is not None:
        out["n_feet_on_boundary"] = int(np.count_nonzero(on_boundary))
    if converged is not None:
        out["n_not_converged"] = int(np.count_nonzero(~converged))
    return out
