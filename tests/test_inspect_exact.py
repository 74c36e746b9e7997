"""``inspect`` is exact on trimmed faces: every candidate point's distance to the trimmed nominal face
(interior foot inside the loops, or the nearest boundary point) equals OCCT's BRepExtrema_DistShapeShape
(point vertex against the nominal ``TopoDS_Face``) within 1e-4 mm.

Faces are built here with OCP (a free-form face with a hole, a periodic tube with a seam cut by a free-form
curve, a dome with a pole) and offset by +0.05 mm along their outward normal (``Geom_OffsetSurface``
approximated, checked against the offset surface at the same parameters), so every candidate point of
the offset face lies 0.05 mm from the nominal face."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, needs_kernel

pytestmark = needs_kernel
OFFSET = 0.05
TOL = 1e-4  # mm: inspect against BRepExtrema, and against the known offset


# --- faces built with OCP -------------------------------------------------------------------------


def _bspline(poles: np.ndarray, degree=(3, 3), periodic_u: bool = False):
    """``Geom_BSplineSurface`` on uniform knots over [0, 1]^2 (clamped, or periodic in u)."""
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt
    from OCP.TColgp import TColgp_Array2OfPnt
    from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal

    def arr(vals, cls=TColStd_Array1OfReal):
        a = cls(1, len(vals))
        for i, x in enumerate(vals, 1):
            a.SetValue(i, x)
        return a

    def knots(n, d, periodic):
        if periodic:
            return list(np.linspace(0, 1, n + 1)), [1] * (n + 1)
        k = list(np.linspace(0, 1, n - d + 1))
        return k, [d + 1] + [1] * (len(k) - 2) + [d + 1]

    nu, nv, _ = poles.shape
    pts = TColgp_Array2OfPnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            pts.SetValue(i + 1, j + 1, gp_Pnt(*map(float, poles[i, j])))
    ku, mu = knots(nu, degree[0], periodic_u)
    kv, mv = knots(nv, degree[1], False)
    int_arr = TColStd_Array1OfInteger
    return Geom_BSplineSurface(
        pts, arr(ku), arr(kv), arr(mu, int_arr), arr(mv, int_arr), degree[0], degree[1], periodic_u, False
    )


def _interp2d(points, periodic: bool):
    from OCP.Geom2dAPI import Geom2dAPI_Interpolate
    from OCP.gp import gp_Pnt2d
    from OCP.TColgp import TColgp_HArray1OfPnt2d

    h = TColgp_HArray1OfPnt2d(1, len(points))
    for i, (x, y) in enumerate(points, 1):
        h.SetValue(i, gp_Pnt2d(float(x), float(y)))
    it = Geom2dAPI_Interpolate(h, periodic, 1e-9)
    it.Perform()
    return it.Curve()


def _face(surface, loops):
    """A valid ``TopoDS_Face`` on ``surface`` bounded by loops of parameter-space curves (the first the
    outer one), each edge with a 3-D curve built to 1e-7 mm; ShapeFix adds a seam where one is missing."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepLib import BRepLib
    from OCP.ShapeFix import ShapeFix_Face
    from OCP.TopoDS import TopoDS

    wires = []
    for loop in loops:
        mk = BRepBuilderAPI_MakeWire()
        for c in loop:
            e = BRepBuilderAPI_MakeEdge(c, surface).Edge()
            BRepLib.BuildCurves3d_s(e, 1e-7)
            mk.Add(e)
        wires.append(mk.Wire())
    mk = BRepBuilderAPI_MakeFace(surface, wires[0], True)
    for w in wires[1:]:
        mk.Add(w)
    fix = ShapeFix_Face(mk.Face())
    fix.Perform()
    face = TopoDS.Face_s(fix.Face())
    assert BRepCheck_Analyzer(face).IsValid()
    return face


