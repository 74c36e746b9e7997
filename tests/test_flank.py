"""Flank milling: closed forms, developable surfaces, tangency residuals, brute-force interference,
whole-surface path and envelope, radius search, bad input."""

import math

import numpy as np
import pytest
from conftest import needs_kernel

from machsurf_cad import examples
from machsurf_cad.errors import InputError
from machsurf_cad.flank_milling import (
    SETTINGS,
    NoAdmissibleSetting,
    RuledSurface,
    interference,
    minimax_setting,
    optimum_setting,
    rule_frame,
    standard_setting,
)
from machsurf_cad.geometry import BSplineCurve, builders


def _arc3d(radius, z, start=0.0, end=120.0):
    a = builders.circular_arc(radius, start, end)
    return BSplineCurve(a.degree, a.knots, a.mults, np.column_stack([a.poles, np.full(len(a.poles), z)]), a.weights)


@pytest.mark.parametrize("shape", ["cylinder", "cone"])
@pytest.mark.parametrize("side", [1, -1])
def test_developable_surfaces_are_exact(shape, side):
    top = 30.0 if shape == "cylinder" else 18.0
    s = RuledSurface.from_curves(_arc3d(30.0, 0.0), _arc3d(top, 50.0))
    st = optimum_setting(s, 0.5, 8.0, side=side)
    assert interference(s, st).max_abs < 1e-6
    assert rule_frame(s, 0.5, side).alpha0_deg < 1e-6


def test_closed_forms_on_straight_directrices():
    s = examples.hypar_ruled(30.0, 80.0)
    for R in (10.0, 40.0):
        fr = rule_frame(s, 0.5)
        a0 = math.radians(fr.alpha0_deg)
        assert fr.alpha0_deg == pytest.approx(30.0, abs=1e-9)
        e = interference(s, standard_setting(s, 0.5, R))
        assert e.max_gouge == pytest.approx(R * (1 - math.cos(a0)), rel=1e-9)  # R (1 - cos alpha0)
        assert e.max_undercut == pytest.approx(0.0, abs=1e-12)
        e = interference(s, standard_setting(s, 0.5, R, distributed=False))
        assert e.max_gouge == pytest.approx(R * (1 - math.cos(2 * a0)), rel=1e-9)  # tangent: the full angle


def test_tangency_conditions_hold_at_the_solution():
    for s, u_p, R in (
        (examples.liu_ruled(), 11.507, 10.0),
        (examples.hypar_ruled(), 0.5, 40.0),
        (examples.eq18_ruled(), 0.4, 10.0),
    ):
        st = optimum_setting(s, u_p, R)
        q, a = st.q, st.a

        def dist(p, q=q, a=a):
            w = p - q
            return np.linalg.norm(w - (w @ a) * a)

        for key, c in (("u0", s.c0), ("u1", s.c1)):
            u = st.contacts[key]
            h = 1e-6
            d0 = dist(c(np.array([u]), 0)[0, 0])
            assert abs(d0 - R) < 1e-9
            slope = (dist(c(np.array([u + h]), 0)[0, 0]) - dist(c(np.array([u - h]), 0)[0, 0])) / (2 * h)
            assert abs(slope) < 1e-6 * max(1.0, np.linalg.norm(c(np.array([u]), 1)[0, 1]))
        # the rule touches the cylinder at M2: the rule line is at distance R from the axis
        fr = st.frame
        m2 = st.contacts["M2"]
        assert abs(dist(m2) - R) < 1e-9
        cross = np.cross(fr.z1, a)
        line_dist = abs((fr.p0 - q) @ cross) / np.linalg.norm(cross)
        assert abs(line_dist - R) < 1e-9


def test_interference_matches_brute_force():
    s = examples.liu_ruled()
    for kind in ("standard", "optimum"):
        st = standard_setting(s, 11.507, 10.0) if kind == "standard" else optimum_setting(s, 11.507, 10.0)
        e = interference(s, st, n_v=51)
        # brute force: dense points of the band, distance to the axis minus R, min over u per v
        su = np.linalg.norm(s.derivatives(np.full(51, 11.507), e.v)[1], axis=1)
        best = np.empty(51)
        for i, (v, du) in enumerate(zip(e.v, 10.0 / su)):
            u = np.linspace(max(0, 11.507 - du), min(23.014, 11.507 + du), 200001)
            p = s.evaluate(u, np.full(u.shape, v))
            w = p - st.q
            w = w - (w @ st.a)[:, None] * st.a
            best[i] = np.linalg.norm(w, axis=1).min() - 10.0
        assert np.abs(best - e.e).max() < 1e-6


