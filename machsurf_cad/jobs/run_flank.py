"""The ``flank`` job: settings, interference, whole-surface path, envelope, study, radius range."""

from __future__ import annotations

from ..batchrun.runner import chunk_map
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish, step_face
from .specs import FlankJob


def _ruled_input(spec: FlankJob):
    from ..examples import example
    from ..flank_milling import RuledSurface

    if spec.example:
        return example(spec.example, "ruled"), f"example {spec.example}"
    f = step_face(spec.part, spec.face)
    tol = spec.ruled_tolerance if spec.ruled_tolerance is not None else 1e-6
    s = RuledSurface.from_surface(f.surface, tolerance=tol, name=f.name)
    return s, f"face {f.index} '{f.name}' of {spec.part} (deviation from ruled: {s.source_deviation:.3g} mm)"


def _example_face(name: str, side: int = 1):
    """The example's surface as the part: a bare sheet, the material on the side away from the tool
    (``side`` -1: the tool is against the normal S_u x S_v, so the face's outward normal is reversed)."""
    from ..examples import example
    from ..geometry.face import Face

    return Face(example(name, "surface"), name=name, reversed=side < 0)


def _write_rule_errors(path, profiles: dict) -> str:
    """CSV: v, then the error (mm) of every admissible setting along the rule."""
    import csv

    kinds = [k for k, e in profiles.items() if not isinstance(e, str)]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["v", *[f"{k}_mm" for k in kinds]])
        if kinds:
            v = profiles[kinds[0]].v
            for i in range(v.size):
                w.writerow([f"{v[i]:.6f}", *[f"{profiles[k].e[i]:.9g}" for k in kinds]])
    return path.name


def run_flank(spec: FlankJob, out, say: Say, progress=None) -> JobOutcome:
    from ..flank_milling import flank
    from .inputs import check_clearance

    surf, desc = _ruled_input(spec)
    if spec.whole and not spec.part:
        check_clearance(spec.clearance, [_example_face(spec.example)])
    check = None
    if spec.part and spec.whole:
        from ..threeaxis.select import select_faces
        from .inputs import body_faces, part_faces

        faces = part_faces(spec.part)
        check_clearance(spec.clearance, faces)
        if str(spec.check_faces).strip().lower() == "body":  # the solid the face bounds: its others are other parts
            check = [f for f in body_faces(faces, spec.face) if f.index != spec.face] or None
        elif str(spec.check_faces).strip().lower() == "rest":
            check = [f for f in faces if f.index != spec.face] or None
        else:
            check = [faces[i] for i in select_faces(faces, spec.check_faces, what="--check-faces") if i != spec.face]
            check = check or None
    res = flank(
        surf,
        spec.tool,
        rule=spec.rule,
        setting=spec.setting,
        side=spec.side,
        whole=spec.whole,
        tolerance=spec.tolerance,
        envelope_tolerance=spec.envelope_tolerance,
        study=spec.study,
        radius_range=spec.radius_range,
        smooth=spec.smooth,
        clearance=spec.clearance,
        check_faces=check,
        gouge_tolerance=spec.gouge_tolerance,
        progress=progress,
        chunks=int(spec.chunks),
        map_chunks=chunk_map(spec.chunks),
    )
    rep = res.report()
    rep["surface"] = desc
    _say_rule(say, spec, res, desc)
    code = EXIT_OK
    with Staging(out) as st:
        rep["error_along_rule_file"] = _write_rule_errors(st.path("error_along_rule.csv"), res.profiles or {})
        if spec.render and res.profiles:
            from ..viz.plots import plot_rule_errors

            plot_rule_errors(
                res.profiles,
                st.path("error_along_rule.png"),
                tolerance=spec.tolerance,
                title=f"error along the rule u = {res.u_p:.5g}, {res.cutter.spec()}, side {spec.side:+d}",
            )
        if res.path is not None:
            code = _whole_surface(st, say, spec, res, surf, rep)
        if res.study is not None:
            _study(st, say, spec, res.study)
        _say_smooth_and_radius_range(say, spec, res)
        outcome = finish(st, "flank", rep, code, res)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _say_rule(say: Say, spec: FlankJob, res, desc: str) -> None:
    """Say the rule, the setting on it with its contacts and interference, and every setting's error there."""
    st_, e, cutter = res.setting, res.interference, res.cutter
    say(
        f"surface: {desc}; rule u = {res.u_p:.6g} (fraction {spec.rule:g}), h_p = {st_.frame.h_p:.4f} mm, "
        f"alpha0 = {st_.frame.alpha0_deg:.4f} deg; tool {cutter.spec()} (R = {res.R:g} mm), side {spec.side:+d}"
    )
    if st_.kind != spec.setting:
        say(f"{spec.setting} does not exist on this rule: {st_.kind} shown (and used where it is missing)")
    say(
        f"{st_.kind}: gamma = {st_.gamma_deg:.6f} deg, h0 = {st_.h0:.6f} mm, h1 = {st_.h1:.6f} mm"
        + (f", phi = {st_.phi_deg:.6f} deg" if st_.phi_deg else "")
    )
    for k in ("M0", "M1", "M2"):
        if k in st_.contacts:
            say(f"  {k} = ({', '.join(f'{x:.5f}' for x in st_.contacts[k])}) mm")
    w = e.worst()
    say(
        f"interference: max gouge {e.max_gouge:.6g} mm, max undercut {e.max_undercut:.6g} mm, worst at v = "
        f"{w['v']:.4f}, xyz ({', '.join(f'{x:.4f}' for x in w['xyz'])}) mm"
    )
    say(
        "all settings on this rule: "
        + "; ".join(
            f"{k} {v['max_abs_mm']:.4g} mm" if "max_abs_mm" in v else f"{k} not admissible"
            for k, v in res.comparison.items()
        )
    )


