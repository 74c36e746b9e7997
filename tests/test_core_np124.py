"""numpy-only checks of the core, run by `make np124` under numpy 1.24 / scipy 1.10 (FreeCAD's)
as well as in the main suite: no kernel, no pyvista."""

import sys

import numpy as np

from machsurf_cad import examples
from machsurf_cad.geometry import builders, insert_knot_surface, local_properties
from machsurf_cad.measure import deviation
from machsurf_cad.toolspec import parse_cutter


def test_core_does_not_load_kernel_or_pyvista():
    import machsurf_cad
    import machsurf_cad.measure  # noqa: F401

    assert "OCP" not in sys.modules or "machsurf_cad.occ" in sys.modules
    assert "pyvista" not in sys.modules or "machsurf_cad.viz" in sys.modules


def test_closed_forms_under_this_numpy():
    s = builders.torus_patch(40.0, 10.0)
    u, v = np.linspace(0.05, 0.95, 30), np.linspace(0.95, 0.05, 30)
    p = local_properties(s, u, v)
    assert np.abs(np.maximum(p.k1, p.k2) - 0.1).max() < 1e-12
    s2 = insert_knot_surface(s, 0.3, "u")
    assert np.abs(s2.evaluate(u, v) - s.evaluate(u, v)).max() < 1e-12
    d = deviation(builders.sphere_patch(50.0), builders.sphere_patch(51.0, lat_deg=(-50, 50), lon_deg=80), samples=30)
    assert np.abs(d.signed + 1.0).max() < 1e-10
    assert parse_cutter("bull:D=20,r=4").R_t == 6.0
    assert examples.eq18_surface(1e-3).max_error <= 1e-3