def test_optimum_beats_standard_tenfold_on_the_hyperbolic_paraboloid():
    from machsurf_cad.flank_milling.study import ratio_curve

    c = ratio_curve(30.0, 80.0, [5.0, 10.0, 20.0, 40.0, 60.0, 78.0])
    assert min(c["ratio"]) >= 10.0
    s = examples.hypar_ruled(30.0, 80.0)
    optimum_setting(s, 0.5, 79.9)  # below h_p / (2 sin alpha0) = 80 mm: exists
    with pytest.raises(NoAdmissibleSetting, match="no admissible"):
        optimum_setting(s, 0.5, 81.0)


def test_minimax_is_no_worse_than_optimum():
    s = examples.liu_ruled()
    o = interference(s, optimum_setting(s, 11.507, 10.0)).max_abs
    m = interference(s, minimax_setting(s, 11.507, 10.0)).max_abs
    assert m <= o + 1e-9


def test_whole_surface_path_envelope_and_its_deviation():
    from machsurf_cad.flank_milling.path import envelope_deviation, envelope_surface, flank_path, position_deviation

    s = examples.hypar_ruled(20.0, 80.0)
    path = flank_path(s, 15.0, "optimum", tolerance=0.01)
    assert len(path.settings) >= 9 and path.axis.shape == (len(path.settings), 3)
    assert np.allclose(np.linalg.norm(path.axis, axis=1), 1.0, rtol=0, atol=1e-9)
    env = envelope_surface(path, tolerance=1e-3)
    assert env.max_error <= 1e-3
    # the fitted envelope lies on the cylinder of the position at its own time t: at R from that axis
    from scipy.interpolate import CubicSpline

    ts = np.linspace(path.u[0], path.u[-1], 9)
    X = env.surface.evaluate_grid(np.linspace(0, path.length, 7), ts)
    P = CubicSpline(path.u, path.tip, axis=0)(ts)
    A = CubicSpline(path.u, path.axis, axis=0)(ts)
    A /= np.linalg.norm(A, axis=1, keepdims=True)
    w = X - P[None]
    w = w - np.einsum("ijk,jk->ij", w, A)[..., None] * A[None]
    assert np.abs(np.linalg.norm(w, axis=-1) - path.R).max() <= 1e-3
    dev = envelope_deviation(path, env.surface, n=41)
    pts, brute = position_deviation(path, n_u=41, n_v=41, refine=60)  # dense positions: near-continuous motion
    inner = ~dev.on_boundary
    # the map's magnitude (distance to the envelope) matches the brute-force swept-volume distance
    assert np.abs(np.abs(dev.signed[inner]) - np.abs(brute.ravel()[inner])).max() < 5e-3
    assert dev.stats["min"] == pytest.approx(min(brute.min(), 0.0), abs=5e-3)  # one gouge sign: negative


def test_radius_range_brackets_the_tolerance():
    from machsurf_cad.flank_milling.path import radius_range, whole_surface_error

    s = examples.hypar_ruled(30.0, 80.0)
    rr = radius_range(s, 0.1, kind="optimum", r_min=1.0, r_max=100.0, n_scan=10, n_rules=5, rel_precision=1e-2)
    assert rr["feasible"] and rr["iterations"]
    assert whole_surface_error(s, rr["R_max_mm"], "optimum", 1, 5) <= 0.1
    assert whole_surface_error(s, rr["R_max_mm"] * 1.03, "optimum", 1, 5) > 0.1


def test_bad_inputs():
    s = examples.hypar_ruled()
    with pytest.raises(InputError, match="outside"):
        optimum_setting(s, 1.5, 10.0)
    crossing = RuledSurface.from_curves(
        builders.line_segment([0, 0, 0], [10, 0, 0]), builders.line_segment([0, 0, 5], [10, 0, -5])
    )
    with pytest.raises(InputError, match="zero length"):
        standard_setting(crossing, 0.5, 5.0)
    with pytest.raises(InputError, match="not a ruled surface: it deviates by"):
        RuledSurface.from_surface(examples.bezier5_patch())
    approx = RuledSurface.from_surface(examples.bezier5_patch(), tolerance=50.0)
    assert 0 < approx.source_deviation < 50.0
    exact = RuledSurface.from_surface(examples.liu_surface())
    assert exact.source_deviation < 1e-9
    with pytest.raises(InputError, match="tool radius"):
        optimum_setting(s, 0.5, -1.0)


