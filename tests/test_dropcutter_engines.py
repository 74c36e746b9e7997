"""The drop-cutter's two engines: the compiled kernel (numba) against the numpy reference, point for point,
on the example parts with every contact kind (face, rim, edge, pointed tip, a cone's bottom circle); the
kernel's answers independent of the batch; the cache stamp that keeps numba from running a stale kernel."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad.threeaxis import compiled
from machsurf_cad.threeaxis.dropcutter import Contact

ROOT = Path(__file__).resolve().parent.parent
needs_numba = pytest.mark.skipif(not compiled.available(), reason="numba is not installed")


def test_the_kernels_cache_stamp_matches_its_callees():
    """numba re-compiles a cached kernel only when the entry point's own file changes: the entry point's
    file carries the hash of the callees' sources, so editing them without it fails here."""
    text = (ROOT / "machsurf_cad" / "threeaxis" / "_jit_drop.py").read_text()
    stamp = re.search(r'KERNEL_SOURCES = "([0-9a-f]+)"', text).group(1)
    assert stamp == compiled.kernel_stamp(), "update KERNEL_SOURCES in _jit_drop.py to compiled.kernel_stamp()"


def _grid(fs, n, margin=3.0):
    lo, hi = fs.sample_xyz.min(0)[:2] - margin, fs.sample_xyz.max(0)[:2] + margin
    x, y = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    return np.column_stack([x.ravel(), y.ravel()])


@pytest.fixture(scope="module")
def parts():
    pytest.importorskip("OCP")
    from machsurf_cad.occ import read_step_faces

    return {name: read_step_faces(ROOT / "example_parts" / name) for name in
            ("mould_insert.step", "freeform_block.step", "bezier5_patch.step")}  # fmt: skip


CASES = [
    ("mould_insert.step", "bull:D=10,r=2"),
    ("mould_insert.step@-100", "bull:D=6,r=1"),  # below z = 0, queries whose only contacts are edges
    ("mould_insert.step", "flat:D=10"),
    ("mould_insert.step", "cone:D=6,angle=10,L=20"),  # a pointed tip and the bottom circle of the cone
    ("freeform_block.step", "ball:D=10"),  # trimmed faces: a hole and long degree-8 trimming curves
    ("freeform_block.step", "flat:D=10"),  # rim contacts on the curved top: the rim certificate
    ("bezier5_patch.step", "bull:D=16,r=3"),
]


def _moved(face, dz):
    from dataclasses import replace

    s = face.surface
    return replace(face, surface=s.with_poles(np.asarray(s.poles) + [0.0, 0.0, dz], s.weights))


@needs_numba
@pytest.mark.parametrize("part,tool", CASES)
def test_compiled_and_numpy_engines_give_the_same_heights(parts, part, tool):
    name, _, dz = part.partition("@")
    faces = parts[name]
    if dz:
        faces = [_moved(f, float(dz)) for f in faces]
    cutter = ms.parse_cutter(tool)
    fs = ms.threeaxis.faceset.face_set(faces, spacing=ms.threeaxis.dropcutter.default_seed_spacing(cutter))
    xy = _grid(fs, 19)
    a = ms.drop_cutter(None, cutter, xy, face_set=fs, engine="compiled")
    b = ms.drop_cutter(None, cutter, xy, face_set=fs, engine="numpy")
    assert a.engine == "compiled" and b.engine == "numpy"
    np.testing.assert_array_equal(np.isnan(a.height), np.isnan(b.height))
    ok = np.isfinite(a.height)
    assert ok.sum() > 100
    assert np.abs(a.height[ok] - b.height[ok]).max() <= 1e-9
    # the contact points lie on the tool at the height found (z - h(rho) = height), whichever engine
    R = float(cutter.profile_points(16)[:, 0].max())
    for r in (a, b):
        p = fs.to_frame(r.contact[ok])
        rho = np.hypot(p[:, 0] - xy[ok, 0], p[:, 1] - xy[ok, 1])
        assert rho.max() <= R * (1 + 1e-9)
        h = np.where(rho >= R * (1 - 1e-12), cutter.height(np.array([R]))[0], cutter.height(np.minimum(rho, R)))
        assert np.abs(p[:, 2] - np.nan_to_num(h, nan=0.0) - r.height[ok]).max() <= 1e-7
    kinds = set(np.unique(a.kind[ok]).tolist())
    if part == "freeform_block.step" and tool.startswith("flat"):  # a flat end on a sloped top: its rim
        assert Contact.RIM in kinds
    else:
        assert Contact.FACE in kinds or Contact.TIP in kinds


@needs_numba
def test_compiled_heights_do_not_depend_on_the_batch(parts):
    """Each query is solved on its own: random subsets give bit-identical heights, contacts and faces."""
    faces = parts["mould_insert.step"]
    cutter = ms.parse_cutter("bull:D=10,r=2")
    fs = ms.threeaxis.faceset.face_set(faces, spacing=ms.threeaxis.dropcutter.default_seed_spacing(cutter))
    xy = _grid(fs, 23)
    full = ms.drop_cutter(None, cutter, xy, face_set=fs, engine="compiled")
    rng = np.random.default_rng(7)
    for size in (1, 17, 230):
        pick = rng.choice(xy.shape[0], size, replace=False)
        part = ms.drop_cutter(None, cutter, xy[pick], face_set=fs, engine="compiled", batch_size=7)
        np.testing.assert_array_equal(part.height, full.height[pick])
        np.testing.assert_array_equal(part.face, full.face[pick])
        np.testing.assert_array_equal(part.kind, full.kind[pick])


