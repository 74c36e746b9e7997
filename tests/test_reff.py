"""Effective radius (relation (30)) and step-over (31) against brute force and direct constructions."""

import math

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad.effradius import effective_radius, parse_directions, reff_maps, stepover
from machsurf_cad.errors import DegenerateGeometryError, InputError
from machsurf_cad.geometry import builders
from machsurf_cad.geometry.face import Face

mpmath = pytest.importorskip("mpmath", reason="mpmath gives the extended-precision reference")


def _reference_reff(R, r, S_deg, a_deg, dps=50):
    """Radius of curvature, at the contact point, of the torus's envelope curve F . n_T = 0 traced
    numerically and projected along F (extended precision, independent of relation (30))."""
    mp = mpmath.mp
    mp.dps = dps
    Rt = mp.mpf(R) - r
    S, a = mp.radians(S_deg), mp.radians(a_deg)
    n_cc = mp.matrix([-mp.sin(S) * mp.sin(a), -mp.sin(S) * mp.cos(a), mp.cos(S)])
    k = -n_cc[1] / n_cc[2]  # feed (0, 1, k) tangent to the surface: F . n_cc = 0
    F = mp.matrix([0, 1, k]) / mp.sqrt(1 + k * k)

    def torus(u, v):
        return mp.matrix([(Rt + r * mp.cos(v)) * mp.cos(u), (Rt + r * mp.cos(v)) * mp.sin(u), r * mp.sin(v)])

    def normal(u, v):
        return mp.matrix([mp.cos(u) * mp.cos(v), mp.sin(u) * mp.cos(v), mp.sin(v)])

    v_c = -(mp.pi / 2 - S)  # contact: torus normal opposite to the surface normal
    u_c = mp.atan2(mp.cos(a), mp.sin(a))

    def g(u, v):
        return (F.T * normal(u, v))[0]

    # trace the curve g = 0 by the parameter along which it is a graph at the contact
    gu = mp.diff(lambda x: g(x, v_c), u_c)
    gv = mp.diff(lambda x: g(u_c, x), v_c)
    by_v = abs(gu) >= abs(gv)
    t_c = v_c if by_v else u_c

    def envelope(t):
        if by_v:
            u, v = mp.findroot(lambda uu: g(uu, t), u_c), t
        else:
            u, v = t, mp.findroot(lambda vv: g(t, vv), v_c)
        x = torus(u, v)
        x = x - (F.T * x)[0] * F  # projection along F
        e1 = mp.matrix([1, 0, 0])
        e2 = mp.matrix([0, F[2], -F[1]])
        return (e1.T * x)[0], (e2.T * x)[0]

    h = mp.mpf(10) ** -12
    p_m, p_0, p_p = envelope(t_c - h), envelope(t_c), envelope(t_c + h)
    dx, dy = (p_p[0] - p_m[0]) / (2 * h), (p_p[1] - p_m[1]) / (2 * h)
    ddx, ddy = (p_p[0] - 2 * p_0[0] + p_m[0]) / h**2, (p_p[1] - 2 * p_0[1] + p_m[1]) / h**2
    kappa = abs(dx * ddy - dy * ddx) / (dx * dx + dy * dy) ** mp.mpf(1.5)
    return float(1 / kappa)


@pytest.mark.parametrize("S", [0.5, 2.0, 15.0, 45.0, 75.0, 88.0, 89.9])
@pytest.mark.parametrize("alpha", [-80.0, -30.0, 0.0, 20.0, 60.0, 85.0, 89.5])
def test_relation_30_against_numerical_envelope(S, alpha):
    R, r = 5.0, 2.0
    ref = _reference_reff(R, r, S, alpha)
    got = float(effective_radius(f"bull:D={2 * R},r={r}", S, alpha))
    assert abs(got - ref) <= 1e-6 * ref


def test_special_values_and_symmetries():
    bull = "bull:D=10,r=2"
    S = np.linspace(0.1, 89.9, 50)
    a = np.linspace(-89, 89, 50)
    A, SS = np.meshgrid(a, S)
    v = effective_radius(bull, SS, A)
    assert np.allclose(v, effective_radius(bull, SS, A + 180.0), rtol=1e-13)  # alpha and alpha + 180
    assert np.allclose(v, effective_radius(bull, SS, -A), rtol=1e-13)
    assert np.all(effective_radius(bull, S, 90.0) == 2.0)  # perpendicular to the steepest slope: r
    assert np.all(effective_radius("ball:D=10", SS, A) == 5.0)  # ball: R everywhere
    assert np.isinf(effective_radius(bull, 0.0, 30.0))  # flat spot, horizontal feed: infinite, not a warning
    assert effective_radius(bull, 0.0, 90.0) == 2.0
    assert effective_radius(bull, 90.0, 40.0) == pytest.approx(5.0, rel=1e-14)  # vertical feed: R
    assert effective_radius(bull, 30.0, 0.0) == pytest.approx(3.0 / 0.5 + 2.0)  # R_t / sin S + r
    assert effective_radius("flat:D=10", 20.0, 0.0) == pytest.approx(5.0 / math.sin(math.radians(20)))


def test_stable_form_near_the_corner():
    mp = mpmath.mp
    mp.dps = 60
    for S, a in ((89.99999, 89.99999), (89.9999999, 89.999999), (60.0, 89.9999999)):
        Sm, am = mp.radians(S), mp.radians(a)
        exact = 3 * mp.cos(am) ** 2 / (mp.sin(Sm) * (1 - mp.sin(am) ** 2 * mp.sin(Sm) ** 2)) + 2
        got = float(effective_radius("bull:D=10,r=2", S, a))
        assert abs(got - float(exact)) <= 1e-12 * float(exact)
    # the printed form loses digits there (this is why it is not used)
    S, a = math.radians(89.9999999), math.radians(89.999999)
    naive = 3 * math.cos(a) ** 2 / (math.sin(S) * (1 - math.sin(a) ** 2 * math.sin(S) ** 2)) + 2
    Sm, am = mp.radians(89.9999999), mp.radians(89.999999)
    exact = float(3 * mp.cos(am) ** 2 / (mp.sin(Sm) * (1 - mp.sin(am) ** 2 * mp.sin(Sm) ** 2)) + 2)
    assert abs(naive - exact) > 1e-8 * exact


def _construct_scallop(R, rho, d):
    """Direct construction: two circles of radius R tangent to a surface circle of signed radius rho
    (convex > 0, concave < 0, inf flat), centres d apart; the scallop height at their intersection."""
    if math.isinf(rho):
        return R - math.sqrt(R * R - d * d / 4)
    if rho > 0:  # surface circle centred at the origin, tools outside it
        yc = math.sqrt((rho + R) ** 2 - d * d / 4)
        yh = yc - math.sqrt(R * R - d * d / 4)  # intersection nearer the surface
        return yh - rho
    P = -rho  # concave: tools inside a circle of radius P
    yc = math.sqrt((P - R) ** 2 - d * d / 4)
    yh = yc + math.sqrt(R * R - d * d / 4)
    return P - yh


@pytest.mark.parametrize("rho", [math.inf, 40.0, 6.0, 1000.0, -40.0, -12.0, -1000.0])
@pytest.mark.parametrize("R", [2.0, 5.0, 9.5])
def test_stepover_matches_direct_construction(R, rho):
    for h in (1e-4, 0.01, 0.2):
        if rho < 0 and -rho <= R + h / 2:
            continue
        d, ok = stepover(h, R, rho)
        assert ok
        assert _construct_scallop(R, rho, float(d)) == pytest.approx(h, rel=1e-9, abs=1e-13)


def test_stepover_unreachable_concave_and_infinite_reff():
    d, ok = stepover(0.01, np.array([5.0, 5.0, np.inf]), np.array([-4.0, -6.0, 30.0]))
    assert np.isnan(d[0]) and not ok[0]
    assert np.isfinite(d[1]) and ok[1]
    assert np.isinf(d[2]) and ok[2]
    with pytest.raises(InputError, match="effective diameter"):
        stepover(11.0, 5.0, np.inf)


