"""Runs inside the FreeCAD GUI under Xvfb: the CAM operation's task panel opened by double-clicking the
operation in the tree, edited with Qt key and mouse events (the pattern chosen with the arrow keys, a
tolerance and a tilt limit typed, a check box clicked, OK clicked), the stored values read back and the
panel captured for each pattern; writes the figures to MACHSURF_FC_OUT and exits."""

import json
import os
import time
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
result = {"ok": False}
try:
    import FreeCAD
    import FreeCADGui as Gui
    from PySide2 import QtCore, QtGui, QtWidgets

    app = QtWidgets.QApplication.instance()

    def settle(n=20):
        for _ in range(n):
            app.processEvents()
            time.sleep(0.01)

    def click(w, pos=None):
        p = QtCore.QPointF(pos if pos is not None else w.rect().center())
        for kind in (QtCore.QEvent.MouseButtonPress, QtCore.QEvent.MouseButtonRelease):
            ev = QtGui.QMouseEvent(kind, p, QtCore.Qt.LeftButton, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
            app.sendEvent(w, ev)
        settle()

    def key(w, k, mod=QtCore.Qt.NoModifier, text=""):
        for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
            app.sendEvent(w, QtGui.QKeyEvent(kind, k, mod, text))

    def type_text(w, text):
        click(w)
        key(w, QtCore.Qt.Key_A, QtCore.Qt.ControlModifier)
        for ch in text:
            key(w, 0, text=ch)
        settle()

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("panel")
    from freecad.machsurf.app.camop import CamOperationFeature
    from freecad.machsurf.gui import view

    op = doc.addObject("Path::FeaturePython", "CamOperation")
    CamOperationFeature(op)
    view.attach(op)
    settle()
    Gui.ActiveDocument.setEdit(op.Name)  # what a double-click in the tree does
    settle(40)
    mw = Gui.getMainWindow()
    form = next(w for w in mw.findChildren(QtWidgets.QWidget) if w.windowTitle() == f"machsurf: {op.Label}")

    def field(name):
        return form.findChild(QtWidgets.QWidget, name)

    def shown():
        return sorted(b.title() for b in form.findChildren(QtWidgets.QGroupBox) if b.isVisible())

    result["raster_groups"] = shown()
    result["raster_stepdown_visible"] = field("StepDown").isVisible()
    combo = field("Pattern")
    combo.setFocus()
    settle()
    target = combo.findText("5-axis surface")
    for _ in range(abs(target - combo.currentIndex())):
        key(combo, QtCore.Qt.Key_Down if target > combo.currentIndex() else QtCore.Qt.Key_Up)
        settle(5)
    result["five_groups"] = shown()
    type_text(field("ChordalTolerance"), "0.5 um")
    type_text(field("MaxLead"), "40 deg")
    click(field("TrimGouges"), QtCore.QPoint(6, field("TrimGouges").height() // 2))
    png = os.path.join(os.path.dirname(out_path), "freecad_cam_panel.png")
    form.grab().save(png)
    result["png"] = png
    box = next(b for b in mw.findChildren(QtWidgets.QDialogButtonBox)
               if b.isVisible() and b.button(QtWidgets.QDialogButtonBox.Ok) is not None)  # fmt: skip
    click(box.button(QtWidgets.QDialogButtonBox.Ok))
    settle(40)
    result["stored"] = {
        "Pattern": str(op.Pattern),
        "ChordalTolerance": op.ChordalTolerance.Value,
        "MaxLead": op.MaxLead.Value,
        "TrimGouges": bool(op.TrimGouges),
        "GougeTolerance": op.GougeTolerance.Value,  # untouched
        "StepOver": op.StepOver.Value,  # untouched
    }
    result["panel_closed"] = not any(
        w.windowTitle() == f"machsurf: {op.Label}" and w.isVisible() for w in mw.findChildren(QtWidgets.QWidget)
    )
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
