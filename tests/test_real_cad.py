"""Cases from real CAD files, built with OCP (the real parts' licences keep them out of the repository):
trimming loops with gaps, parts from 1 mm to 10 m, closest points on trimmed faces and at corners,
periodic B-splines, units, STEP headers and names."""

import numpy as np
import pytest
from conftest import ROOT, needs_kernel
from helpers import assert_close, assert_points_close

import machsurf_cad as ms

pytestmark = needs_kernel
BLOCK = ROOT / "example_parts" / "freeform_block.step"


def _top():
    from machsurf_cad.occ import read_step_face

    return read_step_face(BLOCK, 0)


def _with_gaps(face, gap_mm):
    """The face's loops with every curve shortened at its end so consecutive curves miss by ``gap_mm`` in 3-D
    (the end pole moved back along the curve's end tangent in (u, v), staying inside the domain)."""
    s = face.surface
    loops = []
    for loop in face.loops:
        out = []
        for c in loop:
            if c.periodic or len(loop) == 1:  # a closed periodic curve has no end to move
                out.append(c)
                continue
            p = np.array(c.poles, float)
            t = p[-1] - p[-2]
            t /= np.linalg.norm(t)
            d = s.derivatives(np.array([p[-1, 0]]), np.array([p[-1, 1]]), 1)
            speed = float(np.linalg.norm(d.su[0] * t[0] + d.sv[0] * t[1]))  # mm per unit of (u, v) along t
            p[-1] = p[-1] - t * gap_mm / speed
            out.append(ms.BSplineCurve(c.degree, c.knots, c.mults, p, c.weights, c.periodic))
        loops.append(tuple(out))
    return ms.Face(s, tuple(loops), face.name, uv_bounds=face.uv_bounds)


def _edges_within_tolerance(tface):
    """Every edge's 3-D curve within its tolerance of its curve on the face (OCCT's boolean check)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    from machsurf_cad.occ.convert import curve_on_surface_distance

    exp = TopExp_Explorer(tface, TopAbs_EDGE)
    worst = 0.0
    while exp.More():
        e = TopoDS.Edge_s(exp.Current())
        d = curve_on_surface_distance(e, tface, n=101)  # denser than the build's own check
        assert d <= BRep_Tool.Tolerance_s(e), (d, BRep_Tool.Tolerance_s(e))
        worst = max(worst, d)
        exp.Next()
    return worst


@pytest.mark.parametrize("gap", [1e-5, 1e-4, 2e-3])
def test_loops_with_gaps_give_valid_faces_and_machining_surfaces(tmp_path, gap):
    from machsurf_cad.occ import read_step_faces, write_step
    from machsurf_cad.occ.convert import close_loop, face_from_surface

    face = _with_gaps(_top(), gap)
    assert max(close_loop(lp)[1] for lp in face.loops) > 0  # the loops really have gaps
    tf = face_from_surface(face.surface, [list(lp) for lp in face.loops])  # BRepCheck inside
    assert _edges_within_tolerance(tf) < 1e-3
    res = ms.machining_surface(face, "bull:D=16,r=3", axes=5, lead=10, tolerance=1e-3)
    path = write_step(tmp_path / "ms.step", res.faces())
    back = read_step_faces(path)
    assert [f.name for f in back] == ["S1_guiding", "S2_orientation"] and [len(f.loops) for f in back] == [2, 2]
    for f in res.faces():
        _edges_within_tolerance(face_from_surface(f.surface, [list(lp) for lp in f.loops]))


@pytest.mark.parametrize("scale", [0.01, 10.0, 100.0])  # a 1 mm, 1 m and 10 m part
def test_trimmed_faces_at_any_size(scale):
    from machsurf_cad.occ.convert import face_from_surface

    top = _top()
    s = top.surface.with_poles(top.surface.poles * scale)
    face_from_surface(s, [list(lp) for lp in top.loops])
    res = ms.machining_surface(
        ms.Face(s, top.loops, "scaled"), f"ball:D={10 * scale:g}", axes=3, tolerance=1e-3 * scale
    )
    assert res.s1_fit.max_error <= 1e-3 * scale
    face_from_surface(res.s1.surface, [list(lp) for lp in res.s1.loops])


def _offset_points(face, d, n=61, box=None):
    """Points at exactly ``d`` mm along the outward normal of the face's surface, on a grid of ``box``."""
    u0, u1, v0, v1 = box or face.uv_bounds
    U, V = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n), indexing="ij")
    p = ms.local_properties(face.surface, U.ravel(), V.ravel())
    nrm = p.normal * (-1.0 if face.reversed else 1.0)
    return p.point + d * nrm, U.ravel(), V.ravel()


