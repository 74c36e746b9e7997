"""The ``verify`` job, and the check every path-writing job makes before writing a tool path."""

from __future__ import annotations

import dataclasses

from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish, write_toolpath
from .inputs import part_faces, shank, toolpath_and_cutter
from .specs import VerifyJob

COLLISION_CLEARANCE_MM = 0.01
"""The least distance rapids, shank and holder keep from the part in the jobs (or the gouge tolerance when
smaller): a large gouge tolerance (flank's interference ``--tol``) is not a clearance."""


def check_path(
    st: Staging,
    say: Say,
    tp,
    faces,
    *,
    tolerance: float,
    render: bool,
    cutter=None,
    step_mm=None,
    step_deg=1.0,
    spacing_mm=None,
    progress=None,
    chunks: int = 1,
):
    """Verify ``tp`` against ``faces``; say and draw the result; return ``(VerifyResult, report)``.
    ``chunks`` > 1 splits the placements (over the Dask cluster when the job runs in a batch)."""
    from ..batchrun.runner import chunk_map
    from ..gougecheck import verify

    map_chunks = chunk_map(chunks)
    res = verify(
        faces,
        tp,
        cutter,
        tolerance=tolerance,
        step_mm=step_mm,
        step_deg=step_deg,
        spacing_mm=spacing_mm,
        progress=progress,
        chunks=int(chunks),
        map_chunks=map_chunks,
        clearance_mm=min(tolerance, COLLISION_CLEARANCE_MM),
    )
    rep = res.report()
    say(
        f"tool body against {rep['n_faces']} face(s) ({rep['n_placements_checked']} placements, motion steps "
        f"{res.step_mm:.3g} mm / {res.step_deg:g} deg, between them at most {res.motion_bound_mm:.2g} mm deeper; "
        f"part sampled every {res.spacing_mm:.3g} mm and refined on the "
        f"exact faces): {rep['n_gouging_positions']} gouging position(s), max gouge {rep['max_gouge_mm']:.4g} mm "
        f"(tol {tolerance:g}), {rep['n_collisions']} collision(s)"
        + (f", min clearance {rep['min_clearance_mm']:.4g} mm" if rep["min_clearance_mm"] is not None else "")
    )
    for w in rep["worst"][:3]:
        d = w["depth_mm"]
        where = (
            f"{d:.4g} mm into" if d >= 0 else f"{-d:.4g} mm from (closer than the {res.clearance_mm:g} mm clearance)"
        )
        say(
            f"  {w['status']} at position {w['index']} (pass {w['pass']}, {w['move']}): {where} "
            f"face {w['face_index']} '{w['face']}' near ({', '.join(f'{x:.3f}' for x in w['part_point_mm'])})"
        )
    for w in rep["warnings"]:
        say(f"warning: {w}")
    if render:
        from ..viz import render_gouge_map
        from ..viz.plots import plot_path_distance

        worst = [w["part_point_mm"] for w in rep["worst"]]
        render_gouge_map(
            res.sample_points,
            res.sample_depth,
            st.path("verify_part.png"),
            vtp_path=st.path("verify_part.vtp"),
            tolerance=tolerance,
            worst=worst,
            title=f"{tp.name}: tool depth into the part (max {rep['max_gouge_mm']:.3g} mm)",
        )
        plot_path_distance(
            res.cut_distance,
            res.status,
            st.path("verify_path.png"),
            tolerance=tolerance,
            title=f"{tp.name}: smallest distance between the cutting part and the part",
        )
    return res, rep


