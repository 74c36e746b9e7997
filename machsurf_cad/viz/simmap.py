"""Maps of a cut simulation: what the tool path leaves on the part (mm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from .render import _bar_args, _save


def simulation_polydata(result) -> pv.PolyData:
    """Quad mesh of the nominal samples with point data ``left_mm`` (signed: + material left, - gouge,
    NaN where no placement reached), ``reached``, ``face`` and ``normal``."""
    q = np.asarray(result.quads, int)
    cells = np.concatenate([np.full((q.shape[0], 1), 4), q], axis=1).ravel()
    mesh = pv.PolyData(np.asarray(result.points, float), cells if q.size else None)
    mesh.point_data["left_mm"] = np.where(result.reached, result.value, np.nan)
    mesh.point_data["reached"] = np.asarray(result.reached, np.uint8)
    mesh.point_data["face"] = np.asarray(result.face, np.int32)
    mesh.point_data["normal"] = np.asarray(result.normals, float)
    return mesh


def render_simulation_map(result, png_path, *, vtp_path=None, title: str = "", window_size=(1200, 900)) -> Path:
    """Off-screen PNG of the material left (diverging colours centred on 0: red gouge, blue material
    left, white within the gouge tolerance), legend in mm with the tolerance band marked; grey where
    no placement reached. The .vtp holds the true values."""
    mesh = simulation_polydata(result)
    v = np.asarray(mesh.point_data["left_mm"])
    tol = float(result.tolerance_mm)
    finite = v[np.isfinite(v)]
    vmax = max(float(np.abs(finite).max()) if finite.size else 0.0, 2 * tol, 1e-9)
    p = pv.Plotter(off_screen=True, window_size=list(window_size))
    p.set_background("white")
    p.add_mesh(
        mesh,
        scalars="left_mm",
        cmap="RdBu",
        clim=[-vmax, vmax],
        nan_color="lightgrey",
        scalar_bar_args=_bar_args("material left [mm] (- gouge)", "black", 5),
        annotations={-tol: f"-tol {tol:g}", tol: f"+{tol:g}", 0.0: "0"},
        show_edges=False,
    )
    p.add_text(title, position="upper_left", font_size=11, color="black")
    p.show_axes()
    n = np.asarray(result.normals, float).mean(axis=0)
    if np.linalg.norm(n) > 1e-6:
        c = np.asarray(result.points).mean(axis=0)
        p.camera_position = [tuple(c + n / np.linalg.norm(n) * 3 * mesh.length), tuple(c), _up(n)]
    else:
        p.view_isometric()
    return _save(p, png_path, mesh, vtp_path)


def _up(n) -> tuple:
    n = n / np.linalg.norm(n)
    ref = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    up = ref - (ref @ n) * n
    return tuple(up / np.linalg.norm(up))