def test_optimum_returns_the_best_of_every_solution_found():
    """Liu's surface, R = 10, u = 1, side -1: two three-tangency settings exist; the first one found used to
    be kept (0.0033 mm, a contact beyond the surface); the best (both contacts on it) is 0.0004 mm."""
    s = examples.liu_ruled()
    st = optimum_setting(s, 1.0, 10.0, side=-1)
    e = interference(s, st).max_abs
    others = st.contacts["other_solutions"]
    assert e < 0.0005 and not st.contacts["contact_outside_surface"]
    assert others and min(o["max_abs_mm"] for o in others) > 5 * e


def test_eq18_side_minus_one_optimum_exists_far_from_the_standard_setting():
    """Eq. (18), u = 0.4, R = 40, side -1: the solver used to report "no admissible optimum"; a setting with
    both tangencies exists at gamma = -26.6 deg, h0 = 69.6 mm, error 17.12 mm (an independent solve)."""
    s = examples.eq18_ruled()
    st = optimum_setting(s, 0.4, 40.0, side=-1)
    assert abs(st.gamma_deg + 26.6) < 0.05 and abs(st.h0 - 69.6) < 0.05
    assert abs(interference(s, st).max_abs - 17.12) < 0.01
    assert st.contacts["tangency_residual_mm"] < 1e-9


def test_error_along_the_rule_is_exported_for_every_setting(tmp_path):
    """``flank`` writes the error along the rule of every setting (the paper's figures 6 and 7) as CSV
    (and a plot): the columns equal an independent call of ``interference`` per setting, and the
    optimum's on Liu's middle rule (R 10) is the pinned 0.03393 mm."""
    import csv

    from helpers import run

    from machsurf_cad.flank_milling import interference, tool_setting

    r = run("flank", "--example", "liu", "--tool", "cyl:D=20", "--rule", "0.5", "--no-render", "-o", tmp_path / "f")
    assert r.returncode == 0, r.stdout + r.stderr
    rows = list(csv.reader((tmp_path / "f" / "error_along_rule.csv").open()))
    head, data = rows[0], np.array(rows[1:], float)
    assert head == ["v"] + [f"{k}_mm" for k in SETTINGS]
    assert data.shape == (201, 6) and np.allclose(data[:, 0], np.linspace(0, 1, 201), atol=1e-6)
    surf = examples.liu_ruled()
    lo, hi = surf.u_range
    for j, kind in enumerate(head[1:], 1):
        e = interference(surf, tool_setting(surf, lo + 0.5 * (hi - lo), 10.0, kind.removesuffix("_mm")))
        assert np.abs(data[:, j] - e.e).max() < 1e-8, kind
    assert abs(np.abs(data[:, head.index("optimum_mm")]).max() - 0.03393) < 5e-6


def test_error_along_the_rule_plot(tmp_path):
    pytest.importorskip("matplotlib")
    from helpers import run

    r = run("flank", "--example", "liu", "--tool", "cyl:D=20", "--rule", "0.5", "-o", tmp_path / "f")
    assert r.returncode == 0 and (tmp_path / "f" / "error_along_rule.png").stat().st_size > 20_000


def test_pinned_figures_of_the_paper_cases():
    """Reproducible figures (issue 16): the hyperbolic paraboloid (alpha0 = 30 deg, h_p = 80 mm, R = 40 mm)
    standard-distributed 5.35898 mm and optimum 0.11852 mm; the optimum exists up to R = h_p / (2 sin alpha0) = 80
    mm and not beyond; eq. (18) at u = 0.4, R = 40, side -1: the three-tangency optimum of 17.12 mm that
    a start far from the standard setting finds."""
    from machsurf_cad.flank_milling import tool_setting

    hp = examples.hypar_ruled(30.0, 80.0)
    lo, hi = hp.u_range
    mid = 0.5 * (lo + hi)
    assert abs(interference(hp, tool_setting(hp, mid, 40.0, "standard-distributed")).max_abs - 5.35898) < 1e-5
    assert abs(interference(hp, tool_setting(hp, mid, 40.0, "optimum")).max_abs - 0.11852) < 1e-5
    limit = 80.0 / (2 * math.sin(math.radians(30.0)))
    assert interference(hp, tool_setting(hp, mid, limit - 0.1, "optimum")).max_abs < 1.0
    with pytest.raises(NoAdmissibleSetting, match=r"R = 80.1 mm.*up to R = h_p / \(2 sin alpha0\) = 80 mm"):
        tool_setting(hp, mid, limit + 0.1, "optimum")
    e18 = examples.eq18_ruled()
    assert abs(interference(e18, tool_setting(e18, 0.4, 40.0, "optimum", side=-1)).max_abs - 17.1227) < 1e-3


