"""Cutters: parsing, validation, and the sphere-family form against the profile."""

import math

import numpy as np
import pytest
from helpers import assert_close

from machsurf_cad.cutters import (
    ArcSegment,
    BallEndMill,
    BullNoseEndMill,
    ConicalCutter,
    FlatEndMill,
    LineSegment,
    Shank,
)
from machsurf_cad.errors import InputError
from machsurf_cad.toolspec import cutter_from_apt, parse_cutter

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
    assert np.allclose(
        seg.r(a), (R0 / math.cos(phi)) + (a_paper - R0 * math.tan(phi)) * math.sin(phi), rtol=0, atol=1e-9
    )
    assert math.isclose(seg.a0, R0 * math.tan(phi))  # starts at the real tip, not below it
    assert math.isclose(seg.r(seg.a0), R0 / math.cos(phi))


def test_ball_family_is_one_sphere_and_bull_corner_is_hyperbolic():
    fam = parse_cutter("ball:D=10").sphere_family()
    assert fam[0].kind == "point" and fam[0].radius == 5 and fam[0].a0 == 5
    corner = parse_cutter("bull:D=20,r=4").sphere_family()[0]
    a = np.linspace(corner.a0, corner.a1, 20)
    assert np.allclose(corner.r(a), 4 + np.sqrt(36 + (a - 4) ** 2), rtol=0, atol=1e-9)


def test_profiles_are_continuous():
    for spec in SPECS:
        segs = parse_cutter(spec).profile()
        for s0, s1 in zip(segs[:-1], segs[1:]):
            assert np.allclose(s0.points(2)[-1], s1.points(2)[0], atol=1e-12), spec
        assert isinstance(segs[0], (LineSegment, ArcSegment))


# ----------------------------------------------------------------------------- the shared vocabulary
def _brute_signed_distance(cutter, rho, z):
    """Independent: distance to a dense polyline of the closed half-section, sign by an even-odd ray test."""
    pts = np.concatenate([seg.points(2001) for seg in cutter.profile()])
    top = pts[-1]
    outline = np.concatenate([pts, [[0.0, top[1]]]])  # closed by the top cap
    a, b = outline[:-1], outline[1:]
    ab = b - a
    L2 = np.maximum((ab * ab).sum(1), 1e-300)
    q = np.stack([rho, z], 1)
    d = np.full(rho.size, np.inf)
    for k in range(0, rho.size, 200):  # distance to every polyline segment, in chunks
        w = q[k : k + 200, None, :] - a[None]
        t = np.clip((w * ab[None]).sum(-1) / L2[None], 0, 1)
        d[k : k + 200] = np.sqrt(((w - t[..., None] * ab[None]) ** 2).sum(-1)).min(1)
    poly = np.concatenate([[[0.0, pts[0, 1]]], outline, [[0.0, pts[0, 1]]]])
    inside = np.zeros(rho.size, bool)
    for (x0, y0), (x1, y1) in zip(poly[:-1], poly[1:]):
        if y0 == y1:
            continue
        cross = (y0 > z) != (y1 > z)
        xi = x0 + (z - y0) * (x1 - x0) / (y1 - y0)
        inside ^= cross & (rho < xi)
    return np.where(inside, -d, d)


CUTTERS = [
    "ball:D=10",
    "flat:D=12",
    "bull:D=20,r=4",
    "cone:D=10,angle=10",
    "cone:D=10,angle=-8",
    "drum:D=20,Rp=40,L=20",
    "barrel:D=20,Rp=40,L=20",
    "apt:D=20,r=3,e=7,f=3,alpha=0,beta=5,h=40",
]


@pytest.mark.parametrize("spec", CUTTERS)
def test_signed_distance_matches_a_brute_force_of_the_half_section(spec, rng):
    c = parse_cutter(spec)
    rho = rng.uniform(0, c.D, 3000)
    z = rng.uniform(-c.D / 2, c.length + c.D / 2, 3000)
    ang = rng.uniform(0, 2 * np.pi, 3000)
    pts = np.stack([rho * np.cos(ang), rho * np.sin(ang), z], 1)
    got = c.signed_distance(pts)
    ref = _brute_signed_distance(c, rho, z)
    far = np.abs(ref) > 1e-3  # the sign is only meaningful off the boundary
    assert np.abs(got - ref).max() < 1e-5  # brute polyline: 2001 points per segment (chord error < 1e-5 mm)
    assert (np.sign(got[far]) == np.sign(ref[far])).all()


@pytest.mark.parametrize("spec", ["ball:D=10", "flat:D=12", "bull:D=20,r=4", "bull:D=10,r=5", "ball:D=10,L=20"])
def test_rounded_core_distance_equals_the_profile_distance_and_the_brute_force(spec, rng):
    """The closed form used for ball, flat and bull (a rectangle grown by a disc, cut at the top) against
    the general distance to the profile's segments and the polyline brute force, inside and out."""
    from machsurf_cad.cutter_profiles import _region_distance

    c = parse_cutter(spec)
    assert c._rounded_core() is not None
    rho = np.concatenate([rng.uniform(0, c.D, 3000), np.zeros(50)])
    z = rng.uniform(-c.D / 2, c.length + c.D / 2, rho.size)
    fast = c.cutting_distance_rz(rho, z)
    assert np.abs(fast - _region_distance(c._outline(), rho, z)).max() < 1e-12
    assert np.abs(fast - _brute_signed_distance(c, rho, z)).max() < 1e-5
    assert BallEndMill(10, 3)._rounded_core() is None  # cutting length below the radius: the general form


def test_signed_distance_placed_and_with_a_shank():
    c = BullNoseEndMill(20, 4, 30, shank=Shank(16, 50))
    tip, axis = np.array([10.0, -5.0, 2.0]), np.array([0.0, 0.6, 0.8])
    e1 = np.array([1.0, 0.0, 0.0])
    # on the axis 1 mm below the tip; 3 mm outside the shank's side; 1 mm above the shank top
    pts = [tip - axis, tip + 40 * axis + 11 * e1, tip + 81 * axis]
    assert_close(c.signed_distance(pts, tip=tip, axis=axis), [1.0, 3.0, 1.0], 1e-12)
    assert_close(c.signed_distance([tip + 5 * axis], tip=tip, axis=axis), [-5.0], 1e-12)  # inside, 5 mm above the flat
    assert c.body_parts() == [(8.0, 30.0, 80.0)]


def test_height_width_offset_and_apt_parameters():
    b = BullNoseEndMill(20, 4)
    rho = np.array([0.0, 6.0, 8.0, 10.0, 11.0])
    assert_close(b.height(rho)[:4], [0.0, 0.0, 4 - np.sqrt(16 - 4), 4.0], 1e-12)  # flat, then the corner arc
    assert np.isinf(b.height(rho)[4])
    assert_close(b.width(np.array([0.0, 4.0, 2.0])), [6.0, 10.0, 6 + np.sqrt(16 - 4)], 1e-12)
    ball = BallEndMill(10)
    assert_close(ball.height(np.array([3.0])), [5 - 4.0], 1e-12)
    assert ball.offset(1.0) == BallEndMill(12, ball.length)
    assert b.offset(0.5) == BullNoseEndMill(21, 4.5, b.length)
    assert FlatEndMill(10).offset(2.0) == BullNoseEndMill(14, 2.0, FlatEndMill(10).length)
    with pytest.raises(InputError, match="offset"):
        parse_cutter("cone:D=10,angle=10").offset(1.0)
    # one APT convention (d, r, e, f, alpha, beta, h): e = D/2 - r, f = r; back to the same cutter
    for spec in ("ball:D=10", "flat:D=12", "bull:D=20,r=4", "cone:D=10,angle=10"):
        c = parse_cutter(spec)
        d, r, e, f, al, be, h = c.apt_parameters()
        assert d == c.D and e == pytest.approx(c.D / 2 - c.corner_radius) and f == pytest.approx(c.corner_radius)
        assert cutter_from_apt(c.apt_parameters()) == c
    assert FlatEndMill(12).apt_parameters() == (12.0, 0.0, 6.0, 0.0, 0.0, 0.0, 36.0)
    assert b.end_mill_radii("x") == (4.0, 6.0, 10.0) and ball.end_mill_radii("x").is_ball
    with pytest.raises(InputError, match="ball, flat and bull-nose"):
        parse_cutter("cone:D=10,angle=10").end_mill_radii("machining surfaces")
