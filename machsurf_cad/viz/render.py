"""Deviation maps and surface pictures (off-screen pyvista; lengths in mm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from ..measure import DeviationResult


def _quiet_vtk() -> None:
    """Keep VTK's "no X server" chatter off the terminal while we render (off-screen) - set when a picture is
    taken, not on import: importing machsurf_cad.viz changes no global state."""
    try:
        from vtkmodules.vtkCommonCore import vtkLogger

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    except Exception:  # pragma: no cover - older VTK
        pass


def plotter(**kwargs) -> pv.Plotter:
    """An off-screen plotter, VTK's logger quieted first (its "no X server" warnings are not the user's)."""
    _quiet_vtk()
    return pv.Plotter(off_screen=True, **kwargs)


def _bar_args(title: str, color: str = "black", n_labels: int = 5) -> dict:
    """The one legend layout of every map: vertical on the right, 3 significant digits."""
    return dict(
        title=title,
        color=color,
        fmt="%.3g",
        n_labels=n_labels,
        vertical=True,
        position_x=0.86,
        position_y=0.15,
        height=0.7,
        width=0.06,
    )


def _save(plotter, png_path, mesh=None, vtp_path=None) -> Path:
    """Screenshot to ``png_path`` (folders made), close the plotter, and save ``mesh`` as .vtp if asked."""
    png_path = Path(png_path)
    png_path.parent.mkdir(parents=True, exist_ok=True)
    _quiet_vtk()
    plotter.screenshot(str(png_path))
    plotter.close()
    if vtp_path is not None and mesh is not None:
        mesh.save(str(vtp_path))
    return png_path


def grid_polydata(points) -> pv.PolyData:
    """Quad mesh of a ``(nu, nv, 3)`` point grid; point order is the grid's C order."""
    pts = np.asarray(points, dtype=float)
    nu, nv = pts.shape[:2]
    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1), indexing="ij")
    a = (i * nv + j).ravel()
    quads = np.stack([np.full_like(a, 4), a, a + nv, a + nv + 1, a + 1], axis=1).ravel()
    return pv.PolyData(pts.reshape(-1, 3), quads)


def deviation_polydata(result: DeviationResult) -> pv.PolyData:
    """Mesh of the candidate with point data ``deviation_mm`` (signed, mm)."""
    pts = result.points
    if result.grid_shape is not None and result.grid_index is not None:
        # trimmed: whole grid, then drop the cells that touch a point outside the face
        mesh = grid_polydata(result.grid_points.reshape(*result.grid_shape, 3))
        full = np.full(result.grid_points.shape[0], np.nan)
        full[result.grid_index] = result.signed
        mesh.point_data["deviation_mm"] = full
        inside = np.zeros(mesh.n_points, bool)
        inside[result.grid_index] = True
        faces = mesh.faces.reshape(-1, 5)[:, 1:]
        keep_cells = inside[faces].all(axis=1)
        return mesh.extract_cells(np.nonzero(keep_cells)[0]).extract_surface(algorithm=None)
    if result.grid_shape is not None:
        mesh = grid_polydata(pts.reshape(*result.grid_shape, 3))
        mesh.point_data["deviation_mm"] = result.signed
        return mesh
    if result.triangles is not None and result.triangles.size:
        faces = np.hstack([np.full((result.triangles.shape[0], 1), 3), result.triangles]).ravel()
        mesh = pv.PolyData(pts, faces)
    else:
        mesh = pv.PolyData(pts).delaunay_2d() if pts.shape[0] >= 3 else pv.PolyData(pts)
    mesh.point_data["deviation_mm"] = result.signed
    return mesh


