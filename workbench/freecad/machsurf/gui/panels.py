"""Task panel to edit a feature's parameters (GUI only)."""

import FreeCADGui as Gui
from PySide2 import QtWidgets

EDITABLE = {
    "MachiningSurfaceFeature": ["Tool", "Axes", "Strategy", "Lead", "Tilt", "Tolerance", "Loops"],
    "EffectiveRadiusFeature": ["Tool", "Direction", "Grid", "Scallop"],
    "FlankSettingFeature": ["Radius", "Rule", "Setting", "Side"],
    "EnvelopeFeature": ["Tool", "Motion", "Passes", "Theta", "Tolerance"],
}


class FeaturePanel:
    def __init__(self, obj):
        self.obj = obj
        self.form = QtWidgets.QWidget()
        self.form.setWindowTitle(f"machsurf: {obj.Label}")
        lay = QtWidgets.QFormLayout(self.form)
        self.fields = {}
        for name in EDITABLE.get(obj.Proxy.__class__.__name__, []):
            value = getattr(obj, name)
            if obj.getTypeIdOfProperty(name) == "App::PropertyEnumeration":
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
            lay.addRow(name, w)
            self.fields[name] = w
        self.status = QtWidgets.QLabel(getattr(obj, "Status", ""))
        self.status.setWordWrap(True)
        lay.addRow("Status", self.status)

    def accept(self):
        for name, w in self.fields.items():
            if isinstance(w, QtWidgets.QComboBox):
                setattr(self.obj, name, w.currentText())
            elif isinstance(w, (QtWidgets.QDoubleSpinBox, QtWidgets.QSpinBox)):
                setattr(self.obj, name, w.value())
            else:
                setattr(self.obj, name, w.text())
        self.obj.Document.recompute()
        Gui.Control.closeDialog()
        return True

    def reject(self):
        Gui.Control.closeDialog()
        return True
