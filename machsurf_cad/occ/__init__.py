"""The kernel door: the only subpackage of machsurf_cad that imports OCP/cadquery.

Everything crossing this boundary is plain numpy data (B-spline arrays, :class:`Face`).
Tested with cadquery 2.8.0 and cadquery-ocp 7.9.3.1.1 (OCP 7.9: static methods end in ``_s``).
"""

import importlib.util as _util

if _util.find_spec("OCP") is None:  # pragma: no cover - exercised only without the kernel
    from ..errors import InputError

    raise InputError("the OpenCASCADE kernel (cadquery-ocp) is not installed: pip install 'machsurf_cad[occ]'")
import OCP  # noqa: F401  (any other failure, Ctrl-C included, propagates as itself)

from .convert import (
    check_valid,
    face_from_surface,
    from_geom_surface,
    is_valid,
    to_cq_face,
    to_geom_surface,
)
from .mesh import read_stl, triangulate_face, triangulate_step, write_stl
from .step import from_cq_face, read_step_face, read_step_faces, step_face_summaries, write_step

__all__ = [
    "to_geom_surface",
    "from_geom_surface",
    "to_cq_face",
    "from_cq_face",
    "face_from_surface",
    "check_valid",
    "is_valid",
    "read_step_faces",
    "step_face_summaries",
    "read_step_face",
    "write_step",
    "write_stl",
    "read_stl",
    "triangulate_face",
    "triangulate_step",
]
