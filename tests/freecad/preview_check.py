"""Runs inside the FreeCAD GUI under Xvfb: a 5-axis CAM operation on the block, its preview beside FreeCAD's
Path (tips and axis lines coloured by the body check's distance) read back from the scene graph and saved as
a screenshot; writes the figures to MACHSURF_FC_OUT and exits."""

import json
import os
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}
try:
    import FreeCAD
    import FreeCADGui as Gui
    import numpy as np
    import Part
    from freecad.machsurf import features
    from pivy import coin
    from PySide2 import QtGui

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("preview")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    five = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="5-axis surface", StepOver=4.0,
                         Tool="ball:D=6", Lead=10.0)  # fmt: skip
    five.ToolController = None
    three = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster", StepOver=6.0)
    doc.recompute()
    vp = five.ViewObject.Proxy
    sa = coin.SoSearchAction()
    sa.setType(coin.SoLineSet.getClassTypeId())
    sa.setInterest(coin.SoSearchAction.ALL)
    sa.apply(vp.preview_root)
    paths = sa.getPaths()
    lines = [paths[k].getTail() for k in range(paths.getLength())]
    g = [c for c in five.Path.Commands if c.Name in ("G0", "G1")]
    tips = np.array([(p.x, p.y, p.z) for p in five.PreviewTips])
    d = np.asarray(five.PreviewDistance)
    cut = [c for c in g if c.Name == "G1"]
    result["five"] = {
        "status": five.Status,
        "n_tips": len(tips),
        "n_line_sets": len(lines),
        "polyline_vertices": int(lines[0].numVertices.getValues()[0]) if lines else 0,
        "axis_lines": len(lines[1].numVertices.getValues()) if len(lines) > 1 else 0,
        "n_g1": len(cut),
        "tips_match_g1": bool(
            all(any(np.allclose([c.Parameters[k] for k in "XYZ"], t, atol=1e-6) for t in tips[:50]) for c in cut[:5])
        ),  # fmt: skip
        "min_distance": float(d.min()),
        "max_distance": float(d.max()),
        "gouge_tolerance": five.GougeTolerance.Value,
        "freecad_shows": [five.ViewObject.StartIndex, five.ViewObject.ShowCount, len(five.Path.Commands)],
    }
    result["three"] = {"status": three.Status, "n_tips": len(three.PreviewTips),
                       "freecad_shows": [three.ViewObject.StartIndex, three.ViewObject.ShowCount],
                       "children": three.ViewObject.Proxy.preview_root.getNumChildren()}  # fmt: skip
    for o in doc.Objects:
        if o.ViewObject is not None:
            o.ViewObject.Visibility = False
    five.ViewObject.Visibility = True
    part.ViewObject.Visibility = True
    part.ViewObject.Transparency = 70
    view = Gui.ActiveDocument.ActiveView
    view.viewIsometric()
    Gui.SendMsgToActiveView("ViewFit")
    Gui.updateGui()
    png = os.path.join(os.path.dirname(out_path), "freecad_5axis_preview.png")
    view.saveImage(png, 1200, 900, "White")
    img = QtGui.QImage(png)
    px = [QtGui.QColor(img.pixel(x, y)) for x in range(0, img.width(), 4) for y in range(0, img.height(), 4)]
    result["png"] = png
    result["red_pixels"] = sum(c.red() > 180 and c.green() < 120 and c.blue() < 120 for c in px)
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
