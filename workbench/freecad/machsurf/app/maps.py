"""Per-vertex colour maps of the features' results (App side: no GUI import, recomputes headless).

A map is a quad mesh of points on the result with one value per point: the guiding surface's
deviation from the exact one (machining surface), the effective cutter radius or the step-over
(effective radius), the material a tool path leaves (CAM operation's simulation). It is stored in
properties of the group "Map" so that it is saved with the document and drawn by the view provider
(display mode "Map", with a legend in the 3D view):

- ``MapPoints`` (vector list, mm), ``MapValues`` (float list), ``MapQuads`` (integer list, 4 point
  indices per quad; only quads whose four values are known);
- ``MapTitle`` (what is shown, with its unit), ``MapRange`` (the colour scale's low and high end),
  ``MapMarks`` (values marked on the legend, e.g. the tolerance), ``MapDiverging`` (blue-white-red
  centred on 0 for signed values, else a sequential scale).

The colours are a pure function of the value (:func:`colour`), so the headless tests check the map's
numbers and the GUI draws exactly these.
"""

import math

import numpy as np

GROUP = "Map"
HIDDEN = 2  # property editor mode: not shown (long arrays; the range and marks are read on the legend, where
# they keep their digits: the editor showed them as [-0.00, 0.00]); the title stays visible, read-only
MAX_SIDE = 128  # largest grid drawn per parameter direction (the numbers come from the full grid)


def add_properties(obj):
    """Declare the map properties on ``obj`` (missing ones only: also the migration of older documents)."""
    for kind, name, doc, mode in (
        ("App::PropertyVectorList", "MapPoints", "Points of the colour map (mm)", HIDDEN),
        ("App::PropertyFloatList", "MapValues", "Value at each map point", HIDDEN),
        ("App::PropertyIntegerList", "MapQuads", "Quads of the map, 4 point indices each", HIDDEN),
        ("App::PropertyString", "MapTitle", "What the colour map shows, with its unit", 1),
        ("App::PropertyFloatList", "MapRange", "Low and high end of the colour scale (the legend shows them)", HIDDEN),
        ("App::PropertyFloatList", "MapMarks", "Values marked on the legend (tolerance band)", HIDDEN),
        ("App::PropertyBool", "MapDiverging", "Signed values: blue below 0, white at 0, red above", HIDDEN),
    ):
        if name not in obj.PropertiesList:
            obj.addProperty(kind, name, GROUP, doc)
        obj.setEditorMode(name, mode)


def clear_map(obj):
    """No map (after an error, or before a recompute): nothing stale is drawn."""
    if "MapValues" not in obj.PropertiesList:
        return
    obj.MapQuads = []
    obj.MapValues = []
    obj.MapPoints = []
    obj.MapTitle = ""
    obj.MapRange = []
    obj.MapMarks = []


def grid_map(points, values, inside=None):
    """(points (n, 3), values (n,), quads (k, 4)) of a ``(nu, nv)`` grid, thinned to at most
    :data:`MAX_SIDE` per direction (the last row and column kept); quads with an unknown (NaN) or
    outside corner are left out, and an outside point's value is unknown (NaN)."""
    pts = np.asarray(points, float)
    val = np.asarray(values, float)
    nu, nv = val.shape
    iu = np.unique(np.r_[np.arange(0, nu, max(1, math.ceil(nu / MAX_SIDE))), nu - 1])
    iv = np.unique(np.r_[np.arange(0, nv, max(1, math.ceil(nv / MAX_SIDE))), nv - 1])
    pts, val = pts[np.ix_(iu, iv)], val[np.ix_(iu, iv)]
    ok = np.isfinite(val) & np.isfinite(pts).all(axis=-1)
    if inside is not None:
        ok &= np.asarray(inside, bool)[np.ix_(iu, iv)]
    mu, mv = val.shape
    i, j = np.meshgrid(np.arange(mu - 1), np.arange(mv - 1), indexing="ij")
    a = (i * mv + j).ravel()
    quads = np.stack([a, a + mv, a + mv + 1, a + 1], axis=1)
    quads = quads[ok.ravel()[quads].all(axis=1)]
    return pts.reshape(-1, 3), np.where(ok, val, np.nan).ravel(), quads


