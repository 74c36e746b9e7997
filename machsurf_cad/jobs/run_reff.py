"""The ``reff`` job: effective cutter radius and step-over maps."""

from __future__ import annotations

import time

import numpy as np

from ..batchrun.runner import chunk_map
from .base import JobOutcome, Say, Staging, face_input, finish
from .specs import ReffJob


def _f(x, fmt: str = ".4g") -> str:
    """A figure, or "n/a" where it does not exist (e.g. R_eff on a horizontal plane: infinite everywhere)."""
    return "n/a" if x is None else format(x, fmt)


def run_reff(spec: ReffJob, out, say: Say, progress=None) -> JobOutcome:
    from ..effradius import parse_directions, reff_maps
    from ..toolspec import parse_cutter

    t0 = time.perf_counter()
    cutter = parse_cutter(spec.tool)
    face, desc = face_input(spec.part, spec.example, spec.face)
    dirs = parse_directions(spec.direction)
    compare = None if spec.compare == "none" else spec.compare
    maps = reff_maps(
        face,
        cutter,
        directions=dirs,
        grid=spec.grid,
        compare=compare,
        scallop=spec.scallop,
        axes=spec.axes,
        lead=spec.lead,
        tilt=spec.tilt,
        max_memory_mb=spec.max_memory_mb,
        chunks=int(spec.chunks),
        map_chunks=chunk_map(spec.chunks),
    )
    rep = maps.report()
    _say_maps(say, spec, maps, rep, cutter, desc)
    with Staging(out) as st:
        if spec.render:
            _render_maps(st, spec, maps, rep, cutter, dirs)
        rep["face"] = desc
        rep["time_s"]["job_total_s"] = time.perf_counter() - t0
        outcome = finish(st, "reff", rep, result=maps)
    say(f"outputs in {out}/: {', '.join(outcome.files)}")
    return outcome


def _say_maps(say: Say, spec: ReffJob, maps, rep: dict, cutter, desc: str) -> None:
    """Say the face and tools, then per direction the R_eff figures (and step-overs for a scallop height)."""
    R = cutter.D / 2
    say(
        f"face: {desc}; tool {cutter.spec()} (R = {R:g} mm, r = {rep['r_mm']:g} mm) vs "
        f"{maps.compare.spec() if maps.compare else 'nothing'}; {maps.axes} axes"
        + (f", lead {spec.lead:g} deg, tilt {spec.tilt:g} deg" if maps.axes == 5 else "")
        + f"; grid {spec.grid}x{spec.grid}; computed in {maps.time_s:.3f} s"
    )
    for d in rep["directions"]:
        line = (
            f"theta {d['theta_deg']:>6g} deg: R_eff min {_f(d['r_eff_min_mm'])} / mean {_f(d['r_eff_mean_mm'])} / "
            f"max {_f(d['r_eff_max_mm'])} mm; torus beats ball on {_f(d['area_fraction_torus_beats_ball'], '.1%')} "
            f"of the area"
        )
        if d.get("n_infinite_r_eff"):
            line += f"; {d['n_infinite_r_eff']} flat-spot sample(s) with infinite R_eff"
        line += (
            f"; unreachable {d['unreachable_fraction']:.1%} of the area ({d['n_facing_away_samples']} sample(s) facing "
            "away from the axis, the rest concave tighter than the tool), left out of these figures"
        )
        say(line)
        if spec.scallop:
            say(
                f"    step-over for scallop {spec.scallop:g} mm, between tool centres: torus "
                f"{_f(d.get('stepover_mean_mm'))} mm, ball {_f(d.get('stepover_ball_mean_mm'))} mm (ratio "
                f"{_f(d.get('stepover_ratio_mean'), '.3f')}); on the surface between adjacent contacts: torus "
                f"{_f(d.get('stepover_surface_mean_mm'))} mm (min {_f(d.get('stepover_surface_min_mm'))}), ball "
                f"{_f(d.get('stepover_surface_ball_mean_mm'))} mm"
            )


def _render_maps(st: Staging, spec: ReffJob, maps, rep: dict, cutter, dirs) -> None:
    """Draw every direction's R_eff map (PNG, VTP with its other maps) and the best direction's map."""
    from ..viz import render_scalar_map

    R = cutter.D / 2
    mask = maps.inside if maps.face.is_trimmed else None
    for d in maps.directions:
        tag = f"{d.theta_deg:g}".replace("-", "m")
        render_scalar_map(
            maps.points,
            d.r_eff,
            st.path(f"reff_theta{tag}.png"),
            title=f"effective radius, {cutter.spec()}, theta = {d.theta_deg:g} deg\n"
            f"white line: R_eff = {maps.R_ball:g} mm (ball)",
            label="R_eff [mm]",
            clim=(rep["r_mm"] or 0.0, 2 * R),
            contour_level=maps.R_ball,
            mask=mask,
            vtp_path=st.path(f"reff_theta{tag}.vtp"),
            extra_arrays=_extra_arrays(maps, d),
            view="xy",
        )
    if maps.best_theta_deg is not None:
        render_scalar_map(
            maps.points,
            maps.best_theta_deg,
            st.path("best_direction.png"),
            title=f"best machining direction ({'step-over' if spec.scallop else 'R_eff'}), deg",
            label="theta [deg]",
            clim=(min(dirs), max(dirs)),
            cmap="viridis",
            mask=mask,
            vtp_path=st.path("best_direction.vtp"),
            view="xy",
            categories=sorted(dirs),
        )


def _extra_arrays(maps, d) -> dict:
    """A direction's other maps for its VTP: slope, alpha, ratio to the ball, unreachable, step-overs."""
    extra = {
        "slope_deg": d.slope_deg,
        "alpha_deg": d.alpha_deg,
        "ratio_to_ball": np.nan_to_num(d.r_eff / maps.R_ball, posinf=1e300),
    }
    extra["unreachable"] = d.unreachable.astype(np.uint8)
    if d.stepover is not None:
        extra.update(
            {
                "stepover_mm": np.nan_to_num(d.stepover, nan=-1, posinf=1e300),
                "stepover_ball_mm": np.nan_to_num(d.stepover_ball, nan=-1, posinf=1e300),
                "stepover_surface_mm": np.nan_to_num(d.stepover_surface, nan=-1, posinf=1e300),
            }
        )
    return extra