def _offset(surface, distance: float):
    """The surface offset by ``distance`` along ``su x sv``, as a B-spline within 1e-6 mm of OCCT's
    offset surface at the same parameters (checked on a 61 x 61 grid, not taken from MaxError)."""
    from OCP.Geom import Geom_OffsetSurface
    from OCP.GeomAbs import GeomAbs_C1
    from OCP.GeomConvert import GeomConvert_ApproxSurface

    off = Geom_OffsetSurface(surface, distance, True)
    s = GeomConvert_ApproxSurface(off, 1e-7, GeomAbs_C1, GeomAbs_C1, 9, 9, 1000, 1).Surface()
    if surface.IsUPeriodic():
        s.SetUPeriodic()  # closed: the seam of the candidate face stays a seam
    if surface.IsVPeriodic():
        s.SetVPeriodic()
    u0, u1, v0, v1 = off.Bounds()
    grid = [(u, v) for u in np.linspace(u0, u1, 61) for v in np.linspace(v0, v1, 61)]
    err = max(off.Value(u, v).Distance(s.Value(u, v)) for u, v in grid)
    assert err < 1e-6, f"offset approximation off by {err:.3g} mm"
    return s


def _holed_freeform(surface):
    """A wavy free-form face trimmed by a free-form outer loop, with a circular hole."""
    from OCP.Geom2d import Geom2d_Circle
    from OCP.gp import gp_Ax22d, gp_Dir2d, gp_Pnt2d

    th = np.linspace(0, 2 * np.pi, 13)[:-1]
    r = 1 + 0.15 * np.sin(3 * th)
    outer = _interp2d(np.c_[0.5 + 0.4 * r * np.cos(th), 0.5 + 0.38 * r * np.sin(th)], True)
    hole = Geom2d_Circle(gp_Ax22d(gp_Pnt2d(0.55, 0.45), gp_Dir2d(1, 0), gp_Dir2d(0, -1)), 0.1)  # clockwise
    return _face(surface, [[outer], [hole]])


def _holed_freeform_surface():
    x, y = np.meshgrid(np.linspace(0, 100, 9), np.linspace(0, 80, 9), indexing="ij")
    z = 8 * np.sin(x / 25) * np.cos(y / 20) + 0.002 * (x - 50) ** 2
    return _bspline(np.stack([x, y, z], -1))


def _tube(surface):
    """A periodic tube between the iso v = 0.1 and a free-form curve across the whole period (the face
    closes on itself: its loops run along the seam u = 0 = 1)."""
    from OCP.Geom2d import Geom2d_Line, Geom2d_TrimmedCurve
    from OCP.gp import gp_Dir2d, gp_Pnt2d

    us = np.linspace(1, 0, 17)
    top = _interp2d(np.c_[us, 0.75 + 0.12 * np.sin(4 * np.pi * us) + 0.05 * np.cos(2 * np.pi * us)], False)
    bottom = Geom2d_TrimmedCurve(Geom2d_Line(gp_Pnt2d(0, 0.1), gp_Dir2d(1, 0)), 0.0, 1.0)
    return _face(surface, [[bottom], [top]])


def _tube_surface():
    a, z = np.meshgrid(np.linspace(0, 2 * np.pi, 9)[:-1], np.linspace(0, 60, 6), indexing="ij")
    r = 30 + 4 * np.sin(2 * a) + 3 * np.cos(a + z / 20)
    return _bspline(np.stack([r * np.cos(a), r * np.sin(a), z], -1), periodic_u=True)


def _dome_surface():
    """A free-form dome over 220 degrees whose edge v = 1 is a single point (a pole)."""
    a, t = np.meshgrid(np.linspace(0, np.radians(220), 7), np.linspace(0, 1, 5), indexing="ij")
    rad = 40 * (1 - t**1.5) * (1 + 0.1 * np.sin(2 * a))
    z = 30 * np.sin(t * np.pi / 2) + 2 * np.cos(a) * (1 - t)
    z[:, -1] = 30.0
    return _bspline(np.stack([rad * np.cos(a), rad * np.sin(a), z], -1))


def _natural(surface):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    return BRepBuilderAPI_MakeFace(surface, 1e-7).Face()


