"""The pump's whole-part 3-axis raster: does ``simulate`` agree with ``verify`` and a brute-force body check?

Issue 25 item 4. On /work/shared/real-parts/ventpump.stp (Autodesk, centimetres, read in mm; 732 faces) the
raster ``machining-surface --faces top --axes 3 --tool bull:D=10,r=2 --stepover 2 --toolpath`` is clean by
``verify`` (a 0.007 mm dip: the chords' sag) while ``simulate`` used to report 1 mm gouges on 14 faces and
171 rays that did not converge. This script builds that path (or reads one: ``--toolpath``), then:

1. ``simulate`` on every face (default resolution): the machined region, the border, the gouge, the
   samples not measured;
2. ``verify`` on every face: the body check's gouge and where it lies;
3. a brute force written here: for every sample ``simulate`` finds below the nominal, and every sample of
   the faces the old figure blamed, the signed distance to the tool body placed every 0.1 mm along the
   moves (exact per placement), against ``simulate``'s value there;
4. ``simulate`` again, finer (``--fine`` mm), on the face of ``verify``'s worst point: the sampled gouge
   closes on ``verify``'s refined one as the samples close on the deepest point (``verify`` itself may lie
   up to its ``motion_bound_mm``, 0.005 mm, below the swept motion's depth).

Run ``python benchmarks/simulate_pump.py [--toolpath PATH] [--json OUT]`` (about 3 minutes with the path).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

PUMP = Path("/work/shared/real-parts/ventpump.stp")
OLD_GOUGED_FACES = (660, 661, 662, 663, 664, 665, 666, 667, 668, 669, 670, 671, 676, 697)
"""The faces the old ``simulate`` reported with 1 mm gouges on this raster."""


def _raster(faces, tool: str, stepover: float):
    from machsurf_cad.threeaxis import select_faces
    from machsurf_cad.threeaxis.paths import raster
    from machsurf_cad.toolspec import parse_cutter

    machined = select_faces(faces, "top", axis=(0.0, 0.0, 1.0), what="--faces")
    checked = [faces[i] for i in range(len(faces)) if i not in machined]
    tp = raster([faces[i] for i in machined], parse_cutter(tool), stepover=stepover, check_faces=checked,
                chordal_tolerance=0.005, gouge_tolerance=0.01)  # fmt: skip
    return tp, machined


def body_depth(cutter, tp, P, step: float = 0.1, chunk: int = 2000) -> np.ndarray:
    """Brute force: the smallest signed distance (mm, negative inside) of points ``P`` to the cutting body
    placed every ``step`` mm along every move of ``tp`` (exact per placement)."""
    from scipy.spatial import cKDTree

    from machsurf_cad.simulation.nbuffer import motion_poses

    T, A, _ = motion_poses(tp.tip, tp.axis, step, float(cutter.length))
    best = np.full(P.shape[0], np.inf)
    reach = float(np.hypot(cutter.radius, cutter.length)) + 1e-6
    tree = cKDTree(T)
    for i, near in enumerate(tree.query_ball_point(P, reach)):
        if near:
            q = P[i] - T[near]
            z = np.einsum("ij,ij->i", q, A[near])
            rho = np.sqrt(np.maximum(np.einsum("ij,ij->i", q, q) - z * z, 0.0))
            best[i] = float(cutter.cutting_distance_rz(rho, z).min())
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="simulate_pump")
    ap.add_argument("--toolpath", default=None, help="an APT/CSV path instead of building the raster")
    ap.add_argument("--tool", default="bull:D=10,r=2")
    ap.add_argument("--stepover", type=float, default=2.0)
    ap.add_argument("--fine", type=float, default=0.1, help="resolution of the re-run on verify's worst face, mm")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_faces

    if not PUMP.is_file():
        print(f"{PUMP} not found", file=sys.stderr)
        return 1
    t0 = time.perf_counter()
    faces = read_step_faces(PUMP)
    out: dict = {"part": str(PUMP), "n_faces": len(faces), "tool": args.tool, "stepover_mm": args.stepover}
    if args.toolpath:
        from machsurf_cad.jobs.inputs import read_toolpath_file

        tp = read_toolpath_file(Path(args.toolpath))
    else:
        tp, machined = _raster(faces, args.tool, args.stepover)
        out["faces_machined"] = machined
    out["path_s"] = time.perf_counter() - t0
    out["n_positions"] = int(tp.n_positions)

    sim = ms.simulate(faces, tp)
    rep = sim.report()
    gouged_faces = [f["face"] for f in rep["faces"] if f["max_gouge_mm"] > rep["gouge_tolerance_mm"]]
    out["simulate"] = {k: rep[k] for k in ("resolution_mm", "n_samples", "max_scallop_mm", "mean_scallop_mm",
                                           "machined_region", "border", "not_measured", "max_gouge_mm",
                                           "n_gouged_samples", "n_unconverged", "time_s")}  # fmt: skip
    out["simulate"]["faces_gouged_beyond_tol"] = gouged_faces
    out["simulate"]["max_cut_along_normal_mm"] = float(max(-np.min(sim.normal_value[sim.reached]), 0.0))

    t = time.perf_counter()
    ver = ms.verify(faces, tp)
    k = int(np.argmin(ver.cut_distance))
    out["verify"] = {
        "max_gouge_mm": float(ver.max_gouge),
        "worst_face": int(ver.worst_face[k]),
        "worst_xyz_mm": ver.worst_xyz[k].tolist(),
        "time_s": time.perf_counter() - t,
    }

    # brute force on what simulate finds below the nominal and on the faces the old figure blamed
    sel = np.flatnonzero(sim.reached & ((sim.value < -1e-6) | np.isin(sim.face, OLD_GOUGED_FACES)))
    t = time.perf_counter()
    brute = body_depth(sim.cutter, tp, sim.points[sel])
    inside = brute < 0
    diff = np.where(inside, sim.value[sel] - brute, np.minimum(sim.value[sel], 0.0))
    out["brute_force"] = {
        "n_samples": int(sel.size),
        "step_mm": 0.1,
        "max_gouge_mm": float(max(-brute.min(), 0.0)) if sel.size else 0.0,
        "max_abs_diff_inside_mm": float(np.abs(diff[inside]).max()) if inside.any() else 0.0,
        "max_simulated_gouge_where_outside_mm": float(-diff[~inside].min()) if (~inside).any() else 0.0,
        "time_s": time.perf_counter() - t,
    }

    # finer on the face of verify's worst point: the sampled gouge closes on the body check's refined one
    wf = out["verify"]["worst_face"]
    fine = ms.simulate([faces[wf]], tp, resolution=args.fine)
    out["fine"] = {"face": wf, "resolution_mm": args.fine, "max_gouge_mm": fine.max_gouge,
                   "n_samples": int(fine.points.shape[0]), "time_s": fine.time_s["total_s"]}  # fmt: skip
    out["total_s"] = time.perf_counter() - t0
    from machsurf_cad.results import strict_json

    text = strict_json(out)
    print(text)
    if args.json:
        Path(args.json).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
