"""Renderers, checked after the numbers behind them: the map's data equal the deviations, then the picture
uses the diverging colours on both sides of zero."""

import numpy as np
from conftest import needs_pyvista

from machsurf_cad import deviation
from machsurf_cad.geometry import builders

pytestmark = needs_pyvista


def test_deviation_map_numbers_then_picture(tmp_path):
    import pyvista as pv
    from PIL import Image

    from machsurf_cad.viz import render_deviation

    plane = builders.plane_patch()  # 100 x 100 mm in z = 0
    s = plane
    lo, hi = s.poles[..., 0].min(), s.poles[..., 0].max()
    ramp = s.with_poles(
        s.poles + np.stack([0 * s.poles[..., 0], 0 * s.poles[..., 0], 2 * (s.poles[..., 0] - lo) / (hi - lo) - 1], -1)
    )
    d = deviation(plane, ramp, samples=41)
    # numbers first: the candidate is z = 2 (x - lo) / (hi - lo) - 1 over the plane z = 0: the signed distance
    # of each sample is its height, from -1 to +1 mm exactly
    assert abs(d.stats["max"] - 1.0) < 1e-9 and abs(d.stats["min"] + 1.0) < 1e-9
    assert np.abs(d.signed - d.points[:, 2]).max() < 1e-12
    png = render_deviation(d, tmp_path / "map.png", vtp_path=tmp_path / "map.vtp", tolerance=0.5)
    mesh = pv.read(tmp_path / "map.vtp")
    assert np.abs(np.sort(mesh.point_data["deviation_mm"]) - np.sort(d.signed)).max() < 1e-12
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    red = (img[..., 0] > 170) & (img[..., 2] < 110)
    blue = (img[..., 2] > 170) & (img[..., 0] < 110)
    assert red.sum() > 2000 and blue.sum() > 2000  # both sides of zero are drawn, in opposite colours
