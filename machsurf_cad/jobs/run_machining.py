"""The ``machining-surface`` job: S1/S2 as certified faces, their deviation map, optionally a tool path."""

from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from .base import EXIT_OK, JobOutcome, Say, Staging, face_input, finish
from .specs import MachiningSurfaceJob


def run_machining_surface(spec: MachiningSurfaceJob, out, say: Say, progress=None) -> JobOutcome:
    from ..machining import machining_surface
    from .inputs import check_clearance, cutter_with_body

    if spec.faces is not None:
        from .run_threeaxis import run_three_axis

        return run_three_axis(spec.to_mill3(), out, say, progress)
    t0 = time.perf_counter()
    cutter = cutter_with_body(spec.tool, spec.shank, spec.holder)
    face, desc = face_input(spec.part, spec.example, spec.face)
    from ..geometry.meshsize import check_mesh_size, default_deflection

    stl_deflection = spec.stl_deflection or default_deflection([face])
    check_mesh_size([face], stl_deflection, 5.0, what="S1/S2 for the STL")  # before the fit: S1, S2 ~ the face
    faces_of_part: list = []

    def part():
        """Every face of the file the face came from, read once (an example is its own part); with
        ``--check-faces body`` those of the solid it bounds (the file's other solids are other parts)."""
        if not faces_of_part:
            from .inputs import body_faces, part_faces

            every = part_faces(spec.part) if spec.part else [face]
            faces_of_part.extend(body_faces(every, face.index) if spec.check_faces == "body" else every)
            if len(faces_of_part) < len(every):
                say(
                    f"part: the {len(faces_of_part)} faces of body {face.body} (the solid face {face.index} bounds) "
                    f"of the file's {len(every)} (--check-faces body: its other solids are left out)"
                )
        return faces_of_part

    if spec.toolpath:
        check_clearance(spec.clearance, part())  # before any work
    axis_field, tilt_rep = _tilt_away(say, spec, face, cutter, part) if spec.tilt_away else (None, None)
    ms = machining_surface(
        face,
        cutter,
        axis_field=axis_field,
        axes=spec.axes,
        strategy=spec.strategy,
        lead=spec.lead,
        tilt=spec.tilt,
        axis=spec.axis,
        tolerance=spec.tolerance,
        loops=spec.loops,
        max_poles=spec.max_poles,
        tip=spec.tip,
        lead_margin=spec.lead_margin,
        lead_min=spec.lead_min,
        lead_rate=spec.lead_rate,
        lead_check_faces=part() if spec.lead == "auto" else None,
        degree=(spec.degree, spec.degree),
        progress=progress,
    )
    t_fit = time.perf_counter() - t0
    rep = ms.report()
    if tilt_rep is not None:
        rep["tilt_away"] = tilt_rep
    _say_surfaces(say, spec, ms, rep, cutter, desc)
    code = EXIT_OK
    with Staging(out) as st:
        _write_surfaces(st, spec, ms, rep, cutter, stl_deflection)
        if spec.toolpath:
            code = _write_toolpath(st, say, spec, ms, rep, part)
        rep["nominal"] = desc
        rep["time_s"] = {"fit_s": t_fit, "total_s": time.perf_counter() - t0}
        outcome = finish(st, "machining-surface", rep, code, result=ms)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _say_surfaces(say: Say, spec: MachiningSurfaceJob, ms, rep: dict, cutter, desc: str) -> None:
    """Say the nominal, the tool, each fitted surface, the axis orientation errors, the loops and the auto lead."""
    say(f"nominal: {desc}")
    say(
        f"tool: {cutter.spec()} (r = {rep['r_mm']:g} mm, R_t = {rep['R_t_mm']:g} mm), {ms.axes} axes, {rep['strategy']}"
    )
    for key in ("S1", "S2"):
        f = rep[key]
        if f is None:
            continue
        say(
            f"{f['name']}: degree {f['degrees'][0]}x{f['degrees'][1]}, {f['poles'][0]}x{f['poles'][1]} poles, "
            f"max error {f['max_error_mm']:.3g} mm (tol {spec.tolerance:g}) on {f['n_check_points']} unseen points"
        )
    if ms.axes == 5:
        say(
            f"axis orientation: alpha_max = {rep['alpha_max_deg_for_tolerance']:.4g} deg for the tolerance, "
            f"{rep['alpha_max_deg_for_measured_errors']:.4g} deg for the measured errors; measured axis error "
            f"{rep['axis_error_deg_measured']:.4g} deg"
        )
    say("loops: " + ("none" if not ms.loops.found else "; ".join(r.describe() for r in ms.loops.regions)))
    if rep.get("auto_lead"):
        al = rep["auto_lead"]
        say(
            f"automatic lead: {al['lead_min_deg']:.3f}..{al['lead_max_deg']:.3f} deg (local need up to "
            f"{al['local_need_max_deg']:.3f} deg incl. margin {al['margin_deg']:g}, change at most "
            f"{al['rate_bound_deg_per_mm']:g} deg/mm)"
        )


