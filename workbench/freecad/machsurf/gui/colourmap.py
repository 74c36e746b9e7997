"""The colour map of a feature in the 3D view: the map's mesh coloured per vertex and a legend (GUI only).

The map itself (points, values, range, marks) is computed by the App feature (:mod:`..app.maps`);
this module only turns it into Coin nodes: a smooth-shaded indexed face set with one colour per
vertex and, drawn over the scene in screen space, a colour bar with the title, five values and the
marked values (the tolerance band) as black lines.
"""

import numpy as np
from pivy import coin

from ..app.maps import colour, normalised

LEGEND_STEPS = 32


def has_map(obj) -> bool:
    return "MapValues" in obj.PropertiesList and len(obj.MapValues) > 0 and len(obj.MapQuads) >= 4


def tick_format(values) -> str:
    """One fixed-point format for all of a legend's numbers: the decimals of their step, up to two more where
    the ticks need them (``0.0005``, ``0.0010``; never a mix of ``0.001`` and ``5.00e-04``)."""
    v = np.unique(np.asarray(values, float)[np.isfinite(values)])
    step = float(np.min(np.diff(v))) if v.size > 1 else float(np.max(np.abs(v), initial=0.0))
    if not step > 0:
        return "{:.3f}"
    d0 = max(0, int(np.ceil(-np.log10(step) - 1e-9)))
    d = d0
    while d < min(d0 + 2, 12) and np.max(np.abs(v * 10.0**d - np.round(v * 10.0**d))) > 1e-6:
        d += 1
    return f"{{:.{d}f}}"


def surface_node(obj) -> coin.SoSeparator:
    """The map's mesh with per-vertex colours (empty when there is no map)."""
    sep = coin.SoSeparator()
    if not has_map(obj):
        return sep
    pts = np.array([(p.x, p.y, p.z) for p in obj.MapPoints], float)
    val = np.asarray(obj.MapValues, float)
    quads = np.asarray(obj.MapQuads, int).reshape(-1, 4)
    quads = quads[(quads < len(pts)).all(axis=1)]  # a map being rewritten: skip what does not fit yet
    low, high = obj.MapRange
    rgb = colour(normalised(val, low, high, obj.MapDiverging), obj.MapDiverging)
    hints = coin.SoShapeHints()
    hints.vertexOrdering = coin.SoShapeHints.COUNTERCLOCKWISE
    hints.shapeType = coin.SoShapeHints.UNKNOWN_SHAPE_TYPE  # two-sided lighting
    hints.creaseAngle = 1.0
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(pts), pts.tolist())
    mat = coin.SoMaterial()
    mat.diffuseColor.setValues(0, len(rgb), rgb.tolist())
    binding = coin.SoMaterialBinding()
    binding.value = coin.SoMaterialBinding.PER_VERTEX_INDEXED
    index = np.concatenate([quads, np.full((len(quads), 1), -1)], axis=1).ravel().tolist()
    faces = coin.SoIndexedFaceSet()
    faces.coordIndex.setValues(0, len(index), index)
    faces.materialIndex.setValues(0, len(index), index)
    for node in (hints, coords, mat, binding, faces):
        sep.addChild(node)
    return sep


def _text(sep, xy, text, rgb=(0.0, 0.0, 0.0)):
    s = coin.SoSeparator()
    tr = coin.SoTranslation()
    tr.translation = (xy[0], xy[1], 0.0)
    col = coin.SoBaseColor()
    col.rgb = rgb
    label = coin.SoText2()
    label.string = text
    for node in (tr, col, label):
        s.addChild(node)
    sep.addChild(s)


def legend_node(obj) -> coin.SoSeparator:
    """A colour bar in screen space (left of the view) with the map's title, five values and its marks."""
    sep = coin.SoSeparator()
    if not has_map(obj):
        return sep
    low, high = obj.MapRange
    div = obj.MapDiverging
    hud = coin.SoSeparator()
    cam = coin.SoOrthographicCamera()
    cam.viewportMapping = coin.SoCamera.LEAVE_ALONE
    cam.position = (0.0, 0.0, 5.0)
    cam.height = 2.0
    cam.nearDistance = 0.1
    cam.farDistance = 10.0
    light = coin.SoLightModel()
    light.model = coin.SoLightModel.BASE_COLOR
    font = coin.SoFont()
    font.size = 14
    for node in (cam, light, font):
        hud.addChild(node)
    x0, x1, y0, y1 = -0.97, -0.91, -0.8, 0.75
    values = (
        np.linspace(-max(abs(low), abs(high)), max(abs(low), abs(high)), LEGEND_STEPS + 1)
        if div
        else np.linspace(low, high, LEGEND_STEPS + 1)
    )
    rgb = colour(normalised(values, low, high, div), div)
    ys = np.linspace(y0, y1, LEGEND_STEPS + 1)
    pts = [(x, y, 0.0) for y in ys for x in (x0, x1)]
    coords = coin.SoCoordinate3()
    coords.point.setValues(0, len(pts), pts)
    mat = coin.SoMaterial()
    cols = [tuple(c) for c in rgb for _ in (0, 1)]
    mat.diffuseColor.setValues(0, len(cols), cols)
    binding = coin.SoMaterialBinding()
    binding.value = coin.SoMaterialBinding.PER_VERTEX_INDEXED
    index = []
    for i in range(LEGEND_STEPS):
        a = 2 * i
        index += [a, a + 1, a + 3, a + 2, -1]
    bar = coin.SoIndexedFaceSet()
    bar.coordIndex.setValues(0, len(index), index)
    bar.materialIndex.setValues(0, len(index), index)
    for node in (coords, mat, binding, bar):
        hud.addChild(node)
    span = values[-1] - values[0] or 1.0
    ticks = np.linspace(values[0], values[-1], 5)
    marks = [m for m in obj.MapMarks if values[0] <= m <= values[-1]]
    fmt = tick_format([*ticks, *marks]).format  # one format for the ticks and the marks
    for v in ticks:
        _text(hud, (x1 + 0.01, y0 + (y1 - y0) * (v - values[0]) / span - 0.01), fmt(v))
    if marks:
        mp = []
        for m in marks:
            y = y0 + (y1 - y0) * (m - values[0]) / span
            mp += [(x0 - 0.01, y, 0.0), (x1 + 0.01, y, 0.0)]
        mc = coin.SoCoordinate3()
        mc.point.setValues(0, len(mp), mp)
        black = coin.SoBaseColor()
        black.rgb = (0.0, 0.0, 0.0)
        style = coin.SoDrawStyle()
        style.lineWidth = 3
        lines = coin.SoLineSet()
        lines.numVertices.setValues(0, len(marks), [2] * len(marks))
        s = coin.SoSeparator()
        for node in (mc, black, style, lines):
            s.addChild(node)
        hud.addChild(s)
        _text(hud, (x0, y0 - 0.07), "black lines: tolerance " + ", ".join(fmt(m) for m in marks))
    _text(hud, (x0, y1 + 0.06), obj.MapTitle)
    annotation = coin.SoAnnotation()
    annotation.addChild(hud)
    sep.addChild(annotation)
    return sep


def fill(root: coin.SoSeparator, obj) -> None:
    """Replace ``root``'s children by the map of ``obj`` (surface and legend); empty without a map."""
    root.removeAllChildren()
    if has_map(obj):
        root.addChild(surface_node(obj))
        root.addChild(legend_node(obj))