def test_known_offset_reads_exactly_at_every_boundary_and_corner():
    face = ms.Face(ms.example("blade"))  # untrimmed: the grid includes the four corners and the edges
    pts, _, _ = _offset_points(face, 0.05)
    d = ms.deviation(face, pts)
    assert_close(d.signed, 0.05, 1e-9, "signed deviation of a 0.05 mm offset")
    assert d.on_boundary.sum() >= 4 * 60  # the feet of the edge points are on the parameter boundary


def test_trimmed_nominal_measures_beyond_its_region_to_its_boundary_edges():
    face = _top()
    s = face.surface
    pts, U, V = _offset_points(face, 0.05, n=71, box=s.bounds)  # the whole surface, beyond the trimming
    d = ms.deviation(face, pts)
    inside = face.contains_uv(U, V)
    out = d.outside_trim
    assert out is not None and out.sum() == d.stats["n_outside_trimmed_region"] > 100
    assert_close(d.signed[~out], 0.05, 1e-9, "inside the trimmed region")
    assert (out == ~inside).mean() > 0.99  # the same points, up to the polygonal region test at the boundary
    # independent: distance to 20001 samples per boundary curve (on the surface, in 3-D)
    from scipy.spatial import cKDTree

    curves = [c for lp in face.loops for c in lp]
    B = np.concatenate([s.evaluate(*c.evaluate(np.linspace(*c.bounds, 20001)).T) for c in curves])
    brute = cKDTree(B).query(pts[out])[0]
    mine = np.abs(d.signed[out])
    assert (mine <= brute + 1e-9).all() and (brute - mine).max() < 2e-3  # sample spacing < 0.01 mm
    assert mine.min() > 0.05 - 1e-9  # beyond the region a point is farther than its offset


def test_periodic_bspline_is_finite_on_its_closed_domain_and_agrees_with_occt():

    from machsurf_cad.occ import to_geom_surface

    n, p = 8, 3
    ang = 2 * np.pi * np.arange(n) / n
    prof = np.linspace(0, 50, 5)
    poles = np.stack(
        [
            np.cos(ang)[:, None] * (40 + 5 * np.sin(prof / 10))[None, :],
            np.sin(ang)[:, None] * (40 + 5 * np.sin(prof / 10))[None, :],
            np.broadcast_to(prof, (n, 5)),
        ],
        -1,
    )
    s = ms.BSplineSurface(
        p, 3, np.arange(n + 1) / n, np.ones(n + 1, int), [0.0, 0.5, 1.0], [4, 1, 4], poles, periodic_u=True
    )
    g = to_geom_surface(s)
    u0, u1, v0, v1 = s.bounds
    us = np.array([u0 - 1e-11, u0 - 9.8e-12, u0, 0.37, u1 - 1e-12, u1, u1 + 1e-11])
    vs = np.full(us.shape, 0.3)
    pts = s.evaluate(us, vs)
    assert np.isfinite(pts).all()
    ref = np.empty((us.size, 3))
    for i, (u, v) in enumerate(zip(us, vs)):
        q = g.Value(float(u), float(v))
        ref[i] = (q.X(), q.Y(), q.Z())
    assert_points_close(pts, ref, atol=1e-9)
    assert_points_close(pts[2], pts[5], atol=1e-9)  # closed: u0 and u1 are the same place


