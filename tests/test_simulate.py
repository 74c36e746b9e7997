"""The N-buffer cut simulation: closed forms, an independent z-buffer and brute force, gouges, bad input."""

import math

import numpy as np
import pytest
from conftest import ROOT, needs_kernel
from helpers import assert_close
from scipy.spatial import cKDTree

import machsurf_cad as ms
from machsurf_cad.geometry import builders
from machsurf_cad.scallop import scallop_height, spacing_for_scallop


def _passes(lines, axes, cutter, clearance=5.0):
    return ms.ToolPath.from_passes(lines, axes, cutter=cutter, clearance=clearance)


def _plane_ball_path(R, s, n_pass=5, half=6.0, z=0.0):
    x = np.linspace(-half, half, 49)
    ys = (np.arange(n_pass) - (n_pass - 1) / 2) * s
    tips = [np.stack([x, np.full_like(x, y), np.full_like(x, z)], 1) for y in ys]
    return _passes(tips, [np.tile([0.0, 0, 1], (x.size, 1))] * n_pass, ms.BallEndMill(2 * R))


def _plane(half=1.5, half_y=None):
    hy = half if half_y is None else half_y
    return builders.plane_patch((-half, -hy, 0.0), (2 * half, 0, 0), (0, 2 * hy, 0))


@pytest.mark.parametrize("s", [0.5, 1.0, 2.0, 3.0])
def test_ball_on_a_plane_leaves_the_closed_form_scallop(s):
    R = 5.0
    res = ms.simulate(_plane(1.5, s), _plane_ball_path(R, s), resolution=s / 40)
    exact = R - math.sqrt(R * R - s * s / 4)
    # the samples fall on the cusp line (a multiple of s/40 away from a pass): exact to round-off
    assert_close(res.max_scallop, exact, 1e-6, "max scallop")
    assert res.max_gouge < 1e-9 and res.reached.all()
    # a sample between passes: the profile R - sqrt(R^2 - d^2) of its distance d to the nearest pass
    d = np.abs((res.points[:, 1] + 100 * s) % s)
    d = np.minimum(d, s - d)
    assert_close(res.value, R - np.sqrt(R * R - d * d), 1e-6, "scallop profile")
    assert res.report()["max_scallop_mm"] == res.max_scallop


@pytest.mark.parametrize("kappa_sign", [1, pytest.param(-1, marks=pytest.mark.slow)])  # concave: slow tier
def test_ball_across_a_cylinder_circle_circle_construction(kappa_sign):
    """Passes along the axis of a cylinder of radius 30 (convex: outside; concave: inside), contacts an
    angle apart: the cusp height is the circle-circle construction, solved here by brute force."""
    R, Rs, w = 5.0, 30.0, 3.0
    cyl = builders.cylinder_patch(Rs, 20.0, 40.0)  # axis z, angle 0..40 deg, su x sv points inwards
    face = ms.Face(cyl, name="cyl", reversed=kappa_sign > 0)  # convex: material inside, normal outwards
    dphi = w / Rs
    phis = math.radians(20.0) + (np.arange(5) - 2) * dphi
    dist = Rs + kappa_sign * R  # ball centre distance from the axis
    z = np.linspace(-5, 25, 31)
    tips, axes = [], []
    for p in phis:
        radial = np.array([math.cos(p), math.sin(p), 0.0]) * kappa_sign  # tool axis: along the outward normal
        centre = np.stack([np.full_like(z, dist * math.cos(p)), np.full_like(z, dist * math.sin(p)), z], 1)
        tips.append(centre - R * radial)
        axes.append(np.tile(radial, (z.size, 1)))
    res = ms.simulate(face, _passes(tips, axes, ms.BallEndMill(2 * R)), resolution=0.05)
    # brute force: the two circles of radius R about the centres at angles -+dphi/2; their crossing point
    # on the surface's side, by bisection along the bisector ray from the axis
    c1 = dist * np.array([math.cos(-dphi / 2), math.sin(-dphi / 2)])

    def f(d):  # distance from the bisector point at d to the circle centre, minus R
        return math.hypot(d - c1[0], c1[1]) - R

    lo, hi = (Rs, dist) if kappa_sign > 0 else (dist, Rs)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        # inside the tool circle (f < 0) towards the centres
        if (f(mid) < 0) == (kappa_sign > 0):
            hi = mid
        else:
            lo = mid
    cusp = abs(0.5 * (lo + hi) - Rs)
    assert_close(scallop_height(w, R, kappa_sign / Rs), cusp, 1e-9, "closed form vs brute force")
    # the samples nearest the cusp are resolution/2 away at most: within the profile's change over 0.025 mm
    ang = np.arctan2(res.points[:, 1], res.points[:, 0]) - math.radians(20.0)
    mid_pass = (res.points[:, 2] > 2) & (res.points[:, 2] < 18) & (np.abs(ang) < 1.5 * dphi)
    assert res.reached[mid_pass].all()
    # per sample: the entry of its normal ray into the nearest swept ball (a cylinder of radius R about each
    # pass of centres: in the section, a circle), in closed form
    p2 = res.points[mid_pass, :2]
    n2 = res.normals[mid_pass, :2]
    best = np.full(p2.shape[0], np.inf)
    for ph in phis:
        c = dist * np.array([math.cos(ph), math.sin(ph)])
        w_ = p2 - c
        b = np.einsum("ij,ij->i", w_, n2)
        disc = b * b - (np.einsum("ij,ij->i", w_, w_) - R * R)
        t = -b - np.sqrt(np.where(disc >= 0, disc, np.nan))
        best = np.fmin(best, t)
    assert_close(res.value[mid_pass], best, 1e-6, "thickness left along the normal")
    assert res.value[mid_pass].max() <= cusp + 1e-9 and res.value[mid_pass].max() > cusp - 0.01
    assert res.max_gouge < 1e-9


