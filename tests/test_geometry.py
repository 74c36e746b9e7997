"""Exact evaluation and differential geometry against closed forms and invariants."""

import numpy as np
import pytest
from helpers import random_surface

from machsurf_cad.errors import DegenerateGeometryError, InputError
from machsurf_cad.geometry import (
    BSplineCurve,
    BSplineSurface,
    builders,
    insert_knot_curve,
    insert_knot_surface,
    local_properties,
)
from machsurf_cad.geometry.knots import elevate_and_merge, refit_curve_in_space


def test_sphere_points_normals_curvatures(rng):
    R = 50.0
    s = builders.sphere_patch(R, lat_deg=(-70, 70), lon_deg=270)
    u, v = rng.uniform(0, 1, (2, 2000))
    p = local_properties(s, u, v)
    assert np.abs(np.linalg.norm(p.point, axis=1) - R).max() < 1e-12
    # normal su x sv points to the centre for this parameterisation: curvature +1/R
    assert np.abs(p.normal + p.point / R).max() < 1e-12
    assert np.abs(p.k1 - 1 / R).max() < 1e-14 and np.abs(p.k2 - 1 / R).max() < 1e-14
    assert np.abs(p.gaussian - 1 / R**2).max() < 1e-15


def test_torus_principal_curvatures_and_directions(rng):
    Rt, r = 40.0, 10.0
    s = builders.torus_patch(Rt, r, tube_deg=(-150, 150), angle_deg=180)
    u, v = rng.uniform(0, 1, (2, 2000))
    p = local_properties(s, u, v)
    x, y, z = p.point.T
    rho = np.hypot(x, y)
    assert np.abs(np.hypot(rho - Rt, z) - r).max() < 1e-12
    # closed form: tube curvature 1/r, other cos(phi)/(Rt + r cos(phi)) (signs by the normal)
    cos_phi = (rho - Rt) / r
    k_par = cos_phi / (Rt + r * cos_phi)
    k_tube = 1 / r
    sign = np.sign(np.einsum("ij,ij->i", p.normal, np.stack([x - Rt * x / rho, y - Rt * y / rho, z], 1)))
    assert np.all(sign == -1)  # normal points into the tube
    ks = np.sort(np.stack([p.k1, p.k2], 1), axis=1)
    ref = np.sort(np.stack([np.full_like(k_par, k_tube), k_par], 1), axis=1)
    assert np.abs(ks - ref).max() < 1e-12
    # the direction of the tube curvature is the meridian: orthogonal to the z-rotation direction
    tangential = np.stack([-y, x, 0 * x], 1) / rho[:, None]
    tube_dir = np.where((np.abs(p.k1 - k_tube) < 1e-9)[:, None], p.dir1, p.dir2)
    assert np.abs(np.einsum("ij,ij->i", tube_dir, tangential)).max() < 1e-9


def test_cylinder_curvatures(rng):
    s = builders.cylinder_patch(30.0, 60.0, angle_deg=200)
    u, v = rng.uniform(0, 1, (2, 500))
    p = local_properties(s, u, v)
    assert np.abs(np.hypot(p.point[:, 0], p.point[:, 1]) - 30).max() < 1e-12
    assert np.abs(np.abs(p.k1 + p.k2) - 1 / 30).max() < 1e-14
    assert np.abs(p.gaussian).max() < 1e-15


def test_plane_has_zero_curvature_and_constant_normal():
    s = builders.plane_patch(du=(100, 0, 0), dv=(0, 50, 0))
    p = local_properties(s, np.linspace(0, 1, 7), np.linspace(1, 0, 7))
    assert np.all(p.k1 == 0) and np.all(p.k2 == 0)
    assert np.allclose(p.normal, [0, 0, 1], atol=0)


def test_euler_formula_for_normal_curvature(rng):
    s = random_surface(rng, rational=True)
    u, v = rng.uniform(0.05, 0.95, (2, 300))
    p = local_properties(s, u, v)
    theta = rng.uniform(0, np.pi, 300)
    d = np.cos(theta)[:, None] * p.dir1 + np.sin(theta)[:, None] * p.dir2
    kn = p.normal_curvature(d)
    assert np.abs(kn - (p.k1 * np.cos(theta) ** 2 + p.k2 * np.sin(theta) ** 2)).max() < 1e-12
    assert np.abs(np.einsum("ij,ij->i", p.dir1, p.dir2)).max() < 1e-12
    assert np.abs(np.einsum("ij,ij->i", p.dir1, p.normal)).max() < 1e-12