def _circle_and_line(rho, beta_deg, h):
    """C0 a circle arc of radius rho in z = 0 (centre (0, rho, 0)), C1 a straight line in z = h at beta_deg
    to C0's tangent at u = 0, whose rule is along z: there the sections normal to the rule are the
    directrices themselves, so Rubio's formulas (circle against the tool's circle) are exact."""
    b = math.radians(beta_deg)

    def c0(u, order=2):
        u = np.asarray(u, float)
        z = np.zeros_like(u)
        rows = [
            np.stack([rho * np.sin(u), rho * (1 - np.cos(u)), z], -1),
            np.stack([rho * np.cos(u), rho * np.sin(u), z], -1),
            np.stack([-rho * np.sin(u), rho * np.cos(u), z], -1),
        ]
        return np.stack(rows[: order + 1], -2)

    def c1(u, order=2):
        u = np.asarray(u, float)
        one, z = np.ones_like(u), np.zeros_like(u)
        rows = [
            np.stack([rho * u * math.cos(b), rho * u * math.sin(b), h * one], -1),
            np.stack([rho * math.cos(b) * one, rho * math.sin(b) * one, z], -1),
            np.stack([z, z, z], -1),
        ]
        return np.stack(rows[: order + 1], -2)

    return RuledSurface(c0, c1, (-0.6, 0.6), "circle_line")


@pytest.mark.parametrize(("rho", "beta", "R"), [(30.0, 30.0, 10.0), (15.0, 50.0, 8.0), (200.0, 20.0, 25.0)])
def test_standard_distributed_is_rubios_equal_error_setting(rho, beta, R):
    """Rubio's distributed standard setting shares the error equally between the directrices: on a
    circle (radius rho, convex towards the tool) and a line at beta to it, the error is the paper's
    rho + R - sqrt(R^2 + rho^2 + 2 R rho cos a0) = R (1 - cos a1), a0 + a1 = beta (solved here), and
    the bisector variant (a0 = a1) is worse at the circle."""
    from scipy.optimize import brentq

    s = _circle_and_line(rho, beta, 40.0)
    b = math.radians(beta)
    a0 = brentq(
        lambda a: rho + R - math.sqrt(R * R + rho * rho + 2 * R * rho * math.cos(a)) - R * (1 - math.cos(b - a)), 0, b
    )
    eps = R * (1 - math.cos(b - a0))
    st = standard_setting(s, 0.0, R)
    e0, e1 = st.contacts["end_errors_mm"]
    assert st.kind == "standard-distributed"
    assert abs(e0 + eps) < 1e-9 and abs(e1 + eps) < 1e-9
    e = interference(s, st)
    assert abs(e.e[0] + eps) < 1e-9 and abs(e.e[-1] + eps) < 1e-9 and abs(e.max_abs - eps) < 1e-9
    bis = interference(s, standard_setting(s, 0.0, R, split="bisector"))
    circle_error = rho + R - math.sqrt(R * R + rho * rho + 2 * R * rho * math.cos(b / 2))
    assert abs(bis.e[0] + circle_error) < 1e-9 and bis.max_abs > eps