def _write_surfaces(st: Staging, spec: MachiningSurfaceJob, ms, rep: dict, cutter, stl_deflection: float) -> None:
    """Write S1/S2 (STEP, one STL each) and S1's deviation map from the exact offset (PNG, VTP)."""
    from ..machining.surfaces import fit_deviation
    from ..occ import write_step, write_stl
    from ..viz import render_deviation

    write_step(st.path("machining_surface.step"), ms.faces())
    for f in ms.faces():
        write_stl(st.path(f"{f.name}.stl"), [f], linear_deflection=stl_deflection)
    rep["stl_deflection_mm"] = stl_deflection
    dev = fit_deviation(ms, "S1")
    loops_pts = [(r.xyz, "magenta", f"{r.kind} loop ({r.surface})") for r in ms.loops.regions]
    render_deviation(
        dev,
        st.path("deviation_S1.png"),
        vtp_path=st.path("deviation_S1.vtp"),
        title=f"S1 fit vs exact offset ({cutter.spec()})",
        tolerance=spec.tolerance,
        extra_points=loops_pts,
    )
    rep["S1_deviation_map"] = dev.report()


def _write_toolpath(st: Staging, say: Say, spec: MachiningSurfaceJob, ms, rep: dict, part) -> int:
    """``--toolpath``: passes by step-over or iso-scallop, checked against the part, written; the exit code."""
    from ..linking import surface_for
    from ..machining.toolpath import tool_paths
    from .run_verify import write_checked_toolpath

    # links over a clearance surface around the whole part: a plane along a fixed axis, a sphere or cylinder
    surface = (spec.clearance_surface, spec.clearance_axis)
    fixed = None if spec.axes == 5 else (spec.axis or (0.0, 0.0, 1.0))
    kind, geo = surface_for(part(), fixed, spec.clearance, *surface)
    link = {f"safe_{kind}": geo[0] if kind == "plane" else geo}
    rep["clearance_surface"] = _surface_report(kind, geo)
    if spec.scallop is not None:
        tp = tool_paths(
            ms, scallop=spec.scallop, chordal_tolerance=spec.chordal_tolerance, clearance=spec.clearance,
            overrun=spec.overrun, **link,
        )  # fmt: skip
        i = tp.info
        say(
            f"iso-scallop passes for {spec.scallop:g} mm: spacing on the surface {i['spacing_min_mm']:.4g}.."
            f"{i['spacing_max_mm']:.4g} mm (mean {i['spacing_mean_mm']:.4g}); {i['n_passes_planned']} passes "
            f"where a constant spacing keeping the same scallop needs {i['n_passes_constant_spacing']}; "
            f"overrun {i['overrun_mm']:g} mm ({i['n_overruns_shortened_for_gouging']} shortened where they "
            "would gouge)"
        )
    else:
        tp = tool_paths(
            ms,
            stepover=spec.stepover_or_default,
            chordal_tolerance=spec.chordal_tolerance,
            clearance=spec.clearance,
            **link,
        )
    if spec.axes == 3 and len(part()) > 1:  # the part's other faces may stand in the way: cut out, not refused
        tp = _trimmed_to_reach(say, spec, ms, tp, part())
    rep["toolpath"] = tp.report()
    cs = rep["clearance_surface"]
    say(
        f"links between passes over a {kind} "
        + (f"{cs['height_mm']:.4g} mm along the axis" if kind == "plane" else f"of radius {cs['radius_mm']:.4g} mm")
        + (f" about ({', '.join(f'{x:.3g}' for x in cs['axis'])})" if kind == "cylinder" else "")
    )
    say(
        f"tool path: {tp.n_passes} passes, {tp.n_cut} cutting positions ({tp.n_positions} with approach and "
        f"retract), chordal error {tp.info['chordal_error_measured_mm']:.3g} mm (tol "
        f"{spec.chordal_tolerance:g})" + (", MULTAX (axis not +Z)" if tp.is_multiaxis else "")
    )
    if spec.chordal_tolerance + spec.tolerance >= spec.gouge_tolerance:
        say(
            f"warning: chordal {spec.chordal_tolerance:g} + fit tolerance {spec.tolerance:g} mm reach the "
            f"gouge tolerance {spec.gouge_tolerance:g} mm: chords on convex regions may be refused as gouges"
        )
    check = None
    if spec.trim_gouges or spec.tilt_away or spec.max_axis_angle is not None:  # cut out what no tool reaches
        from ..pathcheck import check_toolpath, machined_area_fraction

        check = check_toolpath(tp, part(), gouge_tolerance=spec.gouge_tolerance, on_gouge="trim",
                               clearance=spec.clearance, clearance_surface=kind, clearance_axis=spec.clearance_axis,
                               max_axis_angle=spec.max_axis_angle)  # fmt: skip
        if check.beyond_axis_limit:
            say(
                f"rotary limit {spec.max_axis_angle:g} deg from +Z: {check.beyond_axis_limit} of the planned "
                f"{tp.n_positions} positions lie past it (cut out, links kept within it)"
            )
        if check.verdict == "trimmed" and check.toolpath is not None:
            pi = np.asarray(check.toolpath.extras.get("planned_index", []), int)
            planned = check.trimmed_from if check.trimmed_from is not None else tp
            frac = machined_area_fraction(ms.nominal, planned, pi[pi >= 0], step=0.2 * ms.cutter.radius)
            rep["machined_area_fraction"] = frac
            say(f"machined area after trimming: {100 * frac:.1f} % of the face")
    rep["verify"], code = write_checked_toolpath(
        st, say, tp, part(), spec, tolerance=spec.gouge_tolerance, render=True, check=check
    )
    return code


