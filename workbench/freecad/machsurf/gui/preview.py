"""A 5-axis path drawn right (GUI only): FreeCAD 0.20 draws a path's B and C words as rotations, so a
5-axis operation shows swirls beside the part. Beside FreeCAD's Path the operation's view draws the tool
tips as a polyline and the tool axes as lines from the tips (every position up to 400 of them, then evenly
spaced ones), and FreeCAD's own drawing of the path is cut down to its last command. Each is coloured by
the body check's distance there on the maps' diverging scale (blue below 0, white at 0, red above): blue
where the cutting part goes into the part by the gouge tolerance or more, white where it touches (the
cutting moves), red at a millimetre and more of clearance (links)."""

import numpy as np
from pivy import coin

from ..app.maps import colour, normalised

AXIS_LINES = 400
AXIS_LENGTH_MM = 10.0


def preview_colours(distance, tolerance):
    """RGB per position: ``-tolerance`` (and deeper) blue, 0 white, 1 mm (and more) red."""
    d = np.asarray(distance, float)
    t = np.where(d < 0, np.clip(d / max(tolerance, 1e-9), -1, 0), np.clip(d / 1.0, 0, 1))
    return colour(normalised(t, -1.0, 1.0, True), True)


def preview_node(obj) -> coin.SoSeparator:
    """The tips' polyline and the axis lines of ``obj``'s 5-axis path (empty for 3 axes or no path)."""
    sep = coin.SoSeparator()
    if "PreviewTips" not in obj.PropertiesList or len(obj.PreviewTips) < 2:
        return sep
    tips = np.array([(p.x, p.y, p.z) for p in obj.PreviewTips], float)
    axes = np.array([(a.x, a.y, a.z) for a in obj.PreviewAxes], float)
    tol = float(obj.GougeTolerance.Value) if hasattr(obj.GougeTolerance, "Value") else float(obj.GougeTolerance)
    rgb = preview_colours(np.asarray(obj.PreviewDistance, float), tol)
    style = coin.SoDrawStyle()
    style.lineWidth = 2
    binding = coin.SoMaterialBinding()
    binding.value = coin.SoMaterialBinding.PER_VERTEX
    sep.addChild(style)
    sep.addChild(binding)
    line = coin.SoSeparator()
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(tips), tips.tolist())
    mat = coin.SoMaterial()
    mat.diffuseColor.setValues(0, len(rgb), rgb.tolist())
    polyline = coin.SoLineSet()
    polyline.numVertices.setValue(len(tips))
    for node in (coords, mat, polyline):
        line.addChild(node)
    sep.addChild(line)
    k = max(1, int(np.ceil(len(tips) / AXIS_LINES)))
    idx = np.arange(0, len(tips), k)
    ends = np.empty((2 * idx.size, 3))
    ends[0::2] = tips[idx]
    ends[1::2] = tips[idx] + AXIS_LENGTH_MM * axes[idx]
    lines = coin.SoSeparator()
    c2 = coin.SoCoordinate3()
    c2.point.setValues(0, len(ends), ends.tolist())
    m2 = coin.SoMaterial()
    m2.diffuseColor.setValues(0, len(ends), np.repeat(rgb[idx], 2, axis=0).tolist())
    segs = coin.SoLineSet()
    segs.numVertices.setValues(0, idx.size, [2] * idx.size)
    for node in (c2, m2, segs):
        lines.addChild(node)
    sep.addChild(lines)
    return sep


def fill(root, obj) -> None:
    root.removeAllChildren()
    root.addChild(preview_node(obj))


def hide_rotations(obj) -> None:
    """FreeCAD's own drawing of a 5-axis path (B and C drawn as rotations) cut down to its last command while
    the preview stands in for it; all of it again for a 3-axis path."""
    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or "ShowCount" not in vobj.PropertiesList:
        return
    if len(obj.PreviewTips) >= 2:
        vobj.StartIndex = max(len(obj.Path.Commands) - 1, 0)
        vobj.ShowCount = 1
    elif int(vobj.ShowCount) == 1:  # ours: show the whole path again
        vobj.StartIndex = 0
        vobj.ShowCount = 0