def test_numpy_engine_on_request_and_bad_engine_refused():
    plane = ms.builders.plane_patch((-20, -20, 0), (40, 0, 0), (0, 40, 0))
    r = ms.drop_cutter([plane], ms.BallEndMill(10), [[0.0, 0.0], [3.0, 4.0]], engine="numpy")
    assert r.engine == "numpy" and np.allclose(r.height, 0.0, atol=1e-12)
    assert r.report()["engine"] == "numpy"
    with pytest.raises(ms.InputError, match="engine"):
        ms.drop_cutter([plane], ms.BallEndMill(10), [[0.0, 0.0]], engine="fast")


@needs_numba
def test_compiled_engine_on_a_closed_form_dome():
    """A sphere of radius 30 under a ball of radius 5: the tip is at sqrt(35^2 - d^2) - 35 + 30 above the
    plane through the centre... (exact: the ball's centre lies on the sphere of radius 35)."""
    sphere = ms.builders.sphere_patch(30.0, (0.0, 90.0), 360.0)
    d = np.linspace(0.0, 30.0, 31)
    xy = np.column_stack([d * np.cos(0.3), d * np.sin(0.3)])
    r = ms.drop_cutter([sphere], ms.BallEndMill(10), xy, engine="compiled")
    assert r.engine == "compiled"
    exact = np.sqrt(35.0**2 - d**2) - 5.0
    # beyond the dome's rim (d > 30 * cos(0)) the ball rests on the rim circle; inside it the closed form holds
    inner = d <= 30.0 * 30.0 / 35.0
    assert np.abs(r.height[inner] - exact[inner]).max() <= 1e-9


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_wall_exactly_R_from_the_axis_touches_the_side_and_does_not_lift_the_tool(engine):
    """Floor z = 0 and a wall x = 10 up to z = 8, ball D10: with the axis exactly R = 5 from the wall the
    tool touches the wall with its side and rests on the floor (height 0, the lowest height at which it
    does not enter the part); 1 um closer the wall enters the disc and the ball rests on the wall's top
    edge: 8 - h(4.999) = 3 + sqrt(25 - 4.999^2). Grid lines R from a wall used to lift the tool by up to
    the wall's height."""
    floor = ms.builders.plane_patch((-20, -20, 0), (30, 0, 0), (0, 40, 0))
    wall = ms.builders.plane_patch((10, -20, 0), (0, 40, 0), (0, 0, 8))
    xy = np.array([[5.0, 0.0], [5.0, 7.3], [5.001, 0.0], [4.0, 1.0]])
    r = ms.drop_cutter([floor, wall], ms.BallEndMill(10), xy, engine=engine)
    assert r.engine == engine
    expected = [0.0, 0.0, 3.0 + np.sqrt(25.0 - 4.999**2), 0.0]
    assert np.abs(r.height - expected).max() <= 1e-9


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
@pytest.mark.parametrize("tool,rc", [("ball:D=10", 5.0), ("bull:D=10,r=2", 2.0), ("flat:D=10", 0.0)])
def test_stacked_faces_give_the_highest_one_across_the_upper_faces_edge(engine, tool, rc):
    """A shelf z = 10 over 0 <= x <= 20 above a floor z = 9 that runs under it (a propeller's blades, one
    above the other): the compiled kernel drops every sample that cannot reach the height a sample of the
    shelf already lifts the tool to, ``10 - h(R)``; the floor stays, and wins where the shelf's edge has
    gone up the profile by more than 1. Across the shelf's edge x = 20 the height is the closed form: on
    the shelf 10, then the higher of its edge at plan distance d, 10 - h(d) (``rc`` the corner radius of
    the D10 cutter), and the floor 9; the floor once d > R."""
    floor = ms.builders.plane_patch((-20, -20, 9), (60, 0, 0), (0, 40, 0))
    shelf = ms.builders.plane_patch((0, -20, 10), (20, 0, 0), (0, 40, 0))
    x = np.r_[np.linspace(10.0, 30.0, 81), 24.99, 25.01]
    r = ms.drop_cutter([floor, shelf], ms.parse_cutter(tool), np.column_stack([x, np.zeros_like(x)]), engine=engine)
    d, flat = x - 20.0, 5.0 - rc
    h = np.where(d <= flat, 0.0, rc - np.sqrt(np.maximum(rc**2 - (d - flat) ** 2, 0.0)))
    expected = np.where(d <= 0, 10.0, np.where(d < 5.0, np.maximum(10.0 - h, 9.0), 9.0))
    assert rc == 0 or np.sum(10.0 - h[(d > 0) & (d < 5)] < 9.0) >= 2  # there the floor is the answer
    assert r.engine == engine
    assert np.abs(r.height - expected).max() <= 1e-9


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_tip_below_the_reference_point_keeps_the_samples_that_can_win(engine):
    """An APT cutter whose tip is 0.56 mm below its reference point (corner centred at (3, 2), a 10 degree
    bottom: the profile's lowest point h_min < 0): over a floor z = 0 the tip stands at -h_min; a shelf
    z = 1.5 whose edge is 4.96 from the axis would put it at 1.5 - h(4.96), lower, and the floor's samples,
    which reach the shelf's height only through -h_min, must stay (they went, the tool 0.66 mm too low,
    when the kernel's sample pruning took h_min with the wrong sign). On a floor alone with a tip 2 mm
    below: 2 everywhere, not NaN."""
    from machsurf_cad.threeaxis.solves import _Profile

    tool = ms.parse_cutter("apt:D=10,r=2,e=3,f=2,alpha=10,beta=0,h=20")
    prof = _Profile(tool)
    assert prof.h_min < -0.5 and prof.monotone
    floor = ms.builders.plane_patch((-20, -20, 0), (40, 0, 0), (0, 40, 0))
    shelf = ms.builders.plane_patch((4.96, -20, 1.5), (20, 0, 0), (0, 40, 0))
    r = ms.drop_cutter([floor, shelf], tool, [[0.0, 0.0]], engine=engine)
    shelf_alone = 1.5 - (2.0 - np.sqrt(4.0 - (4.96 - 3.0) ** 2))
    assert r.engine == engine and shelf_alone < -prof.h_min
    assert abs(r.height[0] + prof.h_min) <= 1e-9
    low = ms.parse_cutter("apt:D=10,r=2,e=3,f=0,alpha=0,beta=0,h=20")
    assert np.abs(ms.drop_cutter([floor], low, [[0.0, 0.0], [3.0, 1.0]], engine=engine).height - 2.0).max() <= 1e-9


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_face_trimmed_beyond_its_knot_domain_is_not_capped_at_its_poles(engine):
    """z = -5 (u - 2)^2 on the knot domain u in [0, 1] (poles' top z = -5), trimmed out to u = 2.9, where the
    evaluated surface peaks at z = 0 (x = 20): its samples' bounds may not stop at the poles' top (they did,
    and a flat D10 over the peak stood on a plane at -0.01 instead)."""
    from machsurf_cad.geometry.bspline import BSplineSurface
    from machsurf_cad.geometry.builders import line_segment
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.threeaxis.faceset import hull_top

    P = np.array([[[5.0 * i, 40.0 * j, z] for j in (0, 1)] for i, z in enumerate((-20.0, -10.0, -5.0))])
    s = BSplineSurface(2, 1, [0, 1], [3, 3], [0, 1], [2, 2], P)
    c = [(0, 0), (2.9, 0), (2.9, 1), (0, 1)]
    ridge = Face(s, (tuple(line_segment(c[i], c[(i + 1) % 4]) for i in range(4)),), "ridge", uv_bounds=(0, 2.9, 0, 1))
    assert hull_top(ridge) == np.inf
    plane = ms.builders.plane_patch((15, 15, -0.01), (10, 0, 0), (0, 10, 0))
    r = ms.drop_cutter([ridge, plane], ms.parse_cutter("flat:D=10"), [[20.0, 20.0], [19.5, 20.0]], engine=engine)
    assert np.abs(r.height).max() <= 1e-9


def test_face_sets_and_heights_are_cached_by_content_and_tool():
    """A repeated query reuses the face set and the heights (the very same numbers); a face changed by 1 um,
    another tool or another engine never reuses them."""
    from machsurf_cad.threeaxis import cache

    cache.clear()
    dome = ms.builders.sphere_patch(30.0, (0.0, 90.0), 360.0)
    xy = np.array([[0.0, 0.0], [7.0, 3.0], [12.0, -5.0]])
    a = ms.drop_cutter([dome], ms.BallEndMill(10), xy)
    b = ms.drop_cutter([dome], ms.BallEndMill(10), xy[::-1])
    assert a.n_cached == 0 and b.n_cached == 3 and b.report()["n_cached"] == 3
    np.testing.assert_array_equal(b.height, a.height[::-1])
    moved = dome.with_poles(np.asarray(dome.poles) + [0.0, 0.0, 1e-3], dome.weights)
    c = ms.drop_cutter([moved], ms.BallEndMill(10), xy)
    assert c.n_cached == 0 and np.allclose(c.height, a.height + 1e-3, atol=1e-9)
    assert ms.drop_cutter([dome], ms.BallEndMill(10.0000001), xy).n_cached == 0  # another tool, however close
    d = ms.drop_cutter([dome], ms.BullNoseEndMill(10, 2), xy)
    e = ms.drop_cutter([dome], ms.BallEndMill(10), xy, engine="numpy")
    assert d.n_cached == 0 and e.n_cached == 0
    assert np.abs(e.height - a.height).max() <= 1e-9
    assert cache.faces_key([dome]) == cache.faces_key([dome.with_poles(dome.poles, dome.weights)])
    assert cache.faces_key([dome]) != cache.faces_key([moved])


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_an_edge_grazing_the_disc_between_its_samples_lifts_the_tool(engine):
    """A thin fin (a vertical wall 10 um inside the tool's circle at its nearest, the edge's samples either
    side of that point, all outside the disc) with its top edge at z = 20 over a floor at z = 0: the ball
    D10 rests on the fin's top edge at 20 - h(4.99999), not on the floor at 0 (on the impeller of the shared
    real parts such a blade-tip edge was missed: the tool 26 mm too low)."""
    from machsurf_cad.geometry.builders import line_segment
    from machsurf_cad.geometry.face import Face

    floor = ms.builders.plane_patch((-20, -20, 0), (40, 0, 0), (0, 40, 0))
    # the fin's surface runs up to z = 40, trimmed at z = 20: ascents on the surface climb out of the trim,
    # only the trimming edge holds the answer
    plane = ms.builders.plane_patch((-20.8, 4.99999, 0), (40, 0, 0), (0, 0, 40))
    c = [(0, 0), (1, 0), (1, 0.5), (0, 0.5)]
    loop = tuple(line_segment(c[i], c[(i + 1) % 4]) for i in range(4))
    fin = Face(plane, (loop,), "fin", uv_bounds=(0.0, 1.0, 0.0, 0.5))
    r = ms.drop_cutter([floor, fin], ms.BallEndMill(10), [[0.0, 0.0]], engine=engine)
    expected = 20.0 - (5.0 - np.sqrt(25.0 - 4.99999**2))
    assert abs(r.height[0] - expected) <= 1e-9


