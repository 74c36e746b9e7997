"""Differential geometry of B-spline surfaces, vectorised and exact.

Conventions
-----------
* Normal ``n = su x sv / |su x sv|``.
* Second fundamental form ``L = suu . n``, ``M = suv . n``, ``N = svv . n``.
* Curvatures (1/mm) are signed with respect to ``n``: a sphere of radius R whose normal
  points outwards has curvature ``-1/R``; one whose normal points inwards ``+1/R``.
  This is the convention of OCCT's ``GeomLProp_SLProps``.
* ``k1 >= k2``; ``dir1``/``dir2`` are unit 3-D tangent vectors (sign arbitrary).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..results import Result
from ..typing import ArrayLike
from .bspline import BSplineSurface
from .normals import _cross, unit_normals


@dataclass(frozen=True, eq=False)
class LocalProperties(Result):
    """Local differential properties at a set of ``(u, v)`` points (mm, 1/mm)."""

    u: np.ndarray
    v: np.ndarray
    point: np.ndarray
    su: np.ndarray
    sv: np.ndarray
    suu: np.ndarray
    suv: np.ndarray
    svv: np.ndarray
    normal: np.ndarray
    E: np.ndarray
    F: np.ndarray
    G: np.ndarray
    L: np.ndarray
    M: np.ndarray
    N: np.ndarray
    gaussian: np.ndarray
    mean: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    dir1: np.ndarray
    dir2: np.ndarray

    def normal_curvature(self, direction) -> np.ndarray:
        """Normal curvature (1/mm) along a tangent ``direction``.

        ``direction`` is either a 3-D vector field (..., 3) (projected onto the tangent
        plane) or a parameter-space direction (..., 2) ``(du, dv)``.
        """
        d = np.asarray(direction, dtype=float)
        if d.shape[-1] == 2:
            du, dv = d[..., 0], d[..., 1]
        else:
            du, dv = tangent_to_parameter(self, d)
        num = self.L * du * du + 2 * self.M * du * dv + self.N * dv * dv
        den = self.E * du * du + 2 * self.F * du * dv + self.G * dv * dv
        return num / den


def tangent_to_parameter(props: LocalProperties, vec: np.ndarray):
    """Parameter-space components ``(du, dv)`` of the tangent part of a 3-D vector."""
    a = np.einsum("...i,...i->...", vec, props.su)
    b = np.einsum("...i,...i->...", vec, props.sv)
    det = props.E * props.G - props.F**2
    du = (props.G * a - props.F * b) / det
    dv = (props.E * b - props.F * a) / det
    return du, dv


def local_properties(surface: BSplineSurface, u: ArrayLike, v: ArrayLike, *, check: bool = True) -> LocalProperties:
    """Fundamental forms, normals, principal curvatures and directions at ``(u, v)``.

    Parameters
    ----------
    surface : BSplineSurface
        The surface (mm).
    u, v : float or array_like
        Parameters (broadcast together).
    check : bool
        Raise where the normal does not exist (else NaN there).

    Returns
    -------
    LocalProperties
        Points, unit normals ``su x sv``, first and second fundamental forms, principal
        curvatures ``k1 >= k2`` (1/mm, signed against the normal as OCCT's GeomLProp) and directions.

    Raises
    ------
    DegenerateGeometryError
        Where the normal does not exist, unless ``check=False``.

    Examples
    --------
    >>> from machsurf_cad.geometry import builders
    >>> s = builders.sphere_patch(radius=50.0)
    >>> p = local_properties(s, 0.3, 0.4)
    >>> round(float(p.k1 * 50), 9), round(float(p.k2 * 50), 9)
    (1.0, 1.0)
    """
    if not isinstance(surface, BSplineSurface):
        raise InputError(f"local_properties needs a BSplineSurface, got {type(surface).__name__}")
    u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    _check_domain(surface, u, v)
    d = surface.derivatives(u, v, 2)
    return _with_limits(surface, properties_from_derivatives(u, v, d, surface.scale, check=False), check)


_LIMIT_FIELDS = ("normal", "L", "M", "N", "gaussian", "mean", "k1", "k2", "dir1", "dir2")


def _with_limits(surface: BSplineSurface, p: LocalProperties, check: bool) -> LocalProperties:
    """Degenerate points (``su x sv = 0``: a sphere's pole, a revolved face on its axis) get the limit
    normal (:func:`~machsurf_cad.geometry.bspline.limit_normals`) and the curvatures of the nearest
    regular neighbour (1e-6 of the domain away); where the limit does not exist (a cone's tip) the
    normal stays undefined: :class:`DegenerateGeometryError` when ``check``, NaN otherwise."""
    from .normals import limit_normals

    bad = ~np.all(np.isfinite(p.normal), axis=-1)
    if not np.any(bad):
        return p
    ub, vb = p.u[bad], p.v[bad]
    lim = limit_normals(surface, ub, vb)
    ok = np.all(np.isfinite(lim), axis=-1)
    if check and not np.all(ok):
        unit_normals(p.su[bad][~ok], p.sv[bad][~ok], surface.scale, ub[~ok], vb[~ok], check=True)
    if not np.any(ok):
        return p
    # curvatures: at the regular neighbour towards the interior (the same probe as the limit normal)
    u0, u1, v0, v1 = surface.bounds
    nu, nv = ub[ok], vb[ok]
    best_u, best_v = nu.copy(), nv.copy()
    found = np.zeros(nu.size, bool)
    for a, b in ((0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)):
        uu = np.clip(nu + a * 1e-6 * (u1 - u0), u0, u1)
        vv = np.clip(nv + b * 1e-6 * (v1 - v0), v0, v1)
        dd = surface.derivatives(uu, vv, 1)
        n = _cross(dd.su, dd.sv)
        good = ~found & (np.sqrt(np.einsum("ij,ij->i", n, n)) > 1e-9 * surface.scale**2)
        best_u[good], best_v[good] = uu[good], vv[good]
        found |= good
    dn = surface.derivatives(best_u, best_v, 2)
    q = properties_from_derivatives(best_u, best_v, dn, surface.scale, check=False)
    fields = {f: np.array(getattr(p, f), copy=True) for f in _LIMIT_FIELDS}
    idx = np.nonzero(bad)
    sel = tuple(i[ok] for i in idx)
    for f in _LIMIT_FIELDS:
        fields[f][sel] = getattr(q, f)
    fields["normal"][sel] = lim[ok]
    return dataclasses.replace(p, **fields)


def _check_domain(surface: BSplineSurface, u, v, rel: float = 1e-9) -> None:
    """Refuse parameters outside the surface's domain (beyond ``rel`` of its size; periodic
    directions wrap and are not checked): a B-spline extrapolated there is not the surface."""
    u0, u1, v0, v1 = surface.bounds
    bad = np.zeros(np.shape(u), bool)
    if not surface.periodic_u:
        tol = rel * (u1 - u0)
        bad |= (u < u0 - tol) | (u > u1 + tol)
    if not surface.periodic_v:
        tol = rel * (v1 - v0)
        bad |= (v < v0 - tol) | (v > v1 + tol)
    if np.any(bad) or not (np.all(np.isfinite(u)) and np.all(np.isfinite(v))):
        i = int(np.argmax(bad)) if np.any(bad) else 0
        raise InputError(
            f"(u, v) outside the surface's domain [{u0:g}, {u1:g}] x [{v0:g}, {v1:g}] (or not finite), "
            f"e.g. ({np.ravel(u)[i]:g}, {np.ravel(v)[i]:g})"
        )


def local_properties_grid(surface: BSplineSurface, us, vs, *, check: bool = True) -> LocalProperties:
    """:func:`local_properties` on the tensor grid ``us x vs`` (arrays of shape (len(us), len(vs))).

    Uses the grid evaluator (basis functions once per grid line, dense BLAS products).
    """
    us = np.asarray(us, dtype=float).ravel()
    vs = np.asarray(vs, dtype=float).ravel()
    U, V = np.meshgrid(us, vs, indexing="ij")
    d = surface.derivatives_grid(us, vs, 2)
    return _with_limits(surface, properties_from_derivatives(U, V, d, surface.scale, check=False), check)


def properties_from_derivatives(u, v, d, scale: float, *, check: bool = True) -> LocalProperties:
    """:class:`LocalProperties` from precomputed derivatives (see :meth:`BSplineSurface.derivatives`)."""
    n = unit_normals(d.su, d.sv, scale, u, v, check=check)

    def dot(a, b):
        return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]

    E, F, G = dot(d.su, d.su), dot(d.su, d.sv), dot(d.sv, d.sv)
    L, M, N = dot(d.suu, n), dot(d.suv, n), dot(d.svv, n)
    det = E * G - F * F
    K = (L * N - M * M) / det
    H = (E * N - 2 * F * M + G * L) / (2 * det)
    # second form in the orthonormal tangent frame (e1 = su/|su|, e2 = n x e1): symmetric, so its
    # eigen-decomposition stays accurate at (near-)umbilic points where H^2 - K cancels.
    su_len = np.sqrt(E)
    e1 = d.su / su_len[..., None]
    e2 = _cross(n, e1)
    x1u = 1.0 / su_len
    b_ = dot(e2, d.su)
    c_ = dot(e2, d.sv)
    x2u = (G * b_ - F * c_) / det
    x2v = (E * c_ - F * b_) / det
    a = L * x1u * x1u
    b = (L * x2u + M * x2v) * x1u
    c = L * x2u * x2u + 2 * M * x2u * x2v + N * x2v * x2v
    half = 0.5 * (a + c)
    rad = np.hypot(0.5 * (a - c), b)
    k1, k2 = half + rad, half - rad
    theta = 0.5 * np.arctan2(2 * b, a - c)
    dir1 = np.cos(theta)[..., None] * e1 + np.sin(theta)[..., None] * e2
    dir2 = _cross(n, dir1)
    return LocalProperties(
        u, v, d.point, d.su, d.sv, d.suu, d.suv, d.svv, n, E, F, G, L, M, N, K, H, k1, k2, dir1, dir2
    )
