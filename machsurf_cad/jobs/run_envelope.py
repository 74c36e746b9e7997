"""The ``envelope`` job: chained passes as certified faces, seams, zebra picture, tool path."""

from __future__ import annotations

from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish, write_toolpath
from .specs import EnvelopeJob


def run_envelope(spec: EnvelopeJob, out, say: Say, progress=None) -> JobOutcome:
    from ..examples import example
    from ..sweep import envelope, load_path
    from ..toolspec import parse_cutter

    cutter = parse_cutter(spec.tool)
    motion = load_path(spec.path) if spec.path else example(spec.example or "sine", "motion")
    thetas = spec.thetas()
    res = envelope(
        cutter,
        motion,
        passes=spec.passes,
        continuity=spec.continuity,
        theta=thetas if len(thetas) > 1 else thetas[0],
        tolerance=spec.tolerance,
        side=spec.side,
        theta_scan=spec.theta_scan,
        compare=spec.render and spec.passes > 1,
        chordal_tolerance=spec.chordal_tolerance,
        clearance=spec.clearance,
        progress=progress,
    )
    rep = res.report()
    _say_passes(say, spec, res, rep, cutter, motion)
    code = _check_seams(say, spec, res, rep)
    tp = res.toolpath
    say(
        f"tool path: {tp.n_passes} pass(es), {tp.n_cut} cutting positions, chordal error "
        f"{tp.info['chordal_error_measured_mm']:.3g} mm (tol {spec.chordal_tolerance:g})"
    )
    with Staging(out) as st:
        code = max(code, _write_passes(st, say, spec, res, rep))
        if spec.render and res.other is not None:
            _zebra(st, spec, res)
        outcome = finish(st, "envelope", rep, code, result=res)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _say_passes(say: Say, spec: EnvelopeJob, res, rep: dict, cutter, motion) -> None:
    """Say the tool and motion, each pass's fit, each seam's gap and angle, and the largest admissible theta."""
    say(
        f"tool {cutter.spec()}, motion: {motion.label}; {spec.passes} pass(es), {spec.continuity.upper()}, "
        f"theta {spec.theta} deg"
    )
    for prow in rep["passes"]:
        f = prow["fit"]
        say(
            f"{prow['name']}: {f['poles'][0]}x{f['poles'][1]} poles, fit error {f['max_error_mm']:.3g} mm "
            f"(tol {spec.tolerance:g})"
        )
    for srow in rep["seams"]:
        ex, fi = srow["exact"], srow["fitted"]
        say(
            f"seam {srow['between'][0] + 1}-{srow['between'][1] + 1}: exact gap {ex['max_gap_mm']:.3g} mm, angle "
            f"{ex['max_normal_angle_deg']:.3g} deg; fitted faces gap {fi['max_gap_mm']:.3g} mm, angle "
            f"{fi['max_normal_angle_deg']:.3g} deg"
        )
    if res.max_theta_deg is not None:
        say(f"largest |theta| without fold-back or loss of envelope (5 deg steps): {res.max_theta_deg:g} deg")


def _check_seams(say: Say, spec: EnvelopeJob, res, rep: dict) -> int:
    """The seams measured on the written faces (reported, said); the exit code of the continuity asked for."""
    check = res.seam_check(spec.seam_angle_tolerance)
    rep["seams_measured_on_written_faces"] = check
    code = EXIT_OK
    if spec.passes > 1:
        say(
            f"written faces: seams gap up to {check['max_gap_mm']:.3g} mm (limit {check['gap_limit_mm']:.3g}), "
            f"normal angle up to {check['max_normal_angle_deg']:.3g} deg (G1 limit {spec.seam_angle_tolerance:g}): "
            f"{check['achieved']}"
        )
        wanted_met = check["g1_met"] if spec.continuity == "g1" else check["g0_met"]
        if not wanted_met:
            say(f"{spec.continuity.upper()} NOT met by the written faces")
            code = EXIT_TOLERANCE
    return code


def _write_passes(st: Staging, say: Say, spec: EnvelopeJob, res, rep: dict) -> int:
    """Write the envelopes (STEP, STL) and the tool path, checked against ``--part`` if given; the check's code."""
    from ..geometry.face import Face
    from ..occ import write_step, write_stl

    chain = res.chain
    tp = res.toolpath
    faces = [Face(f.surface, name=e.name) for e, f in zip(chain.passes, chain.fits)]
    write_step(st.path("envelopes.step"), faces)
    write_stl(st.path("envelopes.stl"), faces, linear_deflection=spec.tolerance * 10)
    if spec.part:  # the passes' tool path against every face of the part they are for
        from .inputs import part_faces
        from .run_verify import write_checked_toolpath

        rep["verify"], vcode = write_checked_toolpath(
            st, say, tp, part_faces(spec.part), spec, tolerance=spec.gouge_tolerance, render=spec.render
        )
        return vcode
    write_toolpath(st, tp, spec)
    rep["verify"] = {"checked": False, "reason": "no --part: nothing to check the tool path against"}
    say("tool path written unchecked: give --part PART.step to check the tool body against the part")
    return EXIT_OK


def _zebra(st: Staging, spec: EnvelopeJob, res) -> None:
    """The zebra picture of the G0 and the G1 chains, with their largest seam angles."""
    from ..sweep import fitted_normals
    from ..viz import render_zebra

    chain = res.chain
    g1 = chain if spec.continuity == "g1" else res.other
    g0 = res.other if spec.continuity == "g1" else chain
    ang0 = max(s["max_normal_angle_deg"] for s in g0.seams_fitted)
    ang1 = max(s["max_normal_angle_deg"] for s in g1.seams_fitted)
    render_zebra(
        [
            (f"G0 (crease up to {ang0:.3g} deg)", fitted_normals(g0)),
            (f"G1 (seam angle {ang1:.2g} deg)", fitted_normals(g1)),
        ],
        st.path("zebra.png"),
    )
