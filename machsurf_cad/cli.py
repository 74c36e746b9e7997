"""The ``machsurf`` command line (also ``python -m machsurf_cad``).

Exit codes: 0 success, 1 bad input (one-line message, no traceback), 2 a tolerance not met.
Every command writes ``report.json`` with each figure it prints; lengths in mm, angles in
degrees. Outputs are staged in a hidden folder and moved into place only on success, so a
failed command never leaves half-written files.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

from . import __version__
from .errors import InputError, MachsurfError

EXIT_OK, EXIT_INPUT, EXIT_TOLERANCE = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # bad usage is bad input: exit 1 with one line
        self.print_usage(sys.stderr)
        print(f"machsurf: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


class Staging:
    """Write outputs into a hidden sibling folder, move them into ``out_dir`` on success.

    Use as a context manager: the files move into place when the block ends normally and are
    removed when it raises, so a failed command leaves nothing half-written.
    """

    def __init__(self, out_dir):
        self.out_dir = Path(out_dir)
        self.out_dir.parent.mkdir(parents=True, exist_ok=True)
        self.dir = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.partial-", dir=str(self.out_dir.parent)))
        self.files: list[Path] = []

    def path(self, name: str) -> Path:
        return self.dir / name

    def commit(self) -> list[Path]:
        self.out_dir.mkdir(parents=True, exist_ok=True)
        moved = []
        for f in sorted(self.dir.iterdir()):
            dest = self.out_dir / f.name
            if dest.exists() and dest.is_dir():
                shutil.rmtree(dest)
            shutil.move(str(f), str(dest))
            moved.append(dest)
        shutil.rmtree(self.dir, ignore_errors=True)
        return moved

    def abort(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> "Staging":
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.commit()
        else:
            self.abort()
        return False


def _write_json(path: Path, data: dict) -> None:
    path.write_text(json.dumps(data, indent=2, default=_json_default) + "\n")


def _json_default(o):
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o)}")


def _say(msg: str = "") -> None:
    print(msg, flush=True)


# ----------------------------------------------------------------------------- commands
def cmd_info(args) -> int:
    from .occ import read_step_faces

    t0 = time.perf_counter()
    faces = read_step_faces(args.part)
    rows = []
    _say(f"{args.part}: {len(faces)} face(s)")
    _say(f"{'idx':>3}  {'name':<16} {'type':<18} {'deg':>5} {'poles':>9} {'trim':>4} {'area mm2':>11}  uv bounds")
    for f in faces:
        s = f.surface
        row = {
            "index": f.index, "name": f.name, "source_type": f.source_type,
            "degree_u": s.degree_u, "degree_v": s.degree_v, "poles_u": s.shape[0], "poles_v": s.shape[1],
            "rational": s.is_rational, "trimmed": f.is_trimmed, "n_loops": len(f.loops),
            "uv_bounds": list(f.uv_bounds), "area_mm2": f.area, "reversed": f.reversed,
        }
        rows.append(row)
        _say(f"{f.index:>3}  {f.name[:16]:<16} {f.source_type[:18]:<18} {s.degree_u:>2},{s.degree_v:<2} "
             f"{s.shape[0]:>4}x{s.shape[1]:<4} {'yes' if f.is_trimmed else 'no':>4} {f.area:>11.2f}  "
             f"[{f.uv_bounds[0]:.4g}, {f.uv_bounds[1]:.4g}] x [{f.uv_bounds[2]:.4g}, {f.uv_bounds[3]:.4g}]")
    report = {"command": "info", "part": str(args.part), "n_faces": len(faces), "faces": rows,
              "time_s": time.perf_counter() - t0}
    with Staging(args.out) as st:
        _write_json(st.path("report.json"), report)
    _say(f"report: {Path(args.out) / 'report.json'}")
    return EXIT_OK


def _mesh_candidate(path: Path):
    from .meshsample import subdivide
    from .occ import read_stl

    pts, tris = read_stl(path)
    return subdivide(pts, tris, 2)


def cmd_inspect(args) -> int:
    from .measure import deviation
    from .occ import read_step_face, read_step_faces

    t0 = time.perf_counter()
    if args.tol is not None and not args.tol > 0:
        raise InputError("--tol must be > 0 mm")
    nominal = read_step_face(args.nominal, args.face)
    cand_path = Path(args.candidate)
    suffix = cand_path.suffix.lower()
    from .progress import Bar

    if suffix == ".stl":
        pts, tris = _mesh_candidate(cand_path)
        with Bar("measuring deviation") as bar:
            result = deviation(nominal, pts, tolerance=args.tol, triangles=tris, progress=bar.update)
        cand_desc = f"STL mesh {cand_path.name} ({tris.shape[0] // 16} triangles, sampled inside triangles)"
    elif suffix in (".step", ".stp"):
        cands = read_step_faces(cand_path)
        idx = args.candidate_face if args.candidate_face is not None else args.face
        if not 0 <= idx < len(cands):
            raise InputError(f"candidate face index {idx} out of range: {cand_path} has {len(cands)} face(s)")
        with Bar("measuring deviation") as bar:
            result = deviation(nominal, cands[idx], samples=args.samples, tolerance=args.tol, progress=bar.update)
        cand_desc = f"STEP face {idx} '{cands[idx].name}' of {cand_path.name}"
    else:
        raise InputError(f"candidate must be .step/.stp or .stl, got {cand_path.name}")
    return _finish_deviation(args, result, nominal, cand_desc, t0)


def _finish_deviation(args, result, nominal, cand_desc, t0) -> int:
    s = result.stats
    _say(f"nominal: face {nominal.index} '{nominal.name}' of {args.nominal}")
    _say(f"candidate: {cand_desc}")
    _say(f"points measured: {s['n_points']}")
    _say(f"max |deviation| = {s['max_abs']:.6g} mm  (max {s['max']:.6g}, min {s['min']:.6g})")
    _say(f"mean = {s['mean']:.6g} mm  RMS = {s['rms']:.6g} mm  p95 |dev| = {s['p95_abs']:.6g} mm")
    _say(f"worst at xyz = ({', '.join(f'{x:.4f}' for x in s['worst_xyz'])}) mm, "
         f"uv = ({s['worst_uv'][0]:.6f}, {s['worst_uv'][1]:.6f})")
    if args.tol is not None:
        _say(f"tolerance {args.tol:g} mm: {'met' if result.within_tolerance else 'NOT met'}")
    with Staging(args.out) as st:
        files = {}
        if not args.no_render:
            from .viz import render_deviation

            render_deviation(result, st.path("deviation.png"), vtp_path=st.path("deviation.vtp"),
                             title=f"{Path(args.candidate).name} vs {nominal.name}", tolerance=args.tol)
            files = {"png": "deviation.png", "vtp": "deviation.vtp"}
        report = {"command": "inspect", "nominal": str(args.nominal), "face": nominal.index,
                  "candidate": str(args.candidate), "candidate_desc": cand_desc, "units": "mm",
                  "deviation": result.report(), "files": files, "time_s": time.perf_counter() - t0}
        _write_json(st.path("report.json"), report)
    _say(f"outputs in {args.out}/: {', '.join(list(files.values()) + ['report.json'])}")
    if args.tol is not None and not result.within_tolerance:
        return EXIT_TOLERANCE
    return EXIT_OK


def _example(table: dict, name: str, what: str):
    """Build the example ``name`` from ``table``, or a one-line error listing the known ones."""
    if name not in table:
        raise InputError(f"unknown {what} {name!r}; known: {', '.join(sorted(table))}")
    return table[name]()


def _step_face(args):
    if not args.part:
        raise InputError("give a STEP file or --example NAME")
    from .occ import read_step_face

    return read_step_face(args.part, args.face)


def _face_or_example(args):
    from .geometry.face import Face

    if args.example:
        from .examples import EXAMPLES

        s = _example(EXAMPLES, args.example, "example")
        return Face(s, name=s.name or args.example), f"example {args.example}"
    f = _step_face(args)
    return f, f"face {f.index} '{f.name}' of {args.part}"


def cmd_machining_surface(args) -> int:
    from .cutters import parse_cutter
    from .machining import machining_surface
    from .machining.surfaces import fit_deviation

    t0 = time.perf_counter()
    cutter = parse_cutter(args.tool)
    face, desc = _face_or_example(args)
    if args.axes not in (3, 5):
        raise InputError("--axes must be 3 or 5")
    axis = None
    if args.axis:
        try:
            axis = tuple(float(x) for x in args.axis.split(","))
        except ValueError:
            raise InputError("--axis must be x,y,z") from None
    from .progress import fit_progress

    cb = fit_progress("fitting S1/S2")
    try:
        ms = machining_surface(face, cutter, axes=args.axes, strategy=args.strategy, lead=args.lead, tilt=args.tilt,
                               axis=axis, tolerance=args.tol, loops=args.loops, max_poles=args.max_poles,
                               tip=args.tip, degree=(args.degree, args.degree), progress=cb)
    finally:
        cb.close()
    rep = ms.report()
    _say(f"nominal: {desc}")
    _say(f"tool: {cutter.spec()} (r = {rep['r_mm']:g} mm, R_t = {rep['R_t_mm']:g} mm), {ms.axes} axes, "
         f"{rep['strategy']}")
    for key in ("S1", "S2"):
        f = rep[key]
        if f is None:
            continue
        _say(f"{f['name']}: degree {f['degrees'][0]}x{f['degrees'][1]}, {f['poles'][0]}x{f['poles'][1]} poles, "
             f"max error {f['max_error_mm']:.3g} mm (tol {args.tol:g}) on {f['n_check_points']} unseen points")
    if ms.axes == 5:
        _say(f"axis orientation: alpha_max = {rep['alpha_max_deg_for_tolerance']:.4g} deg for the tolerance, "
             f"{rep['alpha_max_deg_for_measured_errors']:.4g} deg for the measured errors; measured axis error "
             f"{rep['axis_error_deg_measured']:.4g} deg")
    _say("loops: " + ("none" if not ms.loops.found else "; ".join(r.describe() for r in ms.loops.regions)))
    with Staging(args.out) as st:
        from .occ import write_step, write_stl
        from .viz import render_deviation

        write_step(st.path("machining_surface.step"), ms.faces())
        for f in ms.faces():
            write_stl(st.path(f"{f.name}.stl"), [f], linear_deflection=args.stl_deflection)
        dev = fit_deviation(ms, "S1")
        loops_pts = [(r.xyz, "magenta", f"{r.kind} loop ({r.surface})") for r in ms.loops.regions]
        render_deviation(dev, st.path("deviation_S1.png"), vtp_path=st.path("deviation_S1.vtp"),
                         title=f"S1 fit vs exact offset ({cutter.spec()})", tolerance=args.tol,
                         extra_points=loops_pts)
        files = ["machining_surface.step"] + [f"{f.name}.stl" for f in ms.faces()] + ["deviation_S1.png",
                                                                                     "deviation_S1.vtp"]
        rep["S1_deviation_map"] = dev.report()
        if args.toolpath:
            from .machining.toolpath import tool_paths, write_apt, write_csv

            tp = tool_paths(ms, stepover=args.stepover, chordal_tolerance=args.chordal)
            write_csv(st.path("toolpath.csv"), tp)
            write_apt(st.path("toolpath.apt"), tp, ms)
            files += ["toolpath.csv", "toolpath.apt"]
            rep["toolpath"] = tp.report()
            _say(f"tool path: {len(tp.passes)} passes, {tp.n_points} CL points, chordal error "
                 f"{tp.chordal_error_measured:.3g} mm (tol {args.chordal:g})")
        rep.update({"command": "machining-surface", "nominal": desc, "files": files + ["report.json"],
                    "time_s_total": time.perf_counter() - t0})
        _write_json(st.path("report.json"), rep)
    _say(f"outputs in {args.out}/: {', '.join(rep['files'])}")
    return EXIT_OK


def cmd_reff(args) -> int:
    import numpy as np

    from .cutters import parse_cutter
    from .effradius import parse_directions, reff_maps

    t0 = time.perf_counter()
    cutter = parse_cutter(args.tool)
    face, desc = _face_or_example(args)
    dirs = parse_directions(args.direction)
    compare = None if args.compare == "none" else args.compare
    maps = reff_maps(face, cutter, directions=dirs, grid=args.grid, compare=compare, scallop=args.scallop,
                     axes=args.axes, lead=args.lead, tilt=args.tilt)
    rep = maps.report()
    R = cutter.D / 2
    _say(f"face: {desc}; tool {cutter.spec()} (R = {R:g} mm, r = {rep['r_mm']:g} mm) vs "
         f"{maps.compare.spec() if maps.compare else 'nothing'}; {maps.axes} axes"
         + (f", lead {args.lead:g} deg, tilt {args.tilt:g} deg" if maps.axes == 5 else "")
         + f"; grid {args.grid}x{args.grid}; computed in {maps.time_s:.3f} s")
    for d in rep["directions"]:
        line = (f"theta {d['theta_deg']:>6g} deg: R_eff min {d['r_eff_min_mm']:.4g} / mean {d['r_eff_mean_mm']:.4g} / "
                f"max {d['r_eff_max_mm']:.4g} mm; torus beats ball on {100 * d['area_fraction_torus_beats_ball']:.1f} % "
                f"of the area")
        if d.get("n_infinite_r_eff"):
            line += f"; {d['n_infinite_r_eff']} flat-spot sample(s) with infinite R_eff"
        _say(line)
        if args.scallop:
            _say(f"    step-over for scallop {args.scallop:g} mm: torus {d['stepover_mean_mm']:.4g} mm, ball "
                 f"{d['stepover_ball_mean_mm']:.4g} mm (ratio {d['stepover_ratio_mean']:.3f}); unreachable "
                 f"{d['n_unreachable']} sample(s)")
    with Staging(args.out) as st:
        files = []
        if not args.no_render:
            from .viz import render_scalar_map

            mask = maps.inside if maps.face.is_trimmed else None
            for d in maps.directions:
                tag = f"{d.theta_deg:g}".replace("-", "m")
                extra = {"slope_deg": d.slope_deg, "alpha_deg": d.alpha_deg,
                         "ratio_to_ball": np.nan_to_num(d.r_eff / maps.R_ball, posinf=1e300)}
                if d.stepover is not None:
                    extra.update({"stepover_mm": np.nan_to_num(d.stepover, nan=-1, posinf=1e300),
                                  "stepover_ball_mm": np.nan_to_num(d.stepover_ball, nan=-1, posinf=1e300)})
                render_scalar_map(maps.points, d.r_eff, st.path(f"reff_theta{tag}.png"),
                                  title=f"effective radius, {cutter.spec()}, theta = {d.theta_deg:g} deg\n"
                                        f"white line: R_eff = {maps.R_ball:g} mm (ball)",
                                  label="R_eff [mm]", clim=(rep["r_mm"] or 0.0, 2 * R), contour_level=maps.R_ball,
                                  mask=mask, vtp_path=st.path(f"reff_theta{tag}.vtp"), extra_arrays=extra,
                                  view="xy")
                files += [f"reff_theta{tag}.png", f"reff_theta{tag}.vtp"]
            if maps.best_theta_deg is not None:
                render_scalar_map(maps.points, maps.best_theta_deg, st.path("best_direction.png"),
                                  title=f"best machining direction ({'step-over' if args.scallop else 'R_eff'}), deg",
                                  label="theta [deg]", clim=(min(dirs), max(dirs)), cmap="hsv", mask=mask,
                                  vtp_path=st.path("best_direction.vtp"), view="xy")
                files += ["best_direction.png", "best_direction.vtp"]
        rep.update({"command": "reff", "face": desc, "files": files + ["report.json"],
                    "time_s_total": time.perf_counter() - t0})
        _write_json(st.path("report.json"), rep)
    _say(f"outputs in {args.out}/: {', '.join(rep['files'])}")
    return EXIT_OK


def _ruled_input(args):
    from .flank_milling.ruled import EXAMPLES, RuledSurface

    if args.example:
        return _example(EXAMPLES, args.example, "ruled example"), f"example {args.example}"
    f = _step_face(args)
    tol = args.fit_ruled if args.fit_ruled is not None else 1e-6
    s = RuledSurface.from_surface(f.surface, tolerance=tol, name=f.name)
    return s, f"face {f.index} '{f.name}' of {args.part} (deviation from ruled: {s.source_deviation:.3g} mm)"


def cmd_flank(args) -> int:
    import numpy as np

    from .cutters import FlatEndMill, parse_cutter
    from .flank_milling import interference, tool_setting

    t0 = time.perf_counter()
    cutter = parse_cutter(args.tool)
    if not isinstance(cutter, FlatEndMill):
        raise InputError("flank milling needs a cylindrical cutter: cyl:D=.. (or flat:D=..)")
    R = cutter.D / 2
    surf, desc = _ruled_input(args)
    if not 0.0 <= args.rule <= 1.0:
        raise InputError(f"--rule {args.rule:g} is outside [0, 1] (fraction of the u range)")
    if args.side not in (1, -1):
        raise InputError("--side must be +1 or -1")
    lo, hi = surf.u_range
    u_p = lo + args.rule * (hi - lo)
    st_ = tool_setting(surf, u_p, R, args.setting, side=args.side)
    t_set = time.perf_counter() - t0
    e = interference(surf, st_)
    from .flank_milling import compare_settings

    comparison = compare_settings(surf, u_p, R, side=args.side)
    rep = {"command": "flank", "surface": desc, "tool": cutter.to_dict(), "R_mm": R, "rule": args.rule, "u_p": u_p,
           "setting": st_.report(), "interference": e.report(), "time_setting_s": t_set,
           "all_settings_on_this_rule": comparison}
    _say(f"surface: {desc}; rule u = {u_p:.6g} (fraction {args.rule:g}), h_p = {st_.frame.h_p:.4f} mm, "
         f"alpha0 = {st_.frame.alpha0_deg:.4f} deg; tool {cutter.spec()} (R = {R:g} mm), side {args.side:+d}")
    _say(f"{args.setting}: gamma = {st_.gamma_deg:.6f} deg, h0 = {st_.h0:.6f} mm, h1 = {st_.h1:.6f} mm"
         + (f", phi = {st_.phi_deg:.6f} deg" if st_.phi_deg else ""))
    for k in ("M0", "M1", "M2"):
        if k in st_.contacts:
            _say(f"  {k} = ({', '.join(f'{x:.5f}' for x in st_.contacts[k])}) mm")
    w = e.worst()
    _say(f"interference: max gouge {e.max_gouge:.6g} mm, max undercut {e.max_undercut:.6g} mm, worst at v = "
         f"{w['v']:.4f}, xyz ({', '.join(f'{x:.4f}' for x in w['xyz'])}) mm")
    _say("all settings on this rule: " + "; ".join(
        f"{k} {v['max_abs_mm']:.4g} mm" if "max_abs_mm" in v else f"{k} not admissible" for k, v in comparison.items()))
    with Staging(args.out) as st:
        files = []
        if args.whole:
            from .flank_milling.path import envelope_deviation, envelope_surface, flank_path
            from .geometry.face import Face
            from .occ import write_step, write_stl
            from .progress import Bar

            with Bar("settings along the surface") as bar:
                path = flank_path(surf, R, args.setting, side=args.side, tolerance=args.tol,
                                  progress=lambda i, n: bar.update(i, n))
            _write_flank_cl(st, path, cutter)
            env = envelope_surface(path, tolerance=args.envelope_tol)
            env_face = Face(env.surface, name="flank_envelope")
            write_step(st.path("envelope.step"), [env_face])
            write_stl(st.path("envelope.stl"), [env_face], linear_deflection=0.01)
            dev = envelope_deviation(path, env.surface)
            from .viz import render_deviation

            lo_, hi_ = surf.u_range
            mean_n = surf.normal(np.linspace(lo_, hi_, 9), np.full(9, 0.5)).mean(axis=0) * args.side
            render_deviation(dev, st.path("deviation.png"), vtp_path=st.path("deviation.vtp"),
                             title=f"nominal vs envelope of {cutter.spec()} ({args.setting}); red gouge, blue undercut",
                             tolerance=args.tol, view_direction=mean_n)
            files += ["toolpath.csv", "toolpath.apt", "envelope.step", "envelope.stl", "deviation.png", "deviation.vtp"]
            rep["whole"] = {**path.report(), "envelope_fit": env.report(), "deviation_from_envelope": dev.report()}
            _say(f"whole surface: {len(path.settings)} rules, max gouge {path.max_gouge:.4g} mm, max undercut "
                 f"{path.max_undercut:.4g} mm (rule u = {path.worst['rule_u']:.5g}); envelope {env.surface.shape[0]}x"
                 f"{env.surface.shape[1]} poles, fit error {env.max_error:.3g} mm; nominal vs envelope max "
                 f"{dev.max_abs:.4g} mm" + (f"; {len(path.discontinuities)} setting jump(s)" if path.discontinuities else ""))
        if args.study:
            from .flank_milling.study import parameter_study
            from .viz.plots import plot_ratio_curves

            data = parameter_study()
            plot_ratio_curves(data["by_h_p"], st.path("study_h_p.png"), label_key="h_p_mm",
                              label_fmt="h_p = {:g} mm", title="hyperbolic paraboloid, alpha0 = 30 deg (fig. 9)")
            plot_ratio_curves(data["by_alpha0"], st.path("study_alpha0.png"), label_key="alpha0_deg",
                              label_fmt="alpha0 = {:g} deg", title="hyperbolic paraboloid, h_p = 80 mm (fig. 10)")
            files += ["study_h_p.png", "study_alpha0.png"]
            rep["study"] = data
            _say(f"parameter study: smallest ratio standard/optimum {data['min_ratio']:.3g}")
        if args.radius_range is not None:
            from .flank_milling.path import radius_range

            rr = radius_range(surf, args.radius_range, kind=args.setting, side=args.side)
            rep["radius_range"] = rr
            _say(f"radius range for {args.radius_range:g} mm: " + (
                f"R in [{rr['R_min_mm']:.4g}, {rr['R_max_mm']:.4g}] mm after {len(rr['iterations'])} evaluations"
                if rr["feasible"] else rr["message"]))
        rep["files"] = files + ["report.json"]
        rep["time_s"] = time.perf_counter() - t0
        _write_json(st.path("report.json"), rep)
    _say(f"outputs in {args.out}/: {', '.join(rep['files'])}")
    if args.whole and max(rep["whole"]["max_gouge_mm"], rep["whole"]["max_undercut_mm"]) > args.tol:
        _say(f"tolerance {args.tol:g} mm NOT met on the whole surface")
        return EXIT_TOLERANCE
    return EXIT_OK


def _write_flank_cl(st, path, cutter):
    import csv

    with open(st.path("toolpath.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["rule", "u", "tip_x", "tip_y", "tip_z", "i", "j", "k", "gamma_deg", "h0_mm"])
        for k, (u, p, a, s) in enumerate(zip(path.u, path.tip, path.axis, path.settings)):
            w.writerow([k, f"{u:.10g}", *(f"{x:.6f}" for x in p), *(f"{x:.9f}" for x in a), f"{s.gamma_deg:.6f}",
                        f"{s.h0:.6f}"])
    lines = [f"$$ machsurf_cad flank path: {path.kind}, {len(path.u)} rules, R = {path.R:g} mm", "PARTNO/MACHSURF_FLANK",
             "UNITS/MM", f"CUTTER/{cutter.D:.4f},0.0000,0.0000,0.0000,0.0000,0.0000,{path.length:.4f}", "MULTAX/ON"]
    a0, p0 = path.axis[0], path.tip[0]
    lines += ["RAPID", "GOTO/{:.5f},{:.5f},{:.5f},{:.7f},{:.7f},{:.7f}".format(*(p0 - 10 * a0), *a0)]
    lines += ["GOTO/{:.5f},{:.5f},{:.5f},{:.7f},{:.7f},{:.7f}".format(*p, *a) for p, a in zip(path.tip, path.axis)]
    lines.append("FINI")
    st.path("toolpath.apt").write_text("\n".join(lines) + "\n")


def cmd_envelope(args) -> int:
    import numpy as np

    from .cutters import parse_cutter
    from .sweep import make_envelope
    from .sweep.examples import EXAMPLES, load_path
    from .sweep.passes import build_chain, max_theta

    t0 = time.perf_counter()
    cutter = parse_cutter(args.tool)
    if args.path:
        motion = load_path(args.path)
    else:
        motion = _example(EXAMPLES, args.example or "sine", "example motion")
    if args.passes < 1:
        raise InputError("--passes must be >= 1")
    try:
        thetas = [float(x) for x in str(args.theta).split(",")]
    except ValueError:
        raise InputError(f"--theta must be degrees, e.g. 0 or 0,15,-10; got {args.theta!r}") from None
    for th in thetas:
        if not -180 < th < 180:
            raise InputError(f"theta {th:g} deg is outside (-180, 180)")
    first = make_envelope(motion, cutter, side=args.side)
    chain = build_chain(first, args.passes, continuity=args.continuity,
                        theta_deg=thetas if len(thetas) > 1 else thetas[0], tolerance=args.tol)
    rep = chain.report()
    rep.update({"command": "envelope", "tool": cutter.to_dict(), "motion": motion.label})
    _say(f"tool {cutter.spec()}, motion: {motion.label}; {args.passes} pass(es), {args.continuity.upper()}, "
         f"theta {args.theta} deg")
    for prow in rep["passes"]:
        f = prow["fit"]
        _say(f"{prow['name']}: {f['poles'][0]}x{f['poles'][1]} poles, fit error {f['max_error_mm']:.3g} mm "
             f"(tol {args.tol:g})")
    for srow in rep["seams"]:
        ex, fi = srow["exact"], srow["fitted"]
        _say(f"seam {srow['between'][0] + 1}-{srow['between'][1] + 1}: exact gap {ex['max_gap_mm']:.3g} mm, angle "
             f"{ex['max_normal_angle_deg']:.3g} deg; fitted faces gap {fi['max_gap_mm']:.3g} mm, angle "
             f"{fi['max_normal_angle_deg']:.3g} deg")
    if args.passes > 1 and not args.no_theta_scan:
        rep["max_theta_deg"] = max_theta(first, continuity=args.continuity)
        _say(f"largest |theta| without fold-back or loss of envelope (5 deg steps): {rep['max_theta_deg']:g} deg")
    with Staging(args.out) as st:
        from .geometry.face import Face
        from .occ import write_step, write_stl

        faces = [Face(f.surface, name=e.name) for e, f in zip(chain.passes, chain.fits)]
        write_step(st.path("envelopes.step"), faces)
        write_stl(st.path("envelopes.stl"), faces, linear_deflection=args.tol * 10)
        files = ["envelopes.step", "envelopes.stl"]
        if not args.no_render and args.passes > 1:
            from .viz import render_zebra

            other = "g0" if args.continuity == "g1" else "g1"
            alt = build_chain(first, args.passes, continuity=other,
                              theta_deg=thetas if len(thetas) > 1 else thetas[0], tolerance=args.tol)

            def panel(ch):
                out = []
                for fit in ch.fits:
                    s = fit.surface
                    us, vs = s.sample_grid(60, 120)
                    d = s.derivatives_grid(us, vs, 1)
                    nn = np.cross(d.su, d.sv)
                    out.append((d.point, nn / np.linalg.norm(nn, axis=-1, keepdims=True)))
                return out

            g1 = chain if args.continuity == "g1" else alt
            g0 = alt if args.continuity == "g1" else chain
            ang = max(s["fitted"]["max_normal_angle_deg"] for s in g0.report()["seams"])
            render_zebra([(f"G0 (crease up to {ang:.3g} deg)", panel(g0)),
                          (f"G1 (seam angle {max(s['fitted']['max_normal_angle_deg'] for s in g1.report()['seams']):.2g}"
                           " deg)", panel(g1))], st.path("zebra.png"))
            files.append("zebra.png")
        rep["files"] = files + ["report.json"]
        rep["time_s_total"] = time.perf_counter() - t0
        _write_json(st.path("report.json"), rep)
    _say(f"outputs in {args.out}/: {', '.join(rep['files'])}")
    return EXIT_OK


def cmd_demo(args) -> int:
    from .demo import run_demo

    return run_demo(Path(args.out), say=_say)


# ----------------------------------------------------------------------------- entry point
def _add_face_input(p, example_help: str, part_help: str = "STEP file (or use --example)") -> None:
    p.add_argument("part", nargs="?", help=part_help)
    p.add_argument("--example", help=example_help)
    p.add_argument("--face", type=int, default=0, help="face index (default 0)")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="machsurf", description="Free-form surface machining geometry (mm, degrees).")
    p.add_argument("--version", action="version", version=f"machsurf_cad {__version__}")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    d = sub.add_parser("demo", help="main job on the embedded example part: STEP, STL, deviation map, report")
    d.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    d.set_defaults(func=cmd_demo)

    i = sub.add_parser("info", help="faces of a STEP part: types, degrees, bounds, areas")
    i.add_argument("part", help="STEP file")
    i.add_argument("-o", "--out", default="out/info", help="folder for report.json (default: out/info)")
    i.set_defaults(func=cmd_info)

    n = sub.add_parser("inspect", help="deviation of a candidate (STEP face or STL) from a nominal STEP face")
    n.add_argument("nominal", help="nominal STEP file")
    n.add_argument("candidate", help="candidate STEP (.step/.stp) or mesh (.stl)")
    n.add_argument("--face", type=int, default=0, help="face index in the nominal file (default 0)")
    n.add_argument("--candidate-face", type=int, default=None, help="face index in a candidate STEP (default: --face)")
    n.add_argument("--tol", type=float, default=None, help="tolerance, max |deviation| in mm (exit 2 if not met)")
    n.add_argument("--samples", type=int, default=200, help="grid samples per direction on a STEP candidate")
    n.add_argument("--no-render", action="store_true", help="skip the PNG/VTP (numbers only)")
    n.add_argument("-o", "--out", default="out/inspect", help="output folder (default: out/inspect)")
    n.set_defaults(func=cmd_inspect)
    m = sub.add_parser("machining-surface", help="guiding S1 and orientation S2 surfaces of a face (Table 1)")
    _add_face_input(m, "example surface instead of a STEP: bezier5, blade, hypar, liu, eq18")
    m.add_argument("--tool", required=True, help="ball:D=..|flat:D=..|bull:D=..,r=.. (mm)")
    m.add_argument("--axes", type=int, default=5, help="3 or 5 (default 5)")
    m.add_argument("--strategy", default="planes:x", help="planes:x|y|z|a,b,c or iso:u|v (default planes:x)")
    m.add_argument("--lead", type=float, default=0.0, help="lead angle Omega_t, degrees (5 axes)")
    m.add_argument("--tilt", type=float, default=0.0, help="tilt angle Omega_n, degrees (5 axes)")
    m.add_argument("--axis", default=None, help="fixed axis x,y,z for 3 axes / 3+2 (default 0,0,1)")
    m.add_argument("--tip", action="store_true", help="3 axes: S1 at the tool tip instead of the torus plane")
    m.add_argument("--tol", type=float, default=1e-3, help="fit tolerance, max-norm mm (default 0.001)")
    m.add_argument("--degree", type=int, default=3, help="fit degree in u and v (default 3)")
    m.add_argument("--max-poles", type=int, default=40000, help="pole budget per surface (default 40000)")
    m.add_argument("--loops", choices=["error", "flag", "trim"], default="error",
                   help="on loops: error (default), flag (export and report) or trim (cut interior regions away)")
    m.add_argument("--stl-deflection", type=float, default=0.01, help="STL linear deflection, mm (default 0.01)")
    m.add_argument("--toolpath", action="store_true", help="also write CL files (CSV, APT CLDATA)")
    m.add_argument("--stepover", type=float, default=2.0, help="distance between passes, mm (default 2)")
    m.add_argument("--chordal", type=float, default=0.01, help="chordal tolerance of CL points, mm (default 0.01)")
    m.add_argument("-o", "--out", default="out/machining_surface", help="output folder")
    m.set_defaults(func=cmd_machining_surface)

    e = sub.add_parser("reff", help="effective cutter radius and step-over maps over a face")
    _add_face_input(e, "example surface instead of a STEP: blade, bezier5, ...")
    e.add_argument("--tool", required=True, help="bull:D=..,r=.. | flat:D=.. | ball:D=.. (mm)")
    e.add_argument("--compare", default="ball", help="reference cutter: ball (same D, default), a cutter string, none")
    e.add_argument("--direction", default="0", help="machining direction(s) theta in degrees: 45 | -45,0,45,90 | all")
    e.add_argument("--grid", type=int, default=256, help="samples per parameter direction (default 256)")
    e.add_argument("--scallop", type=float, default=None, help="scallop height, mm: adds step-over maps")
    e.add_argument("--axes", type=int, default=3, help="3 (axis z, default) or 5 (lead/tilt)")
    e.add_argument("--lead", type=float, default=0.0, help="lead angle, degrees (5 axes)")
    e.add_argument("--tilt", type=float, default=0.0, help="tilt angle, degrees (5 axes)")
    e.add_argument("--no-render", action="store_true", help="numbers only")
    e.add_argument("-o", "--out", default="out/reff", help="output folder")
    e.set_defaults(func=cmd_reff)

    f = sub.add_parser("flank", help="flank milling settings of a cylindrical cutter on a ruled surface")
    _add_face_input(f, "eq18 | hypar | liu (the paper's surfaces, exact)", "STEP file with a ruled face (or use --example)")
    f.add_argument("--fit-ruled", type=float, default=None, help="accept a non-ruled face within this many mm")
    f.add_argument("--tool", default="cyl:D=20", help="cylindrical cutter, e.g. cyl:D=80 (mm)")
    f.add_argument("--rule", type=float, default=0.5, help="rule position as a fraction of the u range [0, 1]")
    f.add_argument("--setting", default="optimum",
                   choices=["standard-tangent", "standard-distributed", "optimum", "minimax"])
    f.add_argument("--side", type=int, default=1, help="+1: tool on the side of S_u x S_v, -1: the other")
    f.add_argument("--whole", action="store_true", help="settings on the whole surface: CL files, envelope, map")
    f.add_argument("--tol", type=float, default=0.01, help="whole-surface tolerance and rule step criterion, mm")
    f.add_argument("--envelope-tol", type=float, default=1e-3, help="envelope fit tolerance, mm")
    f.add_argument("--study", action="store_true", help="the paper's parameter study plots (figs 9 and 10)")
    f.add_argument("--radius-range", type=float, default=None, metavar="TOL",
                   help="smallest and largest R keeping the whole surface within TOL mm")
    f.add_argument("-o", "--out", default="out/flank", help="output folder")
    f.set_defaults(func=cmd_flank)

    v = sub.add_parser("envelope", help="swept envelopes of a rotational tool and G1/G0 adjacent passes")
    v.add_argument("--tool", required=True, help="cyl:D=.. | cone:D=..,angle=.. | drum:D=..,Rp=..,L=.. | "
                                                 "barrel:... | ball:D=.. (mm, degrees)")
    v.add_argument("--path", help="JSON path file: {points: [[x,y,z]...], axes: [[i,j,k]...]} (tip points, mm)")
    v.add_argument("--example", help="example motion instead of --path: sine (default), line, helix")
    v.add_argument("--passes", type=int, default=2, help="number of passes (default 2)")
    v.add_argument("--continuity", choices=["g0", "g1"], default="g1", help="between passes (default g1)")
    v.add_argument("--theta", default="0", help="rotation of each next axis about n1, degrees (one, or one per seam)")
    v.add_argument("--side", type=int, default=1, help="envelope sheet: +1 (side of S_a x S_t) or -1")
    v.add_argument("--tol", type=float, default=1e-3, help="fit tolerance per pass, mm (default 0.001)")
    v.add_argument("--no-theta-scan", action="store_true", help="skip the scan of the admissible theta range")
    v.add_argument("--no-render", action="store_true", help="skip the zebra picture")
    v.add_argument("-o", "--out", default="out/envelope", help="output folder")
    v.set_defaults(func=cmd_envelope)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return EXIT_INPUT
    try:
        return int(args.func(args))
    except MachsurfError as exc:
        print(f"machsurf: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("machsurf: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
