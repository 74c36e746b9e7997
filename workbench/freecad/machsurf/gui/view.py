"""View providers: colouring of the result faces (GUI only)."""

import json


class ViewProvider:
    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        self.Object = vobj.Object

    def updateData(self, obj, prop):
        if prop in ("Shape", "Report"):
            colour_result(obj)

    def getIcon(self):
        from .commands import ICON

        return ICON

    def setEdit(self, vobj, mode=0):
        import FreeCADGui as Gui

        from .panels import FeaturePanel

        Gui.Control.showDialog(FeaturePanel(vobj.Object))
        return True

    def unsetEdit(self, vobj, mode=0):
        import FreeCADGui as Gui

        Gui.Control.closeDialog()
        return True

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None


def _ramp(x):
    """Blue (0) to red (1)."""
    x = min(max(x, 0.0), 1.0)
    return (x, 0.3 * (1 - abs(2 * x - 1)), 1.0 - x)


def colour_result(obj):
    """Machining surfaces: each face coloured by its measured error over the tolerance (blue within,
    red at or over); effective radius: the face coloured by mean R_eff between r and 2R."""
    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or not hasattr(obj, "Shape") or obj.Shape.isNull():
        return
    try:
        if obj.Proxy.__class__.__name__ == "MachiningSurfaceFeature":
            tol = max(float(obj.Tolerance), 1e-300)
            errs = [float(obj.MaxErrorS1), float(obj.MaxErrorS2)][: len(obj.Shape.Faces)]
            vobj.DiffuseColor = [_ramp(e / tol) for e in errs]
        elif obj.Proxy.__class__.__name__ == "EffectiveRadiusFeature":
            rep = json.loads(obj.Report or "{}")
            R, r = rep.get("R_mm", 1.0), rep.get("r_mm", 0.0)
            vobj.DiffuseColor = [_ramp((float(obj.ReffMean) - r) / max(2 * R - r, 1e-9))]
    except Exception:
        pass


def attach(obj):
    ViewProvider(obj.ViewObject)
    colour_result(obj)
