"""Scallop-driven raster lines (``raster(..., scallop_mm=H)``): closed forms on planes, the N-buffer
simulation of the planned path as the independent judge on a free-form face."""

import math

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad import builders


def _line_offsets(tp):
    """The y of each raster line (lines along x): the most frequent tip y of each pass's cutting positions
    (a pass also holds the moves linking it to the next line)."""
    cut = tp.move == ms.Move.CUT
    ys = []
    for k in np.unique(tp.pass_index[cut]):
        vals, counts = np.unique(np.round(tp.tip[cut & (tp.pass_index == k), 1], 7), return_counts=True)
        ys.append(vals[np.argmax(counts)])
    return np.unique(ys)


def _plane(alpha_deg):
    t = math.tan(math.radians(alpha_deg))
    return builders.plane_patch((-40, -40, -40 * t), (80, 0, 0), (0, 80, 80 * t))  # z = y tan(alpha)


@pytest.mark.parametrize(("tool", "H"), [("ball:D=10", 0.01), ("bull:D=10,r=2", 0.005)])
def test_flat_floor_gives_the_closed_form_step(tool, H):
    """On a flat floor every line is the closed-form step-over from the last, and the cusp is H exactly."""
    cutter = ms.parse_cutter(tool)
    tp = ms.raster([_plane(0.0)], cutter, scallop=H, extent=(-20, 20, -8, 8))  # a ball: 26 lines
    i = tp.info
    step = ms.scallop_stepover(H, cutter)
    gaps = np.diff(_line_offsets(tp))
    assert i["stepover_flat_floor_mm"] == step
    assert np.abs(gaps[:-1] - step).max() < 1e-6 and gaps[-1] <= step + 1e-6  # the last line at the extent
    assert i["scallop_planned_max_mm"] == pytest.approx(H, abs=1e-9)
    assert i["n_scallop_unmet"] == 0


@pytest.mark.parametrize("alpha", [30.0, 55.0])
def test_slope_across_the_lines_is_met_along_the_normal(alpha):
    """Plane z = y tan(alpha), lines along x: a ball's cusp along the normal for a plan step g is
    r - sqrt(r^2 - (g / (2 cos alpha))^2); every planned step keeps it within H, and is not much smaller
    than the largest step that does (2 cos(alpha) sqrt(2 r H - H^2))."""
    r, H = 5.0, 0.01
    ca = math.cos(math.radians(alpha))
    tp = ms.raster([_plane(alpha)], ms.BallEndMill(10), scallop=H, extent=(-10, 10, -10, 10))
    gaps = np.diff(_line_offsets(tp))[:-1]  # the last line is placed at the extent
    cusp = r - np.sqrt(r * r - (gaps / (2 * ca)) ** 2)
    best = 2 * ca * math.sqrt(2 * r * H - H * H)
    assert cusp.max() <= H * (1 + 1e-9)
    assert gaps.min() >= 0.6 * best and gaps.max() <= best * (1 + 1e-6)
    i = tp.info
    assert i["scallop_planned_max_mm"] == pytest.approx(cusp.max(), rel=1e-6)
    # vertical height = normal height / cos(alpha): the measure named in info
    assert i["scallop_planned_max_vertical_mm"] == pytest.approx(i["scallop_planned_max_mm"] / ca, rel=1e-6)


@pytest.mark.slow
def test_free_form_face_simulation_stays_within_the_target():
    """The bundled free-form face, ball D10, H = 0.01 mm on a 25 x 25 mm window: the N-buffer simulation of
    the planned path (an independent measure of what the moving tool leaves) finds at most H left away
    from the window's borders (a tool radius in: the path's ends and its first and last lines); the
    planner used more lines than the flat-floor step-over where the face slopes."""
    f = ms.example("bezier5")
    ext = (5.0, 30.0, 5.0, 30.0)
    tp = ms.raster([f], ms.BallEndMill(10), scallop=0.01, extent=ext, chordal_tolerance=0.002)
    sim = ms.simulate([f], tp, resolution=0.04)
    p = sim.points
    inner = (p[:, 0] > ext[0] + 5) & (p[:, 0] < ext[1] - 5) & (p[:, 1] > ext[2] + 5) & (p[:, 1] < ext[3] - 5)
    left = float(sim.value[inner & sim.reached].max())
    assert 0.005 < left <= 0.01 * 1.02  # sampled 0.04 mm apart: the simulation's own resolution
    i = tp.info
    assert 0.005 < i["scallop_planned_max_mm"] <= 0.01 * (1 + 1e-9) and i["n_scallop_unmet"] == 0
    assert i["stepover_min_mm"] < 0.9 * i["stepover_flat_floor_mm"]  # closer lines where the face slopes


