"""Runs inside the FreeCAD GUI under Xvfb: a long CAM operation recompute (the raster on the block, the
drop-cutter's numpy path in FreeCAD's Python) with a 100 ms Qt timer ticking beside it, Esc pressed (a Qt key
event to the main window) after 3 s; then a machining surface recomputed to its end with the timer ticking.
Writes the ticks' gaps, the progress bar's values, the times and the statuses to MACHSURF_FC_OUT."""

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
    from freecad.machsurf import features
    from PySide2 import QtCore, QtGui, QtWidgets

    app = QtWidgets.QApplication.instance()
    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("responsive")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    doc.recompute()
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )

    def watched(run, esc_after=None):
        """``run()`` with a 100 ms timer recording when the GUI handled it and what the progress bars showed;
        Esc sent to the main window ``esc_after`` s in."""
        ticks, values, marks = [], [], {}
        timer = QtCore.QTimer()
        timer.setInterval(100)

        def tick():
            ticks.append(time.perf_counter())
            values.append([b.value() for b in Gui.getMainWindow().findChildren(QtWidgets.QProgressBar)
                           if b.isVisible()])  # fmt: skip
            if os.environ.get("MACHSURF_FC_DEBUG"):
                open(os.environ["MACHSURF_FC_DEBUG"], "a").write(f"{ticks[-1]:.2f} {values[-1]}\n")

        timer.timeout.connect(tick)

        def esc():
            marks["esc"] = time.perf_counter()
            for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
                app.sendEvent(Gui.getMainWindow(), QtGui.QKeyEvent(kind, QtCore.Qt.Key_Escape, QtCore.Qt.NoModifier))

        if esc_after is not None:
            QtCore.QTimer.singleShot(int(1000 * esc_after), esc)
        timer.start()
        t0 = time.perf_counter()
        run()
        t1 = time.perf_counter()
        timer.stop()
        stop = marks.get("esc", t1)  # until Esc (or the end): how often the GUI handled its events
        inside = [t for t in ticks if t0 <= t <= stop]
        gaps = [b - a for a, b in zip([t0] + inside, inside + [stop])]
        return {
            "seconds": t1 - t0,
            "ticks": len(inside),
            "max_gap_s": max(gaps),
            "max_gap_at_s": ([t0] + inside)[gaps.index(max(gaps))] - t0,
            "esc_to_end_s": (t1 - marks["esc"]) if "esc" in marks else None,
            "bar_values": sorted({v for vs in values for v in vs}),
        }

    op = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster", StepOver=1.0,
                       Tool="ball:D=6")  # fmt: skip
    op.ToolController = None
    before = len(op.Path.Commands)
    result["cancelled"] = watched(doc.recompute, esc_after=3.0)
    result["cancelled"].update(status=op.Status, n_commands=len(op.Path.Commands), before=before)
    ms = features.make("MachiningSurface", doc, (part, [f"Face{top + 1}"]), Tool="bull:D=16,r=3", Tolerance=1e-5)
    result["finished"] = watched(doc.recompute)
    result["finished"].update(status=ms.Status, error=ms.GuidingSurfaceError.Value, faces=len(ms.Shape.Faces))
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
