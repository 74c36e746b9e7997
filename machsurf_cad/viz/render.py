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


MAX_DECIMALS = 5
"""Legend labels in fixed point up to this many decimals; finer (or from 1e5 up) every label in exponent form."""


def tick_format(values) -> str:
    """The one printf format of every label of a legend (tick or annotation).

    Parameters
    ----------
    values : array_like
        The values the legend labels (its ticks, e.g. ``np.linspace(lo, hi, n_labels)``).

    Returns
    -------
    str
        ``"%.<d>f"`` with the fewest decimals ``d`` (at most :data:`MAX_DECIMALS`) that give every value
        to 1 % of the smallest gap between them; ``"%.2e"`` for all of them when that needs more decimals
        or a value reaches 1e5. One style per legend: 0.001 and 5e-4 read ``0.0010`` and ``0.0005``, never
        ``0.001`` beside ``5.00e-04``.
    """
    v = np.unique(np.asarray(values, dtype=float).ravel())
    if v.size == 0 or not np.all(np.isfinite(v)) or np.abs(v).max() >= 1e5:
        return "%.2e"
    gap = float(np.diff(v).min()) if v.size > 1 else float(np.abs(v).max())
    if gap == 0.0:
        return "%.0f"
    for d in range(MAX_DECIMALS + 1):
        if np.all(np.abs(np.round(v, d) - v) <= 0.01 * gap):
            return f"%.{d}f"
    return "%.2e"


def _bar_args(title: str, color: str, n_labels: int, clim) -> dict:
    """The one legend layout of every map: vertical on the right, labels in :func:`tick_format`'s format
    for the ``n_labels`` ticks over ``clim`` (``(lo, hi)``)."""
    return dict(
        title=title,
        color=color,
        fmt=tick_format(np.linspace(float(clim[0]), float(clim[1]), max(n_labels, 2))),
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
    if result.grid_shape is not None and result.grid_index is not None and result.grid_points is not None:
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
    sargs = _bar_args("deviation [mm]", "black", 5, (-vmax, vmax))
    annotations = {}
    if tol:
        annotations = {tol: f"+tol {sargs['fmt'] % tol}", -tol: f"-tol {sargs['fmt'] % tol}"}
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


LEGEND_LEFT = 0.79
"""Left edge of a categorical map's legend box (fraction of the window's width)."""

MAX_AUTO_CATEGORIES = 10
"""A field with 2 to this many distinct values is drawn as categories (one colour and legend entry each)."""


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
    categories="auto",
    window_size=(1200, 900),
) -> Path:
    """Off-screen PNG of a scalar field on a ``(nu, nv, 3)`` grid (e.g. effective radius, mm).

    Parameters
    ----------
    points : array_like, shape (nu, nv, 3)
        The grid, mm.
    values : array_like, shape (nu, nv)
        The field; ``inf`` shows at the top of the scale, NaN in the background's grey.
    png_path : path
        The picture.
    title, label : str
        Text at the top left; the legend's title, ``"name [unit]"``.
    clim : (float, float), optional
        Fixes the colour scale (values beyond it saturate); default the values' range.
    cmap : str
        Colour map of a continuous field.
    contour_level : float, optional
        Draws iso-lines there (e.g. the zone boundary R_eff = R) in ``contour_color``.
    mask : array_like of bool, shape (nu, nv), optional
        Hides the cells with a corner outside a trimmed face.
    vtp_path : path, optional
        Saves the mesh: every array with its true values (``inf`` included); only the colours saturate,
        through a separate ``<label> (colour)`` array.
    extra_arrays, annotations : dict, optional
        More point data for the .vtp; legend marks ``{value: text}``.
    background, view : str
        Background colour; ``"xy"`` looks along -z (the 3-axis tool axis), else isometric.
    categories : "auto", sequence of float or None
        A field of discrete values (e.g. the best of a few machining directions) drawn with one colour and
        one legend entry per value, with its share of the samples: the given values, or with ``"auto"`` the
        field's own when it takes 2 to :data:`MAX_AUTO_CATEGORIES` distinct values; ``None``: always a
        continuous scale. A categorical map has no ``cmap``, ``clim``, ``annotations`` or iso-lines.
    window_size : (int, int)
        Pixels.

    Returns
    -------
    Path
        ``png_path``.
    """
    vals = np.asarray(values, dtype=float).ravel()
    inside = np.ones(vals.size, bool) if mask is None else np.asarray(mask, bool).ravel()
    cats = _categories(vals[inside], categories)
    mesh = _scalar_mesh(points, vals, label, clim, extra_arrays, cats)
    if mask is not None:
        faces = mesh.faces.reshape(-1, 5)[:, 1:]
        mesh = mesh.extract_cells(np.nonzero(inside[faces].all(axis=1))[0]).extract_surface(algorithm=None)
    p = plotter(window_size=list(window_size))
    p.set_background(background)
    if cats is not None:
        _add_categories(p, mesh, cats, label, vals[inside])
    else:
        _add_continuous(p, mesh, label, clim, cmap, annotations, contour_level, contour_color)
    if title:
        p.add_text(title, position="upper_left", font_size=11, color="white")
    p.show_axes()
    if view == "xy":
        p.view_xy()  # along the 3-axis tool axis
    else:
        p.view_isometric()
    if cats is not None:
        _leave_room(p, 1.0 - LEGEND_LEFT + 0.01)
    return _save(p, png_path, mesh, vtp_path)