def test_a_wall_is_the_cutter_limit_not_a_scallop():
    """A 10 mm step (floor, vertical wall, top): where a cusp's material sits at the wall's foot the tool
    placed to touch it cannot (the cutter's limit): counted, not driving the step-over to zero; on the
    floor and the top the closed-form step-over stays."""
    floor = builders.plane_patch((-30, -30, 0), (60, 0, 0), (0, 30, 0))
    wall = builders.plane_patch((-30, 0, 0), (60, 0, 0), (0, 0, 10))
    top = builders.plane_patch((-30, 0, 10), (60, 0, 0), (0, 30, 0))
    tp = ms.raster([floor, wall, top], ms.BallEndMill(10), scallop=0.01, extent=(-10, 10, -12, 12))
    i = tp.info
    step = ms.scallop_stepover(0.01, ms.BallEndMill(10))
    assert i["n_scallop_unmet"] == 0 and i["n_cusps_at_cutter_limit"] > 0
    assert i["scallop_planned_max_mm"] <= 0.01 * (1 + 1e-9)
    gaps = np.diff(_line_offsets(tp))
    assert np.median(gaps) == pytest.approx(step, rel=1e-6) and i["n_lines"] <= 24 / step + 3  # no collapse


@pytest.mark.parametrize(
    "tool", ["ball:D=10", "bull:D=10,r=2", "flat:D=6", "cone:D=6,angle=10,L=20", "drum:D=30,Rp=60,L=20"]
)
def test_the_swept_surface_equals_the_minimum_over_every_position(tool):
    """The swept lower surface computes only the positions whose lower bound beats the best term found: it
    equals the minimum over every position of the line (written here), bit for bit, on a wavy line with a
    stretch of no part (NaN), offsets beyond the rim and NaN offsets."""
    from machsurf_cad.threeaxis.scallop import SweptLine
    from machsurf_cad.threeaxis.solves import _Profile

    rng = np.random.default_rng(0)
    prof = _Profile(ms.parse_cutter(tool))
    s = np.linspace(0, 60, 241)
    z = np.sin(s / 5) * 3 + rng.normal(0, 0.05, s.size)
    z[100:110] = np.nan
    line = SweptLine(prof, s, z)
    rows = rng.integers(0, s.size, 2000)
    t = rng.uniform(-1.1 * prof.R, 1.1 * prof.R, rows.size)
    t[:5] = np.nan
    zr = line.z  # the positions, refined along the line (inf where no part)
    want = np.full(rows.size, np.inf)
    for k in line.k:
        j = line.refine * rows + k
        zk = np.where((j >= 0) & (j < zr.size), zr[np.clip(j, 0, zr.size - 1)], np.inf)
        h = prof(np.hypot(k * line.ds, t))[0]
        want = np.minimum(want, zk + np.where(np.isfinite(h), h, np.inf))
    got = line(rows, t)
    assert np.isfinite(got).sum() > rows.size // 2
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    "tool",
    [
        "ball:D=10",
        "bull:D=10,r=2",
        "flat:D=6",
        "cone:D=6,angle=10,L=20",
        "drum:D=30,Rp=60,L=20",
        "apt:D=10,r=2,e=3,f=2,alpha=10,beta=0,h=20",
        "drum:D=200,Rp=270.49,L=228.721",
        "bull:D=20,r=4.536",
        "ball:D=5.518",
    ],
)
def test_the_profile_height_from_its_pieces_equals_lower_height_to_the_bit(tool):
    """``_Profile.height`` (each piece's own formula) against the profile's ``lower_height`` search over
    every segment: equal bit for bit on a dense grid, at every piece's ends and a nanometre either side,
    the axis, the rim, beyond it, negative radii, NaN and inf; the pieces kept where ``lower_height`` squares
    a radius differently from a product (r = 4.536, D = 5.518), and a drum whose arcs of 270 mm run past their
    ends by more than a nanometre (``lower_height``'s 1e-9 degrees)."""
    from machsurf_cad.threeaxis.solves import _Profile

    prof = _Profile(ms.parse_cutter(tool))
    tb = prof._pieces()
    assert tb.shape[0] >= 1 and tb[0, 0] <= 1e-9 and tb[-1, 1] >= prof.R - 1e-9  # the pieces cover [0, R]
    ends = np.r_[tb[:, 0], tb[-1, 1]]
    m = prof._piece_margin
    near = np.r_[ends, ends - 1e-9, ends + 1e-9, ends + 2e-9, ends + m, ends - m, ends + 2 * m, ends - 2 * m]
    near = np.r_[near, np.nextafter(near, np.inf), np.nextafter(near, -np.inf)]
    rho = np.r_[np.linspace(-1.0, 1.01 * prof.R, 100001), near, np.nan, np.inf, -np.inf]
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(prof.height(rho), prof(rho)[0])


