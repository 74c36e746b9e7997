"""View providers: colouring of the result faces and the per-vertex colour maps with their legend (GUI only).

A feature with a map (machining surface: deviation of the guiding surface; effective radius: R_eff or
step-over; envelope: the fit's deviation) gets the display mode "Map", its default: the map's mesh
coloured per vertex and a legend. The other modes (Flat Lines, Shaded, ...) show the faces, coloured by
their measured error. A CAM operation's map (material left by its path) is drawn beside the tool path, a
flank setting's (distance from the face to the tool around its rule) beside the placed cylinder.
"""

import json

from pivy import coin

from . import colourmap, preview

MAP_MODE = "Map"


class ViewProvider:
    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        from . import session

        session.install()  # a document with machsurf features opened in any workbench
        self.Object = vobj.Object
        self.map_root = coin.SoSeparator()
        if _is_path(vobj.Object):  # beside the path's lines, shown and hidden with the path
            self.switch = coin.SoSwitch()
            group = coin.SoGroup()
            self.preview_root = coin.SoSeparator()  # a 5-axis path drawn right (preview.py)
            group.addChild(self.map_root)
            group.addChild(self.preview_root)
            self.switch.addChild(group)
            preview.fill(self.preview_root, vobj.Object)
            self.switch.whichChild = 0 if vobj.Visibility else -1
            vobj.RootNode.addChild(self.switch)
        else:
            vobj.addDisplayMode(self.map_root, MAP_MODE)
        colourmap.fill(self.map_root, vobj.Object)

    def onChanged(self, vobj, prop):
        if prop == "Visibility" and hasattr(self, "switch"):
            self.switch.whichChild = 0 if vobj.Visibility else -1

    def getDisplayModes(self, vobj):
        return [] if _is_path(vobj.Object) else [MAP_MODE]

    def getDefaultDisplayMode(self):
        obj = getattr(self, "Object", None)
        return MAP_MODE if obj is not None and "MapValues" in obj.PropertiesList else "Flat Lines"

    def setDisplayMode(self, mode):
        return mode

    def updateData(self, obj, prop):
        if prop in ("Shape", "Report"):
            colour_result(obj)
        if prop == "PreviewDistance" and hasattr(self, "preview_root"):
            preview.fill(self.preview_root, obj)
            preview.hide_rotations(obj)
        if prop in ("MapValues", "MapDiverging") and hasattr(self, "map_root"):
            colourmap.fill(self.map_root, obj)

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
            errs = [float(obj.GuidingSurfaceError), float(obj.OrientationSurfaceError)][: len(obj.Shape.Faces)]
            vobj.DiffuseColor = [_ramp(e / tol) for e in errs]
        elif obj.Proxy.__class__.__name__ == "EffectiveRadiusFeature":
            rep = json.loads(obj.Report or "{}")
            R, r = rep.get("R_mm", 1.0), rep.get("r_mm", 0.0)
            vobj.DiffuseColor = [_ramp((float(obj.ReffMean) - r) / max(2 * R - r, 1e-9))]
    except Exception:
        pass


def _is_path(obj) -> bool:
    """Whether the map is drawn beside the object's own view (a path's lines, a placed tool) instead of
    in a display mode of its own."""
    return obj.TypeId.startswith("Path::") or getattr(getattr(obj, "Proxy", None), "MAP_BESIDE", False)


def attach(obj):
    ViewProvider(obj.ViewObject)
    colour_result(obj)
    if "MapValues" in obj.PropertiesList and not _is_path(obj) and MAP_MODE in obj.ViewObject.listDisplayModes():
        obj.ViewObject.DisplayMode = MAP_MODE
