"""The tool-body check: closed forms, an independent brute force, the demo's path on the whole block."""

import math

import numpy as np
import pytest
from conftest import ROOT, needs_kernel
from helpers import assert_close

import machsurf_cad as ms
from machsurf_cad.geometry import builders


def _trough(rho: float, half_angle_deg: float = 60.0, length: float = 60.0):
    """The inside of a cylinder of radius ``rho`` (axis x at height rho), +-half_angle around its bottom line
    z = 0; the outward normal (into the tool, out of the material) points to the axis."""
    from machsurf_cad.geometry import builders

    arc = builders.circular_arc(rho, -90.0 - half_angle_deg, -90.0 + half_angle_deg, center=(0.0, rho))
    # sweep the (y, z) arc along x: a ruled surface between the arc at x = 0 and at x = length
    c0 = ms.BSplineCurve(arc.degree, arc.knots, arc.mults, np.c_[np.zeros(len(arc.poles)), arc.poles], arc.weights)
    c1 = ms.BSplineCurve(
        arc.degree, arc.knots, arc.mults, np.c_[np.full(len(arc.poles), length), arc.poles], arc.weights
    )
    s = builders.ruled_surface(c0, c1)
    p = ms.local_properties(s, 0.5, 0.5)
    up = float(p.normal[2]) > 0  # the material is below the trough's surface: outward normal points up
    return ms.Face(s, name="trough", reversed=not up)


def _ball_path(r: float, length: float = 60.0):
    tips = [np.array([[10.0, 0.0, 0.0], [length - 10.0, 0.0, 0.0]])]
    return ms.ToolPath.from_passes(tips, [np.array([[0.0, 0.0, 1.0]] * 2)], cutter=ms.BallEndMill(2 * r))


@pytest.mark.parametrize("r,rho", [(9.9, 10.0), (10.5, 10.0), (12.0, 10.0)])
def test_ball_in_a_concave_cylinder_gouges_iff_r_exceeds_rho(r, rho):
    face = _trough(rho)
    res = ms.verify(face, _ball_path(r), gouge_tolerance=1e-3)
    # closed form: with the tip on the bottom line, the distance from the ball's centre to the trough's
    # points at angle t is sqrt(r^2 - 2 rho (r - rho)(1 - cos t)): the depth is largest at the edge t = 60 deg
    depth = r - math.sqrt(r * r - 2 * rho * (r - rho) * (1 - math.cos(math.radians(60.0)))) if r > rho else 0.0
    cut = res.toolpath.move == ms.Move.CUT
    assert_close(res.gouge_depth[cut].max(), depth, 1e-3, "gouge depth")
    assert (res.report()["n_gouging_positions"] > 0) == (r > rho)


def _brute_depth(face, cutter, tip, axis, n=1200):
    """Independent: the part sampled densely in (u, v), the bull-nose body from its closed form in (rho, z)."""
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    U, V = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n), indexing="ij")
    P = s.evaluate(U.ravel(), V.ravel())
    rel = P - tip
    z = rel @ axis
    rho = np.linalg.norm(rel - z[:, None] * axis, axis=1)
    R, r = cutter.D / 2, cutter.r
    Rt = R - r
    tube = np.hypot(rho - Rt, z - r)
    # inside the body, and the depth to its nearest boundary (bottom disc, torus corner, side), shallow points
    flat = (rho <= Rt) & (z >= 0) & (z < r)
    corner = (rho > Rt) & (z < r) & (tube < r)
    side = (z >= r) & (z <= cutter.length) & (rho < R)
    depth = np.zeros(rho.shape)
    depth[flat] = np.minimum(z[flat], r - np.hypot(np.maximum(rho[flat] - Rt, 0), z[flat] - r))
    depth[corner] = r - tube[corner]
    depth[side] = np.minimum(R - rho[side], cutter.length - z[side])
    return float(depth.max())


def test_rear_gouge_agrees_with_an_independent_brute_force():
    """A bull D28 r4 at lead 5 deg along a concave trough of radius 60: its heel cuts behind the contact."""
    face = _trough(60.0, 45.0, 100.0)
    res = ms.machining_surface(face, "bull:D=28,r=4", axes=5, lead=5, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=20.0)
    v = ms.verify(face, tp, gouge_tolerance=0.01, step=0.5)
    w = v.worst(1)[0]
    i = w["index"]
    assert w["status"] == "gouge" and w["depth_mm"] > 1.0
    # the deepest placement of the motion ending at i, brute-forced on a dense parameter grid
    a, b = tp.tip[i - 1], tp.tip[i]
    aa, ab = tp.axis[i - 1], tp.axis[i]
    best = 0.0
    for s in np.linspace(0, 1, 21)[1:]:
        ax = (1 - s) * aa + s * ab
        best = max(best, _brute_depth(face, tp.cutter, (1 - s) * a + s * b, ax / np.linalg.norm(ax), n=900))
    assert abs(best - w["depth_mm"]) <= 1e-3, (best, w["depth_mm"])


