"""Avoiding the part (issue 28): time per position of cutting a fixed-axis path down to the tool's reach
(exact drop-cutter on every face, then skim links), per gap of linking clear stretches by checked links,
and per lattice placement of tilting a 5-axis axis away, each beside the whole-part check of the same path
(the check that confirms it), in one run."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _boss():
    from machsurf_cad import builders

    floor = builders.plane_patch((-30, -30, 0), (60, 0, 0), (0, 60, 0), name="floor")
    top = builders.plane_patch((0, -10, 8), (10, 0, 0), (0, 20, 0), name="boss top")
    walls = [
        builders.plane_patch((0, -10, 0), (0, 20, 0), (0, 0, 8)),
        builders.plane_patch((10, -10, 0), (0, 0, 8), (0, 20, 0)),
        builders.plane_patch((0, -10, 0), (0, 0, 8), (10, 0, 0)),
        builders.plane_patch((0, 10, 0), (10, 0, 0), (0, 0, 8)),
    ]
    return floor, [floor, top, *walls]


def _timed(fn, *args, **kw):
    t = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t


def avoid_rows(quick: bool = False) -> list[dict]:
    import machsurf_cad as ms
    from machsurf_cad.machining.avoid import clear_axis_field

    rows = []
    floor, part = _boss()
    tool = ms.BallEndMill(6, length=20.0)
    step = 2.0 if quick else 0.5
    ys = np.arange(-29.0, 29.01, step)
    tips = [np.column_stack([np.full(ys.size, x), ys, np.zeros(ys.size)]) for x in np.arange(-29.0, 29.01, 2.0)]
    planned = ms.ToolPath.from_passes(tips, [np.tile([0.0, 0, 1], (ys.size, 1))] * len(tips), cutter=tool)
    out, t_reach = _timed(ms.trim_to_reach, planned, part)
    v, t_check = _timed(ms.verify, part, out)
    rows.append({"name": "trim to reach, pocket with a boss (3 axes)", "n": planned.n_cut, "ours_s": t_reach,
                 "ref_s": t_check, "ref": "verify of the result", "max_diff": float(v.max_gouge),
                 "ms_per_position": 1e3 * t_reach / planned.n_cut})  # fmt: skip
    pc, t_trim = _timed(ms.check_toolpath, planned, part, on_gouge="trim")
    gaps = pc.toolpath.info["links_direct"] + pc.toolpath.info["links_over_surface"] if pc.toolpath else 0
    rows.append({"name": "trim + checked links, pocket with a boss", "n": gaps, "ours_s": t_trim,
                 "ref_s": t_check, "ref": "verify of the reach path", "max_diff": float(pc.recheck.max_gouge)
                 if pc.recheck is not None else float("nan")})  # fmt: skip
    blade_floor = ms.Face(ms.builders.plane_patch((0, 0, 0), (40, 0, 0), (0, 20, 0)), name="floor")
    blade = ms.Face(ms.builders.plane_patch((0, 20, 0), (40, 0, 0), (0, -8, 20)), name="blade")
    grid = 11 if quick else 21
    limits = {"lead": 0.0, "max_lead": 40.0, "max_tilt": 90.0, "grid": grid, "step": 10.0}
    (field, rep), t_tilt = _timed(
        clear_axis_field, blade_floor, ms.BallEndMill(6, length=25.0), "planes:x", [blade_floor, blade], **limits
    )
    rows.append({"name": "tilt away, floor under a leaning blade", "n": rep["lattice_points"], "ours_s": t_tilt,
                 "ref_s": float("nan"), "ref": f"{rep['lattice_points_tilted']} tilted", "max_diff": float("nan"),
                 "ms_per_position": 1e3 * t_tilt / rep["lattice_points"]})  # fmt: skip
    prop = (ROOT / "../shared/real-parts/ampath_propeller.stp").resolve()
    if not quick and prop.exists():
        from machsurf_cad.occ import read_step_faces

        faces = read_step_faces(prop)
        axis = (0.83, -0.181, -0.528)
        surf = ms.machining_surface(faces[42], "ball:D=10", axes=3, axis=axis)
        tp = ms.tool_paths(surf, stepover=2.0, safe_plane=ms.part_plane(faces, axis, 5.0))
        out, t_reach = _timed(ms.trim_to_reach, tp, faces, face=faces[42])
        v, t_check = _timed(ms.verify, faces, out)
        rows.append({"name": "trim to reach, propeller face 42 (3+2)", "n": tp.n_cut, "ours_s": t_reach,
                     "ref_s": t_check, "ref": "verify of the result", "max_diff": float(v.max_gouge),
                     "ms_per_position": 1e3 * t_reach / tp.n_cut,
                     "machined_area_fraction": out.info["machined_area_fraction"]})  # fmt: skip
    return rows


if __name__ == "__main__":  # python -m benchmarks.bench_avoid [--quick]
    import json
    import sys

    for r in avoid_rows(quick="--quick" in sys.argv):
        print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}), flush=True)
