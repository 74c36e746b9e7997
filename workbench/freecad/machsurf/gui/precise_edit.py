"""The property editor keeps every digit of a machsurf length (GUI only).

FreeCAD 0.20's property editor stores a length rounded to the user's decimals in mm (2 by default): a
tolerance of ``0.5 um`` typed there became 0.0 mm. When the editor of a length of a machsurf feature gets
the focus, the text the user types is followed and, once the editor has stored its rounded value, the
exact value parsed from that text replaces it (:func:`..app.precise.set_precise`); a value that is not a
length, or a tolerance below 1 nm, is refused with one line in the report view and the value before is
kept. Nothing happens for other properties or objects, or when the user leaves the editor without typing.
"""

import re

import FreeCAD
import FreeCADGui as Gui
from PySide2 import QtCore, QtWidgets

from ..app.precise import LENGTHS, set_precise

_HOOKED = "machsurfPrecise"


def install() -> None:
    """Follow the focus (once per session)."""
    app = QtWidgets.QApplication.instance()
    if app is None or app.property(_HOOKED):
        return
    app.setProperty(_HOOKED, True)
    app.focusChanged.connect(_on_focus)


def property_name(index) -> str:
    """The property a row of the editor shows: its tooltip names it (``Name: ChordalTolerance``); the label
    (``Chordal Tolerance``) without spaces otherwise."""
    tip = str(index.data(QtCore.Qt.ToolTipRole) or "")
    m = re.search(r"^Name: (\w+)", tip, re.MULTILINE)
    return m.group(1) if m else str(index.data() or "").replace(" ", "")


def _class(w) -> str:
    return w.metaObject().className() if w is not None else ""


def _spin_and_editor(w):
    """The ``Gui::QuantitySpinBox`` ``w`` is (or is inside) and the property editor holding it, else Nones."""
    spin = None
    while w is not None:
        name = _class(w)
        if name == "Gui::QuantitySpinBox" and spin is None:
            spin = w
        if name == "Gui::PropertyEditor::PropertyEditor":
            return spin, w
        w = w.parentWidget()
    return None, None


def _machsurf_objects(name: str) -> list:
    """The selected machsurf features that have the length property ``name``."""
    out = []
    for obj in Gui.Selection.getSelection():
        proxy = getattr(obj, "Proxy", None)
        if proxy is not None and type(proxy).__module__.startswith("freecad.machsurf") and name in obj.PropertiesList:
            out.append(obj)
    return out


def _on_focus(_old, new) -> None:
    spin, editor = _spin_and_editor(new)
    if spin is None or spin.property(_HOOKED):
        return
    idx = editor.currentIndex()
    name = property_name(idx.sibling(idx.row(), 0)) if idx.isValid() else None
    objs = [o for o in _machsurf_objects(name) if o.getTypeIdOfProperty(name) in LENGTHS]
    if not objs:
        return
    spin.setProperty(_HOOKED, True)
    line = spin.findChild(QtWidgets.QLineEdit)
    state = {"text": None, "before": [float(getattr(o, name).Value) for o in objs]}

    def typed(text):
        state["text"] = text

    def finished():
        text = state["text"]
        if text is None:  # left without typing: the editor's own value stands
            return
        state["text"] = None
        QtCore.QTimer.singleShot(0, lambda: _apply(objs, name, text, state["before"]))

    if line is not None:
        line.textEdited.connect(typed)
    spin.editingFinished.connect(finished)


def _apply(objs, name, text, before) -> None:
    for obj, old in zip(objs, before):
        why = set_precise(obj, name, text, old)
        if why:
            FreeCAD.Console.PrintError(f"machsurf: {why}\n")