@needs_kernel
def test_demo_path_is_clean_on_the_whole_block_and_a_shifted_one_reads_its_shift():
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    top = faces[0]
    res = ms.machining_surface(top, "bull:D=16,r=3", axes=5, lead=10, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=4.0, chordal_tolerance=0.005)
    v = ms.verify(faces, tp, gouge_tolerance=0.01)
    assert v.clean and v.report()["n_faces"] == 8
    assert v.max_gouge <= 0.005 + 0.002  # chords and fits, within their stated tolerances
    # the cutting positions moved 0.05 mm into the part along the nominal's outward normal at the contact
    uv = tp.extras["uv"]
    cut = ~np.isnan(uv[:, 0])
    n = np.zeros_like(tp.tip)
    n[cut] = top.surface.normals(uv[cut, 0], uv[cut, 1]) * (-1.0 if top.reversed else 1.0)
    moved = ms.ToolPath(tp.tip - 0.05 * n, tp.axis, tp.move, tp.pass_index, cutter=tp.cutter)
    at_positions = ms.verify(faces, moved, gouge_tolerance=0.01, step=1e9, angle_step=180)  # the GOTOs themselves
    assert_close(at_positions.max_gouge, 0.050, 1e-3, "gouge of a path moved 0.05 mm into the part")
    assert at_positions.report()["n_gouging_positions"] >= 0.9 * int(cut.sum())
    along = ms.verify(faces, moved, gouge_tolerance=0.01)  # and as the CNC moves between them: chords add their sag
    assert 0.050 - 1e-3 <= along.max_gouge <= 0.050 + 0.005 + 2e-3


def test_shank_and_holder_collisions_and_rapids():
    from machsurf_cad.geometry import builders

    wall = builders.plane_patch(origin=(0, 0, 0), du=(100, 0, 0), dv=(0, 0, 100))  # x-z plane, normal -y
    face = ms.Face(wall, reversed=True)  # material on y < 0... outward normal +y
    body = ms.BullNoseEndMill(10, 2, 20, shank=ms.Shank(16, 30), holder=ms.Shank(40, 40))
    # tool axis along +y, tip 1 mm off the wall: the cutting part is clear, nothing else near
    tp = ms.ToolPath.from_passes(
        [np.array([[50.0, 1.0, 50.0], [60.0, 1.0, 50.0]])], [np.array([[0, 1.0, 0]] * 2)], cutter=body
    )
    assert ms.verify(face, tp, gouge_tolerance=0.01).clean
    # axis parallel to the wall, 6 mm off: the cutting part (R 5) is clear but the shank (R 8) cuts 2 mm in
    tp2 = ms.ToolPath.from_passes(
        [np.array([[50.0, 6.0, 10.0], [60.0, 6.0, 10.0]])], [np.array([[0, 0, 1.0]] * 2)], cutter=body
    )
    v2 = ms.verify(face, tp2, gouge_tolerance=0.01)
    assert v2.report()["n_collisions"] > 0 and v2.report()["n_gouging_positions"] == 0
    assert_close(v2.report()["min_clearance_mm"], -14.0, 1e-6, "holder depth (R 20, z 60..100 on a 100 mm wall)")
    no_holder = ms.BullNoseEndMill(10, 2, 20, shank=ms.Shank(16, 30))
    v3 = ms.verify(face, tp2, no_holder, gouge_tolerance=0.01)
    assert_close(v3.report()["min_clearance_mm"], -2.0, 1e-6, "shank depth (R 8 at 6 mm from the wall)")


def test_a_rapid_within_a_clearance_of_several_mm_is_seen():
    """A rapid 1.5 mm over a plane, ball D10, part sampled every 1 mm: with a 2 mm clearance it is a
    collision at the closed-form 1.5 mm (the samples' window grows by the clearance; before, the cutting
    part's window ended a sample spacing past the tool and the rapid read clear); with 1 mm it is clear."""
    plane = builders.plane_patch()  # z = 0, 100 x 100
    tp = ms.ToolPath([[20.0, 50, 1.5], [80, 50, 1.5]], [[0, 0, 1.0]] * 2, [ms.Move.RAPID] * 2, [0, 0],
                     cutter=ms.BallEndMill(10))  # fmt: skip
    res = ms.verify(plane, tp, clearance=2.0, spacing=1.0)
    assert not res.clean and res.report()["n_collisions"] == 2
    assert 1.5 <= res.cut_distance.min() < 1.5 + 1e-3
    assert ms.verify(plane, tp, clearance=1.0, spacing=1.0).clean


