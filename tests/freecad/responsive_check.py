"""Runs inside the FreeCAD GUI under Xvfb: a long CAM operation recompute (the raster on the block, the
drop-cutter's numpy path in FreeCAD's Python) with a 100 ms Qt timer ticking beside it, Esc pressed (a Qt key
event to the main window) after 3 s; then a machining surface recomputed to its end with the timer ticking.
Writes the ticks' gaps, the progress bar's values, the times and the statuses to MACHSURF_FC_OUT."""

import os
import sys
import time

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def main(result):
    import FreeCAD
    import FreeCADGui as Gui
    from freecad.machsurf import features
    from PySide2 import QtCore, QtWidgets

    Gui.activateWorkbench("MachsurfWorkbench")
    doc = FreeCAD.newDocument("responsive")
    part, top = fcscript.block(doc)
    mw = Gui.getMainWindow()

    def watched(run, esc_after=None):
        """``run()`` with a 100 ms timer recording when the GUI handled it and what the progress bars showed;
        Esc sent to the main window ``esc_after`` s in."""
        ticks, values, marks = [], [], {}
        timer = QtCore.QTimer()
        timer.setInterval(100)

        def tick():
            ticks.append(time.perf_counter())
            values.append([b.value() for b in mw.findChildren(QtWidgets.QProgressBar) if b.isVisible()])

        def esc():
            marks["esc"] = time.perf_counter()
            fcscript.key(mw, QtCore.Qt.Key_Escape)

        timer.timeout.connect(tick)
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

    op = features.make("CamOperation", doc, (part, [top]), Pattern="raster", StepOver=1.0, Tool="ball:D=6")
    op.ToolController = None
    before = len(op.Path.Commands)
    result["cancelled"] = watched(doc.recompute, esc_after=3.0)
    result["cancelled"].update(status=op.Status, n_commands=len(op.Path.Commands), before=before)
    ms = features.make("MachiningSurface", doc, (part, [top]), Tool="bull:D=16,r=3", Tolerance=1e-5)
    result["finished"] = watched(doc.recompute)
    result["finished"].update(status=ms.Status, error=ms.GuidingSurfaceError.Value, faces=len(ms.Shape.Faces))


fcscript.run(main)
