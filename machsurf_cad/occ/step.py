"""STEP import/export and face inspection through OCCT."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
from OCP.BRepGProp import BRepGProp
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.GeomAdaptor import GeomAdaptor_Surface
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPConstruct import STEPConstruct
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.TCollection import TCollection_HAsciiString
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED, TopAbs_SHELL, TopAbs_SOLID, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Compound
from OCP.TopTools import TopTools_IndexedMapOfShape

from ..errors import InputError
from ..geometry.face import Face
from .convert import face_from_surface, from_geom_surface, pcurve_of_edge
from .quiet import quiet_occt

_SURFACE_TYPES = {
    0: "Plane",
    1: "Cylinder",
    2: "Cone",
    3: "Sphere",
    4: "Torus",
    5: "BezierSurface",
    6: "BSplineSurface",
    7: "SurfaceOfRevolution",
    8: "SurfaceOfExtrusion",
    9: "OffsetSurface",
    10: "OtherSurface",
}


def read_step_shape(path):
    """Read a STEP file; returns ``(shape, reader)``. Raises :class:`InputError` on any problem."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"STEP file not found: {p}")
    if p.stat().st_size == 0:
        raise InputError(f"STEP file is empty: {p}")
    reader = STEPControl_Reader()
    with quiet_occt():
        status = reader.ReadFile(str(p))
    if status != IFSelect_RetDone:
        raise InputError(f"could not read STEP file {p} (corrupt or not STEP)")
    with quiet_occt():
        n = reader.TransferRoots()
    if n == 0:
        raise InputError(f"STEP file {p} holds no transferable shape")
    shape = reader.OneShape()
    if shape.IsNull():
        raise InputError(f"STEP file {p} holds no shape")
    return shape, reader


def iter_faces(shape):
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        yield TopoDS.Face_s(exp.Current())
        exp.Next()


def face_record(face, index: int, name: str, body: int = -1) -> Face:
    """Convert one ``TopoDS_Face`` to a numpy :class:`Face` (NURBS-converted, trimming kept)."""
    surf = BRep_Tool.Surface_s(face)
    source_type = _SURFACE_TYPES.get(int(GeomAdaptor_Surface(surf).GetType()), "OtherSurface")
    nurbs = face
    if source_type != "BSplineSurface":
        conv = BRepBuilderAPI_NurbsConvert(face, False)
        nurbs = TopoDS.Face_s(conv.Shape())
        surf = BRep_Tool.Surface_s(nurbs)
    surface = from_geom_surface(surf, name=name)
    u0, u1, v0, v1 = BRepTools.UVBounds_s(nurbs)
    loops = []
    outer = BRepTools.OuterWire_s(nurbs)
    wires = [outer] + [TopoDS.Wire_s(w) for w in _iter(nurbs, TopAbs_WIRE) if not w.IsSame(outer)]
    for w in wires:
        loop = []
        wexp = BRepTools_WireExplorer(w, nurbs)
        while wexp.More():
            loop.append(pcurve_of_edge(wexp.Current(), nurbs))
            wexp.Next()
        if loop:
            loops.append(loop)
    # a face whose only loop runs along its parameter box is untrimmed: keep the plain form
    sb = surface.bounds
    natural = (
        len(loops) == 1
        and all(abs(a - b) < 1e-9 for a, b in zip((u0, u1, v0, v1), sb))
        and all(_on_box(c, sb) for c in loops[0])
    )
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return Face(
        surface,
        () if natural else tuple(tuple(lp) for lp in loops),
        name,
        index,
        face.Orientation() == TopAbs_REVERSED,
        source_type,
        (u0, u1, v0, v1),
        float(props.Mass()),
        body,
    )


def _on_box(curve, box, tol=1e-9) -> bool:
    import numpy as np

    uv = curve.evaluate(np.linspace(*curve.bounds, 7))
    u0, u1, v0, v1 = box
    return bool(
        np.all(np.isclose(uv[:, 0], u0, atol=tol))
        or np.all(np.isclose(uv[:, 0], u1, atol=tol))
        or np.all(np.isclose(uv[:, 1], v0, atol=tol))
        or np.all(np.isclose(uv[:, 1], v1, atol=tol))
    )


def _iter(shape, kind):
    exp = TopExp_Explorer(shape, kind)
    while exp.More():
        yield exp.Current()
        exp.Next()


def _bodies(shape) -> list:
    """The face maps of the shape's solids, in file order."""
    maps = []
    for solid in _iter(shape, TopAbs_SOLID):
        m = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(solid, TopAbs_FACE, m)
        maps.append(m)
    return maps