def test_bad_input():
    face = ms.Face(ms.example("bezier5"))
    tp = ms.ToolPath.from_passes([np.array([[0.0, 0, 500], [10, 0, 500]])], [np.array([[0, 0, 1.0]] * 2)])
    with pytest.raises(ms.InputError, match="needs the tool"):
        ms.verify(face, tp)
    with pytest.warns(UserWarning, match="never comes within"):
        v = ms.verify(face, tp, ms.BallEndMill(10))
    assert v.clean and v.report()["warnings"]
    with pytest.raises(ms.InputError, match="tolerance must be > 0"):
        ms.verify(face, tp, ms.BallEndMill(10), gouge_tolerance=0)


@needs_kernel
def test_verify_command_reads_apt_and_csv_and_exits_by_the_result(tmp_path):
    import csv
    import json

    from helpers import run

    from machsurf_cad.occ import read_step_faces

    block = ROOT / "example_parts" / "freeform_block.step"
    top = read_step_faces(block, [0])[0]
    res = ms.machining_surface(top, "bull:D=16,r=3", axes=5, lead=10, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=8.0)
    apt = ms.write_apt(tmp_path / "p.apt", tp)
    out = tmp_path / "v"
    r = run("verify", block, "--toolpath", apt, "-o", out)  # the tool from the APT's CUTTER
    assert r.returncode == 0, r.stdout + r.stderr
    rep = json.loads((out / "report.json").read_text())["verify"]
    assert rep["clean"] and rep["n_faces"] == 8 and rep["n_positions"] == tp.n_positions
    assert (out / "verify_part.png").is_file() and (out / "verify_path.png").is_file()
    uv = tp.extras["uv"]
    cut = ~np.isnan(uv[:, 0])
    n = np.zeros_like(tp.tip)
    n[cut] = top.surface.normals(uv[cut, 0], uv[cut, 1]) * (-1.0 if top.reversed else 1.0)
    bad = ms.write_csv(
        tmp_path / "bad.csv", ms.ToolPath(tp.tip - 0.2 * n, tp.axis, tp.move, tp.pass_index, cutter=tp.cutter)
    )
    r = run(
        "verify", block, "--toolpath", bad, "--tool", "bull:D=16,r=3", "--shank", "D=16,L=40", "-o", tmp_path / "v2"
    )
    assert r.returncode == 2 and "NOT clean" in r.stdout
    rep = json.loads((tmp_path / "v2" / "report.json").read_text())["verify"]
    assert rep["max_gouge_mm"] > 0.19 and rep["worst"][0]["face"] == "freeform_top"
    r = run("verify", block, "--toolpath", bad, "-o", tmp_path / "v3")  # our CSV carries its cutter
    assert r.returncode == 2 and "tool bull:D=16,r=3" in r.stdout
    rep3 = json.loads((tmp_path / "v3" / "report.json").read_text())["verify"]
    assert rep3["max_gouge_mm"] == pytest.approx(rep["max_gouge_mm"], abs=1e-9)
    plain = tmp_path / "plain.csv"  # a CSV without our tool column names no tool
    plain.write_text("\n".join(",".join(r[:13]) for r in csv.reader(bad.read_text().splitlines())) + "\n")
    r = run("verify", block, "--toolpath", plain, "-o", tmp_path / "v3b")
    assert r.returncode == 1 and "give --tool" in r.stderr
    r = run("verify", block, "--toolpath", bad, "--tool", "ball:D=10", "--shank", "D=10", "-o", tmp_path / "v4")
    assert r.returncode == 1 and "needs D and L" in r.stderr


