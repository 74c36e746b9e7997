"""Vertical faces (a wall, a hole's cylinder): the drop-cutter seeds no face or rim solve inside them, since
their trimming edges hold their every contact. The test on the poles against closed cases; the heights on
a wall alone against the closed form of its top edge; the example parts' heights with and without the
rule, point for point, in both engines."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad.geometry import builders
from machsurf_cad.geometry.face import Face
from machsurf_cad.threeaxis import cache, compiled, faceset
from machsurf_cad.threeaxis.faceset import face_set, is_vertical

ROOT = Path(__file__).resolve().parent.parent


def _wall_grid(xy_along, z_levels):
    """Poles of a wall over the plan polyline ``xy_along`` (rows along u), the same x, y at each z level."""
    xy = np.asarray(xy_along, float)
    return np.array([[[x, y, z] for z in z_levels] for x, y in xy])


def test_walls_cylinders_and_extrusions_are_vertical():
    assert is_vertical(Face(builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 0, 5))))
    assert is_vertical(Face(builders.plane_patch((0, 0, 5), (10, 0, 0), (0, 0, -5))))  # z falls along v
    assert is_vertical(Face(builders.cylinder_patch(5.0, 10.0)))  # rational along u, straight up along v
    wavy = _wall_grid([(0, 0), (3, 2), (6, -1), (9, 0)], [0.0, 1.0, 4.0, 6.0])  # a cubic wall, z rising
    assert is_vertical(Face(builders.surface_from_grid(wavy, 3, 3)))
    assert is_vertical(Face(builders.surface_from_grid(np.swapaxes(wavy, 0, 1), 3, 3)))  # the other way


def test_tilted_folded_and_flat_faces_are_not():
    assert not is_vertical(Face(builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 1e-9, 5))))  # 1e-9 off
    assert not is_vertical(Face(builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 10, 0))))  # a floor
    folded = _wall_grid([(0, 0), (9, 0)], [0.0, 4.0, 2.0])  # z up then down along v: a fold
    assert not is_vertical(Face(builders.surface_from_grid(folded, 1, 2)))
    flat_row = _wall_grid([(0, 0), (9, 0)], [0.0, 0.0, 2.0])  # z stays between two rows of poles
    assert not is_vertical(Face(builders.surface_from_grid(flat_row, 1, 2)))
    w = np.ones((2, 2))
    w[1, 1] = 2.0  # a weight that changes along the vertical rows: x, y then move along v
    s = builders.surface_from_grid(_wall_grid([(0, 0), (9, 0)], [0.0, 5.0]), 1, 1, weights=w)
    assert not is_vertical(Face(s))


def test_a_face_extrapolated_along_its_height_counts_only_at_degree_one():
    """A face's box past its knot domain (CAD rounding): the surface is extrapolated there. Along the
    vertical parameter z stays linear at degree 1; at degree 3 it is not known to keep rising."""
    lin = builders.surface_from_grid(_wall_grid([(0, 0), (9, 0)], [0.0, 5.0]), 1, 1)
    assert is_vertical(Face(lin, uv_bounds=(0.0, 1.0, 0.0, 1.0 + 1e-6)))
    cub = builders.surface_from_grid(_wall_grid([(0, 0), (9, 0)], [0.0, 1.0, 2.0, 5.0]), 1, 3)
    assert is_vertical(Face(cub, uv_bounds=(0.0, 1.0, 0.0, 1.0)))
    assert not is_vertical(Face(cub, uv_bounds=(0.0, 1.0, 0.0, 1.0 + 1e-6)))
    assert not is_vertical(Face(lin, uv_bounds=(0.0, 1.0, 0.0, 1.01)))  # past a thousandth of its span


def test_a_periodic_height_and_an_open_knot_vectors_extrapolation_are_not_vertical():
    """Found by a hostile review. Rows rising strictly along a periodic parameter wrap from their last pole
    back to their first: z climbs and falls, its top inside the face (a ball D4 sat 2.12 mm too low). An
    open (unclamped) knot vector's domain is inside its first and last knot: a box past the domain is
    extrapolated, and there z turned over (14.1 mm too low); the stray is measured from the domain."""
    from machsurf_cad.geometry.bspline import BSplineSurface
    from machsurf_cad.threeaxis.faceset import _stray

    P = np.array([[[x, 0.0, z] for z in (0.0, 1.0, 2.0, 3.0)] for x in (0.0, 10.0)])
    periodic = BSplineSurface(1, 2, [0, 1], [2, 2], np.arange(5.0), np.ones(5, int), P, periodic_v=True)
    assert not is_vertical(Face(periodic))
    P = np.array([[[x, 0.0, z] for z in (0.0, 9.0, 10.0)] for x in (0.0, 10.0)])
    open_v = BSplineSurface(1, 2, [0, 1], [2, 2], np.arange(6.0), np.ones(6, int), P)
    assert open_v.bounds[2:] == (2.0, 3.0)
    assert is_vertical(Face(open_v))  # its box is its domain
    past = Face(open_v, uv_bounds=(0.0, 1.0, 0.0, 5.0))
    assert _stray(past)[1] == 2.0 and not is_vertical(past)
    v = np.linspace(0.0, 5.0, 5001)
    top = float(open_v.evaluate(np.full(v.size, 0.5), v)[:, 2].max())  # 9.5625 at v = 3.125, inside the box
    for engine in ("numpy", "compiled") if compiled.available() else ("numpy",):
        h = ms.drop_cutter([past], ms.parse_cutter("flat:D=4"), [[5.0, -1.5]], engine=engine).height[0]
        assert h == pytest.approx(top, abs=1e-6)


@pytest.mark.parametrize("faces", ["wall", "cylinder"])
def test_the_path_planners_take_a_part_of_vertical_faces_only(faces):
    """No samples inside any face: the raster, the scallop raster and the waterline plan from the edges (a
    review found them reading the empty face samples' top). Every cutting position rests on the top edge,
    at its closed form: a ball D4 at plan distance ``d`` from the edge stands at ``top - (2 - sqrt(4 - d^2))``
    (the waterline's contour points within its tracing tolerance)."""
    from machsurf_cad.cam.toolpath import Move

    if faces == "wall":  # x in [0, 10], y = 0, z in [0, 5]
        part, top = [builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 0, 5))], 5.0

        def dist(p):
            return np.hypot(p[:, 0] - np.clip(p[:, 0], 0.0, 10.0), p[:, 1])
    else:  # a tube of radius 5 around z, z in [0, 10]
        part, top = [builders.cylinder_patch(5.0, 10.0, 360.0)], 10.0

        def dist(p):
            return np.abs(np.hypot(p[:, 0], p[:, 1]) - 5.0)

    tool = ms.parse_cutter("ball:D=4")
    paths = [(ms.raster(part, tool, stepover=1.0), 1e-9), (ms.waterline(part, tool, stepdown=1.0), 1e-6)]
    if faces == "cylinder":  # (the wall's plan is a line: narrower than one scallop line)
        paths.append((ms.raster(part, tool, scallop=0.05), 1e-9))
    for tp, tol in paths:
        tip = np.asarray(tp.tip)[np.isin(tp.move, [Move.CUT, Move.APPROACH])]
        d = dist(tip)
        assert tip.shape[0] > 0 and np.all(d <= 2.0 + 1e-9)
        np.testing.assert_allclose(tip[:, 2], top - (2.0 - np.sqrt(np.maximum(4.0 - d * d, 0.0))), atol=tol)