def _torus_section_lower(R_t, r, lead_deg, ys, n_theta=200_001):
    """Brute force: the lowest z over the points of the tilted torus (axis leaning by ``lead`` towards +x)
    with a given y (what a tool moving along x leaves), on a fine grid of the ring angle theta where the
    tube angle follows exactly from y; relative to the torus's lowest point."""
    lam = math.radians(lead_deg)
    th = np.linspace(-np.pi, np.pi, n_theta)
    sin_t, cos_t = np.sin(th), np.cos(th)

    def z_of(y):
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (y / sin_t - R_t) / r
        ok = np.abs(c) <= 1
        best = np.inf
        for sgn in (1.0, -1.0):
            ph = sgn * np.arccos(np.clip(c, -1, 1))
            rad = R_t + r * np.cos(ph)  # distance from the axis in the torus frame
            h = r + r * np.sin(ph)  # height along the axis above the tip plane
            z = -rad * cos_t * math.sin(lam) + h * math.cos(lam)  # e1 = (cos lam, 0, -sin lam)
            best = min(best, float(np.where(ok, z, np.inf).min()))
        return best

    low = np.array([z_of(y) for y in ys])
    ph = np.linspace(-np.pi, np.pi, 1_000_001)  # y = 0: the section in the x-z plane holds the lowest point
    zmin = min(
        float((-sgn * (R_t + r * np.cos(ph)) * math.sin(lam) + (r + r * np.sin(ph)) * math.cos(lam)).min())
        for sgn in (1.0, -1.0)
    )
    return low - zmin, zmin


def test_bull_with_lead_on_a_plane_matches_the_tilted_torus_section():
    D, r, lead, s = 16.0, 3.0, 10.0, 1.0
    R_t = D / 2 - r
    cut = ms.BullNoseEndMill(D, r)
    lam = math.radians(lead)
    a = np.array([math.sin(lam), 0.0, math.cos(lam)])
    res_y = np.linspace(-0.4, 0.4, 41)  # the sample rows of the plane below (0.02 mm apart)
    ys = np.unique(np.concatenate([res_y + s / 2, res_y - s / 2]))
    low, zmin = _torus_section_lower(R_t, r, lead, ys)
    x = np.linspace(-12, 12, 25)
    tips = [np.stack([x, np.full_like(x, y), np.full_like(x, -zmin)], 1) for y in (-s / 2, s / 2)]
    res = ms.simulate(_plane(1.0, 0.4), _passes(tips, [np.tile(a, (x.size, 1))] * 2, cut), resolution=0.02)
    # brute force at y: the lower of the two passes' sections
    y = res.points[:, 1]
    brute = np.minimum(np.interp(y + s / 2, ys, low), np.interp(y - s / 2, ys, low))
    assert_close(res.value, brute, 1e-5, "bull section (brute force)")  # the motion refined to ~3e-6 mm
    # relation (30): the effective radius r + R_t / sin(lead) predicts the cusp (0.2 % at this spacing; the
    # section flattens away from the contact: 3 % at 4 mm)
    pred = float(scallop_height(s, r + R_t / math.sin(lam), 0.0))
    assert abs(res.max_scallop - pred) < 0.005 * pred


def test_a_path_moved_into_the_part_gouges_by_that_depth():
    tp = _plane_ball_path(5.0, 1.0, z=-0.05)
    res = ms.simulate(_plane(), tp, resolution=0.05, gouge_tolerance=0.01)
    assert_close(res.max_gouge, 0.05, 1e-3, "max gouge")
    assert res.gouged and res.report()["n_gouged_samples"] > 0


