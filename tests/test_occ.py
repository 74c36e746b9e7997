"""The kernel door: agreement with OCCT's own evaluation, STEP/STL round trips, validity."""

import math
import re

import numpy as np
import pytest
from conftest import ROOT, needs_kernel
from helpers import random_surface

from machsurf_cad import examples
from machsurf_cad.errors import InputError
from machsurf_cad.geometry import builders, local_properties
from machsurf_cad.geometry.face import Face

pytestmark = needs_kernel


def _occt_d2_and_props(g, u, v):
    from OCP.GeomLProp import GeomLProp_SLProps
    from OCP.gp import gp_Dir, gp_Pnt, gp_Vec

    out = {k: [] for k in ("p", "su", "sv", "suu", "suv", "svv", "n", "kmax", "kmin", "dmax", "dmin")}
    props = GeomLProp_SLProps(g, 2, 1e-12)
    for a, b in zip(u, v):
        p, d1u, d1v, d2u, d2v, d2uv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
        g.D2(float(a), float(b), p, d1u, d1v, d2u, d2v, d2uv)
        out["p"].append((p.X(), p.Y(), p.Z()))
        for key, vec in (("su", d1u), ("sv", d1v), ("suu", d2u), ("svv", d2v), ("suv", d2uv)):
            out[key].append((vec.X(), vec.Y(), vec.Z()))
        props.SetParameters(float(a), float(b))
        nn = props.Normal()
        out["n"].append((nn.X(), nn.Y(), nn.Z()))
        out["kmax"].append(props.MaxCurvature())
        out["kmin"].append(props.MinCurvature())
        dmax, dmin = gp_Dir(), gp_Dir()
        props.CurvatureDirections(dmax, dmin)
        out["dmax"].append((dmax.X(), dmax.Y(), dmax.Z()))
        out["dmin"].append((dmin.X(), dmin.Y(), dmin.Z()))
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("rational", [False, True])
def test_evaluation_agrees_with_occt_d2_and_slprops(rng, rational):
    from machsurf_cad.occ import to_geom_surface

    s = random_surface(rng, rational=rational)
    g = to_geom_surface(s)
    u, v = rng.uniform(0, 1, (2, 400))
    ref = _occt_d2_and_props(g, u, v)
    d = s.derivatives(u, v, 2)
    for key, ours in (("p", d.point), ("su", d.su), ("sv", d.sv), ("suu", d.suu), ("suv", d.suv), ("svv", d.svv)):
        scale = max(1.0, np.abs(ref[key]).max())
        assert np.abs(ours - ref[key]).max() < 1e-9 * scale, key
    p = local_properties(s, u, v)
    assert np.abs(p.normal - ref["n"]).max() < 1e-9
    assert np.abs(p.k1 - ref["kmax"]).max() < 1e-9
    assert np.abs(p.k2 - ref["kmin"]).max() < 1e-9
    # directions agree up to sign where the curvatures are distinct
    distinct = (ref["kmax"] - ref["kmin"]) > 1e-6
    dots = np.abs(np.einsum("ij,ij->i", p.dir1, ref["dmax"]))
    assert np.abs(dots[distinct] - 1).max() < 1e-6


def test_quadrics_agree_with_occt_slprops(rng):
    from machsurf_cad.occ import to_geom_surface

    for s in (builders.sphere_patch(25), builders.torus_patch(30, 8), builders.cylinder_patch(12, 40)):
        u, v = rng.uniform(0, 1, (2, 100))
        ref = _occt_d2_and_props(to_geom_surface(s), u, v)
        p = local_properties(s, u, v)
        assert np.abs(p.k1 - ref["kmax"]).max() < 1e-9 and np.abs(p.k2 - ref["kmin"]).max() < 1e-9


def test_numpy_occt_conversion_round_trip_is_exact(rng):
    from machsurf_cad.occ import from_geom_surface, to_geom_surface

    s = random_surface(rng, rational=True)
    assert from_geom_surface(to_geom_surface(s)) == s


def test_step_round_trip_several_named_faces(tmp_path, rng):
    from machsurf_cad.occ import read_step_faces, write_step

    faces = [
        Face(random_surface(rng, rational=True), name="wavy_rational"),
        Face(examples.bezier5_patch(), name="bezier5"),
        Face(builders.torus_patch(40, 10), name="torus"),
    ]
    path = write_step(tmp_path / "three.step", faces)
    text = path.read_text()
    assert "B_SPLINE_SURFACE_WITH_KNOTS" in text and "OFFSET_SURFACE" not in text
    assert "AUTOMOTIVE_DESIGN" in text  # AP214
    back = read_step_faces(path)
    assert [f.name for f in back] == ["wavy_rational", "bezier5", "torus"]
    u, v = rng.uniform(0, 1, (2, 3000))
    for a, b in zip(faces, back):
        assert np.abs(a.surface.evaluate(u, v) - b.surface.evaluate(u, v)).max() < 1e-7


