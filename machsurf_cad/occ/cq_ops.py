"""cadquery entry points: from a face to its machining surfaces in one call, and 3-axis tool paths
on several faces of a cadquery solid (exact drop-cutter on the B-rep).

Examples
--------
>>> import cadquery as cq
>>> from machsurf_cad.occ.cq_ops import machining_surface_faces, machining_surface_op
>>> from machsurf_cad.occ import to_cq_face
>>> from machsurf_cad.geometry.face import Face
>>> from machsurf_cad import examples
>>> face = to_cq_face(Face(examples.bezier5_patch()))
>>> s1, s2, ms = machining_surface_faces(face, "bull:D=28,r=4", lead=20)
>>> s1.isValid() and s2.isValid() and ms.s1_fit.max_error <= 1e-3
True
>>> wp = cq.Workplane().add(face).invoke(machining_surface_op("ball:D=10", lead=10))
>>> len(wp.vals())
2
"""

from __future__ import annotations

import cadquery as cq

from ..machining import machining_surface
from .convert import to_cq_face
from .step import from_cq_face


def machining_surface_faces(face: cq.Face, tool, **kwargs):
    """S1 and S2 of a cadquery Face as cadquery Faces (trimmed like the input), plus the result.

    Keyword arguments are those of :func:`machsurf_cad.machining.machining_surface`
    (mm, degrees). ``S2`` is None for 3 axes.
    """
    ms = machining_surface(from_cq_face(face, "F"), tool, **kwargs)
    out = [to_cq_face(f) for f in ms.faces()]
    return out[0], (out[1] if len(out) > 1 else None), ms


def machining_surface_op(tool, **kwargs):
    """A function for ``Workplane.invoke``: replaces the selected faces by their S1 (and S2) faces."""

    def op(wp: cq.Workplane) -> cq.Workplane:
        faces = [v for v in wp.vals() if isinstance(v, cq.Face)]
        if not faces:
            from ..errors import InputError

            raise InputError("select at least one face before invoking machining_surface_op")
        result = []
        for f in faces:
            s1, s2, _ = machining_surface_faces(f, tool, **kwargs)
            result += [s1] + ([s2] if s2 is not None else [])
        return wp.newObject(result)

    return op


def raster_on_faces(faces, tool, *, check_faces=(), **kwargs):
    """A 3-axis raster tool path over cadquery Faces (e.g. ``solid.faces(">Z").vals()``), keeping the
    tool out of ``check_faces`` too: :func:`machsurf_cad.raster` on their numpy form (mm, degrees).

    >>> import cadquery as cq
    >>> from machsurf_cad.occ.cq_ops import raster_on_faces
    >>> box = cq.Workplane().box(40, 30, 10).faces(">Z").workplane().hole(8)
    >>> solid = box.val()
    >>> top = [f for f in solid.Faces() if f.Center().z > 4.9]
    >>> tp = raster_on_faces(top, "ball:D=6", check_faces=[f for f in solid.Faces() if f not in top],
    ...                      stepover=5.0, chordal_tolerance=0.01)
    >>> z = tp.tip[tp.move == 2, 2]
    >>> bool(abs(z.max() - 5.0) < 1e-9), bool(z.min() < 5.0)  # on the top face; into the hole near it
    (True, True)
    """
    from ..threeaxis import raster
    from ..toolspec import parse_cutter

    cutter = parse_cutter(tool) if isinstance(tool, str) else tool
    mf = [from_cq_face(f, f"face_{i}") for i, f in enumerate(faces)]
    cf = [from_cq_face(f, f"check_{i}") for i, f in enumerate(check_faces)]
    return raster(mf, cutter, check_faces=cf, **kwargs)
