"""Machining surfaces (guiding S1, orientation S2), loop detection and tool paths (numpy only)."""

from .loops import LoopError, LoopRegion, LoopReport
from .strategies import AxisField, FixedAxis, IsoFeed, LeadTilt, PlanesFeed, parse_strategy
from .surfaces import MachiningMaps, MachiningSurface, detect_loops, machining_surface, recover_axis

__all__ = [
    "machining_surface",
    "MachiningSurface",
    "MachiningMaps",
    "recover_axis",
    "detect_loops",
    "LoopError",
    "LoopRegion",
    "LoopReport",
    "AxisField",
    "FixedAxis",
    "IsoFeed",
    "LeadTilt",
    "PlanesFeed",
    "parse_strategy",
]