def test_crossing_profile_segments_have_no_pieces_and_height_searches():
    """Two segments crossing inside a piece (the lowest one changes there): no pieces, and ``height`` is still
    ``lower_height``'s (the lower of the two lines)."""
    from machsurf_cad.cutter_profiles import LineSegment
    from machsurf_cad.threeaxis.solves import _Profile

    prof = _Profile(ms.BallEndMill(10))
    prof.segs = [LineSegment(0.0, 0.0, 5.0, 1.0), LineSegment(0.0, 1.0, 5.0, 0.0)]  # they cross at rho = 2.5
    prof.R = 5.0
    assert prof._pieces().shape == (0, 7)
    rho = np.linspace(0.0, 5.0, 101)
    np.testing.assert_array_equal(prof.height(rho), np.minimum(rho / 5, 1 - rho / 5))


def _brute_cusp(a, ta, b, tb, rows, lo, hi, n=801):
    """The first crossing of ``a`` (at ``ta``) and ``b`` (at ``tb``) at the samples ``rows`` between ``lo`` and
    ``hi``: where ``a`` stops being the lower (``a <= b``, then ``a > b``) on a dense scan, then bisected to the
    last bit (``a``'s surface ends at its rim, inf beyond, so a crossing there is at ``b``'s height). NaN
    where the scan finds none."""
    rows = np.atleast_1d(rows)
    t = np.linspace(lo, hi, n, axis=-1) * np.ones((rows.size, 1))
    r = np.repeat(rows[:, None], n, axis=1)
    d = a(r.ravel(), (t - ta).ravel()).reshape(t.shape) - b(r.ravel(), (tb - t).ravel()).reshape(t.shape)
    sw = (d[:, :-1] <= 0) & (d[:, 1:] > 0)  # (inf - inf: neither)
    found = sw.any(axis=1)
    j = np.argmax(sw, axis=1)
    x0, x1 = t[np.arange(rows.size), j], t[np.arange(rows.size), j + 1]
    for _ in range(100):
        m = 0.5 * (x0 + x1)
        up = a(rows, m - ta) - b(rows, tb - m) > 0
        x0, x1 = np.where(up, x0, m), np.where(up, m, x1)
    z = np.maximum(a(rows, x0 - ta), b(rows, tb - x0))
    return np.where(found, x0, np.nan), np.where(found, z, np.nan)


@pytest.mark.parametrize("tool", ["ball:D=10", "bull:D=10,r=2"])
def test_the_cusp_equals_a_dense_scan_between_wavy_lines(tool):
    """Cusps between two wavy lines (false position with halving, the ends where a swept surface stops at its
    tool's rim) against a dense scan bisected to the last bit, written here: a crossing at the same rows, at
    the same offset and height within 1e-9 mm (a flat end's plateaus cross at steps, wherever a bracket
    lands: not compared); where line b runs 6 mm higher, line a's swept surface is the lower up to its tool's
    rim (``ta + R``): the cusp is there, at line b's height."""
    from machsurf_cad.threeaxis.scallop import SweptLine, cusp_points
    from machsurf_cad.threeaxis.solves import _Profile

    rng = np.random.default_rng(3)
    prof = _Profile(ms.parse_cutter(tool))
    s = np.linspace(0, 60, 241)
    za = np.sin(s / 4) * 0.8 + 0.2 * rng.normal(size=s.size)
    zb = np.cos(s / 5) * 0.8 + 0.2 * rng.normal(size=s.size)
    rows = np.arange(30, 210, 5)
    for ta, tb, lift in ((0.0, 1.5, 0.0), (0.0, 4.0, 0.0), (0.0, 8.0, 6.0)):
        a, b = SweptLine(prof, s, za), SweptLine(prof, s, zb + lift)
        lo, hi = np.full(rows.size, ta - 0.5), np.full(rows.size, tb + 0.5)
        t, z = cusp_points(a, ta, b, tb, rows, lo, hi)
        bt, bz = _brute_cusp(a, ta, b, tb, rows, lo[0], hi[0])
        np.testing.assert_array_equal(np.isnan(t), np.isnan(bt))
        assert np.isfinite(bt).sum() >= 3
        np.testing.assert_allclose(t, bt, atol=1e-9, rtol=0)
        np.testing.assert_allclose(z, bz, atol=1e-9, rtol=0)
        if lift:  # line b 6 mm higher: a is the lower all the way to its tool's rim
            ok = np.isfinite(z)
            assert ok.sum() >= rows.size // 2
            np.testing.assert_allclose(t[ok], ta + prof.R, atol=1e-12)
            np.testing.assert_allclose(z[ok], b(rows[ok], np.full(ok.sum(), tb - ta - prof.R)), atol=1e-12)