@pytest.mark.parametrize("name", ["mould_insert.step", pytest.param("freeform_block.step", marks=pytest.mark.slow)])
def test_fine_cells_cover_every_face_point(parts, name):
    """The compiled kernel skips a neighbourhood when its cells' bounds cannot beat a contact found. That is
    exact only if every face point lies within a fine sample's cover, that fine sample's cell (its owner)
    within ``radius`` of it, and the cell inside its seed sample's cover: checked on random points of every
    face (inside its trim) against a brute-force nearest search written here. A vertical face has no cells
    (its edges hold its contacts: ``tests/test_dropcutter_vertical.py``)."""
    from machsurf_cad.threeaxis.cells import fine_cells

    fs = ms.threeaxis.faceset.face_set(parts[name], spacing=5 / 3)
    c = fine_cells(fs)
    assert c.factor == 4 and c.contained
    pool = fs.pool_xyz
    owner = np.repeat(np.arange(pool.shape[0]), np.diff(c.start))
    fine_face = fs.pool_face[owner]
    assert not np.any(fs.face_vertical[fine_face])
    assert np.all(np.linalg.norm(c.xyz - pool[owner], axis=1) + c.cover <= c.radius[owner] * (1 + 1e-12))
    bounding = ~fs.face_vertical[fs.pool_face]
    assert np.all(c.radius[bounding] <= fs.cover[bounding] * (1 + 1e-9))
    rng = np.random.default_rng(3)
    checked = 0
    for i, face in enumerate(fs.faces):
        if fs.face_vertical[i]:
            continue
        u0, u1, v0, v1 = face.uv_bounds
        u, v = rng.uniform(u0, u1, 400), rng.uniform(v0, v1, 400)
        keep = face.contains_uv(u, v)
        p = face.surface.evaluate(u[keep], v[keep])
        mine = np.nonzero(fine_face == i)[0]
        d = np.linalg.norm(p[:, None, :] - c.xyz[mine][None, :, :], axis=2)
        near = mine[np.argmin(d, axis=1)]
        assert np.all(d.min(axis=1) <= c.cover[near])
        assert np.all(np.linalg.norm(p - pool[owner[near]], axis=1) <= c.radius[owner[near]])
        checked += p.shape[0]
    assert checked > 150 * int((~fs.face_vertical).sum())  # a third of the points at least inside the trims


