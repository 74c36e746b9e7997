"""Conversions between machsurf_cad's numpy B-spline types and OCCT (OCP) objects.

This subpackage is the only place that imports OCP/cadquery. Everything that leaves it
is plain numpy data (:class:`~machsurf_cad.geometry.BSplineSurface`, ...).
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepLib import BRepLib
from OCP.Geom import Geom_BSplineSurface
from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_TrimmedCurve
from OCP.Geom2dConvert import Geom2dConvert
from OCP.GeomConvert import GeomConvert
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.Precision import Precision
from OCP.ShapeFix import ShapeFix_Face
from OCP.TColgp import TColgp_Array1OfPnt2d, TColgp_Array2OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal, TColStd_Array2OfReal
from OCP.TopoDS import TopoDS, TopoDS_Face

from ..errors import InputError
from ..geometry import BSplineCurve, BSplineSurface
from ..geometry.face import close_loop


def _arr1(values, cls=TColStd_Array1OfReal):
    a = cls(1, len(values))
    for i, x in enumerate(values, 1):
        a.SetValue(i, float(x) if cls is TColStd_Array1OfReal else int(x))
    return a


def to_geom_surface(s: BSplineSurface) -> Geom_BSplineSurface:
    """OCCT ``Geom_BSplineSurface`` with the same poles, weights, knots and degrees."""
    nu, nv = s.shape
    poles = TColgp_Array2OfPnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            x, y, z = s.poles[i, j]
            poles.SetValue(i + 1, j + 1, gp_Pnt(float(x), float(y), float(z)))
    ku, mu = _arr1(s.knots_u), _arr1(s.mults_u, TColStd_Array1OfInteger)
    kv, mv = _arr1(s.knots_v), _arr1(s.mults_v, TColStd_Array1OfInteger)
    if s.weights is None:
        return Geom_BSplineSurface(poles, ku, kv, mu, mv, s.degree_u, s.degree_v, s.periodic_u, s.periodic_v)
    w = TColStd_Array2OfReal(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            w.SetValue(i + 1, j + 1, float(s.weights[i, j]))
    return Geom_BSplineSurface(poles, w, ku, kv, mu, mv, s.degree_u, s.degree_v, s.periodic_u, s.periodic_v)


def from_geom_surface(g, name: str = "") -> BSplineSurface:
    """numpy :class:`BSplineSurface` from any ``Geom_Surface`` (converted to B-spline by OCCT first)."""
    if not isinstance(g, Geom_BSplineSurface):
        g = GeomConvert.SurfaceToBSplineSurface_s(g)
    nu, nv = g.NbUPoles(), g.NbVPoles()
    poles = np.empty((nu, nv, 3))
    weights = np.empty((nu, nv))
    for i in range(1, nu + 1):
        for j in range(1, nv + 1):
            p = g.Pole(i, j)
            poles[i - 1, j - 1] = (p.X(), p.Y(), p.Z())
            weights[i - 1, j - 1] = g.Weight(i, j)
    ku = [g.UKnot(i) for i in range(1, g.NbUKnots() + 1)]
    mu = [g.UMultiplicity(i) for i in range(1, g.NbUKnots() + 1)]
    kv = [g.VKnot(i) for i in range(1, g.NbVKnots() + 1)]
    mv = [g.VMultiplicity(i) for i in range(1, g.NbVKnots() + 1)]
    rational = g.IsURational() or g.IsVRational()
    return BSplineSurface(
        g.UDegree(),
        g.VDegree(),
        ku,
        mu,
        kv,
        mv,
        poles,
        weights if rational else None,
        g.IsUPeriodic(),
        g.IsVPeriodic(),
        name,
    )


def to_geom2d_curve(c: BSplineCurve) -> Geom2d_BSplineCurve:
    if c.dim != 2:
        raise InputError("a 2-D (parameter-space) curve is needed")
    n = c.poles.shape[0]
    poles = TColgp_Array1OfPnt2d(1, n)
    for i, (x, y) in enumerate(c.poles, 1):
        poles.SetValue(i, gp_Pnt2d(float(x), float(y)))
    k, m = _arr1(c.knots), _arr1(c.mults, TColStd_Array1OfInteger)
    if c.weights is None:
        return Geom2d_BSplineCurve(poles, k, m, c.degree, c.periodic)
    return Geom2d_BSplineCurve(poles, _arr1(c.weights), k, m, c.degree, c.periodic)


def from_geom2d_curve(g) -> BSplineCurve:
    n = g.NbPoles()
    poles = np.array([[g.Pole(i).X(), g.Pole(i).Y()] for i in range(1, n + 1)])
    w = np.array([g.Weight(i) for i in range(1, n + 1)])
    k = [g.Knot(i) for i in range(1, g.NbKnots() + 1)]
    m = [g.Multiplicity(i) for i in range(1, g.NbKnots() + 1)]
    return BSplineCurve(g.Degree(), k, m, poles, w if g.IsRational() else None, g.IsPeriodic())


def pcurve_of_edge(edge, face) -> BSplineCurve:
    """The edge's parameter-space curve on ``face`` as a 2-D B-spline, oriented along the wire."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d

    c2d = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    adaptor = BRepAdaptor_Curve2d(edge, face)
    first, last = adaptor.FirstParameter(), adaptor.LastParameter()
    if c2d is None:
        raise InputError("an edge of the face has no curve in parameter space")
    trimmed = Geom2d_TrimmedCurve(c2d, first, last)
    bs = Geom2dConvert.CurveToBSplineCurve_s(trimmed)
    from OCP.TopAbs import TopAbs_REVERSED

    if edge.Orientation() == TopAbs_REVERSED:
        bs.Reverse()
    return from_geom2d_curve(bs)


