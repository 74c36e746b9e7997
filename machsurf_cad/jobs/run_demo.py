"""The main job on the embedded example part (``machsurf demo`` / ``make demo``).

Reads the free-form block (a real STEP part with a trimmed B-spline face), evaluates the
free-form face, exports it as STEP and STL, reads both back and measures them against the
exact nominal face: the STEP round trip and the STL's chordal deviation, drawn as a
deviation map. Then builds the 5-axis machining surfaces S1/S2 of a filleted end mill on
the face (trimmed like it), their deviation map against the exact offset, and a tool path
(CSV and APT CLDATA). Everything printed is in ``report.json``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..errors import InputError
from .base import JobOutcome, Say, Staging, finish
from .specs import DemoJob

DEFAULT_PART = Path(__file__).resolve().parents[2] / "example_parts" / "freeform_block.step"
STL_DEFLECTION_MM = 0.01
STL_ANGLE_DEG = 5.0
MS_TOL_MM = 1e-3
CHORDAL_MM = 0.005
GOUGE_TOL_MM = 0.01


def default_part_path(work_dir: Path) -> Path:
    """The embedded example part; rebuilt with the kernel when the checkout does not hold it."""
    if DEFAULT_PART.is_file():
        return DEFAULT_PART
    from ..occ.parts import write_freeform_block

    path = work_dir / "freeform_block.step"
    write_freeform_block(path)
    return path


def run_demo(spec: DemoJob, out, say: Say, progress=None) -> JobOutcome:
    from ..measure import deviation
    from ..meshsample import subdivide
    from ..occ import read_step_faces, read_stl
    from ..viz import render_deviation

    t0 = time.perf_counter()
    with Staging(out) as st:
        part = default_part_path(st.dir)
        faces = read_step_faces(part)
        try:
            nominal = next(f for f in faces if f.name == "freeform_top")
        except StopIteration:
            raise InputError(f"{part} has no face named freeform_top") from None
        say(
            f"part: {part} ({len(faces)} faces); nominal face {nominal.index} '{nominal.name}': "
            f"{nominal.source_type} degree {nominal.surface.degree_u}x{nominal.surface.degree_v}, "
            f"{nominal.surface.shape[0]}x{nominal.surface.shape[1]} poles, trimmed by {len(nominal.loops)} loop(s), "
            f"area {nominal.area:.1f} mm2"
        )

        # exact evaluation: curvature over the trimmed face
        props, kmax, i_worst = _sharpest_curvature(nominal)
        say(
            f"smallest radius of curvature on the face: {1 / kmax:.2f} mm at "
            f"({', '.join(f'{x:.2f}' for x in props.point[i_worst])}) mm"
        )

        # export the nominal face and a ball cutter touching it at that point
        step_path, stl_path, cutter = _export_nominal(st, nominal, props, i_worst)

        # read both back and measure against the exact nominal
        rt = _step_round_trip(say, nominal, step_path)
        pts, tris = read_stl(stl_path)
        spts, stris = subdivide(pts, tris, 2)
        mesh_dev = deviation(nominal, spts, tolerance=STL_DEFLECTION_MM, triangles=stris, progress=progress)
        s = mesh_dev.stats
        say(
            f"STL ({tris.shape[0]} triangles, deflection {STL_DEFLECTION_MM} mm): max |deviation| = "
            f"{s['max_abs']:.4g} mm, RMS {s['rms']:.3g} mm over {s['n_points']} points inside the triangles"
        )
        render_deviation(
            mesh_dev,
            st.path("deviation_stl.png"),
            vtp_path=st.path("deviation_stl.vtp"),
            title="STL mesh vs exact free-form face",
            tolerance=STL_DEFLECTION_MM,
        )

        # machining surfaces: 5-axis filleted end mill, lead 10 deg along planes parallel to yOz
        ms, ms_dev, tp, verify_rep = _machining(st, say, nominal, faces)
        report = {
            "part": str(part),
            "n_faces": len(faces),
            "nominal": _nominal_report(nominal, kmax),
            "step_round_trip": rt.report(),
            "stl": {
                "triangles": int(tris.shape[0]),
                "linear_deflection_mm": STL_DEFLECTION_MM,
                "angular_deflection_deg": STL_ANGLE_DEG,
                "deviation": mesh_dev.report(),
            },
            "cutter": cutter.to_dict(),
            "machining_surface": ms.report(),
            "S1_deviation_map": ms_dev.report(),
            "toolpath": tp.report(),
            "verify": verify_rep,
            "time_s": {"total_s": time.perf_counter() - t0},
        }
        (st.dir / "freeform_block.step").unlink(missing_ok=True)
        if "freeform_block.step" in st.files:
            st.files.remove("freeform_block.step")
        outcome = finish(st, "demo", report, result=ms)
    say(f"outputs in {out}/: " + ", ".join(outcome.files))
    return outcome


def _sharpest_curvature(nominal):
    """Curvature on a 120 x 120 grid over the trimmed face: the properties, the largest |k| and where it is."""
    from ..geometry import local_properties

    u0, u1, v0, v1 = nominal.uv_bounds
    us, vs = np.linspace(u0, u1, 120), np.linspace(v0, v1, 120)
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = nominal.contains_uv(U, V)
    props = local_properties(nominal.surface, U[inside], V[inside])
    kmax = float(np.max(np.maximum(np.abs(props.k1), np.abs(props.k2))))
    i_worst = int(np.argmax(np.maximum(np.abs(props.k1), np.abs(props.k2))))
    return props, kmax, i_worst


def _export_nominal(st: Staging, nominal, props, i_worst: int):
    """Write the nominal face (STEP, STL) and a ball cutter touching it at sample ``i_worst`` (STEP)."""
    from ..occ import write_step, write_stl
    from ..occ.solids import cutter_solid
    from ..occ.step import write_step_shape
    from ..toolspec import parse_cutter

    step_path = st.path("freeform_top.step")
    write_step(step_path, [nominal])
    stl_path = st.path("freeform_top.stl")
    write_stl(stl_path, [nominal], linear_deflection=STL_DEFLECTION_MM, angular_deflection=STL_ANGLE_DEG)
    cutter = parse_cutter("ball:D=10")
    n_out = props.normal[i_worst] * (-1.0 if nominal.reversed else 1.0)
    tip = props.point[i_worst] + cutter.radius * n_out - cutter.radius * np.array([0, 0, 1.0])
    write_step_shape(st.path("cutter_ball_D10.step"), cutter_solid(cutter, tip=tip), [])
    return step_path, stl_path, cutter


def _step_round_trip(say: Say, nominal, step_path):
    """The written STEP face read back: its deviation from the exact nominal (said)."""
    from ..measure import deviation
    from ..occ import read_step_faces

    back = read_step_faces(step_path)[0]
    rt = deviation(nominal, back, samples=150)
    say(
        f"STEP round trip: max |deviation| = {rt.max_abs:.3g} mm over {rt.stats['n_points']} points "
        f"(name '{back.name}', {len(back.loops)} loop(s))"
    )
    return rt


def _machining(st: Staging, say: Say, nominal, faces):
    """S1/S2 of a bull-nose mill (5 axes, lead 10 deg), their map and tool path, checked on the block, written."""
    from ..cam import write_apt, write_csv
    from ..machining import machining_surface
    from ..machining.surfaces import fit_deviation
    from ..machining.toolpath import tool_paths
    from ..occ import write_step
    from ..viz import render_deviation

    ms = machining_surface(
        nominal, "bull:D=16,r=3", axes=5, strategy="planes:x", lead=10.0, tilt=0.0, tolerance=MS_TOL_MM
    )
    write_step(st.path("machining_surface.step"), ms.faces())
    ms_dev = fit_deviation(ms, "S1")
    tp = tool_paths(ms, stepover=4.0, chordal_tolerance=CHORDAL_MM)
    render_deviation(
        ms_dev,
        st.path("deviation_S1.png"),
        vtp_path=st.path("deviation_S1.vtp"),
        title="S1 (bull D16 r3, lead 10 deg) fit vs exact offset; paths of K on S1",
        tolerance=MS_TOL_MM,
        extra_lines=[(p.extras["K"], "darkgreen") for p in tp.cutting_passes() if p.n_positions > 1],
    )
    from .run_verify import check_path

    # the tool body against all 8 faces of the block before the path is written
    _, verify_rep = check_path(st, say, tp, faces, tolerance=GOUGE_TOL_MM, render=True)
    if not verify_rep["clean"]:
        raise InputError("the demo's tool path gouges the block: " + str(verify_rep["worst"][:1]))
    write_csv(st.path("toolpath.csv"), tp)
    write_apt(st.path("toolpath.apt"), tp)
    assert ms.s2_fit is not None  # 5 axes
    say(
        f"machining surfaces (bull:D=16,r=3, 5 axes, lead 10 deg): S1 {ms.s1_fit.surface.shape[0]}x"
        f"{ms.s1_fit.surface.shape[1]} poles, max error {ms.s1_fit.max_error:.3g} mm; S2 "
        f"{ms.s2_fit.surface.shape[0]}x{ms.s2_fit.surface.shape[1]} poles, max error {ms.s2_fit.max_error:.3g} mm "
        f"(tol {MS_TOL_MM} mm); loops: {'none' if not ms.loops.found else len(ms.loops.regions)}; "
        f"axis error {ms.axis_error_deg:.3g} deg"
    )
    say(
        f"tool path: {tp.n_passes} passes, {tp.n_cut} cutting positions, chordal error "
        f"{tp.info['chordal_error_measured_mm']:.3g} mm"
    )
    return ms, ms_dev, tp, verify_rep


def _nominal_report(nominal, kmax: float) -> dict:
    """The report's ``nominal`` entry: the face's index, name, type, degrees, poles, loops, area, curvature."""
    return {
        "index": nominal.index,
        "name": nominal.name,
        "type": nominal.source_type,
        "degrees": [nominal.surface.degree_u, nominal.surface.degree_v],
        "poles": list(nominal.surface.shape),
        "loops": len(nominal.loops),
        "area_mm2": nominal.area,
        "min_radius_of_curvature_mm": 1 / kmax,
    }


__all__ = ["run_demo", "default_part_path", "DEFAULT_PART"]