def test_vertical_is_taken_in_the_tool_frame():
    wall = builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 0, 5))
    assert face_set([wall], spacing=1.0).face_vertical.tolist() == [True]
    assert face_set([wall], axis=(0, 1, 1), spacing=1.0).face_vertical.tolist() == [False]


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_a_wall_alone_is_touched_on_its_top_edge(engine):
    """Only a vertical plane (x in [0, 10], y = 0, z in [0, 5]): the tool stands on its top edge, the ball
    at 5 - (R - sqrt(R^2 - d^2)) at a distance d from it, the flat at 5; nothing beyond the radius."""
    if engine == "compiled" and not compiled.available():
        pytest.skip("numba is not installed")
    wall = builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 0, 5))
    d = np.array([-1.9, -1.0, -0.3, 0.0, 0.4, 1.5, 1.99, 2.5])
    xy = np.column_stack([np.full(d.size, 5.0), d])
    ball = ms.drop_cutter([wall], ms.parse_cutter("ball:D=4"), xy, engine=engine)
    inside = np.abs(d) <= 2.0
    expect = np.where(inside, 5.0 - (2.0 - np.sqrt(np.maximum(4.0 - d * d, 0.0))), np.nan)
    np.testing.assert_allclose(ball.height, expect, atol=1e-9, equal_nan=True)
    flat = ms.drop_cutter([wall], ms.parse_cutter("flat:D=4"), xy, engine=engine)
    np.testing.assert_allclose(flat.height, np.where(inside, 5.0, np.nan), atol=1e-9, equal_nan=True)
    assert face_set([wall], spacing=1.0).sample_xyz.shape[0] == 0  # no sample inside it


