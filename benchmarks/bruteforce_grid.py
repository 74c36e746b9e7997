"""The drop-cutter against an independent reference on 200 x 200 grids (issue 27): per part, the largest
difference of the heights from the reference's (``tests/ball_reference.py`` for the ball,
``tests/profile_reference.py`` for the flat and the bull-nose: dense samples refined on the exact faces, the
tool's rim and the edges), over all points and over the points within 1 mm in plan of a trimming edge
counted apart, with both times.

    python -m benchmarks.bruteforce_grid [--n 200] [--tool ball:D=10] [--spacing 0.15] [PART.step ...]

The example parts by default; ../shared/real-parts files when named.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def grid_row(path: Path, n: int, tool: str = "ball:D=10", spacing: float = 0.15) -> dict:
    sys.path.insert(0, str(ROOT / "tests"))
    from ball_reference import BallReference
    from profile_reference import ProfileReference

    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(path)
    cutter = ms.parse_cutter(tool)
    kind = type(cutter).__name__
    if kind not in ("BallEndMill", "FlatEndMill", "BullNoseEndMill"):
        raise SystemExit(f"the references cover ball, flat and bull end mills, not {tool}")
    t = time.perf_counter()
    ref = BallReference(faces, spacing=spacing) if kind == "BallEndMill" else ProfileReference(faces, spacing=spacing)
    t_sample = time.perf_counter() - t
    lo, hi = ref.P[:, :2].min(axis=0), ref.P[:, :2].max(axis=0)
    X, Y = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n), indexing="ij")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    t = time.perf_counter()
    R = cutter.radius
    bf = ref.heights(xy, R) if kind == "BallEndMill" else ref.heights(xy, R, getattr(cutter, "corner_radius", 0.0))
    t_ref = time.perf_counter() - t
    t = time.perf_counter()
    dc = ms.drop_cutter(faces, cutter, xy).height
    t_dc = time.perf_counter() - t
    both = np.isfinite(bf) & np.isfinite(dc)
    near_trim = ref.etree.query(xy)[0] <= 1.0
    diff = dc - bf
    row = {
        "part": path.name,
        "tool": cutter.spec(),
        "faces": len(faces),
        "points": int(xy.shape[0]),
        "points_with_height": int(both.sum()),
        "nan_mismatch": int((np.isfinite(bf) != np.isfinite(dc)).sum()),
        "max_abs_diff_mm": float(np.abs(diff[both]).max()),
        "most_below_reference_mm": float(max(0.0, -diff[both].min())),
        "points_over_1e-6": int((np.abs(diff[both]) > 1e-6).sum()),
        "near_trim_points": int((both & near_trim).sum()),
        "near_trim_max_abs_diff_mm": float(np.abs(diff[both & near_trim]).max()) if (both & near_trim).any() else 0.0,
        "reference_spacing_mm": spacing,
        "reference_samples": int(ref.P.shape[0]),
        "reference_edge_samples": int(ref.E.shape[0]),
        "reference_s": t_sample + t_ref,
        "drop_cutter_s": t_dc,
    }
    bad = np.flatnonzero(both & (np.abs(diff) > 1e-6))
    row["worst"] = [{"xy": xy[k].tolist(), "drop_cutter": float(dc[k]), "reference": float(bf[k])}
                    for k in bad[np.argsort(-np.abs(diff[bad]))][:5]]  # fmt: skip
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bruteforce_grid")
    ap.add_argument("parts", nargs="*")
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--tool", default="ball:D=10", help="ball, flat or bull (e.g. bull:D=10,r=2)")
    ap.add_argument("--spacing", type=float, default=0.15, help="the reference's face samples, mm")
    args = ap.parse_args(argv)
    parts = [Path(p) for p in args.parts] or [ROOT / "example_parts" / f for f in ("freeform_block.step",
                                                                                 "mould_insert.step")]  # fmt: skip
    for p in parts:
        print(json.dumps(grid_row(p, args.n, args.tool, args.spacing)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
