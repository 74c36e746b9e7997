"""Chains of passes, certified B-spline faces per pass, seam verification on the fitted faces."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..approx import SurfaceFit, fit_surface
from ..results import Result
from .core import Envelope, fold_check, next_pass, seam_report


@dataclass(frozen=True, eq=False)
class PassChain(Result):
    """N passes, each joined to the previous one; fits and seam figures (mm, degrees)."""

    passes: tuple
    fits: tuple
    seams_exact: tuple
    seams_fitted: tuple
    folds: tuple
    continuity: str
    timings: dict

    def report(self) -> dict:
        return {
            "continuity": self.continuity,
            "passes": [
                {
                    "name": e.name,
                    "tool": e.cutter.spec(),
                    "a_range": list(e.a_range),
                    "t_range": list(e.motion.t_range),
                    "side": e.side,
                    "fit": f.report(),
                }
                for e, f in zip(self.passes, self.fits)
            ],
            "seams": [
                {"between": [i, i + 1], "exact": s, "fitted": sf, "fold_check": fc}
                for i, (s, sf, fc) in enumerate(zip(self.seams_exact, self.seams_fitted, self.folds))
            ],
            "time_s": self.timings,
        }


def fit_pass(env: Envelope, tolerance: float = 1e-3, max_poles: int = 40000, progress=None) -> SurfaceFit:
    """The pass's envelope as a B-spline face within ``tolerance`` (mm), parameterised like X(a, t);
    ``progress`` is called after each refinement of the fit (see :func:`~machsurf_cad.approx.fit_surface`)."""
    return fit_surface(env.grid, env.bounds, tolerance=tolerance, max_poles=max_poles, name=env.name, progress=progress)


def fitted_seam(f1: SurfaceFit, f2: SurfaceFit, n: int = 401) -> dict:
    """Gap and normal angle along the seam, measured on the fitted faces (independent of the maps)."""
    s1, s2 = f1.surface, f2.surface
    u1 = s1.bounds[1]
    u0 = s2.bounds[0]
    t = np.linspace(s1.bounds[2], s1.bounds[3], n)
    d1 = s1.derivatives(np.full(n, u1), t, 1)
    d2 = s2.derivatives(np.full(n, u0), t, 1)
    gap = np.linalg.norm(d1.point - d2.point, axis=1)
    n1 = np.cross(d1.su, d1.sv)
    n2 = np.cross(d2.su, d2.sv)
    n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
    n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
    ang = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", n1, n2)), -1, 1)))
    return {"max_gap_mm": float(gap.max()), "max_normal_angle_deg": float(ang.max()), "n_samples": n}


def build_chain(
    first: Envelope,
    n_passes: int = 2,
    *,
    continuity: str = "g1",
    theta_deg=0.0,
    tools=None,
    tolerance: float = 1e-3,
    max_poles: int = 40000,
    kink_deg: float = 10.0,
    progress=None,
) -> PassChain:
    """``n_passes`` passes from ``first``, each from the previous by :func:`next_pass`; every pass is
    fitted within ``tolerance`` and every seam measured before and after fitting.

    ``theta_deg`` is one angle or one per seam; ``tools`` optionally one cutter per later pass;
    ``progress`` (:data:`~machsurf_cad.results.Progress`) is called as the fits refine.
    """
    from ..errors import InputError

    if n_passes < 1:
        raise InputError("n_passes must be >= 1")
    thetas = list(np.broadcast_to(np.asarray(theta_deg, float), (max(n_passes - 1, 0),)))
    t0 = time.perf_counter()
    envs = [first]
    folds = []
    for k in range(n_passes - 1):
        tool = None if tools is None else tools[k]
        nxt = next_pass(
            envs[-1], tool, continuity=continuity, theta_deg=thetas[k], kink_deg=kink_deg, name=f"pass_{k + 2}"
        )
        fc = fold_check(envs[-1], nxt)
        folds.append(fc)
        if fc["folds_back"] or not fc["real_envelope"]:
            raise InputError(
                f"pass {k + 2} with theta = {thetas[k]:g} deg "
                + (
                    f"folds back over pass {k + 1} (at t = {', '.join(f'{x:.3g}' for x in fc['fold_t'][:3])})"
                    if fc["folds_back"]
                    else f"has no real envelope at {fc['n_no_envelope']} sample(s)"
                )
                + ": choose a smaller |theta|"
            )
        envs.append(nxt)
    envs[0] = Envelope(first.motion, first.cutter, first.segment, first.side, first.a_range, "pass_1")
    t_build = time.perf_counter() - t0
    fits = []
    t1 = time.perf_counter()
    for e in envs:
        fits.append(fit_pass(e, tolerance, max_poles, progress))
    t_fit = time.perf_counter() - t1
    seams = tuple(seam_report(a, b) for a, b in zip(envs[:-1], envs[1:]))
    seams_f = tuple(fitted_seam(a, b) for a, b in zip(fits[:-1], fits[1:]))
    return PassChain(
        tuple(envs), tuple(fits), seams, seams_f, tuple(folds), continuity, {"build_s": t_build, "fit_s": t_fit}
    )


def max_theta(first: Envelope, *, continuity: str = "g1", step_deg: float = 5.0) -> float:
    """Largest abs(theta) (degrees, scanned by ``step_deg``) for which the next pass neither folds back nor
    loses its real envelope; checked, not assumed."""
    from ..errors import DegenerateGeometryError

    ok = 0.0
    th = step_deg
    while th < 180.0:
        good = True
        for sgn in (1, -1):
            try:
                nxt = next_pass(first, continuity=continuity, theta_deg=sgn * th)
                fc = fold_check(first, nxt)
                good &= not fc["folds_back"] and fc["real_envelope"]
            except DegenerateGeometryError:
                good = False
        if not good:
            break
        ok = th
        th += step_deg
    return ok