@pytest.fixture(scope="module")
def parts():
    pytest.importorskip("OCP")
    from machsurf_cad.occ import read_step_faces

    names = ("mould_insert.step", "freeform_block.step")
    return {name: read_step_faces(ROOT / "example_parts" / name) for name in names}


def _without_the_rule(monkeypatch):
    cache.clear()
    monkeypatch.setattr(faceset, "is_vertical", lambda face, stray=None: False)


@pytest.mark.parametrize("name, n_vertical", [("freeform_block.step", 6), ("mould_insert.step", 28)])
@pytest.mark.parametrize("spec", ["ball:D=10", "bull:D=10,r=2", "flat:D=10"])
def test_the_rule_leaves_every_height_as_it_was(parts, monkeypatch, name, n_vertical, spec):
    """Walls, hole and notch cylinders of the block and the mould: heights with the walls' own face and rim
    solves (the rule off) and without them, on a grid over the whole part and beyond it (every wall within
    the tool's reach of many points): the same within 1e-9 mm, NaN at the same points."""
    engine = "compiled" if compiled.available() else "numpy"
    faces = parts[name]
    tool = ms.parse_cutter(spec)
    spacing = ms.threeaxis.dropcutter.default_seed_spacing(tool)
    cache.clear()
    fs = face_set(faces, spacing=spacing)
    assert int(fs.face_vertical.sum()) == n_vertical
    _, lo, hi, _ = fs.pool_extent
    n = 41 if engine == "compiled" else 15
    x, y = np.meshgrid(np.linspace(lo[0] - 4, hi[0] + 4, n), np.linspace(lo[1] - 4, hi[1] + 4, n))
    xy = np.column_stack([x.ravel(), y.ravel()])
    new = ms.drop_cutter(None, tool, xy, face_set=fs, engine=engine).height
    with monkeypatch.context() as m:
        _without_the_rule(m)
        fs_all = face_set(faces, spacing=spacing)
        assert not fs_all.face_vertical.any() and fs_all.sample_xyz.shape[0] > fs.sample_xyz.shape[0]
        old = ms.drop_cutter(None, tool, xy, face_set=fs_all, engine=engine).height
    cache.clear()
    assert np.array_equal(np.isnan(new), np.isnan(old))
    assert np.nanmax(np.abs(new - old)) <= 1e-9
    assert np.isfinite(new).sum() > 0.5 * new.size


def test_a_vertical_faces_edge_samples_seed_only_their_edges():
    """The edge samples of a vertical face carry a cover and rise of -inf (no face or rim bound) and a
    min_tilt of inf (no face seed); their edge bounds are those of any edge."""
    wall = builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 0, 5))
    floor = builders.plane_patch((-5, -5, 0), (20, 0, 0), (0, 10, 0))
    fs = face_set([wall, floor], spacing=1.0)
    n_int = fs.sample_xyz.shape[0]
    mine = fs.edge_face[fs.edge_id] == 0
    assert np.all(fs.sample_face == 1)
    assert np.all(fs.cover[n_int:][mine] == -np.inf) and np.all(fs.rise[n_int:][mine] == -np.inf)
    assert np.all(fs.min_tilt[n_int:][mine] == np.inf)
    assert np.all(np.isfinite(fs.edge_cover[mine])) and np.all(np.isfinite(fs.edge_rise[mine]))
    assert np.all(np.isfinite(fs.cover[n_int:][~mine]))


def test_a_machined_vertical_face_keeps_its_place_in_the_plan_box():
    """A floor (x, y in [0, 10]) and a wall standing at x = 15, both machined: the raster's plan box reaches
    the wall (from its edges' samples: it has none inside it), as it did from its samples before."""
    from machsurf_cad.threeaxis.dropcutter import machining_face_set

    floor = builders.plane_patch((0, 0, 0), (10, 0, 0), (0, 10, 0))
    wall = builders.plane_patch((15, 0, 0), (0, 10, 0), (0, 0, 5))
    fs, box = machining_face_set([floor, wall], [], ms.parse_cutter("ball:D=4"), axis=(0, 0, 1))
    assert fs.face_vertical.tolist() == [False, True]
    assert box == pytest.approx((0.0, 15.0, 0.0, 10.0), abs=1e-12)
    _, box_floor = machining_face_set([floor], [wall], ms.parse_cutter("ball:D=4"), axis=(0, 0, 1))
    assert box_floor == pytest.approx((0.0, 10.0, 0.0, 10.0), abs=1e-12)  # the wall only avoided
