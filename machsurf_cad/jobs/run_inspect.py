"""The ``info`` and ``inspect`` jobs."""

from __future__ import annotations

import time
from pathlib import Path

from ..errors import InputError
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish
from .specs import InfoJob, InspectJob


def run_info(spec: InfoJob, out, say: Say, progress=None) -> JobOutcome:
    from ..occ import step_face_summaries

    t0 = time.perf_counter()
    summaries = step_face_summaries(spec.part)  # no NURBS conversion: a 250-face part in about a second
    rows = []
    n_bodies = len({r["body"] for r in summaries if r["body"] >= 0})
    say(f"{spec.part}: {len(summaries)} face(s)" + (f" in {n_bodies} bodies (solids)" if n_bodies > 1 else ""))
    btxt = f"{'body':>4} " if n_bodies > 1 else ""
    say(f"{'idx':>3}  {btxt}{'name':<16} {'type':<18} {'deg':>5} {'poles':>9} {'trim':>4} {'area mm2':>11}  uv bounds")
    for r in summaries:
        deg, poles = r["degrees"], r["poles"]
        b = r["uv_bounds"]
        rows.append(
            {
                "index": r["index"],
                "name": r["name"],
                "source_type": r["source_type"],
                "degree_u": deg[0] if deg else None,
                "degree_v": deg[1] if deg else None,
                "poles_u": poles[0] if poles else None,
                "poles_v": poles[1] if poles else None,
                "rational": r["rational"],
                "trimmed": r["trimmed"],
                "n_loops": r["n_loops"] if r["trimmed"] else 0,
                "uv_bounds": b,
                "area_mm2": r["area_mm2"],
                "reversed": r["reversed"],
                "body": r["body"],
            }
        )
        dtxt = f"{deg[0]:>2},{deg[1]:<2}" if deg else f"{'-':>5}"
        ptxt = f"{poles[0]:>4}x{poles[1]:<4}" if poles else f"{'-':>9}"
        say(
            f"{r['index']:>3}  "
            + (f"{r['body']:>4} " if n_bodies > 1 else "")
            + f"{r['name'][:16]:<16} {r['source_type'][:18]:<18} {dtxt} {ptxt} "
            f"{'yes' if r['trimmed'] else 'no':>4} {r['area_mm2']:>11.2f}  "
            f"[{b[0]:.4g}, {b[1]:.4g}] x [{b[2]:.4g}, {b[3]:.4g}]"
        )
    report = {
        "part": str(spec.part),
        "n_faces": len(summaries),
        "n_bodies": n_bodies,
        "faces": rows,
        "time_s": {"total_s": time.perf_counter() - t0},
    }
    with Staging(out) as st:
        outcome = finish(st, "info", report)
    say(f"report: {Path(out) / 'report.json'}")
    return outcome


def _mesh_candidate(path: Path):
    from ..meshsample import subdivide
    from ..occ import read_stl

    pts, tris = read_stl(path)
    return subdivide(pts, tris, 2)


def run_inspect(spec: InspectJob, out, say: Say, progress=None) -> JobOutcome:
    from ..measure import deviation
    from ..occ import read_step_face

    t0 = time.perf_counter()
    nominal = read_step_face(spec.nominal, spec.face)
    cand_path = Path(spec.candidate)
    suffix = cand_path.suffix.lower()
    if suffix == ".stl":
        pts, tris = _mesh_candidate(cand_path)
        result = deviation(
            nominal, pts, tolerance=spec.tolerance, triangles=tris, progress=progress, max_memory_mb=spec.max_memory_mb
        )
        cand_desc = f"STL mesh {cand_path.name} ({tris.shape[0] // 16} triangles, sampled inside triangles)"
    elif suffix in (".step", ".stp"):
        idx = spec.candidate_face if spec.candidate_face is not None else spec.face
        try:
            cand = read_step_face(cand_path, idx)
        except InputError as exc:
            raise InputError(f"candidate: {exc}") from None
        result = deviation(
            nominal,
            cand,
            samples=spec.samples,
            tolerance=spec.tolerance,
            progress=progress,
            max_memory_mb=spec.max_memory_mb,
        )
        cand_desc = f"STEP face {idx} '{cand.name}' of {cand_path.name}"
    else:
        raise InputError(f"candidate must be .step/.stp or .stl, got {cand_path.name}")
    rep = result.report()
    say(f"nominal: face {nominal.index} '{nominal.name}' of {spec.nominal}")
    say(f"candidate: {cand_desc}")
    say(f"points measured: {rep['n_points']}")
    say(f"max |deviation| = {rep['max_abs_mm']:.6g} mm  (max {rep['max_mm']:.6g}, min {rep['min_mm']:.6g})")
    say(f"mean = {rep['mean_mm']:.6g} mm  RMS = {rep['rms_mm']:.6g} mm  p95 |dev| = {rep['p95_abs_mm']:.6g} mm")
    say(
        f"worst at xyz = ({', '.join(f'{x:.4f}' for x in rep['worst_xyz_mm'])}) mm, "
        f"uv = ({rep['worst_uv'][0]:.6f}, {rep['worst_uv'][1]:.6f})"
    )
    if result.outside_trim is not None:
        n_out = int(result.outside_trim.sum())
        say(
            f"nominal is trimmed: {n_out} candidate point(s) lie beyond its trimmed region"
            + (
                f" (measured to its boundary edges, up to {rep['max_abs_outside_trimmed_region']:.6g} mm)"
                if n_out
                else ""
            )
        )
    if spec.tolerance is not None:
        say(f"tolerance {spec.tolerance:g} mm: {'met' if result.within_tolerance else 'NOT met'}")
    code = EXIT_TOLERANCE if (spec.tolerance is not None and not result.within_tolerance) else EXIT_OK
    with Staging(out) as st:
        if spec.render:
            from ..viz import render_deviation

            outside = []
            if result.outside_trim is not None and result.outside_trim.any():
                outside = [(result.points[result.outside_trim], "magenta", "beyond the nominal's trimmed region")]
            render_deviation(
                result,
                st.path("deviation.png"),
                vtp_path=st.path("deviation.vtp"),
                title=f"{cand_path.name} vs {nominal.name}",
                tolerance=spec.tolerance,
                extra_points=outside,
            )
        report = {
            "nominal": str(spec.nominal),
            "face": nominal.index,
            "candidate": str(spec.candidate),
            "candidate_desc": cand_desc,
            "deviation": rep,
            "time_s": {"total_s": time.perf_counter() - t0},
        }
        outcome = finish(st, "inspect", report, code, result)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome
