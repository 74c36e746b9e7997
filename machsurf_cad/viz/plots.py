"""2-D plots (matplotlib figures drawn by the Agg canvas, without pyplot: importing this module changes
no global state, such as pyplot's backend); lengths in mm, angles in degrees."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..cam.toolpath import Move


def _figure(figsize, dpi, layout=None):
    """A figure and its axes on its own Agg canvas (nothing registered with pyplot)."""
    fig = Figure(figsize=figsize, dpi=dpi, layout=layout)
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def plot_ratio_curves(curves, png_path, *, label_key: str, label_fmt: str, title: str) -> Path:
    """Error ratio standard / optimum against R, one curve per study parameter (log axes)."""
    fig, ax = _figure((8, 5.5), 120)
    for c in curves:
        ax.plot(c["R_mm"], c["ratio"], marker="o", ms=3, label=label_fmt.format(c[label_key]))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(10.0, color="grey", ls="--", lw=1)
    ax.text(ax.get_xlim()[0] * 1.05, 10.5, "tenfold", color="grey")
    ax.set_xlabel("tool radius R [mm]")
    ax.set_ylabel("error ratio standard (distributed) / optimum")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    png_path = Path(png_path)
    fig.tight_layout()
    fig.savefig(png_path)
    return png_path


NEAR_TOLERANCES = 1.0
"""Without the move kinds, positions farther than this many tolerances from the part count as off it."""


def plot_path_distance(distance, status, png_path, *, tolerance: float, title: str = "", move=None) -> Path:
    """Plot the smallest signed distance between the tool's cutting part and the part along the path.

    Parameters
    ----------
    distance : array_like, shape (n,)
        Per position, mm (negative: inside the part; ``inf``: nowhere near it).
    status : array_like of int, shape (n,)
        0 clear, 1 gouge (drawn red), 2 collision (black crosses).
    png_path : path
        The picture.
    tolerance : float
        The gouge tolerance, mm: dashed at ``-tolerance``, the band below it shaded.
    title : str
        The plot's title.
    move : array_like of int, shape (n,), optional
        The move kind of each position (``Move``): the cutting moves make the blue line and the scale. Without
        it, the positions within :data:`NEAR_TOLERANCES` tolerances of the part do.

    Returns
    -------
    Path
        ``png_path``.

    Notes
    -----
    The other positions (rapids, links, retracts: millimetres off the part) are a thin grey line that leaves
    the top of the axes, so that the cutting clearance fills the height. The legend is right of the axes.
    """
    fig = _path_distance_figure(distance, status, tolerance=tolerance, title=title, move=move)
    png_path = Path(png_path)
    fig.savefig(png_path)
    return png_path


def _path_distance_figure(distance, status, *, tolerance: float, title: str = "", move=None):
    """The figure of :func:`plot_path_distance` (constrained layout, drawn on its own Agg canvas)."""
    d = np.asarray(distance, float)
    st = np.asarray(status)
    x = np.arange(d.size)
    fin = np.isfinite(d)
    if move is not None:
        cutting = fin & (np.asarray(move) == int(Move.CUT))
        labels = ("cutting moves", "other moves")
    else:
        cutting = fin & (d <= NEAR_TOLERANCES * tolerance)
        labels = (f"within {NEAR_TOLERANCES * tolerance:g} mm of the part", "farther (rapids, links, air)")
    lo, hi = _distance_range(d[cutting | (fin & (st != 0))], tolerance)
    fig, ax = _figure((11, 4.5), 120, layout="constrained")
    away = np.where(fin, d, hi + 10 * (hi - lo))  # inf (nowhere near the part) leaves the top too
    n_off = int(np.count_nonzero(~cutting))
    ax.plot(x, away, lw=0.5, color="0.6", label=f"{labels[1]}: {n_off} positions,\nmost off the top")
    ax.plot(x, np.where(cutting, d, np.nan), lw=1.0, color="tab:blue", label=labels[0])
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.axhline(-tolerance, color="tab:red", ls="--", lw=1, label=f"-tolerance ({tolerance:g} mm)")
    ax.axhspan(lo - (hi - lo), -tolerance, color="tab:red", alpha=0.08, lw=0)
    ax.scatter(x[st == 1], np.clip(d[st == 1], lo, hi), s=10, color="tab:red", label="gouge", zorder=3)
    ax.scatter(x[st == 2], np.clip(d[st == 2], lo, hi), s=14, color="black", marker="x", label="collision", zorder=3)
    ax.set_ylim(lo, hi)
    ax.set_xlim(-0.5, max(d.size - 0.5, 0.5))
    ax.set_xlabel("position (GOTO index)")
    ax.set_ylabel("smallest distance tool - part [mm]\n(negative: inside the part)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=9)
    return fig


def _distance_range(near, tolerance: float) -> tuple[float, float]:
    """The y range of the path-distance plot: the given distances and the tolerance band, with margins."""
    lo = min(float(near.min()) if near.size else 0.0, -1.5 * tolerance)
    hi = max(float(near.max()) if near.size else 0.0, 0.5 * tolerance)
    pad = 0.06 * (hi - lo)
    return lo - pad, hi + pad


def plot_simulation_histogram(value, reached, png_path, *, tolerance: float, heights=(), title: str = "") -> Path:
    """Histogram of the material left per nominal sample (mm; negative: gouge), the gouge tolerance and the
    report's heights marked."""
    v = np.asarray(value, float)[np.asarray(reached, bool)]
    fig, ax = _figure((9, 4.5), 120)
    if v.size:
        ax.hist(v, bins=120, color="tab:blue", alpha=0.85)
    ax.axvline(-tolerance, color="tab:red", ls="--", lw=1, label=f"-tolerance ({tolerance:g} mm)")
    for h in heights:
        ax.axvline(h, color="grey", ls=":", lw=0.8)
    ax.set_yscale("log")
    ax.set_xlabel("material left along the normal [mm] (negative: gouge)")
    ax.set_ylabel("samples")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right")
    png_path = Path(png_path)
    fig.tight_layout()
    fig.savefig(png_path)
    return png_path


def plot_rule_errors(profiles: dict, png_path, *, tolerance: float | None = None, title: str = "") -> Path:
    """The error along the rule (mm) of every setting against v (0 at C0, 1 at C1): negative gouge,
    positive undercut (the flank paper's figures 6 and 7). ``profiles``: setting name -> Interference
    (settings that do not exist, given as a reason string, are listed in the legend's title)."""
    fig, ax = _figure((7.5, 4.5), 110)
    missing = []
    for kind, e in profiles.items():
        if isinstance(e, str):
            missing.append(kind)
            continue
        ax.plot(e.v, e.e, label=f"{kind} (max |e| {e.max_abs:.3g} mm)")
    ax.axhline(0.0, color="0.3", lw=0.8)
    if tolerance is not None:
        for y in (-tolerance, tolerance):
            ax.axhline(y, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel("v along the rule (0: directrix C0, 1: C1)")
    ax.set_ylabel("error, mm (- gouge, + undercut)")
    ax.set_title(title)
    ax.legend(fontsize=8, title=("not admissible: " + ", ".join(missing)) if missing else None, title_fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png_path)
    return Path(png_path)
