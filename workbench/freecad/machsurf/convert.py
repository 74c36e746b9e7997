"""FreeCAD Part geometry <-> machsurf_cad numpy types, as B-spline arrays only."""

import FreeCAD
import numpy as np
import Part

from machsurf_cad.errors import InputError
from machsurf_cad.geometry import BSplineCurve, BSplineSurface
from machsurf_cad.geometry.face import Face


def _surface_arrays(bs, name=""):
    if bs.isUPeriodic() or bs.isVPeriodic():
        # OCCT's periodic knot vectors (the poles wrap) read as arrays describe another surface (a converted
        # cylinder was off by 2.6 mm): the same surface as a clamped B-spline, same parametrisation
        bs = bs.copy()
        if bs.isUPeriodic():
            bs.setUNotPeriodic()
        if bs.isVPeriodic():
            bs.setVNotPeriodic()
    poles = np.array([[[p.x, p.y, p.z] for p in row] for row in bs.getPoles()])
    w = np.array(bs.getWeights(), dtype=float)
    rational = bool(bs.isURational() or bs.isVRational())
    return BSplineSurface(
        bs.UDegree,
        bs.VDegree,
        bs.getUKnots(),
        bs.getUMultiplicities(),
        bs.getVKnots(),
        bs.getVMultiplicities(),
        poles,
        w if rational else None,
        bool(bs.isUPeriodic()),
        bool(bs.isVPeriodic()),
        name,
    )


def _connect(loop, bounds):
    """A seam edge (a closed surface's boundary, used twice in the wire) gives the same 2-D curve both times,
    on one side of the parameter range: each curve of the loop that does not start where the previous one
    ends is moved by the period (u1 - u0 or v1 - v0) when that joins them."""
    u0, u1, v0, v1 = bounds
    tol = 1e-6 * max(1.0, abs(u1 - u0), abs(v1 - v0))
    out = list(loop)
    for k in range(len(out)):
        prev_end = out[k - 1].evaluate(np.array([out[k - 1].bounds[1]]))[0] if k else None
        if prev_end is None:
            continue
        c = out[k]
        start = c.evaluate(np.array([c.bounds[0]]))[0]
        if np.linalg.norm(start - prev_end) <= tol:
            continue
        for shift in ((u1 - u0, 0.0), (u0 - u1, 0.0), (0.0, v1 - v0), (0.0, v0 - v1)):
            if np.linalg.norm(start + shift - prev_end) <= tol:
                out[k] = BSplineCurve(c.degree, c.knots, c.mults, c.poles + np.array(shift), c.weights)
                break
    return out


def _on_side(c, bounds, tol=1e-9):
    """Whether a 2-D trimming curve lies on one side of the parameter rectangle (its poles do)."""
    u0, u1, v0, v1 = bounds
    pu, pv = c.poles[:, 0], c.poles[:, 1]
    scale = tol * max(1.0, abs(u1 - u0), abs(v1 - v0))
    return any(np.all(np.abs(x - t) <= scale) for x, t in ((pu, u0), (pu, u1), (pv, v0), (pv, v1)))


