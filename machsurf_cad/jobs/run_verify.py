"""The ``verify`` job, and the check every path-writing job makes before writing a tool path."""

from __future__ import annotations

import dataclasses

from ..pathcheck import COLLISION_CLEARANCE as COLLISION_CLEARANCE_MM
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish, write_toolpath
from .inputs import part_faces, shank, toolpath_and_cutter
from .specs import VerifyJob


def check_path(
    st: Staging,
    say: Say,
    tp,
    faces,
    *,
    tolerance: float,
    render: bool,
    cutter=None,
    step=None,
    angle_step=1.0,
    spacing=None,
    progress=None,
    chunks: int = 1,
):
    """Verify ``tp`` against ``faces``; say and draw the result; return ``(VerifyResult, report)``.
    ``chunks`` > 1 splits the placements (over the Dask cluster when the job runs in a batch)."""
    from ..batchrun.runner import chunk_map
    from ..gougecheck import verify

    res = verify(
        faces,
        tp,
        cutter,
        gouge_tolerance=tolerance,
        step=step,
        angle_step=angle_step,
        spacing=spacing,
        progress=progress,
        chunks=int(chunks),
        map_chunks=chunk_map(chunks),
        clearance=min(tolerance, COLLISION_CLEARANCE_MM),
    )
    rep = res.report()
    _say_check(say, res, rep, tolerance)
    if render:
        _draw_check(st, tp, res, rep, tolerance)
    return res, rep


def _say_check(say: Say, res, rep: dict, tolerance: float) -> None:
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


def _draw_check(st: Staging, tp, res, rep: dict, tolerance: float) -> None:
    from ..viz import render_gouge_map
    from ..viz.plots import plot_path_distance

    render_gouge_map(
        res.sample_points,
        res.sample_depth,
        st.path("verify_part.png"),
        vtp_path=st.path("verify_part.vtp"),
        tolerance=tolerance,
        worst=[w["part_point_mm"] for w in rep["worst"]],
        title=f"{tp.name}: tool depth into the part (max {rep['max_gouge_mm']:.3g} mm)",
    )
    plot_path_distance(
        res.cut_distance,
        res.status,
        st.path("verify_path.png"),
        tolerance=tolerance,
        title=f"{tp.name}: smallest distance between the cutting part and the part",
        move=tp.move,
    )


def on_gouge(spec) -> str:
    """The body check's policy of a path-writing job: ``trim`` (--trim-gouges), ``allow`` (--allow-gouge)
    or ``refuse``."""
    trim = spec.trim_gouges or getattr(spec, "tilt_away", False)  # tilting away trims what it cannot clear
    return "trim" if trim else "allow" if spec.allow_gouge else "refuse"


def _write_checked(st: Staging, say: Say, tp, faces, spec, *, tolerance: float, render: bool, check=None,
                   stem: str = "toolpath"):  # fmt: skip
    """Check ``tp`` against the part (:func:`machsurf_cad.pathcheck.check_toolpath`), then write what may
    be written: the clean path, its clear stretches (``spec.trim_gouges``), or the gouging path
    (``spec.allow_gouge``, listed in the report). Returns ``(verify report, exit code, the path written or
    None)``."""
    from ..pathcheck import check_toolpath

    pc = check or check_toolpath(
        tp, faces, gouge_tolerance=tolerance, on_gouge=on_gouge(spec), clearance=spec.clearance
    )
    rep = pc.report()  # the check's report, its verdict and any trimmed recheck
    _say_check(say, pc.check, rep, tolerance)
    if render:
        _draw_check(st, tp, pc.check, rep, tolerance)
    if pc.toolpath is not None:
        write_toolpath(st, pc.toolpath, spec, stem)
        _say_rapids(say, rep.get("rapids"), "n_rapids_at_feed" in pc.toolpath.info)
    if pc.verdict == "trimmed":
        cut, again = pc.toolpath, pc.recheck
        assert cut is not None and again is not None
        dense = pc.trimmed_from if pc.trimmed_from is not None else tp
        split = f" (the planned {tp.n_cut} with points inserted along long moves)" if dense is not tp else ""
        say(
            f"tool path cut down to its clear stretches: {cut.n_cut} of {dense.n_cut} cutting "
            f"positions{split} in {cut.n_passes} pass(es); links checked clear: "
            f"{cut.info.get('links_direct', 0)} direct, "
            f"{cut.info.get('links_over_surface', 0)} over the {cut.info.get('clearance_surface', 'plane')} around "
            f"the part, {len(cut.info.get('runs_reversed', []))} stretch(es) cut backwards and "
            f"{len(cut.info.get('runs_visited_later', []))} visited later to be reached, "
            f"{len(cut.info.get('runs_left_out', []))} stretch(es) left out that no clear link reaches; "
            f"checked again: clean, max gouge {again.max_gouge:.3g} mm"
        )
    elif pc.verdict == "gouges allowed":
        say("tool path written with its gouges and collisions (--allow-gouge): see verify.worst in the report")
    elif pc.verdict == "refused" and pc.beyond_axis_limit:
        say(
            f"tool path NOT written: {pc.beyond_axis_limit} of its {tp.n_positions} positions lie past the rotary "
            "limit, and no stretch within it and clear of the part can be linked"
        )
    elif pc.verdict == "refused":
        say(
            "tool path NOT written: no clear stretch is left, or no clear link reaches or leaves any of them "
            "(trimmed: --trim-gouges or tilt away)"
            if getattr(spec, "trim_gouges", False) or getattr(spec, "tilt_away", False)
            else "tool path NOT written: it gouges or collides beyond the tolerance (--trim-gouges keeps the clear "
            "stretches, --allow-gouge writes it anyway)"
        )
    return rep, (EXIT_TOLERANCE if pc.toolpath is None else EXIT_OK), pc.toolpath


def _say_rapids(say: Say, rapids: dict | None, measured: bool) -> None:
    """The links' line from the report's ``rapids`` (when the written path's rapids were ``measured``):
    their lengths at the plunge feed (where the whole tool comes within the clearance) and rapid, the rapids
    slowed and the moves split there, and the least distance the rapids keep."""
    if not (measured and rapids):
        return
    least = rapids["rapid_distance_min_mm"]
    keep = "all over the clearance surface" if least is None else f"the least {least:.4g} mm from the part"
    say(
        f"links: {rapids['link_length_at_feed_mm']:.4g} mm at the plunge feed, where the whole tool (holder "
        f"included) comes within the clearance {rapids['clearance_mm']:g} mm of the part "
        f"({rapids['n_rapids_at_feed']} rapid(s) slowed, {rapids['n_links_split']} link move(s) split there); "
        f"{rapids['rapid_length_mm']:.4g} mm rapid, {keep}"
    )


def write_checked_toolpath(st: Staging, say: Say, tp, faces, spec, *, tolerance: float, render: bool, check=None,
                           stem: str = "toolpath"):  # fmt: skip
    """Check ``tp`` against the part and write it unless it gouges (:func:`_write_checked`); with
    ``spec.simulate`` the written path's cut is simulated on the part too (report ``simulate``; a simulated
    gouge beyond ``tolerance`` exits 2). Returns ``(verify report, exit code)``."""
    rep, code, written = _write_checked(st, say, tp, faces, spec, tolerance=tolerance, render=render, check=check,
                                        stem=stem)  # fmt: skip
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
            tolerance=spec.gouge_tolerance,
            render=spec.render,
            cutter=cutter,
            step=spec.step,
            angle_step=spec.angle_step,
            spacing=spec.spacing,
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