def test_maps_on_a_tilted_plane_match_closed_forms():
    S0 = 25.0
    t = math.tan(math.radians(S0))
    plane = builders.plane_patch(origin=(0, 0, 0), du=(100, 0, 0), dv=(0, 80, 80 * t))  # steepest slope along y
    m = reff_maps(plane, "bull:D=10,r=2", directions=[0, 90, 45], grid=32, scallop=0.01)
    d0, d90, d45 = m.directions
    assert np.allclose(d0.slope_deg, S0, rtol=0, atol=1e-9) and np.allclose(d0.alpha_deg, 90.0, rtol=0, atol=1e-9)
    assert np.allclose(d0.r_eff, 2.0, rtol=0, atol=1e-9)  # feed along X: perpendicular to the slope
    assert np.allclose(d90.r_eff, 3.0 / math.sin(math.radians(S0)) + 2.0, rtol=0, atol=1e-9)
    # theta = 45: the feed's projection normal to the axis makes 45 deg with the steepest slope
    assert np.allclose(d45.alpha_deg, 45.0, rtol=0, atol=1e-9)
    assert np.allclose(d45.r_eff, effective_radius("bull:D=10,r=2", S0, 45.0), rtol=0, atol=1e-9)
    # flat surface: step-over 2 sqrt(h (2 R_eff - h)); ball the same with R
    assert np.allclose(d90.stepover, 2 * np.sqrt(0.01 * (2 * d90.r_eff - 0.01)), rtol=0, atol=1e-9)
    assert np.allclose(d90.stepover_ball, 2 * np.sqrt(0.01 * (10 - 0.01)), rtol=0, atol=1e-9)
    rep = m.report()
    assert rep["directions"][0]["area_fraction_torus_beats_ball"] == 0.0
    assert rep["directions"][1]["area_fraction_torus_beats_ball"] == 1.0
    assert rep["best_direction"]["histogram_deg"]["90"] == 32 * 32


def test_five_axis_lead_on_a_plane():
    plane = builders.plane_patch()
    m = reff_maps(plane, "bull:D=10,r=2", directions=[30], grid=8, axes=5, lead=10.0)
    d = m.directions[0]
    assert np.allclose(d.slope_deg, 10.0, rtol=0, atol=1e-9) and np.allclose(d.alpha_deg, 0.0, atol=1e-6)
    assert np.allclose(d.r_eff, 3.0 / math.sin(math.radians(10)) + 2.0, rtol=0, atol=1e-9)
    flat = reff_maps(plane, "bull:D=10,r=2", directions=[30], grid=8, axes=3)
    assert np.all(np.isinf(flat.directions[0].r_eff)) and flat.report()["directions"][0]["n_infinite_r_eff"] == 64


def test_stepover_on_a_cylinder_uses_the_section_radius():
    cyl = Face(builders.cylinder_patch(40.0, 100.0, angle_deg=60), reversed=True)  # convex, seen from outside
    # rotate the patch so that it faces up: the cylinder axis is z; use feed along z is vertical...
    # instead check rho directly through the direction map at theta where the feed follows the axis
    from machsurf_cad.geometry.bspline import BSplineSurface

    s = cyl.surface
    poles = s.poles[..., [2, 1, 0]] * np.array([1, 1, 1])  # swap x and z: axis along x, surface faces +z
    s2 = BSplineSurface(s.degree_u, s.degree_v, s.knots_u, s.mults_u, s.knots_v, s.mults_v, poles, s.weights)
    face = Face(s2)
    if face.surface.normals(0.5, 0.5)[2] < 0:
        face = Face(s2, reversed=True)
    m = reff_maps(face, "bull:D=10,r=2", directions=[0], grid=16, scallop=0.01)
    d = m.directions[0]  # feed along x = the cylinder axis: the section across it is the 40 mm circle
    assert np.allclose(d.rho, 40.0, rtol=1e-9)
    ref, _ = stepover(0.01, d.r_eff, 40.0)
    assert np.allclose(d.stepover, ref, rtol=0, atol=1e-9)