@pytest.mark.parametrize("unit,factor", [("INCH", 25.4), ("CM", 10.0)])
def test_inch_and_cm_files_read_in_mm(tmp_path, unit, factor):
    import cadquery as cq
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from machsurf_cad.occ import read_step_faces

    box = cq.Workplane().box(2 * factor, 3 * factor, 4 * factor).val().wrapped  # 2 x 3 x 4 units, built in mm
    w = STEPControl_Writer()
    Interface_Static.SetCVal_s("write.step.unit", unit)
    w.Transfer(box, STEPControl_AsIs)
    w.Write(str(tmp_path / "box.step"))
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    text = (tmp_path / "box.step").read_text().upper()
    assert ("'INCH'" in text) if unit == "INCH" else (".CENTI." in text)  # the file really is in that unit
    faces = read_step_faces(tmp_path / "box.step")
    areas = sorted(round(f.area, 6) for f in faces)
    f2 = factor * factor
    assert_close(areas, sorted([6 * f2, 6 * f2, 8 * f2, 8 * f2, 12 * f2, 12 * f2]), 1e-6 * f2)


def test_step_header_names_and_refusals(tmp_path):
    from machsurf_cad.occ import read_step_faces, write_step

    res = ms.machining_surface(ms.example("bezier5"), "ball:D=10", axes=3, tolerance=1e-2)
    path = write_step(tmp_path / "surfaces.step", res.faces(), author="J. Doe", organization="ACME")
    text = path.read_text()
    assert f"'machsurf_cad {ms.__version__}'" in text and "('J. Doe')" in text and "('ACME')" in text
    assert "Open CASCADE 7" not in text.split("ENDSEC")[0]  # the header says who wrote it
    assert "PRODUCT('surfaces','surfaces'" in text and "NEXT_ASSEMBLY_USAGE" not in text
    assert "OPEN_SHELL('S1_guiding'" in text and [f.name for f in read_step_faces(path)] == ["S1_guiding"]
    with pytest.raises(ms.InputError, match="no face"):
        write_step(tmp_path / "empty.step", [])


def test_faces_with_a_pole_machine_and_a_cone_tip_is_refused():
    """A sphere patch containing its pole (su x sv = 0 on a collapsed edge): the normal there is the limit
    of the normals around it, so S1 of a ball is the sphere of radius R + r; a cone's tip has no limit."""
    from machsurf_cad.geometry import builders

    s = builders.sphere_patch(50.0, lat_deg=(30.0, 90.0), lon_deg=360.0)  # u = 1 is the pole
    n = s.normals(np.array([1.0, 1.0, 1.0]), np.array([0.0, 0.3, 0.8]))
    assert_points_close(n, np.broadcast_to([0, 0, -1.0], (3, 3)), atol=1e-9)  # su x sv points to the centre
    p = ms.local_properties(s, np.array([1.0]), np.array([0.4]))
    assert_close([p.k1[0] * 50, p.k2[0] * 50], [1.0, 1.0], 1e-3)  # curvatures 1 mm from the pole's neighbour
    res = ms.machining_surface(ms.Face(s, reversed=True), "ball:D=10", axes=3, tolerance=1e-3)
    us = np.linspace(0, 1, 61)
    g = res.s1.surface.evaluate_grid(us, us)
    assert np.abs(np.linalg.norm(g, axis=-1) - 55.0).max() <= 1e-3  # the ball centre's sphere, pole included
    prof = ms.BSplineCurve(1, [0, 1], [2, 2], [[30.0, 0.0], [0.0, 30.0]])  # a cone, its tip at u = 1
    cone = builders.revolve_profile(prof, 360.0)
    with pytest.raises(ms.DegenerateGeometryError, match="no limit normal"):
        ms.machining_surface(ms.Face(cone, reversed=True), "ball:D=10", axes=3, tolerance=1e-3)


