"""Task panel to edit a feature's parameters (GUI only).

Quantities (lengths, angles) are edited as text with their unit and every digit (``0.001 mm``,
``0.5 um``, ``10 deg``); pressing OK writes only the fields the user changed, so an untouched
0.001 mm comes back as 0.001 mm. The fields are grouped as the property editor groups them; on a CAM
operation the groups that do not apply to its pattern (5-axis limits for a raster, the flank setting for
a waterline) are hidden and shown again when the pattern changes in the panel.
"""

import re

import FreeCADGui as Gui
from PySide2 import QtWidgets

EDITABLE = {
    "MachiningSurfaceFeature": ["Tool", "Axes", "Strategy", "Lead", "Tilt", "Tolerance", "Loops"],
    "EffectiveRadiusFeature": ["Tool", "Direction", "Grid", "Scallop", "MapShows"],
    "FlankSettingFeature": ["Radius", "RulePosition", "Setting", "ToolSide"],
    "EnvelopeFeature": ["Tool", "Motion", "Passes", "PassTurn", "Tolerance"],
    "CamOperationFeature": [
        "Pattern",
        "StepOver",
        "Angle",
        "StepDown",
        "Lead",
        "Tilt",
        "MaxLead",
        "MaxTilt",
        "SurfaceTolerance",
        "ToolSide",
        "FlankSetting",
        "ChordalTolerance",
        "GougeTolerance",
        "TrimGouges",
        "AllowGouge",
        "Clearance",
        "SimulateScallops",
        "ScallopLimit",
        "Tool",
    ],  # fmt: skip
}

PATTERN_GROUPS = {  # CAM operation: the property groups (and single fields) each pattern uses
    "raster": {"Strategy", "Accuracy", "Linking", "Simulation", "Cutter"},
    "waterline": {"Strategy", "Accuracy", "Linking", "Simulation", "Cutter"},
    "5-axis surface": {"Strategy", "5-axis", "Accuracy", "Linking", "Simulation", "Cutter"},
    "flank": {"Flank", "Accuracy", "Linking", "Cutter"},
}
PATTERN_FIELDS = {"StepDown": {"waterline"}, "Angle": {"raster"}, "StepOver": {"raster", "5-axis surface"}}

UNITS = {"App::PropertyLength": "mm", "App::PropertyDistance": "mm", "App::PropertyAngle": "deg"}


def label(name: str) -> str:
    """A property's name as the property editor shows it: ``RulePosition`` -> ``Rule position``."""
    return re.sub(r"(?<=[a-z])(?=[A-Z])", " ", name).capitalize()


def _read(w):
    if isinstance(w, QtWidgets.QComboBox):
        return w.currentText()
    if isinstance(w, QtWidgets.QCheckBox):
        return w.isChecked()
    if isinstance(w, (QtWidgets.QDoubleSpinBox, QtWidgets.QSpinBox)):
        return w.value()
    return w.text()


def _field(obj, name):
    """The editor of one property: unit text, combo box, check box, spin box or text."""
    value = getattr(obj, name)
    kind = obj.getTypeIdOfProperty(name)
    if kind in UNITS:
        w = QtWidgets.QLineEdit(f"{value.Value!r} {UNITS[kind]}")
        w.setToolTip(obj.getDocumentationOfProperty(name) + " (any unit: 0.5 um, 0.02 in, 1 deg)")
        return w
    if kind == "App::PropertyEnumeration":
        w = QtWidgets.QComboBox()
        w.addItems(obj.getEnumerationsOfProperty(name))
        w.setCurrentText(str(value))
    elif kind == "App::PropertyBool":
        w = QtWidgets.QCheckBox()
        w.setChecked(bool(value))
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
    w.setToolTip(obj.getDocumentationOfProperty(name))
    return w


class FeaturePanel:
    def __init__(self, obj):
        self.obj = obj
        self.form = QtWidgets.QWidget()
        self.form.setWindowTitle(f"machsurf: {obj.Label}")
        outer = QtWidgets.QVBoxLayout(self.form)
        self.fields = {}
        self.initial = {}
        self.groups = {}
        self.rows = {}
        for name in EDITABLE.get(obj.Proxy.__class__.__name__, []):
            if name not in obj.PropertiesList:
                continue
            group = obj.getGroupOfProperty(name) or "Parameters"
            if group not in self.groups:
                box = QtWidgets.QGroupBox(group)
                box.setLayout(QtWidgets.QFormLayout())
                outer.addWidget(box)
                self.groups[group] = box
            w = _field(obj, name)
            w.setObjectName(name)
            lab = QtWidgets.QLabel(label(name))
            self.groups[group].layout().addRow(lab, w)
            self.rows[name] = (lab, w)
            self.fields[name] = w
            self.initial[name] = _read(w)
        self.status = QtWidgets.QLabel(getattr(obj, "Status", ""))
        self.status.setWordWrap(True)
        outer.addWidget(self.status)
        pattern = self.fields.get("Pattern")
        if isinstance(pattern, QtWidgets.QComboBox):
            pattern.currentTextChanged.connect(self.show_for_pattern)
            self.show_for_pattern(pattern.currentText())

    def show_for_pattern(self, pattern: str) -> None:
        """Only the groups and fields the operation's pattern uses."""
        use = PATTERN_GROUPS.get(pattern)
        if use is None:
            return
        for group, box in self.groups.items():
            box.setVisible(group in use)
        for name, patterns in PATTERN_FIELDS.items():
            if name in self.rows:
                for w in self.rows[name]:
                    w.setVisible(pattern in patterns)

    def accept(self):
        """Write what the user changed (lengths exactly, :func:`..app.precise.set_precise`) and recompute; a
        value that cannot be stored is said in the panel's status line and the panel stays open."""
        from ..app.precise import LENGTHS, set_precise

        for name, w in self.fields.items():
            value = _read(w)
            if value == self.initial[name]:  # only what the user changed
                continue
            try:
                if self.obj.getTypeIdOfProperty(name) in LENGTHS:
                    why = set_precise(self.obj, name, value, float(getattr(self.obj, name).Value))
                else:
                    setattr(self.obj, name, value)
                    why = None
            except Exception as exc:  # a text FreeCAD cannot take: one line
                why = f"{label(name)}: {value!r}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"
            if why:
                self.status.setText(f"not stored: {why}")
                return False
        self.obj.Document.recompute()
        Gui.Control.closeDialog()
        return True

    def reject(self):
        Gui.Control.closeDialog()
        return True