CASES = {
    "holed_freeform": (_holed_freeform_surface, _holed_freeform),
    "periodic_tube_with_seam": (_tube_surface, _tube),
    "dome_with_pole": (_dome_surface, _natural),
}


# --- measuring ------------------------------------------------------------------------------------


def _write(path: Path, tface) -> Path:
    from machsurf_cad.occ.step import write_step_shape

    return write_step_shape(path, tface)


def _step_face(path: Path, index: int = 0):
    """The ``TopoDS_Face`` ``index`` of a STEP file, in the order inspect reads faces."""
    from machsurf_cad.occ.step import iter_faces, read_step_shape

    return list(iter_faces(read_step_shape(path)[0]))[index]


def brep_distances(tface, points) -> np.ndarray:
    """BRepExtrema_DistShapeShape of each point (as a vertex) to the face, mm."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.gp import gp_Pnt

    out = np.empty(len(points))
    for i, p in enumerate(points):
        ds = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, p))).Vertex(), tface)
        assert ds.IsDone()
        out[i] = ds.Value()
    return out


def _checked(signed: np.ndarray, n: int = 300) -> np.ndarray:
    """About ``n`` strided points plus the 10 smallest and 10 largest readings."""
    order = np.argsort(signed)
    return np.unique(np.r_[np.arange(0, signed.size, max(1, signed.size // n)), order[:10], order[-10:]])


def _inspect(nominal: Path, candidate: Path, out: Path, face: int = 0, samples: int = 120):
    from machsurf_cad.jobs import InspectJob, run_job

    job = InspectJob(
        nominal=str(nominal), candidate=str(candidate), face=face, candidate_face=0, samples=samples, render=False
    )
    return run_job(job, out)


def _assert_matches_brep(signed, points, tface, what: str, n: int = 300) -> None:
    sel = _checked(signed, n)
    occ = brep_distances(tface, points[sel])
    diff = np.abs(np.abs(signed[sel]) - occ)
    k = int(np.argmax(diff))
    assert diff[k] <= TOL, f"{what}: inspect {signed[sel][k]:.6f} vs BRepExtrema {occ[k]:.6f} at {points[sel][k]}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_offset_face_reads_its_offset_and_matches_brepextrema(tmp_path, case):
    make_surface, make_face = CASES[case]
    surface = make_surface()
    nominal = _write(tmp_path / "nominal.step", make_face(surface))
    candidate = _write(tmp_path / "candidate.step", make_face(_offset(surface, OFFSET)))
    out = _inspect(nominal, candidate, tmp_path / "inspect")
    res = out.result
    dev = out.report["deviation"]
    assert abs(dev["max_mm"] - OFFSET) <= TOL and abs(dev["min_mm"] - OFFSET) <= TOL, dev
    assert np.abs(res.signed - OFFSET).max() <= TOL
    assert dev["n_not_converged"] == 0
    _assert_matches_brep(res.signed, res.points, _step_face(nominal), case)


@pytest.mark.parametrize("case", sorted(CASES))
def test_points_all_around_match_brepextrema(tmp_path, case):
    """Points up to 15 mm off the surface, over and beyond the face (trimmed away regions, holes, past
    the seam and the pole): several local feet, feet on the loops; the distance is BRepExtrema's."""
    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_face

    make_surface, make_face = CASES[case]
    path = _write(tmp_path / "nominal.step", make_face(make_surface()))
    face = read_step_face(path, 0)
    u0, u1, v0, v1 = face.surface.bounds
    pts = []
    for seed in (0, 1, 2):
        rng = np.random.default_rng(seed)
        uv = rng.uniform([u0, v0], [u1, v1], (600, 2))
        props = ms.local_properties(face.surface, uv[:, 0], uv[:, 1])
        pts.append(props.point + rng.uniform(-15, 15, (600, 1)) * props.normal + rng.normal(scale=2.0, size=(600, 3)))
    pts = np.concatenate(pts)
    d = ms.deviation(face, pts)
    occ = brep_distances(_step_face(path), pts)
    diff = np.abs(np.abs(d.signed) - occ)
    k = int(np.argmax(diff))
    assert diff[k] <= TOL, f"{case}: {d.signed[k]:.6f} vs BRepExtrema {occ[k]:.6f} at {pts[k]}"
    if face.is_trimmed:
        assert d.outside_trim.sum() > 10  # some points are nearest to a loop


