"""The ``simulate`` job, and the simulation the path-writing jobs run with ``--simulate``."""

from __future__ import annotations

from ..batchrun.runner import chunk_map
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish
from .inputs import part_faces, toolpath_and_cutter
from .specs import SimulateJob


def _mm(v) -> str:
    return "-" if v is None or v != v else f"{v:.4g} mm"


def simulate_path(
    st: Staging,
    say: Say,
    tp,
    faces,
    *,
    cutter=None,
    tolerance: float,
    render: bool,
    progress=None,
    prefix: str = "simulate",
    **kw,
):
    """Simulate ``tp`` on ``faces``; say and draw the result; return ``(SimulationResult, report)``. The
    material left is said for the machined region and for the border apart, the samples not measured
    (rays that did not converge) with where they lie."""
    from ..simulation import simulate

    res = simulate(faces, tp, cutter, gouge_tolerance=tolerance, progress=progress, **kw)
    rep = res.report()
    say(
        f"cut simulated (N-buffer) on {rep['n_faces']} face(s): {rep['n_samples']:,} samples "
        f"{res.resolution_mm:.3g} mm apart, {rep['n_placements']:,} placements ({res.motion_step_mm:.3g} mm apart, "
        f"refined over the motion: last change {res.motion_residual_mm:.2g} mm) in {res.time_s['total_s']:.2f} s"
    )
    reg, bd, nm = rep["machined_region"], rep["border"], rep["not_measured"]
    say(
        f"  machined region (under and between the passes, {100 * reg['area_fraction']:.1f} % of the area): "
        f"material left max {_mm(rep['max_scallop_mm'])}, mean {_mm(rep['mean_scallop_mm'])}"
    )
    say(
        f"  border (reached around the passes, {100 * bd['area_fraction']:.1f} % of the area): material left max "
        f"{_mm(bd['max_material_mm'])}, mean {_mm(bd['mean_material_mm'])}; not reached within {res.stock_mm:g} mm: "
        f"{100 * rep['not_reached_fraction']:.1f} % of the samples"
    )
    say(
        f"  max gouge {rep['max_gouge_mm']:.4g} mm (depth inside the swept tool, tol {tolerance:g}) on "
        f"{rep['n_gouged_samples']} sample(s)"
    )
    say("  machined area above: " + ", ".join(f"{h} mm {100 * f:.1f} %" for h, f in rep["fraction_above_mm"].items()))
    if nm["n_samples"] or nm["n_rays"] or nm["n_motion_probes"]:
        where = ", ".join(f"{f['name']}: {f['n_samples']}" for f in nm["per_face"][:8])
        say(
            f"  warning: {nm['n_rays'] + nm['n_motion_probes']} ray(s) did not converge; {nm['n_samples']} sample(s) "
            f"not measured (in no figure; report not_measured)" + (f" on {where}" if where else "")
        )
    if render:
        from ..viz import render_simulation_map
        from ..viz.plots import plot_simulation_histogram

        render_simulation_map(
            res,
            st.path(f"{prefix}_map.png"),
            vtp_path=st.path(f"{prefix}_map.vtp"),
            title=f"{tp.name}: material left (machined region max {_mm(rep['max_scallop_mm'])}, border max "
            f"{_mm(bd['max_material_mm'])}, gouge {rep['max_gouge_mm']:.3g} mm)",
        )
        plot_simulation_histogram(
            res.value,
            res.reached & res.measured,
            st.path(f"{prefix}_histogram.png"),
            tolerance=tolerance,
            heights=res.heights_mm,
            title=f"{tp.name}: material left per sample ({rep['n_samples']:,} samples)",
        )
    return res, rep


def run_simulate(spec: SimulateJob, out, say: Say, progress=None) -> JobOutcome:
    path, tp, cutter = toolpath_and_cutter(spec.toolpath, spec.tool, say)
    faces = part_faces(spec.part, spec.faces)
    say(
        f"part: {spec.part} ({len(faces)} face(s) simulated); tool path: {path.name}, {tp.n_positions} positions, "
        f"{tp.n_passes} pass(es); tool {cutter.spec()}"
    )
    with Staging(out) as st:
        res, rep = simulate_path(
            st,
            say,
            tp,
            faces,
            cutter=cutter,
            tolerance=spec.gouge_tolerance,
            render=spec.render,
            progress=progress,
            resolution=spec.resolution,
            depth=spec.depth,
            stock=spec.stock,
            motion_step=spec.motion_step,
            heights=spec.height_values(),
            max_samples=int(spec.max_samples),
            chunks=int(spec.chunks),
            map_chunks=chunk_map(spec.chunks),
        )
        code = EXIT_TOLERANCE if res.gouged else EXIT_OK
        say(
            "GOUGE: the path cuts below the nominal beyond the tolerance"
            if res.gouged
            else "no gouge beyond the tolerance"
        )
        report = {"part": str(spec.part), "toolpath": str(path), "tool": cutter.to_dict(), "simulate": rep}
        outcome = finish(st, "simulate", report, code, res)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome
