"""S1 = F + r n: machsurf_cad's certified bicubic fit vs OCCT's GeomConvert_ApproxSurface on a
Geom_OffsetSurface (bicubic C2, and OCCT's own choice of degree up to 9), both measured against
the exact offset by the same dense sampling (301 x 301 points off every knot)."""

from __future__ import annotations

import time

import numpy as np

from machsurf_cad import examples
from machsurf_cad.approx import fit_surface
from machsurf_cad.geometry.bspline import unit_normals
from machsurf_cad.machining.surfaces import derived_breaks


def _cases():
    from pathlib import Path

    from machsurf_cad.occ import read_step_faces

    top = read_step_faces(Path(__file__).resolve().parent.parent / "example_parts" / "freeform_block.step")[0]
    return [
        ("bezier5, r = 4", examples.bezier5_patch(), 4.0),
        ("blade, r = 5", examples.propeller_blade(), 5.0),
        ("freeform_top, r = 5", top.surface, 5.0),
    ]


def _measure(F, r, surf_eval, n=301):
    u0, u1, v0, v1 = F.bounds
    shift = (np.arange(n) + 0.3819660112501051) / n
    us, vs = u0 + (u1 - u0) * shift, v0 + (v1 - v0) * shift
    d = F.derivatives_grid(us, vs, 1)
    exact = d.point + r * unit_normals(d.su, d.sv, F.scale)
    return float(np.linalg.norm(surf_eval(us, vs) - exact, axis=-1).max())


def _occt(F, r, tol, max_deg):
    from OCP.Geom import Geom_OffsetSurface
    from OCP.GeomAbs import GeomAbs_C2

    from machsurf_cad.occ import from_geom_surface, to_geom_surface

    t = time.perf_counter()
    off = Geom_OffsetSurface(to_geom_surface(F), r)
    app = GeomConvert_ApproxSurface_(off, tol, GeomAbs_C2, GeomAbs_C2, max_deg, max_deg, 10000, 1)
    dt = time.perf_counter() - t
    if not app.HasResult():
        return None
    s = from_geom_surface(app.Surface())
    return s, dt, app.MaxError()


def GeomConvert_ApproxSurface_(*args):
    from OCP.GeomConvert import GeomConvert_ApproxSurface

    return GeomConvert_ApproxSurface(*args)


def offset_fit_rows(quick=False):
    rows = []
    tols = (1e-3,) if quick else (1e-3, 1e-4)
    for name, F, r in _cases():

        def s1(us, vs, F=F, r=r):
            d = F.derivatives_grid(us, vs, 1)
            return d.point + r * unit_normals(d.su, d.sv, F.scale)

        for tol in tols:
            t = time.perf_counter()
            fit = fit_surface(s1, F.bounds, tolerance=tol, breaks=derived_breaks(F))
            t_ours = time.perf_counter() - t
            e_ours = _measure(F, r, fit.surface.evaluate_grid)
            row = {
                "case": name,
                "tol": tol,
                "ours_poles": fit.n_poles,
                "ours_deg": "3x3",
                "ours_s": t_ours,
                "ours_err": e_ours,
            }
            for label, deg in (("occt3", 3), ("occt9", 9)):
                res = _occt(F, r, tol, deg)
                if res is None:
                    row.update({f"{label}_poles": None, f"{label}_deg": "-", f"{label}_s": None, f"{label}_err": None})
                    continue
                s, dt, _ = res
                row.update(
                    {
                        f"{label}_poles": int(s.shape[0] * s.shape[1]),
                        f"{label}_deg": f"{s.degree_u}x{s.degree_v}",
                        f"{label}_s": dt,
                        f"{label}_err": _measure(F, r, s.evaluate_grid),
                    }
                )
            if row.get("occt3_err"):
                same = fit_surface(s1, F.bounds, tolerance=row["occt3_err"], breaks=derived_breaks(F))
                row["ours_at_occt3_err_poles"] = same.n_poles
                row["ours_at_occt3_err_err"] = _measure(F, r, same.surface.evaluate_grid)
            rows.append(row)
    return rows


def print_rows(rows):
    print(
        f"\n{'S1 = F + r n fit':<22} {'tol mm':>7} | {'ours poles':>10} {'err mm':>9} {'s':>6} | "
        f"{'OCCT bicubic poles':>18} {'err mm':>9} {'s':>6} | {'OCCT best deg':>13} {'poles':>6} {'err mm':>9} "
        f"{'s':>6} | {'ours at OCCT-3 err: poles':>25} {'ratio':>6} {'time ours/occt3':>15}"
    )
    print("-" * 188)
    for r in rows:

        def f(x, fmt):
            return format(x, fmt) if x is not None else "-"

        same = r.get("ours_at_occt3_err_poles")
        ratio_p = same / r["occt3_poles"] if same and r.get("occt3_poles") else float("nan")
        ratio_t = r["ours_s"] / r["occt3_s"] if r.get("occt3_s") else float("nan")
        print(
            f"{r['case']:<22} {r['tol']:>7.0e} | {r['ours_poles']:>10} {r['ours_err']:>9.2e} {r['ours_s']:>6.3f} | "
            f"{f(r['occt3_poles'], '>18')} {f(r['occt3_err'], '>9.2e')} {f(r['occt3_s'], '>6.3f')} | "
            f"{r['occt9_deg']:>13} {f(r['occt9_poles'], '>6')} {f(r['occt9_err'], '>9.2e')} "
            f"{f(r['occt9_s'], '>6.3f')} | {f(same, '>25')} {ratio_p:>6.2f} {ratio_t:>15.2f}",
            flush=True,
        )
