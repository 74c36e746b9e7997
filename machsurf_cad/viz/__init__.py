"""Rendering with pyvista: the only subpackage of machsurf_cad that imports pyvista.

Off-screen PNGs and .vtp files for interactive review. Numbers first: every picture here
is drawn from a result object whose figures are already in the JSON report.
"""

from .render import deviation_polydata, render_deviation, render_gouge_map, render_scalar_map, render_zebra
from .simmap import render_simulation_map, simulation_polydata

__all__ = [
    "deviation_polydata",
    "render_deviation",
    "render_gouge_map",
    "render_scalar_map",
    "render_zebra",
    "render_simulation_map",
    "simulation_polydata",
]