def test_grid_equals_scattered_evaluation(rng):
    for rational in (False, True):
        s = random_surface(rng, rational=rational)
        us, vs = np.sort(rng.uniform(0, 1, 17)), np.sort(rng.uniform(0, 1, 13))
        g = s.derivatives_grid(us, vs, 2)
        U, V = np.meshgrid(us, vs, indexing="ij")
        d = s.derivatives(U, V, 2)
        for a, b in ((g.point, d.point), (g.su, d.su), (g.sv, d.sv), (g.suu, d.suu), (g.suv, d.suv), (g.svv, d.svv)):
            assert np.abs(a - b).max() < 1e-9


def test_derivatives_match_finite_differences(rng):
    s = random_surface(rng, rational=True)
    u, v = rng.uniform(0.1, 0.9, (2, 50))
    h = 1e-6
    d = s.derivatives(u, v, 2)
    fd_u = (s.evaluate(u + h, v) - s.evaluate(u - h, v)) / (2 * h)
    fd_uv = (s.derivatives(u, v + h, 1).su - s.derivatives(u, v - h, 1).su) / (2 * h)
    assert np.abs(fd_u - d.su).max() < 1e-5 * np.abs(d.su).max()
    assert np.abs(fd_uv - d.suv).max() < 1e-4 * np.abs(d.suv).max()


def test_knot_insertion_keeps_geometry(rng):
    s = random_surface(rng, rational=True)
    s2 = insert_knot_surface(s, 0.37, "u", times=2)
    s3 = insert_knot_surface(s2, 0.61, "v")
    assert s3.shape == (s.shape[0] + 2, s.shape[1] + 1)
    u, v = rng.uniform(0, 1, (2, 2000))
    assert np.abs(s3.evaluate(u, v) - s.evaluate(u, v)).max() < 1e-11
    c = BSplineCurve(3, [0, 0.4, 1], [4, 1, 4], rng.normal(size=(5, 3)), rng.uniform(0.5, 2, 5))
    c2 = insert_knot_curve(c, 0.4, 2)
    x = np.linspace(0, 1, 301)
    assert np.abs(c2.evaluate(x) - c.evaluate(x)).max() < 1e-13
    assert c2.mults.tolist() == [4, 3, 4]


def test_degree_elevation_and_merging_keep_curves(rng):
    c0 = BSplineCurve(2, [0, 0.5, 1], [3, 1, 3], rng.normal(size=(4, 3)))
    c1 = BSplineCurve(3, [0, 0.3, 1], [4, 1, 4], rng.normal(size=(5, 3)))
    a, b = elevate_and_merge([c0, c1])
    x = np.linspace(0, 1, 201)
    assert a.degree == b.degree == 3 and np.array_equal(a.knots, b.knots)
    assert np.abs(a.evaluate(x) - c0.evaluate(x)).max() < 1e-12
    assert np.abs(b.evaluate(x) - c1.evaluate(x)).max() < 1e-12
    e = refit_curve_in_space(c0, 4, [0, 0.5, 1], [5, 3, 5])
    assert np.abs(e.evaluate(x) - c0.evaluate(x)).max() < 1e-12


def test_periodic_surface_wraps_and_is_continuous(rng):
    n = 6
    s = BSplineSurface(3, 1, np.arange(7.0), [1] * 7, [0, 1], [2, 2], rng.normal(size=(n, 2, 3)), periodic_u=True)
    v = rng.uniform(0, 1, 20)
    assert np.abs(s.evaluate(0.0, v) - s.evaluate(6.0, v)).max() < 1e-12
    assert np.abs(s.evaluate(-1.5, v) - s.evaluate(4.5, v)).max() < 1e-12
    assert np.abs(s.derivatives(0.0, v, 2).suu - s.derivatives(6.0, v, 2).suu).max() < 1e-10


def cone_with_tip():
    """A cone of half angle 45 deg, its tip at u = 1 (the whole u = 1 iso-line collapsed)."""
    prof = BSplineCurve(1, [0, 1], [2, 2], [[30.0, 0.0], [0.0, 30.0]])
    return builders.revolve_profile(prof, 360.0)


