"""``machining-surface --faces ... --axes 3``: 3-axis machining of whole parts by exact drop-cutter.

Machines the faces named by ``--faces`` (all, top or a list) while keeping the tool out of the check
faces (by default the rest of the part): the certified height-field CL surface, and raster or
waterline tool paths checked against every face of the part before they are written.
"""

from __future__ import annotations

import time

from ..errors import InputError, ToleranceError
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish
from .specs import MachiningSurfaceJob


def _part(spec: MachiningSurfaceJob):
    """Every face of the part, and a description."""
    if spec.example:
        from ..examples import example as build
        from ..geometry.face import Face

        s = build(spec.example, "surface")
        return [Face(s, name=s.name or spec.example)], f"example {spec.example}"
    from .inputs import part_faces

    return part_faces(spec.part), str(spec.part)


def run_three_axis(spec: MachiningSurfaceJob, out, say: Say, progress=None) -> JobOutcome:
    from ..threeaxis import select_faces
    from ..threeaxis.paths import raster
    from ..threeaxis.zlevel import waterline
    from ..toolspec import parse_cutter

    t0 = time.perf_counter()
    cutter = parse_cutter(spec.tool)
    if spec.shank or spec.holder:
        import dataclasses

        from .inputs import shank as _shank

        shank, holder = _shank(spec.shank, "shank"), _shank(spec.holder, "holder")
        cutter = dataclasses.replace(cutter, shank=shank, holder=holder)  # type: ignore[type-var]
    faces, desc = _part(spec)
    axis = spec.axis if spec.axis is not None else (0.0, 0.0, 1.0)
    machined = select_faces(faces, spec.faces or "all", axis=axis, what="--faces")
    chk = spec.check_faces.strip().lower()
    if chk in ("rest", "all"):
        checked = [i for i in range(len(faces)) if i not in machined]
    else:
        checked = [i for i in select_faces(faces, chk, axis=axis, what="--check-faces") if i not in machined]
    if spec.pattern == "raster" and (spec.faces or "all").strip().lower() not in ("all", "top"):
        from ..threeaxis.select import faces_away

        vertical = [i for i in machined if faces_away(faces[i], axis, below=0.01)]
        if vertical and len(vertical) == len(machined):
            raise InputError(
                f"face {vertical[0]} is parallel to the tool axis: a raster along it touches the face only at its "
                "edges; use --pattern waterline (or another --axis)"
            )
    mf = [faces[i] for i in machined]
    cf = [faces[i] for i in checked]
    rep: dict = {
        "nominal": desc,
        "tool": cutter.spec(),
        "axes": 3,
        "axis": [float(a) for a in axis],
        "faces_machined": machined,
        "faces_checked": checked,
        "n_faces_part": len(faces),
    }
    say(f"part: {desc}, {len(faces)} faces; machining {len(machined)} ({spec.faces}), avoiding {len(checked)} more")
    say(f"tool: {cutter.spec()}, axis {tuple(float(a) for a in axis)}: exact drop-cutter on the B-rep")
    code = EXIT_OK
    with Staging(out) as st:
        if spec.cl_surface or not spec.toolpath:
            code = _cl_surface(st, say, spec, cutter, mf, cf, axis, rep, progress)
        if spec.toolpath:
            from .run_verify import write_checked_toolpath

            common = dict(
                check_faces=cf,
                chordal_tolerance_mm=spec.chordal,
                clearance_mm=spec.clearance,
                axis=axis,
                progress=progress,
            )
            if spec.pattern == "raster":
                tp = raster(
                    mf,
                    cutter,
                    stepover_mm=None if spec.scallop is not None else spec.stepover_mm,
                    scallop_mm=spec.scallop,
                    angle_deg=spec.angle,
                    direction=spec.direction,
                    verify_tolerance_mm=spec.gouge_tol,
                    **common,
                )
            else:
                tp = waterline(mf, cutter, stepdown_mm=spec.stepdown or spec.stepover_mm, grid_mm=spec.grid,
                               verify_tolerance_mm=spec.gouge_tol, **common)  # fmt: skip
            i = tp.info
            rep["toolpath"] = tp.report()
            say(
                f"{i['pattern']} tool path: {i['n_passes']} passes, {tp.n_cut} cutting positions; chordal error "
                f"measured {i['chordal_error_measured_mm']:.3g} mm (tol {spec.chordal:g}) on points no position used"
                + (
                    f"; step-over {i['stepover_mm']:.4g} mm, {i['n_links_on_part']} links on the part, "
                    f"{i['n_retracts']} retracts"
                    if i["pattern"] == "raster"
                    else f"; {i['n_moves_dropped_above_level'] + i.get('n_moves_dropped_after_body_check', 0)} "
                    "moves dropped where the part rises above the level between crossings (contours cut "
                    "open: material left there, refine --grid)"
                )  # fmt: skip
            )
            if i.get("scallop_target_mm") is not None:
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
                if i["n_scallop_unmet"]:
                    w = i["scallop_unmet"][0]
                    say(
                        f"scallop target not met between {i['n_scallop_unmet']} pair(s) of lines at the smallest "
                        f"step-over (1/32 of the flat-floor one): up to {w['left_mm']:.4g} mm near "
                        f"({w['at_xy_mm'][0]:.3f}, {w['at_xy_mm'][1]:.3f}) mm"
                    )
                    code = max(code, EXIT_TOLERANCE)
            rep["verify"], c2 = write_checked_toolpath(st, say, tp, faces, spec, tolerance=spec.gouge_tol, render=True)
            code = max(code, c2)
        rep["time_s"] = {"total_s": time.perf_counter() - t0}
        outcome = finish(st, "machining-surface", rep, code)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _cl_surface(st: Staging, say: Say, spec, cutter, mf, cf, axis, rep, progress) -> int:
    """The certified height-field CL surface, written as a named STEP face; exit 2 when the pole budget
    ends before the tolerance (the error reached is reported, nothing is written for it)."""
    from ..geometry.face import Face
    from ..occ import write_step
    from ..threeaxis.heightfield import cl_surface

    try:
        fit, info = cl_surface(
            mf, cutter, check_faces=cf, tolerance_mm=spec.tol, axis=axis, degree=spec.degree,
            max_poles=spec.max_poles, progress=progress,
        )  # fmt: skip
    except ToleranceError as exc:
        rep["cl_surface"] = {"tolerance_mm": spec.tol, "reached_mm": exc.reached, "written": False}
        say(f"CL surface: tolerance {spec.tol:g} mm not reached within {spec.max_poles} poles ({exc}): exit 2")
        return EXIT_TOLERANCE
    except InputError:
        raise
    write_step(st.path("cl_surface.step"), [Face(fit.surface, name="cl_surface")])
    r = fit.report()
    rep["cl_surface"] = dict(r, **info, written=True)
    say(
        f"CL surface (tool tips, height field): {r['poles'][0]}x{r['poles'][1]} poles, max error "
        f"{r['max_error_mm']:.3g} mm (tol {spec.tol:g}) against the exact drop-cutter on "
        f"{r['n_check_points']} unseen points; "
        f"{100 * info['share_without_face']:.1f} % of the plan box has no face under the tool"
    )
    return EXIT_OK
