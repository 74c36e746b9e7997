"""GUI commands: one per feature, and a STEP export of the results (GUI only)."""

import os

import FreeCAD
import FreeCADGui as Gui

RESOURCES = os.path.join(os.path.dirname(os.path.dirname(__file__)), "resources")
ICON = os.path.join(RESOURCES, "machsurf.svg")
NAMES = [
    "Machsurf_MachiningSurface",
    "Machsurf_EffectiveRadius",
    "Machsurf_FlankSetting",
    "Machsurf_Envelope",
    "Machsurf_CamOperation",
    "Machsurf_ExportStep",
]


def _noop(context, text):
    return text


# FreeCAD's marker for texts to translate (lupdate collects them); the identity where it is missing
QT_TRANSLATE_NOOP = getattr(getattr(FreeCAD, "Qt", None), "QT_TRANSLATE_NOOP", _noop)


def _selected_face():
    sel = Gui.Selection.getSelectionEx()
    if not sel or not sel[0].SubElementNames:
        return None
    return sel[0].Object, [sel[0].SubElementNames[0]]


class _FeatureCommand:
    kind = ""
    text = ""
    tip = ""
    icon = "machsurf.svg"
    needs_face = True

    def source(self):
        return _selected_face() if self.needs_face else None

    def GetResources(self):
        return {"Pixmap": os.path.join(RESOURCES, self.icon), "MenuText": self.text, "ToolTip": self.tip}

    def IsActive(self):
        return FreeCAD.ActiveDocument is not None

    def Activated(self):
        from ..app import features

        src = self.source()
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
    kind = "MachiningSurface"
    text = QT_TRANSLATE_NOOP("Machsurf_MachiningSurface", "Guiding and orientation surfaces")
    tip = QT_TRANSLATE_NOOP(
        "Machsurf_MachiningSurface",
        "Select a face: the surfaces the tool centre (guiding surface, the paper's S1) and the axis "
        "(orientation surface, S2) move on for a ball, flat or bull-nose end mill in 3 or 5 axes, fitted "
        "as B-splines with their error measured.",
    )


class EffectiveRadiusCommand(_FeatureCommand):
    kind, icon = "EffectiveRadius", "effective_radius.svg"
    text = QT_TRANSLATE_NOOP("Machsurf_EffectiveRadius", "Effective cutter radius")
    tip = QT_TRANSLATE_NOOP(
        "Machsurf_EffectiveRadius",
        "Select a face: the radius the surface sees of a bull-nose cutter moving in one direction "
        "(where a torus beats a ball) and the step-over for a scallop height.",
    )


class FlankSettingCommand(_FeatureCommand):
    kind, icon = "FlankSetting", "flank.svg"
    text = QT_TRANSLATE_NOOP("Machsurf_FlankSetting", "Flank-milling setting")
    tip = QT_TRANSLATE_NOOP(
        "Machsurf_FlankSetting",
        "Select a ruled face: the position of a cylindrical cutter along one rule (standard, optimum with "
        "three tangencies, or minimax) and how far it cuts into or leaves material along the rule.",
    )


class EnvelopeCommand(_FeatureCommand):
    kind, icon, needs_face = "Envelope", "envelope.svg", False
    text = QT_TRANSLATE_NOOP("Machsurf_Envelope", "Swept envelopes")
    tip = QT_TRANSLATE_NOOP(
        "Machsurf_Envelope",
        "The surface a rotational tool sweeps along a motion, and adjacent passes joined with continuous "
        "tangent planes (G1).",
    )


class CamOperationCommand(_FeatureCommand):
    kind, icon = "CamOperation", "cam_operation.svg"
    text = QT_TRANSLATE_NOOP("Machsurf_CamOperation", "CAM operation")
    tip = QT_TRANSLATE_NOOP(
        "Machsurf_CamOperation",
        "Select faces of a part: a path on them in the document's Path Job with the Job's tool (3-axis exact "
        "drop-cutter raster or waterline, 5-axis on one face, or flank milling of a ruled face), checked "
        "against every face of the part before it is kept.",
    )

    def source(self):
        sel = Gui.Selection.getSelectionEx()
        if not sel or not sel[0].SubElementNames:
            return None
        return [(s.Object, list(s.SubElementNames)) for s in sel if s.SubElementNames]


class ExportStepCommand:
    def GetResources(self):
        return {
            "Pixmap": os.path.join(RESOURCES, "export_step.svg"),
            "MenuText": QT_TRANSLATE_NOOP("Machsurf_ExportStep", "Export results to STEP"),
            "ToolTip": QT_TRANSLATE_NOOP(
                "Machsurf_ExportStep",
                "Write every valid machsurf result to one STEP file, each face a named product "
                "(S1_guiding, S2_orientation, pass_1, ...) that CAM systems show.",
            ),
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
    Gui.addCommand("Machsurf_CamOperation", CamOperationCommand())
    Gui.addCommand("Machsurf_ExportStep", ExportStepCommand())