def _add_continuous(p, mesh, label, clim, cmap, annotations, contour_level, contour_color) -> None:
    """Draw ``mesh`` by its ``<label> (colour)`` values, unlit, with the legend on the right (6 labels over
    ``clim``, by default the values' range) and the iso-lines at ``contour_level``."""
    colour = f"{label} (colour)"
    shown = np.asarray(mesh.point_data[colour])
    finite = shown[np.isfinite(shown)]
    if clim is None:
        clim = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    p.add_mesh(
        mesh,
        scalars=colour,
        cmap=cmap,
        clim=clim,
        scalar_bar_args=_bar_args(label, "white", 6, clim),
        annotations=annotations or {},
        lighting=False,
    )  # a map: colours must read true against the legend
    if contour_level is not None and mesh.n_points > 3:
        lines = mesh.contour([contour_level], scalars=colour)
        if lines.n_points:
            p.add_mesh(lines, color=contour_color, line_width=3)


def _categories(vals: np.ndarray, categories) -> np.ndarray | None:
    """The legend entries of a categorical map (sorted values), or ``None`` for a continuous scale."""
    if categories is None:
        return None
    if isinstance(categories, str):
        if categories != "auto":
            raise ValueError(f"categories must be 'auto', a sequence of values or None, not {categories!r}")
        u = np.unique(vals[np.isfinite(vals)])
        return u if 2 <= u.size <= MAX_AUTO_CATEGORIES else None
    return np.unique(np.asarray(categories, dtype=float))


def _scalar_mesh(points, vals, label, clim, extra_arrays, cats) -> pv.PolyData:
    """The grid's mesh with the true values (``label``), the saturated colour values (``<label> (colour)``),
    the extra arrays and, for categories, the cell data ``<label> (category)``: the index of the value most of
    the cell's corners take (NaN where none takes one), so each cell has one of the legend's colours."""
    mesh = grid_polydata(np.asarray(points, dtype=float))
    shown = np.where(np.isinf(vals), np.sign(vals) * 1e300, vals)
    mesh.point_data[label] = vals  # the data: true values
    mesh.point_data[f"{label} (colour)"] = shown if clim is None else np.clip(shown, clim[0], clim[1])
    for k, v in (extra_arrays or {}).items():
        mesh.point_data[k] = np.asarray(v, dtype=float).ravel()
    if cats is not None:
        corner = _category_index(vals, cats)[mesh.faces.reshape(-1, 5)[:, 1:]]
        counts = np.stack([(corner == k).sum(axis=1) for k in range(cats.size)], axis=1)
        mesh.cell_data[f"{label} (category)"] = np.where(counts.max(axis=1) > 0, counts.argmax(axis=1), np.nan)
    return mesh


