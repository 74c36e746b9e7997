"""Runs inside FreeCADCmd: a CamOperation on the free-form block in a Path Job (created for it), its tool from
the Job's ToolController, its Path against the CSV machsurf writes for the same path, the ToolBit mapping
(bull-nose FlatRadius), and a Job without tools. Writes every figure to MACHSURF_FC_OUT."""

import csv
import json
import os
import sys
import types

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript
from fcscript import split_moves


def path_moves(commands):
    return split_moves(commands)[0]


def safe_moves(commands):
    return split_moves(commands)[1]


root = os.environ["MACHSURF_ROOT"]


def main(result):
    import FreeCAD
    import numpy as np
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.app.camop import cutter_from_toolbit, find_job
    from freecad.machsurf.convert import face_to_numpy, surface_to_part

    import machsurf_cad as ms

    doc = FreeCAD.newDocument("cam")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    top = max(
        (i for i, f in enumerate(part.Shape.Faces) if isinstance(f.Surface, Part.BSplineSurface)),
        key=lambda i: part.Shape.Faces[i].Area,
    )
    op = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster", StepOver=4.0)
    status_after_make = op.Status  # the Job's creation recomputed the document: no false "no tool" error
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
    # FreeCAD's Path simulator (its voxel engine, as the Path_Simulator command runs it) takes the operation's
    # moves with the ToolBit's shape: material comes off the stock, and what is left still holds the part
    import PathSimulator

    stock = job.Stock.Shape
    sim = PathSimulator.PathSim()
    sim.BeginSimulation(stock, 0.5)
    sim.SetToolShape(job.Tools.Group[0].Tool.Shape, 0.05)
    pos = FreeCAD.Placement(FreeCAD.Vector(0, 0, stock.BoundBox.ZMax), FreeCAD.Rotation())
    applied = 0
    for c in op.Path.Commands:
        if c.Name in ("G0", "G1"):
            pos = sim.ApplyCommand(pos, c)
            applied += 1
    left = sim.GetResultMesh()[0]
    result["path_simulator"] = {"applied": applied, "stock_volume": stock.Volume, "left_volume": left.Volume,
                                "part_volume": part.Shape.Volume}  # fmt: skip
    # the same path from machsurf_cad directly, written as CSV: every non-rapid row is one G1, same point
    faces = [face_to_numpy(f, f"Block.Face{i + 1}") for i, f in enumerate(part.Shape.Faces)]
    rest = [f for i, f in enumerate(faces) if i != top]
    tp = ms.raster([faces[top]], ms.parse_cutter(op.CutterUsed), check_faces=rest, stepover=4.0,
                   chordal_tolerance=0.005, clearance=5.0, gouge_tolerance=0.01)  # the defaults  # fmt: skip
    tp = ms.check_toolpath(tp, faces, gouge_tolerance=0.01, clearance=5.0).toolpath  # what is written: checked
    csv_path = fcscript.out_file("cam.csv")
    ms.write_csv(csv_path, tp)
    rows = [r for r in csv.DictReader(open(csv_path)) if r["move"] != "rapid"]
    dev = max(
        max(abs(c.Parameters[k] - float(r[f"tip_{k.lower()}"])) for k in "XYZ") for c, r in zip(g1, rows)
    ) if len(rows) == len(g1) else None  # fmt: skip
    result["csv"] = {"rows": len(rows), "cut_rows": sum(r["move"] == "cut" for r in rows), "max_dev": dev}
    # the ToolBit mapping: FreeCAD's bull-nose FlatRadius is D/2 - r
    bull = types.SimpleNamespace(ShapeName="bullnose", Diameter=10.0, FlatRadius=3.0, CuttingEdgeHeight=20.0)
    ball = types.SimpleNamespace(ShapeName="ballend", Diameter=6.0, CuttingEdgeHeight=0.0)
    chamfer = types.SimpleNamespace(ShapeName="chamfer", Diameter=12.0, FlatRadius=1.0, CuttingEdgeAngle=90.0)

    def refused(tool):
        try:
            return "accepted: " + cutter_from_toolbit(tool)
        except Exception as exc:
            return str(exc)

    result["mapping"] = {
        "bull": cutter_from_toolbit(bull), "ball": cutter_from_toolbit(ball), "chamfer": cutter_from_toolbit(chamfer),
        "pointed_vbit": refused(types.SimpleNamespace(ShapeName="v-bit", Diameter=6.0, TipDiameter=0.0,
                                                      CuttingEdgeAngle=60.0)),
        "drill": refused(types.SimpleNamespace(ShapeName="drill", Diameter=6.0)),
    }  # fmt: skip
    # a Tool text that disagrees with the ToolController is refused by name (the controller's flat D5 stays)
    op.Tool = "ball:D=6"
    doc.recompute()
    result["mismatch"] = {"status": op.Status, "n_commands": len(op.Path.Commands)}
    op.Tool = "flat:D=5"  # agreeing: fine
    doc.recompute()
    result["mismatch"]["agreeing_status"] = op.Status
    op.Tool = ""
    doc.recompute()
    # 5 axes on the guiding surface (ball D6, lead 10 deg): B/C give back machsurf's axes, tips as its path
    five = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="5-axis surface", StepOver=4.0,
                         Tool="ball:D=6", Lead=10.0)  # fmt: skip
    five.ToolController = None
    apt = fcscript.out_file("five.apt")
    five.AptFile = apt
    doc.recompute()
    m5 = ms.machining_surface(faces[top], "ball:D=6", axes=5, strategy="planes:-0,1,0", lead=10.0, tolerance=1e-3)
    tp5 = ms.tool_paths(m5, stepover=4.0, chordal_tolerance=0.005, clearance=5.0,
                        safe_sphere=ms.part_sphere(faces, 5.0))  # fmt: skip
    moves = path_moves(five.Path.Commands)
    safe = safe_moves(five.Path.Commands)
    result["safe_moves"] = {
        "first": [dict(c.Parameters) for c in safe[:2]],
        "last": dict(safe[-1].Parameters) if safe else None,
        "path_first": dict(moves[0].Parameters),
        "path_last": dict(moves[-1].Parameters),
        "stock_top": job.Stock.Shape.BoundBox.ZMax,
        "status_after_make": status_after_make,
    }
    tips = np.array([[c.Parameters[k] for k in "XYZ"] for c in moves])
    bc = np.radians([[c.Parameters["B"], c.Parameters["C"]] for c in moves])
    axes = np.stack([np.sin(bc[:, 0]) * np.cos(bc[:, 1]), np.sin(bc[:, 0]) * np.sin(bc[:, 1]), np.cos(bc[:, 0])], 1)
    same = len(moves) == len(tp5.tip)
    result["five_axis"] = {
        "status": five.Status,
        "verdict": five.Verdict,
        "tool": five.CutterUsed,
        "n_moves": len(moves),
        "n_direct": int(len(tp5.tip)),
        "cut_points": five.CutPoints,
        "direct_cut": int(tp5.n_cut),
        "tip_dev": float(np.abs(tips - tp5.tip).max()) if same else None,
        "axis_dev": float(np.abs(axes - tp5.axis).max()) if same else None,
        "max_c_jump": float(np.degrees(np.abs(np.diff(bc[:, 1]))).max()),
        "max_b": float(np.degrees(bc[:, 0]).max()),
        "surface_error": five.SurfaceError.Value,
        # no ToolController: the operation posts its own tool change before its first move
        "tool_change": [(c.Name, dict(c.Parameters)) for c in five.Path.Commands if c.Name in ("M6", "M3")],
        "tool_change_before_moves": next(i for i, c in enumerate(five.Path.Commands) if c.Name == "M6")
        < next(i for i, c in enumerate(five.Path.Commands) if c.Name in ("G0", "G1")),
    }
    back = ms.read_apt(apt)  # the APT beside it: the same positions and axes
    result["apt"] = {
        "n": int(len(back.tip)),
        "tip_dev": float(np.abs(back.tip - tp5.tip).max()) if len(back.tip) == len(tp5.tip) else None,
        "axis_dev": float(np.abs(back.axis - tp5.axis).max()) if len(back.tip) == len(tp5.tip) else None,
        "feed_line": next((ln.strip() for ln in open(apt) if ln.startswith("FEDRAT")), ""),
    }
    # a bull D40 r2 at lead 3 gouges the block's top (its concave parts): refused, or cut down and relinked
    # (TrimGouges), or tilted away (the lead raised where it must be)
    trim = {}
    for name, props in (("refused", {}), ("trimmed", {"TrimGouges": True}),
                        ("tilted", {"MaxLead": 30.0})):  # fmt: skip
        op2 = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="5-axis surface", StepOver=4.0,
                            Tool="bull:D=40,r=2", Lead=3.0, **props)  # fmt: skip
        op2.ToolController = None
        doc.recompute()
        own = path_moves(op2.Path.Commands)
        entry = {"status": op2.Status, "verdict": op2.Verdict, "n_moves": len(own), "max_gouge": op2.MaxGouge.Value}
        if own:
            t2 = np.array([[c.Parameters[k] for k in "XYZ"] for c in own])
            b2 = np.radians([[c.Parameters["B"], c.Parameters["C"]] for c in own])
            a2 = np.stack([np.sin(b2[:, 0]) * np.cos(b2[:, 1]), np.sin(b2[:, 0]) * np.sin(b2[:, 1]),
                           np.cos(b2[:, 0])], 1)  # fmt: skip
            mv = np.array([ms.Move.RAPID if c.Name == "G0" else ms.Move.CUT for c in own])
            written = ms.ToolPath(t2, a2, mv, np.zeros(len(own), int), cutter=ms.parse_cutter("bull:D=40,r=2"))
            entry["independent_clean"] = bool(ms.verify(faces, written, gouge_tolerance=0.011).clean)
            entry["area"] = json.loads(op2.Report).get("machined_area_fraction")
        trim[name] = entry
        doc.removeObject(op2.Name)
    result["trim"] = trim
    # bad input on the operation: a one-line status, an empty path, the document intact; then it recovers
    bad = {}
    for prop, value in (("StepOver", 0.0), ("StepOver", 1e9), ("Lead", 95.0), ("SurfaceTolerance", 0.0),
                        ("ChordalTolerance", -1.0), ("Clearance", -5.0), ("Tool", "cone:D=0")):  # fmt: skip
        keep = getattr(five, prop)
        setattr(five, prop, value)
        doc.recompute()
        bad[f"{prop}={value}"] = {"status": five.Status, "n_commands": len(five.Path.Commands),
                                  "cut_points": five.CutPoints}  # fmt: skip
        setattr(five, prop, keep)
    n_objects = len(doc.Objects)
    doc.recompute()
    result["bad_input"] = {"cases": bad, "recovered": five.Status, "n_g1": sum(c.Name == "G1" for c in
                           five.Path.Commands), "objects_same": n_objects == len(doc.Objects)}  # fmt: skip
    # flank milling of a ruled face (Liu's surface) by the D20 end mill: the same path as machsurf_cad's
    s = ms.example("liu")
    u0, u1, v0, v1 = s.bounds
    ruled = doc.addObject("Part::Feature", "Ruled")
    ruled.Shape = surface_to_part(s).toShape(u0, u1, v0, v1)
    fl = features.make("CamOperation", doc, (ruled, ["Face1"]), Pattern="flank", Tool="flat:D=20,L=80",
                       GougeTolerance=0.5, ChordalTolerance=0.05)  # fmt: skip
    fl.ToolController = None
    doc.recompute()
    fr = ms.flank(face_to_numpy(ruled.Shape.Faces[0], "Ruled"), "cyl:D=20,L=80", whole=True, tolerance=0.05)
    fmoves = path_moves(fl.Path.Commands)
    ftips = np.array([[c.Parameters[k] for k in "XYZ"] for c in fmoves])
    fsame = len(fmoves) == len(fr.toolpath.tip)
    result["flank"] = {
        "status": fl.Status,
        "verdict": fl.Verdict,
        "n_moves": len(fmoves),
        "n_direct": int(len(fr.toolpath.tip)),
        "tip_dev": float(np.abs(ftips - fr.toolpath.tip).max()) if fsame else None,
        "max_gouge": fl.MaxGouge.Value,
        "direct_rule_gouge": float(fr.path.report()["max_gouge_mm"]) if fr.path is not None else None,
    }
    fl.Tool = "ball:D=10"  # flank needs a cylinder: a message, an empty path
    doc.recompute()
    result["flank_ball"] = {"status": fl.Status, "n_commands": len(fl.Path.Commands)}
    # the material left (simulated), as a colour map: its largest value is MaxScallop; a limit under it warns
    op.SimulateScallops = True
    op.ScallopLimit = 0.05
    doc.recompute()
    vals = np.array(op.MapValues)
    result["simulation"] = {
        "status": op.Status,
        "max_scallop": op.MaxScallop.Value,
        "map_max": float(vals.max()) if vals.size else None,
        "map_min": float(vals.min()) if vals.size else None,
        "n_values": int(vals.size),
        "n_quads": len(op.MapQuads) // 4,
        "title": op.MapTitle,
        "n_g1": sum(c.Name == "G1" for c in op.Path.Commands),
    }
    # a Job without tools and no Tool text: one line, an empty path
    for tc in list(job.Tools.Group):
        job.Tools.removeObject(tc)
        doc.removeObject(tc.Name)
    op.ToolController = None
    doc.recompute()
    result["no_tool"] = {"status": op.Status, "n_commands": len(op.Path.Commands), "cut_points": op.CutPoints}


fcscript.run(main)