def test_the_samples_bounds_hold_on_every_face_point_and_stop_at_the_faces_top(parts):
    """Both engines skip a neighbourhood whose ``z + rise`` (face samples, edge samples, fine samples) cannot
    beat a contact found. ``rise`` is cut to the face's highest pole (no face point is higher): checked on
    random points of every mould face (inside its trim) against every sample whose cover holds them, and the
    cut is exact at the tops of the slopes (its bound is the slope's height, not a sample spacing above it).
    Vertical faces (walls) are bounded by their edges alone (``tests/test_dropcutter_vertical.py``)."""
    from machsurf_cad.threeaxis.cells import fine_cells
    from machsurf_cad.threeaxis.faceset import hull_top

    fs = ms.threeaxis.faceset.face_set(parts["mould_insert.step"], spacing=5 / 3)
    c = fine_cells(fs)
    pool, pool_face = fs.pool_xyz, fs.pool_face
    owner = np.repeat(np.arange(pool.shape[0]), np.diff(c.start))
    rng = np.random.default_rng(5)
    checked = at_top = 0
    for i, face in enumerate(fs.faces):
        if fs.face_vertical[i]:
            continue
        u0, u1, v0, v1 = face.uv_bounds
        u, v = rng.uniform(u0, u1, 300), rng.uniform(v0, v1, 300)
        keep = face.contains_uv(u, v)
        p = face.surface.evaluate(u[keep], v[keep])
        top = hull_top(face)
        assert np.isfinite(top)
        assert np.all(p[:, 2] <= top + 1e-12)
        for xyz, rise, cov in ((pool[pool_face == i], fs.rise[pool_face == i], fs.cover[pool_face == i]),
                               (c.xyz[pool_face[owner] == i], c.rise[pool_face[owner] == i],
                                c.cover[pool_face[owner] == i])):  # fmt: skip
            d = np.linalg.norm(p[:, None, :] - xyz[None, :, :], axis=2)
            inside = d <= cov[None, :]
            assert inside.any(axis=1).all()
            bound = np.where(inside, xyz[None, :, 2] + rise[None, :], np.inf)
            assert np.all(p[:, 2, None] <= bound + 1e-12)
            assert np.all(xyz[:, 2] + rise <= max(top, xyz[:, 2].max()) + 1e-12)
        checked += p.shape[0]
        if p.shape[0] and np.ptp(p[:, 2]) > 1.0:  # a wall or a slope: its top samples' bounds stop at its top
            hi = fs.sample_xyz[fs.sample_face == i, 2] >= top - 1e-9
            at_top += int(hi.sum())
            assert np.all(fs.rise[: fs.sample_xyz.shape[0]][fs.sample_face == i][hi] <= 1e-9)
    assert checked > 4000 and at_top > 50


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_closed_edge_is_searched_across_its_seam(engine):
    """A disc of radius 5 trimmed by one circle (its seam at angle 0) from a plane rising towards -10 deg: a
    flat end mill D12 centred over it rests on the circle's highest point, z = 5 tan(5 deg) at -10 deg, just
    before the seam. Searched from the seam's first sample, a window stopped at the seam saw only the lower
    side (FreeCAD's stock bull nose gouged the block by 0.027 mm that way); it runs across the seam."""
    from machsurf_cad.geometry.builders import circular_arc
    from machsurf_cad.threeaxis import solves
    from machsurf_cad.threeaxis.faceset import face_set

    slope = np.tan(np.radians(5.0))
    d = np.array([np.cos(np.radians(-10.0)), np.sin(np.radians(-10.0))])
    poles = [[[x, y, slope * (np.array([x, y]) @ d)] for y in (-20.0, 20.0)] for x in (-20.0, 20.0)]
    plane = ms.builders.bezier_surface(np.array(poles))
    disc = ms.Face(plane, ((circular_arc(5.0 / 40.0, 0.0, 360.0, center=(0.5, 0.5)),),), name="disc")
    fs = face_set([disc], spacing=2.0)
    e = int(np.nonzero(fs.edge_loop)[0][0])
    k = int(np.nonzero(fs.edge_id == e)[0][0])  # the loop's first sample: at its seam
    tool = ms.FlatEndMill(12.0)
    c = np.zeros((1, 2))
    expect = 5.0 * slope
    if engine == "numpy":
        prof = solves._Profile(tool)
        g, _ = solves._edge_search(fs, prof, c, np.array([e]), fs.edge_t[k : k + 1], fs.edge_dt[k : k + 1])
        assert g[0] == pytest.approx(expect, abs=1e-9)
    assert ms.drop_cutter([disc], tool, c, engine=engine).height[0] == pytest.approx(expect, abs=1e-9)


@pytest.mark.parametrize(  # the numpy engine in the slow tier: the fast one compares the engines point for point
    "engine", [pytest.param("numpy", marks=pytest.mark.slow), pytest.param("compiled", marks=needs_numba)]
)
def test_ball_heights_equal_an_independent_reference_to_1e6_mm_near_the_trims_too(parts, engine):
    """The ball D10 on the block (a hole, long degree-8 trimming curves): 300 random points and 200 points
    within 1 mm in plan of a trimming edge against ``tests/ball_reference.py`` (dense samples climbed to
    their maxima on the exact faces by Newton, and on the exact edges by golden section): equal within
    1e-6 mm. The 200 x 200 grids of every part are in ``benchmarks/bruteforce_grid.py``."""
    from ball_reference import BallReference

    faces = parts["freeform_block.step"]
    ref = BallReference(faces, spacing=0.3)  # coarser than the benchmark's 0.15: the climb makes it exact
    rng = np.random.default_rng(27)
    lo, hi = ref.P[:, :2].min(axis=0), ref.P[:, :2].max(axis=0)
    edge = ref.E[rng.choice(ref.E.shape[0], 200, replace=False), :2]
    xy = np.vstack([rng.uniform(lo, hi, (300, 2)), edge + rng.uniform(-1, 1, (200, 2)) / np.sqrt(2)])
    bf = ref.heights(xy, 5.0)
    dc = ms.drop_cutter(faces, ms.BallEndMill(10), xy, engine=engine).height
    np.testing.assert_array_equal(np.isnan(bf), np.isnan(dc))
    ok = np.isfinite(bf)
    assert ok.sum() > 400
    assert np.abs(dc[ok] - bf[ok]).max() <= 1e-6


PROFILE_SPECS = ["ball:D=10", "flat:D=16", "bull:D=20,r=4", "cone:D=10,angle=6", "cone:D=10,angle=-8",
                 "drum:D=20,Rp=40,L=20", "barrel:D=20,Rp=40,L=20",
                 "apt:D=20,r=4,e=6,f=4,alpha=10,beta=5,h=60"]  # fmt: skip


