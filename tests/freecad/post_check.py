"""Runs inside FreeCADCmd: a Path Job with two machsurf operations on the block (rasters across and along,
the Job's ToolController), posted through FreeCAD's own linuxcnc and grbl post-processors; each G-code
file is read back move by move (G0 rapid, G1 cut, modal coordinates) and the moves are checked by
machsurf's tool-body check against every face of the block. Writes the figures to MACHSURF_FC_OUT."""

import importlib
import os
import re
import sys

sys.path.insert(0, os.path.join(os.environ["MACHSURF_ROOT"], "tests", "freecad"))
import fcscript


def moves(gcode: str):
    """(positions (n, 3), rapid flags) of the G0/G1 lines, coordinates modal, starting from the first full
    position; other words and comments ignored."""
    pos = {"X": None, "Y": None, "Z": None}
    mode, out = None, []
    for line in gcode.splitlines():
        line = re.sub(r"\(.*?\)", "", line).upper()
        words = dict(re.findall(r"([A-Z])\s*(-?\d*\.?\d+)", line))
        g = words.get("G")
        if g is not None and float(g) in (0.0, 1.0):
            mode = int(float(g))
        axes = {k: float(v) for k, v in words.items() if k in "XYZ"}
        if not axes or mode is None:
            continue
        pos.update(axes)
        if None not in pos.values():
            out.append(([pos["X"], pos["Y"], pos["Z"]], mode == 0))
    return out


def main(result):
    import FreeCAD
    import numpy as np
    from freecad.machsurf import features
    from freecad.machsurf.app.camop import find_job
    from freecad.machsurf.convert import face_to_numpy

    import machsurf_cad as ms

    doc = FreeCAD.newDocument("post")
    part, top = fcscript.block(doc)
    src = (part, [top])
    op1 = features.make("CamOperation", doc, src, Pattern="raster", StepOver=6.0, Angle=0.0)
    op2 = features.make("CamOperation", doc, src, Pattern="raster", StepOver=6.0, Angle=90.0)
    doc.recompute()
    job = find_job(doc, create=False)
    result["ops"] = [{"status": o.Status, "verdict": o.Verdict, "tool": o.CutterUsed} for o in (op1, op2)]
    faces = [face_to_numpy(f, f"Face{i + 1}") for i, f in enumerate(part.Shape.Faces)]
    cutter = ms.parse_cutter(op1.CutterUsed)
    objects = [job.Tools.Group[0], op1, op2]
    zmax = max(f.BoundBox.ZMax for f in part.Shape.Faces)
    posted = {}
    for name in ("linuxcnc", "grbl"):
        post = importlib.import_module(f"PathScripts.post.{name}_post")
        gfile = fcscript.out_file(f"two_ops_{name}.ngc")
        post.export(objects, gfile, "--no-show-editor")  # grbl writes the file and returns nothing
        with open(gfile) as fh:
            gcode = fh.read()
        mv = moves(gcode)
        tips = np.array([p for p, _ in mv], float)
        rapid = np.array([r for _, r in mv], bool)
        move = np.where(rapid, ms.Move.RAPID, ms.Move.CUT)
        tp = ms.ToolPath(tips, np.tile([0.0, 0.0, 1.0], (len(tips), 1)), move, np.zeros(len(tips), int), cutter=cutter)
        v = ms.verify(faces, tp, cutter, gouge_tolerance=0.01)
        rep = v.report()
        # a rapid that moves in x or y runs at a height above the whole part, or is a link the check found clear
        xy = np.hypot(*(np.diff(tips[:, :2], axis=0).T)) > 1e-9
        low_xy_rapids = int(np.count_nonzero(rapid[1:] & xy & (np.minimum(tips[1:, 2], tips[:-1, 2]) < zmax)))
        posted[name] = {
            "lines": len(gcode.splitlines()),
            "moves": len(mv),
            "rapids": int(rapid.sum()),
            "m6": len(re.findall(r"\bM0?6\b", gcode)),
            "clean": bool(v.clean),
            "max_gouge": float(v.max_gouge),
            "collisions": int(rep["n_collisions"]),
            "gouging_positions": int(rep["n_gouging_positions"]),
            "low_xy_rapids": low_xy_rapids,
            "first_move_z_above_part": bool(tips[0, 2] > zmax),
            "last_move_z_above_part": bool(tips[-1, 2] > zmax),
        }
    result["posted"] = posted


fcscript.run(main)