def _category_index(vals: np.ndarray, cats: np.ndarray) -> np.ndarray:
    """Index into ``cats`` of every value (-1 where it is none of them)."""
    idx = np.full(vals.size, -1)
    for k, c in enumerate(cats):
        idx[np.isclose(vals, c, rtol=1e-9, atol=1e-12)] = k
    return idx


def category_colors(n: int) -> list[str]:
    """``n`` distinct colours (hex) for a categorical map: matplotlib's tab10, then tab20."""
    from matplotlib import colormaps, colors

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return [colors.to_hex(cmap(k % cmap.N)) for k in range(n)]


def _add_categories(p, mesh, cats: np.ndarray, label: str, vals: np.ndarray) -> None:
    """Draw ``mesh`` by its ``<label> (category)`` cells, one colour each, and a legend with one entry per
    category: ``name = value unit (share of the samples)``."""
    colors = category_colors(cats.size)
    p.add_mesh(
        mesh,
        scalars=f"{label} (category)",
        preference="cell",
        cmap=colors,
        n_colors=cats.size,
        clim=[-0.5, cats.size - 0.5],
        show_scalar_bar=False,
        lighting=False,
    )
    name, _, unit = label.partition("[")
    unit = unit.rstrip("]").strip()
    idx = _category_index(vals, cats)
    known = max(int(np.count_nonzero(np.isfinite(vals))), 1)
    entries = []
    for k, c in enumerate(cats):
        share = 100.0 * np.count_nonzero(idx == k) / known
        pct = f"{share:.0f} %" if share >= 0.5 or share == 0 else "< 1 %"
        entries.append([f"{name.strip()} = {c:g} {unit} ({pct})".replace("  ", " "), colors[k]])
    height = min(0.06 * cats.size + 0.02, 0.9)
    box = p.add_legend(entries, bcolor="white", face="rectangle", loc="center right", size=(0.2, height))
    box.SetPosition(LEGEND_LEFT, 0.5 - height / 2)  # right of the scene, which _leave_room moves left
    box.SetPosition2(0.99 - LEGEND_LEFT, height)


def _leave_room(p, right: float) -> None:
    """Zoom the camera out and move the scene left so that it keeps off the right ``right`` fraction of the
    window, where a legend box goes (call after the view is set)."""
    cam = p.camera
    cam.zoom(1.0 - right)
    w, h = p.window_size
    d = np.asarray(cam.focal_point) - np.asarray(cam.position)
    height = 2.0 * np.linalg.norm(d) * np.tan(np.radians(cam.view_angle) / 2)
    side = np.cross(d / np.linalg.norm(d), np.asarray(cam.up))
    shift = side / np.linalg.norm(side) * (right / 2) * height * w / h
    cam.position = tuple(np.asarray(cam.position) + shift)
    cam.focal_point = tuple(np.asarray(cam.focal_point) + shift)


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


GOUGE_DECADES = 2
"""The gouge map's log scale starts this many decades below the tolerance."""


