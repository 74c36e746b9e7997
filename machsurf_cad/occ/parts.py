"""Example parts that need the kernel (booleans): a block with a trimmed free-form top face, and a
mould insert of 51 faces for 3-axis machining."""

from __future__ import annotations

import cadquery as cq
import numpy as np

from ..geometry import builders
from ..geometry.face import Face
from .convert import face_from_surface
from .step import face_record, iter_faces, write_step_shape


def freeform_top_surface():
    """Bicubic free-form surface over about 130 x 100 mm at z = 30..50 mm (the block's top)."""
    nu, nv = 7, 6
    x = np.linspace(-5.0, 135.0, nu)
    y = np.linspace(-5.0, 105.0, nv)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = 40 + 8 * np.sin(X / 140 * np.pi) * np.cos(Y / 110 * np.pi * 0.8) + 0.05 * X
    return builders.surface_from_grid(np.stack([X, Y, Z], axis=-1), 3, 3, name="freeform_top")


def freeform_block():
    """Solid block 120 x 90 mm with the free-form top, a through hole (D = 24 mm) and a corner cut.

    Returns ``(cadquery Shape, names)`` where ``names`` maps TopoDS faces to names; the top
    face is a trimmed B-spline face named ``freeform_top``.
    """
    top = face_from_surface(freeform_top_surface())
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Vec

    prism = cq.Shape.cast(BRepPrimAPI_MakePrism(top, gp_Vec(0, 0, -120)).Shape())
    box = cq.Solid.makeBox(120, 90, 200, pnt=cq.Vector(5, 5, -40))
    hole = cq.Solid.makeCylinder(12, 300, pnt=cq.Vector(70, 45, -150))
    notch = cq.Solid.makeCylinder(25, 300, pnt=cq.Vector(125, 95, -150))
    solid = prism.intersect(box).cut(hole).cut(notch).clean()
    from OCP.BRep import BRep_Tool
    from OCP.GeomAbs import GeomAbs_BSplineSurface
    from OCP.GeomAdaptor import GeomAdaptor_Surface

    names = [
        (f, "freeform_top")
        for f in iter_faces(solid.wrapped)
        if GeomAdaptor_Surface(BRep_Tool.Surface_s(f)).GetType() == GeomAbs_BSplineSurface and _is_top(f)
    ]
    return solid, names


def _is_top(face) -> bool:
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return props.CentreOfMass().Z() > 20.0


def write_freeform_block(path) -> list[Face]:
    """Write the block to STEP and return its faces as numpy :class:`Face` records."""
    solid, names = freeform_block()
    write_step_shape(path, solid.wrapped, names)
    return [face_record(f, i, "") for i, f in enumerate(iter_faces(solid.wrapped))]


def mould_insert():
    """A 100 x 80 x 25 mm mould insert of 51 faces for 3-axis work (cadquery solid).

    Rounded block (R 8 corners); a 60 x 44 x 10 mm pocket with R 5 corners and an R 3 floor fillet;
    four bosses D 10 x 7 mm with R 2 top fillets in the pocket; a slot 6 mm wide and 6 mm deep (narrower
    than a D 10 tool); a spherical dome (R 40) on one corner of the top (a flat spot at its crest)."""
    base = cq.Workplane("XY").box(100, 80, 25, centered=(True, True, False)).edges("|Z").fillet(8)
    base = base.faces(">Z").workplane().rect(60, 44).cutBlind(-10)
    part = base.edges(cq.selectors.BoxSelector((-31, -23, 14), (31, 23, 26))).edges("|Z").fillet(5)
    part = part.edges(cq.selectors.BoxSelector((-31, -23, 14.5), (31, 23, 15.5))).fillet(3)
    for x, y in [(-18, -10), (18, 10), (-18, 10), (18, -10)]:
        boss = cq.Workplane("XY").workplane(offset=15).center(x, y).circle(5).extrude(7).faces(">Z").edges().fillet(2)
        part = part.union(boss)
    part = part.cut(cq.Workplane("XY").workplane(offset=19).center(0, -33).rect(70, 6).extrude(10))
    dome = cq.Workplane("XY").sphere(40).translate((38, 30, 25 - 36))
    cap = dome.intersect(cq.Workplane("XY").box(30, 18, 20, centered=(True, True, False)).translate((38, 30, 25)))
    return part.union(cap).clean().val()


def write_mould_insert(path) -> list[Face]:
    """Write the mould insert to STEP and return its faces."""
    solid = mould_insert()
    write_step_shape(path, solid.wrapped, [])
    return [face_record(f, i, "") for i, f in enumerate(iter_faces(solid.wrapped))]
