"""Task panel to edit a feature's parameters (GUI only).

Quantities (lengths, angles) are edited as text with their unit and every digit (``0.001 mm``,
``0.5 um``, ``10 deg``); pressing OK writes only the fields the user changed, so an untouched
0.001 mm comes back as 0.001 mm.
"""

import re

import FreeCADGui as Gui
from PySide2 import QtWidgets

EDITABLE = {
    "MachiningSurfaceFeature": ["Tool", "Axes", "Strategy", "Lead", "Tilt", "Tolerance", "Loops"],
    "EffectiveRadiusFeature": ["Tool", "Direction", "Grid", "Scallop", "MapShows"],
    "FlankSettingFeature": ["Radius", "RulePosition", "Setting", "ToolSide"],
    "EnvelopeFeature": ["Tool", "Motion", "Passes", "PassTurn", "Tolerance"],
}


UNITS = {"App::PropertyLength": "mm", "App::PropertyDistance": "mm", "App::PropertyAngle": "deg"}


def label(name: str) -> str:
    """A property's name as the property editor shows it: ``RulePosition`` -> ``Rule position``."""
    return re.sub(r"(?<=[a-z])(?=[A-Z])", " ", name).capitalize()


def _read(w):
    if isinstance(w, QtWidgets.QComboBox):
        return w.currentText()
    if isinstance(w, (QtWidgets.QDoubleSpinBox, QtWidgets.QSpinBox)):
        return w.value()
    return w.text()


class FeaturePanel:
    def __init__(self, obj):
        self.obj = obj
        self.form = QtWidgets.QWidget()
        self.form.setWindowTitle(f"machsurf: {obj.Label}")
        lay = QtWidgets.QFormLayout(self.form)
        self.fields = {}
        self.initial = {}
        for name in EDITABLE.get(obj.Proxy.__class__.__name__, []):
            value = getattr(obj, name)
            kind = obj.getTypeIdOfProperty(name)
            if kind in UNITS:
                w = QtWidgets.QLineEdit(f"{value.Value!r} {UNITS[kind]}")
                w.setToolTip(obj.getDocumentationOfProperty(name) + " (any unit: 0.5 um, 0.02 in, 1 deg)")
            elif kind == "App::PropertyEnumeration":
                w = QtWidgets.QComboBox()
                w.addItems(obj.getEnumerationsOfProperty(name))
                w.setCurrentText(str(value))
            elif isinstance(value, float):
                w = QtWidgets.QDoubleSpinBox()
                w.setDecimals(6)
                w.setRange(-1e6, 1e6)
                w.setValue(value)
            elif isinstance(value, int):
                w = QtWidgets.QSpinBox()
                w.setRange(-1000000, 1000000)
                w.setValue(value)
            else:
                w = QtWidgets.QLineEdit(str(value))
            lay.addRow(label(name), w)
            self.fields[name] = w
            self.initial[name] = _read(w)
        self.status = QtWidgets.QLabel(getattr(obj, "Status", ""))
        self.status.setWordWrap(True)
        lay.addRow("Status", self.status)

    def accept(self):
        for name, w in self.fields.items():
            value = _read(w)
            if value != self.initial[name]:  # only what the user changed
                setattr(self.obj, name, value)
        self.obj.Document.recompute()
        Gui.Control.closeDialog()
        return True

    def reject(self):
        Gui.Control.closeDialog()
        return True
