"""2-D plots (matplotlib, Agg backend) for studies; lengths in mm, angles in degrees."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def plot_ratio_curves(curves, png_path, *, label_key: str, label_fmt: str, title: str) -> Path:
    """Error ratio standard / optimum against R, one curve per study parameter (log axes)."""
    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
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
    plt.close(fig)
    return png_path
