"""The ``simulate`` job, and the simulation the path-writing jobs run with ``--simulate``."""

from __future__ import annotations

from ..batchrun.runner import chunk_map
from .base import EXIT_OK, EXIT_TOLERANCE, JobOutcome, Say, Staging, finish
from .run_verify import part_faces, toolpath_and_cutter
from .specs import SimulateJob


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
    """Simulate ``tp`` on ``faces``; say and draw the result; return ``(SimulationResult, report)``."""
    from ..simulation import simulate

    res = simulate(faces, tp, cutter, tolerance=tolerance, progress=progress, **kw)
    rep = res.report()
    say(
        f"cut simulated (N-buffer) on {rep['n_faces']} face(s): {rep['n_samples']:,} samples "
        f"{res.resolution_mm:.3g} mm apart, {rep['n_placements']:,} placements ({res.motion_step_mm:.3g} mm apart, "
        f"refined over the motion: last change {res.motion_residual_mm:.2g} mm) in {res.time_s['total_s']:.2f} s"
    )
    say(
        f"  material left: max {rep['max_scallop_mm']:.4g} mm, mean {rep['mean_scallop_mm']:.4g} mm; "
        f"max gouge {rep['max_gouge_mm']:.4g} mm (tol {tolerance:g}"
        + (", deeper than --depth: a lower bound" if rep["gouge_deeper_than_depth"] else "")
        + f"); not reached within {res.stock_mm:g} mm: {100 * rep['not_reached_fraction']:.1f} % of the samples"
    )
    say("  area above: " + ", ".join(f"{h} mm {100 * f:.1f} %" for h, f in rep["fraction_above_mm"].items()))
    if rep["n_unconverged"]:
        say(f"  warning: {rep['n_unconverged']} ray(s) did not converge (their cut is a lower bound)")
    if render:
        from ..viz import render_simulation_map
        from ..viz.plots import plot_simulation_histogram

        render_simulation_map(
            res,
            st.path(f"{prefix}_map.png"),
            vtp_path=st.path(f"{prefix}_map.vtp"),
            title=f"{tp.name}: material left (max {rep['max_scallop_mm']:.3g} mm, gouge {rep['max_gouge_mm']:.3g} mm)",
        )
        plot_simulation_histogram(
            res.value,
            res.reached,
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
            tolerance=spec.tol,
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
