"""Runs inside the FreeCAD GUI under Xvfb: a CAM programmer's steps, each captured as the screen shows it -
the block's top face picked (the machsurf toolbar beside it), the CAM operation's toolbar button clicked
(a Path Job and its tool made, the raster computed off the GUI thread and checked), the operation's task
panel opened from the tree, a step-over typed and OK clicked (recomputed), the result in the property view.
Writes the figures and the screenshots' paths to MACHSURF_FC_OUT and exits."""

import os
import sys
import time

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    from PySide2 import QtCore, QtWidgets

    mw = Gui.getMainWindow()
    mw.showNormal()
    mw.setGeometry(0, 0, 1560, 1120)
    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("steps")
    part, top = fcscript.block(doc)
    view = Gui.ActiveDocument.ActiveView
    view.viewIsometric()
    Gui.SendMsgToActiveView("ViewFit")
    shots = []

    def results_in_view():
        """The property view scrolled to the operation's results (its last groups)."""
        for tree in mw.findChildren(QtWidgets.QTreeView):
            model = tree.model()
            if tree.isVisible() and model is not None and model.headerData(0, QtCore.Qt.Horizontal) == "Property":
                tree.scrollToBottom()

    def shot(name):
        fcscript.settle(30)
        path = fcscript.out_file(f"freecad_step_{len(shots) + 1}_{name}.png")
        screen = QtWidgets.QApplication.primaryScreen()
        screen.grabWindow(mw.winId()).save(path)
        shots.append(path)

    def recomputed(op, timeout=300.0):
        """Wait, handling events as FreeCAD does, until the operation has its verdict or its error."""
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < timeout:
            fcscript.settle(10)
            if str(op.Status) and not doc.mustExecute():
                return time.perf_counter() - t0
        raise RuntimeError(f"no verdict after {timeout} s (status {op.Status!r})")

    # 1: the face picked
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(doc.Name, part.Name, top)
    result["selected"] = [list(s.SubElementNames) for s in Gui.Selection.getSelectionEx()]
    shot("face_picked")

    # 2: the CAM operation's toolbar button clicked
    def is_cam(b):
        return b.defaultAction() is not None and b.defaultAction().text() == "CAM operation" and b.isVisible()

    button = next(b for b in mw.findChildren(QtWidgets.QToolButton) if is_cam(b))
    fcscript.click(button)
    ops = [o for o in doc.Objects if o.Name.startswith("CamOperation")]
    result["ops_made"] = len(ops)
    op = ops[0]
    result["first_s"] = recomputed(op)
    result["first"] = {"status": op.Status, "verdict": op.Verdict, "tool": op.CutterUsed,
                       "stepover": op.StepOver.Value, "cut_points": op.CutPoints, "max_gouge": op.MaxGouge.Value,
                       "in_job": any(o.TypeId == "Path::FeaturePython" and o.Name.startswith("Job")
                                     for o in doc.Objects)}  # fmt: skip
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(op)
    fcscript.settle()
    results_in_view()
    shot("path_computed")
    # 3: the task panel, as a double-click in the tree opens it
    Gui.ActiveDocument.setEdit(op.Name)
    fcscript.settle(40)
    title = f"machsurf: {op.Label}"
    form = next(w for w in mw.findChildren(QtWidgets.QWidget) if w.windowTitle() == title)
    result["panel_open"] = form.isVisible()
    field = form.findChild(QtWidgets.QWidget, "StepOver")
    fcscript.click(field)
    fcscript.retype(field, "3 mm")
    shot("panel_edited")
    # 4: OK: recomputed with the new step-over, the verdict in the property view
    box = next(b for b in mw.findChildren(QtWidgets.QDialogButtonBox)
               if b.isVisible() and b.button(QtWidgets.QDialogButtonBox.Ok) is not None)  # fmt: skip
    fcscript.click(box.button(QtWidgets.QDialogButtonBox.Ok))
    result["second_s"] = recomputed(op)
    result["second"] = {"status": op.Status, "verdict": op.Verdict, "stepover": op.StepOver.Value,
                        "cut_points": op.CutPoints, "max_gouge": op.MaxGouge.Value}  # fmt: skip
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(op)
    fcscript.settle()
    results_in_view()
    shot("recomputed")
    result["shots"] = shots


fcscript.run(main)