def _whole_surface(st: Staging, say: Say, spec: FlankJob, res, surf, rep: dict) -> int:
    """``--whole``: the checked tool path, the envelopes (STEP, STL) and the deviation map; the exit code."""
    from ..flank_milling import mean_normal
    from ..geometry.face import Face
    from ..occ import write_step, write_stl
    from .inputs import part_faces
    from .run_verify import write_checked_toolpath

    code = EXIT_OK
    cutter = res.cutter
    env, dev = res.envelope, res.envelope_deviation
    # the tool body against the part: every face of a STEP part, or the example's surface
    faces = part_faces(spec.part) if spec.part else [_example_face(spec.example, spec.side)]
    if spec.part and str(spec.check_faces).strip().lower() == "body":  # the face's solid: the others are other parts
        from .inputs import body_faces

        faces = body_faces(faces, spec.face)
    gtol = spec.gouge_tolerance if spec.gouge_tolerance is not None else spec.tolerance
    rep["whole"]["verify"], vcode = write_checked_toolpath(
        st, say, res.toolpath, faces, spec, tolerance=gtol, render=spec.render
    )
    vcode = max(vcode, _other_tools(st, say, spec, res, rep, faces, gtol))
    env_faces = [
        Face(fit.surface, name=f"flank_envelope_{k}" if len(res.segment_envelopes) > 1 else "flank_envelope")
        for k, (_, fit, *_) in enumerate(res.segment_envelopes)
        if fit is not None
    ]
    if env_faces:
        write_step(st.path("envelope.step"), env_faces)
        write_stl(st.path("envelope.stl"), env_faces, linear_deflection=0.01)
    if spec.render and dev is not None:
        from ..viz import render_deviation

        render_deviation(
            dev,
            st.path("deviation.png"),
            vtp_path=st.path("deviation.vtp"),
            title=f"nominal vs {'envelope' if env is not None else 'positions'} of {cutter.spec()} "
            f"({spec.setting}); blue gouge (negative), red undercut",
            tolerance=spec.tolerance,
            view_direction=mean_normal(surf, spec.side),
        )
    _say_whole(say, spec, res)
    if (res.whole_error_mm or 0.0) > spec.tolerance:
        say(f"tolerance {spec.tolerance:g} mm NOT met on the whole surface")
        code = EXIT_TOLERANCE
    return max(code, vcode)


def _other_tools(st: Staging, say: Say, spec: FlankJob, res, rep: dict, faces, gtol: float) -> int:
    """Several diameters: each tool's share said; the paths of the tools after the main one checked and
    written as ``toolpath_2``, ``toolpath_3``, ... with the next tool numbers. The worst exit code."""
    import dataclasses

    from .run_verify import write_checked_toolpath

    code, k = EXIT_OK, 1
    for p, prep in zip(res.by_diameter, rep["whole"].get("by_diameter", [])):
        ranges = ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in p.u_machined) or "none"
        say(
            f"{p.cutter.spec()}: {prep['n_rules_machined']} rules, u in {ranges}, "
            f"{100 * p.machined_fraction:.1f} % of the face" + (f" ({p.why_none})" if p.why_none else "")
        )
        if p.toolpath is None or p.toolpath is res.toolpath:
            continue
        k += 1
        sub = dataclasses.replace(spec, tool_number=spec.tool_number + k - 1)
        say(f"tool {sub.tool_number}, {p.cutter.spec()}: toolpath_{k}")
        prep["verify"], c = write_checked_toolpath(st, say, p.toolpath, faces, sub, tolerance=gtol, render=False,
                                                   stem=f"toolpath_{k}")  # fmt: skip
        code = max(code, c)
    if res.by_diameter:
        w = rep["whole"]
        left = ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in w["u_left_out"]) or "none"
        say(f"all tools: {100 * w['machined_fraction_all_tools']:.1f} % of the face machined; u left out: {left}")
    return code