def test_collapsed_edge_gets_its_limit_normal_and_a_cone_tip_is_reported():
    # a triangle-like patch: the whole v = 1 edge collapsed to one point of a plane: its normal is the plane's
    poles = [[[0, 0, 0], [50, 50, 0]], [[100, 0, 0], [50, 50, 0]]]
    s = builders.bezier_surface(poles)
    n = s.normals(np.array([0.5, 0.2, 0.9]), np.array([1.0, 1.0, 1.0]))
    assert np.abs(n - [0, 0, 1.0]).max() < 1e-9
    # a cone's tip: the normals around it turn all the way round, no limit
    cone = cone_with_tip()
    with pytest.raises(DegenerateGeometryError, match="no limit normal"):
        cone.normals(np.array([1.0, 0.5]), np.array([0.3, 0.5]))
    n = cone.normals(np.array([1.0]), np.array([0.3]), check=False)
    assert np.isnan(n).all()


def test_invalid_construction_is_refused():
    with pytest.raises(InputError, match="sum\\(mults\\)"):
        BSplineSurface(3, 3, [0, 1], [4, 4], [0, 1], [4, 4], np.zeros((3, 4, 3)))
    with pytest.raises(InputError, match="finite"):
        BSplineSurface(1, 1, [0, 1], [2, 2], [0, 1], [2, 2], [[[0, 0, np.nan], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]])
    with pytest.raises(InputError, match="weights"):
        builders.bezier_surface(np.zeros((2, 2, 3)), weights=[[1, 1], [1, -1]])


def test_types_are_immutable_and_equality_is_exact():
    s = builders.plane_patch()
    with pytest.raises((AttributeError, TypeError)):
        s.degree_u = 3
    with pytest.raises(ValueError):
        s.poles[0, 0, 0] = 1.0
    t = s.with_poles(s.poles + 1e-15)
    assert s == builders.plane_patch() and s != t


def test_evaluate_with_normals_matches_derivatives(rng):
    import machsurf_cad.geometry.bspline as B

    s = random_surface(rng, rational=True)
    n = 5 * B._CHUNK + 17  # large enough for the threaded path
    u, v = rng.uniform(0, 1, (2, n))
    p, nrm = s.evaluate_with_normals(u, v)
    d = s.derivatives(u, v, 1)
    ref = np.cross(d.su, d.sv)
    ref /= np.linalg.norm(ref, axis=1, keepdims=True)
    assert np.abs(p - d.point).max() < 1e-12 and np.abs(nrm - ref).max() < 1e-12
    collapsed = builders.bezier_surface([[[0, 0, 0], [50, 50, 0]], [[100, 0, 0], [50, 50, 0]]])
    with pytest.raises(DegenerateGeometryError):
        collapsed.evaluate_with_normals(np.array([0.3, 0.5]), np.array([0.2, 1.0]))


def test_surface_atlas_equals_each_surface_evaluated_alone(rng):
    """Many surfaces (polynomial and rational, of several degree pairs, periodic, one above the power
    basis' degree limit) evaluated together: the same points and derivatives as each surface's own
    evaluation, inside and a little outside their domains."""
    from machsurf_cad.geometry.atlas import SurfaceAtlas

    per = BSplineSurface(3, 1, np.arange(7.0), [1] * 7, [0, 1], [2, 2], rng.normal(size=(6, 2, 3)), periodic_u=True)
    surfs = [
        random_surface(rng),
        random_surface(rng, rational=True),
        random_surface(rng, degree=(2, 2), n=(6, 4)),
        random_surface(rng, rational=True, degree=(3, 2)),
        random_surface(rng, degree=(8, 2), n=(10, 4)),
        per,
    ]
    atlas = SurfaceAtlas(surfs)
    n = 3000
    fid = rng.integers(0, len(surfs), n)
    box = np.array([[s.knots_u[0], s.knots_u[-1], s.knots_v[0], s.knots_v[-1]] for s in surfs])[fid]
    u = box[:, 0] + rng.uniform(-0.05, 1.05, n) * (box[:, 1] - box[:, 0])
    v = box[:, 2] + rng.uniform(-0.05, 1.05, n) * (box[:, 3] - box[:, 2])
    u[:50], v[:50] = box[:50, 0], box[:50, 3]  # corners: the last span
    got = atlas.derivatives(fid, u, v, 2)
    for f, s in enumerate(surfs):
        sel = fid == f
        d = s.derivatives(u[sel], v[sel], 2)
        for a, b in zip(got, [d.point, d.su, d.sv, d.suu, d.suv, d.svv]):
            assert np.abs(a[sel] - b).max() <= 1e-12 * max(1.0, np.abs(b).max())