def test_the_cusp_beyond_a_tie_at_its_ends_and_beside_a_stretch_without_faces():
    """Two cases a hostile review found (against the dense scan above): a bull D10 r2 on a plateau 9 mm long
    between two lines 1 mm apart over a pocket, where both tools' flats stand on the plateau at the bracket's
    ends (the two surfaces equal there): the switch is inside, at the plateau's middle (t = 0.5), not at an
    end; and a ball's line with no face under it for 4.7 mm either side of the row (its swept surface inf
    short of its rim): the crossing inside the bracket, not NaN."""
    from machsurf_cad.threeaxis.scallop import SweptLine, cusp_points
    from machsurf_cad.threeaxis.solves import _Profile

    s = np.linspace(0, 40, 161)
    row = np.array([80])  # s = 20
    bull = _Profile(ms.parse_cutter("bull:D=10,r=2"))
    plateau = SweptLine(bull, s, np.where(np.abs(s - 20) < 4.5, 0.0, -1.0))
    t, z = cusp_points(plateau, 0.0, plateau, 1.0, row, [-2.0], [3.0])
    (bt,), (bz,) = _brute_cusp(plateau, 0.0, plateau, 1.0, 80, -2.0, 3.0)
    assert t[0] == pytest.approx(0.5, abs=1e-9) and bt == pytest.approx(0.5, abs=1e-9)
    assert z[0] == pytest.approx(bz, abs=1e-9) and z[0] < -0.29
    ball = _Profile(ms.BallEndMill(10))
    a = SweptLine(ball, s, np.where(np.abs(s - 20) <= 4.7, np.nan, -3.0))
    b = SweptLine(ball, s, np.zeros_like(s))
    with np.errstate(invalid="ignore"):
        t, z = cusp_points(a, 0.0, b, 3.0, row, [-3.0], [4.0])
        (bt,), (bz,) = _brute_cusp(a, 0.0, b, 3.0, 80, -3.0, 4.0)
    assert np.isfinite(bt) and t[0] == pytest.approx(bt, abs=1e-9) and z[0] == pytest.approx(bz, abs=1e-9)


def test_the_unmet_message_names_the_worst_pair():
    """The command's line on pairs of lines still over the target names the worst of them and where (the mould
    insert, bull D10 r2, 0.02 mm: its first unmet pair left 0.79 mm, its second 2.31 mm; the line said 0.79)."""
    from machsurf_cad.jobs.run_threeaxis import _say_scallop

    unmet = [
        {"between_mm": [0.49, 0.69], "left_mm": 0.7884, "at_xy_mm": [-29.751, 0.588]},
        {"between_mm": [16.86, 17.06], "left_mm": 2.309, "at_xy_mm": [-9.752, 21.855]},
    ]
    info = {"stepover_min_mm": 0.205, "stepover_max_mm": 6.56, "stepover_flat_floor_mm": 6.56,
            "scallop_planned_max_mm": 2.309, "scallop_planned_max_vertical_mm": 7.53, "scallop_target_mm": 0.02,
            "scallop_planned_worst_xy_mm": [-9.752, 21.855], "n_cusps_at_cutter_limit": 0, "n_scallop_unmet": 2,
            "scallop_unmet": unmet}  # fmt: skip
    lines = []
    assert _say_scallop(lines.append, info) == 2
    assert "up to 2.309 mm near (-9.752, 21.855) mm" in lines[-1]
