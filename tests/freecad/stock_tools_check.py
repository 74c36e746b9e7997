"""Runs inside FreeCADCmd: the CAM operation's raster on the block at its default settings with each of
FreeCAD's stock end mill, ball end and bull nose ToolBits (Mod/Path/Tools/Bit) in a ToolController: the
verdict, status and cutter of each; the stock chamfer and V-bit mapped to machsurf's cone. Writes the
figures to MACHSURF_FC_OUT."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import PathScripts.PathToolBit as PathToolBit
    import PathScripts.PathToolController as PathToolController
    from freecad.machsurf import features
    from freecad.machsurf.app.camop import cutter_from_toolbit

    bits = os.path.join(FreeCAD.getResourceDir(), "Mod", "Path", "Tools", "Bit")

    def bit(name):
        return PathToolBit.Factory.CreateFrom(os.path.join(bits, f"{name}.fctb"), name)

    doc = FreeCAD.newDocument("stock")  # the ToolBits are made in the active document
    for name in ("45degree_chamfer", "60degree_Vbit"):  # mapped only (a raster each would double the time)
        result[name] = cutter_from_toolbit(bit(name))
    part, top = fcscript.block(doc)
    op = features.make("CamOperation", doc, (part, [top]), Pattern="raster")  # not computed yet
    out = {}
    for k, name in enumerate(("5mm_Endmill", "6mm_Ball_End", "6mm_Bullnose")):
        op.ToolController = PathToolController.Create(f"TC {name}", tool=bit(name), toolNumber=k + 2)
        doc.recompute()
        out[name] = {"status": op.Status, "verdict": op.Verdict, "tool": op.CutterUsed,
                     "max_gouge": op.MaxGouge.Value, "cut_points": op.CutPoints}  # fmt: skip
    result["stock"] = out
    result["defaults"] = {"chordal": op.ChordalTolerance.Value, "gouge": op.GougeTolerance.Value}


fcscript.run(main)
