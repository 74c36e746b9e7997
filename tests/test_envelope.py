"""Swept envelopes (eq. (21)) and adjacent passes (Corollaries 5.2, 5.3, 5.5) against brute force."""

import math

import numpy as np
import pytest

from machsurf_cad.errors import DegenerateGeometryError, InputError
from machsurf_cad.examples import helix_motion, sine_motion
from machsurf_cad.sweep import Motion, fold_check, make_envelope, next_pass, seam_report
from machsurf_cad.sweep.passes import build_chain, max_theta

TOOLS = [
    "cyl:D=10,L=20",
    "cone:D=10,angle=10,L=20",
    "cone:D=12,angle=-8,L=15",
    "drum:D=20,Rp=40,L=20",
    "barrel:D=20,Rp=40,L=20",
]


def _tool_distance(env, X, t):
    """Signed distance from points X to the tool surface at time t (min over the sphere family), and the
    sphere parameter where it is attained: brute force over 4001 spheres."""
    a = np.linspace(*env.a_range, 4001)
    T, A = env.motion.T(np.array([t]))[0], env.motion.A(np.array([t]))[0]
    c = T + a[:, None] * A
    r = env.segment.r(a)
    d = np.linalg.norm(X[:, None, :] - c[None, :, :], axis=-1) - r[None, :]
    return d.min(axis=1), a[np.argmin(d, axis=1)]


@pytest.mark.parametrize("tool", TOOLS)
def test_envelope_points_lie_on_the_tool_with_its_normal(tool):
    env = make_envelope(helix_motion(), tool)
    a = np.linspace(*env.a_range, 9)
    for t in (0.1, 0.5, 0.9):
        X = env.points(a, np.full(a.shape, t))
        n, _ = env.normals(a, np.full(a.shape, t))
        S, _, _, r, _, A = env.frame(a, np.full(a.shape, t))
        # exactly on the sphere of parameter a, with the sphere's outward normal
        assert np.abs(np.linalg.norm(X - S, axis=1) - r).max() < 1e-9
        assert np.abs((X - S) / r[:, None] - n).max() < 1e-9
        # and outside every other sphere of the tool: on the tool surface
        dmin, _ = _tool_distance(env, X, t)
        assert np.abs(dmin).max() < 1e-6
        # normals point away from the axis
        radial = (X - S) - np.einsum("ij,ij->i", X - S, A)[:, None] * A
        assert np.all(np.einsum("ij,ij->i", radial, n) >= -1e-12)


def test_envelope_agrees_with_dense_discrete_positions():
    env = make_envelope(sine_motion(), "cone:D=10,angle=10,L=20")
    a = np.linspace(*env.a_range, 7)
    ts = np.linspace(0.2, 0.8, 4)
    X = env.points(*np.meshgrid(a, ts, indexing="ij")).reshape(-1, 3)
    dense = np.linspace(0.0, 1.0, 801)
    best = np.full(X.shape[0], np.inf)
    for t in dense:
        d, _ = _tool_distance(env, X, t)
        best = np.minimum(best, d)
    # no discrete tool position cuts into the envelope, and it is reached (up to the t spacing)
    assert best.min() > -1e-6
    assert best.max() < 2e-3


def test_closed_forms_ball_and_cylinder():
    line = Motion.line((0, 0, 0), (100, 0, 0), axis=(0, 0, 1))
    ball = make_envelope(line, "ball:D=10")
    X = ball.grid(np.linspace(-90, 90, 13), np.linspace(0, 1, 11))
    assert np.abs(np.hypot(X[..., 1], X[..., 2] - 5.0) - 5.0).max() < 1e-12  # a cylinder about the centre line
    for side in (1, -1):
        cyl = make_envelope(line, "cyl:D=10,L=30", side=side)
        X = cyl.grid(np.linspace(0, 30, 7), np.linspace(0, 1, 9))
        assert np.abs(X[..., 1] - 5.0 * side).max() < 1e-12  # the plane pair y = +-5


def test_cone_starts_at_the_real_tip():
    line = Motion.line((0, 0, 0), (100, 0, 0), axis=(0, 0, 1))
    env = make_envelope(line, "cone:D=10,angle=10,L=20")
    assert env.a_range[0] == pytest.approx(5 * math.tan(math.radians(10)))
    X = env.points(np.full(5, env.a_range[0]), np.linspace(0, 1, 5))
    assert np.abs(X[:, 2]).max() < 1e-12  # level with the tool tip, not below it
    assert np.abs(np.abs(X[:, 1]) - 5.0).max() < 1e-12  # at the tip radius D/2


@pytest.mark.parametrize("theta", [0.0, 20.0, -30.0])
def test_g1_seams_before_and_after_fitting(theta):
    first = make_envelope(sine_motion(), "cone:D=10,angle=10,L=20")
    chain = build_chain(first, 3, continuity="g1", theta_deg=theta, tolerance=1e-3)
    for s in chain.seams_exact:
        assert s["max_gap_mm"] < 1e-6 and s["max_normal_angle_deg"] < 1e-4
    for s, f in zip(chain.seams_fitted, chain.fits):
        assert s["max_gap_mm"] <= 2e-3 and f.max_error <= 1e-3
    # the axis condition (40): A2 . n1(a1, t) = -r'(a0) = -sin(10 deg)
    e1, e2 = chain.passes[0], chain.passes[1]
    t = np.linspace(0, 1, 21)
    n1, _ = e1.normals(np.full(21, e1.a_range[1]), t)
    assert np.abs(np.einsum("ij,ij->i", e2.motion.A(t), n1) + math.sin(math.radians(10))).max() < 1e-9


def test_different_tools_and_g0():
    first = make_envelope(sine_motion(), "cone:D=10,angle=10,L=20")
    cyl = next_pass(first, "cyl:D=8,L=15", continuity="g1")  # Corollary 5.2: another tool
    s = seam_report(first, cyl)
    assert s["max_gap_mm"] < 1e-6 and s["max_normal_angle_deg"] < 1e-4
    g0 = next_pass(first, continuity="g0", kink_deg=12.0)
    s = seam_report(first, g0)
    assert s["max_gap_mm"] < 1e-6 and s["max_normal_angle_deg"] == pytest.approx(12.0, abs=1e-3)


def test_fold_back_is_detected_not_assumed():
    first = make_envelope(sine_motion(), "cone:D=10,angle=10,L=20")
    lim = max_theta(first)
    assert 0 < lim < 90  # it happens well before 90 degrees, and we find where
    fc = fold_check(first, next_pass(first, theta_deg=lim + 30))
    assert fc["folds_back"] or not fc["real_envelope"]
    with pytest.raises(InputError, match="folds back|no real envelope"):
        build_chain(first, 2, theta_deg=lim + 30)


def test_bad_inputs():
    with pytest.raises(InputError, match="zero-length axis"):
        Motion.line((0, 0, 0), (1, 0, 0), axis=(0, 0, 0))
    with pytest.raises(InputError, match="cusp"):
        Motion.from_points([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0], [3, 1, 0]])
    steep = Motion.line((0, 0, 0), (1, 0, 20), axis=(0, 0, 1))  # moving almost along the axis
    with pytest.raises(DegenerateGeometryError, match="no real envelope"):
        make_envelope(steep, "cone:D=10,angle=10,L=20").points(np.array([3.0]), np.array([0.5]))
    first = make_envelope(sine_motion(), "cone:D=10,angle=10,L=20")
    with pytest.raises(InputError, match="theta"):
        next_pass(first, theta_deg=200.0)
