"""Runs inside the FreeCAD GUI under Xvfb: the CAM operation's task panel opened as a double-click in the
tree opens it, edited with Qt key and mouse events (the pattern chosen with the arrow keys, a tolerance and
a tilt limit typed, a check box clicked, OK clicked), the stored values read back and the panel captured;
writes the figures to MACHSURF_FC_OUT and exits."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    from freecad.machsurf.app.camop import CamOperationFeature
    from freecad.machsurf.gui import view
    from PySide2 import QtCore, QtWidgets

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("panel")
    op = doc.addObject("Path::FeaturePython", "CamOperation")
    CamOperationFeature(op)
    view.attach(op)
    fcscript.settle()
    Gui.ActiveDocument.setEdit(op.Name)  # what a double-click in the tree does
    fcscript.settle(40)
    mw = Gui.getMainWindow()
    title = f"machsurf: {op.Label}"
    form = next(w for w in mw.findChildren(QtWidgets.QWidget) if w.windowTitle() == title)

    def field(name):
        return form.findChild(QtWidgets.QWidget, name)

    def shown():
        return sorted(b.title() for b in form.findChildren(QtWidgets.QGroupBox) if b.isVisible())

    def type_text(name, text):
        fcscript.click(field(name))
        fcscript.retype(field(name), text)

    result["raster_groups"] = shown()
    result["raster_stepdown_visible"] = field("StepDown").isVisible()
    combo = field("Pattern")
    combo.setFocus()
    fcscript.settle()
    target = combo.findText("5-axis surface")
    for _ in range(abs(target - combo.currentIndex())):
        fcscript.key(combo, QtCore.Qt.Key_Down if target > combo.currentIndex() else QtCore.Qt.Key_Up)
        fcscript.settle(5)
    result["five_groups"] = shown()
    type_text("ChordalTolerance", "0.5 um")
    type_text("MaxLead", "40 deg")
    check = field("TrimGouges")
    fcscript.click(check, QtCore.QPoint(6, check.height() // 2))
    result["png"] = fcscript.out_file("freecad_cam_panel.png")
    form.grab().save(result["png"])
    box = next(b for b in mw.findChildren(QtWidgets.QDialogButtonBox)
               if b.isVisible() and b.button(QtWidgets.QDialogButtonBox.Ok) is not None)  # fmt: skip
    fcscript.click(box.button(QtWidgets.QDialogButtonBox.Ok))
    fcscript.settle(40)
    result["stored"] = {
        "Pattern": str(op.Pattern),
        "ChordalTolerance": op.ChordalTolerance.Value,
        "MaxLead": op.MaxLead.Value,
        "TrimGouges": bool(op.TrimGouges),
        "GougeTolerance": op.GougeTolerance.Value,  # untouched
        "StepOver": op.StepOver.Value,  # untouched
    }
    widgets = mw.findChildren(QtWidgets.QWidget)
    result["panel_closed"] = not any(w.windowTitle() == title and w.isVisible() for w in widgets)


fcscript.run(main)