@needs_numba
@pytest.mark.parametrize("spec", PROFILE_SPECS)
def test_the_kernels_profile_pieces_give_lower_heights_numbers_to_the_bit(spec):
    """The kernel evaluates the cutter's lower surface from pieces of [0, R] (one segment lowest on each):
    on 20,001 radii, the piece ends and points 1e-9 mm beside them (where the kernel falls back to the search
    over the segments), h, h' and h'' are the search's own numbers, bit for bit."""
    from machsurf_cad.threeaxis._jit_geom import lower_height, prof
    from machsurf_cad.threeaxis.dropcutter import _Profile

    p = _Profile(ms.parse_cutter(spec))
    PR = compiled._profile(p)
    tb = PR[2]
    assert tb.shape[0] >= 1 and tb[0, 0] < 1e-9 and tb[-1, 1] == pytest.approx(p.R)  # pieces cover [0, R]
    ends = np.r_[tb[:, 0], tb[-1, 1]]
    rho = np.r_[np.linspace(0.0, p.R, 20001), ends, ends - 1e-9, ends + 1e-9, ends + 3e-9, ends - 3e-9]
    rho = np.r_[rho, np.nextafter(ends + 1e-9, np.inf), np.nextafter(ends - 1e-9, -np.inf)]
    for r in rho[(rho >= 0) & (rho <= p.R)]:
        assert prof(PR, r) == lower_height(PR[0], min(r, PR[1][0])), (spec, r)


@needs_numba
def test_a_long_drums_profile_gets_no_pieces_and_the_kernel_searches():
    """A drum of 270 mm arcs (D 200, L 229): ``lower_height`` runs an arc 1e-9 degrees past its ends, 4.7 nm
    here, more than the pieces' 1 nm margin, so the pieces would differ there (by 4.3e-9 mm): it gets none,
    and the kernel's heights are the search's own numbers on either side of the arcs' ends."""
    from machsurf_cad.threeaxis._jit_geom import lower_height, prof
    from machsurf_cad.threeaxis.dropcutter import _Profile

    p = _Profile(ms.parse_cutter("drum:D=200,Rp=270.49,L=228.721"))
    PR = compiled._profile(p)
    assert PR[2].shape == (0, 7)
    ends = np.unique(np.clip([s.points(2)[:, 0] for s in p.segs], 0.0, p.R))
    rho = np.r_[np.linspace(0.0, p.R, 2001), ends + 2e-9, ends - 2e-9]
    for r in rho[(rho >= 0) & (rho <= p.R)]:
        assert prof(PR, r) == lower_height(PR[0], min(r, PR[1][0])), r


@needs_numba
def test_crossing_profile_segments_get_no_pieces():
    """Two segments crossing inside a piece (the lowest one changes there): no pieces, the search runs."""
    segs = np.array([[0.0, 0.0, 0.0, 5.0, 1.0, 0.0], [0.0, 0.0, 1.0, 5.0, 0.0, 0.0]])  # they cross at rho = 2.5
    assert compiled._pieces(segs, 5.0).shape == (0, 7)


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_ball_on_a_c0_crease_rests_on_the_crease(engine):
    """A roof as one B-spline face only C0 along its ridge (degree 1 across it, a single knot there): the ridge
    ``z = 10 + 0.2 x`` at y = 0, the sides falling 0.5 per mm. Over points near the ridge the ball rests on it:
    tip = 10 + 0.2 cx + sqrt(1.04 (R^2 - cy^2)) - R (the highest point of the ridge in the disc), which no
    stationary point of either side gives; checked against a brute force over 0.005 mm samples too."""
    poles = np.array([[[x, y, 10 + 0.2 * x - 0.5 * abs(y)] for y in (-20.0, 0.0, 20.0)] for x in (-20.0, 20.0)])
    roof = ms.BSplineSurface(1, 1, [0, 1], [2, 2], [0, 0.5, 1], [2, 1, 2], poles)
    R = 5.0
    xy = np.array([[cx, cy] for cx in (-3.0, 0.0, 2.5) for cy in (0.0, 0.3, -0.7, 1.1)])
    r = ms.drop_cutter([roof], ms.BallEndMill(2 * R), xy, engine=engine)
    closed = 10 + 0.2 * xy[:, 0] + np.sqrt(1.04 * (R**2 - xy[:, 1] ** 2)) - R
    assert np.abs(r.height - closed).max() < 1e-9
    assert set(r.kind.tolist()) == {int(Contact.EDGE)}
    g = np.arange(-6.0, 6.0, 0.005)
    X, Y = np.meshgrid(g, g)
    for (cx, cy), h in zip(xy, r.height):
        x, y = X + cx, Y + cy
        d2 = (x - cx) ** 2 + (y - cy) ** 2
        z = 10 + 0.2 * x - 0.5 * np.abs(y)
        brute = np.max(np.where(d2 <= R * R, z + np.sqrt(np.maximum(R * R - d2, 0)) - R, -np.inf))
        assert brute <= h + 1e-12 and h - brute < 1e-3  # the samples never above, and close below