def render_deviation(
    result: DeviationResult,
    png_path,
    *,
    title: str = "deviation",
    vtp_path=None,
    tolerance: float | None = None,
    extra_lines=None,
    extra_points=None,
    view_direction=None,
    window_size=(1200, 900),
) -> Path:
    """Off-screen PNG of a deviation map.

    Diverging colour map centred on zero (blue below the reference normal, red above), legend
    in mm, tolerance band drawn as black iso-lines at +/- tolerance and shaded in the legend.
    Also writes the mesh with its ``deviation_mm`` data as .vtp when ``vtp_path`` is given.
    ``view_direction`` (a vector from the scene towards the camera) replaces the isometric view,
    e.g. the surface's mean normal for a face seen edge-on from the iso direction.
    """
    tol = tolerance if tolerance is not None else result.tolerance
    mesh = deviation_polydata(result)
    vmax = max(result.max_abs, tol or 0.0, 1e-12)
    p = plotter(window_size=list(window_size))
    p.set_background("white")
    sargs = _bar_args("deviation [mm]", "black", 5)
    annotations = {}
    if tol:
        annotations = {tol: f"+tol {tol:g}", -tol: f"-tol {tol:g}"}
    p.add_mesh(
        mesh,
        scalars="deviation_mm",
        cmap="coolwarm",
        clim=[-vmax, vmax],
        scalar_bar_args=sargs,
        annotations=annotations,
        smooth_shading=True,
    )
    if tol and mesh.n_points > 3:
        try:
            lines = mesh.contour([-tol, tol], scalars="deviation_mm")
            if lines.n_points:
                p.add_mesh(lines, color="black", line_width=3)
        except Exception:  # contouring is cosmetic; numbers are in the report
            pass
    if extra_lines is not None:
        for pts, color in extra_lines:
            p.add_mesh(pv.lines_from_points(np.asarray(pts)), color=color, line_width=4)
    for pts, color, label in extra_points or []:
        pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        if pts.size:
            p.add_mesh(pv.PolyData(pts), color=color, point_size=8, render_points_as_spheres=True, label=label)
    if extra_points and any(len(np.asarray(e[0])) for e in extra_points):
        p.add_legend(bcolor="white", size=(0.2, 0.08), loc="lower left")
    s = result.stats
    text = (
        f"{title}\nmax abs deviation = {s['max_abs']:.4g} mm   max = {s['max']:.4g}   min = {s['min']:.4g}\n"
        f"RMS = {s['rms']:.4g} mm   points = {s['n_points']}"
        + (f"\ntolerance = {tol:g} mm: {'MET' if s['max_abs'] <= tol else 'NOT MET'}" if tol else "")
    )
    p.add_text(text, position="upper_left", font_size=11, color="black")
    w = np.array(s["worst_xyz"])
    p.add_mesh(pv.PolyData(w[None, :]), color="magenta", point_size=14, render_points_as_spheres=True)
    p.show_axes()
    if view_direction is not None:
        d = np.asarray(view_direction, float)
        d = d / np.linalg.norm(d)
        c = np.asarray(mesh.center)
        up = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        p.camera_position = [tuple(c + d * mesh.length * 2.0), tuple(c), tuple(up)]
        p.reset_camera()
    else:
        p.view_isometric()
    return _save(p, png_path, mesh, vtp_path)


def render_scalar_map(
    points,
    values,
    png_path,
    *,
    title: str = "",
    label: str = "value [mm]",
    clim=None,
    cmap: str = "jet",
    contour_level: float | None = None,
    contour_color: str = "white",
    mask=None,
    vtp_path=None,
    extra_arrays: dict | None = None,
    annotations: dict | None = None,
    background: str = "dimgray",
    view: str = "iso",
    window_size=(1200, 900),
) -> Path:
    """Off-screen PNG of a scalar field on a ``(nu, nv, 3)`` grid (e.g. effective radius, mm).

    ``clim`` fixes the colour scale (values beyond it saturate; ``inf`` shows at the top),
    ``contour_level`` draws iso-lines (e.g. the zone boundary R_eff = R), ``mask`` hides grid
    points outside a trimmed face. All arrays are saved in the .vtp with their true values
    (``inf`` included); only the colours saturate, through a separate ``<label> (colour)`` array.
    """
    pts = np.asarray(points, dtype=float)
    mesh = grid_polydata(pts)
    vals = np.asarray(values, dtype=float).ravel()
    shown = np.where(np.isinf(vals), np.sign(vals) * 1e300, vals)
    colour = f"{label} (colour)"
    mesh.point_data[label] = vals  # the data: true values
    mesh.point_data[colour] = shown if clim is None else np.clip(shown, clim[0], clim[1])
    for k, v in (extra_arrays or {}).items():
        mesh.point_data[k] = np.asarray(v, dtype=float).ravel()
    if mask is not None:
        m = np.asarray(mask, bool).ravel()
        faces = mesh.faces.reshape(-1, 5)[:, 1:]
        mesh = mesh.extract_cells(np.nonzero(m[faces].all(axis=1))[0]).extract_surface(algorithm=None)
    p = plotter(window_size=list(window_size))
    p.set_background(background)
    sargs = _bar_args(label, "white", 6)
    p.add_mesh(
        mesh, scalars=colour, cmap=cmap, clim=clim, scalar_bar_args=sargs, annotations=annotations or {}, lighting=False
    )  # a map: colours must read true against the legend
    if contour_level is not None and mesh.n_points > 3:
        lines = mesh.contour([contour_level], scalars=colour)
        if lines.n_points:
            p.add_mesh(lines, color=contour_color, line_width=3)
    if title:
        p.add_text(title, position="upper_left", font_size=11, color="white")
    p.show_axes()
    if view == "xy":
        p.view_xy()  # along the 3-axis tool axis
    else:
        p.view_isometric()
    return _save(p, png_path, mesh, vtp_path)


