"""Lengths typed with every digit: FreeCAD's property editor rounds a length to the user's decimals in mm
(2 by default) when it stores it, so a tolerance of ``0.5 um`` typed there became 0.0 mm. The GUI hook
(:mod:`..gui.precise_edit`) hands the text the user typed to :func:`set_precise`, which parses it with
FreeCAD's unit parser and stores the exact value, or refuses it with one line and keeps the value before.
"""

import FreeCAD

LENGTHS = ("App::PropertyLength", "App::PropertyDistance")
"""The property types whose typed text is stored exactly."""
PRECISE = ("Tolerance", "SurfaceTolerance", "ChordalTolerance", "GougeTolerance")
"""The tolerances (sub-micron values): refused below :data:`SMALLEST_MM` instead of stored."""

SMALLEST_MM = 1e-6
"""Below 1 nm FreeCAD shows a length as 0.00 mm: such a tolerance is refused, not stored."""


def set_precise(obj, name: str, text: str, before: float):
    """Store ``text`` (``0.5 um``, ``0.0005 mm``, ``0.0005``: mm when no unit) in ``obj.<name>`` exactly; on a
    bad value restore ``before`` (mm) and return the one-line reason, else return None."""
    try:
        q = FreeCAD.Units.Quantity(str(text).strip())
    except Exception:
        q = None
    why = None
    if q is None or q.Unit not in (FreeCAD.Units.Unit(), FreeCAD.Units.Length):
        why = f"{name}: {text!r} is not a length (e.g. 0.5 um, 0.0005 mm)"
    elif obj.getTypeIdOfProperty(name) == "App::PropertyLength" and q.Value < 0:
        why = f"{name} must be >= 0 mm, got {text!r}: not stored, kept {before:g} mm"
    elif name in PRECISE and not q.Value >= SMALLEST_MM:
        why = f"{name} must be at least {SMALLEST_MM:g} mm (1 nm), got {text!r}: not stored, kept {before:g} mm"
    if why is not None:
        setattr(obj, name, before)
        return why
    setattr(obj, name, float(q.Value))
    return None