@pytest.mark.parametrize("part", ["freeform_block.step", "mould_insert.step"])
def test_the_grid_trimming_test_classifies_every_point_as_the_point_test(part):
    """``contains_uv_grid`` (the faces' sampling grids) against ``contains_uv`` on the same points, every
    trimmed face of two parts, a grid reaching past the box and rows at random v (one on its edge): the same
    mask bit for bit (points on a polygon's vertex rows included)."""
    from machsurf_cad.occ import read_step_faces

    rng = np.random.default_rng(3)
    faces = [f for f in read_step_faces(ROOT / "example_parts" / part) if f.is_trimmed]
    assert len(faces) >= 8
    for face in faces:
        u0, u1, v0, v1 = face.uv_bounds
        us = np.linspace(u0 - 0.02 * (u1 - u0), u1, 151)
        vs = np.sort(np.r_[v0, rng.uniform(v0, v1, 120), face.trim_polygons()[0][:5, 1]])
        U, V = np.meshgrid(us, vs, indexing="ij")
        grid = face.contains_uv_grid(us, vs)
        assert grid.shape == (us.size, vs.size) and 0 < grid.sum() < grid.size
        np.testing.assert_array_equal(grid, face.contains_uv(U.ravel(), V.ravel()).reshape(U.shape))


def _even_odd(u, v, polys):
    """Brute-force even-odd rule: every point against every polygon edge (rows ``lo < v <= hi``, the crossing
    at the same ``x`` as the library's)."""
    x0 = np.concatenate([p[:, 0] for p in polys])
    y0 = np.concatenate([p[:, 1] for p in polys])
    x1 = np.concatenate([np.roll(p[:, 0], -1) for p in polys])
    y1 = np.concatenate([np.roll(p[:, 1], -1) for p in polys])
    out = np.zeros(u.size, bool)
    for a in range(0, u.size, 100):
        pu, pv = u[a : a + 100, None], v[a : a + 100, None]
        crosses = (y0 < pv) != (y1 < pv)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = x0 + (pv - y0) * (x1 - x0) / (y1 - y0)
        out[a : a + 100] = np.sum(crosses & (pu < x), axis=1) % 2 == 1
    return out


def test_the_point_trimming_test_equals_a_brute_force_on_rows_of_many_points():
    """Points clipped onto the sides of the parameter box, where the block's loops run along those sides (a row
    of many points of one v, crossed by hundreds of polygon edges: the check's refinement patches), polygon
    vertices and NaN: ``contains_uv``'s rows sorted with their crossings, and its point-by-crossing comparison
    (small batches force the first), equal a brute-force even-odd rule over every edge."""
    from machsurf_cad.geometry.face import _points_in_polygons
    from machsurf_cad.occ import read_step_faces

    rng = np.random.default_rng(5)
    off = np.linspace(-1.0, 1.0, 5)
    OU, OV = (a.ravel() for a in np.meshgrid(off, off, indexing="ij"))
    for face in read_step_faces(ROOT / "example_parts" / "freeform_block.step"):
        polys = face.trim_polygons()
        u0, u1, v0, v1 = face.uv_bounds
        cu, cv = rng.uniform(u0, u1, 60), rng.uniform(v0, v1, 60)
        u = np.clip(cu[:, None] + 0.1 * (u1 - u0) * OU, u0, u1).ravel()
        v = np.clip(cv[:, None] + 0.1 * (v1 - v0) * OV, v0, v1).ravel()
        verts = np.concatenate(polys)[:: max(1, sum(len(p) for p in polys) // 300)]
        u = np.r_[u, verts[:, 0], np.nan, 0.5 * (u0 + u1)]
        v = np.r_[v, verts[:, 1], 0.5 * (v0 + v1), np.nan]
        want = _even_odd(u, v, polys)
        assert 0 < want.sum() < want.size - 2
        on_sides = np.isin(v, [v0, v1]).sum()
        assert on_sides > 50  # rows of many points exercised
        np.testing.assert_array_equal(face.contains_uv(u, v), want)
        np.testing.assert_array_equal(_points_in_polygons(u, v, polys, batch=50), want)
    # a polygon with a NaN vertex: its crossings are right of no point, in both branches
    poly = [np.array([[0, 0], [1, 0], [np.nan, 0.5], [1, 1], [0, 1]], float)]
    u, v = np.full(6, 0.5), np.full(6, 0.25)
    for batch in (1, 4_000_000):
        with np.errstate(invalid="ignore"):
            np.testing.assert_array_equal(_points_in_polygons(u, v, poly, batch=batch), _even_odd(u, v, poly))