def test_bad_inputs():
    with pytest.raises(InputError, match="radians"):
        parse_directions("0.785,1.57")
    with pytest.raises(InputError, match="not an angle in degrees"):
        parse_directions("400")
    assert parse_directions("all")[:3] == [0.0, 5.0, 10.0]
    plane = builders.plane_patch(dv=(0, 100, 30))
    with pytest.raises(InputError, match="larger than the tool radius"):
        reff_maps(plane, "bull:D=10,r=2", scallop=6.0)
    from test_geometry import cone_with_tip

    with pytest.raises(DegenerateGeometryError, match="normal undefined"):  # a cone's tip: no limit normal
        reff_maps(cone_with_tip(), "bull:D=10,r=2", grid=9)
    with pytest.raises(InputError, match="lead and tilt apply to 5 axes"):
        reff_maps(plane, "bull:D=10,r=2", lead=10)
    with pytest.raises(InputError, match="at or below the tangent plane"):  # the same limit as machining surfaces
        reff_maps(plane, "bull:D=10,r=2", axes=5, lead=90)
    with pytest.raises(InputError, match="tilt angle 1e"):
        reff_maps(plane, "bull:D=10,r=2", axes=5, tilt=1e6)
    with pytest.raises(InputError, match="GiB, over the"):
        reff_maps(plane, "bull:D=10,r=2", grid=4096, directions="all")


def test_unreachable_samples_are_counted_and_left_out_of_the_scores():
    """3 axes on a sphere band from latitude -30 to 60 deg (outward normal away from the centre): the lower
    third faces away from +Z; its area fraction is exact (sin 0 - sin -30) / (sin 60 - sin -30)."""
    from machsurf_cad.geometry import builders

    s = builders.sphere_patch(50.0, (-30.0, 60.0), 90.0)  # su x sv points to the centre
    face = ms.Face(s, name="band", reversed=True)
    m = ms.reff_maps(face, "bull:D=10,r=2", directions=[0.0, 90.0], grid=256)
    exact = (0.0 - math.sin(math.radians(-30))) / (math.sin(math.radians(60)) - math.sin(math.radians(-30)))
    for d in m.report()["directions"]:
        assert abs(d["unreachable_fraction"] - exact) < 0.01, d
        assert d["n_facing_away_samples"] == d["n_unreachable_samples"] > 0
    # the scores are those of the reachable part alone: the same as on the band from 0 to 60 deg
    upper = ms.reff_maps(ms.Face(builders.sphere_patch(50.0, (0.5, 60.0), 90.0), reversed=True), "bull:D=10,r=2",
                         directions=[0.0], grid=256)  # fmt: skip
    a, b = m.report()["directions"][0], upper.report()["directions"][0]
    assert abs(a["r_eff_mean_mm"] - b["r_eff_mean_mm"]) < 0.02 * b["r_eff_mean_mm"]
    assert a["r_eff_max_mm"] < 1e3  # no radius from the far side


def test_a_concave_section_tighter_than_the_tool_is_unreachable():
    """A ball R 8 in a trough of radius 6 (feed along the trough): cannot reach; R 5: can, and the step-over
    on the surface is the circle-circle spacing (arc length), the chord between centres relation (31)."""
    from machsurf_cad.geometry import builders
    from machsurf_cad.scallop import spacing_for_scallop

    arc = builders.circular_arc(6.0, -150.0, -30.0, center=(0.0, 6.0))
    c0 = ms.BSplineCurve(arc.degree, arc.knots, arc.mults, np.c_[np.zeros(len(arc.poles)), arc.poles], arc.weights)
    c1 = ms.BSplineCurve(arc.degree, arc.knots, arc.mults, np.c_[np.full(len(arc.poles), 40.0), arc.poles],
                         arc.weights)  # fmt: skip
    s = builders.ruled_surface(c0, c1)
    up = float(ms.local_properties(s, 0.5, 0.5).normal[2]) > 0
    face = ms.Face(s, name="trough", reversed=not up)
    m = ms.reff_maps(face, "ball:D=16", directions=[0.0], grid=64, scallop=0.01)
    d = m.report()["directions"][0]
    assert d["unreachable_fraction"] == 1.0 and d["r_eff_mean_mm"] is None
    m = ms.reff_maps(face, "ball:D=10", directions=[0.0], grid=64, scallop=0.01)
    d = m.report()["directions"][0]
    assert d["unreachable_fraction"] == 0.0
    w = float(spacing_for_scallop(0.01, 5.0, -1 / 6.0))
    # chord between the centres, 1 mm from the trough's axis: 2 (6 - 5) sin(w / (2 * 6))
    assert abs(d["stepover_surface_mean_mm"] - w) < 1e-9
    assert abs(d["stepover_mean_mm"] - 2 * 1.0 * math.sin(w / 12.0)) < 1e-9