def render_gouge_map(
    points, depth, png_path, *, tolerance: float, title: str = "", vtp_path=None, worst=None, window_size=(1200, 900)
) -> Path:
    """Off-screen PNG of the part's samples coloured by how deep the tool went into them.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        The part's samples, mm.
    depth : array_like, shape (n,)
        The deepest the tool went into each sample, mm (0 or less: never inside).
    png_path : path
        The picture.
    tolerance : float
        The gouge tolerance, mm: marked on the legend, the colours turn red beyond it.
    title : str
        First line of the text; two lines follow: what the colours mean and how many samples the tool entered.
    vtp_path : path, optional
        Saves the samples with their true depths (``gouge_depth_mm``).
    worst : array_like, shape (k, 3), optional
        Points drawn in magenta (the worst gouges or collisions).
    window_size : (int, int)
        Pixels.

    Returns
    -------
    Path
        ``png_path``.

    Notes
    -----
    Samples the tool never entered are small grey points (the part's shape); the entered ones are larger,
    on a log scale from :data:`GOUGE_DECADES` decades below the tolerance (shallower ones in its first
    colour) to the deepest or twice the tolerance: viridis within the tolerance, reds beyond. A clean path
    enters samples by hundredths of the tolerance, a linear scale up to the tolerance would draw them all
    in one pale colour. Seen isometrically from the side of the entered samples.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    d = np.maximum(np.asarray(depth, dtype=float).ravel(), 0.0)
    cloud = pv.PolyData(pts)
    cloud.point_data["gouge_depth_mm"] = d
    entered = d > 0
    p = plotter(window_size=list(window_size))
    p.set_background("white")
    if np.any(~entered):
        p.add_mesh(pv.PolyData(pts[~entered]), color="silver", point_size=2, lighting=False)
    fmt = "%g"
    if entered.any():
        fmt = _add_depths(p, pts[entered], d[entered], tolerance)
    if worst is not None and len(worst):
        w = pv.PolyData(np.asarray(worst, dtype=float).reshape(-1, 3))
        p.add_mesh(w, color="magenta", point_size=12, render_points_as_spheres=True)
    n_in = int(np.count_nonzero(entered))
    text = (
        f"{title}\ncolour: how deep the tool went into each sample of the part, mm (log scale; red: deeper than "
        f"the tolerance {fmt % tolerance}); grey: samples it never entered\n{n_in:,} of {d.size:,} samples "
        f"entered, deepest {d.max(initial=0.0):.3g} mm"
    )
    p.add_text(text.lstrip("\n"), position="upper_left", font_size=10, color="black")
    p.show_axes()
    _view_toward(p, pts, pts[entered] if n_in else pts)
    return _save(p, png_path, cloud, vtp_path)


def _add_depths(p, pts: np.ndarray, d: np.ndarray, tolerance: float) -> str:
    """The entered samples on the gouge map's log scale, its legend labelled at the decades, the tolerance
    and the top; returns the legend's format."""
    lo, hi = tolerance / 10.0**GOUGE_DECADES, max(float(d.max()), 2.0 * tolerance)
    a, b = np.log10(lo), np.log10(hi)
    decades = 10.0 ** np.arange(np.ceil(a - 1e-9), np.floor(b + 1e-9) + 1)
    fmt = tick_format(np.r_[decades, tolerance, hi])
    top = [] if np.log10(hi) - np.log10(decades[-1]) < 0.15 else [hi]  # not on top of the last decade's label
    marks = {float(np.log10(v)): fmt % v for v in np.r_[decades, top]}
    marks[float(np.log10(tolerance))] = f"tol {fmt % tolerance}"
    sub = pv.PolyData(pts)
    sub.point_data["log10 depth"] = np.log10(np.clip(d, lo, hi))
    bar = {**_bar_args("depth in the part [mm]", "black", 2, (lo, hi)), "n_labels": 0, "fmt": fmt}
    p.add_mesh(
        sub,
        scalars="log10 depth",
        cmap=_tolerance_cmap((np.log10(tolerance) - a) / (b - a)),
        clim=[a, b],
        point_size=6,
        lighting=False,
        scalar_bar_args=bar,
        annotations=marks,
    )
    return fmt


def _tolerance_cmap(frac: float):
    """Viridis below ``frac`` of the scale (within the tolerance), reds above it."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    n = 256
    k = int(np.clip(round(frac * n), 1, n - 1))
    below = colormaps["viridis"](np.linspace(0.0, 0.9, k))
    above = colormaps["Reds"](np.linspace(0.55, 1.0, n - k))
    return ListedColormap(np.vstack([below, above]))


def _view_toward(p, pts: np.ndarray, target: np.ndarray) -> None:
    """An isometric view of ``pts`` from the octant where ``target`` lies (+x +y +z when it is central)."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, ext = (lo + hi) / 2, hi - lo
    off = target.mean(axis=0) - centre
    sign = np.where(np.abs(off) > 0.1 * ext, np.sign(off), 1.0)
    direction = sign / np.sqrt(3.0)
    size = max(float(np.linalg.norm(ext)), 1e-9)
    p.camera_position = [tuple(centre + 3 * size * direction), tuple(centre), (0.0, 0.0, 1.0)]
    p.reset_camera()
