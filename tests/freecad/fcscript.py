"""Shared by the scripts FreeCAD runs in the tests (imported from MACHSURF_ROOT/tests/freecad): the result
file, the example block with its free-form top face, and Qt input sent as a user's (key presses, mouse
clicks) with FreeCAD's event loop let run between them."""

import json
import os
import sys
import time
import traceback

ROOT = os.environ["MACHSURF_ROOT"]
OUT = os.environ["MACHSURF_FC_OUT"]


def run(main) -> None:
    """``main(result)`` with ``result`` a dict (``ok`` set when main returns, the traceback when it raises),
    written as JSON to MACHSURF_FC_OUT; then FreeCAD exits."""
    result = {"ok": False}
    limit = float(os.environ.get("MACHSURF_FC_WATCHDOG_S", "0") or 0)
    if limit > 0:  # a hang ends with every thread's stack in hang_traceback.txt (the test prints it)
        import faulthandler

        faulthandler.dump_traceback_later(limit, exit=True, file=open(out_file("hang_traceback.txt"), "w"))
    try:
        main(result)
        result["ok"] = True
    except Exception:
        result["error"] = traceback.format_exc()
    finally:
        with open(OUT, "w") as fh:
            json.dump(result, fh, indent=1, default=str)
        sys.stdout.flush()
        os._exit(0)


def out_file(name: str) -> str:
    """A file beside the result (screenshots, posted G-code)."""
    return os.path.join(os.path.dirname(OUT), name)


def block(doc):
    """The example block as a Part feature of ``doc`` and the sub-element name of its largest B-spline face."""
    import Part

    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(ROOT, "example_parts", "freeform_block.step"))
    doc.recompute()
    faces = part.Shape.Faces
    spline = [i for i, f in enumerate(faces) if isinstance(f.Surface, Part.BSplineSurface)]
    top = max(spline, key=lambda i: faces[i].Area)
    return part, f"Face{top + 1}"


def _app():
    from PySide2 import QtWidgets

    return QtWidgets.QApplication.instance()


def settle(n: int = 20) -> None:
    """Let the GUI handle its events (timers too) for about ``n`` x 10 ms."""
    app = _app()
    for _ in range(n):
        app.processEvents()
        time.sleep(0.01)


def key(w, k, mod=None, text: str = "") -> None:
    """One key pressed and released on widget ``w``."""
    from PySide2 import QtCore, QtGui

    mod = QtCore.Qt.NoModifier if mod is None else mod
    for kind in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
        _app().sendEvent(w, QtGui.QKeyEvent(kind, k, mod, text))


def click(w, pos=None) -> None:
    """A left click on ``w`` (its centre, or ``pos``), then the events handled."""
    from PySide2 import QtCore, QtGui

    p = QtCore.QPointF(pos if pos is not None else w.rect().center())
    for kind in (QtCore.QEvent.MouseButtonPress, QtCore.QEvent.MouseButtonRelease):
        ev = QtGui.QMouseEvent(kind, p, QtCore.Qt.LeftButton, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
        _app().sendEvent(w, ev)
    settle()


def retype(w, text: str, enter: bool = False) -> None:
    """Select all in the focused editor ``w`` (Ctrl+A) and type ``text`` key by key (then Return)."""
    from PySide2 import QtCore

    key(w, QtCore.Qt.Key_A, QtCore.Qt.ControlModifier)
    for ch in text:
        key(w, 0, text=ch)
    if enter:
        key(w, QtCore.Qt.Key_Return)
    settle()


def split_moves(commands):
    """(machsurf's own moves, the safe moves the CAM operation adds around them: the ``G0`` that follow a
    ``(machsurf safe moves N: ...)`` comment, N of them)."""
    own, safe, skip = [], [], 0
    for c in commands:
        if c.Name.startswith("(machsurf safe moves"):
            skip = int(c.Name.split()[3].rstrip(":"))
        elif c.Name in ("G0", "G1"):
            (safe if skip else own).append(c)
            skip = max(skip - 1, 0)
    return own, safe
