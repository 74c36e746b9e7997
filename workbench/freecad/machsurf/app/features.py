"""Parametric App-level features (no GUI import: they recompute headless in FreeCADCmd).

Each feature is a ``Part::FeaturePython`` whose properties mirror the machsurf_cad Python API
(lengths in mm, angles in degrees). ``execute`` calls machsurf_cad and turns the returned B-spline
arrays into Part faces; the measured errors and reports of the last recompute are read-only
properties. Lengths are ``App::PropertyLength``/``PropertyDistance`` and angles ``App::PropertyAngle``
(they show their units and keep every digit: 0.5 um typed stays 0.0005 mm). On bad input the
message goes to the report view as one line (no traceback) and into ``Status``; the shape is cleared
and every result emptied, so nothing of the previous recompute survives; the document is left as it
was. Documents saved with plain-float properties are migrated on opening (``onDocumentRestored``).
"""

import json

import FreeCAD
import Part

from .. import ensure_core

ensure_core()

from machsurf_cad.errors import InputError, MachsurfError
from machsurf_cad.results import strict_json

from ..convert import face_to_numpy, face_to_part, surface_to_part
from . import maps

READ_ONLY = 1
TOOL_SIDES = ("normal side", "opposite side")  # the flank tool on the side the face normal points to, or not
# results of version 0.2 renamed to CAM vocabulary (the paper's S1/S2 stay in the tooltips)
RENAMED_RESULTS = (
    ("MaxErrorS1", "GuidingSurfaceError"),
    ("MaxErrorS2", "OrientationSurfaceError"),
    ("PolesS1", "GuidingSurfacePoles"),
    ("PolesS2", "OrientationSurfacePoles"),
)


def _add(obj, kind, name, group, doc, value=None, read_only=False):
    """Add a property unless it exists; one of another type (a float saved by an older version where
    a length or angle is now a quantity) is replaced by the new type with the same value."""
    if name in obj.PropertiesList and obj.getTypeIdOfProperty(name) != kind:
        old = getattr(obj, name)
        obj.removeProperty(name)
        obj.addProperty(kind, name, group, doc)
        try:
            setattr(obj, name, value_of(old) if isinstance(old, (int, float)) or hasattr(old, "Value") else old)
        except Exception:  # a value the new type cannot hold: its default
            if value is not None:
                setattr(obj, name, value)
    elif name not in obj.PropertiesList:
        obj.addProperty(kind, name, group, doc)
        if value is not None:
            setattr(obj, name, value)
    if read_only:
        obj.setEditorMode(name, READ_ONLY)


def _rename(obj, old, new):
    """Migration of a property renamed to CAM vocabulary: remove ``old`` (when ``new`` is not there yet)
    and return its value for the new property, else None."""
    if old not in obj.PropertiesList or new in obj.PropertiesList:
        return None
    value = getattr(obj, old)
    obj.removeProperty(old)
    return value


def value_of(q) -> float:
    """A quantity property's value in mm or degrees (FreeCAD's internal units), or a plain number."""
    return float(q.Value) if hasattr(q, "Value") else float(q)


LENGTH, DISTANCE, ANGLE = "App::PropertyLength", "App::PropertyDistance", "App::PropertyAngle"
PREFERENCES = "User parameter:BaseApp/Preferences/Mod/machsurf"


def preference(name, default):
    """A machsurf preference (the preferences page writes them): float, int or str like ``default``."""
    p = FreeCAD.ParamGet(PREFERENCES)
    if isinstance(default, float):
        return p.GetFloat(name, default)
    if isinstance(default, int):
        return p.GetInt(name, default)
    return p.GetString(name, default)


def tool_text(text):
    """A feature's Tool: a cutter text (``ball:D=10``) or a name from the tool library of the preferences
    (a JSON object of names to cutter texts)."""
    text = str(text).strip()
    if ":" in text or not text:
        return text
    path = preference("ToolLibrary", "")
    if not path:
        raise MachsurfError(f"tool '{text}' is not a cutter text (e.g. ball:D=10) and no tool library is set")
    try:
        with open(path) as fh:
            library = json.load(fh)
    except (OSError, ValueError) as exc:
        raise MachsurfError(f"the tool library {path} cannot be read: {exc}") from None
    if text not in library:
        raise MachsurfError(f"tool '{text}' is not in the tool library {path} ({', '.join(sorted(library))})")
    return str(library[text])


