"""Runs inside FreeCADCmd: a CamOperation on the free-form block in a Path Job (created for it), its tool from
the Job's ToolController, its Path against the CSV machsurf writes for the same path, the ToolBit mapping
(bull-nose FlatRadius), and a Job without tools. Writes every figure to MACHSURF_FC_OUT."""

import csv
import json
import os
import traceback
import types

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}
try:
    import FreeCAD
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.app.camop import cutter_from_toolbit, find_job
    from freecad.machsurf.convert import face_to_numpy

    import machsurf_cad as ms

    doc = FreeCAD.newDocument("cam")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    op = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster", StepOver=4.0)
    doc.recompute()
    job = find_job(doc, create=False)
    g1 = [c for c in op.Path.Commands if c.Name == "G1"]
    result["op"] = {
        "status": op.Status,
        "verdict": op.Verdict,
        "in_job": job is not None and op in job.Operations.Group,
        "tool": op.CutterUsed,
        "tc_diameter": job.Tools.Group[0].Tool.Diameter.Value if job else None,
        "n_g1": len(g1),
        "n_g0": sum(c.Name == "G0" for c in op.Path.Commands),
        "cut_points": op.CutPoints,
        "max_gouge": op.MaxGouge.Value,
    }
    # the same path from machsurf_cad directly, written as CSV: every non-rapid row is one G1, same point
    faces = [face_to_numpy(f, f"Block.Face{i + 1}") for i, f in enumerate(part.Shape.Faces)]
    rest = [f for i, f in enumerate(faces) if i != top]
    tp = ms.raster([faces[top]], ms.parse_cutter(op.CutterUsed), check_faces=rest, stepover_mm=4.0,
                   chordal_tolerance_mm=0.01, clearance_mm=5.0, verify_tolerance_mm=0.01)  # fmt: skip
    csv_path = os.path.join(os.path.dirname(out_path), "cam.csv")
    ms.write_csv(csv_path, tp)
    rows = [r for r in csv.DictReader(open(csv_path)) if r["move"] != "rapid"]
    dev = max(
        max(abs(c.Parameters[k] - float(r[f"tip_{k.lower()}"])) for k in "XYZ") for c, r in zip(g1, rows)
    ) if len(rows) == len(g1) else None  # fmt: skip
    result["csv"] = {"rows": len(rows), "cut_rows": sum(r["move"] == "cut" for r in rows), "max_dev": dev}
    # the ToolBit mapping: FreeCAD's bull-nose FlatRadius is D/2 - r
    bull = types.SimpleNamespace(ShapeName="bullnose", Diameter=10.0, FlatRadius=3.0, CuttingEdgeHeight=20.0)
    ball = types.SimpleNamespace(ShapeName="ballend", Diameter=6.0, CuttingEdgeHeight=0.0)
    try:
        cutter_from_toolbit(types.SimpleNamespace(ShapeName="chamfer", Diameter=6.0))
        chamfer = "accepted"
    except Exception as exc:
        chamfer = str(exc)
    result["mapping"] = {"bull": cutter_from_toolbit(bull), "ball": cutter_from_toolbit(ball), "chamfer": chamfer}
    # a Job without tools and no Tool text: one line, an empty path
    for tc in list(job.Tools.Group):
        job.Tools.removeObject(tc)
        doc.removeObject(tc.Name)
    op.ToolController = None
    doc.recompute()
    result["no_tool"] = {"status": op.Status, "n_commands": len(op.Path.Commands), "cut_points": op.CutPoints}
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
