"""3-axis (and 3+2) machining of whole parts: exact drop-cutter on the B-rep, the certified
height-field CL surface, raster and waterline tool paths."""

from .dropcutter import Contact, DropCutterResult, default_seed_spacing, drop_cutter
from .faceset import FaceSet, axis_frame, face_set
from .heightfield import cl_surface
from .paths import Direction, Pattern, raster
from .reachpath import trim_to_reach
from .select import select_faces, top_faces
from .wholepart import Mill3Result, mill3
from .zlevel import waterline

__all__ = [
    "Contact",
    "Direction",
    "DropCutterResult",
    "FaceSet",
    "Mill3Result",
    "Pattern",
    "axis_frame",
    "cl_surface",
    "default_seed_spacing",
    "drop_cutter",
    "face_set",
    "mill3",
    "raster",
    "select_faces",
    "top_faces",
    "trim_to_reach",
    "waterline",
]