# measured: the two passes of the example envelope at 1e-9 mm need 12,000 poles each, 0.14 GB and 30 s
FIT_BUDGET = (
    "A fit stops at 40,000 poles (about 0.5 GB; 1e-9 mm on the example envelope: 12,000 poles a pass, "
    "0.14 GB, 30 s); Esc cancels it"
)
REFF_BYTES_PER_SAMPLE = 650  # measured peak of reff_maps per grid sample (grid 1024: 0.63 GB above the imports, 2.1 s)


def reff_memory_text(grid: int) -> str:
    """The memory an effective-radius map of ``grid`` x ``grid`` samples needs, as text."""
    mb = grid * grid * REFF_BYTES_PER_SAMPLE / 1e6
    return f"about {mb / 1000:.1f} GB" if mb >= 1000 else f"about {max(mb, 1):.0f} MB"


def source_face(obj):
    """The selected face of ``obj.Source``, with a clear error for every way it can be wrong."""
    if obj.Source is None:
        raise MachsurfError("the source face was deleted or is not set: link a face in 'Source'")
    src, subs = obj.Source
    if src is None or not hasattr(src, "Shape"):
        raise MachsurfError("the source object is gone or has no shape")
    if not subs:
        faces = src.Shape.Faces
        if len(faces) != 1:
            raise MachsurfError(f"select one face of {src.Label} (it has {len(faces)} faces)")
        return faces[0]
    name = subs[0]
    if not name.startswith("Face"):
        raise MachsurfError(f"'{name}' of {src.Label} is not a face: select a face")
    try:
        return src.Shape.getElement(name)
    except Exception:
        raise MachsurfError(f"{src.Label} has no {name} any more (topology changed or face deleted)") from None


def _surface_and_deviation(*args, **kwargs):
    """:func:`machsurf_cad.machining_surface` and its deviation map, both off the GUI thread (the GUI thread
    only writes them: a deviation computed there stalled the window a quarter of a second)."""
    from machsurf_cad import machining_surface

    ms = machining_surface(*args, **kwargs)
    return ms, maps.deviation(ms)


class _Base:
    """Error handling and property migrations shared by the features.

    Every property is declared in ``properties(obj)``, which only adds what is missing: called on
    creation and again in ``onDocumentRestored``, it migrates documents saved by older versions
    (their new properties appear with their defaults).
    """

    def __init__(self, obj):
        obj.Proxy = self
        self.properties(obj)

    def properties(self, obj):  # pragma: no cover - every feature overrides it
        raise NotImplementedError

    def onDocumentRestored(self, obj):
        self.Object = obj
        self.properties(obj)
        attach_view(obj)  # a document made headless gets the machsurf view (icon, colours, task panel)

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None

    def tick(self, message="reading the part"):
        """Work the GUI thread does itself (reading FreeCAD's shapes): the busy bar stepped and the GUI's
        events handled between its steps (Esc cancels there too)."""
        from . import worker

        self.bar(0, None, message)
        worker.pump()
        if worker.cancel_requested():
            raise Cancelled("cancelled by the user")

    def core(self, fn, *args, progress=True, **kwargs):
        """``fn(*args, **kwargs)``, a machsurf_cad call, off the GUI thread with its progress on FreeCAD's bar
        (:func:`.worker.run`; ``progress``: whether ``fn`` reports progress)."""
        from . import worker

        return worker.run(fn, args, kwargs, self.bar, cancelled=Cancelled, progress=progress)

    def execute(self, obj):
        from . import worker

        self.bar = Progress()  # compute passes it to machsurf_cad: progress, and Esc cancels
        try:
            try:
                with worker.recompute():
                    note = self.compute(obj)
            finally:
                self.bar.stop()
            obj.Status = f"warning: {note}" if note else "ok"
            if note:
                FreeCAD.Console.PrintWarning(f"{obj.Label}: {note}\n")
        except Exception as exc:  # every failure: one line, the shape and results emptied, the document unharmed
            text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            if not isinstance(exc, (MachsurfError, ValueError)):
                text = f"{type(exc).__name__}: {text}"
            self.clear(obj)
            obj.Status = f"error: {text}"
            FreeCAD.Console.PrintError(f"{obj.Label}: {text}\n")

    def clear(self, obj):
        """Empty the shape (or path) and every result property (no stale figure survives a failed recompute)."""
        if "Shape" in obj.PropertiesList and obj.getTypeIdOfProperty("Shape") == "Part::PropertyPartShape":
            obj.Shape = Part.Shape()
        if "Path" in obj.PropertiesList:
            import Path

            obj.Path = Path.Path()
        for name in obj.PropertiesList:
            group = obj.getGroupOfProperty(name)
            if group == "Preview":  # a 5-axis path's preview (lists)
                setattr(obj, name, [])
            if group != "Result" or name == "Status":
                continue
            kind = obj.getTypeIdOfProperty(name)
            if kind == "App::PropertyString":
                setattr(obj, name, "")
            elif kind in ("App::PropertyFloat", LENGTH, DISTANCE, ANGLE):
                setattr(obj, name, 0.0)
        if hasattr(self, "map"):
            del self.map
        maps.clear_map(obj)


