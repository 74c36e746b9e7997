"""machsurf FreeCAD add-on: a thin view over machsurf_cad's numpy core (no cadquery/OCP here).

Geometry crosses between FreeCAD's OpenCASCADE and machsurf_cad as B-spline arrays (degree,
knots, multiplicities, poles, weights). Lengths in mm, angles in degrees.
"""

import sys
from pathlib import Path


def ensure_core():
    """Make ``machsurf_cad`` importable: installed, or the repository this add-on is linked from."""
    try:
        import machsurf_cad

        return
    except ImportError:
        pass
    here = Path(__file__).resolve()
    for parent in here.parents:
        if (parent / "machsurf_cad" / "__init__.py").is_file():
            sys.path.insert(0, str(parent))
            break
    import machsurf_cad  # noqa: F401  (raises a clear ImportError if not found)


ensure_core()

from machsurf_cad import __version__ as __version__
