"""2-D plots (matplotlib figures drawn by the Agg canvas, without pyplot: importing this module changes
no global state, such as pyplot's backend); lengths in mm, angles in degrees."""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def _figure(figsize, dpi):
    """A figure and its axes on its own Agg canvas (nothing registered with pyplot)."""
    fig = Figure(figsize=figsize, dpi=dpi)
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


def plot_path_distance(distance, status, png_path, *, tolerance: float, title: str = "") -> Path:
    """Smallest signed distance between the tool's cutting part and the part along the path (mm), per
    position: below -tolerance a gouge (red), collisions marked in black."""
    import numpy as np

    d = np.asarray(distance, float)
    x = np.arange(d.size)
    fig, ax = _figure((10, 4.5), 120)
    shown = np.clip(d, -10 * max(tolerance, 1e-9) - np.nanmax(-d[np.isfinite(d)], initial=0), 5.0)
    ax.plot(x, shown, lw=0.8, color="tab:blue", label="tool to part, mm")
    ax.axhline(-tolerance, color="tab:red", ls="--", lw=1, label=f"-tolerance ({tolerance:g} mm)")
    st = np.asarray(status)
    ax.scatter(x[st == 1], shown[st == 1], s=10, color="tab:red", label="gouge", zorder=3)
    ax.scatter(x[st == 2], shown[st == 2], s=14, color="black", marker="x", label="collision", zorder=3)
    ax.set_xlabel("position (GOTO index)")
    ax.set_ylabel("smallest distance tool-part [mm] (clipped at 5)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right")
    png_path = Path(png_path)
    fig.tight_layout()
    fig.savefig(png_path)
    return png_path


def plot_simulation_histogram(value, reached, png_path, *, tolerance: float, heights=(), title: str = "") -> Path:
    """Histogram of the material left per nominal sample (mm; negative: gouge), the gouge tolerance and the
    report's heights marked."""
    import numpy as np

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
