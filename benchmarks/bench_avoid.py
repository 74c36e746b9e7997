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
    rows += _session8_rows(quick)
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


def _session8_rows(quick: bool) -> list[dict]:
    """The avoidance added for issue 28 after the first rows: links over a clearance cylinder, a rotary
    limit, several flank diameters and rapids kept clear of the whole tool, each per its own unit."""
    import machsurf_cad as ms
    from machsurf_cad import builders
    from machsurf_cad.flank_milling import RuledSurface
    from machsurf_cad.geometry.builders import line_segment
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.linking import link_runs
    from machsurf_cad.machining.avoid import clear_axis_field

    rows = []
    # links over a cylinder about a bar 100 mm long: passes on top, at the end (axis along the bar) and on top
    # again, per link (the bar is a plate with its material below: nothing is cut from underneath)
    bar = builders.plane_patch((0, -5, 0), (100, 0, 0), (0, 10, 0), name="bar")
    x = np.linspace(10, 40, 7)
    top = np.column_stack([x, np.zeros(7), np.zeros(7)])
    up = np.tile([0.0, 0, 1], (7, 1))
    runs = [(top, up), (np.array([[100.0, -3, 0], [100, 3, 0]]), np.tile([1.0, 0, 0], (2, 1))),
            (top[::-1] + [50.0, 2.0, 0.0], up)]  # fmt: skip
    tool = ms.BallEndMill(6, length=10.0)
    for kind in ("cylinder", "sphere"):
        tp, t = _timed(link_runs, runs, [bar], tool, clearance=5.0, clearance_surface=kind)
        v, t_check = _timed(ms.verify, [bar], tp)
        n = tp.info["links_direct"] + tp.info["links_over_surface"]
        rows.append({"name": f"links over a clearance {kind}, bar 100 x 10 (5 axes)", "n": n, "ours_s": t,
                     "ref_s": t_check, "ref": f"verify; link length {tp.link_length():.0f} mm",
                     "max_diff": float(v.max_gouge), "ms_per_position": 1e3 * t / max(n, 1)})  # fmt: skip
    # a rotary limit of 45 deg on a half pipe: tilt away within it, then the check that cuts out the rest
    c = builders.cylinder_patch(radius=20.0, height=40.0, angle_deg=180.0, name="pipe")
    pipe = Face(c.with_poles(np.asarray(c.poles)[..., [2, 0, 1]], c.weights), name="pipe")
    if pipe.surface.normals(np.array([0.5]), np.array([0.5]))[0][2] < 0:
        pipe = Face(pipe.surface, name="pipe", reversed=True)
    grid = 11 if quick else 19
    (field, rep), t_tilt = _timed(clear_axis_field, pipe, ms.BallEndMill(6, length=20.0), "planes:x", [pipe],
                                  lead=0.0, max_lead=30.0, max_tilt=0.0, grid=grid, max_axis_angle=45.0)  # fmt: skip
    rows.append({"name": "tilt away within a 45 deg rotary limit, half pipe", "n": rep["lattice_points"],
                 "ours_s": t_tilt, "ref_s": float("nan"), "ref": f"{rep['lattice_points_tilted']} tilted",
                 "max_diff": float("nan"), "ms_per_position": 1e3 * t_tilt / rep["lattice_points"]})  # fmt: skip
    surf = ms.machining_surface(pipe, ms.BallEndMill(6, length=20.0), axes=5, strategy="planes:x", axis_field=field)
    tp = ms.tool_paths(surf, stepover=4.0, chordal_tolerance=0.005, safe_sphere=ms.part_sphere([pipe], 5.0))
    pc, t_lim = _timed(ms.check_toolpath, tp, [pipe], on_gouge="trim", max_axis_angle=45.0)
    rows.append({"name": "check + cut out past a 45 deg rotary limit, half pipe", "n": tp.n_positions,
                 "ours_s": t_lim, "ref_s": float("nan"), "ref": f"{pc.beyond_axis_limit} past the limit",
                 "max_diff": float(pc.recheck.max_gouge) if pc.recheck is not None else float("nan"),
                 "ms_per_position": 1e3 * t_lim / tp.n_positions})  # fmt: skip
    # several flank diameters beside a wall: each stretch to the largest cylinder that clears, per rule
    blade = RuledSurface.from_curves(line_segment([0, 0, 0], [0, 40, 0]), line_segment([0, 0, 20], [0, 40, 20]))
    wall = Face(builders.plane_patch((5, 25, -5), (0, 25, 0), (0, 0, 40)), name="wall")
    res, t_fl = _timed(ms.flank, blade, ["cyl:D=4", "cyl:D=6"], setting="standard-distributed", whole=True,
                       check_faces=[wall], gouge_tolerance=0.01)  # fmt: skip
    n_rules = sum(len(b.cleared.path.settings) for b in res.by_diameter if b.cleared is not None)
    rows.append({"name": "flank D6 + D4 beside a wall (largest that clears)", "n": n_rules, "ours_s": t_fl,
                 "ref_s": float("nan"), "ref": f"{len(res.by_diameter)} tools",
                 "max_diff": float("nan"), "ms_per_position": 1e3 * t_fl / max(n_rules, 1)})  # fmt: skip
    # rapids kept clear of the whole tool (holder D20) beside the bridge over a floor, per rapid move
    floor = builders.plane_patch((-40, -30, 0), (100, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((0, -30, 12), (20, 0, 0), (0, 60, 0), name="bridge")
    holder_tool = ms.BallEndMill(6, length=10.0, holder=ms.Shank(20, 30))
    ys = np.linspace(-20, 20, 21)
    runs = []
    for k, x0 in enumerate((-13.0, -8.0, 28.0, 33.0)):
        t_ = np.column_stack([np.full(ys.size, x0), ys if k % 2 == 0 else ys[::-1], np.zeros(ys.size)])
        runs.append((t_, np.tile([0.0, 0, 1], (ys.size, 1))))
    tp, t_link = _timed(link_runs, runs, [floor, bridge], holder_tool, clearance=5.0)
    n_rapid = int(np.sum(tp.move != ms.Move.CUT))
    rows.append({"name": "links with rapids kept 5 mm from the whole tool (holder D20)", "n": n_rapid,
                 "ours_s": t_link, "ref_s": float("nan"), "ref": f"{tp.info['n_rapids_at_feed']} at feed",
                 "max_diff": float("nan"), "ms_per_position": 1e3 * t_link / max(n_rapid, 1)})  # fmt: skip
    return rows


if __name__ == "__main__":  # python -m benchmarks.bench_avoid [--quick]
    import json
    import sys

    for r in avoid_rows(quick="--quick" in sys.argv):
        print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}), flush=True)
