"""Effective-radius map: 1024 x 1024 on the propeller face (slope, direction, R_eff, step-over) vs the
same grid through per-point OCCT property calls (GeomLProp_SLProps normal + curvatures, then the
formula per point)."""

from __future__ import annotations

import math
import time

import numpy as np

from machsurf_cad import examples
from machsurf_cad.effradius import effective_radius, reff_maps, stepover


def reff_rows(quick=False):
    from OCP.GeomLProp import GeomLProp_SLProps
    from OCP.gp import gp_Dir

    from machsurf_cad.occ import to_geom_surface

    F = examples.propeller_blade()
    g = 256 if quick else 1024
    t = time.perf_counter()
    m = reff_maps(F, "bull:D=10,r=2", directions=[0.0], grid=g, scallop=0.01)
    cold = time.perf_counter() - t
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        m = reff_maps(F, "bull:D=10,r=2", directions=[0.0], grid=g, scallop=0.01)
        best = min(best, time.perf_counter() - t)
    d = m.directions[0]
    # per point through OCCT: normal, principal curvatures and directions, then the formulas
    geom = to_geom_surface(F)
    props = GeomLProp_SLProps(geom, 2, 1e-12)
    n_ref = 64 if quick else 256  # per-point time measured on a sub-grid, scaled to the full grid
    idx = np.linspace(0, g - 1, n_ref).astype(int)
    vals = np.empty((n_ref, n_ref))
    t = time.perf_counter()
    dmax, dmin = gp_Dir(), gp_Dir()
    for a, i in enumerate(idx):
        for b, j in enumerate(idx):
            props.SetParameters(float(m.us[i]), float(m.vs[j]))
            nn = props.Normal()
            n = np.array([nn.X(), nn.Y(), nn.Z()])
            k1, k2 = props.MaxCurvature(), props.MinCurvature()
            props.CurvatureDirections(dmax, dmin)
            e1 = np.array([dmax.X(), dmax.Y(), dmax.Z()])
            S = math.degrees(math.acos(min(1.0, abs(n[2]))))
            fz = -n[0] / n[2]
            f = np.array([1.0, 0.0, fz]) / math.hypot(1.0, fz)
            sinS = math.hypot(n[0], n[1])
            cos_a = abs(n[0]) / sinS
            r_eff = float(effective_radius("bull:D=10,r=2", S, math.degrees(math.acos(min(1.0, cos_a)))))
            tdir = np.cross(f, n)
            c = float(tdir @ e1)
            kn = k1 * c * c + k2 * (1 - c * c)
            rho = -1.0 / kn if abs(kn) > 1e-14 else math.inf
            vals[a, b] = float(stepover(0.01, r_eff, rho)[0])
    per_point = (time.perf_counter() - t) / (n_ref * n_ref)
    occ_full = per_point * g * g
    diff = float(np.nanmax(np.abs(vals - d.stepover[np.ix_(idx, idx)])))
    return [
        {
            "name": f"R_eff + step-over map {g}^2, blade (warm)",
            "n": g * g,
            "ours_s": best,
            "ref_s": occ_full,
            "ref": "SLProps per point*",
            "max_diff": diff,
        },
        {
            "name": f"R_eff + step-over map {g}^2, blade (cold)",
            "n": g * g,
            "ours_s": cold,
            "ref_s": occ_full,
            "ref": "SLProps per point*",
            "max_diff": diff,
        },
    ]
