"""Exact B-spline/NURBS geometry in numpy: types, evaluation, differential geometry, builders."""

from . import builders
from .bspline import BSplineCurve, BSplineSurface, SurfaceDerivatives
from .differential import LocalProperties, local_properties, local_properties_grid
from .knots import elevate_and_merge, insert_knot_curve, insert_knot_surface, refit_curve_in_space

__all__ = [
    "BSplineCurve",
    "BSplineSurface",
    "SurfaceDerivatives",
    "LocalProperties",
    "local_properties",
    "local_properties_grid",
    "builders",
    "insert_knot_curve",
    "insert_knot_surface",
    "refit_curve_in_space",
    "elevate_and_merge",
]