def zebra_values(normals, *, light=(0.3, 0.2, 1.0), stripes: int = 24) -> np.ndarray:
    """Reflection-line (zebra) value in [0, 1] per normal: stripes of the angle to a light direction."""
    L = np.asarray(light, float)
    L = L / np.linalg.norm(L)
    ang = np.arccos(np.clip(np.abs(np.asarray(normals) @ L), -1, 1))
    return 0.5 * (1 + np.sign(np.sin(stripes * ang)))


def render_zebra(
    panels, png_path, *, window_size=(1600, 800), stripes: float | None = None, light=(0.3, 0.2, 1.0)
) -> Path:
    """Side-by-side zebra renderings. ``panels`` is a list of ``(title, [(points (nu,nv,3), normals), ...])``:
    continuous stripes across a seam show G1, kinked stripes show a G0 crease. By default the stripe
    density is set so that about 12 stripes cover the range of normal directions."""
    n = len(panels)
    if stripes is None:
        L = np.asarray(light, float) / np.linalg.norm(light)
        angs = np.concatenate(
            [
                np.arccos(np.clip(np.abs(np.asarray(nrm).reshape(-1, 3) @ L), -1, 1))
                for _, surfs in panels
                for _, nrm in surfs
            ]
        )
        stripes = 12 * np.pi / max(float(np.ptp(angs)), 1e-6)
    p = plotter(window_size=list(window_size), shape=(1, n))
    for k, (title, surfaces) in enumerate(panels):
        p.subplot(0, k)
        p.set_background("lightsteelblue")
        for pts, nrm in surfaces:
            mesh = grid_polydata(pts)
            mesh.point_data["zebra"] = zebra_values(np.asarray(nrm).reshape(-1, 3), light=light, stripes=stripes)
            p.add_mesh(mesh, scalars="zebra", cmap="gray", clim=[0, 1], show_scalar_bar=False, lighting=False)
        p.add_text(title, position="upper_left", font_size=12, color="black")
        p.view_isometric()
    return _save(p, png_path)


def render_gouge_map(
    points, depth, png_path, *, tolerance: float, title: str = "", vtp_path=None, worst=None, window_size=(1200, 900)
) -> Path:
    """Off-screen PNG of the part's samples coloured by how deep the tool went into them (mm): white
    where it never did, yellow to red up to the deepest, the tolerance marked on the legend. The
    .vtp holds the true depths (``gouge_depth_mm``); ``worst`` points are drawn in magenta."""
    pts = np.asarray(points, float)
    d = np.maximum(np.asarray(depth, float), 0.0)
    cloud = pv.PolyData(pts)
    cloud.point_data["gouge_depth_mm"] = d
    vmax = max(float(d.max()), 2 * tolerance, 1e-9)
    p = plotter(window_size=list(window_size))
    p.set_background("white")
    sargs = _bar_args("tool depth into the part [mm]", "black", 5)
    p.add_mesh(
        cloud,
        scalars="gouge_depth_mm",
        cmap="YlOrRd",
        clim=[0.0, vmax],
        point_size=3,
        render_points_as_spheres=False,
        scalar_bar_args=sargs,
        annotations={tolerance: f"tol {tolerance:g}"},
    )
    if worst is not None and len(worst):
        p.add_mesh(
            pv.PolyData(np.asarray(worst, float).reshape(-1, 3)),
            color="magenta",
            point_size=12,
            render_points_as_spheres=True,
        )
    p.add_text(title, position="upper_left", font_size=11, color="black")
    p.show_axes()
    p.view_isometric()
    return _save(p, png_path, cloud, vtp_path)