def test_distributed_and_bisector_on_the_paper_surfaces():
    """Hyperbolic paraboloid (straight directrices): equal error is the bisector, R (1 - cos alpha0) =
    5.35898 mm; Liu's middle rule (R 10, curved C1): equal error 0.483864 mm against the bisector's
    0.564782 mm (Rubio's closed form with the normal-section curvature radius gives 0.4886 mm)."""
    from machsurf_cad.flank_milling import tool_setting

    hp = examples.hypar_ruled(30.0, 80.0)
    mid = 0.5 * sum(hp.u_range)
    d = interference(hp, tool_setting(hp, mid, 40.0, "standard-distributed")).max_abs
    b = interference(hp, tool_setting(hp, mid, 40.0, "standard-bisector")).max_abs
    assert abs(d - 40 * (1 - math.cos(math.radians(30)))) < 1e-9 and abs(b - d) < 1e-9
    liu = examples.liu_ruled()
    mid = 0.5 * sum(liu.u_range)
    d = interference(liu, tool_setting(liu, mid, 10.0, "standard-distributed"))
    b = interference(liu, tool_setting(liu, mid, 10.0, "standard-bisector"))
    assert abs(d.max_abs - 0.483864) < 1e-6 and abs(b.max_abs - 0.564782) < 1e-6
    assert abs(d.e[0] - d.e[-1]) < 1e-9


@pytest.mark.parametrize(("side", "key", "bracket", "u_edge", "error"), [
    (1, "u0", (20.13, 20.72), 20.42304, 0.18456),
    (-1, "u1", (21.28, 21.87), 21.51005, 0.25717),
])  # fmt: skip
def test_liu_optimum_where_its_contact_reaches_the_surface_edge(side, key, bracket, u_edge, error):
    """Liu's surface, R = 10: beyond the rule where a tangency point reaches the end of the directrix
    (C0 on side +1, C1 on side -1) the optimum's contacts leave the surface; the error on that last rule
    whose contacts stay on the surface is pinned (the rule found by a root solve of the contact position)."""
    from scipy.optimize import brentq

    from machsurf_cad.flank_milling import tool_setting

    s = examples.liu_ruled()
    hi = s.u_range[1]
    u = brentq(lambda x: tool_setting(s, x, 10.0, "optimum", side=side).contacts[key] - hi, *bracket, xtol=1e-12)
    st = tool_setting(s, u, 10.0, "optimum", side=side)
    assert abs(u - u_edge) < 1e-5 and abs(st.contacts[key] - hi) < 1e-9
    assert abs(interference(s, st).max_abs - error) < 1e-5


@needs_kernel  # --whole writes the envelope as STEP
def test_whole_liu_side_minus_one_is_checked_against_the_material_side(tmp_path):
    """An example surface is a bare sheet: with the tool on side -1 the material is on the normal's side.
    The tool-body check then finds only the cut's own interference (as the settings' along-rule error
    says), no collision of the sideways approach or retract."""
    import json

    from helpers import run

    r = run("flank", "--example", "liu", "--whole", "--side", "-1", "--no-render", "-o", tmp_path / "f")
    assert r.returncode == 2, r.stdout + r.stderr
    rep = json.loads((tmp_path / "f" / "report.json").read_text())
    v, w = rep["whole"]["verify"], rep["whole"]
    assert v["n_collisions"] == 0
    assert all(g["move"] == "cut" for g in v["worst"])
    assert abs(v["max_gouge_mm"] - w["max_gouge_mm"]) < 0.01


def test_whole_path_beyond_the_existence_limit_falls_back_and_is_cut_into_segments():
    """Hyperbolic paraboloid (alpha0 30 deg, h_p 80 mm) with R = 80.5 mm, just beyond the middle rule's
    existence limit of 80 mm: the optimum is missing around the middle, where Rubio's setting is used
    (its error is the closed form R (1 - cos alpha0) there); the path is cut into three continuous
    segments at the two jumps, one pass each."""
    from machsurf_cad.flank_milling import flank_path

    s = examples.hypar_ruled(30.0, 80.0)
    p = flank_path(s, 80.5, "optimum", tolerance=0.01)
    fb = p.fallback_u
    assert fb.size > 0 and 0.35 < fb.min() < 0.5 < fb.max() < 0.65
    assert all(st.kind == ("standard-distributed" if st.frame.u_p in fb else "optimum") for st in p.settings)
    segs = p.segments()
    assert [len(x.settings) for x in segs] == [np.sum(p.u < fb.min()), fb.size, np.sum(p.u > fb.max())]
    assert abs(segs[1].max_gouge - 80.5 * (1 - math.cos(math.radians(30)))) < 1e-6
    for seg in segs:  # inside a segment the axis moves continuously (within the step criterion)
        assert np.linalg.norm(np.diff(seg.tip, axis=0), axis=1).max() < 5.0
    assert p.toolpath().report()["n_passes"] == 3
    assert len(p.report()["segments_u"]) == 3 and p.report()["n_fallback_rules"] == fb.size


