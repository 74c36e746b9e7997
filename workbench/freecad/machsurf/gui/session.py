"""What the GUI sets up once per FreeCAD session, from the workbench or from the first machsurf object shown
(a document opened in another workbench): the property editor's exact lengths, and the event pump that
keeps the GUI live while a recompute runs off its thread (:mod:`..app.worker`), with Esc cancelling it.

FreeCAD's own progress bar answers Esc with a modal "abort?" question; the pump puts its Esc filter first
in line on every round, so Esc cancels a machsurf recompute at once instead.
"""

from PySide2 import QtCore, QtWidgets

from ..app import worker
from . import precise_edit


class _Escape(QtCore.QObject):
    """Esc while a machsurf call runs off the GUI thread: cancel it (the key goes no further)."""

    def eventFilter(self, obj, event):
        if event.type() == QtCore.QEvent.KeyPress and event.key() == QtCore.Qt.Key_Escape and worker.busy():
            worker.request_cancel()
            return True
        return False


_ESCAPE = None


def _pump() -> None:
    app = QtWidgets.QApplication.instance()
    app.removeEventFilter(_ESCAPE)
    app.installEventFilter(_ESCAPE)  # installed last: asked first, before FreeCAD's progress bar
    app.processEvents()


def install() -> None:
    global _ESCAPE
    precise_edit.install()
    if _ESCAPE is None:
        _ESCAPE = _Escape()
        _warm_imports()
    worker.set_pump(_pump)


def _warm_imports() -> None:
    """Import the core's heavy modules now: an extension module's first import holds Python's lock for up to
    half a second, which in a recompute's worker thread would stall the GUI that long."""
    from .. import ensure_core

    ensure_core()
    import scipy.optimize
    import scipy.spatial  # noqa: F401

    import machsurf_cad.gougecheck
    import machsurf_cad.machining.surfaces
    import machsurf_cad.threeaxis.paths  # noqa: F401