def _surface_report(kind: str, geo) -> dict:
    """The clearance surface's kind and size (mm)."""
    if kind == "plane":
        return {"kind": kind, "height_mm": float(geo[0]), "axis": [float(x) for x in geo[1]]}
    if kind == "sphere":
        return {"kind": kind, "centre_mm": [float(x) for x in geo[0]], "radius_mm": float(geo[1])}
    return {"kind": kind, "point_mm": [float(x) for x in geo[0]], "axis": [float(x) for x in geo[1]],
            "radius_mm": float(geo[2]), "half_length_mm": float(geo[3])}  # fmt: skip


def _trimmed_to_reach(say: Say, spec: MachiningSurfaceJob, ms, tp, faces):
    """The fixed-axis path without the positions where the part stops the tool (drop-cutter on every face),
    skim-linked (:func:`machsurf_cad.trim_to_reach`); the figures said."""
    from ..threeaxis.reachpath import trim_to_reach

    try:
        out = trim_to_reach(tp, faces, gouge_tolerance=spec.gouge_tolerance, clearance=spec.clearance,
                            face=ms.nominal)  # fmt: skip
    except InputError as exc:
        bodies = sorted({f.body for f in faces if f.body >= 0})
        if len(bodies) > 1 and "reaches none" in str(exc):  # another part of an assembly may stand in the way
            raise InputError(
                f"{exc}; the file holds {len(bodies)} solids: if the others are other parts of an assembly, "
                "--check-faces body machines the face in its own solid"
            ) from None
        raise
    i = out.info
    frac = i.get("machined_area_fraction")
    say(
        f"reach along the axis on all {len(faces)} faces (exact drop-cutter): {i['reach_positions_trimmed']} of "
        f"{i['reach_positions_planned']} planned positions lie where the part stops the tool; "
        f"{i['reach_positions_kept']} cutting positions kept ({i['reach_positions_inserted']} put along moves "
        f"the part stops part-way) in {i['reach_runs']} run(s), {i['links_skim']} skim link(s) (highest "
        f"{i['link_height_max_mm']:.4g} mm above its ends)"
        + ("" if frac is None else f"; machined area {100 * frac:.1f} % of the face")
    )
    return out


def _tilt_away(say: Say, spec: MachiningSurfaceJob, face, cutter, part):
    """The axis field turned away from the part within ``--max-lead``/``--max-tilt``
    (:func:`machsurf_cad.machining.avoid.clear_axis_field`), and its report, said."""
    from ..machining.avoid import clear_axis_field

    lead = float(spec.lead)
    field, rep = clear_axis_field(
        face,
        cutter,
        spec.strategy,
        part(),
        lead=lead,
        tilt=spec.tilt,
        max_lead=lead if spec.max_lead is None else spec.max_lead,
        max_tilt=spec.max_tilt or 0.0,
        gouge_tolerance=spec.gouge_tolerance,
        max_axis_angle=spec.max_axis_angle,
    )
    say(
        f"tilt away within lead {lead:g}..{rep['max_lead_deg']:g} deg, tilt +-{rep['max_tilt_deg']:g} deg on all "
        f"{len(part())} faces: {rep['lattice_points_tilted']} of {rep['lattice_points']} lattice points tilted (axis "
        f"turned up to {rep['axis_change_max_deg']:.3g} deg, at most {rep['axis_turn_max_deg_per_mm']:.3g} deg/mm "
        f"against a bound of {rep['axis_turn_bound_deg_per_mm']:.3g}: {rep['max_turn_deg_per_mm']:.3g} asked, or the "
        f"nominal axis's own turn where the face curves faster, {rep['nominal_axis_turn_max_deg_per_mm']:.3g}), "
        f"{rep['lattice_points_clear_nowhere']} clear with no orientation (cut out of the path)"
    )
    regions = rep["regions_clear_nowhere"]
    if regions:
        big = regions[0]
        at = ", ".join(f"{x:.4g}" for x in big["xyz_mm"])
        box = [round(x, 4) for x in big["uv_box"]]
        say(
            f"  {rep['n_regions_clear_nowhere']} region(s) no orientation clears, "
            f"{rep['area_clear_nowhere_mm2']:.4g} mm^2 in all; the largest {big['area_mm2']:.4g} mm^2 around "
            f"({at}), uv box {box} (report: tilt_away.regions_clear_nowhere)"
        )
    return field, rep
