"""A CAM operation in FreeCAD's Path (0.20) / CAM (1.0) Job: machsurf's 3-axis tool path as Path commands.

``features.make("CamOperation", doc, (part, ["Face3", "Face7"]), Pattern="raster", StepOver=1.0)``
adds a ``Path::FeaturePython`` operation to the document's Job (creating one on the part if there is
none). Its tool comes from the Job's ToolController (ToolBit shapes endmill, ballend, bullnose:
diameter and corner radius mapped explicitly, the bull-nose's FlatRadius being D/2 - r) or, without
one, from the ``Tool`` text. It runs machsurf's exact drop-cutter on the selected faces (raster or
waterline), checks the tool body against every face of the part, and holds the moves as ``G0``/``G1``
commands at the tool tip (one ``G1`` per CL point), feeds from the ToolController (FreeCAD's mm/s).
A path that gouges beyond ``GougeTolerance`` is not written (``Verdict`` says where) unless
``AllowGouge`` is set. No GUI import: it recomputes headless.
"""

import json

import Path

from .. import ensure_core

ensure_core()

from machsurf_cad.errors import InputError

from ..convert import face_to_numpy
from .features import ANGLE, LENGTH, Progress, _add, _Base, attach_view, tool_text, value_of

# the ToolBit shapes machsurf maps (FreeCAD's names), and how
TOOLBIT_SHAPES = ("endmill", "ballend", "bullnose")


def cutter_from_toolbit(tool) -> str:
    """machsurf's cutter text of a FreeCAD ToolBit (or a legacy Path.Tool): ``flat:``, ``ball:`` or ``bull:``."""
    shape = str(getattr(tool, "ShapeName", "") or getattr(tool, "ToolType", "")).lower()
    D = value_of(tool.Diameter)
    L = value_of(tool.CuttingEdgeHeight) if hasattr(tool, "CuttingEdgeHeight") else 0.0
    length = f",L={L:g}" if L > 0 else ""
    if shape in ("endmill", "endmill.fcstd"):
        return f"flat:D={D:g}{length}"
    if shape in ("ballend", "ballend.fcstd", "ballendmill"):
        return f"ball:D={D:g}{length}"
    if shape in ("bullnose", "bullnose.fcstd"):
        flat = value_of(tool.FlatRadius)  # FreeCAD: radius of the flat bottom; machsurf: the corner radius
        r = D / 2 - flat
        if not 0 < r <= D / 2:
            raise InputError(f"bull-nose ToolBit with D = {D:g} mm and FlatRadius = {flat:g} mm has no corner radius")
        return f"bull:D={D:g},r={r:g}{length}"
    raise InputError(f"ToolBit shape '{shape}' is not supported (use {', '.join(TOOLBIT_SHAPES)})")


def _source_faces(obj):
    """(faces to machine as machsurf Faces, every face of the source parts) from ``obj.Source``."""
    if not obj.Source:
        raise InputError("select the faces to machine in 'Source'")
    machined, others = [], []
    for src, subs in obj.Source:
        if src is None or not hasattr(src, "Shape"):
            raise InputError("a source object is gone or has no shape")
        names = [s for s in subs if s]
        bad = [s for s in names if not s.startswith("Face")]
        if bad:
            raise InputError(f"'{bad[0]}' of {src.Label} is not a face: select faces")
        chosen = {int(s[4:]) - 1 for s in names} if names else set(range(len(src.Shape.Faces)))
        for i, f in enumerate(src.Shape.Faces):
            nf = face_to_numpy(f, f"{src.Label}.Face{i + 1}")
            (machined if i in chosen else others).append(nf)
    return machined, others


def find_job(doc, part=None, create=True):
    """The document's Path/CAM Job (the first), or a new one on ``part``; None without the Path workbench."""
    for o in doc.Objects:
        if hasattr(o, "Operations") and hasattr(o, "Tools") and hasattr(o, "Model"):
            return o
    if not create or part is None:
        return None
    try:
        from Path.Main import Job as PathJob  # FreeCAD 1.0 (CAM)
    except ImportError:
        try:
            import PathScripts.PathJob as PathJob  # FreeCAD 0.20 (Path)
        except ImportError:
            return None
    return PathJob.Create("Job", [part], None)