class MachiningSurfaceFeature(_Base):
    """Guiding surface S1 and orientation surface S2 of a face (machsurf_cad.machining)."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Face to machine")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "ball:D=.., flat:D=.., bull:D=..,r=.. (mm)", "bull:D=20,r=4")
        old_axes = None  # migration: an enumeration of "5" and "3" before 0.4 (Axes = 3 from a script failed)
        if "Axes" in obj.PropertiesList and obj.getTypeIdOfProperty("Axes") == "App::PropertyEnumeration":
            old_axes = int(str(obj.Axes))
            obj.removeProperty("Axes")
        _add(obj, "App::PropertyIntegerConstraint", "Axes", "Strategy", "3 (fixed axis along z) or 5 (lead and tilt)",
             (5, 3, 5, 2))  # fmt: skip
        if old_axes is not None:
            obj.Axes = old_axes
        _add(
            obj,
            "App::PropertyString",
            "Strategy",
            "Strategy",
            "Tool path directions: planes:x|y|z|a,b,c (parallel planes) or iso:u|v (isoparametric)",
            "planes:x",
        )
        _add(
            obj,
            ANGLE,
            "Lead",
            "Strategy",
            "Lead angle: the axis leans towards the feed (the paper's Omega_t; 5 axes only)",
            10.0,
        )
        _add(
            obj,
            ANGLE,
            "Tilt",
            "Strategy",
            "Tilt angle: the axis turns about the normal (the paper's Omega_n; 5 axes only)",
            0.0,
        )
        _add(
            obj,
            LENGTH,
            "Tolerance",
            "Approximation",
            "Largest distance between the fitted guiding/orientation surfaces and the exact ones, measured "
            "on points the fit never saw. " + FIT_BUDGET,
            preference("DefaultTolerance", 1e-3),
        )
        _add(
            obj,
            "App::PropertyEnumeration",
            "Loops",
            "Approximation",
            "On loops: error, flag or trim",
            ["error", "flag", "trim"],
        )
        if "trim" not in obj.getEnumerationsOfProperty("Loops"):  # migration from 0.1 (error, flag)
            current = str(obj.Loops)
            obj.Loops = ["error", "flag", "trim"]
            obj.Loops = current
        for old, new in RENAMED_RESULTS:
            _rename(obj, old, new)
        for name, kind, doc in (
            ("GuidingSurfaceError", LENGTH, "Measured largest error of the guiding surface (tool centres; the "
             "paper's S1), on points the fit never saw"),
            ("OrientationSurfaceError", LENGTH, "Measured largest error of the orientation surface (a point on the "
             "tool axis; the paper's S2)"),
            ("AlphaMax", ANGLE, "Bound of the tool-axis orientation error for the measured errors (alpha_max)"),
        ):  # fmt: skip
            _add(obj, kind, name, "Result", doc, read_only=True)
        for name, doc in (
            ("GuidingSurfacePoles", "Poles of the guiding surface (S1)"),
            ("OrientationSurfacePoles", "Poles of the orientation surface (S2)"),
            ("LoopReport", "Loops found"),
            ("Status", "Last recompute"),
            ("Report", "JSON report of the last recompute"),
        ):
            _add(obj, "App::PropertyString", name, "Result", doc, read_only=True)
        maps.add_properties(obj)

    def compute(self, obj):
        f = face_to_numpy(source_face(obj), "F")
        axes = int(obj.Axes)
        if axes not in (3, 5):
            raise InputError(f"Axes must be 3 or 5, got {axes}")
        ms, dev = self.core(
            _surface_and_deviation,
            f,
            tool_text(obj.Tool),
            axes=axes,
            strategy=obj.Strategy,
            lead=value_of(obj.Lead) if axes == 5 else 0.0,  # lead and tilt are 5-axis settings
            tilt=value_of(obj.Tilt) if axes == 5 else 0.0,
            tolerance=value_of(obj.Tolerance),
            loops=str(obj.Loops),
        )
        faces = [face_to_part(x) for x in ms.faces()]
        self.tick("writing the result")
        obj.Shape = Part.Compound(faces)
        self.tick("writing the result")
        obj.GuidingSurfaceError = ms.s1_fit.max_error
        obj.GuidingSurfacePoles = "x".join(str(n) for n in ms.s1_fit.surface.shape)
        obj.OrientationSurfaceError = ms.s2_fit.max_error if ms.s2_fit else 0.0
        obj.OrientationSurfacePoles = "x".join(str(n) for n in ms.s2_fit.surface.shape) if ms.s2_fit else ""
        maps.deviation_map(obj, ms, dev)
        obj.AlphaMax = ms.alpha_max_deg_measured or 0.0
        obj.LoopReport = "none" if not ms.loops.found else "; ".join(r.describe() for r in ms.loops.regions)
        obj.Report = strict_json(ms.report(), indent=None)


class EffectiveRadiusFeature(_Base):
    """Effective cutter radius over a face for one machining direction (machsurf_cad.effradius); the shape is
    the face, coloured by the GUI; the figures are properties."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Face to analyse")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "bull:D=..,r=.. (mm)", "bull:D=10,r=2")
        _add(obj, ANGLE, "Direction", "Strategy", "Machining direction, from the X axis", 0.0)
        _add(
            obj,
            "App::PropertyIntegerConstraint",
            "Grid",
            "Strategy",
            "Samples per parameter direction (8 to 1024; 1024 needs about 0.7 GB, see MemoryNeeded)",
            (min(max(preference("DefaultGrid", 64), 8), 1024), 8, 1024, 8),
        )
        _add(obj, "App::PropertyString", "MemoryNeeded", "Strategy", "Memory the grid needs (stated before running)",
             read_only=True)  # fmt: skip
        obj.MemoryNeeded = reff_memory_text(int(obj.Grid))
        _add(obj, LENGTH, "Scallop", "Strategy", "Scallop height for the step-over; 0 for none", 0.0)
        _add(obj, "App::PropertyEnumeration", "MapShows", "Map", "What the colour map shows (step-over needs a "
             "scallop height)", ["effective radius", "step-over"])  # fmt: skip
        for name, kind, doc in (
            ("ReffMin", LENGTH, "Smallest effective cutter radius over the face"),
            ("ReffMean", LENGTH, "Mean effective cutter radius over the face"),
            ("ReffMax", LENGTH, "Largest effective cutter radius over the face"),
            ("TorusBeatsBall", "App::PropertyFloat", "Area fraction where the torus's R_eff beats the ball's"),
        ):
            _add(obj, kind, name, "Result", doc, read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)
        maps.add_properties(obj)

    def onChanged(self, obj, prop):
        if prop == "Grid" and "MemoryNeeded" in obj.PropertiesList:
            obj.MemoryNeeded = reff_memory_text(int(obj.Grid))

    def compute(self, obj):
        from machsurf_cad import reff_maps

        fc = source_face(obj)
        f = face_to_numpy(fc, "F")
        m = self.core(
            reff_maps,
            f,
            tool_text(obj.Tool),
            progress=False,
            directions=[value_of(obj.Direction)],
            grid=int(obj.Grid),
            scallop=value_of(obj.Scallop) or None,
        )
        d = m.report()["directions"][0]
        obj.ReffMin, obj.ReffMean, obj.ReffMax = d["r_eff_min_mm"], d["r_eff_mean_mm"], d["r_eff_max_mm"]
        obj.TorusBeatsBall = d["area_fraction_torus_beats_ball"]
        obj.Report = strict_json(m.report(), indent=None)
        self.map = m
        maps.reff_map(obj, m, str(obj.MapShows))
        obj.Shape = fc.copy()


class FlankSettingFeature(_Base):
    """Optimum (or standard/minimax) flank setting of a cylindrical cutter on a ruled face; the shape is
    the placed cylinder (machsurf_cad.flank_milling)."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Ruled face")
        _add(obj, LENGTH, "Radius", "Cutter", "Radius of the cylindrical cutter (the paper's R)", 10.0)
        rule = _rename(obj, "Rule", "RulePosition")
        side = _rename(obj, "Side", "ToolSide")
        _add(
            obj,
            "App::PropertyFloatConstraint",
            "RulePosition",
            "Strategy",
            "Which rule (straight line of the face) the tool touches: 0 at the face's first rule, 1 at its last "
            "(fraction of the parameter range across the rules)",
            (0.5 if rule is None else float(rule), 0.0, 1.0, 0.05),
        )
        _add(
            obj,
            "App::PropertyEnumeration",
            "Setting",
            "Strategy",
            "Tool setting",
            ["optimum", "standard-distributed", "standard-bisector", "standard-tangent", "minimax"],
        )
        _add(
            obj,
            "App::PropertyEnumeration",
            "ToolSide",
            "Strategy",
            "Side of the face the tool is on: the side its normal points to, or the opposite one "
            "(the paper's side +1 / -1)",
            list(TOOL_SIDES),
        )
        if side is not None:  # an older document's Side +1/-1
            obj.ToolSide = TOOL_SIDES[0] if int(side) >= 0 else TOOL_SIDES[1]
        for name, kind, doc in (
            ("MaxGouge", LENGTH, "Deepest the cutter goes into the face along the rule"),
            ("MaxUndercut", LENGTH, "Thickest material left along the rule"),
            ("Gamma", ANGLE, "Tool axis inclination to the rule (the paper's gamma)"),
        ):
            _add(obj, kind, name, "Result", doc, read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)
        maps.add_properties(obj)

    MAP_BESIDE = True  # the strip's map is drawn beside the placed cylinder

    def compute(self, obj):
        from machsurf_cad import flank

        face = face_to_numpy(source_face(obj), "F")
        res = self.core(
            flank,
            face,
            value_of(obj.Radius),
            rule=float(obj.RulePosition),
            setting=str(obj.Setting),
            side=1 if str(obj.ToolSide) == TOOL_SIDES[0] else -1,
        )
        st, e = res.setting, res.interference
        obj.MaxGouge, obj.MaxUndercut, obj.Gamma = e.max_gouge, e.max_undercut, st.gamma_deg
        obj.Report = strict_json(res.report(), indent=None)
        tip, axis, length = st.placement()
        maps.flank_map(obj, face, res.u_p, (tip, axis, length), value_of(obj.Radius))
        obj.Shape = Part.makeCylinder(
            value_of(obj.Radius), float(length), FreeCAD.Vector(*map(float, tip)), FreeCAD.Vector(*map(float, axis))
        )


class EnvelopeFeature(_Base):
    """Swept envelopes of a rotational tool along an example motion, chained G1 (machsurf_cad.sweep)."""

    def properties(self, obj):
        _add(
            obj,
            "App::PropertyString",
            "Tool",
            "Cutter",
            "cyl:|cone:|drum:|barrel:|ball: (mm, deg)",
            "cone:D=10,angle=10,L=20",
        )
        _add(obj, "App::PropertyString", "Motion", "Motion", "Example motion: sine, line, helix", "sine")
        _add(obj, "App::PropertyInteger", "Passes", "Motion", "Number of passes", 2)
        theta = _rename(obj, "Theta", "PassTurn")
        _add(obj, ANGLE, "PassTurn", "Motion", "Turn of the tool axis about the seam normal from one pass to the "
             "next (the paper's theta)", 0.0 if theta is None else value_of(theta))  # fmt: skip
        _add(
            obj,
            LENGTH,
            "Tolerance",
            "Approximation",
            "Largest distance of the fitted envelopes from the exact ones. " + FIT_BUDGET,
            preference("DefaultTolerance", 1e-3),
        )
        _add(obj, LENGTH, "MaxSeamGap", "Result", "Largest gap at a seam between passes", read_only=True)
        _add(obj, ANGLE, "MaxSeamAngle", "Result", "Largest normal angle at a seam between passes", read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)
        maps.add_properties(obj)

    def compute(self, obj):
        from machsurf_cad import envelope, example

        res = self.core(
            envelope,
            tool_text(obj.Tool),
            example(str(obj.Motion), "motion"),
            passes=int(obj.Passes),
            theta=value_of(obj.PassTurn),
            tolerance=value_of(obj.Tolerance),
        )
        ch = res.chain
        faces = []
        for fit in ch.fits:
            s = fit.surface
            u0, u1, v0, v1 = s.bounds
            faces.append(surface_to_part(s).toShape(u0, u1, v0, v1))
        obj.Shape = Part.Compound(faces)
        rep = ch.report()
        obj.MaxSeamGap = max([s["fitted"]["max_gap_mm"] for s in rep["seams"]] or [0.0])
        obj.MaxSeamAngle = max([s["fitted"]["max_normal_angle_deg"] for s in rep["seams"]] or [0.0])
        obj.Report = strict_json(rep, indent=None)
        maps.envelope_map(obj, ch, value_of(obj.Tolerance))


def attach_view(obj):
    """In the GUI, give ``obj`` machsurf's view provider unless it has it (headless: nothing)."""
    if not FreeCAD.GuiUp or getattr(obj, "ViewObject", None) is None:
        return
    from ..gui.view import ViewProvider, attach

    if not isinstance(obj.ViewObject.Proxy, ViewProvider):
        attach(obj)