def test_cli_inspect_reads_the_offset_of_a_holed_face(tmp_path):
    import json

    from helpers import run

    surface = _holed_freeform_surface()
    nominal = _write(tmp_path / "nominal.step", _holed_freeform(surface))
    candidate = _write(tmp_path / "candidate.step", _holed_freeform(_offset(surface, OFFSET)))
    r = run("inspect", nominal, candidate, "--candidate-face", "0", "--no-render", "-o", tmp_path / "o")
    assert r.returncode == 0, r.stderr
    dev = json.loads((tmp_path / "o" / "report.json").read_text())["deviation"]
    assert abs(dev["max_mm"] - OFFSET) <= TOL and abs(dev["min_mm"] - OFFSET) <= TOL
    assert f"{dev['max_abs_mm']:.6g}" in r.stdout


# --- the shared real parts (not in the repository) ------------------------------------------------


def _real_parts() -> Path | None:
    for d in (Path("/work/shared/real-parts"), ROOT.parent / "shared" / "real-parts"):
        if (d / "turbo3d_impeller.step").is_file():
            return d
    return None


REAL = _real_parts()
needs_real_parts = pytest.mark.skipif(REAL is None, reason="shared/real-parts (public STEP parts) not present")


@needs_real_parts
def test_impeller_face87_against_the_shared_offset_file_matches_brepextrema(tmp_path):
    """The reported case: ``inspect`` read 0.018..1.018 mm, worst at uv (0.0001, 0). Face 87 is periodic in
    v (a closed surface of revolution, seam at v = 0 = 1); points just before the seam were stopped on the
    edge v = 0 (distance to the seam curve, up to 1.018 mm) instead of crossing to their foot at v ~ 0.997.

    Note: the shared derived file is not a uniform 0.05 mm offset: its surface (degree 10 x 11) is up to
    0.43 mm from face 87's offset surface at the same parameters, and BRepExtrema itself reads
    0.0180..0.0568 mm on it (GeomConvert_ApproxSurface C2 degree 11 makes such a surface while reporting
    a MaxError of 2e-7 mm). inspect must read what BRepExtrema reads; the next test reads 0.0500 on an
    offset of face 87 checked against the offset surface."""
    cand = REAL / "derived" / "turbo3d_impeller_face87_offset005.step"
    out = _inspect(REAL / "turbo3d_impeller.step", cand, tmp_path / "o", face=87, samples=200)
    res = out.result
    assert res.signed.max() < 0.06  # was 1.018
    _assert_matches_brep(res.signed, res.points, _step_face(REAL / "turbo3d_impeller.step", 87), "face 87", 300)
    # the corner of the old worst reading: u = 0 side, next to the seam
    near = np.argsort(np.linalg.norm(res.points - [50.0976, 1.9734, 1.0173], axis=1))[:50]
    occ = brep_distances(_step_face(REAL / "turbo3d_impeller.step", 87), res.points[near])
    assert np.abs(np.abs(res.signed[near]) - occ).max() <= TOL


@needs_real_parts
def test_impeller_face87_reads_a_checked_offset_as_0050_everywhere(tmp_path):
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED

    nominal = REAL / "turbo3d_impeller.step"
    tface = _step_face(nominal, 87)
    sign = -1.0 if tface.Orientation() == TopAbs_REVERSED else 1.0  # along the outward normal
    cand = _write(tmp_path / "offset.step", _natural(_offset(BRep_Tool.Surface_s(tface), sign * OFFSET)))
    res = _inspect(nominal, cand, tmp_path / "o", face=87, samples=200).result
    assert np.abs(res.signed - OFFSET).max() <= TOL
    _assert_matches_brep(res.signed, res.points, tface, "face 87 offset", 200)
