"""Cutters: parsing, validation, and the sphere-family form against the profile."""

import math

import numpy as np
import pytest

from machsurf_cad.cutters import ArcSegment, BallEndMill, BullNoseEndMill, ConicalCutter, LineSegment, parse_cutter
from machsurf_cad.errors import InputError

SPECS = [
    "ball:D=10",
    "flat:D=16",
    "bull:D=20,r=4",
    "cone:D=10,angle=6",
    "cone:D=10,angle=-8",
    "drum:D=20,Rp=40,L=20",
    "barrel:D=20,Rp=40,L=20",
    "apt:D=20,r=4,e=6,f=4,alpha=10,beta=5,h=60",
]


@pytest.mark.parametrize("spec", SPECS)
def test_spec_round_trip(spec):
    c = parse_cutter(spec)
    assert parse_cutter(c.spec()) == c


def test_names_and_paper_mapping():
    b = parse_cutter("bull:D=20,r=4")
    assert isinstance(b, BullNoseEndMill)
    assert b.R_t == 6.0 and b.radius == 10.0 and b.r == 4.0
    assert parse_cutter("ball:D=10") == BallEndMill(10.0)


@pytest.mark.parametrize(
    "text, word",
    [
        ("bull:D=10,r=6", "r = 6"),
        ("ball:D=-3", "D must be > 0"),
        ("ball:D=nan", "finite"),
        ("wobble:D=3", "unknown cutter kind"),
        ("ball:X=3", "unknown parameter 'X'"),
        ("bull:D=10", "needs parameters: r"),
        ("ball", "kind:K=V"),
        ("cone:D=10,angle=95", "angle"),
        ("flat:D=abc", "must be a number"),
    ],
)
def test_bad_cutters_raise_naming_the_parameter(text, word):
    with pytest.raises(InputError, match=word.replace("(", r"\(")):
        parse_cutter(text)


def _on_profile(cutter, pts, tol=1e-9):
    """Distance of (rho, z) points to the cutter's profile segments (independent geometry)."""
    best = np.full(pts.shape[0], np.inf)
    for seg in cutter.profile():
        if isinstance(seg, LineSegment):
            a = np.array([seg.rho0, seg.z0])
            b = np.array([seg.rho1, seg.z1])
            t = np.clip(((pts - a) @ (b - a)) / max((b - a) @ (b - a), 1e-300), 0, 1)
            d = np.linalg.norm(pts - (a + t[:, None] * (b - a)), axis=1)
        else:
            d = np.abs(np.hypot(pts[:, 0] - seg.rho_c, pts[:, 1] - seg.z_c) - seg.radius)
        best = np.minimum(best, d)
    return best


@pytest.mark.parametrize("spec", SPECS)
def test_sphere_family_grazes_the_profile(spec):
    c = parse_cutter(spec)
    fam = c.sphere_family()
    assert fam, "every cutter has a non-planar part"
    for seg in fam:
        if seg.kind == "point":
            continue
        a = np.linspace(seg.a0, seg.a1, 201)
        g = seg.grazing_points(a)
        assert _on_profile(c, g).max() < 1e-9
        # the sphere touches there: its radius is the distance from its centre on the axis
        assert np.abs(np.hypot(g[:, 0], g[:, 1] - a) - seg.r(a)).max() < 1e-9
        # r'(a) is the derivative of r(a)
        h = 1e-6
        fd = (seg.r(a[1:-1] + h) - seg.r(a[1:-1] - h)) / (2 * h)
        assert np.abs(fd - seg.r_a(a[1:-1])).max() < 1e-6


def test_cone_family_matches_envelope_paper_formula():
    # paper eq. (2): r(a) = R0 cos(phi) + a sin(phi) with R0 the radius at the sphere a = 0
    c = ConicalCutter(10.0, 6.0, 30.0)
    seg = c.sphere_family()[-1]
    phi = math.radians(6)
    R0 = 5.0
    a = np.linspace(seg.a0, seg.a1, 50)
    # in the paper's frame the tip plane is not at a = 0: shift by the tip offset
    a_paper = a - 0.0
    assert np.allclose(seg.r(a), (R0 / math.cos(phi)) + (a_paper - R0 * math.tan(phi)) * math.sin(phi))
    assert math.isclose(seg.a0, R0 * math.tan(phi))  # starts at the real tip, not below it
    assert math.isclose(seg.r(seg.a0), R0 / math.cos(phi))


def test_ball_family_is_one_sphere_and_bull_corner_is_hyperbolic():
    fam = parse_cutter("ball:D=10").sphere_family()
    assert fam[0].kind == "point" and fam[0].radius == 5 and fam[0].a0 == 5
    corner = parse_cutter("bull:D=20,r=4").sphere_family()[0]
    a = np.linspace(corner.a0, corner.a1, 20)
    assert np.allclose(corner.r(a), 4 + np.sqrt(36 + (a - 4) ** 2))


def test_profiles_are_continuous():
    for spec in SPECS:
        segs = parse_cutter(spec).profile()
        for s0, s1 in zip(segs[:-1], segs[1:]):
            assert np.allclose(s0.points(2)[-1], s1.points(2)[0], atol=1e-12), spec
        assert isinstance(segs[0], (LineSegment, ArcSegment))
