"""The N-buffer cut simulation: closed forms, an independent z-buffer and brute force, gouges, bad input."""

import math

import numpy as np
import pytest
from conftest import ROOT, needs_kernel
from helpers import assert_close
from scipy.spatial import cKDTree

import machsurf_cad as ms
from machsurf_cad.geometry import builders
from machsurf_cad.simulation.scallop import scallop_height, spacing_for_scallop


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


@pytest.mark.parametrize("kappa_sign", [1, -1])
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
    res = ms.simulate(_plane(), tp, resolution=0.05, tolerance=0.01)
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
