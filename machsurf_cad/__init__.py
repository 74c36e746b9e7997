"""machsurf_cad: free-form surface machining geometry on the OpenCASCADE kernel.

Units: millimetres for lengths, degrees for angles, at every public boundary.
The algorithms are numpy/scipy only; :mod:`machsurf_cad.occ` is the single door to the
kernel (cadquery/OCP) and :mod:`machsurf_cad.viz` the single user of pyvista.
"""

from .errors import DegenerateGeometryError, InputError, MachsurfError, ToleranceError
from .geometry import BSplineCurve, BSplineSurface, builders, local_properties

__version__ = "0.1.0"

__all__ = ["BSplineCurve", "BSplineSurface", "builders", "local_properties", "MachsurfError", "InputError",
           "DegenerateGeometryError", "ToleranceError", "__version__"]
