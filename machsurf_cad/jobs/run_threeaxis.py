"""``mill3``: 3-axis machining of whole parts by exact drop-cutter (:func:`machsurf_cad.mill3`).

Machines the faces named by ``--faces`` (top, all or a list) while keeping the tool out of the check
faces (by default the rest of the part): raster or waterline tool paths checked against every face of
the part before they are written, and the certified height-field CL surface on request.
"""

from __future__ import annotations

import time

from ..errors import InputError, ToleranceError
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish
from .specs import Mill3Job


def _part(spec: Mill3Job):
    """Every face of the part, and a description."""
    if spec.example:
        from ..examples import example as build
        from ..geometry.face import Face

        s = build(spec.example, "surface")
        return [Face(s, name=s.name or spec.example)], f"example {spec.example}"
    from .inputs import part_faces

    return part_faces(spec.part), str(spec.part)


def run_three_axis(spec: Mill3Job, out, say: Say, progress=None) -> JobOutcome:
    from ..threeaxis.wholepart import machined_and_checked

    t0 = time.perf_counter()
    from .inputs import check_clearance, cutter_with_body

    cutter = cutter_with_body(spec.tool, spec.shank, spec.holder)
    faces, desc = _part(spec)
    axis = tuple(float(a) for a in (spec.axis if spec.axis is not None else (0.0, 0.0, 1.0)))
    machined, checked = machined_and_checked(faces, spec.faces, spec.check_faces, axis)
    check_clearance(spec.clearance, faces)
    rep: dict = {
        "nominal": desc,
        "tool": cutter.spec(),
        "axes": 3,
        "axis": list(axis),
        "faces_machined": machined,
        "faces_checked": checked,
        "n_faces_part": len(faces),
    }
    say(f"part: {desc}, {len(faces)} faces; machining {len(machined)} ({spec.faces}), avoiding {len(checked)} more")
    say(f"tool: {cutter.spec()}, axis {axis}: exact drop-cutter on the B-rep")
    code = EXIT_OK
    with Staging(out) as st:
        if spec.cl_surface:
            mf, cf = [faces[i] for i in machined], [faces[i] for i in checked]
            code = _cl_surface(st, say, spec, cutter, mf, cf, axis, rep, progress)
        if spec.toolpath:
            code = max(code, _toolpath(st, say, spec, cutter, faces, axis, rep, progress))
        rep["time_s"] = {"total_s": time.perf_counter() - t0}
        outcome = finish(st, "mill3", rep, code)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _toolpath(st: Staging, say: Say, spec: Mill3Job, cutter, faces, axis, rep: dict, progress) -> int:
    """Plan the path (:func:`machsurf_cad.mill3`), say its figures, write it if the body check allows."""
    from ..threeaxis.wholepart import mill3
    from .run_verify import on_gouge, write_checked_toolpath

    res = mill3(
        faces, cutter, faces=spec.faces, check_faces=spec.check_faces, axis=axis, pattern=spec.pattern,
        stepover=spec.stepover, scallop=spec.scallop, angle=spec.angle, direction=spec.direction,
        stepdown=spec.stepdown, grid_step=spec.grid_step, chordal_tolerance=spec.chordal_tolerance,
        clearance=spec.clearance, gouge_tolerance=spec.gouge_tolerance, on_gouge=on_gouge(spec), progress=progress,
    )  # fmt: skip
    tp, code = res.planned, EXIT_OK
    i = tp.info
    rep["toolpath"] = tp.report()
    full = res.reach_summary()
    rep["reach"] = list(res.reach)
    if full:
        rep["reachable_fraction"], rep["touched_fraction"] = full["reachable_fraction"], full["touched_fraction"]
        away = full["faces_out_of_reach"]
        say(
            f"the tool can touch {100 * full['reachable_fraction']:.1f} % of the machined faces' area along the axis "
            f"(the dropped tool {100 * full['touched_fraction']:.1f} %)"
            + (f"; out of its reach: face(s) {', '.join(map(str, away))}" if away else "")
        )
    say(
        f"{i['pattern']} tool path: {i['n_passes']} passes, {tp.n_cut} cutting positions; chordal error "
        f"measured {i['chordal_error_measured_mm']:.3g} mm (tol {spec.chordal_tolerance:g}) on points no position "
        "used"
        + (
            f"; step-over {i['stepover_mm']:.4g} mm, {i['n_links_on_part']} links on the part, "
            f"{i['n_retracts']} retracts"
            if i["pattern"] == "raster"
            else f"; {i['n_moves_dropped_above_level'] + i.get('n_moves_dropped_after_body_check', 0)} "
            "moves dropped where the part rises above the level between crossings (contours cut "
            "open: material left there, refine --grid-step)"
        )  # fmt: skip
    )
    if i.get("scallop_target_mm") is not None:
        code = _say_scallop(say, i)
    rep["verify"], c2 = write_checked_toolpath(
        st, say, tp, faces, spec, tolerance=spec.gouge_tolerance, render=True, check=res.check
    )
    return max(code, c2)


