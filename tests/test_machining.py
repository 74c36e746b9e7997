"""Machining surfaces (Tournier et al.): closed forms, invariants on unseen points, brute-force drop
cutter, the paper's example, loops, tool paths, bad input."""

import math

import numpy as np
import pytest
from helpers import assert_points_close

from machsurf_cad import examples
from machsurf_cad.errors import DegenerateGeometryError, InputError, ToleranceError
from machsurf_cad.geometry import builders
from machsurf_cad.geometry.face import Face
from machsurf_cad.machining import LoopError, machining_surface, recover_axis
from machsurf_cad.machining.strategies import LeadTilt, LocalFrame, PlanesFeed
from machsurf_cad.toolspec import parse_cutter

TOL = 1e-3


def _unseen(rng, face, n=3000):
    u0, u1, v0, v1 = face.uv_bounds if isinstance(face, Face) else face.bounds
    return rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)


def test_plane_offsets_are_moved_planes(rng):
    plane = builders.plane_patch(du=(100, 0, 0), dv=(0, 80, 0))
    for tool, dz in (("ball:D=10", 5.0), ("bull:D=20,r=4", 4.0), ("flat:D=16", 0.0)):
        ms = machining_surface(plane, tool, axes=5, lead=15, tolerance=TOL)
        u, v = _unseen(rng, plane)
        p = ms.s1.surface.evaluate(u, v)
        assert np.abs(p[:, 2] - dz).max() <= TOL
        assert np.abs(p[:, :2] - plane.evaluate(u, v)[:, :2]).max() <= TOL


def test_sphere_and_cylinder_offsets_are_concentric(rng):
    R, r = 50.0, 5.0
    sph = builders.sphere_patch(R, lat_deg=(-50, 50), lon_deg=90)
    # su x sv points to the centre: as a bowl (tool inside) the offset radius is R - r ...
    ms = machining_surface(sph, f"ball:D={2 * r}", axes=5, strategy="planes:z", lead=10, tolerance=TOL)
    u, v = _unseen(rng, sph)
    assert np.abs(np.linalg.norm(ms.s1.surface.evaluate(u, v), axis=1) - (R - r)).max() <= TOL
    # ... and as a dome (face reversed: outward normal away from the centre) R + r
    ms = machining_surface(
        Face(sph, reversed=True), f"ball:D={2 * r}", axes=5, strategy="planes:z", lead=10, tolerance=TOL
    )
    assert np.abs(np.linalg.norm(ms.s1.surface.evaluate(u, v), axis=1) - (R + r)).max() <= TOL
    cyl = Face(builders.cylinder_patch(30.0, 60.0, angle_deg=120), reversed=True)
    ms = machining_surface(cyl, "bull:D=20,r=4", axes=5, strategy="iso:u", lead=10, tolerance=TOL)
    p = ms.s1.surface.evaluate(*_unseen(rng, cyl))
    assert np.abs(np.hypot(p[:, 0], p[:, 1]) - 34.0).max() <= TOL