@needs_numba
def test_edge_windows_kept_or_evaluated_give_the_same_heights(parts, monkeypatch):
    """The edge search reads its windows' points computed once per face set; a face set too large to keep
    them (``MAX_WINDOW_BYTES``) evaluates them per search: the same heights, contacts and kinds, bit for bit."""
    from machsurf_cad.threeaxis.dropcutter import default_seed_spacing
    from machsurf_cad.threeaxis.faceset import face_set

    cutter = ms.parse_cutter("flat:D=10")
    out = []
    for limit in (compiled.MAX_WINDOW_BYTES, 0):
        monkeypatch.setattr(compiled, "MAX_WINDOW_BYTES", limit)
        fs = face_set(parts["freeform_block.step"], spacing=default_seed_spacing(cutter))
        assert (compiled._packed(fs)[3][18].shape[0] > 0) == (limit > 0)  # the windows
        out.append(ms.drop_cutter(None, cutter, _grid(fs, 25), face_set=fs, engine="compiled"))
    a, b = out
    assert a.n_cached == b.n_cached == 0  # both solved, none read from the other's heights
    assert np.array_equal(a.height, b.height, equal_nan=True) and np.array_equal(a.kind, b.kind)
    assert np.array_equal(a.contact, b.contact, equal_nan=True)


def test_creases_are_cut_to_the_trimming():
    """The roof's ridge (v = 0.5) inside a slanted quadrilateral trimming loop: one crease from u = 0.2 to
    0.7, where the loop's sides cross it (closed form), and the ball still rests on it there."""
    from machsurf_cad.geometry.builders import line_segment
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.threeaxis.faceset import _creases

    poles = np.array([[[x, y, 10 + 0.2 * x - 0.5 * abs(y)] for y in (-20.0, 0.0, 20.0)] for x in (-20.0, 20.0)])
    roof = ms.BSplineSurface(1, 1, [0, 1], [2, 2], [0, 0.5, 1], [2, 1, 2], poles)
    c = [(0.1, 0.3), (0.8, 0.2), (0.6, 0.8), (0.3, 0.7)]
    face = Face(roof, (tuple(line_segment(c[i], c[(i + 1) % 4]) for i in range(4)),), "trimmed roof")
    (crease,) = _creases(face)
    ends = crease.evaluate(np.array(crease.bounds))
    assert np.abs(ends - [[0.2, 0.5], [0.7, 0.5]]).max() < 1e-9
    R, xy = 5.0, np.array([[-3.0, 0.3]])  # u = 0.425: the ridge's highest point in the disc lies inside the loop
    r = ms.drop_cutter([face], ms.BallEndMill(2 * R), xy)
    assert abs(r.height[0] - (10 + 0.2 * -3.0 + np.sqrt(1.04 * (R**2 - 0.3**2)) - R)) < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", ["freeform_block.step", "mould_insert.step"])