def store_map(obj, points, values, quads, *, title, low, high, marks=(), diverging=False):
    """Write a map into ``obj``'s properties: the points with a known value (NaN: none) and the quads
    between them."""
    import FreeCAD

    points, values, quads = np.asarray(points, float), np.asarray(values, float), np.asarray(quads, int)
    known = np.isfinite(values) & np.isfinite(points).all(axis=1)
    quads = quads[known[quads].all(axis=1)] if quads.size else quads.reshape(0, 4)
    used = np.nonzero(known)[0]
    renumber = np.full(len(values), -1)
    renumber[used] = np.arange(len(used))
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        high = low + max(abs(low), 1.0) * 1e-6 if math.isfinite(low) else 1.0
        low = low if math.isfinite(low) else 0.0
    obj.MapPoints = [FreeCAD.Vector(*map(float, p)) for p in points[used]]
    obj.MapValues = [float(v) for v in values[used]]
    obj.MapQuads = [int(k) for k in renumber[quads].ravel()]
    obj.MapTitle = str(title)
    obj.MapRange = [float(low), float(high)]
    obj.MapMarks = [float(m) for m in marks]
    obj.MapDiverging = bool(diverging)


# colour scales: a few stops, interpolated linearly (no matplotlib in FreeCAD's Python needed)
DIVERGING = ((0.0, (0.23, 0.30, 0.75)), (0.5, (0.87, 0.87, 0.87)), (1.0, (0.71, 0.02, 0.15)))  # coolwarm ends
SEQUENTIAL = (
    (0.0, (0.27, 0.00, 0.33)),
    (0.25, (0.23, 0.32, 0.55)),
    (0.5, (0.13, 0.57, 0.55)),
    (0.75, (0.37, 0.79, 0.38)),
    (1.0, (0.99, 0.91, 0.14)),
)  # viridis stops


def colour(t, diverging=False):
    """RGB (0..1) of ``t`` in [0, 1] (clipped) on the map's scale; an array of t gives an (n, 3) array."""
    stops = DIVERGING if diverging else SEQUENTIAL
    x = np.clip(np.asarray(t, float), 0.0, 1.0)
    pos = np.array([s[0] for s in stops])
    rgb = np.array([s[1] for s in stops])
    return np.stack([np.interp(x, pos, rgb[:, k]) for k in range(3)], axis=-1)


def normalised(values, low, high, diverging=False):
    """Where each value sits on the colour scale (0..1): linear from ``low`` to ``high``; a diverging
    scale is centred on 0 (0.5) and symmetric, ``high`` being the largest magnitude."""
    v = np.asarray(values, float)
    if diverging:
        top = max(abs(low), abs(high), 1e-300)
        return 0.5 + 0.5 * v / top
    return (v - low) / max(high - low, 1e-300)


def deviation(ms):
    """The guiding surface's signed deviation from its exact map (mm, along the face normal), on a grid
    off the fit's samples, inside the trimmed face: ``machsurf_cad``'s own deviation map (computed off the GUI
    thread with the surface)."""
    from machsurf_cad.machining.surfaces import fit_deviation

    return fit_deviation(ms, "S1", samples=MAX_SIDE)


def deviation_map(obj, ms, dev):
    """Store :func:`deviation` ``dev`` of ``ms`` as ``obj``'s map."""
    n = MAX_SIDE
    val = np.full(n * n, np.nan)
    pts = np.full((n * n, 3), np.nan)
    if dev.grid_index is not None:
        val[dev.grid_index] = dev.signed
        pts[:] = dev.grid_points
    else:
        val[:] = dev.signed
        pts[:] = dev.points
    p, v, q = grid_map(pts.reshape(n, n, 3), val.reshape(n, n))
    tol = float(ms.tolerance)
    top = max(float(np.nanmax(np.abs(val))) if np.isfinite(val).any() else 0.0, tol)
    store_map(obj, p, v, q, title="guiding surface deviation [mm]", low=-top, high=top, marks=(-tol, tol),
              diverging=True)  # fmt: skip
    return dev


