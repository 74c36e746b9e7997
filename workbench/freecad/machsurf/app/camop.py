"""A CAM operation in FreeCAD's Path (0.20) / CAM (1.0) Job: machsurf's tool paths as Path commands.

``features.make("CamOperation", doc, (part, ["Face3", "Face7"]), Pattern="raster", StepOver=1.0)``
adds a ``Path::FeaturePython`` operation to the document's Job (creating one on the part if there is
none). Its tool comes from the Job's ToolController (ToolBit shapes endmill, ballend, bullnose, chamfer
and V-bit: diameter and corner radius mapped explicitly, the bull-nose's FlatRadius being D/2 - r) or,
without one, from the ``Tool`` text, and then the operation posts its own tool change; a ``Tool`` text
that disagrees with the controller is refused by name. Patterns:

- ``raster``, ``waterline``: machsurf's exact 3-axis drop-cutter on the selected faces, avoiding the rest;
- ``5-axis surface``: the guiding/orientation surfaces of one face (lead, tilt) and the tool path on them,
  its passes linked over a sphere around the whole part (no rapid through it);
- ``flank``: the flank milling path of a cylindrical cutter (the end mill) along one ruled face, lifted
  clear of the part's other faces and linked clear of them.

Every path is checked against every face of the part (``Verdict``); one that gouges beyond
``GougeTolerance`` is not written unless ``AllowGouge`` is set. The moves are ``G0``/``G1`` commands at
the tool tip (one ``G1`` per CL point), feeds from the ToolController (FreeCAD's mm/s); 5-axis moves add
the tool axis as ``B`` (its angle from Z) and ``C`` (its azimuth about Z, continuous), degrees, the
convention of a B-C head (:func:`rotary_angles`). ``SimulateScallops`` also simulates the cut and maps
the material left (per-vertex colours in the 3D view). No GUI import: it recomputes headless.
"""

import math

import numpy as np
import Path

from .. import ensure_core

ensure_core()

from machsurf_cad.errors import InputError
from machsurf_cad.linking import surface_for
from machsurf_cad.results import strict_json

from ..convert import face_to_numpy
from . import maps
from .features import ANGLE, LENGTH, TOOL_SIDES, _add, _Base, attach_view, tool_text, value_of

PATTERNS = ("raster", "waterline", "5-axis surface", "flank")
SIMULATION_SAMPLES = 40_000
PREVIEW = (
    ("PreviewTips", "App::PropertyVectorList", "5-axis path: tool tips (mm), drawn beside FreeCAD's Path"),
    ("PreviewAxes", "App::PropertyVectorList", "5-axis path: unit tool axes, drawn as lines from the tips"),
    ("PreviewDistance", "App::PropertyFloatList", "5-axis path: the body check's distance per position (mm)"),
)

SAFE_MARK = "machsurf safe moves"
"""A comment before the moves the operation adds around machsurf's path (to and from the clearance
height); its number says how many G0 follow."""

# the ToolBit shapes machsurf maps (FreeCAD's names), and how
TOOLBIT_SHAPES = ("endmill", "ballend", "bullnose", "chamfer", "v-bit")


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
    if shape in ("chamfer", "chamfer.fcstd", "v-bit", "v_bit", "v-bit.fcstd", "vbit"):
        return _cone_from_toolbit(tool, shape, D)
    raise InputError(f"ToolBit shape '{shape}' is not supported (use {', '.join(TOOLBIT_SHAPES)})")