def test_nbuffer_agrees_with_an_independent_zbuffer_on_a_free_form_face():
    """3-axis ball on a free-form face: a z-buffer written here (the lowest point of the balls over any xy,
    over the densely interpolated motion) gives the machined height field Z; the thickness along the normal
    it implies (p + t n on Z, by fixed-point iteration) against the N-buffer's."""
    R = 6.0
    s = ms.example("bezier5")
    u = np.linspace(0.05, 0.95, 20)
    v = np.linspace(0.0, 1.0, 81)
    U, V = np.meshgrid(u, v, indexing="ij")
    d = s.derivatives(U, V, 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    n *= np.sign(n[..., 2:3])  # the face is a height field: outward normal up
    centres = d.point + R * n
    tips = [c - [0, 0, R] for c in centres]
    # rapids between passes 40 mm up the axis: clear of the face (5 mm would cut through its middle)
    tp = _passes(tips, [np.tile([0.0, 0, 1], (v.size, 1))] * u.size, ms.BallEndMill(2 * R), clearance=40.0)
    up = float(ms.local_properties(s, 0.5, 0.5).normal[2]) > 0
    res = ms.simulate(ms.Face(s, name="f", reversed=not up), tp, resolution=1.0, stock=2.0)
    assert res.max_gouge < 0.005  # the chords between positions 1.25 mm apart sag into the curved face
    dense = []
    for c in centres:
        t = np.linspace(0, 1, 20 * (len(c) - 1) + 1)
        k = np.minimum((t * (len(c) - 1)).astype(int), len(c) - 2)
        f = (t * (len(c) - 1) - k)[:, None]
        dense.append(c[k] * (1 - f) + c[k + 1] * f)
    C = np.concatenate(dense)
    tree = cKDTree(C[:, :2])

    def Z(xy):  # z-buffer: lowest ball point above each xy
        z = np.full(xy.shape[0], np.inf)
        for i, near in enumerate(tree.query_ball_point(xy, R)):
            c = C[near]
            d2 = ((c[:, :2] - xy[i]) ** 2).sum(1)
            z[i] = (c[:, 2] - np.sqrt(np.maximum(R * R - d2, 0.0))).min() if len(near) else np.inf
        return z

    rng = np.random.default_rng(3)
    inner = np.flatnonzero(res.reached & (res.value < 1.0))
    pick = rng.choice(inner, 400, replace=False)
    P, N = res.points[pick], res.normals[pick]
    t = np.zeros(pick.size)
    for _ in range(30):
        t = (Z(P[:, :2] + t[:, None] * N[:, :2]) - P[:, 2]) / N[:, 2]
    ok = np.isfinite(t)
    assert ok.sum() > 350
    assert_close(res.value[pick][ok], t[ok], 1e-3, "N-buffer vs z-buffer")


def test_scallop_spacing_inverts_the_height():
    for k in (0.0, 0.02, -0.05, 0.3):
        w = spacing_for_scallop(0.01, 5.0, k)
        assert_close(scallop_height(w, 5.0, k), 0.01, 1e-12, f"kappa {k}")
    assert np.isnan(spacing_for_scallop(6.0, 5.0, 0.0))  # a ball R 5 cannot leave 6 mm on a plane


def test_bad_input_is_refused_with_one_line():
    tp = _plane_ball_path(5.0, 1.0)
    with pytest.raises(ms.InputError, match="resolution"):
        ms.simulate(_plane(), tp, resolution=0.0)
    with pytest.raises(ms.InputError, match="budget"):
        ms.simulate(_plane(), tp, resolution=1e-4, max_samples=1000)
    far = _plane_ball_path(5.0, 1.0, z=50.0)
    with pytest.raises(ms.InputError, match="no contact"):
        ms.simulate(_plane(), far, resolution=0.1)
    bare = ms.ToolPath(tp.tip, tp.axis, tp.move, tp.pass_index, None, None, None, "bare", {}, {})
    with pytest.raises(ms.InputError, match="tool"):
        ms.simulate(_plane(), bare)


@needs_kernel
@pytest.mark.slow  # the path-writing commands' simulation stays in the fast tier
def test_simulate_command_on_the_example_block(tmp_path):
    """A 3-axis ball path on the block's top face, simulated on all 8 faces by the command; then the same path
    moved 0.05 mm into the part along the normal: max gouge 0.050 +- 0.001 mm and exit 2."""
    import json

    from helpers import run

    from machsurf_cad.occ import read_step_faces

    block = ROOT / "example_parts" / "freeform_block.step"
    top = read_step_faces(block, [0])[0]
    res = ms.machining_surface(top, "ball:D=10", axes=3, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=2.0, chordal_tolerance=2e-4)  # chords that sag 0.2 um at most
    apt = ms.write_apt(tmp_path / "p.apt", tp)
    out = tmp_path / "s"
    r = run("simulate", block, "--toolpath", apt, "--resolution", "0.5", "-o", out)
    assert r.returncode == 0, r.stdout + r.stderr
    rep = json.loads((out / "report.json").read_text())["simulate"]
    assert rep["n_faces"] == 8 and rep["n_positions"] == tp.n_positions
    # passes 2 mm apart on a gently curved face leave about the plane's R - sqrt(R^2 - 1) = 0.101 mm between
    # them (the closed forms are tested above); the strip between the face's edge and the first pass (up to
    # 2 mm wide) more; no gouge beyond the chords' sag
    top_rep = rep["faces"][0]
    assert top_rep["reached_fraction"] > 0.99 and 0.01 < top_rep["mean_scallop_mm"] < 0.05
    assert 0.09 < top_rep["max_scallop_mm"] < 0.6 and rep["max_gouge_mm"] < 5e-4 and not rep["gouged"]
    assert set(rep["fraction_above_mm"]) >= {"0.01", "0.05"} and rep["resolution_mm"] == 0.5
    assert rep["samples_x_positions_per_s"] > 0 and rep["time_s"]["total_s"] > 0
    for f in ("simulate_map.png", "simulate_map.vtp", "simulate_histogram.png"):
        assert (out / f).stat().st_size > 1000
    # into the part by 0.05 mm along the nominal's normal at each contact
    uv = tp.extras["uv"]
    cut = tp.move == ms.Move.CUT
    d = top.surface.derivatives(uv[cut, 0], uv[cut, 1], 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= -1 if top.reversed else 1
    tips = tp.tip.copy()
    tips[cut] -= 0.05 * n
    moved = ms.ToolPath(tips, tp.axis, tp.move, tp.pass_index, tp.cc, tp.feed, tp.cutter, "moved", {}, {})
    bad = ms.write_csv(tmp_path / "moved.csv", moved)
    r = run(
        "simulate", block, "--toolpath", bad, "--tool", "ball:D=10", "--faces", "0", "--no-render", "-o", tmp_path / "m"
    )
    assert r.returncode == 2, r.stdout + r.stderr
    rep = json.loads((tmp_path / "m" / "report.json").read_text())["simulate"]
    assert_close(rep["max_gouge_mm"], 0.05, 1e-3, "max gouge") and rep["gouged"]
    # bad input: one line, exit 1
    r = run("simulate", block, "--toolpath", apt, "--resolution", "0", "-o", tmp_path / "b1")
    assert r.returncode == 1 and "resolution" in r.stderr and "Traceback" not in r.stderr
    r = run("simulate", block, "--toolpath", apt, "--resolution", "0.001", "-o", tmp_path / "b2")
    assert r.returncode == 1 and "budget" in r.stderr
    r = run(
        "simulate",
        block,
        "--toolpath",
        apt,
        "--tool",
        "ball:D=12",
        "--faces",
        "3",
        "--no-render",
        "-o",
        tmp_path / "b3",
    )
    assert "warning" in r.stdout and "using --tool" in r.stdout
    far = ms.ToolPath(tp.tip + [0, 0, 200.0], tp.axis, tp.move, tp.pass_index, None, None, tp.cutter, "far", {}, {})
    r = run("simulate", block, "--toolpath", ms.write_apt(tmp_path / "far.apt", far), "-o", tmp_path / "b4")
    assert r.returncode == 1 and "no contact" in r.stderr


@needs_kernel
def test_path_writing_commands_simulate_what_they_write(tmp_path):
    import json

    from helpers import run

    out = tmp_path / "ms"
    r = run(
        "machining-surface", "--example", "bezier5", "--tool", "ball:D=20", "--axes", "3", "--toolpath",
        "--stepover", "6", "--simulate", "--simulate-resolution", "1", "--clearance", "60", "-o", out,
    )  # fmt: skip
    assert r.returncode == 0, r.stdout + r.stderr
    rep = json.loads((out / "report.json").read_text())
    sim = rep["verify"]["simulate"]
    # on a plane, 6 mm passes of a ball R 10 leave 0.455 mm at most and 0.15 mm on average (d^2 / 2R over
    # d in [0, 3]); the curved face about that, more in the strips along its edges
    assert 0.08 < sim["mean_scallop_mm"] < 0.3 and sim["max_scallop_mm"] > 0.3 and not sim["gouged"], sim
    assert (out / "simulate_map.png").is_file()


def test_flat_end_mill_with_lead_on_a_plane_leaves_the_rim_ellipse():
    """A flat end mill R 5 leaning 5 deg towards the feed: translating along x its rim's shadow across the feed
    is the half-ellipse z = R sin(lead) (1 - sqrt(1 - y^2 / R^2)); two passes 1.8 mm apart. The entry jumps where
    the rim passes a sample: the motion is refined by golden-section search."""
    R, lam, s = 5.0, math.radians(5.0), 1.8
    a = np.array([math.sin(lam), 0.0, math.cos(lam)])
    x = np.linspace(-12, 12, 25)
    tips = [np.stack([x, np.full_like(x, y), np.full_like(x, R * math.sin(lam))], 1) for y in (-s / 2, s / 2)]
    res = ms.simulate(
        _plane(1.0, 0.5), _passes(tips, [np.tile(a, (x.size, 1))] * 2, ms.FlatEndMill(10)), resolution=0.02
    )
    b = R * math.sin(lam)
    y = res.points[:, 1]
    exact = np.minimum(b * (1 - np.sqrt(1 - ((y + s / 2) / R) ** 2)), b * (1 - np.sqrt(1 - ((y - s / 2) / R) ** 2)))
    assert_close(res.value, exact, 5e-5, "flat end mill's rim ellipse")
    assert res.motion_bound_smooth_mm is None  # a sharp corner: no smooth bound is claimed


@pytest.mark.parametrize("spec", ["ball:D=10", "flat:D=10", "bull:D=16,r=3", "bull:D=10,r=5"])
def test_closed_form_ray_entry_agrees_with_sphere_tracing_the_profile(spec, rng):
    """The exact entry of rays into ball, flat and bull bodies (cylinders and spheres as quadratics, the
    torus traced on its own) against sphere tracing on the general profile distance with no step limit,
    on random rays through and beside the body: same status everywhere; the traced entry is not later
    (but for the torus, traced in both) and within 1e-6 mm on 99 % of the rays (the tracing stops
    1e-7 mm from the body: earlier by 1e-7 / sin of the grazing angle)."""
    from machsurf_cad.simulation.nbuffer import _sphere_trace, march

    c = ms.parse_cutter(spec)
    n = 40000
    ax = rng.normal(size=(n, 3))
    ax[:, 2] = np.abs(ax[:, 2]) + 1
    A = ax / np.linalg.norm(ax, axis=1)[:, None]
    T = rng.uniform(-1, 1, (n, 3))
    P = rng.uniform([-12, -12, -4], [12, 12, 20], (n, 3))
    N = rng.normal(size=(n, 3))
    N /= np.linalg.norm(N, axis=1)[:, None]
    a, sa = march(c, P, N, T, A, -5.0, 5.0)
    b, sb = _sphere_trace(c, P, N, T, A, -5.0, 5.0, max_steps=20000)
    ok = sa != 3  # a bull's torus march may stop on a grazing ray: its value is a lower bound, counted
    assert (sa == 3).mean() < 1e-3 and np.all(a[~ok] <= b[~ok] + 1e-9)
    assert np.array_equal(sa[ok], sb[ok])
    fin = ok & np.isfinite(a)
    gap = a[fin] - b[fin]
    assert fin.sum() > n / 10 and gap.min() > -1e-6 and np.quantile(gap, 0.99) < 1e-6 and gap.max() < 1e-3


def test_flank_cylinder_around_a_convex_cylinder_cuts_the_chord_sag():
    """Flank milling: a cylindrical cutter D10 (axis parallel to the face's axis, the side in contact)
    moved around a convex cylinder R_s 30 in straight motions 2 deg apart. Its side cuts into the face
    between positions; each sample's thickness against a brute force written here (the section is 2-D:
    the ray along the radius against 1001 discs of radius R along every chord, closed form), and the
    deepest cut the closed form (R_s + R)(1 - cos(1 deg)) up to where the samples fall."""
    R, Rs = 5.0, 30.0
    face = ms.Face(builders.cylinder_patch(Rs, 20.0, 40.0), name="cyl", reversed=True)
    th = np.radians(np.arange(-6.0, 46.1, 2.0))
    centres = (Rs + R) * np.stack([np.cos(th), np.sin(th)], 1)
    tips = np.concatenate([centres, np.full((th.size, 1), -10.0)], 1)
    tp = _passes([tips], [np.tile([0.0, 0.0, 1.0], (th.size, 1))], ms.FlatEndMill(2 * R, 40.0))
    res = ms.simulate(face, tp, resolution=0.25, depth=0.5, stock=0.5)
    assert res.reached.all()
    deepest = (Rs + R) * (1 - math.cos(math.radians(1.0)))  # 0.00533 mm, between two positions
    # the samples nearest the mid angle are at most 0.125 mm off it: sag 0.125^2 / (2 R_s) lower at most
    assert deepest - 0.125**2 / (2 * Rs) <= res.max_gouge <= deepest + 1e-9
    band = np.abs(np.asarray(res.points)[:, 2] - 10.0) < 2.0  # the section is the same at every height
    pts = np.asarray(res.points)[band]
    n2 = pts[:, :2] / np.linalg.norm(pts[:, :2], axis=1, keepdims=True)  # outward normal in the section
    s = np.linspace(0.0, 1.0, 1001)[:, None]
    discs = np.concatenate([centres[k] * (1 - s) + centres[k + 1] * s for k in range(th.size - 1)])
    best = np.full(pts.shape[0], np.inf)
    for i in range(0, discs.shape[0], 4000):
        w = pts[:, None, :2] - discs[None, i : i + 4000]
        b = np.einsum("ijk,ik->ij", w, n2)
        disc = b * b - (np.einsum("ijk,ijk->ij", w, w) - R * R)
        t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        best = np.minimum(best, t.min(axis=1))
    assert np.abs(np.asarray(res.value)[band] - best).max() < 2e-6
    assert_close(res.max_gouge, -best.min(), 2e-6, "deepest cut against the brute force")
    # at the positions' angles the side of the neighbouring motions cuts R (1 / cos(1 deg) - 1) deep
    at20 = np.abs(np.degrees(np.arctan2(pts[:, 1], pts[:, 0])) - 20.0) < 1e-9
    assert at20.sum() >= 5
    assert_close(np.asarray(res.value)[band][at20], -R * (1 / math.cos(math.radians(1.0)) - 1), 2e-6)


# ---------------------------------------------------------------- machined region, border, gouges, not measured
# issue 25 item 4: the border around the passes is reported apart from the scallops between them; a gouge is
# the depth of the nominal point inside the swept tool (what verify measures), not the cut along the normal;
# rays that do not converge are not measured.

R_BALL = 5.0
S_CUSP = 4.0 * math.sin(math.radians(15.0))  # 1.035276 mm: the cusp R - sqrt(R^2 - s^2/4) is 0.026867 mm


def _cusp(R, s):
    return R - math.sqrt(R * R - s * s / 4.0)


def _raster(cutter, s, n_pass=5, half=4.0, z=0.0, npts=33, axis=(0.0, 0.0, 1.0), slope=None):
    """Passes along x from -half to half, ``s`` apart across; on the plane z = y tan(slope) when given (the
    tips lifted so that the tool touches it: contacts ``s`` apart along the slope)."""
    x = np.linspace(-half, half, npts)
    tips = []
    for k in range(n_pass):
        c = (k - (n_pass - 1) / 2) * s
        if slope is None:
            tips.append(np.stack([x, np.full_like(x, c), np.full_like(x, z)], 1))
        else:  # a ball whose centre lies R above the sloped plane, its contact c along the slope
            th = math.radians(slope)
            n = np.array([0.0, -math.sin(th), math.cos(th)])
            centre = np.array([0.0, c * math.cos(th), c * math.sin(th)]) + R_BALL * n
            tips.append(np.stack([x, np.full_like(x, centre[1]), np.full_like(x, centre[2] - R_BALL)], 1))
    return _passes(tips, [np.tile(axis, (x.size, 1))] * n_pass, cutter)


def _zbuffer_ball(xy, centres, R):
    """Brute force: the lowest point of the balls R about ``centres`` (dense along the motion) above each xy."""
    z = np.full(xy.shape[0], np.inf)
    for i in range(0, centres.shape[0], 4000):
        c = centres[i : i + 4000]
        d2 = ((xy[:, None, :] - c[None, :, :2]) ** 2).sum(-1)
        low = np.where(d2 <= R * R, c[None, :, 2] - np.sqrt(np.maximum(R * R - d2, 0.0)), np.inf)
        z = np.minimum(z, low.min(axis=1))
    return z


def _dense_centres(tp, R, step=0.005):
    """Ball centres every ``step`` mm along the cutting moves of ``tp`` (3 axes: the axis is +z)."""
    out = []
    cut = tp.move == ms.Move.CUT
    for j in np.flatnonzero(cut):
        a, b = tp.tip[j - 1], tp.tip[j]
        k = max(1, math.ceil(np.linalg.norm(b - a) / step))
        f = np.linspace(0.0, 1.0, k + 1)[:, None]
        out.append(a * (1 - f) + b * f)
    return np.concatenate(out) + [0.0, 0.0, R]


@pytest.mark.parametrize("per_step", [20.0, 17.3])
def test_ball_raster_on_a_plane_reports_the_cusp_in_the_machined_region_and_the_border_apart(per_step):
    """Five passes of a ball R 5, 1.0353 mm apart, from x = -4 to 4 on a plane 12 x 8.3 mm: the cusp is
    R - sqrt(R^2 - s^2/4) = 0.026867 mm; the border around the passes (beyond the outer passes and past their
    ends) is left up to the blade's 1 mm and is reported apart. Samples s/20 apart fall on the cusp lines: the
    figure is exact; s/17.3 apart, the nearest sample lies within half a spacing of a cusp line: the reported
    maximum is within the profile's drop over res/2, R - sqrt(R^2 - (s/2 - res/2)^2) <= max <= h. The mean
    over the region is the profile's mean over [0, s/2] up to the trapezoidal rule's res^2 f''/12."""
    R, s = R_BALL, S_CUSP
    h = _cusp(R, s)
    assert abs(h - 0.026867) < 5e-7
    res_mm = s / per_step
    plane = builders.plane_patch((-6.0, -4 * s, 0.0), (12.0, 0, 0), (0, 8 * s, 0))
    tp = _raster(ms.BallEndMill(2 * R), s)
    res = ms.simulate(plane, tp, resolution=res_mm)
    rep = res.report()
    p = res.points
    box = (np.abs(p[:, 0]) <= 4.0 + 1e-9) & (np.abs(p[:, 1]) <= 2 * s + 1e-9)  # under and between the passes
    assert np.array_equal(res.in_region, box & res.reached)
    if per_step == 20.0:
        assert_close(rep["max_scallop_mm"], h, 1e-9, "cusp on the sampled cusp lines")
    else:
        assert _cusp(R, s - res_mm) - 1e-12 <= rep["max_scallop_mm"] <= h + 1e-12
    a = s / 2
    mean = (R * a - 0.5 * (a * math.sqrt(R * R - a * a) + R * R * math.asin(a / R))) / a
    assert abs(rep["mean_scallop_mm"] - mean) <= res_mm**2 / (12 * (R - 0.11)) * 1.05 + 1e-9
    # the border: what the old single figure reported (0.9997 in the issue); reached up to the 1 mm blade
    b = rep["border"]
    assert b["n_samples"] == int((res.reached & ~box).sum()) > 0 and 0.9 < b["max_material_mm"] <= 1.0
    assert b["max_material_mm"] == pytest.approx(float(res.value[res.reached & ~box].max()))
    region_area = 8.0 * 4 * s
    assert abs(rep["machined_region"]["area_mm2"] - region_area) < 2 * (8.0 + 4 * s) * res_mm
    total = float(res.area.sum())
    assert_close(total, 12.0 * 8 * s, 1e-9, "sampled area")
    assert_close(b["area_mm2"] + rep["machined_region"]["area_mm2"] + res.area[~res.reached].sum(), total, 1e-9)
    assert rep["max_gouge_mm"] < 1e-12 and rep["not_measured"]["n_samples"] == 0
    # every reached sample against a z-buffer of the balls every 0.005 mm along the passes (independent)
    rng = np.random.default_rng(7)
    pick = rng.choice(np.flatnonzero(res.reached), 300, replace=False)
    z = _zbuffer_ball(p[pick, :2], _dense_centres(tp, R), R)
    assert_close(res.value[pick], z, 2e-6, "material left against the z-buffer")
    # strict JSON: NaN/inf as null
    import json

    from machsurf_cad.results import strict_json

    json.loads(strict_json(rep), parse_constant=lambda c: pytest.fail(f"non-strict JSON constant {c}"))


@pytest.mark.parametrize("kind", ["flat", "bull"])
def test_flat_and_bull_rasters_on_a_plane_leave_the_floor_and_the_torus_cusp(kind):
    """3 axes on a plane, passes along x: a flat end mill D10 with passes 8 mm apart leaves a flat floor (no
    scallop: its bottom overlaps); a bull D10 r2 (R_t 3) with passes 7 mm apart leaves, at a distance d from the
    nearest pass, 0 under the flat bottom (d <= R_t) and r - sqrt(r^2 - (d - R_t)^2) beyond: the cusp at d = 3.5
    is 2 - sqrt(4 - 0.25) = 0.06351 mm. The flat end mill reaches nothing beyond its radius (no border); the
    bull's torus does (border, reported apart)."""
    cut, s = (ms.FlatEndMill(10), 8.0) if kind == "flat" else (ms.BullNoseEndMill(10, 2), 7.0)
    plane = builders.plane_patch((-8.0, -2.0 * s, 0.0), (16.0, 0, 0), (0, 4.0 * s, 0))
    tp = _raster(cut, s, n_pass=3)
    res = ms.simulate(plane, tp, resolution=s / 40)  # rows on the cusp lines y = +-s/2
    rep = res.report()
    p = res.points
    d = np.min(np.abs(p[:, 1][:, None] - np.array([-s, 0.0, s])[None, :]), axis=1)
    box = (np.abs(p[:, 0]) <= 4.0 + 1e-9) & (np.abs(p[:, 1]) <= s + 1e-9)
    if kind == "flat":
        assert rep["max_scallop_mm"] < 1e-12 and rep["border"]["n_samples"] == 0
        # under the flat bottoms: the passes' footprints (discs of radius 5 along them): all reached samples
        foot = np.min(np.hypot(np.maximum(np.abs(p[:, 0]) - 4.0, 0.0)[:, None],
                               p[:, 1][:, None] - np.array([-s, 0.0, s])[None, :]), axis=1)  # fmt: skip
        assert np.array_equal(res.in_region, res.reached) and np.all(foot[res.reached] <= 5.0 + 1e-9)
    else:
        r_, R_t = 2.0, 3.0
        exact = np.where(d <= R_t, 0.0, r_ - np.sqrt(np.maximum(r_ * r_ - (d - R_t) ** 2, 0.0)))
        reg = res.in_region
        assert np.all(reg[box & res.reached]) and reg.sum() > 0
        inner = reg & box
        assert_close(res.value[inner], exact[inner], 1e-6, "torus section across the passes")
        assert_close(rep["max_scallop_mm"], r_ - math.sqrt(r_ * r_ - (s / 2 - R_t) ** 2), 1e-6, "bull cusp")
        # past the pass ends, under the flat bottom (within R_t of the end point) is machined; the rest is border
        end = np.hypot(np.maximum(np.abs(p[:, 0]) - 4.0, 0.0), d)
        assert np.array_equal(reg & ~box, res.reached & ~box & (end <= R_t + 1e-9))
        assert rep["border"]["n_samples"] > 0 and rep["border"]["max_material_mm"] > 0.5
    assert rep["max_gouge_mm"] < 1e-12


def test_ball_raster_on_a_sloped_plane_leaves_the_cusp_along_the_slope():
    """A plane rising 20 deg across the feed, a 3-axis ball R 5 touching it with contacts s = 1.0353 mm apart
    along the slope: the material left along the normal at a distance d (along the slope) from the nearest
    contact line is R - sqrt(R^2 - d^2); the cusp 0.026867 mm. The machined region is the strip between the
    outer contact lines, over the passes' length."""
    R, s, th = R_BALL, S_CUSP, math.radians(20.0)
    along = np.array([0.0, math.cos(th), math.sin(th)])
    plane = builders.plane_patch(-4 * s * along + [-6.0, 0, 0], (12.0, 0, 0), 8 * s * along)
    tp = _raster(ms.BallEndMill(2 * R), s, slope=20.0)
    res = ms.simulate(plane, tp, resolution=s / 20)
    rep = res.report()
    c = res.points @ along  # coordinate along the slope
    d = np.min(np.abs(c[:, None] - (np.arange(5) - 2)[None, :] * s), axis=1)
    box = (np.abs(res.points[:, 0]) <= 4.0 + 1e-9) & (np.abs(c) <= 2 * s + 1e-9)
    assert np.array_equal(res.in_region, box & res.reached)
    assert_close(res.value[box], R - np.sqrt(R * R - d[box] ** 2), 1e-6, "profile along the slope")
    assert_close(rep["max_scallop_mm"], _cusp(R, s), 1e-6, "cusp on the slope")
    assert rep["border"]["max_material_mm"] > 0.5 and rep["max_gouge_mm"] < 1e-9


def _top_and_wall(delta=0.002):
    """The pump's mechanism, built here: a top face z = 0 (y < 0) meeting a wall y = 0 (z < 0) at a convex
    edge; a bull D10 r2 raster over the top, dipping ``delta`` below it (a chord's sag), passes running over
    the edge (the tool overhangs the wall)."""
    top = ms.Face(builders.plane_patch((-8, -8, 0), (16, 0, 0), (0, 8, 0)), name="top")
    wall_s = builders.plane_patch((-8, 0, -6), (16, 0, 0), (0, 0, 6))
    out = float(ms.local_properties(wall_s, 0.5, 0.5).normal[1]) > 0
    wall = ms.Face(wall_s, name="wall", reversed=not out)
    x = np.linspace(-6, 6, 25)
    tips = [np.stack([x, np.full_like(x, y), np.full_like(x, -delta)], 1) for y in np.arange(-7.0, 3.01, 2.0)]
    tp = _passes(tips, [np.tile([0.0, 0, 1], (x.size, 1))] * len(tips), ms.BullNoseEndMill(10, 2))
    return [top, wall], tp


def _body_depth(cut, tp, P, step=0.01):
    """Brute force: the signed distance of points to the tool body placed every ``step`` mm along the
    moves (3 axes), the smallest over the placements (negative: inside)."""
    from machsurf_cad.simulation.nbuffer import motion_poses

    T, A, _ = motion_poses(tp.tip, tp.axis, step, float(cut.length))
    best = np.full(P.shape[0], np.inf)
    for i in range(0, T.shape[0], 2000):
        q = P[:, None, :] - T[None, i : i + 2000, :]
        rho = np.hypot(q[..., 0], q[..., 1])
        best = np.minimum(best, cut.cutting_distance_rz(rho, q[..., 2]).min(axis=1))
    return best


def test_a_dip_at_a_convex_edge_gouges_its_depth_not_the_length_of_the_wall_blade():
    """The tool dips 2 um into the top face and holds the edge: the wall's blades at the edge run along the
    top face under the tool's flat bottom, so along the wall's normal the cut is 1 mm long (the old figure:
    1 mm "gouges" on every wall, as on the pump's 14 faces). The gouge is the depth of the nominal point
    inside the swept tool: 2 um, as verify's body check and a brute force here (every 0.01 mm) find."""
    faces, tp = _top_and_wall(0.002)
    res = ms.simulate(faces, tp, resolution=0.1)
    rep = res.report()
    assert_close(rep["max_gouge_mm"], 0.002, 1e-9, "gouge at the edge")
    assert not rep["gouged"] and rep["n_unconverged"] == 0 and rep["not_measured"]["n_samples"] == 0
    walls = rep["faces"][1]
    assert walls["name"] == "wall" and walls["max_gouge_mm"] == pytest.approx(0.002, abs=1e-9)
    assert float(-res.normal_value[res.face == 1].min()) > 0.5  # what the thickness along the normal says
    gouged = np.flatnonzero(res.reached & (res.value < 0))
    on_wall = gouged[res.face[gouged] == 1]
    assert on_wall.size > 10
    gouged = np.concatenate([on_wall, np.random.default_rng(5).choice(gouged, 200, replace=False)])
    brute = _body_depth(ms.BullNoseEndMill(10, 2), tp, res.points[gouged])
    assert_close(res.value[gouged], np.minimum(brute, 0.0), 1e-6, "depth inside the tool (brute force)")
    v = ms.verify(faces, tp)
    assert abs(v.max_gouge - res.max_gouge) <= 1e-6


def test_rays_that_do_not_converge_are_counted_located_and_not_measured(monkeypatch):
    """Sphere tracing the whole bull body (its general path) crawls along rays that graze its flat bottom: the
    tool dips 0.0995 mm into the top face, the wall's sample row at z = -0.1 runs 0.5 um under the bottom.
    Such a ray is neither a gouge nor a scallop: its samples are reported as not measured (count, faces, where)
    and left out of every figure. The closed-form path measures them all, with the same gouge."""
    import machsurf_cad.simulation.nbuffer as nb

    faces, tp = _top_and_wall(0.0995)
    monkeypatch.setattr(nb, "ray_core", lambda cutter: None)
    res = ms.simulate(faces, tp, resolution=0.1)
    rep = res.report()
    nm = rep["not_measured"]
    assert rep["n_unconverged"] > 0 and nm["n_rays"] == rep["n_unconverged"]
    assert nm["n_samples"] == int((~res.measured).sum()) > 0 and {f["name"] for f in nm["per_face"]} <= {"top", "wall"}
    assert len(nm["where_xyz_mm"]) == min(20, nm["n_samples"])
    assert not (res.in_region & ~res.measured).any() and not (res.on_border & ~res.measured).any()
    assert_close(rep["max_gouge_mm"], 0.0995, 1e-6, "gouge of the measured samples")
    monkeypatch.undo()
    exact = ms.simulate(faces, tp, resolution=0.1)
    assert exact.n_unconverged == 0 and exact.measured.all()
    ok = res.measured & res.reached
    assert_close(res.value[ok], exact.value[ok], 1e-5, "measured samples agree with the closed form")


def test_the_torus_quartic_solves_the_grazing_rays_sphere_tracing_cannot():
    """Rays parallel to a bull's flat bottom, 1e-9 to 1e-2 mm above it, enter its torus where the tube's
    height above the bottom equals theirs: closed form. Sphere tracing crawls (steps the size of the height);
    the quartic's root is exact."""
    from machsurf_cad.simulation.rays import _trace_torus, torus_quartic_entry

    rng = np.random.default_rng(3)
    R_t, r, m = 3.0, 2.0, 2000
    eps = 10 ** rng.uniform(-9, -2, m)
    y = rng.uniform(-4.9, 4.9, m)
    qp = np.stack([np.full(m, -7.0), y, np.zeros(m)], 1)
    dp = np.tile([1.0, 0.0, 0.0], (m, 1))
    t0, stop = np.zeros(m), np.full(m, 20.0)
    _, st = _trace_torus(R_t, r, qp, dp, eps, np.zeros(m), t0, stop, 600)
    t, sq = torus_quartic_entry(R_t, r, qp, dp, eps, np.zeros(m), t0, stop)
    rho = R_t + np.sqrt(np.maximum(r * r - (eps - r) ** 2, 0.0))  # the tube at the ray's height
    hit = np.abs(y) < rho
    exact = 7.0 - np.sqrt(np.maximum(rho**2 - y**2, 0.0))
    assert (st == 3).sum() > m / 4  # the tracing stalls on many
    assert np.array_equal(sq == 0, hit) and np.all(sq[~hit] == 2)
    assert_close(t[hit], exact[hit], 1e-8, "entry into the torus")


def test_the_map_shows_the_border_and_what_was_not_measured():
    """The map's point data name each sample's region (1 machined, 0 border, -1 not reached, -2 not measured)."""
    pytest.importorskip("pyvista")
    from machsurf_cad.viz.simmap import simulation_polydata

    res = ms.simulate(_plane(3.0, 3.0), _raster(ms.BallEndMill(10), 1.0, n_pass=3, half=1.5), resolution=0.1)
    reg = np.asarray(simulation_polydata(res).point_data["region"])
    assert set(np.unique(reg)) >= {0, 1} and np.array_equal(reg == 1, res.in_region)
    assert np.array_equal(reg == 0, res.on_border)