class CamOperationFeature(_Base):
    """machsurf's 3-axis raster or waterline path on the selected faces, checked against the whole part."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSubList", "Source", "Nominal", "Faces to machine (the rest of the part is avoided)")
        _add(obj, "App::PropertyLink", "ToolController", "Cutter", "The Job's ToolController whose ToolBit is used")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "Cutter text when there is no ToolController: ball:D=10", "")
        _add(obj, "App::PropertyEnumeration", "Pattern", "Strategy", "Raster lines or constant-z waterlines",
             ["raster", "waterline"])  # fmt: skip
        _add(obj, LENGTH, "StepOver", "Strategy", "Distance between raster lines", 2.0)
        _add(obj, ANGLE, "Angle", "Strategy", "Raster direction, from the X axis", 0.0)
        _add(obj, LENGTH, "StepDown", "Strategy", "Distance between waterline levels", 1.0)
        _add(obj, LENGTH, "ChordalTolerance", "Accuracy", "Largest distance of the moves from the exact CL surface",
             0.01)  # fmt: skip
        _add(obj, LENGTH, "GougeTolerance", "Accuracy", "Deepest the tool body may go into the part", 0.01)
        _add(obj, "App::PropertyBool", "AllowGouge", "Accuracy", "Write a gouging path anyway (listed in Verdict)",
             False)  # fmt: skip
        _add(obj, LENGTH, "Clearance", "Linking", "Rapid height above the part, along the tool axis", 5.0)
        _add(obj, "App::PropertyBool", "Active", "Path", "Operation is part of the program", True)
        _add(obj, "App::PropertyString", "Comment", "Path", "Comment", "machsurf exact drop-cutter")
        _add(obj, "App::PropertyString", "Verdict", "Result", "Tool body against every face of the part",
             read_only=True)  # fmt: skip
        _add(obj, LENGTH, "MaxGouge", "Result", "Deepest point of the tool body in the part", read_only=True)
        _add(obj, "App::PropertyInteger", "CutPoints", "Result", "CL points (one G1 each)", read_only=True)
        _add(obj, LENGTH, "CutLength", "Result", "Length of the cutting moves", read_only=True)
        _add(obj, "App::PropertyString", "CutterUsed", "Result", "The cutter machsurf machined with", read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)

    def clear(self, obj):
        super().clear(obj)
        obj.CutPoints = 0

    def tool_controller(self, obj):
        """The operation's ToolController, else (without a Tool text) the Job's first one, else None."""
        if obj.ToolController is not None or obj.Tool:
            return obj.ToolController
        job = find_job(obj.Document, create=False)
        tools = list(job.Tools.Group) if job is not None else []
        return tools[0] if tools else None

    def cutter_text(self, obj) -> str:
        tc = self.tool_controller(obj)
        if tc is not None:
            return cutter_from_toolbit(tc.Tool)
        if not obj.Tool:
            raise InputError("no tool: add a ToolController to the Job or set 'Tool' (e.g. ball:D=10)")
        return tool_text(obj.Tool)

    def compute(self, obj):
        import machsurf_cad as ms

        faces, others = _source_faces(obj)
        if not faces:
            raise InputError("no face to machine in 'Source'")
        cutter = ms.parse_cutter(self.cutter_text(obj))
        gtol = value_of(obj.GougeTolerance)
        common = dict(
            check_faces=others,
            chordal_tolerance_mm=value_of(obj.ChordalTolerance),
            clearance_mm=value_of(obj.Clearance),
            verify_tolerance_mm=gtol,
        )
        bar = Progress()  # FreeCAD's progress bar (the GUI's status bar, the console headless)
        try:
            if str(obj.Pattern) == "raster":
                tp = ms.raster(faces, cutter, stepover_mm=value_of(obj.StepOver), angle_deg=value_of(obj.Angle),
                               progress=bar, **common)  # fmt: skip
            else:
                tp = ms.waterline(faces, cutter, stepdown_mm=value_of(obj.StepDown), progress=bar, **common)
            bar.stop()
            v = ms.verify(faces + others, tp, tolerance=gtol, progress=bar)
        finally:
            bar.stop()
        vr = v.report()
        rep = {"toolpath": tp.report(), "verify": v.report(), "cutter": cutter.spec()}
        obj.Report = json.dumps(rep, default=float)
        obj.MaxGouge = float(v.max_gouge)
        obj.CutterUsed = cutter.spec()
        obj.Verdict = (
            "clean: no gouge or collision beyond the tolerance"
            if v.clean
            else f"{vr['n_gouging_positions']} gouging position(s) (deepest {v.max_gouge:.4g} mm), "
            f"{vr['n_collisions']} collision(s) (closest {vr['min_clearance_mm']:.4g} mm); worst at position "
            f"{vr['worst'][0]['index']} ({vr['worst'][0]['move']}) near "
            f"({', '.join(f'{x:.3f}' for x in vr['worst'][0]['part_point_mm'])}) mm"
        )
        if not v.clean and not obj.AllowGouge:
            obj.Path = Path.Path()
            raise InputError(f"the path gouges the part ({obj.Verdict}): not written (AllowGouge writes it)")
        obj.Path = Path.Path(self.commands(obj, tp))
        obj.CutPoints = int(tp.n_cut)
        obj.CutLength = float(tp.report().get("cut_length_mm", 0.0))

    def commands(self, obj, tp):
        """G0 for rapids, G1 for the rest at the tool tip; feeds (mm/s, FreeCAD's unit) from the ToolController."""
        from machsurf_cad import Move

        tc = self.tool_controller(obj)
        horiz = value_of(tc.HorizFeed) if tc is not None and value_of(tc.HorizFeed) > 0 else 1000.0 / 60.0
        vert = value_of(tc.VertFeed) if tc is not None and value_of(tc.VertFeed) > 0 else 300.0 / 60.0
        cmds = [Path.Command(f"({obj.Label}: machsurf {obj.Pattern}, {obj.CutterUsed})")]
        for p, m in zip(tp.tip, tp.move):
            xyz = {"X": float(p[0]), "Y": float(p[1]), "Z": float(p[2])}
            if m == Move.RAPID:
                cmds.append(Path.Command("G0", xyz))
            else:
                cmds.append(Path.Command("G1", {**xyz, "F": horiz if m == Move.CUT else vert}))
        return cmds


def make_operation(doc, source, **props):
    """The CamOperation in the document's Job (created on the source part when there is none)."""
    obj = doc.addObject("Path::FeaturePython", "CamOperation")
    CamOperationFeature(obj)
    if source is not None:
        obj.Source = [source] if isinstance(source, tuple) else source
    job = find_job(doc, obj.Source[0][0] if obj.Source else None)
    if job is not None:
        job.Operations.addObject(obj)
        if obj.ToolController is None and not props.get("Tool") and job.Tools.Group:
            obj.ToolController = job.Tools.Group[0]
    for k, v in props.items():
        setattr(obj, k, v)
    attach_view(obj)
    return obj