def test_trimmed_face_of_real_part_keeps_loops(tmp_path):
    from machsurf_cad.occ import read_step_faces, write_step

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    top = next(f for f in faces if f.name == "freeform_top")
    assert top.source_type == "BSplineSurface" and top.is_trimmed and len(top.loops) == 2
    # the hole (D = 24 mm at x = 70, y = 45) is outside the face, a point away from it inside
    u0, u1, v0, v1 = top.uv_bounds
    us, vs = np.linspace(u0, u1, 200), np.linspace(v0, v1, 200)
    U, V = np.meshgrid(us, vs, indexing="ij")
    P = top.surface.evaluate(U, V)
    inside = top.contains_uv(U, V)
    r_hole = np.hypot(P[..., 0] - 70, P[..., 1] - 45)
    assert not np.any(inside & (r_hole < 11.5))
    assert np.all(inside[(r_hole > 12.5) & (P[..., 0] > 8) & (P[..., 0] < 95) & (P[..., 1] > 8) & (P[..., 1] < 68)])
    # area of the trimmed region by quadrature of |su x sv| agrees with the kernel's
    d = top.surface.derivatives(U, V, 1)
    dA = np.linalg.norm(np.cross(d.su, d.sv), axis=-1) * (us[1] - us[0]) * (vs[1] - vs[0])
    assert abs(dA[inside].sum() - top.area) / top.area < 0.01
    # the trimmed face survives a write/read with its loops
    back = read_step_faces(write_step(tmp_path / "top.step", [top]))[0]
    assert len(back.loops) == 2 and abs(back.area - top.area) < 1e-6 * top.area


def test_any_face_type_is_converted_to_nurbs():
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    hole = [f for f in faces if f.source_type == "Cylinder" and abs(f.area - 2 * math.pi * 12 * 0) >= 0]
    assert hole, "the block has cylindrical faces"
    found_hole = False
    for f in hole:
        u0, u1, v0, v1 = f.uv_bounds
        U, V = np.meshgrid(np.linspace(u0, u1, 30), np.linspace(v0, v1, 30), indexing="ij")
        P = f.surface.evaluate(U, V)
        r = np.hypot(P[..., 0] - 70, P[..., 1] - 45)
        if np.abs(r - 12).max() < 1e-9:
            found_hole = True
    assert found_hole


def test_stl_deflection_is_measured(tmp_path):
    from machsurf_cad.measure import deviation
    from machsurf_cad.meshsample import subdivide
    from machsurf_cad.occ import read_stl, write_stl

    s = builders.sphere_patch(40.0)
    path = write_stl(tmp_path / "s.stl", [Face(s, name="sphere")], linear_deflection=0.02)
    pts, tris = read_stl(path)
    # vertices lie on the sphere (STL stores float32: 40 mm * 6e-8); interiors inside it
    assert np.abs(np.linalg.norm(pts, axis=1) - 40).max() < 1e-5
    spts, _ = subdivide(pts, tris, 2)
    r = np.linalg.norm(spts, axis=1)
    dev = deviation(s, spts)
    inner = ~dev.on_boundary  # feet on the patch's edge measure the distance to the edge instead
    assert inner.mean() > 0.95
    assert np.abs(dev.signed[inner] - (40 - r[inner])).max() < 1e-9  # closed form: distance to a sphere
    assert dev.max_abs <= 0.02 * 1.05


def test_bad_step_inputs_raise_input_errors(tmp_path):
    from machsurf_cad.occ import read_step_face, read_step_faces

    with pytest.raises(InputError, match="not found"):
        read_step_faces(tmp_path / "missing.step")
    (tmp_path / "empty.step").write_text("")
    with pytest.raises(InputError, match="empty"):
        read_step_faces(tmp_path / "empty.step")
    (tmp_path / "junk.step").write_text("this is not a STEP file\n" * 20)
    with pytest.raises(InputError, match="could not read|no transferable"):
        read_step_faces(tmp_path / "junk.step")
    with pytest.raises(InputError, match=re.escape("out of range")):
        read_step_face(ROOT / "example_parts" / "freeform_block.step", 99)


def test_step_without_faces(tmp_path):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.gp import gp_Pnt

    from machsurf_cad.occ import read_step_faces
    from machsurf_cad.occ.step import write_step_shape

    path = write_step_shape(tmp_path / "vertex.step", BRepBuilderAPI_MakeVertex(gp_Pnt(1, 2, 3)).Vertex())
    with pytest.raises(InputError, match="no faces|no transferable|no shape"):
        read_step_faces(path)


