"""Runs inside the FreeCAD GUI under Xvfb: the colour maps of the machining surface (deviation), the
effective radius (R_eff) and the CAM operation (material left) in the 3D view, each saved as a screenshot;
writes the display modes and the pixel figures of each picture to MACHSURF_FC_OUT."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript

root = os.environ["MACHSURF_ROOT"]


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    import numpy as np
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.app.maps import colour
    from PySide2 import QtGui

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("maps_gui")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    src = (part, [f"Face{top + 1}"])
    objs = {
        "deviation": features.make("MachiningSurface", doc, src, Tool="bull:D=16,r=3", Lead=10.0, Tolerance=1e-3),
        "reff": features.make("EffectiveRadius", doc, src, Tool="bull:D=10,r=2", Direction=30.0, Grid=96),
        "scallop": features.make("CamOperation", doc, src, Pattern="raster", StepOver=4.0, SimulateScallops=True),
        "envelope": features.make("Envelope", doc, None, Tool="cone:D=10,angle=10,L=20", Passes=2),
    }
    from freecad.machsurf.convert import surface_to_part

    import machsurf_cad as msc

    s = msc.example("hypar")
    u0, u1, v0, v1 = s.bounds
    ruled = doc.addObject("Part::Feature", "Hypar")
    ruled.Shape = surface_to_part(s).toShape(u0, u1, v0, v1)
    objs["flank"] = features.make("FlankSetting", doc, (ruled, ["Face1"]), Radius=40.0, Setting="optimum")
    doc.recompute()
    view = Gui.ActiveDocument.ActiveView
    from freecad.machsurf.gui.colourmap import legend_node
    from pivy import coin

    def legend_texts(obj):
        """The strings the legend draws (title, five values, the marks' line)."""
        sa = coin.SoSearchAction()
        sa.setType(coin.SoText2.getClassTypeId())
        sa.setInterest(coin.SoSearchAction.ALL)
        node = legend_node(obj)
        sa.apply(node)
        paths = sa.getPaths()
        return [paths[k].getTail().string.getValues()[0] for k in range(paths.getLength())]

    shots = {}
    for name, obj in objs.items():
        for o in doc.Objects:  # only this feature (and, for the path, nothing of the part) in the picture
            if o.ViewObject is not None:
                o.ViewObject.Visibility = False
        obj.ViewObject.Visibility = True  # last: hiding the Job's group hides its operations
        if name == "flank":  # the map beside the placed cylinder: the face too, half transparent
            ruled.ViewObject.Visibility = True
            ruled.ViewObject.Transparency = 70
            obj.ViewObject.Transparency = 60
        view.viewIsometric()
        Gui.SendMsgToActiveView("ViewFit")
        Gui.updateGui()
        png = fcscript.out_file(f"map_{name}.png")
        view.saveImage(png, 1200, 900, "White")
        img = QtGui.QImage(png)
        w, h = img.width(), img.height()
        arr = np.array([[QtGui.QColor(img.pixel(x, y)).getRgbF()[:3] for x in range(0, w, 3)] for y in range(0, h, 3)])
        # the legend bar: unlit, so its colours are the scale's own; the map: lit colours off the background
        div = bool(obj.MapDiverging)
        ends = colour([0.0, 1.0], div)
        legend = arr[:, : int(0.06 * arr.shape[1])]
        near = [float(np.min(np.abs(legend - e).max(axis=-1))) for e in ends]
        body = arr[:, int(0.15 * arr.shape[1]) :]
        coloured = np.abs(body - 1.0).max(axis=-1) > 0.05
        shots[name] = {
            "png": png,
            "size": [w, h],
            "mode": obj.ViewObject.DisplayMode if "Map" in obj.ViewObject.listDisplayModes() else "beside",
            "modes": obj.ViewObject.listDisplayModes(),
            "legend_end_colour_error": near,
            "map_pixel_fraction": float(coloured.mean()),
            "n_values": len(obj.MapValues),
            "title": obj.MapTitle,
            "status": obj.Status,
            "legend_texts": legend_texts(obj),
            "range_mark_editor_modes": [obj.getEditorMode(n) for n in ("MapRange", "MapMarks")],
        }
    result["shots"] = shots
    # after an error the map is gone from the view too (no stale colours)
    ms = objs["deviation"]
    ms.ViewObject.Visibility = True
    ms.Tool = "nonsense"
    doc.recompute()
    result["after_error"] = {"status": ms.Status, "n_values": len(ms.MapValues),
                             "children": ms.ViewObject.Proxy.map_root.getNumChildren()}  # fmt: skip


fcscript.run(main)