def reff_map(obj, m, shows):
    """The effective-radius feature's map: ``shows`` is 'effective radius' (mm) or 'step-over' (mm, for the
    feature's scallop height) of its one direction, over the face's grid (outside the trimmed face left out)."""
    from machsurf_cad.errors import InputError

    d = m.directions[0]
    if shows == "step-over":
        if d.stepover is None:
            raise InputError("the step-over map needs a scallop height: set 'Scallop' above 0")
        values, title = d.stepover, f"step-over for a {m.scallop:g} mm scallop [mm]"
    else:
        values, title = d.r_eff, "effective cutter radius [mm]"
    values = np.where(np.isfinite(values), values, np.nan)  # an infinite R_eff (flat spot) has no colour
    p, v, q = grid_map(m.points, values, m.inside)
    known = values[np.asarray(m.inside, bool) & np.isfinite(values)]
    low, high = (float(known.min()), float(known.max())) if known.size else (0.0, 1.0)
    store_map(obj, p, v, q, title=title, low=low, high=high)


def simulation_map(obj, sim, tolerance):
    """Material a tool path leaves (mm along the outward normal: + left, - gouge) from
    ``machsurf_cad.simulate``: in the machined region (under and between the passes; its largest value is
    ``max_scallop``), and gouges wherever they are; the unmachined border and samples not measured are not
    drawn (the report gives the border's figures)."""
    value = np.where(sim.in_region | (sim.known & (sim.value < 0)), sim.value, np.nan)
    ok = np.isfinite(value)
    top = max(float(np.nanmax(np.abs(value))) if ok.any() else 0.0, tolerance)
    store_map(obj, sim.points, value, np.asarray(sim.quads, int).reshape(-1, 4),
              title="material left, machined region [mm] (+ left, - gouge)", low=-top, high=top,
              marks=(-tolerance, tolerance), diverging=True)  # fmt: skip


def envelope_map(obj, chain, tolerance, n: int = 64):
    """Each pass's fitted face against its exact envelope (mm, signed along the fitted face's normal), on
    grids off the fit's samples, all passes in one map."""
    P, V, Q = [], [], []
    top = tolerance
    for env, fit in zip(chain.passes, chain.fits):
        a0, a1, t0, t1 = env.bounds
        w = (np.arange(n) + 0.3819660112501051) / n
        as_, ts = a0 + (a1 - a0) * w, t0 + (t1 - t0) * w
        d = fit.surface.derivatives_grid(as_, ts, 1)
        normal = np.cross(d.su, d.sv)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        diff = d.point - env.grid(as_, ts)
        signed = np.einsum("...i,...i->...", diff, normal)
        p, v, q = grid_map(d.point, signed)
        Q.append(q + sum(len(x) for x in P))
        P.append(p)
        V.append(v)
        top = max(top, float(np.nanmax(np.abs(signed))))
    store_map(obj, np.concatenate(P), np.concatenate(V), np.concatenate(Q), title="envelope fit deviation [mm]",
              low=-top, high=top, marks=(-tolerance, tolerance), diverging=True)  # fmt: skip


def flank_map(obj, face, u_p, placement, R, n_v: int = 97, n_u: int = 41):
    """Distance from the ruled face to the placed cylinder (mm: + outside the tool, - gouge) over the band
    the setting's interference is measured on: ``R`` mm either side of the tool's rule along the
    directrices. Across the band at each point of the rule its smallest value is the error along the rule
    (the feature's MaxGouge is minus the lowest); the colour scale spans that error, larger distances
    (the face turning away from the tool) saturate."""
    tip, axis, length = placement
    u0, u1, v0, v1 = face.uv_bounds
    vs = np.linspace(v0, v1, n_v)
    su = np.linalg.norm(face.surface.derivatives(np.full(n_v, u_p), vs, 1).su, axis=1)
    half = R / max(float(np.median(su)), 1e-12)
    us = np.linspace(max(u0, u_p - half), min(u1, u_p + half), n_u)
    pts = face.surface.evaluate_grid(us, vs)
    q = pts - np.asarray(tip, float)
    a = np.asarray(axis, float)
    along = q @ a
    dist = np.linalg.norm(q - along[..., None] * a, axis=-1) - R
    p, v, qd = grid_map(pts, dist)
    profile = dist.min(axis=0)  # along the rule: the closest approach across the band
    top = max(float(np.abs(profile).max()), 1e-6)
    store_map(obj, p, v, qd, title="distance to the tool [mm] (+ outside, - gouge)", low=-top, high=top,
              diverging=True)  # fmt: skip
