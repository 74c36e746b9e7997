"""Maps of a cut simulation: what the tool path leaves on the part (mm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from ..cam.toolpath import Move
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
    """Off-screen PNG of the material a cut simulation leaves on the part.

    Parameters
    ----------
    result : SimulationResult
        The simulation (its samples, values, regions and tool path).
    png_path : path
        The picture.
    vtp_path : path, optional
        Saves the mesh of :func:`simulation_polydata`: the true values and the ``region`` of every sample.
    title : str
        Text at the top left.
    window_size : (int, int)
        Pixels.

    Returns
    -------
    Path
        ``png_path``.

    Notes
    -----
    The machined region in diverging colours centred on 0 (red gouge, blue material left, white within the
    gouge tolerance; legend in mm, the tolerance band marked) scaled to the region's own values; the border
    around the passes in its own colours (purples, its own legend on the left: it does not stretch the
    region's scale); light grey where no placement reached, magenta where not measured. The coloured samples
    are unlit (their colours read true against the legends), the unreached part is shaded for its shape. The
    camera is :func:`simulation_view`'s: on the machined side, framing what the path reached.
    """
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
    rest = mesh.extract_points(reg == REGION_NOT_REACHED, adjacent_cells=False)
    if rest.n_cells:
        p.add_mesh(rest, color=NOT_REACHED_COLOR, ambient=0.4, diffuse=0.6)
    main = mesh.extract_points(reg >= REGION_BORDER, adjacent_cells=True)
    if main.n_points:
        main.point_data["left_mm"] = np.where(main.point_data["region"] == REGION_BORDER, np.nan, main["left_mm"])
        bar = _bar_args("machined [mm] (- gouge)", "black", 5, (-vmax, vmax))
        mark = bar["fmt"] % tol
        p.add_mesh(
            main,
            scalars="left_mm",
            cmap="RdBu",
            clim=[-vmax, vmax],
            nan_color=NOT_REACHED_COLOR,
            scalar_bar_args=bar,
            annotations={-tol: f"-tol {mark}", tol: f"+tol {mark}"},
            lighting=False,
        )
    _add_border(p, mesh, reg)
    lost = mesh.extract_points(reg == REGION_NOT_MEASURED, adjacent_cells=False)
    if lost.n_points:
        p.add_mesh(lost, color="magenta", point_size=6, style="points")
    p.add_text(title, position="upper_left", font_size=11, color="black")
    p.show_axes()
    position, focal, up, scale = simulation_view(result, window_size[0] / window_size[1])
    p.enable_parallel_projection()
    p.camera_position = [position, focal, up]
    p.reset_camera_clipping_range()
    p.camera.parallel_scale = scale
    return _save(p, png_path, mesh, vtp_path)


NOT_REACHED_COLOR = "lightgrey"
"""Colour of the samples no placement reached (shaded)."""


def _add_border(p, mesh, reg: np.ndarray) -> None:
    """The border around the passes in purples, with its own legend on the left (0 to its largest value)."""
    border = mesh.extract_points(reg == REGION_BORDER, adjacent_cells=False)
    if not border.n_points:
        return
    b = np.asarray(border.point_data["left_mm"])
    top = max(float(np.nanmax(b)) if np.isfinite(b).any() else 1.0, 1e-9)
    bar = {**_bar_args("border [mm]", "black", 5, (0.0, top)), "position_x": 0.04, "position_y": 0.22, "height": 0.63}
    p.add_mesh(border, scalars="left_mm", cmap="Purples", clim=[0.0, top], scalar_bar_args=bar, lighting=False)


SCENE_WIDTH, SCENE_CENTRE = 0.56, 0.45
"""Fraction of the window's width the simulation map's reached samples may take, and where their middle is
(the border's legend is on the left, the machined region's on the right with its tolerance marks)."""


def simulation_view(result, aspect: float = 4 / 3) -> tuple:
    """The simulation map's camera: on the machined side of the part, framing what the path reached.

    Parameters
    ----------
    result : SimulationResult
        The simulation.
    aspect : float
        The window's width / height.

    Returns
    -------
    tuple
        ``(position, focal_point, view_up, parallel_scale)`` of a parallel projection. The camera looks along
        the mean outward normal of the machined region's samples (the reached samples when none is machined,
        all of them when none is reached), turned to the side the tool's axis points to (the side the tool
        comes from) when the two disagree, or along that axis when the normals cancel out. It frames the
        reached samples in :data:`SCENE_WIDTH` of the window's width (around :data:`SCENE_CENTRE`) and 80 % of
        its height.
    """
    pts = np.asarray(result.points, float)
    nrm = np.asarray(result.normals, float)
    reached = np.asarray(result.reached, bool)
    machined = reached & np.asarray(result.machined if result.machined is not None else reached, bool)
    sel = next((m for m in (machined, reached) if m.any()), np.ones(len(pts), bool))
    n = nrm[sel].mean(axis=0)
    axis = _mean_axis(result)
    if np.linalg.norm(n) < 1e-6:
        n = axis if axis is not None else np.array([0.0, 0.0, 1.0])
    elif axis is not None and float(n @ axis) < 0:
        n = -n  # normals pointing into the material: the tool comes from the other side
    n = n / np.linalg.norm(n)
    up = np.asarray(_up(n))
    framed = pts[reached] if reached.any() else pts
    right = np.cross(-n, up)  # the screen's x when looking along -n
    x, y = framed @ right, framed @ up
    c = framed.mean(axis=0)
    c = c + right * ((x.max() + x.min()) / 2 - c @ right) + up * ((y.max() + y.min()) / 2 - c @ up)
    scale = max(np.ptp(x) / (2 * SCENE_WIDTH * aspect), np.ptp(y) / (2 * 0.8), 1e-6)
    c = c + right * (0.5 - SCENE_CENTRE) * 2 * scale * aspect  # the scene's middle at SCENE_CENTRE
    size = max(float(np.linalg.norm(np.ptp(pts, axis=0))), 1e-9)
    return tuple(c + 3 * size * n), tuple(c), tuple(up), float(scale)


def _mean_axis(result) -> np.ndarray | None:
    """Unit mean tool axis over the cutting moves of ``result.toolpath`` (all moves when none cuts), or None."""
    tp = getattr(result, "toolpath", None)
    if tp is None or getattr(tp, "axis", None) is None:
        return None
    a = np.asarray(tp.axis, float).reshape(-1, 3)
    cut = np.asarray(tp.move) == int(Move.CUT) if getattr(tp, "move", None) is not None else np.ones(len(a), bool)
    m = a[cut].mean(axis=0) if cut.any() else a.mean(axis=0)
    return m / np.linalg.norm(m) if np.linalg.norm(m) > 1e-6 else None


def _up(n) -> tuple:
    """A view-up vector square to the direction ``n``: +z, or +y when ``n`` is nearly vertical."""
    n = n / np.linalg.norm(n)
    ref = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    up = ref - (ref @ n) * n
    return tuple(up / np.linalg.norm(up))
