"""The deviation function against closed forms and an independent brute-force closest point."""

import numpy as np
import pytest
from helpers import random_surface

from machsurf_cad.geometry import builders
from machsurf_cad.geometry.face import Face
from machsurf_cad.measure import deviation, project_points


def test_plane_vs_offset_plane():
    ref = builders.plane_patch(du=(100, 0, 0), dv=(0, 80, 0))
    for off in (0.25, -1.5):
        cand = builders.plane_patch(origin=(5, 5, off), du=(90, 0, 0), dv=(0, 70, 0))
        d = deviation(ref, cand, samples=60, tolerance=0.3)
        assert np.abs(d.signed - off).max() < 1e-12
        assert d.stats["rms"] == pytest.approx(abs(off), abs=1e-12)
        assert d.within_tolerance == (abs(off) <= 0.3)


def test_sphere_vs_concentric_sphere_and_sign():
    ref = builders.sphere_patch(50.0, lat_deg=(-70, 70), lon_deg=120)
    for R in (50.3, 49.2):
        cand = builders.sphere_patch(R, lat_deg=(-60, 60), lon_deg=100)
        d = deviation(ref, cand, samples=80)
        # the reference normal points to the centre: a bigger sphere is on the negative side
        assert np.abs(d.signed - (50.0 - R)).max() < 1e-10
        assert d.stats["n_not_converged"] == 0


def test_cylinder_vs_coaxial_cylinder():
    ref = builders.cylinder_patch(30.0, 60.0, angle_deg=180)
    cand = builders.cylinder_patch(29.6, 50.0, angle_deg=160)
    d = deviation(ref, cand, samples=70)
    assert np.abs(d.signed - 0.4).max() < 1e-10


def test_face_orientation_flips_the_sign():
    ref = builders.plane_patch()
    cand = builders.plane_patch(origin=(0, 0, 1))
    d = deviation(Face(ref, reversed=True), cand, samples=10)
    assert np.allclose(d.signed, -1.0, rtol=0, atol=1e-9)


def test_projection_matches_brute_force_on_free_form(rng):
    s = random_surface(rng, rational=True)
    uv = rng.uniform(0.05, 0.95, (300, 2))
    d = s.derivatives(uv[:, 0], uv[:, 1], 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    pts = d.point + rng.uniform(-2, 2, (300, 1)) * n + rng.normal(scale=0.5, size=(300, 3))
    proj = project_points(s, pts)
    dist = np.linalg.norm(pts - proj.foot, axis=1)
    # brute force, independent of Newton: nearest of a dense grid, then two local re-gridding passes
    us = np.linspace(0, 1, 400)
    grid = s.evaluate_grid(us, us).reshape(-1, 3)
    from scipy.spatial import cKDTree

    _, idx = cKDTree(grid).query(pts)
    cu, cv = us[idx // 400], us[idx % 400]
    h = us[1] - us[0]
    brute = np.empty(len(pts))
    for k in range(len(pts)):
        a, b, hh = cu[k], cv[k], 2 * h
        for _ in range(3):
            lu = np.clip(np.linspace(a - hh, a + hh, 41), 0, 1)
            lv = np.clip(np.linspace(b - hh, b + hh, 41), 0, 1)
            g = s.evaluate_grid(lu, lv)
            dd = np.linalg.norm(g - pts[k], axis=-1)
            i, j = np.unravel_index(np.argmin(dd), dd.shape)
            a, b, hh = lu[i], lv[j], hh / 10
        brute[k] = dd.min()
    assert np.all(dist <= brute + 1e-9)  # Newton is never worse than brute force
    assert np.abs(dist - brute).max() < 1e-5  # the brute force resolves to a few 1e-6 mm
    # orthogonality of the residual where the foot is interior
    inner = ~proj.on_boundary
    dd = s.derivatives(proj.uv[inner, 0], proj.uv[inner, 1], 1)
    r = pts[inner] - proj.foot[inner]
    assert np.abs(np.einsum("ij,ij->i", r, dd.su)).max() < 1e-8 * np.abs(dd.su).max()
    assert np.abs(np.einsum("ij,ij->i", r, dd.sv)).max() < 1e-8 * np.abs(dd.sv).max()


def test_overhanging_points_measure_true_distance_to_the_edge():
    ref = builders.plane_patch(du=(100, 0, 0), dv=(0, 100, 0))
    d = deviation(ref, np.array([[110.0, 50.0, 3.0], [50.0, 50.0, -2.0]]))
    assert d.signed[0] == pytest.approx(np.hypot(10, 3), abs=1e-12)
    assert d.signed[1] == pytest.approx(-2.0, abs=1e-12)
    assert d.on_boundary.tolist() == [True, False]


def test_statistics_are_consistent(rng):
    ref = builders.plane_patch()
    pts = np.column_stack([rng.uniform(0, 100, 1000), rng.uniform(0, 100, 1000), rng.normal(size=1000)])
    d = deviation(ref, pts)
    z = pts[:, 2]
    assert d.stats["max"] == pytest.approx(z.max()) and d.stats["min"] == pytest.approx(z.min())
    assert d.stats["rms"] == pytest.approx(np.sqrt(np.mean(z**2)))
    assert d.stats["p95_abs"] == pytest.approx(np.percentile(np.abs(z), 95))
    w = int(np.argmax(np.abs(z)))
    assert d.stats["worst_xyz"] == pytest.approx(pts[w].tolist())