def face_from_surface(surface: BSplineSurface, loops: list[list[BSplineCurve]] | None = None) -> TopoDS_Face:
    """A valid ``TopoDS_Face`` on ``surface``, natural bounds or trimmed by parameter-space loops.

    ``loops[0]`` is the outer loop, further loops are holes; each loop is a list of 2-D
    B-spline curves in the surface's (u, v) domain, joined end to end. Loops from other
    systems often have small gaps between their curves (CATIA: 3e-5 mm, Autodesk: 1e-3 mm):
    consecutive ends closer than 1e-3 of the loop's parameter size are joined at their mid
    point (:func:`close_loop`). Every edge gets a 3-D curve built at a tolerance that scales
    with the surface's size, its tolerance is raised to cover the measured distance between
    its 3-D curve and its curve on the surface (what OCCT's booleans check), and the face must
    pass ``BRepCheck_Analyzer``; an invalid face raises :class:`InputError`.
    """
    geom = to_geom_surface(surface)
    size = _size(surface)
    if not loops:
        u0, u1, v0, v1 = surface.bounds
        face = BRepBuilderAPI_MakeFace(geom, u0, u1, v0, v1, Precision.Confusion_s()).Face()
    else:
        wires = [_wire_on_surface(close_loop(loop)[0], geom, size) for loop in oriented_loops(loops)]
        mk = BRepBuilderAPI_MakeFace(geom, wires[0], True)
        for w in wires[1:]:
            mk.Add(w)
        if not mk.IsDone():
            raise InputError("could not build a trimmed face from the given loops")
        fixer = ShapeFix_Face(mk.Face())
        fixer.SetPrecision(_build_tolerance(size))
        fixer.Perform()
        face = TopoDS.Face_s(fixer.Face())
        settle_tolerances(face)
    check_valid(face, what=f"face '{surface.name}'")
    return face


def reversed_curve(c: BSplineCurve) -> BSplineCurve:
    """The same curve run backwards over the same parameter range."""
    a, b = c.bounds
    w = None if c.weights is None else np.asarray(c.weights)[::-1]
    return BSplineCurve(c.degree, (a + b) - np.asarray(c.knots)[::-1], np.asarray(c.mults)[::-1],
                        np.asarray(c.poles)[::-1], w, c.periodic)  # fmt: skip


