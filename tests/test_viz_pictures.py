"""The pictures as a user reads them (issue 26, item 9): facts about the drawn pixels, the camera and the
legends, on synthetic inputs (no kernel, a second or two per picture)."""

import re
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import needs_pyvista

pytestmark = needs_pyvista

WHITE = np.array([255, 255, 255])


def _image(path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def _near(img: np.ndarray, rgb, tol: int = 12) -> np.ndarray:
    return np.abs(img - np.asarray(rgb)).max(axis=-1) <= tol


def _grid(x0, x1, y0, y1, z, n, m):
    """A flat ``n x m`` grid at height ``z``: its points (C order) and quads."""
    X, Y = np.meshgrid(np.linspace(x0, x1, n), np.linspace(y0, y1, m), indexing="ij")
    pts = np.stack([X, Y, np.full_like(X, z)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(m - 1), indexing="ij")
    a = (i * m + j).ravel()
    return pts, np.stack([a, a + m, a + m + 1, a + 1], axis=1)


def _slab(flip_normals: bool = False):
    """A simulation of a 60 x 45 mm slab machined on its top (z = 0, a 4 mm scallop pattern up to 0.03 mm,
    a border ring up to 0.2 mm) and never reached on its bottom (z = -30, sampled 4 times as densely: the
    mean normal of all samples points down, away from the tool). The tool axis is +z."""
    top, qt = _grid(0, 60, 0, 45, 0.0, 61, 46)
    bot, qb = _grid(0, 60, 0, 45, -30.0, 121, 91)
    pts = np.concatenate([top, bot])
    nrm = np.concatenate([np.tile([0.0, 0, 1], (len(top), 1)), np.tile([0.0, 0, -1], (len(bot), 1))])
    reached = np.r_[np.ones(len(top), bool), np.zeros(len(bot), bool)]
    inner = (top[:, 0] > 5) & (top[:, 0] < 55) & (top[:, 1] > 5) & (top[:, 1] < 40)
    machined = np.r_[inner, np.zeros(len(bot), bool)]
    scallop = 0.015 * (1 - np.cos(2 * np.pi * top[:, 0] / 4.0))
    value = np.r_[np.where(inner, scallop, 0.1 + 0.1 * top[:, 1] / 45), np.full(len(bot), np.nan)]
    n_pos = 20
    path = SimpleNamespace(axis=np.tile([0.0, 0, 1], (n_pos, 1)), move=np.full(n_pos, 2))
    return SimpleNamespace(
        points=pts,
        normals=-nrm if flip_normals else nrm,
        quads=np.concatenate([qt, qb + len(top)]),
        reached=reached,
        measured=np.ones(len(pts), bool),
        machined=machined,
        value=value,
        face=np.r_[np.zeros(len(top), int), np.ones(len(bot), int)],
        tolerance_mm=0.01,
        toolpath=path,
    )


@pytest.mark.parametrize("flip", [False, True])
def test_simulation_map_looks_at_the_machined_side(flip):
    """The camera is on the side the machined samples face (their outward normal, or the tool's axis when the
    normals point into the material); the mean normal of all the samples points the other way here."""
    from machsurf_cad.viz.simmap import simulation_view

    res = _slab(flip_normals=flip)
    position, focal, _, scale = simulation_view(res)
    to_camera = np.asarray(position) - np.asarray(focal)
    outward = np.array([0.0, 0.0, 1.0])  # the machined top's outward normal, whatever the data say
    assert to_camera @ outward > 0.99 * np.linalg.norm(to_camera)
    assert (-1 if flip else 1) * res.normals.mean(axis=0) @ outward < 0  # "all samples" would look from below
    assert 60 / (2 * 4 / 3) < scale < 60  # the top's 60 mm fill about half the width


@pytest.mark.parametrize("flip", [False, True])
def test_simulation_map_pixels_show_the_machined_region_not_the_unreached_side(tmp_path, flip):
    """From above, most of the slab's picture is the machined region's blues; the unreached bottom's grey is
    hidden (from below it is the whole picture), even when the samples' normals point into the material."""
    from machsurf_cad.viz import render_simulation_map
    from machsurf_cad.viz.simmap import SCENE_CENTRE, SCENE_WIDTH

    res = _slab(flip_normals=flip)
    img = _image(render_simulation_map(res, tmp_path / "map.png", title="slab", window_size=(800, 600)))
    h, w, _ = img.shape
    x0, x1 = int(w * (SCENE_CENTRE - SCENE_WIDTH / 2)), int(w * (SCENE_CENTRE + SCENE_WIDTH / 2))
    scene = img[int(0.1 * h) : int(0.9 * h), x0:x1]
    drawn = ~_near(scene, WHITE, 6)
    grey = drawn & (np.ptp(scene, axis=-1) <= 8)
    blue = drawn & (scene[..., 2] - scene[..., 0] > 30)
    assert drawn.mean() > 0.5  # the slab fills the scene (the camera frames what the path reached)
    assert grey.sum() < 0.15 * drawn.sum()
    assert blue.sum() > 0.5 * drawn.sum()


def _cut_distances():
    """20 passes of 30 cutting positions 0 to 3 um off the part, each after a rapid (inf), an approach
    (0.05 mm) and a retract (5 mm); tolerance 0.01 mm."""
    rng = np.random.default_rng(3)
    d, move = [], []
    for _ in range(20):
        d += [np.inf, 0.05, *list(-0.003 * rng.random(30)), 5.0]
        move += [0, 1, *[2] * 30, 3]
    return np.array(d), np.array(move)


@pytest.mark.parametrize("with_moves", [True, False])
def test_path_distance_legend_is_off_the_path_and_the_scale_is_the_cutting_moves(tmp_path, with_moves):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from machsurf_cad.viz.plots import _path_distance_figure, plot_path_distance

    d, move = _cut_distances()
    status = np.zeros(d.size, int)
    fig = _path_distance_figure(d, status, tolerance=0.01, move=move if with_moves else None)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    cutting = next(ln for ln in ax.get_lines() if ln.get_color() == "tab:blue")
    assert not legend.overlaps(ax.get_window_extent(renderer))
    assert not legend.overlaps(cutting.get_window_extent(renderer))
    lo, hi = ax.get_ylim()
    assert lo < -0.01 and hi < 0.02  # the tolerance in view, the 5 mm retracts not on the scale
    assert (d[move == 2].max() - d[move == 2].min()) / (hi - lo) > 0.1  # the clearance is readable
    png = plot_path_distance(d, status, tmp_path / "p.png", tolerance=0.01, move=move if with_moves else None)
    assert _image(png).shape[1] > 1000


def test_gouge_map_colours_vary_and_red_means_beyond_the_tolerance(tmp_path, monkeypatch):
    """A clean path enters samples by 1e-5 to 4e-3 mm: on the log scale they take many colours (a linear
    scale to the tolerance drew them all pale yellow); the few beyond the tolerance are red; the caption says
    what the colours mean."""
    import pyvista as pv

    from machsurf_cad.viz import render_gouge_map

    texts = []
    original = pv.Plotter.add_text
    monkeypatch.setattr(
        pv.Plotter, "add_text", lambda self, text, **kw: texts.append(text) or original(self, text, **kw)
    )
    top, _ = _grid(0, 60, 0, 45, 0.0, 121, 91)
    side, _ = _grid(0, 60, 0, 45, -30.0, 61, 46)
    pts = np.concatenate([top, side])
    rng = np.random.default_rng(7)
    depth = np.zeros(len(pts))
    entered = rng.choice(len(top), 1500, replace=False)
    depth[entered] = 10 ** rng.uniform(-5, np.log10(4e-3), entered.size)
    depth[entered[:40]] = 0.015  # beyond the tolerance
    img = _image(render_gouge_map(pts, depth, tmp_path / "g.png", tolerance=0.01, title="t", window_size=(900, 700)))
    scene = img[:, : int(0.8 * img.shape[1])]  # left of the legend
    coloured = scene[np.ptp(scene, axis=-1) > 60]
    bins = np.unique(coloured // 32, axis=0, return_counts=True)[1]
    assert (bins >= 30).sum() >= 15  # many distinct colours, each on many pixels (the linear scale drew 9)
    red = (img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)
    assert red.sum() > 40
    assert "log scale" in texts[0] and "never entered" in texts[0] and "1,500 of" in texts[0]


def _directions(n=64):
    """A 64 x 64 grid whose best direction is -45, 0, 45 or 90 deg by quadrant."""
    X, Y = np.meshgrid(np.linspace(0, 100, n), np.linspace(0, 60, n), indexing="ij")
    pts = np.stack([X, Y, 0.002 * X * Y], axis=-1)
    best = np.select([(X < 50) & (Y < 30), (X >= 50) & (Y < 30), X < 50], [-45.0, 0.0, 45.0], 90.0)
    return pts, best


def _major_colours(img: np.ndarray, ignore, share: float = 0.004) -> int:
    """How many colours (quantised to 16 levels) cover more than ``share`` of the pixels, those near the
    ``ignore`` colours left out."""
    keep = np.ones(img.shape[:2], bool)
    for rgb in ignore:
        keep &= ~_near(img, rgb, 40)
    q, counts = np.unique(img[keep] // 16, axis=0, return_counts=True)
    return int((counts > share * img.shape[0] * img.shape[1]).sum())


def test_best_direction_map_has_one_colour_and_legend_entry_per_direction(tmp_path):
    """Called as the reff job calls it, four directions make four flat colours (no continuous scale), and
    the legend right of the scene shows one swatch per direction, never taken ones included when given."""
    from machsurf_cad.viz import render_scalar_map
    from machsurf_cad.viz.render import LEGEND_LEFT, category_colors

    pts, best = _directions()
    common = dict(label="theta [deg]", clim=(-45, 90), cmap="viridis", view="xy", window_size=(900, 700))
    img = _image(render_scalar_map(pts, best, tmp_path / "b.png", title="best", **common))
    split = int(LEGEND_LEFT * img.shape[1])
    dimgray, text = (105, 105, 105), [(255, 255, 255), (0, 0, 0)]
    assert _major_colours(img[:, :split], [dimgray, *text]) == 4
    for rgb in (np.array([int(c[i : i + 2], 16) for i in (1, 3, 5)]) for c in category_colors(4)):
        assert _near(img[:, :split], rgb, 6).sum() > 0.03 * split * img.shape[0]
        assert _near(img[:, split:], rgb, 6).sum() > 20  # its legend swatch
    given = render_scalar_map(pts, best, tmp_path / "c.png", categories=[-45, 0, 45, 90, 135], **common)
    legend = _image(given)[:, int(LEGEND_LEFT * 900) :]
    swatches = [np.array([int(c[i : i + 2], 16) for i in (1, 3, 5)]) for c in category_colors(5)]
    assert sum(_near(legend, rgb, 6).sum() > 20 for rgb in swatches) == 5


def test_a_continuous_field_keeps_its_continuous_scale(tmp_path):
    from machsurf_cad.viz import render_scalar_map

    pts, _ = _directions()
    r_eff = 3.0 + 13.0 * pts[..., 0] / 100.0
    img = _image(render_scalar_map(pts, r_eff, tmp_path / "r.png", label="R_eff [mm]", clim=(3, 16), view="xy"))
    assert _major_colours(img, [(105, 105, 105)], share=0.0005) > 20


def test_tick_format_is_one_style_per_legend():
    from machsurf_cad.viz.render import tick_format

    fmt = tick_format(np.linspace(-0.001, 0.001, 5))
    assert (fmt % 0.001, fmt % 5e-4, fmt % 0.0) == ("0.0010", "0.0005", "0.0000")
    assert tick_format(np.linspace(3, 16, 6)) == "%.1f"
    tiny = tick_format(np.linspace(0, 5e-6, 5))
    assert all("e" in tiny % v for v in np.linspace(0, 5e-6, 5))
    assert tick_format([1e-4, 1e-3, 1e-2, 0.02]) == "%.4f"


def _one_style(labels) -> bool:
    """Every label in one form: all exponent, or all fixed with the same number of decimals."""
    forms = {("e" if "e" in s else len(s.split(".")[1]) if "." in s else 0) for s in labels}
    return len(forms) == 1


def test_every_legend_in_the_pictures_has_one_label_style(tmp_path, monkeypatch):
    """The scalar bars the maps draw (ticks and tolerance marks) each label in one style, for the issue's
    0.001 / 5e-4 tolerance and deviations, the simulation's and the gouge map's legends."""
    import pyvista as pv

    from machsurf_cad.viz import render_deviation, render_gouge_map, render_simulation_map

    bars = []
    original = pv.Plotter.add_scalar_bar

    def spy(self, *args, **kwargs):
        actor = original(self, *args, **kwargs)
        lut = actor.GetLookupTable()
        lo, hi = lut.GetRange()
        fmt, n = actor.GetLabelFormat(), actor.GetNumberOfLabels()
        marks = [lut.GetAnnotation(i) for i in range(lut.GetNumberOfAnnotatedValues())]
        bars.append(([fmt % t for t in np.linspace(lo, hi, n)] if n else [], marks))
        return actor

    monkeypatch.setattr(pv.Plotter, "add_scalar_bar", spy)
    pts, _ = _grid(0, 50, 0, 40, 0.0, 26, 21)
    signed = 5e-4 * np.sin(pts[:, 0] / 8.0)
    stats = dict(max_abs=5e-4, max=5e-4, min=-5e-4, rms=3e-4, n_points=len(pts), worst_xyz=pts[0].tolist())
    dev = SimpleNamespace(
        points=pts, grid_shape=(26, 21), grid_index=None, signed=signed, triangles=None, tolerance=1e-3
    )
    dev.max_abs, dev.stats = 5e-4, stats
    render_deviation(dev, tmp_path / "d.png", tolerance=1e-3, window_size=(600, 450))
    render_simulation_map(_slab(), tmp_path / "s.png", window_size=(600, 450))
    depth = np.where(np.arange(len(pts)) % 7 == 0, 10 ** np.linspace(-5, -2.5, len(pts)), 0.0)
    render_gouge_map(pts, depth, tmp_path / "g.png", tolerance=1e-3, window_size=(600, 450))
    assert len(bars) == 4  # deviation, machined region, border, gouge depth
    for ticks, marks in bars:
        numbers = [m for s in marks for m in re.findall(r"[-+]?\d[\d.e+-]*", s)]
        assert _one_style(ticks + numbers), (ticks, marks)