def _named_faces(path):
    """``[(TopoDS_Face, name, body)]`` of a STEP file, in file order (names from the faces' entities; body:
    the index of the solid the face bounds, -1 if none)."""
    shape, reader = read_step_shape(path)
    tr = reader.WS().TransferReader()
    bodies = _bodies(shape)
    out = []
    for i, f in enumerate(iter_faces(shape)):
        ent = tr.EntityFromShapeResult(f, -1)
        name = ""
        if ent is not None and hasattr(ent, "Name") and ent.Name() is not None:
            name = ent.Name().ToCString()
        body = next((k for k, m in enumerate(bodies) if m.Contains(f)), -1)
        out.append((f, name or f"face_{i}", body))
    if not out:
        raise InputError(f"STEP file {path} holds no faces")
    return out


def from_cq_face(cq_face, name: str = "") -> Face:
    """A numpy :class:`~machsurf_cad.geometry.face.Face` from a cadquery ``Face`` (NURBS-converted)."""
    return face_record(cq_face.wrapped, -1, name or "face")


def read_step_faces(path, indices=None) -> list[Face]:
    """Faces of a STEP file as numpy :class:`Face` objects, with their index and name.

    Any surface type is converted to NURBS by the kernel (``BRepBuilderAPI_NurbsConvert``);
    parameter bounds and trimming loops are kept. Unnamed faces are called ``face_<index>``.
    With ``indices`` only those faces are converted (conversion is the costly part: a cylinder
    with 200 edges takes seconds); an index out of range raises with the face count.
    """
    from ..checks import index

    named = _named_faces(path)
    indices = range(len(named)) if indices is None else [index("face index", i) for i in indices]
    out = []
    for i in indices:
        if not 0 <= int(i) < len(named):
            names = ", ".join(f"{k} {n}" for k, (_, n, _) in enumerate(named[:8])) + (", ..." if len(named) > 8 else "")
            raise InputError(
                f"face index {i} out of range: {path} has {len(named)} face(s) (0..{len(named) - 1}: {names}); "
                "`machsurf info` lists them"
            )
        f, name, body = named[int(i)]
        out.append(face_record(f, int(i), name, body))
    return out


def read_step_face(path, index: int) -> Face:
    """Face ``index`` of a STEP file (only that face is converted to NURBS)."""
    return read_step_faces(path, [index])[0]


def step_face_summaries(path) -> list[dict]:
    """What ``info`` shows of every face, without converting any to NURBS: index, name, surface type,
    degrees and poles (B-spline and Bezier faces only), loops, uv bounds, area (mm^2), orientation."""
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface

    rows = []
    for i, (f, name, body) in enumerate(_named_faces(path)):
        surf = BRep_Tool.Surface_s(f)
        kind = _SURFACE_TYPES.get(int(GeomAdaptor_Surface(surf).GetType()), "OtherSurface")
        deg = poles = None
        rational = False
        if isinstance(surf, (Geom_BSplineSurface, Geom_BezierSurface)):
            deg = [surf.UDegree(), surf.VDegree()]
            poles = [surf.NbUPoles(), surf.NbVPoles()]
            rational = bool(surf.IsURational() or surf.IsVRational())
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f)
        n_wires = sum(1 for _ in _iter(f, TopAbs_WIRE))
        su0, su1, sv0, sv1 = surf.Bounds()
        natural = n_wires == 1 and all(abs(a - b) < 1e-9 for a, b in zip((u0, u1, v0, v1), (su0, su1, sv0, sv1)))
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(f, props)
        rows.append(
            {
                "index": i,
                "name": name,
                "source_type": kind,
                "degrees": deg,
                "poles": poles,
                "rational": rational,
                "n_loops": n_wires,
                "trimmed": not natural,
                "uv_bounds": [u0, u1, v0, v1],
                "area_mm2": float(props.Mass()),
                "reversed": f.Orientation() == TopAbs_REVERSED,
                "body": body,
            }
        )
    return rows