def _write_checked(st: Staging, say: Say, tp, faces, spec, *, tolerance: float, render: bool):
    """Check ``tp`` against the part, then write it unless it gouges (``spec.allow_gouge`` writes it
    anyway, listed in the report). Returns ``(verify report, exit code, the path written or None)``."""
    res, rep = check_path(st, say, tp, faces, tolerance=tolerance, render=render)
    if rep["clean"]:
        write_toolpath(st, tp, spec)
        return rep, EXIT_OK, tp
    if spec.trim_gouges:  # keep the clear stretches, relinked; rapids that still collide go up step by step
        from ..gougecheck import clear_runs, verify

        clearance = spec.clearance
        for _ in range(4):
            cut = clear_runs(tp, res, clearance=clearance)
            if cut is None:
                break
            again = verify(faces, cut, tolerance=tolerance, clearance_mm=min(tolerance, COLLISION_CLEARANCE_MM))
            if again.clean:
                n0, n1 = tp.n_cut, cut.n_cut
                say(
                    f"tool path cut down to its clear stretches (--trim-gouges): {n1} of {n0} cutting positions in "
                    f"{cut.n_passes} pass(es), linking {clearance:g} mm along the axis; checked again: clean, max "
                    f"gouge {again.max_gouge:.3g} mm"
                )
                write_toolpath(st, cut, spec)
                rep["trimmed"] = {
                    "n_cut_kept": n1,
                    "n_cut_before": n0,
                    "n_passes": cut.n_passes,
                    "clearance_mm": clearance,
                    "recheck": again.report(),
                }
                return rep, EXIT_OK, cut
            clearance *= 2.0
        say("tool path NOT written: no clear stretch is left, or its linking moves collide (--trim-gouges)")
        return rep, EXIT_TOLERANCE, None
    if spec.allow_gouge:
        write_toolpath(st, tp, spec)
        say("tool path written with its gouges and collisions (--allow-gouge): see verify.worst in the report")
        return rep, EXIT_OK, tp
    say(
        "tool path NOT written: it gouges or collides beyond the tolerance (--trim-gouges keeps the clear "
        "stretches, --allow-gouge writes it anyway)"
    )
    return rep, EXIT_TOLERANCE, None


def write_checked_toolpath(st: Staging, say: Say, tp, faces, spec, *, tolerance: float, render: bool):
    """Check ``tp`` against the part and write it unless it gouges (:func:`_write_checked`); with
    ``spec.simulate`` the written path's cut is simulated on the part too (report ``simulate``; a simulated
    gouge beyond ``tolerance`` exits 2). Returns ``(verify report, exit code)``."""
    rep, code, written = _write_checked(st, say, tp, faces, spec, tolerance=tolerance, render=render)
    if getattr(spec, "simulate", False):
        if written is None:
            say("--simulate: nothing written, nothing simulated")
        else:
            from .run_simulate import simulate_path

            sim, srep = simulate_path(
                st, say, written, faces, tolerance=tolerance, render=render, resolution=spec.simulate_resolution
            )
            rep["simulate"] = srep
            if sim.gouged and not spec.allow_gouge:
                say(f"the simulated cut gouges {sim.max_gouge:.4g} mm (tol {tolerance:g}): exit 2")
                code = EXIT_TOLERANCE
    return rep, code


def run_verify(spec: VerifyJob, out, say: Say, progress=None) -> JobOutcome:
    path, tp, cutter = toolpath_and_cutter(spec.toolpath, spec.tool, say)
    cutter = dataclasses.replace(cutter, shank=shank(spec.shank, "shank"), holder=shank(spec.holder, "holder"))
    if cutter.holder is not None and cutter.shank is not None and cutter.holder.diameter < cutter.shank.diameter:
        say("warning: the holder is narrower than the shank")
    faces = part_faces(spec.part, spec.faces)
    say(
        f"part: {spec.part} ({len(faces)} face(s) checked); tool path: {path.name}, {tp.n_positions} positions, "
        f"{tp.n_passes} pass(es); tool {cutter.spec()}"
        + (f", shank D{cutter.shank.diameter:g} L{cutter.shank.length:g}" if cutter.shank else "")
        + (f", holder D{cutter.holder.diameter:g} L{cutter.holder.length:g}" if cutter.holder else "")
    )
    with Staging(out) as st:
        res, rep = check_path(
            st,
            say,
            tp,
            faces,
            tolerance=spec.tol,
            render=spec.render,
            cutter=cutter,
            step_mm=spec.step,
            step_deg=spec.step_deg,
            spacing_mm=spec.spacing,
            progress=progress,
            chunks=int(spec.chunks),
        )
        code = EXIT_OK if res.clean else EXIT_TOLERANCE
        say("clean" if res.clean else "NOT clean: gouges or collisions beyond the tolerance")
        skipped = tp.info.get("skipped_statements") or {}
        if skipped:
            say("warning: APT statements skipped: " + ", ".join(f"{k} x{n}" for k, n in sorted(skipped.items())))
        report = {
            "part": str(spec.part),
            "toolpath": str(path),
            "tool": cutter.to_dict(),
            "verify": rep,
            "apt_statements_skipped": skipped,
        }
        outcome = finish(st, "verify", report, code, res)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome
