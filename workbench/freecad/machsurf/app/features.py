"""Parametric App-level features (no GUI import: they recompute headless in FreeCADCmd).

Each feature is a ``Part::FeaturePython`` whose properties mirror the machsurf_cad Python API
(lengths in mm, angles in degrees). ``execute`` calls machsurf_cad and turns the returned B-spline
arrays into Part faces; the measured errors and reports of the last recompute are read-only
properties. On bad input the message goes to the report view and into ``Status``, and the feature
is marked invalid; the document is left as it was.
"""

import json

import FreeCAD
import Part

from .. import ensure_core

ensure_core()

from machsurf_cad.errors import MachsurfError

from ..convert import face_to_numpy, face_to_part, surface_to_part

READ_ONLY = 1


def _add(obj, kind, name, group, doc, value=None, read_only=False):
    if name not in obj.PropertiesList:
        obj.addProperty(kind, name, group, doc)
        if value is not None:
            setattr(obj, name, value)
    if read_only:
        obj.setEditorMode(name, READ_ONLY)


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

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None

    def execute(self, obj):
        try:
            self.compute(obj)
            obj.Status = "ok"
        except Exception as exc:  # every failure: a message, an invalid feature, the document unharmed
            msg = (
                f"{obj.Label}: {exc}"
                if isinstance(exc, (MachsurfError, ValueError))
                else f"{obj.Label}: {type(exc).__name__}: {exc}"
            )
            obj.Status = str(exc)
            FreeCAD.Console.PrintError(msg + "\n")
            raise RuntimeError(msg) from None  # marks the feature invalid; the document stays as it was


class MachiningSurfaceFeature(_Base):
    """Guiding surface S1 and orientation surface S2 of a face (machsurf_cad.machining)."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Face to machine")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "ball:D=.., flat:D=.., bull:D=..,r=.. (mm)", "bull:D=20,r=4")
        _add(obj, "App::PropertyEnumeration", "Axes", "Strategy", "3 or 5 axes", ["5", "3"])
        _add(obj, "App::PropertyString", "Strategy", "Strategy", "planes:x|y|z|a,b,c or iso:u|v", "planes:x")
        _add(obj, "App::PropertyFloat", "Lead", "Strategy", "Lead angle Omega_t (deg), leans towards the feed", 10.0)
        _add(obj, "App::PropertyFloat", "Tilt", "Strategy", "Tilt angle Omega_n (deg), about the normal", 0.0)
        _add(obj, "App::PropertyFloat", "Tolerance", "Approximation", "Max-norm fit tolerance (mm)", 1e-3)
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
        for name, doc in (
            ("MaxErrorS1", "Measured max error of S1 (mm)"),
            ("MaxErrorS2", "Measured max error of S2 (mm)"),
            ("AlphaMax", "Axis orientation error bound for the measured errors (deg)"),
        ):
            _add(obj, "App::PropertyFloat", name, "Result", doc, read_only=True)
        for name, doc in (
            ("PolesS1", "Poles of S1"),
            ("PolesS2", "Poles of S2"),
            ("LoopReport", "Loops found"),
            ("Status", "Last recompute"),
            ("Report", "JSON report of the last recompute"),
        ):
            _add(obj, "App::PropertyString", name, "Result", doc, read_only=True)

    def compute(self, obj):
        from machsurf_cad import machining_surface

        f = face_to_numpy(source_face(obj), "F")
        ms = machining_surface(
            f,
            obj.Tool,
            axes=int(obj.Axes),
            strategy=obj.Strategy,
            lead=float(obj.Lead),
            tilt=float(obj.Tilt),
            tolerance=float(obj.Tolerance),
            loops=str(obj.Loops),
        )
        faces = [face_to_part(x) for x in ms.faces()]
        obj.Shape = Part.Compound(faces)
        obj.MaxErrorS1 = ms.s1_fit.max_error
        obj.PolesS1 = "x".join(str(n) for n in ms.s1_fit.surface.shape)
        obj.MaxErrorS2 = ms.s2_fit.max_error if ms.s2_fit else 0.0
        obj.PolesS2 = "x".join(str(n) for n in ms.s2_fit.surface.shape) if ms.s2_fit else ""
        obj.AlphaMax = ms.alpha_max_deg_measured or 0.0
        obj.LoopReport = "none" if not ms.loops.found else "; ".join(r.describe() for r in ms.loops.regions)
        obj.Report = json.dumps(ms.report(), default=float)


class EffectiveRadiusFeature(_Base):
    """Effective cutter radius over a face for one machining direction (machsurf_cad.effradius); the shape is
    the face, coloured by the GUI; the figures are properties."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Face to analyse")
        _add(obj, "App::PropertyString", "Tool", "Cutter", "bull:D=..,r=.. (mm)", "bull:D=10,r=2")
        _add(obj, "App::PropertyFloat", "Direction", "Strategy", "Machining direction theta (deg from X)", 0.0)
        _add(obj, "App::PropertyInteger", "Grid", "Strategy", "Samples per parameter direction", 64)
        _add(obj, "App::PropertyFloat", "Scallop", "Strategy", "Scallop height (mm), 0 for none", 0.0)
        for name in ("ReffMin", "ReffMean", "ReffMax", "TorusBeatsBall"):
            _add(obj, "App::PropertyFloat", name, "Result", name + " (mm, or area fraction)", read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)

    def compute(self, obj):
        from machsurf_cad import reff_maps

        fc = source_face(obj)
        f = face_to_numpy(fc, "F")
        m = reff_maps(
            f, obj.Tool, directions=[float(obj.Direction)], grid=int(obj.Grid), scallop=float(obj.Scallop) or None
        )
        d = m.report()["directions"][0]
        obj.ReffMin, obj.ReffMean, obj.ReffMax = d["r_eff_min_mm"], d["r_eff_mean_mm"], d["r_eff_max_mm"]
        obj.TorusBeatsBall = d["area_fraction_torus_beats_ball"]
        obj.Report = json.dumps(m.report(), default=float)
        self.map = m
        obj.Shape = fc.copy()


class FlankSettingFeature(_Base):
    """Optimum (or standard/minimax) flank setting of a cylindrical cutter on a ruled face; the shape is
    the placed cylinder (machsurf_cad.flank_milling)."""

    def properties(self, obj):
        _add(obj, "App::PropertyLinkSub", "Source", "Nominal", "Ruled face")
        _add(obj, "App::PropertyFloat", "Radius", "Cutter", "Cylinder radius (mm)", 10.0)
        _add(obj, "App::PropertyFloat", "Rule", "Strategy", "Rule position, fraction of the u range", 0.5)
        _add(
            obj,
            "App::PropertyEnumeration",
            "Setting",
            "Strategy",
            "Tool setting",
            ["optimum", "standard-distributed", "standard-bisector", "standard-tangent", "minimax"],
        )
        _add(obj, "App::PropertyInteger", "Side", "Strategy", "+1 or -1", 1)
        for name in ("MaxGouge", "MaxUndercut", "Gamma"):
            _add(obj, "App::PropertyFloat", name, "Result", name + " (mm or deg)", read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)

    def compute(self, obj):
        from machsurf_cad import flank

        res = flank(
            face_to_numpy(source_face(obj), "F"),
            float(obj.Radius),
            rule=float(obj.Rule),
            setting=str(obj.Setting),
            side=int(obj.Side),
        )
        st, e = res.setting, res.interference
        obj.MaxGouge, obj.MaxUndercut, obj.Gamma = e.max_gouge, e.max_undercut, st.gamma_deg
        obj.Report = json.dumps(res.report(), default=float)
        tip, axis, length = st.placement()
        obj.Shape = Part.makeCylinder(
            float(obj.Radius), float(length), FreeCAD.Vector(*map(float, tip)), FreeCAD.Vector(*map(float, axis))
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
        _add(obj, "App::PropertyFloat", "Theta", "Motion", "Axis turn about n1 between passes (deg)", 0.0)
        _add(obj, "App::PropertyFloat", "Tolerance", "Approximation", "Fit tolerance (mm)", 1e-3)
        _add(obj, "App::PropertyFloat", "MaxSeamGap", "Result", "Largest seam gap (mm)", read_only=True)
        _add(obj, "App::PropertyFloat", "MaxSeamAngle", "Result", "Largest seam normal angle (deg)", read_only=True)
        for name in ("Status", "Report"):
            _add(obj, "App::PropertyString", name, "Result", name, read_only=True)

    def compute(self, obj):
        from machsurf_cad import envelope, example

        res = envelope(
            obj.Tool,
            example(str(obj.Motion), "motion"),
            passes=int(obj.Passes),
            theta_deg=float(obj.Theta),
            tolerance=float(obj.Tolerance),
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
        obj.Report = json.dumps(rep, default=float)


def make(kind, doc=None, source=None, **props):
    """Create a feature in ``doc`` (``kind``: MachiningSurface, EffectiveRadius, FlankSetting, Envelope)."""
    doc = doc or FreeCAD.ActiveDocument
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
        setattr(obj, k, v)
    return obj