def _say_whole(say: Say, spec: FlankJob, res) -> None:
    """Say the whole-surface figures: errors, envelope, the rules without the setting, the segments."""
    path, env, dev = res.path, res.envelope, res.envelope_deviation
    say(
        f"whole surface: {len(path.settings)} rules, max gouge {path.max_gouge:.4g} mm, max undercut "
        f"{path.max_undercut:.4g} mm (rule u = {path.worst['rule_u']:.5g}); "
        + (
            f"envelope {env.surface.shape[0]}x{env.surface.shape[1]} poles, fit error {env.max_error:.3g} mm; "
            f"nominal vs envelope max {dev.max_abs:.4g} mm"
            if env is not None
            else "no envelope fitted (see the segments); "
            + (f"nominal vs tool positions max {dev.max_abs:.4g} mm" if dev is not None else "")
        )
        + (f"; {len(path.discontinuities)} setting jump(s)" if path.discontinuities else "")
    )
    cl = res.cleared
    if cl is not None:
        rep = cl.report()
        say(
            f"clear of the part's other faces: {rep['n_rules_kept']} of {rep['n_rules_planned']} rules kept, "
            f"{rep['n_rules_lifted']} lifted along the axis (up to {rep['max_lift_mm'] or 0:.3g} mm); "
            f"{100 * rep['machined_fraction']:.1f} % of the rules' length in contact (the rest is left to another "
            "tool and counts in the deviation above)"
        )
        for r in rep["rules_left_out"]:
            say(
                f"  left out: u in [{r['u_range'][0]:.5g}, {r['u_range'][1]:.5g}], {r['n_rules']} rule(s): the "
                f"cylinder would enter the part {r['deepest_intrusion_mm']:.3g} mm"
            )
    if path.fallback_u.size:
        say(
            f"{spec.setting} does not exist on {path.fallback_u.size} of {len(path.settings)} rules "
            f"(u in [{path.fallback_u.min():.5g}, {path.fallback_u.max():.5g}]): standard-distributed "
            "used there"
        )
    if len(res.segment_envelopes) > 1:
        say(f"the path is cut into {len(res.segment_envelopes)} segments where the setting jumps:")
    for seg, fit, d, *why in res.segment_envelopes if len(res.segment_envelopes) > 1 or env is None else ():
        say(
            f"  u in [{seg.u[0]:.5g}, {seg.u[-1]:.5g}], {len(seg.settings)} rules, max gouge "
            f"{seg.max_gouge:.4g} mm, max undercut {seg.max_undercut:.4g} mm; "
            + (
                f"envelope fit {fit.max_error:.3g} mm, nominal vs envelope {d.max_abs:.4g} mm"
                if fit is not None
                else why[0] + (f"; nominal vs tool positions {d.max_abs:.4g} mm" if d is not None else "")
            )
        )


def _study(st: Staging, say: Say, spec: FlankJob, data: dict) -> None:
    """``--study``: the paper's figs 9 and 10 (pictures) and the smallest ratio standard/optimum."""
    if spec.render:
        from ..viz.plots import plot_ratio_curves

        plot_ratio_curves(
            data["by_h_p"],
            st.path("study_h_p.png"),
            label_key="h_p_mm",
            label_fmt="h_p = {:g} mm",
            title="hyperbolic paraboloid, alpha0 = 30 deg (fig. 9)",
        )
        plot_ratio_curves(
            data["by_alpha0"],
            st.path("study_alpha0.png"),
            label_key="alpha0_deg",
            label_fmt="alpha0 = {:g} deg",
            title="hyperbolic paraboloid, h_p = 80 mm (fig. 10)",
        )
    say(f"parameter study: smallest ratio standard/optimum {data['min_ratio']:.3g}")


def _say_smooth_and_radius_range(say: Say, spec: FlankJob, res) -> None:
    """Say the ``--smooth`` path against the rule-by-rule optima, and the ``--radius-range`` result."""
    if res.smooth is not None:
        sm, ro = res.smooth["smooth_minimax"], res.smooth["rule_optima"]
        say(
            f"smooth minimax over {res.smooth['n_rules']} rules: max |error| {sm['max_abs_mm']:.4g} mm, axis "
            f"turn at most {sm['max_turn_reached_deg_per_mm']:.4g} deg/mm "
            f"(bound {sm['max_turn_bound_deg_per_mm']:.4g}, "
            f"{'met' if sm['bound_met'] else 'NOT met'}); rule-by-rule optima: {ro['max_abs_mm']:.4g} mm, "
            f"{ro['max_turn_deg_per_mm']:.4g} deg/mm"
        )
    if res.radius_range is not None:
        rr = res.radius_range
        say(
            f"radius range for {spec.radius_range:g} mm: "
            + (
                f"R in [{rr['R_min_mm']:.4g}, {rr['R_max_mm']:.4g}] mm after {len(rr['iterations'])} evaluations"
                if rr["feasible"]
                else rr["message"]
            )
        )