@pytest.mark.parametrize("tool", ["ball:D=12", "bull:D=28,r=4", "flat:D=16"])
def test_invariants_on_points_the_fit_never_saw(rng, tool):
    F = examples.bezier5_patch()
    ms = machining_surface(F, tool, axes=5, strategy="planes:x", lead=20, tilt=10, tolerance=TOL)
    c = parse_cutter(tool)
    r = {"ball": c.D / 2, "bull": getattr(c, "r", 0), "flat": 0.0}[c.kind]
    Rt = {"ball": 0.0, "bull": c.D / 2 - r, "flat": c.D / 2}[c.kind]
    u, v = _unseen(rng, F)
    d = F.derivatives(u, v, 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    s1 = ms.s1.surface.evaluate(u, v)
    s2 = ms.s2.surface.evaluate(u, v)
    # S1 at distance r from F along F's normal
    assert np.linalg.norm(s1 - (d.point + r * n), axis=1).max() <= TOL
    # exact axis from the paper's construction, built independently here
    f = np.cross(n, [1.0, 0, 0])
    f /= np.linalg.norm(f, axis=1, keepdims=True)
    lt, tn = math.radians(20), math.radians(10)
    axis = math.cos(lt) * n + math.sin(lt) * (math.cos(tn) * f + math.sin(tn) * np.cross(n, f))
    w = s2 - s1
    if c.kind == "ball":
        assert np.abs(np.linalg.norm(w, axis=1) - c.D).max() <= 2 * TOL  # S2 = S1 + L u, L = D
        assert np.linalg.norm(w / c.D - axis, axis=1).max() <= 2 * TOL / c.D
    else:
        assert np.abs(np.linalg.norm(w, axis=1) - Rt).max() <= 2 * TOL
        assert np.abs(np.einsum("ij,ij->i", w, axis)).max() <= 2 * TOL
        # the axis recovered from the fitted surfaces is within alpha_max of the exact axis
        got = recover_axis(s1, s2, n)
        ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", got, axis), -1, 1)))
        assert ang.max() <= ms.alpha_max_deg_measured + 1e-9
        assert ms.alpha_max_deg_measured <= ms.alpha_max_deg_tolerance


def test_papers_example_is_free_of_loops():
    # degree-5 Bezier patch, filleted end mill R_t = 10, r = 4, planes parallel to yOz, Ot = 20, On = 0
    F = examples.bezier5_patch()
    assert (F.degree_u, F.degree_v) == (5, 5)
    ms = machining_surface(F, "bull:D=28,r=4", axes=5, strategy="planes:x", lead=20, tilt=0, tolerance=TOL)
    assert not ms.loops.found
    assert ms.s1_fit.max_error <= TOL and ms.s2_fit.max_error <= TOL
    assert ms.axis_error_deg <= ms.alpha_max_deg_measured


def test_lead_and_tilt_sign_convention():
    n = np.array([[0.0, 0.0, 1.0]])
    fr = LocalFrame(np.zeros((1, 3)), np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]), n, np.zeros(1), np.zeros(1))
    feed = PlanesFeed((1, 0, 0))
    assert np.allclose(
        feed.feed(fr), [[0, 1, 0]], rtol=0, atol=1e-9
    )  # planes parallel to yOz feed along +y on a face facing +z
    a = LeadTilt(20, 0, feed).axis(fr)[0]
    assert np.allclose(
        a, [0, math.sin(math.radians(20)), math.cos(math.radians(20))], rtol=0, atol=1e-9
    )  # leans towards the feed
    a = LeadTilt(20, 90, feed).axis(fr)[0]
    assert np.allclose(
        a, [-math.sin(math.radians(20)), 0, math.cos(math.radians(20))], rtol=0, atol=1e-9
    )  # turned about n to n x f
    assert np.allclose(LeadTilt(0, 45, feed).axis(fr)[0], [0, 0, 1], rtol=0, atol=1e-9)  # tilt alone does nothing


def _tilted_wave():
    x = np.linspace(0, 80, 9)
    y = np.linspace(0, 60, 7)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = 0.35 * X + 3 * np.sin(np.pi * Y / 60) + 2 * np.cos(np.pi * X / 80)
    return builders.interpolate_grid(np.stack([X, Y, Z], -1), 3, 3, np.linspace(0, 1, 9), np.linspace(0, 1, 7))


def _drop_cutter_tip_z(F, Rt, r, xy, uv_guess):
    """Brute force: lowest tip height of a vertical bull-nose cutter at xy touching F (dense sampling)."""
    R = Rt + r

    def height(p):
        rho = np.hypot(p[..., 0] - xy[0], p[..., 1] - xy[1])
        h = np.where(rho <= Rt, 0.0, r - np.sqrt(np.clip(r * r - (rho - Rt) ** 2, 0, None)))
        return np.where(rho <= R, p[..., 2] - h, -np.inf)

    us = np.linspace(0, 1, 401)
    z = height(F.evaluate_grid(us, us))
    i, j = np.unravel_index(np.argmax(z), z.shape)
    a, b, hw = us[i], us[j], 2 * (us[1] - us[0])
    best = z[i, j]
    for _ in range(4):
        lu = np.clip(np.linspace(a - hw, a + hw, 41), 0, 1)
        lv = np.clip(np.linspace(b - hw, b + hw, 41), 0, 1)
        zz = height(F.evaluate_grid(lu, lv))
        i, j = np.unravel_index(np.argmax(zz), zz.shape)
        a, b, hw, best = lu[i], lv[j], hw / 10, max(best, zz[i, j])
    return best


