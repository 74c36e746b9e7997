"""Runs inside the FreeCAD GUI under Xvfb: types tolerances into FreeCAD's own property editor with Qt key
and mouse events (a click on the value cell opens the editor, Ctrl+A, the characters, Return), as a user
does, and reads back what the feature stored; writes the figures to MACHSURF_FC_OUT and exits."""

import json
import os
import time
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}
try:
    import FreeCAD
    import FreeCADGui as Gui
    import Part
    from PySide2 import QtCore, QtGui, QtWidgets

    app = QtWidgets.QApplication.instance()

    def settle(n=10):
        for _ in range(n):
            app.processEvents()
            time.sleep(0.01)

    def send_keys(w, text):
        for ch in text:
            for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
                app.sendEvent(w, QtGui.QKeyEvent(kind, 0, QtCore.Qt.NoModifier, ch))

    def send_key(w, key, mod=QtCore.Qt.NoModifier):
        for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
            app.sendEvent(w, QtGui.QKeyEvent(kind, key, mod))

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("typing")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    doc.recompute()
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(part, "Face1")
    Gui.runCommand("Machsurf_MachiningSurface")
    doc.recompute()
    feat = next(o for o in doc.Objects if o.Name.startswith("MachiningSurface"))
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(feat)
    settle(30)
    editors = [w for w in Gui.getMainWindow().findChildren(QtWidgets.QTreeView)
               if w.metaObject().className() == "Gui::PropertyEditor::PropertyEditor"]  # fmt: skip
    from freecad.machsurf.gui.precise_edit import property_name

    def row(model, name, parent=None):
        parent = QtCore.QModelIndex() if parent is None else parent
        for r in range(model.rowCount(parent)):
            i = model.index(r, 0, parent)
            if property_name(i) == name:
                return i
            sub = row(model, name, i)
            if sub is not None:
                return sub
        return None

    def type_into(name, text):
        """Click the value cell of ``name``, select all, type ``text``, Return; what the editor showed."""
        pe = next(w for w in editors if w.isVisible())
        model = pe.model()
        i = row(model, name)
        if i is None:
            names = []

            def walk(p):
                for r in range(model.rowCount(p)):
                    names.append(property_name(model.index(r, 0, p)))
                    walk(model.index(r, 0, p))

            walk(QtCore.QModelIndex())
            raise RuntimeError(f"no row {name} in the property editor: {names}")
        cell = i.sibling(i.row(), 1)
        pe.scrollTo(cell)
        settle()
        centre = QtCore.QPointF(pe.visualRect(cell).center())
        for kind in (QtCore.QEvent.MouseButtonPress, QtCore.QEvent.MouseButtonRelease):
            app.sendEvent(pe.viewport(), QtGui.QMouseEvent(kind, centre, QtCore.Qt.LeftButton, QtCore.Qt.LeftButton,
                                                           QtCore.Qt.NoModifier))  # fmt: skip
        settle()
        ed = app.focusWidget()
        cls = ed.metaObject().className()
        send_key(ed, QtCore.Qt.Key_A, QtCore.Qt.ControlModifier)
        send_keys(ed, text)
        send_key(ed, QtCore.Qt.Key_Return)
        settle(20)
        return cls, model.data(cell)

    typed = {}
    for text in ("0.5 um", "0.0005 mm", "2.5 um", "0.0000001 mm", "3 deg"):
        feat.Tolerance = 0.001
        settle()
        cls, shown = type_into("Tolerance", text)
        typed[text] = {"stored_mm": feat.Tolerance.Value, "shown": shown, "editor": cls}
    result["typed"] = typed
    doc.recompute()
    result["status_after"] = feat.Status
    # the CAM operation's tolerances (not computed here: only what the editor stores)
    from freecad.machsurf.app.camop import CamOperationFeature

    op = doc.addObject("Path::FeaturePython", "Op")
    CamOperationFeature(op)
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(op)
    settle(30)
    result["camop"] = {name: [type_into(name, "0.5 um")[1], getattr(op, name).Value]
                       for name in ("ChordalTolerance", "SurfaceTolerance")}  # fmt: skip
    # every length keeps its digits; an angle is FreeCAD's own editing (2 decimals)
    result["camop"]["StepOver"] = [type_into("StepOver", "2.345 mm")[1], op.StepOver.Value]
    result["camop"]["Lead"] = [type_into("Lead", "12.5 deg")[1], op.Lead.Value]
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
