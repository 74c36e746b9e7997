"""Runs inside FreeCADCmd: the CAM operation's raster on the block at its default settings with each of
FreeCAD's stock end mill, ball end and bull nose ToolBits (Mod/Path/Tools/Bit) in a ToolController: the
verdict, status and cutter of each; the stock chamfer and V-bit mapped to machsurf's cone. Writes the
figures to MACHSURF_FC_OUT."""

import glob
import json
import os
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}
try:
    import FreeCAD
    import Part
    import PathScripts.PathToolBit as PathToolBit
    import PathScripts.PathToolController as PathToolController
    from freecad.machsurf import features

    bits = os.path.join(FreeCAD.getResourceDir(), "Mod", "Path", "Tools", "Bit")
    doc = FreeCAD.newDocument("stock")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    op = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster")
    doc.recompute()
    out = {}
    from freecad.machsurf.app.camop import cutter_from_toolbit

    for name in ("45degree_chamfer", "60degree_Vbit"):  # mapped only (a raster each would double the time)
        result[name] = cutter_from_toolbit(PathToolBit.Factory.CreateFrom(os.path.join(bits, f"{name}.fctb"), name))
    for name in ("5mm_Endmill", "6mm_Ball_End", "6mm_Bullnose"):
        path = os.path.join(bits, f"{name}.fctb")
        if not os.path.isfile(path):
            out[name] = {"missing": path, "found": sorted(glob.glob(os.path.join(bits, "*")))}
            continue
        bit = PathToolBit.Factory.CreateFrom(path, name)
        tc = PathToolController.Create(f"TC {name}", tool=bit, toolNumber=len(out) + 2)
        op.ToolController = tc
        doc.recompute()
        out[name] = {"status": op.Status, "verdict": op.Verdict, "tool": op.CutterUsed,
                     "max_gouge": op.MaxGouge.Value, "cut_points": op.CutPoints}  # fmt: skip
    result["stock"] = out
    result["defaults"] = {"chordal": op.ChordalTolerance.Value, "gouge": op.GougeTolerance.Value}
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
