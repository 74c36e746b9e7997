"""machsurf_cad: free-form surface machining geometry on the OpenCASCADE kernel.

Units: millimetres for lengths, degrees for angles, at every public boundary.
The algorithms are numpy/scipy only; :mod:`machsurf_cad.occ` is the single door to the
kernel (cadquery/OCP) and :mod:`machsurf_cad.viz` the single user of pyvista.
"""

from .errors import DegenerateGeometryError, InputError, MachsurfError, ToleranceError
from .geometry import BSplineCurve, BSplineSurface, builders, local_properties

__version__ = "0.1.0"

_LAZY = {  # the main entry points, imported on first use (numpy/scipy only)
    "machining_surface": ("machsurf_cad.machining", "machining_surface"),
    "reff_maps": ("machsurf_cad.effradius", "reff_maps"),
    "flank": ("machsurf_cad.flank_milling", "flank"),
    "envelope": ("machsurf_cad.sweep", "envelope"),
    "deviation": ("machsurf_cad.measure", "deviation"),
    "parse_cutter": ("machsurf_cad.cutters", "parse_cutter"),
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        mod, attr = _LAZY[name]
        return getattr(importlib.import_module(mod), attr)
    raise AttributeError(f"module 'machsurf_cad' has no attribute {name!r}")


__all__ = ["BSplineCurve", "BSplineSurface", "builders", "local_properties", "MachsurfError", "InputError",
           "DegenerateGeometryError", "ToleranceError", "__version__", *_LAZY]