def _cone_from_toolbit(tool, shape: str, D: float) -> str:
    """A chamfer mill or V-bit as machsurf's cone: its flat tip (``TipDiameter``, else twice ``FlatRadius``) is
    the cone's D, half its ``CuttingEdgeAngle`` the taper, the cutting edge up to the ToolBit's diameter
    its length. A pointed tip (no flat) is refused: machsurf's cone has a flat tip."""
    if not hasattr(tool, "CuttingEdgeAngle"):
        raise InputError(f"{shape} ToolBit without a CuttingEdgeAngle")
    half = value_of(tool.CuttingEdgeAngle) / 2.0
    tip = value_of(tool.TipDiameter) if hasattr(tool, "TipDiameter") else 2 * value_of(getattr(tool, "FlatRadius", 0.0))
    if not tip > 0:
        raise InputError(f"{shape} ToolBit with a pointed tip is not supported (machsurf's cone needs a flat tip)")
    if not 0 < half < 89:
        raise InputError(f"{shape} ToolBit with CuttingEdgeAngle {2 * half:g} deg is not supported")
    L = (D - tip) / 2 / math.tan(math.radians(half))
    return f"cone:D={tip:g},angle={half:g},L={L:.6g}" if L > 0 else f"cone:D={tip:g},angle={half:g}"


def _source_faces(obj, between=None):
    """(faces to machine as machsurf Faces, every other face of the source parts, the machined area in mm^2)
    from ``obj.Source``."""
    if not obj.Source:
        raise InputError("select the faces to machine in 'Source'")
    machined, others, area = [], [], 0.0
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
            if between is not None:
                between()
            area += f.Area if i in chosen else 0.0
    return machined, others, area


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


def verdict_text(vr: dict) -> str:
    """One line of a body check's report: clean, or what gouges and collides and where (never a crash on
    a figure that is None: no collision has no closest distance)."""
    if vr["clean"]:
        return "clean: no gouge or collision beyond the tolerance"
    close = vr.get("min_clearance_mm")
    w = vr["worst"][0] if vr.get("worst") else None
    return (
        f"{vr['n_gouging_positions']} gouging position(s) (deepest {vr['max_gouge_mm']:.4g} mm), "
        f"{vr['n_collisions']} collision(s)"
        + (f" (closest {close:.4g} mm)" if close is not None else "")
        + (
            f"; worst at position {w['index']} ({w['move']}) near "
            f"({', '.join(f'{x:.3f}' for x in w['part_point_mm'])}) mm"
            if w
            else ""
        )
    )


