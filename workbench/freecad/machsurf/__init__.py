"""machsurf FreeCAD add-on: a thin view over machsurf_cad's numpy core (no cadquery/OCP here).

Geometry crosses between FreeCAD's OpenCASCADE and machsurf_cad as B-spline arrays (degree,
knots, multiplicities, poles, weights). Lengths in mm, angles in degrees.
"""

import os
import sys
from pathlib import Path


def _numba_cache():
    """numba's compiled drop-cutter kernel, for FreeCAD's Python (``python3-numba``), cached in FreeCAD's user
    folder: beside the sources numba would share one cache with the repository's own environment, and each
    would throw the other's away (numba keeps one kernel per file and numba version)."""
    if "NUMBA_CACHE_DIR" not in os.environ and "numba" not in sys.modules:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        os.environ["NUMBA_CACHE_DIR"] = os.path.join(base, "machsurf_cad", "freecad-numba")


def ensure_core():
    """Make ``machsurf_cad`` importable: the repository this add-on lives in, by its real path (FreeCAD reaches
    it through the Mod folder's link: numba keys its cache by the sources' path, and a path through another
    link would compile the kernel again), else the installed package."""
    here = Path(__file__).resolve()
    for parent in here.parents:
        if (parent / "machsurf_cad" / "__init__.py").is_file():
            if "machsurf_cad" not in sys.modules and str(parent) not in sys.path[:1]:
                sys.path.insert(0, str(parent))
            break
    import machsurf_cad  # noqa: F401  (raises a clear ImportError if not found)


_numba_cache()
ensure_core()

from machsurf_cad import __version__ as __version__
