"""Runs inside FreeCADCmd: the features' colour maps against machsurf_cad computed directly, the colour
scale, the migration of properties renamed to CAM vocabulary, cancelling a recompute from the progress
bar, the memory a grid needs. Writes every figure to MACHSURF_FC_OUT."""

import json
import os
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}
try:
    import FreeCAD
    import numpy as np
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.app import maps
    from freecad.machsurf.app.features import Progress
    from freecad.machsurf.convert import face_to_numpy

    import machsurf_cad as msc
    from machsurf_cad.machining.surfaces import fit_deviation

    doc = FreeCAD.newDocument("maps")
    shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = shape
    idx = max(
        (i for i, f in enumerate(shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: shape.Faces[i].Area,
    )
    fname = f"Face{idx + 1}"
    nominal = face_to_numpy(shape.Faces[idx], "F")

    # the machining surface's map: the guiding surface's deviation, as machsurf_cad measures it directly
    ms = features.make("MachiningSurface", doc, (part, [fname]), Tool="bull:D=16,r=3", Lead=10.0, Tolerance=1e-3)
    doc.recompute()
    direct = msc.machining_surface(nominal, "bull:D=16,r=3", axes=5, strategy="planes:x", lead=10.0, tolerance=1e-3)
    dev = fit_deviation(direct, "S1", samples=maps.MAX_SIDE)
    pts = np.array([(p.x, p.y, p.z) for p in ms.MapPoints])
    vals = np.array(ms.MapValues)
    # each map point is a point of the direct map's grid: same point, same value
    grid = dev.grid_points if dev.grid_points is not None else dev.points
    full = np.full(len(grid), np.nan)
    full[dev.grid_index if dev.grid_index is not None else slice(None)] = dev.signed
    d2 = ((pts[:, None, :] - grid[None, :, :]) ** 2).sum(-1)
    nearest = d2.argmin(axis=1)
    result["deviation_map"] = {
        "status": ms.Status,
        "n_points": len(vals),
        "n_quads": len(ms.MapQuads) // 4,
        "max_point_gap": float(np.sqrt(d2.min(axis=1)).max()),
        "max_value_diff": float(np.abs(vals - full[nearest]).max()),
        "max_abs": float(np.abs(vals).max()),
        "direct_max_abs": float(dev.max_abs),
        "fit_max_error": ms.GuidingSurfaceError.Value,
        "range": list(ms.MapRange),
        "marks": list(ms.MapMarks),
        "diverging": bool(ms.MapDiverging),
        "title": ms.MapTitle,
        "quads_in_range": bool(np.all(np.array(ms.MapQuads) < len(vals))),
    }

    # the effective-radius map (grid 64: not thinned) and the step-over map, against reff_maps directly
    er = features.make("EffectiveRadius", doc, (part, [fname]), Tool="bull:D=10,r=2", Direction=30.0, Grid=64,
                       Scallop=0.01)  # fmt: skip
    doc.recompute()
    m = msc.reff_maps(nominal, "bull:D=10,r=2", directions=[30.0], grid=64, scallop=0.01)
    d = m.directions[0]
    inside = np.asarray(m.inside, bool)
    reff_vals = np.array(er.MapValues)
    result["reff_map"] = {
        "status": er.Status,
        "n_points": len(reff_vals),
        "min": float(reff_vals.min()),
        "max": float(reff_vals.max()),
        "direct_min": float(d.r_eff[inside & np.isfinite(d.r_eff)].min()),
        "direct_max": float(d.r_eff[inside & np.isfinite(d.r_eff)].max()),
        "prop_min": er.ReffMin.Value,
        "prop_max": er.ReffMax.Value,
        "range": list(er.MapRange),
        "title": er.MapTitle,
        "memory_64": er.MemoryNeeded,
    }
    er.MapShows = "step-over"
    doc.recompute()
    so = np.array(er.MapValues)
    ok = inside & np.isfinite(d.stepover)
    result["stepover_map"] = {
        "status": er.Status,
        "min": float(so.min()),
        "max": float(so.max()),
        "direct_min": float(d.stepover[ok].min()),
        "direct_max": float(d.stepover[ok].max()),
        "title": er.MapTitle,
    }
    er.Scallop = 0.0  # a step-over map without a scallop height: a message, no stale map
    doc.recompute()
    result["stepover_without_scallop"] = {"status": er.Status, "n_values": len(er.MapValues), "valid": er.isValid()}
    er.Grid = 1024
    result["memory_1024"] = er.MemoryNeeded

    # the envelope's map: each pass's fit against its exact envelope; the flank setting's: the distance from
    # the face to the placed cylinder around the rule (its most negative value is the setting's gouge)
    env = features.make("Envelope", doc, None, Tool="cone:D=10,angle=10,L=20", Passes=2, Tolerance=1e-3)
    s = msc.example("hypar")
    u0, u1, v0, v1 = s.bounds
    from freecad.machsurf.convert import surface_to_part

    ruled = doc.addObject("Part::Feature", "Hypar")
    ruled.Shape = surface_to_part(s).toShape(u0, u1, v0, v1)
    fl = features.make("FlankSetting", doc, (ruled, ["Face1"]), Radius=40.0, Setting="optimum")
    doc.recompute()
    ev = np.array(env.MapValues)
    fv = np.array(fl.MapValues)
    result["envelope_map"] = {"status": env.Status, "n": int(ev.size), "max_abs": float(np.abs(ev).max()),
                              "marks": list(env.MapMarks), "title": env.MapTitle}  # fmt: skip
    result["flank_map"] = {"status": fl.Status, "n": int(fv.size), "min": float(fv.min()), "max": float(fv.max()),
                           "gouge": fl.MaxGouge.Value, "undercut": fl.MaxUndercut.Value,
                           "title": fl.MapTitle}  # fmt: skip

    # the colour scales
    result["colours"] = {
        "div_low": maps.colour(0.0, True).tolist(),
        "div_mid": maps.colour(0.5, True).tolist(),
        "div_high": maps.colour(1.0, True).tolist(),
        "seq_low": maps.colour(0.0).tolist(),
        "seq_high": maps.colour(1.0).tolist(),
        "clipped": maps.colour(7.0).tolist(),
        "norm_div": maps.normalised([-2.0, 0.0, 1.0], -2.0, 2.0, True).tolist(),
        "norm_seq": maps.normalised([3.0, 4.0, 5.0], 3.0, 5.0).tolist(),
    }

    # documents of version 0.2: paper vocabulary renamed (values kept), results dropped and recomputed
    old = doc.addObject("Part::FeaturePython", "OldFlank")
    features.FlankSettingFeature(old)
    for name in ("RulePosition", "ToolSide"):
        old.removeProperty(name)
    old.addProperty("App::PropertyFloatConstraint", "Rule", "Strategy", "")
    old.Rule = (0.25, 0.0, 1.0, 0.05)
    old.addProperty("App::PropertyInteger", "Side", "Strategy", "")
    old.Side = -1
    old.Proxy.onDocumentRestored(old)
    oldms = doc.addObject("Part::FeaturePython", "OldMS")
    features.MachiningSurfaceFeature(oldms)
    oldms.removeProperty("GuidingSurfaceError")
    oldms.addProperty("App::PropertyLength", "MaxErrorS1", "Result", "")
    oldms.MaxErrorS1 = 0.5
    oldms.Proxy.onDocumentRestored(oldms)
    oldenv = doc.addObject("Part::FeaturePython", "OldEnv")
    features.EnvelopeFeature(oldenv)
    oldenv.removeProperty("PassTurn")
    oldenv.addProperty("App::PropertyAngle", "Theta", "Motion", "")
    oldenv.Theta = 4.0
    oldenv.Proxy.onDocumentRestored(oldenv)
    result["migration"] = {
        "rule": float(old.RulePosition),
        "side": str(old.ToolSide),
        "old_gone": [
            n
            for n in ("Rule", "Side", "MaxErrorS1", "Theta")
            if n in old.PropertiesList + oldms.PropertiesList + oldenv.PropertiesList
        ],  # fmt: skip
        "guiding_error_prop": "GuidingSurfaceError" in oldms.PropertiesList,
        "pass_turn": oldenv.PassTurn.Value,
        "map_props": "MapValues" in oldms.PropertiesList,
    }

    # cancel: FreeCAD's sequencer raises RuntimeError from next(True) when the user pressed Esc
    class Cancelling:
        calls = 0

        def start(self, text, steps):
            pass

        def next(self, can_abort=False):
            Cancelling.calls += 1
            if can_abort and Cancelling.calls >= 2:
                raise RuntimeError("abort exception")

        def stop(self):
            pass

    ms.Tool = "bull:D=16,r=3"
    ms.Tolerance = 1e-5  # several refinements: progress is called more than once
    doc.recompute()
    before = {"valid": ms.isValid(), "n_values": len(ms.MapValues), "error": ms.GuidingSurfaceError.Value}
    proxy = ms.Proxy
    real = Progress.__init__

    def cancelling_init(self, indicator=None):
        real(self, indicator=Cancelling)

    Progress.__init__ = cancelling_init  # the test's stand-in for the GUI's Esc
    ms.Tolerance = 2e-5
    doc.recompute()
    Progress.__init__ = real
    result["cancel"] = {
        "before": before,
        "status": ms.Status,
        "shape_null": ms.Shape.isNull(),
        "error": ms.GuidingSurfaceError.Value,
        "n_values": len(ms.MapValues),
        "calls": Cancelling.calls,
        "proxy_same": ms.Proxy is proxy,
    }
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
with open(out_path, "w") as fh:
    json.dump(result, fh, default=str)
