"""GUI commands: one per feature, and a STEP export of the results (GUI only)."""

import os

import FreeCAD
import FreeCADGui as Gui

ICON = os.path.join(os.path.dirname(os.path.dirname(__file__)), "resources", "machsurf.svg")
NAMES = [
    "Machsurf_MachiningSurface",
    "Machsurf_EffectiveRadius",
    "Machsurf_FlankSetting",
    "Machsurf_Envelope",
    "Machsurf_ExportStep",
]


def _selected_face():
    sel = Gui.Selection.getSelectionEx()
    if not sel or not sel[0].SubElementNames:
        return None
    return sel[0].Object, [sel[0].SubElementNames[0]]


class _FeatureCommand:
    kind = ""
    text = ""
    needs_face = True

    def GetResources(self):
        return {"Pixmap": ICON, "MenuText": self.text, "ToolTip": self.text}

    def IsActive(self):
        return FreeCAD.ActiveDocument is not None

    def Activated(self):
        from ..app import features

        src = _selected_face() if self.needs_face else None
        if self.needs_face and src is None:
            FreeCAD.Console.PrintError("machsurf: select a face first\n")
            return
        doc = FreeCAD.ActiveDocument
        doc.openTransaction(self.text)
        obj = features.make(self.kind, doc, src)  # with machsurf's view provider in the GUI
        doc.commitTransaction()
        doc.recompute()
        if src is not None:
            Gui.Selection.clearSelection()
        return obj


class MachiningSurfaceCommand(_FeatureCommand):
    kind, text = "MachiningSurface", "Machining surfaces S1/S2 of the selected face"


class EffectiveRadiusCommand(_FeatureCommand):
    kind, text = "EffectiveRadius", "Effective cutter radius map of the selected face"


class FlankSettingCommand(_FeatureCommand):
    kind, text = "FlankSetting", "Flank-milling setting on the selected ruled face"


class EnvelopeCommand(_FeatureCommand):
    kind, text, needs_face = "Envelope", "Swept envelopes of a tool (G1 passes)", False


class ExportStepCommand:
    def GetResources(self):
        return {
            "Pixmap": ICON,
            "MenuText": "Export machsurf results to STEP",
            "ToolTip": "Write the selected (or all) machsurf results to STEP, one named object per feature",
        }

    def IsActive(self):
        return FreeCAD.ActiveDocument is not None

    def Activated(self, path=None):
        import Import
        from PySide2 import QtWidgets

        doc = FreeCAD.ActiveDocument
        objs = [
            o
            for o in doc.Objects
            if hasattr(o, "Proxy") and o.Proxy.__class__.__module__.endswith("features") and o.isValid()
        ]
        if path is None:
            path, _ = QtWidgets.QFileDialog.getSaveFileName(None, "Export STEP", "", "STEP (*.step *.stp)")
        if path:
            # one named object per result face (S1_guiding, S2_orientation, pass_k, ...): the STEP carries
            # the names as product names, which CAM systems show
            tmp = []
            for o in objs:
                names = _face_names(o)
                for i, f in enumerate(o.Shape.Faces):
                    t = doc.addObject("Part::Feature", "machsurf_export")
                    t.Shape = f
                    t.Label = f"{o.Label}_{names[i] if i < len(names) else 'face' + str(i + 1)}"
                    tmp.append(t)
            try:
                Import.export(tmp, path)
            finally:
                for t in tmp:
                    doc.removeObject(t.Name)
            FreeCAD.Console.PrintMessage(f"machsurf: wrote {len(tmp)} named face(s) to {path}\n")
        return path


def _face_names(obj):
    kind = obj.Proxy.__class__.__name__
    if kind == "MachiningSurfaceFeature":
        return ["S1_guiding", "S2_orientation"]
    if kind == "EnvelopeFeature":
        return [f"pass_{i + 1}" for i in range(len(obj.Shape.Faces))]
    return ["face"]


def register():
    Gui.addCommand("Machsurf_MachiningSurface", MachiningSurfaceCommand())
    Gui.addCommand("Machsurf_EffectiveRadius", EffectiveRadiusCommand())
    Gui.addCommand("Machsurf_FlankSetting", FlankSettingCommand())
    Gui.addCommand("Machsurf_Envelope", EnvelopeCommand())
    Gui.addCommand("Machsurf_ExportStep", ExportStepCommand())