def test_auto_lead_matches_the_rear_gouge_threshold_of_a_concave_cylinder():
    """A bull D28 r4 feeding along a concave cylinder of radius 60: local gouge iff R_t / sin(lead) + r > rho.
    lead="auto" (no margin) finds asin(10 / 56) = 10.29 deg; a brute force (dense trough samples, the
    bull-nose body in closed form) bisected on the lead agrees within 0.1 deg; lead 5 gouges 1.8 mm."""
    face = _trough(60.0, 45.0, 100.0)
    cut = ms.BullNoseEndMill(28, 4)
    res = ms.machining_surface(face, cut, axes=5, lead="auto", lead_margin=0.0, tolerance=1e-3)
    auto = res.report()["auto_lead"]["lead_min_deg"]
    assert_close(auto, math.degrees(math.asin(10 / 56)), 1e-9, "closed-form threshold")

    def depth(lead_deg):  # tool at the bottom line, axis leaned by the lead towards the feed (+y here)
        lam = math.radians(lead_deg)
        axis = np.array([0.0, math.sin(lam), math.cos(lam)])
        # the tip placed so that the body's lowest point (the contact, normal +z) is at the bottom (0, 0, 0)
        return _brute_depth(face, cut, -_lowest_point(cut, axis), axis, n=900)

    lo, hi = 5.0, 20.0
    assert depth(lo) > 1.0 and depth(hi) < 1e-4
    for _ in range(18):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if depth(mid) > 1e-4 else (lo, mid)
    assert abs(hi - auto) < 0.1, (hi, auto)
    tp = ms.tool_paths(ms.machining_surface(face, cut, axes=5, lead=5, tolerance=1e-3), stepover=10)
    assert ms.verify(face, tp, gouge_tolerance=0.01).max_gouge > 1.7  # the 1.80 mm behind the contact


def _lowest_point(cutter, axis):
    """The point of the tool body lowest along -z when the tip is at the origin (the contact with a
    horizontal bottom line), from the profile: the corner torus point whose normal is -z."""
    ez = np.array([0.0, 0.0, 1.0])
    w = ez - (ez @ axis) * axis  # the radial direction towards which the torus's lowest point lies is -w
    w = w / np.linalg.norm(w) if np.linalg.norm(w) > 1e-12 else np.array([1.0, 0.0, 0.0])
    centre = -cutter.R_t * w + cutter.r * axis  # corner circle centre in that direction
    return centre - cutter.r * ez


def _channel(radius: float = 8.0, length: float = 60.0):
    """A concave channel: the lower half (+-80 deg) of a cylinder of ``radius`` along x, open upwards."""
    from machsurf_cad.geometry import builders

    arc = builders.circular_arc(radius, -170.0, -10.0, center=(0.0, radius))
    pts = np.asarray(arc.poles)
    c0 = ms.BSplineCurve(arc.degree, arc.knots, arc.mults, np.c_[np.zeros(len(pts)), pts], arc.weights)
    c1 = ms.BSplineCurve(arc.degree, arc.knots, arc.mults, np.c_[np.full(len(pts), length), pts], arc.weights)
    s = builders.ruled_surface(c0, c1)
    up = ms.local_properties(s, 0.5, 0.5).normal[2] > 0
    return ms.Face(s, name="channel", reversed=not up)


@pytest.mark.parametrize("tool", ["bull:D=20,r=3", "flat:D=20"])
def test_three_axis_bull_and_flat_in_a_narrow_channel_are_global_loops(tool):
    """3 axes, fixed axis tilted 5 deg, a channel (radius 8) narrower than the tool (radius 10): the tool body
    cuts the channel's walls at every placement; reported as a global loop (the ball D10 fits, no loop)."""
    face = _channel()
    ax = (math.sin(math.radians(5)), 0.0, math.cos(math.radians(5)))
    with pytest.raises(ms.LoopError, match="global loop"):
        ms.machining_surface(face, tool, axes=3, axis=ax, strategy="planes:y", tolerance=1e-3)
    res = ms.machining_surface(face, tool, axes=3, axis=ax, strategy="planes:y", tolerance=1e-3, loops="flag")
    glob = [r for r in res.loops.regions if r.kind == "global"]
    assert glob and glob[0].n_samples > 1000
    ok = ms.machining_surface(face, "ball:D=10", axes=3, axis=ax, strategy="planes:y", tolerance=1e-3)
    assert not ok.loops.found


@needs_kernel
def test_envelope_tool_path_is_checked_against_a_given_part(tmp_path):
    import json

    from helpers import run

    block = ROOT / "example_parts" / "freeform_block.step"  # x 5..125, y 5..95, z -40..51
    out = tmp_path / "env"
    path = tmp_path / "path.json"  # a D10 cylinder, axis z, 8 mm from the y = 5 wall: 2 mm into it
    path.write_text(json.dumps({"points": [[x, 8.0, 0.0] for x in (20.0, 40.0, 60.0, 80.0, 100.0)]}))
    r = run(
        "envelope", "--tool", "cyl:D=10", "--path", path, "--passes", "1", "--part", block, "--no-render", "-o", out
    )
    assert r.returncode == 2 and "tool path NOT written" in r.stdout
    v = json.loads((out / "report.json").read_text())["verify"]
    assert v["n_gouging_positions"] > 0 and abs(v["max_gouge_mm"] - 2.0) < 1e-3  # R 5, 3 mm from the axis
    r = run("envelope", "--tool", "cyl:D=10", "--path", path, "--passes", "1", "--no-render", "-o", out)
    assert r.returncode == 0 and "written unchecked" in r.stdout


@needs_kernel
def test_a_tool_buried_in_the_material_is_a_gouge():
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")  # x 5..125, y 5..95, z -40..51
    tp = ms.ToolPath.from_passes(
        [np.array([[60.0, 50, 0], [70, 50, 0]])], [np.array([[0, 0, 1.0]] * 2)], cutter=ms.FlatEndMill(10)
    )  # touches no face: entirely inside the block
    v = ms.verify(faces, tp)
    rep = v.report()
    assert rep["n_gouging_positions"] == 2 and rep["n_collisions"] == 1  # approach and cut; the rapid too
    assert v.max_gouge > 5.0 - 1.0  # at least its depth behind the nearest face, less the radius


def test_trim_gouges_keeps_the_clear_stretches_and_rechecks_them(tmp_path):

    from machsurf_cad.pathcheck import clear_runs

    face = ms.Face(ms.example("bezier5"), name="bezier5")
    res = ms.machining_surface(face, "bull:D=28,r=4", axes=5, lead=5, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=5.0)
    v = ms.verify(face, tp)
    kept = clear_runs(tp, v)
    assert kept is not None and 0 < kept.n_cut < tp.n_cut
    # every kept cutting position was a clear one of the original path, in the same order within its run
    orig = {tuple(np.round(p, 9)) for p, s, m in zip(tp.tip, v.status, tp.move) if s == 0 and m in (1, 2)}
    cutting = (kept.move == ms.Move.CUT) | (kept.move == ms.Move.APPROACH)
    assert all(tuple(np.round(p, 9)) in orig for p in kept.tip[cutting])
    assert ms.verify(face, kept).clean  # on this face the relinked stretches are clean


@needs_kernel
def test_trim_gouges_writes_the_clear_stretches(tmp_path):  # the command writes STEP: needs the kernel
    import json

    from helpers import run

    face = ms.Face(ms.example("bezier5"), name="bezier5")
    out = tmp_path / "t"
    r = run(
        "machining-surface",
        "--example",
        "bezier5",
        "--tool",
        "bull:D=28,r=4",
        "--lead",
        "5",
        "--tolerance",
        "0.001",
        "--toolpath",
        "--stepover",
        "5",
        "--trim-gouges",
        "-o",
        out,
    )
    assert r.returncode == 0 and "cut down to its clear stretches" in r.stdout, r.stdout
    t = json.loads((out / "report.json").read_text())["verify"]["trimmed"]
    assert t["recheck"]["clean"] and t["n_cut_kept"] < t["n_cut_before"]
    back = ms.read_apt(out / "toolpath.apt")
    assert ms.verify(face, back, ms.BullNoseEndMill(28, 4)).clean  # what was written is clean, read back from the file


def test_the_motion_between_placements_cannot_hide_a_gouge():
    """A ball D10 moving straight over a convex ridge (two planes meeting at x = 0, slopes -+0.2) with
    its tip 0.02 mm below the ridge: the motion gouges 0.02 mm at x = 0, where no position is.
    Placements 1 mm apart (x = +-0.5 nearest) read a clearance of 0.5^2 / (2 R) - 0.02 = 0.005 mm: a
    silent gouge. The default step sqrt(4 R tol) = 0.447 mm misses at most step^2 / (8 R) = tol / 2
    (reported): the gouge is flagged and its depth within that bound."""
    left = builders.plane_patch((-10, -10, -2), (10, 0, 2), (0, 20, 0))
    right = builders.plane_patch((0, -10, 0), (10, 0, -2), (0, 20, 0))
    tips = [np.array([[-2.5, 0.0, -0.02], [2.5, 0.0, -0.02]])]
    tp = ms.ToolPath.from_passes(tips, [np.array([[0.0, 0, 1]] * 2)], cutter=ms.BallEndMill(10), clearance=5)
    coarse = ms.verify([left, right], tp, gouge_tolerance=0.01, step=1.0)
    assert coarse.clean and abs(coarse.cut_distance.min() - 0.005) < 1e-3  # a 1 mm step sees 0.005 clearance
    assert abs(coarse.motion_bound_mm - 1 / 40) < 1e-12  # ... and says it may miss 0.025 mm
    res = ms.verify([left, right], tp, gouge_tolerance=0.01)
    assert math.isclose(res.step_mm, math.sqrt(4 * 5 * 0.01)) and math.isclose(res.motion_bound_mm, 0.005)
    assert not res.clean and 0.02 - res.motion_bound_mm <= res.max_gouge <= 0.02 + 1e-6
    assert res.report()["motion_bound_mm"] == res.motion_bound_mm


@needs_kernel
def test_a_tool_high_above_a_hole_is_not_buried():
    """The block's top has a round hole: a tool 60 mm above it, next to the hole's axis, has a sample of the
    hole's wall as its nearest part point, whose normal faces away from it. It is not in the material:
    clear (the buried test asks every one of the nearest samples, not the nearest alone). The same tool
    sunk into the block is still found buried."""
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    cutter = ms.BallEndMill(6)
    above = ms.ToolPath(np.array([[75.2, 63.66, 109.7]]), np.array([[0.0, 0.0, 1.0]]), np.array([ms.Move.RAPID]),
                        np.array([0]), cutter=cutter)  # fmt: skip
    with pytest.warns(UserWarning, match="never comes within"):  # one position far from the part: said
        v = ms.verify(faces, above, gouge_tolerance=0.01)
    assert v.clean and v.report()["n_collisions"] == 0
    inside = ms.ToolPath(np.array([[65.0, 30.0, 0.0]]), np.array([[0.0, 0.0, 1.0]]), np.array([ms.Move.CUT]),
                         np.array([0]), cutter=cutter)  # fmt: skip
    w = ms.verify(faces, inside, gouge_tolerance=0.01)
    assert not w.clean and w.max_gouge > 1.0  # at least this deep (a bound: the nearest tangent planes)


@needs_kernel
def test_far_from_every_face_buried_needs_the_winding_number_too():
    """Far from the part the nearest samples can all show their backs (the impeller's rapids 116 mm above its
    blade tips read 80 mm "into" them): there a tool is buried only if the samples' winding number says it is
    inside. The block's winding number is 1 in its material and 0 far outside (a closed part); with
    every face turned over, a tool 60 mm above it is behind all its nearest samples yet outside: clear."""
    from dataclasses import replace

    from machsurf_cad.buried import winding_number
    from machsurf_cad.gougecheck import _sample_part
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    w = winding_number(faces, _sample_part(faces, 1.0, 10**7), np.array([[20.0, 20, 0], [65, 50, 200], [300, 0, 0]]))
    assert abs(w[0] - 1) < 0.02 and abs(w[1]) < 0.02 and abs(w[2]) < 0.02
    turned = [replace(f, reversed=not f.reversed) for f in faces]
    above = ms.ToolPath(np.array([[65.0, 50, 110], [75, 50, 110]]), np.array([[0.0, 0, 1]] * 2),
                        np.array([ms.Move.RAPID] * 2), np.array([0, 0]), cutter=ms.BallEndMill(6))  # fmt: skip
    with pytest.warns(UserWarning, match="never comes within"):
        assert ms.verify(turned, above).clean


def test_the_same_check_twice_is_answered_once_and_a_changed_input_is_checked_again():
    """verify keeps its last results by content: the same faces, positions, tool and parameters give the very
    same result at once (a raster's own check, then the check before writing); a position moved by 1 um, a
    face moved, or another tolerance is checked again."""
    import machsurf_cad as ms
    from machsurf_cad import gougecheck

    gougecheck._RECENT.clear()
    dome = ms.builders.plane_patch()  # z = 0, 100 x 100 mm
    tips = [np.array([[x, 50.0, -0.02] for x in np.linspace(20, 80, 81)])]  # 0.02 mm into it
    tp = ms.ToolPath.from_passes(tips, [np.tile([0.0, 0.0, 1.0], (81, 1))], cutter=ms.BallEndMill(10))
    a = ms.verify([dome], tp, gouge_tolerance=0.01)
    b = ms.verify([dome], tp, gouge_tolerance=0.01)
    # answered from the first check (its own timings: a second run would measure its own), reporting the path
    # it was given
    assert b.toolpath is tp and b.time_s == a.time_s and np.array_equal(b.cut_distance, a.cut_distance)
    assert len(gougecheck._RECENT) == 1
    assert abs(a.max_gouge - 0.02) < 2e-3
    moved = tips[0].copy()
    moved[40, 2] += 1e-3
    tp2 = ms.ToolPath.from_passes([moved], [np.tile([0.0, 0.0, 1.0], (81, 1))], cutter=ms.BallEndMill(10))
    c = ms.verify([dome], tp2, gouge_tolerance=0.01)
    assert c.time_s != a.time_s and not np.array_equal(c.cut_distance, a.cut_distance)
    d = ms.verify([dome], tp, gouge_tolerance=0.03)
    assert d.clean and not a.clean