def test_three_axis_filleted_s1_is_a_drop_cutter_position(rng):
    F = _tilted_wave()
    Rt, r = 6.0, 4.0
    ms = machining_surface(F, "bull:D=20,r=4", axes=3, tolerance=TOL)
    assert not ms.loops.found
    tip = machining_surface(F, "bull:D=20,r=4", axes=3, tolerance=TOL, tip=True)
    for uu, vv in rng.uniform(0.2, 0.8, (12, 2)):
        s1 = ms.s1.surface.evaluate(uu, vv)
        z = _drop_cutter_tip_z(F, Rt, r, s1[:2], (uu, vv))
        assert abs((s1[2] - r) - z) <= TOL + 1e-5
        assert np.linalg.norm(tip.s1.surface.evaluate(uu, vv) - (s1 - [0, 0, r])) <= 2 * TOL


def test_three_axis_filleted_is_singular_at_horizontal_spots():
    with pytest.raises(DegenerateGeometryError, match="parallel to the face normal"):
        machining_surface(examples.bezier5_patch(), "bull:D=20,r=4", axes=3, tolerance=TOL)


def test_trimmed_face_gives_trimmed_s1_s2():
    from conftest import HAS_OCP, ROOT

    if not HAS_OCP:
        pytest.skip("cadquery-ocp is not installed: the trimmed example comes from STEP")
    from machsurf_cad.occ import read_step_faces

    top = read_step_faces(ROOT / "example_parts" / "freeform_block.step")[0]
    ms = machining_surface(top, "ball:D=10", axes=5, lead=10, tolerance=TOL)
    assert len(ms.s1.loops) == len(top.loops) == 2 and ms.s1.loops == top.loops
    assert ms.s1.uv_bounds == top.uv_bounds
    # tool paths stay on the trimmed face: no contact point inside the D = 24 mm hole at (70, 45)
    from machsurf_cad.machining.toolpath import tool_paths

    tp = tool_paths(ms, stepover=4.0, chordal_tolerance=0.01)
    cc = np.concatenate([p.cc for p in tp.cutting_passes()])
    assert np.hypot(cc[:, 0] - 70, cc[:, 1] - 45).min() >= 12.0 - 1e-6
    uv = np.concatenate([p.extras["uv"] for p in tp.cutting_passes()])
    inside = top.contains_uv(uv[:, 0], uv[:, 1])
    # a pass ends on the face's boundary: such a point may fall either side of the loop by a rounding
    on_loop = [min(np.abs(np.linalg.norm(p - q, axis=1)).min() for p in top.trim_polygons()) for q in uv[~inside]]
    assert np.all(np.array(on_loop) < 1e-5)
    # some plane crosses the hole: it is split in two passes on the same level
    levels = [round(p.extras["level"][0], 9) for p in tp.cutting_passes()]
    assert len(levels) > len(set(levels))


def _hourglass_slot():
    """A slot: bottom half circle of radius 15, walls x = +-w(z), w = 15 - 10 sin^2(pi (z - 15) / 44),
    a 10 mm neck at z = 37. Seen from inside, every concave radius is >= 9.8 mm (no local loop for
    r = 6) and the neck is convex, but the offsets of the two walls cross there: a global loop."""
    a = np.radians(np.linspace(180, 360, 60))
    bottom = np.column_stack([15 * np.cos(a), 15 + 15 * np.sin(a)])
    z = np.linspace(15, 59, 80)[1:]
    w = 15 - 10 * np.sin(np.pi * (z - 15) / 44) ** 2
    prof = np.concatenate([np.column_stack([-w[::-1], z[::-1]]), bottom, np.column_stack([w, z])])
    c0 = builders.interpolate_curve(np.column_stack([prof[:, 0], np.zeros(len(prof)), prof[:, 1]]), 3)
    c1 = c0.with_poles(c0.poles + [0.0, 40.0, 0.0])
    return builders.ruled_surface(c0, c1)


def test_global_loop_is_detected_and_reported():
    s = _hourglass_slot()
    d = s.derivatives(0.5, 0.5, 1)
    n = np.cross(d.su, d.sv)
    face = Face(s, reversed=bool(n[2] < 0))  # outward normal up, into the slot, at the bottom
    with pytest.raises(LoopError) as info:
        machining_surface(face, "ball:D=12", axes=5, strategy="iso:v", lead=0, tolerance=0.01)
    kinds = {r.kind for r in info.value.loops.regions}
    assert "global" in kinds and "local" not in kinds
    region = next(r for r in info.value.loops.regions if r.kind == "global")
    assert 28 < region.worst_xyz[2] < 46  # the flagged offset points are at the neck (z = 37)
    flagged = machining_surface(face, "ball:D=12", axes=5, strategy="iso:v", lead=0, tolerance=0.01, loops="flag")
    assert flagged.loops.found and flagged.report()["loops"]["regions"][0]["n_samples"] > 0


def test_offset_larger_than_concave_radius_is_a_local_loop():
    bowl = builders.sphere_patch(20.0, lat_deg=(-40, 40), lon_deg=80)  # normal to the centre: concave, R = 20
    with pytest.raises(LoopError, match="local loop"):
        machining_surface(bowl, "ball:D=50", axes=5, strategy="planes:z", lead=5, tolerance=TOL)


def test_bad_inputs():
    F = examples.bezier5_patch()
    with pytest.raises(InputError, match="lead angle"):
        machining_surface(F, "bull:D=20,r=4", axes=5, lead=95, tolerance=TOL)
    with pytest.raises(DegenerateGeometryError, match="parallel to the face normal"):
        machining_surface(F, "bull:D=20,r=4", axes=5, lead=0, tolerance=TOL)  # axis along n: S2 undefined
    with pytest.raises(ToleranceError, match="reached"):
        machining_surface(F, "bull:D=20,r=4", axes=5, lead=20, tolerance=1e-9, max_poles=200)
    from test_geometry import cone_with_tip

    from machsurf_cad.geometry.face import Face

    with pytest.raises(DegenerateGeometryError, match="no limit normal"):  # a cone's tip
        machining_surface(Face(cone_with_tip(), reversed=True), "ball:D=10", axes=5, lead=10, tolerance=TOL)
    with pytest.raises(InputError, match="Table 1"):
        machining_surface(F, "cone:D=10,angle=5", axes=5, lead=10)
    with pytest.raises(DegenerateGeometryError, match="tangent to the surface"):
        recover_axis(np.zeros((1, 3)), np.array([[0, 0, 5.0]]), np.array([[0, 0, 1.0]]))


def test_tool_paths_on_planes_and_cl_files(tmp_path):
    from machsurf_cad.cam import Move, read_apt, write_apt, write_csv
    from machsurf_cad.machining.toolpath import tool_paths

    F = examples.bezier5_patch()
    ms = machining_surface(F, "bull:D=28,r=4", axes=5, strategy="planes:x", lead=20, tolerance=TOL)
    tp = tool_paths(ms, stepover=5.0, chordal_tolerance=0.01)
    levels = sorted({round(p.extras["level"][0], 9) for p in tp.cutting_passes()})
    assert np.allclose(np.diff(levels), 5.0, rtol=0, atol=1e-9)
    for p in tp.cutting_passes():
        assert np.abs(p.extras["K"][:, 0] - p.extras["level"][0]).max() < 1e-8  # C1 lies in its plane x = level
        assert np.allclose(np.linalg.norm(p.axis, axis=1), 1.0, rtol=0, atol=1e-9)
        # tip = CL - r u and CL = K + R_t v: |CL - K| = R_t, (CL - K) . u = 0
        w = p.extras["CL"] - p.extras["K"]
        assert np.abs(np.linalg.norm(w, axis=1) - 10.0).max() < 3 * TOL
        assert np.allclose(p.tip, p.extras["CL"] - 4.0 * p.axis, rtol=0, atol=1e-9)
    assert tp.info["chordal_error_measured_mm"] <= 0.01
    assert tp.info["axis_error_deg_measured"] <= ms.alpha_max_deg_measured
    rows = write_csv(tmp_path / "p.csv", tp).read_text().splitlines()
    assert len(rows) == tp.n_positions + 1 and rows[0].startswith("pass,index,move,tip_x,tip_y,tip_z,i,j,k")
    assert rows[0].split(",")[13] == "tool" and rows[1].count('"bull:D=28,r=4"') == 1  # the cutter on every row
    apt = write_apt(tmp_path / "p.apt", tp).read_text().splitlines()
    assert apt[3] == "CUTTER/28.0000,4.0000,10.0000,4.0000,0.0000,0.0000,84.0000"
    assert apt[4:7] == ["LOADTL/1", "SPINDL/RPM,10000.0000,CLW", "MULTAX/ON"] and apt[-1] == "FINI"
    gotos = [ln for ln in apt if ln.startswith("GOTO/")]
    assert len(gotos) == tp.n_positions == tp.n_cut + 2 * tp.n_passes
    first = [float(x) for x in gotos[1][5:].split(",")]
    p0 = tp.cutting_passes()[0]
    assert_points_close(first[:3], p0.tip[0], atol=1e-5)
    assert_points_close(first[3:], p0.axis[0], atol=1e-9)
    back = read_apt(tmp_path / "p.apt")  # round trip: same positions, axes, moves and passes
    assert_points_close(back.tip, tp.tip, atol=1e-5)
    assert_points_close(back.axis, tp.axis, atol=2e-9)
    assert (back.move == tp.move).all() and (back.pass_index == tp.pass_index).all()
    assert back.cutter == ms.cutter.__class__(28.0, 4.0, 84.0)
    # approach and retract along the axis from the shank side, 5 mm
    app = np.nonzero(tp.move == Move.APPROACH)[0]
    assert_points_close(tp.tip[app - 1] - tp.tip[app], 5.0 * tp.axis[app], atol=1e-12)


def test_iso_paths_three_axis(tmp_path):
    from machsurf_cad.machining.toolpath import tool_paths

    ms = machining_surface(_tilted_wave(), "ball:D=10", axes=3, strategy="iso:u", tolerance=TOL)
    tp = tool_paths(ms, stepover=4.0, chordal_tolerance=0.005)
    assert len(tp.cutting_passes()) >= 10
    for p in tp.cutting_passes():
        assert np.allclose(
            p.extras["uv"][:, 1], p.extras["level"][0], rtol=0, atol=1e-9
        )  # v constant along an iso-u pass
        assert np.allclose(p.axis, [0, 0, 1], rtol=0, atol=1e-9)
        assert np.allclose(p.tip, p.extras["K"] - [0, 0, 5.0], rtol=0, atol=1e-9)


def _dimpled_plate():
    x = np.linspace(0, 100, 41)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = -6.0 * np.exp(-((X - 50) ** 2 + (Y - 50) ** 2) / 100.0)  # bottom radius w^2 / (2 depth) = 8.3 mm
    return builders.interpolate_grid(np.stack([X, Y, Z], -1), 3, 3, np.linspace(0, 1, 41), np.linspace(0, 1, 41))


def test_loops_can_be_trimmed_away(tmp_path):
    plate = _dimpled_plate()
    with pytest.raises(LoopError, match="local loop"):
        machining_surface(plate, "ball:D=20", axes=5, strategy="planes:x", lead=5, tolerance=0.01)
    ms = machining_surface(plate, "ball:D=20", axes=5, strategy="planes:x", lead=5, tolerance=0.01, loops="trim")
    assert ms.loops.found and ms.report()["trimmed_holes"] == 1
    assert len(ms.s1.loops) == 2 and ms.s1.loops == ms.s2.loops  # the box plus one hole, same on S1 and S2
    for region in ms.loops.regions:  # every flagged sample is cut away, the far corners stay
        assert not ms.s1.contains_uv(region.uv[:, 0], region.uv[:, 1]).any()
    assert ms.s1.contains_uv(np.array([0.05, 0.95]), np.array([0.05, 0.95])).all()
    from conftest import HAS_OCP

    if HAS_OCP:  # the trimmed faces are valid B-rep faces and survive a STEP round trip
        from machsurf_cad.occ import read_step_faces, write_step

        back = read_step_faces(write_step(tmp_path / "trim.step", ms.faces()))
        assert [len(f.loops) for f in back] == [2, 2]


def test_tool_paths_avoid_trimmed_loops():
    from machsurf_cad.machining.surfaces import fit_deviation
    from machsurf_cad.machining.toolpath import tool_paths

    ms = machining_surface(
        _dimpled_plate(), "ball:D=20", axes=5, strategy="planes:x", lead=5, tolerance=0.01, loops="trim"
    )
    tp = tool_paths(ms, stepover=5.0, chordal_tolerance=0.01)
    uv = np.concatenate([p.extras["uv"] for p in tp.cutting_passes()])
    assert ms.s1.contains_uv(uv[:, 0], uv[:, 1]).all()
    dev = fit_deviation(ms, "S1", samples=60)
    assert ms.s1.contains_uv(dev.foot_uv[:, 0], dev.foot_uv[:, 1]).all() and dev.max_abs <= 0.01
