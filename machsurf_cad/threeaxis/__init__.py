"""3-axis (and 3+2) machining of whole parts: exact drop-cutter on the B-rep, height fields, raster
and waterline tool paths."""

from .dropcutter import Contact, DropCutterResult, default_seed_spacing, drop_cutter
from .faceset import FaceSet, axis_frame, face_set

__all__ = ["Contact", "DropCutterResult", "FaceSet", "axis_frame", "default_seed_spacing", "drop_cutter", "face_set"]