def test_the_threaded_sampled_pass_gives_the_single_pass_figures():
    """From 4096 placements the sampled pass runs in a thread per core: per placement the same distances,
    seeds and sample depths as in one piece (bit for bit)."""

    from machsurf_cad import gougecheck as g
    from machsurf_cad.coarsepass import coarse_pass
    from machsurf_cad.examples import example

    face = ms.Face(example("bezier5", "surface"), name="bezier5")
    smp = g._sample_part([face], 1.0, 10**7)
    from scipy.spatial import cKDTree

    tree = cKDTree(smp.P)
    rng = np.random.default_rng(2)
    lo, hi = smp.P.min(axis=0), smp.P.max(axis=0)
    T = rng.uniform(lo, hi, (5000, 3)) - [0, 0, 2.0]
    A = rng.normal([0, 0, 1], 0.2, (5000, 3))
    A /= np.linalg.norm(A, axis=1, keepdims=True)
    c = ms.parse_cutter("bull:D=10,r=2")
    args = (c, tree, smp.P, 1.0, 0.01, T, A, 1, None, None)
    one = coarse_pass(*args, threaded_from=10**9)
    many = coarse_pass(*args)
    for a, b in zip(one, many):
        np.testing.assert_array_equal(a, b)
    assert np.isfinite(one[0]).sum() > 1000 and (one[4] > 0).any()  # placements near the face, some inside it


def test_a_path_checked_again_after_a_change_measures_only_its_new_placements_with_the_same_figures():
    """The sampled pass keeps the last checks' placements by their exact bits: a path whose moves were
    split (a raster's gouging moves refined) is checked again on its new placements only, and every figure
    equals a check from scratch bit for bit."""
    from machsurf_cad import coarsepass, gougecheck
    from machsurf_cad.examples import example

    face = ms.Face(example("bezier5", "surface"), name="bezier5")
    s = np.linspace(0.1, 0.9, 40)
    uv = np.array([[u, v] for v in (0.3, 0.6) for u in s])
    d = face.surface.derivatives(uv[:, 0], uv[:, 1], 1)
    nrm = np.cross(d.su, d.sv)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) * np.sign(nrm[:, 2:3])
    tips = d.point + nrm * 5.0 - [0, 0, 5.0] - nrm * 0.02  # the ball's centre 0.02 mm too close
    axes = np.tile([0.0, 0, 1], (tips.shape[0], 1))
    tool = ms.BallEndMill(10)
    tp = ms.ToolPath.from_passes([tips[:40], tips[40:]], [axes[:40], axes[40:]], cutter=tool)
    split = np.insert(tp.tip, [7, 30], [(tp.tip[6] + tp.tip[7]) / 2, (tp.tip[29] + tp.tip[30]) / 2], axis=0)
    tp2 = ms.ToolPath(split, np.insert(tp.axis, [7, 30], tp.axis[[7, 30]], axis=0),
                      np.insert(tp.move, [7, 30], ms.Move.CUT),
                      np.insert(tp.pass_index, [7, 30], tp.pass_index[[7, 30]]), cutter=tool)  # fmt: skip
    counts = []

    def seen(done, total, msg):
        counts.append(total)

    for memo in (gougecheck._RECENT, gougecheck._SAMPLED, coarsepass._LAST):
        memo.clear()
    first = ms.verify([face], tp, gouge_tolerance=0.01)
    again = ms.verify([face], tp2, gouge_tolerance=0.01, progress=seen)
    assert 0 < max(counts) <= 12 and first.n_placements > 200  # the two split moves' placements only
    for memo in (gougecheck._RECENT, gougecheck._SAMPLED, coarsepass._LAST):
        memo.clear()
    fresh = ms.verify([face], tp2, gouge_tolerance=0.01)
    for name in ("cut_distance", "holder_distance", "worst_face", "worst_xyz", "status", "sample_depth"):
        np.testing.assert_array_equal(getattr(again, name), getattr(fresh, name))
    assert fresh.max_gouge > 0.015 and (fresh.sample_depth > 0).any()


def test_the_check_does_not_depend_on_the_order_of_the_faces():
    """The faces are checked in the order of their content: the same faces in another order give the same
    figures with the face indices of that order, answered from the first check."""
    from machsurf_cad import gougecheck

    gougecheck._RECENT.clear()
    faces = [ms.Face(ms.builders.plane_patch(), name="floor"),
             ms.Face(ms.builders.plane_patch(origin=(0, 0, 3.0)), name="shelf")]  # fmt: skip
    tips = np.array([[x, 50.0, 2.9] for x in np.linspace(20, 80, 31)])  # 0.1 mm into the shelf, clear of the floor
    tp = ms.ToolPath.from_passes([tips], [np.tile([0.0, 0.0, 1.0], (31, 1))], cutter=ms.BallEndMill(6))
    a = ms.verify(faces, tp, gouge_tolerance=0.01)
    b = ms.verify(faces[::-1], tp, gouge_tolerance=0.01)
    assert b.time_s == a.time_s  # one check
    np.testing.assert_array_equal(a.cut_distance, b.cut_distance)
    assert a.face_names == ("floor", "shelf") and b.face_names == ("shelf", "floor")
    assert set(a.worst_face[a.status != 0]) == {1} and set(b.worst_face[b.status != 0]) == {0}
    assert a.face_names[a.worst_face[5]] == b.face_names[b.worst_face[5]] == "shelf"
    np.testing.assert_array_equal(np.array(a.face_names)[a.sample_face], np.array(b.face_names)[b.sample_face])


