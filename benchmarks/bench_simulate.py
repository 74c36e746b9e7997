"""Cut simulation (N-buffer) and iso-scallop passes.

1. A 5-axis ball path of 10^4 positions (100 passes 1 mm apart, the axis swinging +-10 deg) on the
   example free-form face sampled every 0.1 mm (10^6 samples), against a brute force written here: for
   a random subset of samples, the entry of the normal ray into every ball of the motion sampled every
   0.02 mm (ray-sphere, closed form), scaled to all samples. Goal: under 20 s for ours.
2. The same path at coarser resolutions: how the time grows with the sample count.
3. Iso-scallop against a constant step-over keeping the same scallop (the smallest iso spacing), on the
   free-form and on the 400 mm blade: passes and cutting length.
"""

from __future__ import annotations

import time

import numpy as np


def _ball_path(face, R: float = 5.0, n_pass: int = 100, n_pos: int = 100):
    import machsurf_cad as ms

    u = np.linspace(0.02, 0.98, n_pass)
    v = np.linspace(0.0, 1.0, n_pos)
    U, V = np.meshgrid(u, v, indexing="ij")
    d = face.derivatives(U, V, 1)
    n = np.cross(d.su, d.sv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    n *= np.sign(n[..., 2:3])
    centre = d.point + R * n
    tilt = np.radians(10.0 * np.sin(2 * np.pi * V))
    axis = np.stack([np.zeros_like(tilt), np.sin(tilt), np.cos(tilt)], -1)
    tips = centre - R * axis
    return ms.ToolPath.from_passes(list(tips), list(axis), cutter=ms.BallEndMill(2 * R), clearance=40.0), centre


def _brute(P, N, centre, R, step=0.02):
    """Lowest entry of each ray P + t N into the balls along the densely sampled centre paths (closed form)."""
    dense = []
    for c in centre:
        seg = np.linalg.norm(np.diff(c, axis=0), axis=1)
        k = np.maximum(1, np.ceil(seg / step).astype(int))
        parts = [c[:1]]
        for i in range(len(seg)):
            s = (np.arange(1, k[i] + 1) / k[i])[:, None]
            parts.append(c[i] * (1 - s) + c[i + 1] * s)
        dense.append(np.concatenate(parts))
    C = np.concatenate(dense)
    best = np.full(P.shape[0], np.inf)
    for i in range(0, C.shape[0], 2000):
        w = P[:, None, :] - C[None, i : i + 2000, :]
        b = np.einsum("ijk,ik->ij", w, N)
        disc = b * b - (np.einsum("ijk,ijk->ij", w, w) - R * R)
        t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        best = np.minimum(best, t.min(axis=1))
    return best, C.shape[0]


def simulate_rows(quick=False):
    import machsurf_cad as ms

    face = ms.example("bezier5")
    up = float(ms.local_properties(face, 0.5, 0.5).normal[2]) > 0
    F = ms.Face(face, name="bezier5", reversed=not up)
    tp, centre = _ball_path(face, n_pass=30 if quick else 100, n_pos=34 if quick else 100)
    rows = []
    res_list = (0.4, 0.2) if quick else (0.4, 0.2, 0.1)
    sims = {}
    for res in res_list:
        t = time.perf_counter()
        sims[res] = ms.simulate(F, tp, resolution=res, stock=2.0)
        sims[res].time_s["bench_s"] = time.perf_counter() - t
    fine = sims[res_list[-1]]
    rng = np.random.default_rng(0)
    pick = rng.choice(np.flatnonzero(fine.reached), 300 if quick else 2000, replace=False)
    t = time.perf_counter()
    brute, n_balls = _brute(fine.points[pick], fine.normals[pick], centre, 5.0)
    t_brute = (time.perf_counter() - t) * fine.points.shape[0] / pick.size
    ok = np.isfinite(brute)
    for res in res_list:
        s = sims[res]
        rows.append(
            {
                "name": f"simulate {tp.n_positions} pos x {s.points.shape[0]} samples ({res:g} mm)",
                "n": int(s.points.shape[0]),
                "ours_s": s.time_s["bench_s"],
                "ref_s": t_brute * s.points.shape[0] / fine.points.shape[0],
                "ref": f"ray-ball, {n_balls} balls*",
                "max_diff": float(np.abs(fine.value[pick][ok] - brute[ok]).max()) if s is fine else float("nan"),
                "samples_x_positions_per_s": s.report()["samples_x_positions_per_s"],
            }
        )
    return rows


def isoscallop_rows(quick=False):
    """Iso-scallop vs constant step-over with the same max scallop: passes and cutting length."""
    import machsurf_cad as ms
    from machsurf_cad.machining.isoscallop import iso_scallop_paths

    out = []
    cases = [("bezier5", "ball:D=10", 3, 0.0), ("bezier5", "bull:D=16,r=3", 5, 10.0)]
    if not quick:
        cases.append(("blade", "bull:D=20,r=4", 5, 10.0))
    for name, tool, axes, lead in cases:
        ms_res = ms.machining_surface(ms.example(name), tool, axes=axes, lead=lead, tolerance=1e-3)
        t = time.perf_counter()
        iso = iso_scallop_paths(ms_res, scallop=0.01, chordal_tolerance=0.002, clearance=60)
        t_iso = time.perf_counter() - t
        const = ms.tool_paths(
            ms_res, stepover=iso.info["spacing_min_mm"], chordal_tolerance=0.002, strategy=ms.IsoFeed("v")
        )
        out.append(
            {
                "case": f"{name} {tool} {axes} axes" + (f" lead {lead:g}" if axes == 5 else ""),
                "iso_passes": iso.info["n_passes_planned"],
                "iso_cut_length_mm": iso.cut_length(),
                "iso_spacing_mm": [iso.info["spacing_min_mm"], iso.info["spacing_max_mm"]],
                "constant_passes": const.n_passes,
                "constant_cut_length_mm": const.cut_length(),
                "plan_s": t_iso,
            }
        )
    return out


def print_iso(rows):
    print(f"{'iso-scallop 0.01 mm vs constant step-over (same max)':<52} {'passes':>14} {'cut length mm':>22}")
    for r in rows:
        print(
            f"{r['case']:<52} {r['iso_passes']:>6} vs {r['constant_passes']:>5} "
            f"{r['iso_cut_length_mm']:>10.0f} vs {r['constant_cut_length_mm']:>9.0f}"
        )