class Cancelled(MachsurfError):
    """The user cancelled a recompute (Esc on FreeCAD's progress bar)."""


class Progress:
    """machsurf_cad's ``progress(done, total, message)`` on FreeCAD's progress bar (Base.ProgressIndicator).

    A known total gives a bar, an unknown one (``total`` None: a fit refining until its tolerance) a busy
    indicator stepped once a call. Every step lets the user cancel (Esc in the GUI): the recompute then
    stops with :class:`Cancelled`, and the feature is emptied like after any error.
    """

    def __init__(self, indicator=None):
        self.indicator = indicator or (lambda: FreeCAD.Base.ProgressIndicator())
        self.bar = None
        self.done = 0
        self.total = None

    def __call__(self, done, total=None, message=""):
        steps = int(total) if total else 0
        if self.bar is None or steps != self.total:
            self.stop()
            self.bar = self.indicator()
            self.bar.start(str(message or "machsurf"), steps)
            self.total = steps
        n = max(0, int(done) - self.done) if steps else 1
        try:
            for _ in range(n):
                self.bar.next(True)  # True: may be cancelled here
        except RuntimeError:  # FreeCAD's sequencer aborts with RuntimeError("abort exception")
            self.bar = None
            raise Cancelled("cancelled by the user") from None
        self.done = max(self.done, int(done))

    def stop(self):
        if self.bar is not None:
            self.bar.stop()
        self.bar = None
        self.done = 0
        self.total = None


def make(kind, doc=None, source=None, **props):
    """Create a feature in ``doc`` (``kind``: MachiningSurface, EffectiveRadius, FlankSetting, Envelope,
    CamOperation: a Path operation in the document's Job, see :mod:`.camop`)."""
    doc = doc or FreeCAD.ActiveDocument
    if kind == "CamOperation":
        from .camop import make_operation

        return make_operation(doc, source, **props)
    classes = {
        "MachiningSurface": MachiningSurfaceFeature,
        "EffectiveRadius": EffectiveRadiusFeature,
        "FlankSetting": FlankSettingFeature,
        "Envelope": EnvelopeFeature,
    }
    obj = doc.addObject("Part::FeaturePython", kind)
    classes[kind](obj)
    if source is not None:
        obj.Source = source
    for k, v in props.items():
        if k == "Axes" and isinstance(v, str) and v.strip().isdigit():  # Axes="3" as the 0.3 enumeration took it
            v = int(v)
        setattr(obj, k, v)
    attach_view(obj)
    return obj