def write_step(
    path, faces: list[Face], *, extra_shapes: list | None = None, author: str = "", organization: str = ""
) -> Path:
    """Write faces (and optional named solids, e.g. cutters) to a STEP AP214 file, each face named.

    Surfaces are written as B_SPLINE_SURFACE_WITH_KNOTS (never OFFSET_SURFACE) so that any CAM
    system reads them. The file holds one product named like the file, without assembly
    structure (FreeCAD 0.20 crashes on OCCT's default assembly of several faces, and on several
    products), and each face sits in its own shell; faces and shells carry the face's name (the
    shells' names are what FreeCAD shows). ``extra_shapes`` holds ``(TopoDS_Shape, name)`` pairs. The header
    names machsurf_cad and its version as the originating system, and ``author``/``organization``.
    The file is written under a temporary name and moved into place: a failure leaves no
    half-written file.

    Raises
    ------
    InputError
        No face to write, an invalid face, or OCCT failing to write.
    """
    if not faces and not extra_shapes:
        raise InputError(f"nothing to write to {path}: no face")
    from OCP.TopoDS import TopoDS_Shell

    builder = BRep_Builder()
    comp = TopoDS_Compound()
    builder.MakeCompound(comp)
    named = []
    for f in faces:
        tf = face_from_surface(f.surface, [list(loop) for loop in f.loops] or None)
        shell = TopoDS_Shell()  # each face in its own named shell: FreeCAD labels shells, not faces
        builder.MakeShell(shell)
        builder.Add(shell, tf)
        name = f.name or f.surface.name or "face"
        builder.Add(comp, shell)
        named += [(tf, name), (shell, name)]
    for shape, name in extra_shapes or []:
        builder.Add(comp, shape)
        named.append((shape, name))
    product = Path(path).stem
    return write_step_shapes(path, [(comp, product)], sub_names=named, author=author, organization=organization)


def write_step_shape(path, shape, named: list | None = None) -> Path:
    """Write one shape to STEP AP214 (mm), naming the listed sub-shapes ``(TopoDS_Shape, name)``."""
    return write_step_shapes(path, [(shape, Path(path).stem)], sub_names=named or [])


def write_step_shapes(
    path, shapes: list, *, sub_names: list | None = None, author: str = "", organization: str = ""
) -> Path:
    """Write ``(shape, name)`` pairs to STEP AP214 (mm), each shape a product of that name, no assembly
    structure; ``sub_names`` names sub-shapes (faces, shells) inside them."""
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader

    from .._version import __version__

    path = Path(path)
    writer = STEPControl_Writer()
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    Interface_Static.SetIVal_s("write.step.assembly", 0)
    for shape, name in shapes:
        Interface_Static.SetCVal_s("write.step.product.name", name or "shape")
        with quiet_occt():
            status = writer.Transfer(shape, STEPControl_AsIs)
        if status != IFSelect_RetDone:
            raise InputError(f"OCCT could not translate {name!r} to STEP for {path}")
    fp = writer.WS().TransferWriter().FinderProcess()
    for sub, name in list(shapes) + list(sub_names or []):
        item = STEPConstruct.FindEntity_s(fp, sub)
        if item is not None and name:
            item.SetName(TCollection_HAsciiString(name))
    from OCP.StepBasic import StepBasic_Product

    model = writer.Model()
    products = [model.Value(i) for i in range(1, model.NbEntities() + 1)]
    products = [e for e in products if isinstance(e, StepBasic_Product)]
    if len(products) == len(shapes):  # OCCT appends " 1", " 2"...: give each product its exact name
        for prod, (_, name) in zip(products, shapes):
            prod.SetName(TCollection_HAsciiString(name or "shape"))
            prod.SetId(TCollection_HAsciiString(name or "shape"))
    shell_names = [name for sub, name in sub_names or [] if sub.ShapeType() == TopAbs_SHELL]
    from OCP.StepShape import StepShape_OpenShell

    shells = [model.Value(i) for i in range(1, model.NbEntities() + 1)]
    shells = [e for e in shells if isinstance(e, StepShape_OpenShell)]
    if len(shells) == len(shell_names):
        for sh, name in zip(shells, shell_names):
            sh.SetName(TCollection_HAsciiString(name))
    header = APIHeaderSection_MakeHeader(model)
    system = TCollection_HAsciiString(f"machsurf_cad {__version__}")
    header.SetOriginatingSystem(system)
    header.SetPreprocessorVersion(system)
    header.SetAuthorValue(1, TCollection_HAsciiString(author or "machsurf_cad user"))
    header.SetOrganizationValue(1, TCollection_HAsciiString(organization or "unspecified"))
    header.SetName(TCollection_HAsciiString(path.name))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".step", dir=str(path.parent))
    os.close(fd)
    try:
        with quiet_occt():
            ok = writer.Write(tmp) == IFSelect_RetDone
        if not ok:
            raise InputError(f"OCCT failed to write STEP file {path}")
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