@pytest.mark.parametrize("spec", ["flat:D=10", "bull:D=10,r=2"])
def test_flat_and_bull_heights_equal_an_independent_reference_to_1e6_mm_near_the_trims_too(parts, name, spec):
    """The flat D10 and the bull D10 r2 on the block and the mould: 300 random points and 200 points within 1 mm
    in plan of a trimming edge against ``tests/profile_reference.py`` (dense samples climbed on the exact faces
    by Newton, along the tool's rim circle by Newton on its angle, and on the exact edges by golden section):
    equal within 1e-6 mm (on the 200 x 200 grids, ``benchmarks/bruteforce_grid.py --tool``, within 4e-11)."""
    from profile_reference import ProfileReference

    faces = parts[name]
    cutter = ms.parse_cutter(spec)
    ref = ProfileReference(faces, spacing=0.3)
    rng = np.random.default_rng(28)
    lo, hi = ref.P[:, :2].min(axis=0), ref.P[:, :2].max(axis=0)
    edge = ref.E[rng.choice(ref.E.shape[0], 200, replace=False), :2]
    xy = np.vstack([rng.uniform(lo, hi, (300, 2)), edge + rng.uniform(-1, 1, (200, 2)) / np.sqrt(2)])
    bf = ref.heights(xy, 5.0, 0.0 if spec.startswith("flat") else 2.0)
    dc = ms.drop_cutter(faces, cutter, xy).height
    np.testing.assert_array_equal(np.isnan(bf), np.isnan(dc))
    ok = np.isfinite(bf)
    assert ok.sum() > 400
    assert np.abs(dc[ok] - bf[ok]).max() <= 1e-6


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
def test_a_flat_end_on_the_tops_of_the_moulds_steep_fillets_equals_the_reference(parts, engine):
    """A flat D8 at four points of the mould's raster where its rim rests on the top of a steep fillet (faces
    29 and 30, x = +-26): the rim contact equals ``tests/profile_reference.py`` within 1e-6 mm. A rim ascent
    that kept points up to 1e-3 R off the circle and read their heights to first order lost this contact
    (the rise of z across the circle is steep there) and put the tool up to 1 mm low: a flat D8 raster gouged
    0.15 mm, while 40,000-point grids of the mould showed nothing."""
    from profile_reference import ProfileReference

    faces = parts["mould_insert.step"]
    xy = np.array([[-25.997983, 0.666667], [-25.996518, 0.666667], [-25.999447, 0.666667], [25.998172, 0.666667]])
    bf = ProfileReference(faces, spacing=0.3).heights(xy, 4.0, 0.0)
    r = ms.drop_cutter(faces, ms.FlatEndMill(8), xy, engine=engine)
    assert np.all(r.kind == Contact.RIM) and set(r.face) == {29, 30}
    assert np.abs(r.height - bf).max() <= 1e-6


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=needs_numba)])
@pytest.mark.parametrize("a, cy", [(0.05, 3.0), (0.1, 4.0), (0.1, 5.5), (0.1, 3.0), (0.2, 3.0)])
def test_the_face_ascent_climbs_along_the_side_of_the_box_where_g_leaves_it(engine, a, cy):
    """``z = 0.3 x + a (y - 5)^2`` on [0, 10]^2 under a ball D10 at (9, cy): g rises out of the face across
    x = 10, so its maximum over the face lies on that side (at its end y = 0 for the last two). The ascent
    from (8, cy - 0.5) reaches it within 1e-9 mm (an independent search along the side: 100,001 samples,
    then a bounded scalar minimisation): a step clamped at the side used to crawl along it and stop up to
    0.012 mm short."""
    from scipy.optimize import minimize_scalar

    from machsurf_cad.threeaxis import _jit_solve, faceset, solves

    poles = np.array([[[x, y, 0.3 * x + c] for y, c in zip((0.0, 5.0, 10.0), (25 * a, -25 * a, 25 * a))]
                      for x in (0.0, 10.0)])  # fmt: skip
    face = ms.BSplineSurface(1, 2, [0, 1], [2, 2], [0, 1], [3, 3], poles)
    R = 5.0

    def side(y):  # g on the side x = 10: z minus the ball's lower surface at the distance from the axis
        return 3.0 + a * (y - 5) ** 2 - (R - np.sqrt(np.maximum(R * R - 1.0 - (y - cy) ** 2, 0.0)))

    ys = np.linspace(0.0, 10.0, 100_001)
    y0 = ys[np.argmax(side(ys))]
    lo, hi = max(y0 - 1e-4, 0.0), min(y0 + 1e-4, 10.0)
    best = minimize_scalar(lambda y: -side(y), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    exact = max(side(best.x), side(lo), side(hi))
    fs = faceset.face_set([face], spacing=0.5)
    prof = solves._Profile(ms.BallEndMill(2 * R))
    if engine == "numpy":
        u, v, g, _ = solves._face_newton(fs, prof, np.array([[9.0, cy]]), np.array([0]), np.array([0.8]),
                                         np.array([cy / 10 - 0.05]))  # fmt: skip
        u, g = u[0], g[0]
    else:
        S, _, _, _ = compiled._packed(fs)
        W = (np.empty((6, 3)), np.empty((6, 3)), np.empty((6, 3)), np.empty((9, 3)), np.empty((3, 3)), np.empty(480))
        u, v, g = _jit_solve.face_newton(S, compiled._profile(prof), fs.spacing, 9.0, cy, 0, 0.8, cy / 10 - 0.05, W)
    assert u == 1.0
    assert abs(g - exact) < 1e-9


@needs_numba
@pytest.mark.parametrize("name", ["freeform_block.step", "mould_insert.step"])
def test_the_kernels_trim_test_classifies_as_the_faces_do(parts, name):
    """The kernel's even-odd test (its polygon edges in slabs of v whose bounds are quantiles of the edges'
    ends) against :meth:`.Face.contains_uv` on the same polygons: random points of each trimmed face's box,
    points on the polygons' vertex rows (``v`` of a vertex: the rays through the slabs' bounds) and points
    within 1e-6 of the box's lower side, where the block's top has a loop of thousands of edges level but
    for rounding."""
    from machsurf_cad.geometry.face import TRIM_TOLERANCE
    from machsurf_cad.threeaxis._jit_geom import inside
    from machsurf_cad.threeaxis.faceset import face_set

    fs = face_set(parts[name], spacing=2.0)
    S, _, T, _ = compiled._packed(fs)
    rng = np.random.default_rng(7)
    checked = 0
    for f, face in enumerate(fs.faces):
        if not face.is_trimmed:
            continue
        u0, u1, v0, v1 = fs.bounds[f]
        verts = np.concatenate(face.trim_polygons(TRIM_TOLERANCE))
        u = np.concatenate([rng.uniform(u0, u1, 1500), rng.uniform(u0, u1, 300), rng.uniform(u0, u1, 200)])
        low_side = v0 + rng.uniform(0, 1e-6, 200) * (v1 - v0)
        v = np.concatenate([rng.uniform(v0, v1, 1500), rng.choice(verts[:, 1], 300), low_side])
        want = face.contains_uv(u, v)
        got = np.array([inside(S, T, f, a, b) for a, b in zip(u, v)])
        assert np.array_equal(got, want), f"face {f}: {np.sum(got != want)} of {u.size} points differ"
        checked += u.size
    assert checked >= 4000
