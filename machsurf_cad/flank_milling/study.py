"""The paper's parameter study (figures 9 and 10): error ratio standard / optimum on the hyperbolic
paraboloid of section 3.2 (k = h_p, rule at u = 0.5), against the tool radius R for several
alpha0 and several h_p. Errors are max |interference| along the rule (mm)."""

from __future__ import annotations

import math

import numpy as np

from .settings import NoAdmissibleSetting, interference, optimum_setting, standard_setting


def ratio_curve(alpha0_deg: float, h_p: float, radii) -> dict:
    """Standard-distributed and optimum errors and their ratio for each R (NaN where no optimum)."""
    from ..examples import hypar_ruled

    s = hypar_ruled(alpha0_deg, h_p)
    std, opt = [], []
    for R in radii:
        e_s = interference(s, standard_setting(s, 0.5, float(R))).max_abs
        try:
            e_o = interference(s, optimum_setting(s, 0.5, float(R))).max_abs
        except NoAdmissibleSetting:
            e_o = math.nan
        std.append(e_s)
        opt.append(e_o)
    std_a, opt_a = np.array(std), np.array(opt)
    return {
        "alpha0_deg": alpha0_deg,
        "h_p_mm": h_p,
        "R_mm": [float(r) for r in radii],
        "standard_mm": std_a.tolist(),
        "optimum_mm": opt_a.tolist(),
        "ratio": (std_a / opt_a).tolist(),
        "R_limit_mm": h_p / (2 * math.sin(math.radians(alpha0_deg))),
    }


def parameter_study(
    alphas=(10.0, 20.0, 30.0, 45.0),
    h_ps=(40.0, 80.0, 120.0),
    alpha_fixed: float = 30.0,
    h_p_fixed: float = 80.0,
    n_r: int = 12,
) -> dict:
    """Curves against R: one per alpha0 at h_p = h_p_fixed (fig. 10), one per h_p at alpha0 = alpha_fixed (fig. 9).

    R runs from 2 mm to just below the three-tangency limit h_p / (2 sin alpha0).
    """

    def radii(a, h):
        lim = h / (2 * math.sin(math.radians(a)))
        return np.geomspace(2.0, 0.98 * lim, n_r)

    by_alpha = [ratio_curve(a, h_p_fixed, radii(a, h_p_fixed)) for a in alphas]
    by_hp = [ratio_curve(alpha_fixed, h, radii(alpha_fixed, h)) for h in h_ps]
    return {
        "by_alpha0": by_alpha,
        "by_h_p": by_hp,
        "min_ratio": float(np.nanmin([r for c in by_alpha + by_hp for r in c["ratio"]])),
    }
