"""Evaluation benchmarks: 10^6 points with derivatives and normals, curvatures, projections."""

from __future__ import annotations

import time

import numpy as np

from machsurf_cad import examples
from machsurf_cad.geometry import builders, local_properties_grid
from machsurf_cad.geometry.bspline import unit_normals
from machsurf_cad.measure import project_points


def _surface(rational: bool):
    rng = np.random.default_rng(7)
    nu = nv = 20
    x = np.linspace(0, 200, nu)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = 20 * np.sin(X / 40) * np.cos(Y / 50) + rng.normal(scale=1, size=X.shape)
    w = rng.uniform(0.7, 1.5, (nu, nv)) if rational else None
    return builders.surface_from_grid(np.stack([X, Y, Z], -1), 3, 3, weights=w)


def _time(fn, repeat=1):
    best = np.inf
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def _eval_d1_normals(rational: bool, quick: bool):
    from OCP.gp import gp_Pnt, gp_Vec

    from machsurf_cad.occ import to_geom_surface

    s = _surface(rational)
    n = 100_000 if quick else 1_000_000
    rng = np.random.default_rng(1)
    u, v = rng.uniform(0, 1, (2, n))

    def ours():
        return s.evaluate_with_normals(u, v)

    t_ours, (P, N) = _time(ours, 5)
    g = to_geom_surface(s)

    def occt():
        pts = np.empty((n, 3))
        nrm = np.empty((n, 3))
        p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
        for i in range(n):
            g.D1(u[i], v[i], p, du, dv)
            c = du.Crossed(dv)
            c.Normalize()
            pts[i] = (p.X(), p.Y(), p.Z())
            nrm[i] = (c.X(), c.Y(), c.Z())
        return pts, nrm

    t_occ, (Po, No) = _time(occt)
    diff = max(np.abs(P - Po).max(), np.abs(N - No).max())
    kind = "rational" if rational else "non-rational"
    return {
        "name": f"point+d1+normal, scattered, bicubic {kind}",
        "n": n,
        "ours_s": t_ours,
        "ref_s": t_occ,
        "ref": "OCCT D1 per point",
        "max_diff": float(diff),
    }


def eval_nonrational(quick=False):
    return _eval_d1_normals(False, quick)


def eval_rational(quick=False):
    return _eval_d1_normals(True, quick)


def grid_d1_normals(quick=False):
    """10^6 points as a 1000 x 1000 parameter grid: point, d1, normal vs OCCT per point."""
    from OCP.gp import gp_Pnt, gp_Vec

    from machsurf_cad.occ import to_geom_surface

    s = _surface(True)
    m = 300 if quick else 1000
    us, vs = s.sample_grid(m, m)

    def ours():
        d = s.derivatives_grid(us, vs, 1)
        return d.point, unit_normals(d.su, d.sv, s.scale)

    t_ours, (P, N) = _time(ours, 3)
    g = to_geom_surface(s)

    def occt():
        pts = np.empty((m, m, 3))
        nrm = np.empty((m, m, 3))
        p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
        for i in range(m):
            for j in range(m):
                g.D1(us[i], vs[j], p, du, dv)
                c = du.Crossed(dv)
                c.Normalize()
                pts[i, j] = (p.X(), p.Y(), p.Z())
                nrm[i, j] = (c.X(), c.Y(), c.Z())
        return pts, nrm

    t_occ, (Po, No) = _time(occt)
    diff = max(np.abs(P - Po).max(), np.abs(N - No).max())
    return {
        "name": f"point+d1+normal, {m}^2 grid, bicubic rational",
        "n": m * m,
        "ours_s": t_ours,
        "ref_s": t_occ,
        "ref": "OCCT D1 per point",
        "max_diff": float(diff),
    }


def curvatures(quick=False):
    """Principal curvatures on a 1000 x 1000 grid vs GeomLProp_SLProps per point."""
    from OCP.GeomLProp import GeomLProp_SLProps

    from machsurf_cad.occ import to_geom_surface

    s = examples.propeller_blade()
    m = 300 if quick else 1000
    us, vs = s.sample_grid(m, m)
    U, V = np.meshgrid(us, vs, indexing="ij")
    t_ours, p = _time(lambda: local_properties_grid(s, us, vs), 3)
    g = to_geom_surface(s)
    props = GeomLProp_SLProps(g, 2, 1e-12)
    uf, vf = U.ravel(), V.ravel()

    def occt():
        k = np.empty((uf.size, 2))
        for i in range(uf.size):
            props.SetParameters(uf[i], vf[i])
            k[i] = (props.MaxCurvature(), props.MinCurvature())
        return k

    t_occ, k = _time(occt)
    diff = max(np.abs(p.k1.ravel() - k[:, 0]).max(), np.abs(p.k2.ravel() - k[:, 1]).max())
    return {
        "name": f"principal curvatures, {m}^2 grid, blade",
        "n": uf.size,
        "ours_s": t_ours,
        "ref_s": t_occ,
        "ref": "GeomLProp_SLProps",
        "max_diff": float(diff),
    }


def projection(quick=False):
    """Closest points of 10^5 points near the blade vs GeomAPI_ProjectPointOnSurf per point."""
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    from machsurf_cad.occ import to_geom_surface

    s = examples.propeller_blade()
    n = 10_000 if quick else 100_000
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0.02, 0.98, (2, n))
    d = s.derivatives(u, v, 1)
    nn = np.cross(d.su, d.sv)
    nn /= np.linalg.norm(nn, axis=1, keepdims=True)
    pts = d.point + rng.uniform(-3, 3, (n, 1)) * nn
    t_ours, proj = _time(lambda: project_points(s, pts))
    dist = np.linalg.norm(pts - proj.foot, axis=1)
    g = to_geom_surface(s)

    def occt():
        out = np.empty(n)
        proj_ = GeomAPI_ProjectPointOnSurf()
        for i in range(n):
            proj_.Init(gp_Pnt(*pts[i]), g)
            out[i] = proj_.LowerDistance() if proj_.NbPoints() else np.nan
        return out

    t_occ, dist_occ = _time(occt)
    ok = np.isfinite(dist_occ)
    return {
        "name": "closest point on surface, blade",
        "n": n,
        "ours_s": t_ours,
        "ref_s": t_occ,
        "ref": "GeomAPI_ProjectPoint",
        "max_diff": float(np.abs(dist[ok] - dist_occ[ok]).max()),
    }


BENCHMARKS = [eval_nonrational, eval_rational, grid_d1_normals, curvatures, projection]
