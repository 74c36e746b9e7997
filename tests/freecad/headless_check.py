"""Runs inside FreeCADCmd (FreeCAD's own Python): builds features, recomputes, compares with machsurf_cad
run directly, changes the tool, saves and reopens, checks bad input. Writes every figure to the JSON
file named by MACHSURF_FC_OUT (FreeCADCmd exits 0 even on an uncaught exception: the test reads this)."""

import json
import os
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript

root = os.environ["MACHSURF_ROOT"]
# the add-on is installed in the Mod folder of $HOME (see tests/test_freecad.py)


def main(result):
    result["steps"] = []

    def step(name, **kw):
        result["steps"].append(name)
        result[name] = kw

    import FreeCAD
    import numpy as np
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.convert import face_to_numpy

    from machsurf_cad.machining import machining_surface

    result["no_ocp_in_process"] = "OCP" not in sys.modules and "cadquery" not in sys.modules
    doc = FreeCAD.newDocument("machsurf_test")
    shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = shape
    # the free-form top: the B-spline face with the largest area above z = 20
    idx = max(
        (i for i, f in enumerate(shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: shape.Faces[i].Area,
    )
    fname = f"Face{idx + 1}"
    ms = features.make("MachiningSurface", doc, (part, [fname]), Tool="bull:D=16,r=3", Lead=10.0, Tolerance=1e-3)
    doc.recompute()
    step(
        "recompute",
        valid=ms.isValid(),
        status=ms.Status,
        max_s1=ms.GuidingSurfaceError.Value,
        max_s2=ms.OrientationSurfaceError.Value,
        poles=ms.GuidingSurfacePoles,
        n_faces=len(ms.Shape.Faces),
    )
    # the same computation directly through machsurf_cad, compared by sampling
    nominal = face_to_numpy(shape.Faces[idx], "F")
    direct = machining_surface(nominal, "bull:D=16,r=3", axes=5, strategy="planes:x", lead=10.0, tolerance=1e-3)
    dev = 0.0
    for fc_face, np_face in zip(ms.Shape.Faces, direct.faces()):
        s = np_face.surface
        u0, u1, v0, v1 = s.bounds
        for u in np.linspace(u0, u1, 15):
            for v in np.linspace(v0, v1, 15):
                p = fc_face.Surface.value(float(u), float(v))
                dev = max(dev, float(np.linalg.norm(np.array([p.x, p.y, p.z]) - s.evaluate(u, v))))
    trimmed = [len(f.Wires) for f in ms.Shape.Faces]
    step("compare_direct", max_dev=dev, wires=trimmed, direct_max_s1=direct.s1_fit.max_error)
    # change the tool and recompute
    ms.Tool = "ball:D=10"
    doc.recompute()
    step(
        "change_tool",
        valid=ms.isValid(),
        max_s1=ms.GuidingSurfaceError.Value,
        report_tool=json.loads(ms.Report)["tool"]["spec"],
    )
    # quantities: units shown, every digit kept (0.5 um typed stays 0.0005 mm), floats of old documents migrated
    q = features.make("MachiningSurface", doc, (part, [fname]), Tool="ball:D=10")
    q.Tolerance = "0.5 um"
    tol_value, tol_text = q.Tolerance.Value, q.Tolerance.UserString
    q.Tolerance = 0.001
    old = doc.addObject("Part::FeaturePython", "OldFloats")
    old.addProperty("App::PropertyFloat", "Tolerance", "Approximation", "as saved by 0.2")
    old.addProperty("App::PropertyFloat", "Lead", "Strategy", "as saved by 0.2")
    old.Tolerance, old.Lead = 0.002, 7.5
    features.MachiningSurfaceFeature(old)
    old.Proxy.onDocumentRestored(old)
    step(
        "quantities",
        half_micron=tol_value,
        types=[q.getTypeIdOfProperty(n) for n in ("Tolerance", "Lead", "GuidingSurfaceError", "AlphaMax")],
        tol_text=tol_text,
        mm_text=q.Tolerance.UserString,
        lead_text=q.Lead.UserString,
        migrated=[
            old.getTypeIdOfProperty("Tolerance"),
            old.Tolerance.Value,
            old.getTypeIdOfProperty("Lead"),
            old.Lead.Value,
        ],
    )
    # Axes from a script: the integer users write (and "3" through the factory); a 0.3 enumeration migrated
    q.Axes = 3
    q.Lead = 0.0
    doc.recompute()
    axes_int = {"value": q.Axes, "status": q.Status, "type": q.getTypeIdOfProperty("Axes")}
    q.Axes = 4
    doc.recompute()
    axes_int["four_status"] = q.Status
    enum = doc.addObject("Part::FeaturePython", "OldAxes")
    enum.addProperty("App::PropertyEnumeration", "Axes", "Strategy", "as saved by 0.3")
    enum.Axes = ["5", "3"]
    enum.Axes = "3"
    features.MachiningSurfaceFeature(enum)
    enum.Proxy.onDocumentRestored(enum)
    axes_int["migrated"] = [enum.getTypeIdOfProperty("Axes"), enum.Axes]
    factory = features.make("MachiningSurface", doc, (part, [fname]), Tool="ball:D=10", Axes="3", Lead=0.0)
    axes_int["factory"] = factory.Axes
    step("axes_int", **axes_int)
    for o in (q, old, enum, factory):
        doc.removeObject(o.Name)
    # an invalid tool after a good recompute: the shape and every result emptied, one line, no stale number
    ms.Tool = "bull:D=-1,r=2"
    doc.recompute()
    step(
        "invalid_tool",
        shape_null=ms.Shape.isNull(),
        max_s1=ms.GuidingSurfaceError.Value,
        report=ms.Report,
        poles=ms.GuidingSurfacePoles,
        status=ms.Status,
    )
    ms.Tool = "ball:D=10"
    doc.recompute()
    # the other features
    flat_face = max(
        (i for i, f in enumerate(shape.Faces) if isinstance(f.Surface, Part.Plane)), key=lambda i: shape.Faces[i].Area
    )  # the bottom
    er = features.make("EffectiveRadius", doc, (part, [fname]), Tool="bull:D=10,r=2", Direction=45.0, Grid=32)
    env = features.make("Envelope", doc, None, Tool="cone:D=10,angle=10,L=20", Passes=2)
    doc.recompute()
    step(
        "other_features",
        reff_valid=er.isValid(),
        reff_mean=er.ReffMean.Value,
        env_valid=env.isValid(),
        env_status=env.Status,
        env_gap=env.MaxSeamGap.Value,
        env_faces=len(env.Shape.Faces),
    )
    # bad input: an edge, a planar face (converted), an unreachable tolerance, a deleted source
    bad_edge = features.make("MachiningSurface", doc, (part, ["Edge1"]), Tool="ball:D=10")
    planar = features.make(
        "MachiningSurface", doc, (part, [f"Face{flat_face + 1}"]), Tool="ball:D=10", Lead=10.0, Strategy="planes:x"
    )
    tight = features.make("MachiningSurface", doc, (part, [fname]), Tool="bull:D=16,r=3", Lead=10.0, Tolerance=1e-12)
    doc.recompute()
    step(
        "bad_input",
        edge_valid=bad_edge.isValid(),
        edge_shape_null=bad_edge.Shape.isNull(),
        edge_status=bad_edge.Status,
        planar_valid=planar.isValid(),
        planar_status=planar.Status,
        planar_faces=len(planar.Shape.Faces),
        tight_valid=tight.isValid(),
        tight_shape_null=tight.Shape.isNull(),
        tight_status=tight.Status,
    )
    # save, reopen, recompute
    path = fcscript.out_file("machsurf_test.FCStd")
    ms_name = ms.Name
    ms.removeProperty("Loops")  # as a document saved before the property existed
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc2 = FreeCAD.openDocument(path)
    ms2 = doc2.getObject(ms_name)
    ms2.Tool = "bull:D=16,r=3"
    doc2.recompute()
    step(
        "reopen",
        valid=ms2.isValid(),
        max_s1=ms2.GuidingSurfaceError.Value,
        n_faces=len(ms2.Shape.Faces),
        proxy=type(ms2.Proxy).__name__,
        proxy_module=type(ms2.Proxy).__module__,
        loops=str(ms2.Loops),
        loops_enum=list(ms2.getEnumerationsOfProperty("Loops")),
    )
    # delete the source and recompute: a message and an invalid feature, nothing else broken
    doc2.removeObject("Block")
    doc2.recompute()
    step(
        "deleted_source",
        valid=ms2.isValid(),
        shape_null=ms2.Shape.isNull(),
        max_s1=ms2.GuidingSurfaceError.Value,
        status=ms2.Status,
        n_objects=len(doc2.Objects),
    )
    # preferences (the preferences page writes them): default tolerance and grid of new features, a tool library
    prefs = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/machsurf")
    library = fcscript.out_file("tools.json")
    with open(library, "w") as fh:
        json.dump({"bull16": "bull:D=16,r=3"}, fh)
    prefs.SetFloat("DefaultTolerance", 0.002)
    prefs.SetInt("DefaultGrid", 40)
    prefs.SetString("ToolLibrary", library)
    doc3 = FreeCAD.newDocument("prefs")
    block = doc3.addObject("Part::Feature", "Block")
    block.Shape = shape
    named = features.make("MachiningSurface", doc3, (block, [fname]), Tool="bull16", Lead=10.0)
    unknown = features.make("MachiningSurface", doc3, (block, [fname]), Tool="bull99")
    reff = features.make("EffectiveRadius", doc3, (block, [fname]), Tool="bull16")
    doc3.recompute()
    step(
        "preferences",
        tolerance=named.Tolerance.Value,
        grid=reff.Grid,
        status=named.Status,
        tool=json.loads(named.Report)["tool"]["spec"] if named.Report else "",
        unknown_status=unknown.Status,
    )


fcscript.run(main)
