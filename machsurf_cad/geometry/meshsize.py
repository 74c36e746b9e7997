"""How many triangles a mesher needs for a face at a given chordal (linear) and angular deflection.

Used before meshing (STL export) to refuse, with the figure, a mesh that would take hours and gigabytes,
and to choose a default deflection relative to the faces' size. The estimate samples the face on a grid:
per cell its area and curvature (the turn of the normal per mm between neighbouring samples); a mesher
that keeps the sag of an edge of length ``l`` under ``d`` on curvature ``k`` uses ``l = sqrt(8 d / k)``
(and ``l = theta / k`` for the angular bound ``theta``), so a cell of area ``A`` holds about
``2 A / l^2`` triangles, times :data:`OCCT_FACTOR` (OCCT 7.9's mesher makes about 4 times that: measured on
the bezier5 and blade examples at 0.01 mm, 8,530 and 21,122 triangles against 2,158 and 5,264 estimated).
It is an order of magnitude, not a count.
"""

from __future__ import annotations

import math

import numpy as np

from .face import Face

MAX_TRIANGLES = 20_000_000
"""Most triangles an export meshes before it refuses (about 1 GB of mesh and minutes of meshing)."""
OCCT_FACTOR = 4.0
"""Triangles OCCT's incremental mesher makes per triangle of the curvature model (measured, see above)."""
BYTES_PER_TRIANGLE = 50
"""Binary STL bytes per triangle (plus the mesher's own structures, about as much again)."""


def _cells(face: Face, n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Area (mm^2) and curvature (1/mm) of the ``(n-1)^2`` cells of an ``n x n`` grid over the face's uv box."""
    u0, u1, v0, v1 = face.uv_bounds
    U, V = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n), indexing="ij")
    d = face.surface.derivatives(U.ravel(), V.ravel(), 1)
    P = d.point.reshape(n, n, 3)
    N = np.cross(d.su, d.sv)
    N = (N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)).reshape(n, n, 3)
    du, dv = P[1:, :-1] - P[:-1, :-1], P[:-1, 1:] - P[:-1, :-1]
    area = np.linalg.norm(np.cross(du, dv), axis=2)
    ku = np.linalg.norm(N[1:, :-1] - N[:-1, :-1], axis=2) / np.maximum(np.linalg.norm(du, axis=2), 1e-12)
    kv = np.linalg.norm(N[:-1, 1:] - N[:-1, :-1], axis=2) / np.maximum(np.linalg.norm(dv, axis=2), 1e-12)
    return area.ravel(), np.maximum(ku, kv).ravel()


def estimate_triangles(faces, linear_deflection: float, angular_deflection_deg: float = 5.0) -> float:
    """About how many triangles meshing ``faces`` at these deflections (mm, degrees) gives."""
    total = 0.0
    theta = math.radians(angular_deflection_deg)
    for f in faces:
        area, k = _cells(f)
        k = np.maximum(k, 1e-12)
        length = np.minimum(np.sqrt(8.0 * linear_deflection / k), theta / k)
        total += float(np.sum(np.maximum(OCCT_FACTOR * 2.0 * area / length**2, 2.0)))
    return total


def default_deflection(faces, *, floor_mm: float = 0.01, budget: int = 2_000_000) -> float:
    """The STL deflection used when none is given: ``floor_mm``, or larger where that would need more than
    ``budget`` triangles (the curvature-limited count falls as 1/deflection), rounded up to 2 digits."""
    est = estimate_triangles(faces, floor_mm, angular_deflection_deg=90.0)
    if est <= budget:
        return floor_mm
    d = floor_mm * est / budget
    e = 10 ** math.floor(math.log10(d))
    return math.ceil(d / e * 10) / 10 * e


def check_mesh_size(faces, linear_deflection: float, angular_deflection_deg: float, what: str = "the STL") -> float:
    """The estimated triangle count, or a one-line refusal when it exceeds :data:`MAX_TRIANGLES`."""
    from ..errors import InputError

    est = estimate_triangles(faces, linear_deflection, angular_deflection_deg)
    if est > MAX_TRIANGLES:
        suggest = default_deflection(faces, floor_mm=linear_deflection, budget=MAX_TRIANGLES // 10)
        raise InputError(
            f"meshing {what} at deflection {linear_deflection:g} mm needs about {est:.3g} triangles "
            f"(about {est * 2 * BYTES_PER_TRIANGLE / 2**30:.3g} GB), more than {MAX_TRIANGLES:,}: "
            f"give a larger deflection, e.g. {suggest:g} mm"
        )
    return est


__all__ = ["estimate_triangles", "default_deflection", "check_mesh_size", "MAX_TRIANGLES"]
