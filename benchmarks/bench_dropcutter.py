"""Exact drop-cutter on the B-rep against OpenCAMLib's BatchDropCutter on a fine mesh (same STEP part,
same plan grid, in one run), and a full raster path with linking on the 51-face mould insert."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _grid(lo, hi, n):
    x, y = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    return np.column_stack([x.ravel(), y.ravel()])


def dropcutter_rows(quick=False, deflection=0.001):
    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_faces, triangulate_step
    from machsurf_cad.threeaxis.reference import has_opencamlib, ocl_drop_cutter

    rows = []
    cutter = ms.BullNoseEndMill(10, 2)
    cases = [("bezier5_patch.step", "1 free-form face"), ("mould_insert.step", "mould insert, 51 faces")]
    sizes = [31, 61] if quick else [61, 200]
    for fname, label in cases:
        path = ROOT / "example_parts" / fname
        faces = read_step_faces(path)
        t = time.perf_counter()
        P, T = triangulate_step(path, linear_deflection=deflection, angular_deflection=2.0)
        t_mesh = time.perf_counter() - t
        lo, hi = P.min(axis=0)[:2], P.max(axis=0)[:2]
        for n in sizes:
            xy = _grid(lo, hi, n)
            t = time.perf_counter()
            ours = ms.drop_cutter(faces, cutter, xy).height
            t_ours = time.perf_counter() - t
            if has_opencamlib():
                t = time.perf_counter()
                ref = ocl_drop_cutter(P, T, cutter, xy)
                t_ref = time.perf_counter() - t
                diff = float(np.nanmax(np.abs(ours - ref)))
                name = f"OpenCAMLib {len(T) // 1000}k tri"
            else:
                t_ref, diff, name = float("nan"), float("nan"), "OpenCAMLib missing"
            rows.append(
                {
                    "name": f"drop-cutter bull D10 r2, {label}",
                    "n": int(xy.shape[0]),
                    "ours_s": t_ours,
                    "ref_s": t_ref,
                    "ref": name,
                    "max_diff": diff,
                    "mesh_s": t_mesh,
                    "mesh_deflection_mm": deflection,
                }
            )
    path = ROOT / "example_parts" / "mould_insert.step"
    faces = read_step_faces(path)
    top = ms.top_faces(faces)
    rest = [f for i, f in enumerate(faces) if i not in top]
    t = time.perf_counter()
    tp = ms.raster([faces[i] for i in top], cutter, check_faces=rest, stepover=4.0 if quick else 1.0,
                   chordal_tolerance=0.01)  # fmt: skip
    t_path = time.perf_counter() - t
    t = time.perf_counter()
    v = ms.verify(faces, tp, gouge_tolerance=0.01)
    t_verify = time.perf_counter() - t
    rows.append(
        {
            "name": f"raster path + links, 51 faces, {tp.n_cut} pos",
            "n": int(tp.n_cut),
            "ours_s": t_path,
            "ref_s": t_verify,
            "ref": "(verify of that path)",
            "max_diff": float(v.max_gouge),
        }
    )
    return rows