def test_deviation_on_the_positions_agrees_with_the_envelope():
    """Where a segment's envelope cannot be fitted its map is measured on the tool positions: on Liu's
    surface both maps exist and agree within 0.002 mm (the largest deviation 0.3468 mm on both)."""
    from machsurf_cad.flank_milling import flank_path
    from machsurf_cad.flank_milling.path import envelope_deviation, envelope_surface, positions_deviation

    p = flank_path(examples.liu_ruled(), 10.0, "optimum", tolerance=0.01)
    a = envelope_deviation(p, envelope_surface(p, tolerance=1e-3).surface, n=61)
    b = positions_deviation(p, n=61)
    assert np.abs(a.signed - b.signed).max() < 0.002
    assert abs(a.max_abs - 0.3468) < 1e-4 and abs(b.max_abs - a.max_abs) < 1e-9


@pytest.mark.slow
def test_smooth_minimax_path_bounds_the_axis_turn_and_beats_the_rule_optima():
    """Beyond the paper: minimax settings along the surface with the axis turn between rules bounded.
    The turn rate (angle between consecutive axes over the travel of the rules' middles, computed here)
    stays within the bound, every rule's error is its interference, and the largest error is below the
    rule-by-rule optima's on the same rules (Liu, R 10, 6 rules)."""
    from machsurf_cad.flank_milling import compare_with_rule_optima, smooth_minimax_path

    s = examples.liu_ruled()
    p = smooth_minimax_path(s, 10.0, n_rules=6, max_turn_rate=2.5)
    mids = np.array([0.5 * (st.frame.p0 + st.frame.p1) for st in p.settings])
    turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", p.axis[:-1], p.axis[1:]), -1, 1)))
    rate = turn / np.linalg.norm(np.diff(mids, axis=0), axis=1)
    assert rate.max() <= 2.5 * (1 + 1e-6) and p.smoothness["bound_met"]
    assert abs(rate.max() - p.smoothness["max_turn_reached_deg_per_mm"]) < 1e-9
    errs = [interference(s, st, n_v=101) for st in p.settings]
    assert abs(max(e.max_gouge for e in errs) - p.max_gouge) < 1e-12
    c = compare_with_rule_optima(s, 10.0, n_rules=6, max_turn_rate=2.5)
    assert c["smooth_minimax"]["max_abs_mm"] < 0.5 * c["rule_optima"]["max_abs_mm"]
    with pytest.raises(InputError, match="max_turn_rate must be > 0"):
        smooth_minimax_path(s, 10.0, max_turn_rate=-1.0)


def test_smooth_bound_below_zero_is_a_one_line_error(tmp_path):
    from helpers import run

    r = run("flank", "--example", "hypar", "--smooth", "-1", "--no-render", "-o", tmp_path / "f")
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines() == [
        "machsurf: error: smooth must be an axis turn bound >= 0 deg/mm (0: the default), got -1.0"
    ]


def test_eq18_at_r40_on_both_sides():
    """Eq. (18), u = 0.4, R = 40 mm, both sides (the rule is twisted by 2 x 64.7 deg): Rubio's equal-error
    standard setting 23.5121 mm (side +1) and 20.5387 mm (side -1), the tangent one 11.4839 / 39.8790 mm;
    the optimum exists only on side -1 (17.1227 mm) and its absence on side +1 names the limit."""
    from machsurf_cad.flank_milling import tool_setting

    s = examples.eq18_ruled()
    for side, dist, tang in ((1, 23.5121, 11.4839), (-1, 20.5387, 39.8790)):
        st = tool_setting(s, 0.4, 40.0, "standard-distributed", side=side)
        e0, e1 = st.contacts["end_errors_mm"]
        assert abs(e0 - e1) < 1e-9 and abs(interference(s, st).max_abs - dist) < 1e-4
        assert abs(interference(s, tool_setting(s, 0.4, 40.0, "standard-tangent", side=side)).max_abs - tang) < 1e-4
    assert abs(interference(s, tool_setting(s, 0.4, 40.0, "optimum", side=-1)).max_abs - 17.1227) < 1e-4
    with pytest.raises(NoAdmissibleSetting, match=r"side \+1 at u = 0.4.*up to R = h_p / \(2 sin alpha0\)"):
        tool_setting(s, 0.4, 40.0, "optimum", side=1)
