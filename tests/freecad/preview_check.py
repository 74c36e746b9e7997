"""Runs inside the FreeCAD GUI under Xvfb: a 5-axis CAM operation on the block, its preview beside FreeCAD's
Path (tips and axis lines coloured by the body check's distance) read back from the scene graph and saved as
a screenshot, and a 3-axis operation (no preview); writes the figures to MACHSURF_FC_OUT and exits."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    import numpy as np
    from freecad.machsurf import features
    from pivy import coin
    from PySide2 import QtGui

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("preview")
    part, top = fcscript.block(doc)
    five = features.make("CamOperation", doc, (part, [top]), Pattern="5-axis surface", StepOver=4.0,
                         Tool="ball:D=6", Lead=10.0)  # fmt: skip
    five.ToolController = None
    three = features.make("CamOperation", doc, (part, [top]), Pattern="raster", StepOver=6.0)
    doc.recompute()
    sa = coin.SoSearchAction()
    sa.setType(coin.SoLineSet.getClassTypeId())
    sa.setInterest(coin.SoSearchAction.ALL)
    sa.apply(five.ViewObject.Proxy.preview_root)
    paths = sa.getPaths()
    lines = [paths[k].getTail() for k in range(paths.getLength())]
    own, _ = fcscript.split_moves(five.Path.Commands)  # machsurf's moves, one per position of its path
    moves = np.array([[c.Parameters[k] for k in "XYZ"] for c in own])
    tips = np.array([(p.x, p.y, p.z) for p in five.PreviewTips])
    d = np.asarray(five.PreviewDistance)
    result["five"] = {
        "status": five.Status,
        "n_tips": len(tips),
        "n_line_sets": len(lines),
        "polyline_vertices": int(lines[0].numVertices.getValues()[0]) if lines else 0,
        "axis_lines": len(lines[1].numVertices.getValues()) if len(lines) > 1 else 0,
        "n_g1": sum(c.Name == "G1" for c in own),
        "n_moves": len(own),
        "tips_vs_moves_mm": float(np.abs(moves - tips).max()) if moves.shape == tips.shape else None,
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
    result["png"] = fcscript.out_file("freecad_5axis_preview.png")
    view.saveImage(result["png"], 1200, 900, "White")
    img = QtGui.QImage(result["png"])
    px = [QtGui.QColor(img.pixel(x, y)) for x in range(0, img.width(), 4) for y in range(0, img.height(), 4)]
    result["red_pixels"] = sum(c.red() > 180 and c.green() < 120 and c.blue() < 120 for c in px)


fcscript.run(main)
