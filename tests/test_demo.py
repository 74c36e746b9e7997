"""`machsurf demo`: the main job's numbers, then its picture."""

import json
import os
import subprocess
import sys

import numpy as np
from conftest import ROOT, needs_kernel, needs_pyvista

pytestmark = [needs_kernel, needs_pyvista]


def test_demo_outputs_and_figures(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = tmp_path / "out"
    r = subprocess.run(
        [sys.executable, "-m", "machsurf_cad", "demo", "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        stdin=subprocess.DEVNULL,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    assert "Warning" not in r.stderr and "deprecated" not in r.stderr.lower(), r.stderr  # nothing a user should not see
    rep = json.loads((out / "report.json").read_text())
    for f in rep["files"]:
        assert (out / f).is_file(), f
    assert rep["step_round_trip"]["max_abs_mm"] < 1e-7
    stl = rep["stl"]["deviation"]
    assert stl["max_abs_mm"] < 2 * rep["stl"]["linear_deflection_mm"]
    assert stl["n_points"] > 10 * rep["stl"]["triangles"] / 4
    assert f"{stl['max_abs_mm']:.4g}" in r.stdout
    assert 100 < rep["nominal"]["min_radius_of_curvature_mm"] < 1e4
    ms = rep["machining_surface"]
    assert ms["S1"]["max_error_mm"] <= 1e-3 and ms["S2"]["max_error_mm"] <= 1e-3
    assert rep["S1_deviation_map"]["max_abs_mm"] <= 1e-3 and not ms["loops"]["found"]
    assert rep["toolpath"]["chordal_error_measured_mm"] <= 0.005
    v = rep["verify"]  # the tool body against all 8 faces of the block: clean
    assert v["clean"] and v["n_faces"] == 8 and v["max_gouge_mm"] <= 0.01 and v["n_collisions"] == 0
    # the picture comes after its numbers: a rendered image, not a blank frame
    from PIL import Image

    img = np.asarray(Image.open(out / "deviation_stl.png").convert("RGB"))
    assert img.shape[0] >= 600 and img.shape[1] >= 800
    colours = np.unique(img.reshape(-1, 3), axis=0)
    assert len(colours) > 200
    blue = (img[..., 2].astype(int) - img[..., 0] > 60).mean()
    red = (img[..., 0].astype(int) - img[..., 2] > 60).mean()
    assert blue > 0.001 and red > 0.001  # both signs of chordal deviation are visible