def _say_scallop(say: Say, i: dict) -> int:
    say(
        f"scallop-driven lines: step-over {i['stepover_min_mm']:.4g}..{i['stepover_max_mm']:.4g} mm "
        f"(flat floor {i['stepover_flat_floor_mm']:.4g}), largest cusp planned "
        f"{i['scallop_planned_max_mm']:.4g} mm along the normal "
        f"({i['scallop_planned_max_vertical_mm']:.4g} vertically), target {i['scallop_target_mm']:g} mm"
        + (
            f"; {i['n_cusps_at_cutter_limit']} cusp position(s) where the tool placed right there leaves "
            "more (walls, corners narrower than the tool: the cutter's limit, not the step-over's)"
            if i["n_cusps_at_cutter_limit"]
            else ""
        )
    )
    if i["n_scallop_unmet"]:  # the worst pair over the target is the worst of all (the others are within it)
        w = i["scallop_planned_worst_xy_mm"]
        say(
            f"scallop target not met between {i['n_scallop_unmet']} pair(s) of lines at the smallest "
            f"step-over (1/32 of the flat-floor one): up to {i['scallop_planned_max_mm']:.4g} mm near "
            f"({w[0]:.3f}, {w[1]:.3f}) mm"
        )
        return EXIT_TOLERANCE
    return EXIT_OK


def _cl_surface(st: Staging, say: Say, spec, cutter, mf, cf, axis, rep, progress) -> int:
    """The certified height-field CL surface, written as a named STEP face; exit 2 when the pole budget
    ends before the tolerance (the error reached is reported, nothing is written for it)."""
    from ..geometry.face import Face
    from ..occ import write_step
    from ..threeaxis.heightfield import cl_surface

    try:
        fit, info = cl_surface(
            mf, cutter, check_faces=cf, tolerance=spec.tolerance, axis=axis, degree=spec.degree,
            max_poles=spec.max_poles, progress=progress,
        )  # fmt: skip
    except ToleranceError as exc:
        rep["cl_surface"] = {"tolerance_mm": spec.tolerance, "reached_mm": exc.reached, "written": False}
        say(f"CL surface: tolerance {spec.tolerance:g} mm not reached within {spec.max_poles} poles ({exc}): exit 2")
        return EXIT_TOLERANCE
    except InputError:
        raise
    write_step(st.path("cl_surface.step"), [Face(fit.surface, name="cl_surface")])
    r = fit.report()
    rep["cl_surface"] = dict(r, **info, written=True)
    say(
        f"CL surface (tool tips, height field): {r['poles'][0]}x{r['poles'][1]} poles, max error "
        f"{r['max_error_mm']:.3g} mm (tol {spec.tolerance:g}) against the exact drop-cutter on "
        f"{r['n_check_points']} unseen points; "
        f"{100 * info['share_without_face']:.1f} % of the plan box has no face under the tool"
    )
    return EXIT_OK