class CamOperationFeature(_Base):
    """machsurf's 3-axis raster or waterline path on the selected faces, checked against the whole part."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSubList", "Source", "Nominal", "Faces to machine (the rest of the part is avoided)")
        _add(obj, "App::PropertyLink", "ToolController", "Cutter", "The Job's ToolController whose ToolBit is used")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "Cutter text when there is no ToolController: ball:D=10", "")
        _add(obj, "App::PropertyEnumeration", "Pattern", "Strategy", "3-axis raster lines or constant-z "
             "waterlines; 5-axis on the guiding surface of one face; flank milling of one ruled face",
             list(PATTERNS))  # fmt: skip
        if "flank" not in obj.getEnumerationsOfProperty("Pattern"):  # migration: 3-axis patterns only before
            current = str(obj.Pattern)
            obj.Pattern = list(PATTERNS)
            obj.Pattern = current
        _add(obj, LENGTH, "StepOver", "Strategy", "Distance between raster lines", 2.0)
        _add(obj, ANGLE, "Angle", "Strategy", "Raster direction, from the X axis", 0.0)
        _add(obj, LENGTH, "StepDown", "Strategy", "Distance between waterline levels", 1.0)
        _add(obj, ANGLE, "Lead", "5-axis", "Lead angle: the axis leans towards the feed (the paper's Omega_t)", 10.0)
        _add(obj, ANGLE, "Tilt", "5-axis", "Tilt angle: the axis turns about the normal (the paper's Omega_n)", 0.0)
        _add(obj, LENGTH, "SurfaceTolerance", "5-axis", "Largest error of the fitted guiding and orientation "
             "surfaces, measured on points the fit never saw", 1e-3)  # fmt: skip
        _add(obj, "App::PropertyEnumeration", "ToolSide", "Flank", "Side of the ruled face the cutter is on: the "
             "side its normal points to, or the opposite one (the paper's side +1 / -1)", list(TOOL_SIDES))  # fmt: skip
        _add(obj, "App::PropertyEnumeration", "FlankSetting", "Flank", "Tool setting on each rule",
             ["optimum", "standard-distributed", "standard-bisector", "standard-tangent"])  # fmt: skip
        _add(obj, LENGTH, "ChordalTolerance", "Accuracy", "Largest distance of the moves from the exact CL surface "
             "(below GougeTolerance: a chord may dip that far into the part)", 0.005)  # fmt: skip
        _add(obj, LENGTH, "GougeTolerance", "Accuracy", "Deepest the tool body may go into the part", 0.01)
        _add(obj, "App::PropertyBool", "AllowGouge", "Accuracy", "Write a gouging path anyway (listed in Verdict)",
             False)  # fmt: skip
        _add(obj, "App::PropertyBool", "TrimGouges", "Accuracy", "Cut out the stretches that gouge or collide and "
             "join the rest by links checked clear (what is left out is in Report)", False)  # fmt: skip
        _add(obj, ANGLE, "MaxLead", "5-axis", "Tilt away: largest lead the axis may take where the tool would touch "
             "the part (0: no tilting); what no orientation clears is cut out", 0.0)  # fmt: skip
        _add(obj, ANGLE, "MaxTilt", "5-axis", "Tilt away: largest tilt either side the axis may take", 0.0)
        _add(obj, LENGTH, "Clearance", "Linking", "Rapid height above the part, along the tool axis", 5.0)
        _add(obj, "App::PropertyBool", "SimulateScallops", "Simulation", "Also simulate the cut and map the "
             "material left (takes a few seconds)", False)  # fmt: skip
        _add(obj, LENGTH, "ScallopLimit", "Simulation", "Largest material left allowed (0: no limit); over it the "
             "Status warns", 0.0)  # fmt: skip
        _add(obj, "App::PropertyFile", "AptFile", "Output", "Also write the path as APT CLDATA to this file "
             "(machsurf's writer: GOTO with the tool axis i, j, k); empty: none", "")  # fmt: skip
        _add(obj, "App::PropertyBool", "Active", "Path", "Operation is part of the program", True)
        _add(obj, "App::PropertyString", "Comment", "Path", "Comment", "machsurf exact drop-cutter")
        _add(obj, "App::PropertyString", "Verdict", "Result", "Tool body against every face of the part",
             read_only=True)  # fmt: skip
        _add(obj, LENGTH, "MaxGouge", "Result", "Deepest point of the tool body in the part", read_only=True)
        _add(obj, "App::PropertyInteger", "CutPoints", "Result", "CL points (one G1 each)", read_only=True)
        _add(obj, LENGTH, "CutLength", "Result", "Length of the cutting moves", read_only=True)
        _add(obj, "App::PropertyString", "CutterUsed", "Result", "The cutter machsurf machined with", read_only=True)
        for name, kind, doc in PREVIEW:  # 5-axis paths: what the view draws beside FreeCAD's Path
            _add(obj, kind, name, "Preview", doc)
            obj.setEditorMode(name, 2)
        _add(obj, LENGTH, "MaxScallop", "Result", "Largest material left by the path (simulated)", read_only=True)
        _add(obj, LENGTH, "SurfaceError", "Result", "Measured largest error of the guiding surface (5-axis)",
             read_only=True)  # fmt: skip
        maps.add_properties(obj)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)

    def clear(self, obj):
        super().clear(obj)
        obj.CutPoints = 0

    def execute(self, obj):
        if getattr(self, "configuring", False):  # inside make_operation: no tool yet, not an error
            obj.Status = "waiting for its Job and ToolController"
            return
        super().execute(obj)

    def tool_controller(self, obj):
        """The operation's ToolController, else (without a Tool text) the Job's first one, else None."""
        if obj.ToolController is not None or obj.Tool:
            return obj.ToolController
        job = find_job(obj.Document, create=False)
        tools = list(job.Tools.Group) if job is not None else []
        return tools[0] if tools else None

    def cutter_text(self, obj) -> str:
        """The ToolController's ToolBit (the tool's one source of truth); the Tool text only without one. A Tool
        text that disagrees with the controller is refused by name, never silently overridden."""
        import machsurf_cad as ms

        tc = self.tool_controller(obj)
        if tc is not None:
            text = cutter_from_toolbit(tc.Tool)
            if obj.Tool and ms.parse_cutter(tool_text(obj.Tool)).spec() != ms.parse_cutter(text).spec():
                raise InputError(
                    f"Tool '{obj.Tool}' disagrees with the ToolController '{tc.Label}' ({text}): clear Tool to use "
                    "the controller's ToolBit, or set the ToolController of that tool"
                )
            return text
        if not obj.Tool:
            raise InputError("no tool: add a ToolController to the Job or set 'Tool' (e.g. ball:D=10)")
        return tool_text(obj.Tool)

    def compute(self, obj):
        import machsurf_cad as ms

        faces, others, area = _source_faces(obj, between=self.tick)
        if not faces:
            raise InputError("no face to machine in 'Source'")
        cutter = ms.parse_cutter(self.cutter_text(obj))
        gtol = value_of(obj.GougeTolerance)
        bar = self.bar  # FreeCAD's progress bar (the GUI's status bar, the console headless); Esc cancels
        tp = self.toolpath(obj, ms, faces, others, cutter, bar)
        bar.stop()
        pc = self.core(
            ms.check_toolpath,
            tp,
            faces + others,
            gouge_tolerance=gtol,
            on_gouge="trim" if obj.TrimGouges or self.tilts_away(obj) else "allow" if obj.AllowGouge else "refuse",
            clearance=value_of(obj.Clearance),
        )
        bar.stop()
        v = pc.check
        vr = v.report()
        rep = {"toolpath": tp.report(), "verify": pc.report(), "cutter": cutter.spec()}
        if self.tilts_away(obj) and getattr(self, "tilt_report", None) is not None:
            rep["tilt_away"] = self.tilt_report
        if pc.verdict == "trimmed" and pc.toolpath is not None and len(faces) == 1:
            kept = np.asarray(pc.toolpath.extras.get("planned_index", []), int)
            planned = pc.trimmed_from if pc.trimmed_from is not None else tp
            from machsurf_cad.pathcheck import machined_area_fraction

            rep["machined_area_fraction"] = machined_area_fraction(
                faces[0], planned, kept[kept >= 0], step=0.2 * cutter.radius
            )
        obj.MaxGouge = float(v.max_gouge)
        obj.CutterUsed = cutter.spec()
        obj.Verdict = verdict_text(vr)
        if pc.verdict == "trimmed" and pc.toolpath is not None and pc.recheck is not None:
            obj.MaxGouge = float(pc.recheck.max_gouge)  # what is written
            info = pc.toolpath.info
            frac = rep.get("machined_area_fraction")
            obj.Verdict = (
                f"trimmed, then clean: {pc.toolpath.n_cut} cutting positions kept"
                + (f" ({100 * frac:.1f} % of the face)" if frac is not None else "")
                + f", {len(info.get('runs_left_out', []))} stretch(es) no clear link reaches left out; planned: "
                + verdict_text(vr)
            )
        if pc.toolpath is None:
            obj.Path = Path.Path()
            raise InputError(
                f"the path gouges the part ({obj.Verdict}): not written (TrimGouges cuts the gouges out, AllowGouge "
                "writes it)"
            )
        tp = pc.toolpath  # the path as planned, or cut down to its clear stretches (TrimGouges, tilt away)
        obj.Path = Path.Path(self.commands(obj, tp))
        self.preview(obj, tp, pc.recheck if pc.recheck is not None else v)
        if str(obj.AptFile):
            ms.write_apt(str(obj.AptFile), tp, self.post_options(obj, ms))
        obj.CutPoints = int(tp.n_cut)
        obj.CutLength = float(tp.report().get("cut_length_mm", 0.0))
        note = None
        if obj.SimulateScallops:
            # about SIMULATION_SAMPLES nominal samples: a map FreeCAD draws and saves at ease, a few seconds
            res = max(math.sqrt(area / SIMULATION_SAMPLES), 1e-3)
            sim = self.core(ms.simulate, faces, tp, gouge_tolerance=gtol, resolution=res)
            bar.stop()
            maps.simulation_map(obj, sim, gtol)
            obj.MaxScallop = sim.max_scallop
            rep["simulation"] = sim.report()
            limit = value_of(obj.ScallopLimit)
            if limit > 0 and sim.max_scallop > limit:
                note = f"the path leaves up to {sim.max_scallop:.4g} mm, over the scallop limit {limit:g} mm"
        else:
            maps.clear_map(obj)
        obj.Report = strict_json(rep, indent=None)
        return note

    def toolpath(self, obj, ms, faces, others, cutter, bar):
        """machsurf's tool path of the operation's pattern."""
        pattern = str(obj.Pattern)
        common = dict(
            check_faces=others,
            chordal_tolerance=value_of(obj.ChordalTolerance),
            clearance=value_of(obj.Clearance),
            gouge_tolerance=value_of(obj.GougeTolerance),
        )
        if pattern == "raster":
            return self.core(ms.raster, faces, cutter, stepover=value_of(obj.StepOver), angle=value_of(obj.Angle),
                             **common)  # fmt: skip
        if pattern == "waterline":
            return self.core(ms.waterline, faces, cutter, stepdown=value_of(obj.StepDown), **common)
        if len(faces) != 1:
            raise InputError(f"the {pattern} pattern machines one face: select one (got {len(faces)})")
        if pattern == "flank":
            spec = cutter.spec()
            if not spec.startswith("flat:"):
                raise InputError(f"flank milling needs a flat end mill (a cylinder), not {spec}")
            # the part's other faces: each rule's cylinder lifted clear of them, the segments linked clear of them
            beside = {"check_faces": others, "gouge_tolerance": value_of(obj.GougeTolerance)} if others else {}
            res = self.core(ms.flank, faces[0], "cyl:" + spec[len("flat:"):], setting=str(obj.FlankSetting),
                            whole=True, side=1 if str(obj.ToolSide) == TOOL_SIDES[0] else -1,
                            tolerance=value_of(obj.ChordalTolerance), clearance=value_of(obj.Clearance),
                            **beside)  # fmt: skip
            obj.SurfaceError = 0.0
            return res.toolpath
        a = math.radians(value_of(obj.Angle))  # passes along the raster direction: planes normal to it in xy
        strategy = f"planes:{-math.sin(a):.12g},{math.cos(a):.12g},0"
        field = None
        if self.tilts_away(obj):  # the axis turned away from the part within MaxLead / MaxTilt
            from machsurf_cad.machining.avoid import clear_axis_field

            lead = value_of(obj.Lead)
            limits = {"lead": lead, "tilt": value_of(obj.Tilt), "max_lead": max(value_of(obj.MaxLead), lead),
                      "max_tilt": value_of(obj.MaxTilt), "gouge_tolerance": value_of(obj.GougeTolerance)}  # fmt: skip
            field, tilt_rep = self.core(clear_axis_field, faces[0], cutter, strategy, faces + others, progress=False,
                                        **limits)  # fmt: skip
            self.tilt_report = tilt_rep
        m = self.core(ms.machining_surface, faces[0], cutter, axes=5, strategy=strategy, lead=value_of(obj.Lead),
                      tilt=value_of(obj.Tilt), axis_field=field, tolerance=value_of(obj.SurfaceTolerance))  # fmt: skip
        obj.SurfaceError = float(m.s1_fit.max_error)
        # passes linked over the whole part: a cylinder about a long part, else a sphere
        kind, geo = surface_for(faces + others, None, value_of(obj.Clearance))
        return self.core(ms.tool_paths, m, stepover=value_of(obj.StepOver), progress=False,
                         chordal_tolerance=value_of(obj.ChordalTolerance), clearance=value_of(obj.Clearance),
                         **{f"safe_{kind}": geo})  # fmt: skip

    def preview(self, obj, tp, check) -> None:
        """A 5-axis path's tips, axes and the body check's distance per position (empty for 3 axes, which
        FreeCAD draws right): FreeCAD 0.20 draws B and C as rotations, so the view draws these instead."""
        five = bool(np.any(np.abs(np.asarray(tp.axis)[:, 2] - 1.0) > 1e-12))
        d = np.asarray(check.cut_distance, float) if five and len(check.cut_distance) == len(tp.tip) else None
        obj.PreviewTips = [tuple(map(float, p)) for p in tp.tip] if d is not None else []
        obj.PreviewAxes = [tuple(map(float, a)) for a in tp.axis] if d is not None else []
        obj.PreviewDistance = [float(x) if np.isfinite(x) else 1e9 for x in d] if d is not None else []

    def tilts_away(self, obj) -> bool:
        return str(obj.Pattern) == "5-axis surface" and (value_of(obj.MaxLead) > 0 or value_of(obj.MaxTilt) > 0)

    def feeds(self, obj):
        """(cutting, plunge) feeds in mm/s (FreeCAD's unit) from the ToolController, else 1000 and 300 mm/min."""
        tc = self.tool_controller(obj)
        horiz = value_of(tc.HorizFeed) if tc is not None and value_of(tc.HorizFeed) > 0 else 1000.0 / 60.0
        vert = value_of(tc.VertFeed) if tc is not None and value_of(tc.VertFeed) > 0 else 300.0 / 60.0
        return horiz, vert

    def post_options(self, obj, ms):
        """machsurf's APT options with the ToolController's feeds (mm/min), speed and tool number."""
        tc = self.tool_controller(obj)
        horiz, vert = self.feeds(obj)
        rpm = float(getattr(tc, "SpindleSpeed", 0) or 0) if tc is not None else 0.0
        number = int(getattr(tc, "ToolNumber", 1) or 1) if tc is not None else 1
        return ms.PostOptions(feed=horiz * 60.0, plunge_feed=vert * 60.0,
                              spindle=rpm if rpm > 0 else 10000.0, tool_number=number,
                              partno=str(obj.Label).upper()[:40])  # fmt: skip

    def commands(self, obj, tp):
        """G0 for rapids, G1 for the rest at the tool tip; feeds (mm/s, FreeCAD's unit) from the ToolController;
        B and C (degrees) when the tool axis is not +Z everywhere."""
        from machsurf_cad import Move

        horiz, vert = self.feeds(obj)
        five = bool(np.any(np.abs(np.asarray(tp.axis)[:, 2] - 1.0) > 1e-12))
        b, c = rotary_angles(tp.axis) if five else (None, None)
        cmds = [Path.Command(f"({obj.Label}: machsurf {obj.Pattern}, {obj.CutterUsed})")]
        if self.tool_controller(obj) is None:  # no controller posts the change: this operation does
            import machsurf_cad

            opts = self.post_options(obj, machsurf_cad)
            cmds += [Path.Command(f"(machsurf tool change: no ToolController, T{opts.tool_number} = {obj.CutterUsed})"),
                     Path.Command("M6", {"T": opts.tool_number}), Path.Command("M3", {"S": opts.spindle})]  # fmt: skip
        if five:
            cmds.append(Path.Command("(B: tool axis angle from Z, C: its azimuth about Z, degrees; B-C head)"))
        z_clear = self.clearance_height(obj, tp)
        first = {"X": float(tp.tip[0, 0]), "Y": float(tp.tip[0, 1])}
        if five:
            first.update(B=float(b[0]), C=float(c[0]))
        # from wherever the last operation left the tool: up to the clearance height, across, then down
        cmds.append(Path.Command(f"({SAFE_MARK} 2: clearance height {z_clear:.3f} mm)"))
        cmds += [Path.Command("G0", {"Z": z_clear}), Path.Command("G0", {**first, "Z": z_clear})]
        for i, (p, m) in enumerate(zip(tp.tip, tp.move)):
            words = {"X": float(p[0]), "Y": float(p[1]), "Z": float(p[2])}
            if five:
                words.update(B=float(b[i]), C=float(c[i]))
            if m == Move.RAPID:
                cmds.append(Path.Command("G0", words))
            else:
                cmds.append(Path.Command("G1", {**words, "F": horiz if m == Move.CUT else vert}))
        cmds.append(Path.Command(f"({SAFE_MARK} 1: back to the clearance height)"))
        cmds.append(Path.Command("G0", {"Z": max(z_clear, float(tp.tip[-1, 2]))}))
        return cmds

    def clearance_height(self, obj, tp) -> float:
        """The Job's clearance height: above its stock (or the part) by the Job's ClearanceHeightOffset
        (else this operation's Clearance), and never below the path's highest point."""
        job = find_job(obj.Document, create=False)
        top = float(np.max(tp.tip[:, 2]))
        offset = value_of(obj.Clearance)
        if job is not None:
            stock = getattr(job, "Stock", None)
            if stock is not None and hasattr(stock, "Shape") and not stock.Shape.isNull():
                top = max(top, float(stock.Shape.BoundBox.ZMax))
            sheet = getattr(job, "SetupSheet", None)
            off = getattr(sheet, "ClearanceHeightOffset", None) if sheet is not None else None
            if off is not None:
                try:
                    offset = max(offset, float(getattr(off, "Value", off)))
                except (TypeError, ValueError):
                    pass
        return top + offset


def rotary_angles(axis):
    """(B, C) in degrees of unit tool axes (n, 3) for a B-C head: axis = (sin B cos C, sin B sin C, cos B),
    B in [0, 180]; C continuous along the path (unwrapped, no 360 deg jumps), held where the axis is
    vertical (C is free there)."""
    a = np.asarray(axis, float).reshape(-1, 3)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    b = np.degrees(np.arccos(np.clip(a[:, 2], -1.0, 1.0)))
    c = np.degrees(np.arctan2(a[:, 1], a[:, 0]))
    free = np.hypot(a[:, 0], a[:, 1]) < 1e-9
    if free.all():
        return b, np.zeros_like(c)
    known = np.nonzero(~free)[0]
    c[free] = np.interp(np.nonzero(free)[0], known, c[known])  # hold: nearest defined azimuth around
    c = np.degrees(np.unwrap(np.radians(c)))
    return b, c


def make_operation(doc, source, **props):
    """The CamOperation in the document's Job (created on the source part when there is none). It does
    not compute until its Job and ToolController are set (a Job's creation recomputes the document)."""
    obj = doc.addObject("Path::FeaturePython", "CamOperation")
    CamOperationFeature(obj)
    obj.Proxy.configuring = True
    if source is not None:
        obj.Source = [source] if isinstance(source, tuple) else source
    job = find_job(doc, obj.Source[0][0] if obj.Source else None)
    if job is not None:
        job.Operations.addObject(obj)
        if obj.ToolController is None and not props.get("Tool") and job.Tools.Group:
            obj.ToolController = job.Tools.Group[0]
    for k, v in props.items():
        setattr(obj, k, v)
    obj.Proxy.configuring = False
    obj.touch()
    attach_view(obj)
    return obj