@pytest.mark.parametrize(
    ("tool", "clear"),
    [("ball:D=10", 0.0), ("ball:D=10", 5.0), ("bull:D=6,r=1,L=40", 5.0), ("cone:D=6,angle=10,L=20", 5.0),
     ("with holder", 5.0)],
)  # fmt: skip
def test_the_sampled_pass_equals_a_brute_force_over_every_sample(tool, clear):
    """The sampled pass finds a cutting tool's samples through spheres along its axis (not one sphere around
    the whole body): per placement the smallest distance, its sample (the first of equal ones) and the samples
    inside the tool with their depths equal the same figures taken over every sample of the part, bit for bit
    (tilted axes, samples up to the clearance beyond the tool)."""
    from scipy.spatial import cKDTree

    from machsurf_cad.coarsepass import coarse

    rng = np.random.default_rng(11)
    if tool == "with holder":  # the bounding sphere of the whole body: the cutting part's figures all the same
        c = ms.BullNoseEndMill(10, 2, 20, shank=ms.Shank(16, 30), holder=ms.Shank(40, 40))
    else:
        c = ms.parse_cutter(tool)
    h, tol = 0.5, 0.01
    x, y = np.meshgrid(np.arange(-20, 20, h), np.arange(-20, 20, h))
    P = np.column_stack([x.ravel(), y.ravel(), 2 * np.sin(x.ravel() / 4) * np.cos(y.ravel() / 5)])
    P = np.concatenate([P, P[::7] + [0.0, 0.0, 12.0]])  # a second sheet at the height of the tool's body
    m = 200
    A = rng.normal([0, 0, 1], 0.4, (m, 3))
    A /= np.linalg.norm(A, axis=1, keepdims=True)
    T = np.column_stack([rng.uniform(-12, 12, (m, 2)), rng.uniform(-1.5, 8.0, m)])
    # lone samples far from the part, each in a corner of the region the figures see (``pad`` beyond the tool's
    # radius, below its tip or above its top) of a placement: the only sample that placement sees
    pad = h + tol + clear
    r_cut = c.profile_points(16)[:, 0].max()
    eps = np.array([0.02, 0.1, 0.3])
    lone = np.column_stack([100.0 + 10 * np.arange(6), np.zeros(6), np.zeros(6)])
    P = np.concatenate([P, lone])
    depth = np.r_[-(pad - eps), c.length + pad - eps]
    T[:6] = lone - np.column_stack([r_cut + pad - np.r_[eps, eps], np.zeros(6), depth])
    A[:6] = [0.0, 0.0, 1.0]
    cut_d, _, seed, idx, val, _, pl = coarse(c, cKDTree(P), P, h, tol, T, A, clear=clear)
    want_d, want_seed = np.full(m, np.inf), np.full(m, -1)
    pairs = []
    for k in range(m):
        rel = P - T[k]
        Ak = np.broadcast_to(A[k], rel.shape)  # the pass's own arithmetic, for equal bits
        z = np.einsum("ij,ij->i", rel, Ak)
        rho = np.linalg.norm(rel - z[:, None] * Ak, axis=1)
        near = (z > -pad) & (z < c.length + pad) & (rho < c.profile_points(16)[:, 0].max() + pad)
        sd = np.full(P.shape[0], np.inf)
        sd[near] = c.cutting_distance_rz(rho[near], z[near])
        if np.isfinite(sd).any():
            want_d[k], want_seed[k] = sd.min(), int(np.argmin(sd))
        pairs += [(k, i, -sd[i]) for i in np.flatnonzero(sd < 0)]
    assert np.isfinite(want_d).sum() > m // 2 and len(pairs) > 100 and np.all(want_seed[:6] >= P.shape[0] - 6)
    np.testing.assert_array_equal(cut_d, want_d)
    np.testing.assert_array_equal(seed, want_seed)
    got = sorted(zip(pl.tolist(), idx.tolist(), val.tolist()))
    assert got == sorted(pairs)