def face_to_numpy(face, name="F"):
    """A Part.Face (any surface type: converted to NURBS) as a machsurf_cad Face with its trimming."""
    if not isinstance(face, Part.Face):
        raise InputError("select a face (not an edge, vertex or solid)")
    f = face
    if not isinstance(f.Surface, Part.BSplineSurface):
        f = face.toNurbs().Faces[0]
    surf = _surface_arrays(f.Surface, name)
    u0, u1, v0, v1 = f.ParameterRange
    loops = []
    outer = f.OuterWire
    wires = [outer] + [w for w in f.Wires if not w.isSame(outer)]
    for w in wires:
        loop = []
        for e in w.OrderedEdges if hasattr(w, "OrderedEdges") else w.Edges:
            c2d, first, last = f.curveOnSurface(e)
            bs = c2d.toBSpline(first, last)
            if bs.isPeriodic():
                bs.setNotPeriodic()
            m = bs.getMultiplicities()
            if m[0] <= bs.Degree or m[-1] <= bs.Degree:  # a closed curve's knots (a hole's circle): clamp
                bs.segment(bs.FirstParameter, bs.LastParameter)
            poles = np.array([[p.x, p.y] for p in bs.getPoles()])
            weights = np.array(bs.getWeights(), dtype=float)
            c = BSplineCurve(
                bs.Degree, bs.getKnots(), bs.getMultiplicities(), poles, weights if bs.isRational() else None, False
            )
            if e.Orientation == "Reversed":
                c = BSplineCurve(
                    c.degree,
                    (c.knots[-1] + c.knots[0]) - c.knots[::-1],
                    c.mults[::-1],
                    c.poles[::-1],
                    None if c.weights is None else c.weights[::-1],
                )
            loop.append(c)
        loops.append(_connect(loop, (u0, u1, v0, v1)))
    sb = surf.bounds
    # untrimmed only when the one loop runs along the four sides of the parameter rectangle (a 4-edge loop
    # with a curved side, e.g. a cylinder cut by a free-form top, is a trimmed face)
    natural = (
        len(loops) == 1
        and all(abs(a - b) < 1e-9 for a, b in zip((u0, u1, v0, v1), sb))
        and len(loops[0]) == 4
        and all(_on_side(c, (u0, u1, v0, v1)) for c in loops[0])
    )
    return Face(
        surf,
        () if natural else tuple(tuple(lp) for lp in loops),
        name,
        -1,
        f.Orientation == "Reversed",
        type(face.Surface).__name__,
        (u0, u1, v0, v1),
        float(face.Area),
    )


def surface_to_part(s):
    """A Part.BSplineSurface from a machsurf_cad BSplineSurface (buildFromPolesMultsKnots)."""
    bs = Part.BSplineSurface()
    poles = [[FreeCAD.Vector(*map(float, p)) for p in row] for row in s.poles]
    weights = None if s.weights is None else [[float(w) for w in row] for row in s.weights]
    args = (
        poles,
        [int(m) for m in s.mults_u],
        [int(m) for m in s.mults_v],
        [float(k) for k in s.knots_u],
        [float(k) for k in s.knots_v],
        bool(s.periodic_u),
        bool(s.periodic_v),
        int(s.degree_u),
        int(s.degree_v),
    )
    if weights is None:
        bs.buildFromPolesMultsKnots(*args)
    else:
        bs.buildFromPolesMultsKnots(*args, weights)
    return bs


def face_to_part(face):
    """A Part.Face from a machsurf_cad Face: natural bounds, or the same trimming loops."""
    bs = surface_to_part(face.surface)
    if not face.loops:
        u0, u1, v0, v1 = face.surface.bounds
        return bs.toShape(u0, u1, v0, v1)
    from machsurf_cad.geometry.face import close_loop

    wires = []
    for loop in face.loops:
        edges = []
        for c in close_loop(loop)[0]:  # a STEP loop's gaps (3.4e-5 mm from CATIA) closed at their mid points
            g = Part.Geom2d.BSplineCurve2d()
            poles = [FreeCAD.Base.Vector2d(float(x), float(y)) for x, y in c.poles]
            if c.weights is None:
                g.buildFromPolesMultsKnots(
                    poles, [int(m) for m in c.mults], [float(k) for k in c.knots], False, int(c.degree)
                )
            else:
                g.buildFromPolesMultsKnots(
                    poles,
                    [int(m) for m in c.mults],
                    [float(k) for k in c.knots],
                    False,
                    int(c.degree),
                    [float(w) for w in c.weights],
                )
            edges.append(g.toShape(bs, *c.bounds))
        wires.append(Part.Wire(edges))
    f = Part.Face(bs, wires[0])
    for w in wires[1:]:
        f.cutHoles([w]) if hasattr(f, "cutHoles") else None
    f.validate()
    return f
