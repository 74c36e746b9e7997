"""Runs inside FreeCADCmd with the repository cloned into the Mod folder as the Addon Manager does (no link
to workbench/): the workbench package is found through the root package.xml, the core beside it, and a
feature recomputes. Writes its figures to MACHSURF_FC_OUT."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import Part
    from freecad.machsurf import features

    import machsurf_cad

    doc = FreeCAD.newDocument("addon")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(os.environ["MACHSURF_ROOT"], "example_parts", "freeform_block.step"))
    idx = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    ms = features.make("MachiningSurface", doc, (part, [f"Face{idx + 1}"]), Tool="ball:D=10", Lead=10.0)
    doc.recompute()
    result.update(
        {
            "features_file": features.__file__,
            "core_file": machsurf_cad.__file__,
            "status": ms.Status,
            "faces": len(ms.Shape.Faces),
            "max_s1": ms.GuidingSurfaceError.Value,
        }
    )


fcscript.run(main)
