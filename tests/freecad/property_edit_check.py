"""Runs inside the FreeCAD GUI under Xvfb: types tolerances into FreeCAD's own property editor with Qt key
and mouse events (a click on the value cell opens the editor, Ctrl+A, the characters, Return), as a user
does, and reads back what the feature stored; writes the figures to MACHSURF_FC_OUT and exits."""

import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    from freecad.machsurf.app.camop import CamOperationFeature
    from freecad.machsurf.gui.precise_edit import property_name
    from PySide2 import QtCore, QtWidgets

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("typing")
    part, _ = fcscript.block(doc)
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(part, "Face1")
    Gui.runCommand("Machsurf_MachiningSurface")
    doc.recompute()
    feat = next(o for o in doc.Objects if o.Name.startswith("MachiningSurface"))
    editors = [w for w in Gui.getMainWindow().findChildren(QtWidgets.QTreeView)
               if w.metaObject().className() == "Gui::PropertyEditor::PropertyEditor"]  # fmt: skip

    def row(model, name, parent=None):
        parent = QtCore.QModelIndex() if parent is None else parent
        for r in range(model.rowCount(parent)):
            i = model.index(r, 0, parent)
            found = i if property_name(i) == name else row(model, name, i)
            if found is not None:
                return found
        return None

    def type_into(obj, name, text):
        """Select ``obj``, click the value cell of ``name``, type ``text``, Return: the editor's class and the
        cell's text after."""
        Gui.Selection.clearSelection()
        Gui.Selection.addSelection(obj)
        fcscript.settle(30)
        pe = next(w for w in editors if w.isVisible())
        model = pe.model()
        i = row(model, name)
        if i is None:
            raise RuntimeError(f"no row {name} in the property editor")
        cell = i.sibling(i.row(), 1)
        pe.scrollTo(cell)
        fcscript.settle()
        fcscript.click(pe.viewport(), pe.visualRect(cell).center())
        ed = QtWidgets.QApplication.instance().focusWidget()
        cls = ed.metaObject().className()
        fcscript.retype(ed, text, enter=True)
        return cls, model.data(cell)

    typed = {}
    for text in ("0.5 um", "0.0005 mm", "2.5 um", "0.0000001 mm", "3 deg"):
        feat.Tolerance = 0.001
        cls, shown = type_into(feat, "Tolerance", text)
        typed[text] = {"stored_mm": feat.Tolerance.Value, "shown": shown, "editor": cls}
    result["typed"] = typed
    doc.recompute()
    result["status_after"] = feat.Status
    # the CAM operation's tolerances (not computed here: only what the editor stores)
    op = doc.addObject("Path::FeaturePython", "Op")
    CamOperationFeature(op)
    result["camop"] = {name: [type_into(op, name, "0.5 um")[1], getattr(op, name).Value]
                       for name in ("ChordalTolerance", "SurfaceTolerance")}  # fmt: skip
    # every length keeps its digits; an angle is FreeCAD's own editing (2 decimals)
    result["camop"]["StepOver"] = [type_into(op, "StepOver", "2.345 mm")[1], op.StepOver.Value]
    result["camop"]["Lead"] = [type_into(op, "Lead", "12.5 deg")[1], op.Lead.Value]


fcscript.run(main)