def test_cutter_solids_volumes_match_closed_forms():
    from machsurf_cad.occ.solids import cutter_solid, solid_volume
    from machsurf_cad.toolspec import parse_cutter

    ball = parse_cutter("ball:D=10,L=30")
    assert abs(solid_volume(cutter_solid(ball)) - (math.pi * 25 * 25 + 2 / 3 * math.pi * 125)) < 1e-6
    flat = parse_cutter("flat:D=16,L=40")
    assert abs(solid_volume(cutter_solid(flat, tip=(5, 6, 7), axis=(1, 1, 0))) - math.pi * 64 * 40) < 1e-6
    bull = parse_cutter("bull:D=20,r=4,L=50")
    Rt, r = 6.0, 4.0
    # quarter torus corner by Pappus + inner cylinder + upper cylinder
    corner_area = math.pi * r * r / 4
    centroid = Rt + 4 * r / (3 * math.pi)
    ref = 2 * math.pi * centroid * corner_area + math.pi * Rt**2 * r + math.pi * 100 * (50 - r)
    assert abs(solid_volume(cutter_solid(bull)) - ref) < 1e-6
    cone = parse_cutter("cone:D=10,angle=6,L=30")
    R1 = 5 + 30 * math.tan(math.radians(6))
    ref = math.pi * 30 / 3 * (25 + 5 * R1 + R1 * R1)
    assert abs(solid_volume(cutter_solid(cone)) - ref) < 1e-6


def test_cadquery_face_round_trip(rng):
    from machsurf_cad.occ import from_cq_face, read_step_faces, to_cq_face

    top = read_step_faces(ROOT / "example_parts" / "freeform_block.step")[0]
    cqf = to_cq_face(top)
    assert cqf.isValid() and abs(cqf.Area() - top.area) < 1e-6 * top.area
    back = from_cq_face(cqf, "top")
    u, v = rng.uniform(0, 1, (2, 500))
    assert np.abs(back.surface.evaluate(u, v) - top.surface.evaluate(u, v)).max() < 1e-12
    assert len(back.loops) == 2


@pytest.mark.parametrize(
    "spec",
    [
        "ball:D=10",
        "flat:D=16",
        "bull:D=20,r=4",
        "cone:D=10,angle=6",
        "cone:D=12,angle=-8",
        "drum:D=20,Rp=40,L=20",
        "barrel:D=20,Rp=40,L=20",
        "apt:D=20,r=4,e=6,f=4,alpha=10,beta=5,h=60",
    ],
)
def test_every_cutter_solid_is_valid_with_the_profile_volume(spec):
    from machsurf_cad.occ import is_valid
    from machsurf_cad.occ.solids import cutter_solid, solid_volume
    from machsurf_cad.toolspec import parse_cutter

    c = parse_cutter(spec)
    solid = cutter_solid(c, tip=(3, -2, 7), axis=(0.2, 0.1, 1.0))
    assert is_valid(solid)
    # independent volume: integral of pi rho(z)^2 over the dense profile (trapezoid rule on z)
    prof = np.concatenate([seg.points(4001) for seg in c.profile()])
    prof = prof[np.argsort(prof[:, 1], kind="stable")]
    z = np.linspace(prof[:, 1].min(), prof[:, 1].max(), 200001)
    rho = np.interp(z, *_monotone(prof))
    ref = float(np.sum(0.5 * (rho[1:] ** 2 + rho[:-1] ** 2) * np.diff(z)) * math.pi)
    assert abs(solid_volume(solid) - ref) < 1e-4 * ref


def _monotone(prof):
    """For each z keep the largest radius (profile points sorted by z): rho(z) of the solid."""
    zs, idx = np.unique(np.round(prof[:, 1], 9), return_index=True)
    rho = np.maximum.reduceat(prof[:, 0], idx)
    return zs, rho


@pytest.mark.parametrize("name", ["freeform_block.step", "mould_insert.step"])
def test_every_face_rebuilds_valid_with_its_area(name):
    """Every face of a part, holes included (the block's bottom face is a reversed plane with a round
    hole: its loops run clockwise and were rebuilt invalid before), rebuilds as a valid face of the same
    area within 2e-5 (adaptive integration: the default one is off by 1.4 % on a rational circle hole)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from machsurf_cad.occ import read_step_faces
    from machsurf_cad.occ.convert import face_from_surface

    faces = read_step_faces(ROOT / "example_parts" / name)
    for f in faces:
        topo = face_from_surface(f.surface, [list(lp) for lp in f.loops] or None)
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(topo, props, 1e-10)
        assert abs(props.Mass() - f.area) <= 2e-5 * f.area, (f.index, f.source_type)
