"""Runs inside the FreeCAD GUI under Xvfb: activates the workbench, selects a face, runs the command,
saves a screenshot, exports STEP, writes the figures to MACHSURF_FC_OUT and exits."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript

root = os.environ["MACHSURF_ROOT"]


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    import Part

    Gui.activateWorkbench("MachsurfWorkbench")
    result["workbench"] = Gui.activeWorkbench().name()
    doc = FreeCAD.newDocument("gui_check")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    doc.recompute()
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(part, "Face1")
    Gui.runCommand("Machsurf_MachiningSurface")
    doc.recompute()
    ms = next(o for o in doc.Objects if o.Name.startswith("MachiningSurface"))
    result.update(
        {
            "valid": ms.isValid(),
            "status": ms.Status,
            "max_s1": ms.GuidingSurfaceError.Value,
            "faces": len(ms.Shape.Faces),
            "colours": [list(c) for c in ms.ViewObject.DiffuseColor],
        }
    )
    part.ViewObject.Transparency = 60
    view = Gui.ActiveDocument.ActiveView
    view.viewIsometric()
    Gui.SendMsgToActiveView("ViewFit")
    Gui.updateGui()
    png = fcscript.out_file("freecad_gui.png")
    view.saveImage(png, 1200, 900, "White")
    result["png"] = png
    from freecad.machsurf.gui.commands import ExportStepCommand

    step = fcscript.out_file("freecad_export.step")
    ExportStepCommand().Activated(step)
    result["step_bytes"] = os.path.getsize(step)
    text = open(step, errors="replace").read()
    result["step_names"] = [n for n in ("S1_guiding", "S2_orientation") if n in text]
    # the task panel: OK without edits writes nothing (0.001 mm stays 0.001 mm); a typed quantity keeps its digits
    from freecad.machsurf.gui.panels import FeaturePanel

    ms.Tolerance = 0.001
    doc.recompute()
    panel = FeaturePanel(ms)
    panel.accept()
    untouched = ms.Tolerance.Value
    panel = FeaturePanel(ms)
    panel.fields["Tolerance"].setText("0.5 um")
    panel.accept()
    result["panel"] = {"untouched": untouched, "typed": ms.Tolerance.Value, "status": ms.Status}
    # a document made without the GUI's view providers (as FreeCADCmd makes it) gets them when opened
    from freecad.machsurf.app import features as features_module
    from freecad.machsurf.app.features import MachiningSurfaceFeature
    from PySide2 import QtWidgets

    bare = doc.addObject("Part::FeaturePython", "Bare")
    MachiningSurfaceFeature(bare)
    before = type(bare.ViewObject.Proxy).__name__
    path = fcscript.out_file("gui_saved.FCStd")
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc2 = FreeCAD.openDocument(path)
    from freecad.machsurf.gui.commands import NAMES

    infos = {n: Gui.Command.get(n).getInfo() for n in NAMES}
    result["commands"] = {
        n: {"pixmap": i["pixmap"], "menu": i["menuText"], "tip": i["toolTip"]} for n, i in infos.items()
    }
    ui = Gui.PySideUic.loadUi(
        os.path.join(os.path.dirname(features_module.__file__), "..", "resources", "preferences.ui")
    )
    result["preferences_ui"] = sorted(
        w.objectName() for w in ui.findChildren(QtWidgets.QWidget) if w.property("prefEntry")
    )
    # Edit > Preferences: the machsurf page is listed with the workbench's icon (grabbed, then closed)
    from PySide2 import QtCore, QtGui

    app = QtWidgets.QApplication.instance()
    prefs = {}

    def grab_preferences():
        dlg = app.activeModalWidget()
        if dlg is None:
            return
        for lst in dlg.findChildren(QtWidgets.QListWidget):
            for k in range(lst.count()):
                item = lst.item(k)
                if item.text() == "machsurf":
                    img = item.icon().pixmap(32, 32).toImage()
                    rgb = [QtGui.QColor(img.pixel(x, y)) for x in range(32) for y in range(32)]
                    # FreeCAD's stand-in for a missing icon is a black cross: no saturated pixel
                    prefs["icon_saturated"] = sum(max(c.red(), c.green(), c.blue()) - min(c.red(), c.green(), c.blue())
                                                  > 60 for c in rgb)  # fmt: skip
        prefs["png"] = fcscript.out_file("freecad_preferences.png")
        dlg.grab().save(prefs["png"])
        dlg.reject()

    QtCore.QTimer.singleShot(1500, grab_preferences)
    Gui.runCommand("Std_DlgPreferences")
    result["preferences"] = prefs
    result["reopened_view"] = {"before": before, "after": type(doc2.getObject("Bare").ViewObject.Proxy).__name__}


fcscript.run(main)