def _signed_area(loop) -> float:
    pts = np.concatenate([c.evaluate(np.linspace(*c.bounds, 65))[:-1] for c in loop])
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def oriented_loops(loops) -> list[list[BSplineCurve]]:
    """Loops turned the way OCCT wants them on the surface's own orientation: the outer loop (the
    first) counter-clockwise in (u, v), holes clockwise. Loops read from a reversed face (its normal
    against ``su x sv``) run the other way; rebuilt as they were, the face is invalid
    (``BRepCheck_BadOrientationOfSubshape``, e.g. a block's bottom face with a hole)."""
    out = []
    for k, loop in enumerate(loops):
        loop = list(loop)
        area = _signed_area(loop)
        want_ccw = k == 0
        if (area > 0) != want_ccw and area != 0.0:
            loop = [reversed_curve(c) for c in reversed(loop)]
        out.append(loop)
    return out


def _size(surface: BSplineSurface) -> float:
    """Diagonal of the pole box (mm): the scale every build tolerance follows."""
    p = surface.poles.reshape(-1, 3)
    return float(max(np.linalg.norm(p.max(axis=0) - p.min(axis=0)), 1e-9))


def _build_tolerance(size: float) -> float:
    """3-D curve approximation tolerance of trimming edges: 1e-5 mm up to 1 m, then 1e-8 of the size."""
    return max(1e-5, 1e-8 * size)


def curve_on_surface_distance(edge, face, n: int = 33) -> float:
    """Largest distance (mm) between an edge's 3-D curve and its curve on the face, at ``n`` parameters."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface

    c3 = BRepAdaptor_Curve(edge)
    c2 = BRepAdaptor_Curve2d(edge, face)
    srf = BRepAdaptor_Surface(face, False)
    d = 0.0
    for t in np.linspace(c3.FirstParameter(), c3.LastParameter(), n):
        uv = c2.Value(float(t))
        d = max(d, c3.Value(float(t)).Distance(srf.Value(uv.X(), uv.Y())))
    return d


def settle_tolerances(face) -> float:
    """Raise each edge's tolerance to 1.5 times its measured curve-on-surface distance where it is
    smaller, and the vertices' to cover their edges; returns the largest edge tolerance (mm)."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    builder = BRep_Builder()
    worst = 0.0
    exp = TopExp_Explorer(face, TopAbs_EDGE)
    while exp.More():
        e = TopoDS.Edge_s(exp.Current())
        d = curve_on_surface_distance(e, face)
        tol = BRep_Tool.Tolerance_s(e)
        if d > tol:
            builder.UpdateEdge(e, 1.5 * d)
        worst = max(worst, BRep_Tool.Tolerance_s(e))
        exp.Next()
    BRepLib.UpdateTolerances_s(face, False)
    return worst


def _wire_on_surface(loop: list[BSplineCurve], geom, size: float = 100.0):
    mk = BRepBuilderAPI_MakeWire()
    tol = _build_tolerance(size)
    from OCP.GeomAbs import GeomAbs_C1

    for c in loop:
        e = BRepBuilderAPI_MakeEdge(to_geom2d_curve(c), geom).Edge()
        BRepLib.BuildCurves3d_s(e, tol, GeomAbs_C1, 14, 400)
        mk.Add(e)
    if not mk.IsDone():
        raise InputError("trimming loop is not closed or its curves do not join")
    return mk.Wire()


def to_cq_face(face) -> object:
    """A cadquery ``Face`` from a numpy :class:`~machsurf_cad.geometry.face.Face` (trimming kept)."""
    import cadquery as cq

    return cq.Face(face_from_surface(face.surface, [list(lp) for lp in face.loops] or None))


def check_valid(shape, what: str = "shape") -> None:
    """Raise :class:`InputError` if ``BRepCheck_Analyzer`` finds the shape invalid."""
    if not BRepCheck_Analyzer(shape).IsValid():
        raise InputError(f"{what} is not valid (BRepCheck_Analyzer)")


def is_valid(shape) -> bool:
    return bool(BRepCheck_Analyzer(shape).IsValid())
