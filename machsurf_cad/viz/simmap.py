"""Maps of a cut simulation: what the tool path leaves on the part (mm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from .render import _bar_args, _save, plotter

REGION_MACHINED, REGION_BORDER, REGION_NOT_REACHED, REGION_NOT_MEASURED = 1, 0, -1, -2
"""Values of the map's ``region`` point data."""


def simulation_polydata(result) -> pv.PolyData:
    """Quad mesh of the nominal samples with point data ``left_mm`` (signed: + material left, - gouge,
    NaN where no placement reached or not measured), ``region`` (1 machined region, 0 border, -1 not reached,
    -2 not measured), ``reached``, ``face`` and ``normal``."""
    q = np.asarray(result.quads, int)
    cells = np.concatenate([np.full((q.shape[0], 1), 4), q], axis=1).ravel()
    mesh = pv.PolyData(np.asarray(result.points, float), cells if q.size else None)
    known = np.asarray(result.reached & result.measured, bool)
    region = np.where(result.machined, REGION_MACHINED, REGION_BORDER)
    region = np.where(result.reached, region, REGION_NOT_REACHED)
    region = np.where(result.measured, region, REGION_NOT_MEASURED)
    mesh.point_data["left_mm"] = np.where(known, result.value, np.nan)
    mesh.point_data["region"] = region.astype(np.int8)
    mesh.point_data["reached"] = np.asarray(result.reached, np.uint8)
    mesh.point_data["face"] = np.asarray(result.face, np.int32)
    mesh.point_data["normal"] = np.asarray(result.normals, float)
    return mesh


def render_simulation_map(result, png_path, *, vtp_path=None, title: str = "", window_size=(1200, 900)) -> Path:
    """Off-screen PNG of the material left: the machined region in diverging colours centred on 0 (red gouge,
    blue material left, white within the gouge tolerance; legend in mm, the tolerance band marked) scaled to
    the region's own values; the border around the passes in its own colours (purples, its own legend on
    the left: it does not stretch the region's scale); light grey where no placement reached, magenta where
    not measured. Seen along the mean normal of the reached samples. The .vtp holds the true values and the
    ``region`` of every sample."""
    mesh = simulation_polydata(result)
    v = np.asarray(mesh.point_data["left_mm"])
    reg = np.asarray(mesh.point_data["region"])
    tol = float(result.tolerance_mm)
    inside = v[np.isfinite(v) & (reg == REGION_MACHINED)]
    gouge = v[np.isfinite(v) & (v < 0)]
    vmax = max(float(np.abs(inside).max()) if inside.size else 0.0, float(-gouge.min()) if gouge.size else 0.0)
    vmax = max(vmax, 2 * tol, 1e-9)
    p = plotter(window_size=list(window_size))
    p.set_background("white")
    main = mesh.copy()
    main.point_data["left_mm"] = np.where(reg == REGION_BORDER, np.nan, v)
    p.add_mesh(
        main,
        scalars="left_mm",
        cmap="RdBu",
        clim=[-vmax, vmax],
        nan_color="lightgrey",
        scalar_bar_args=_bar_args("machined [mm] (- gouge)", "black", 5),
        annotations={-tol: f"-tol {tol:g}", tol: f"+{tol:g}", 0.0: "0"},
        show_edges=False,
    )
    border = mesh.extract_points(reg == REGION_BORDER, adjacent_cells=False)
    if border.n_points:
        b = np.asarray(border.point_data["left_mm"])
        top = float(np.nanmax(b)) if np.isfinite(b).any() else 1.0
        bar = {**_bar_args("border [mm]", "black", 5), "position_x": 0.04}
        p.add_mesh(border, scalars="left_mm", cmap="Purples", clim=[0.0, max(top, 1e-9)], scalar_bar_args=bar)
    lost = mesh.extract_points(reg == REGION_NOT_MEASURED, adjacent_cells=False)
    if lost.n_points:
        p.add_mesh(lost, color="magenta", point_size=6, style="points")
    p.add_text(title, position="upper_left", font_size=11, color="black")
    p.show_axes()
    seen = np.asarray(result.reached, bool) if np.any(result.reached) else np.ones(len(reg), bool)
    n = np.asarray(result.normals, float)[seen].mean(axis=0)  # looking at what the path reached
    if np.linalg.norm(n) > 1e-6:
        c = np.asarray(result.points)[seen].mean(axis=0)
        p.camera_position = [tuple(c + n / np.linalg.norm(n) * 3 * mesh.length), tuple(c), _up(n)]
    else:
        p.view_isometric()
    return _save(p, png_path, mesh, vtp_path)


def _up(n) -> tuple:
    n = n / np.linalg.norm(n)
    ref = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    up = ref - (ref @ n) * n
    return tuple(up / np.linalg.norm(up))
