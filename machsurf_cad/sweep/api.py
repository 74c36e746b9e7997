"""``envelope()``: everything ``machsurf envelope`` computes, as one result (mm, degrees, seconds)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..cam.chordal import chord_error, douglas_peucker
from ..cam.toolpath import ToolPath
from ..errors import InputError
from ..glossary import renamed
from ..results import Result
from ..typing import ArrayLike, ProgressLike, ToolLike
from .core import Motion, make_envelope
from .passes import PassChain, build_chain, max_theta

Continuity = Literal["g0", "g1"]
"""Continuity between adjacent passes: G1 (Corollaries 5.2, 5.3) or G0 with a crease (eq. (41))."""


@dataclass(frozen=True, eq=False)
class EnvelopeResult(Result):
    """Chained passes with certified faces, seams, fold checks; the tool path along the passes; the
    other continuity's chain for comparison (zebra) and the admissible theta range when asked."""

    chain: PassChain
    toolpath: ToolPath
    other: PassChain | None = None
    max_theta_deg: float | None = None
    time_s: dict | None = None

    def seam_check(self, angle_tol_deg: float = 0.05) -> dict:
        """What the written faces achieve at their seams (measured on the fitted faces, not claimed):
        the largest gap (mm) against twice the fit tolerance, the largest normal angle (degrees)
        against ``angle_tol_deg`` for G1."""
        seams = self.chain.seams_fitted
        gap = max((s["max_gap_mm"] for s in seams), default=0.0)
        ang = max((s["max_normal_angle_deg"] for s in seams), default=0.0)
        tol = max(f.tolerance for f in self.chain.fits)
        g0 = gap <= 2 * tol
        g1 = g0 and ang <= angle_tol_deg
        return {
            "max_gap_mm": gap,
            "gap_limit_mm": 2 * tol,
            "max_normal_angle_deg": ang,
            "angle_limit_deg": angle_tol_deg,
            "g0_met": g0,
            "g1_met": g1,
            "achieved": "G1" if g1 else ("G0" if g0 else "none"),
        }

    def report(self) -> dict:
        rep = self.chain.report()
        rep["chain_time_s"] = rep.pop("time_s")
        rep.update(
            {
                "tool": self.chain.passes[0].cutter.to_dict(),
                "motion": self.chain.passes[0].motion.label,
                "toolpath": self.toolpath.report(),
                "time_s": dict(self.time_s or {}),
            }
        )
        if self.max_theta_deg is not None:
            rep["max_theta_deg"] = self.max_theta_deg
        if self.other is not None:
            rep["other_continuity"] = {
                "continuity": self.other.continuity,
                "seams": [{"fitted": s} for s in self.other.seams_fitted],
            }
        return rep


def chain_toolpath(
    chain: PassChain, *, chordal_tolerance: float = 0.01, n_dense: int = 2001, clearance: float = 5.0
) -> ToolPath:
    """The passes' motions as the one :class:`ToolPath` type: tip and axis sampled densely along each
    pass, kept where the chords stay within ``chordal_tolerance`` mm of the dense tip path (measured)."""
    if not chordal_tolerance > 0:
        raise InputError("chordal tolerance must be > 0 mm")
    tips: list[np.ndarray] = []
    axes: list[np.ndarray] = []
    extras: list[dict] = []
    err = 0.0
    for e in chain.passes:
        t = np.linspace(*e.motion.t_range, n_dense)
        T, A = e.motion.T(t), e.motion.A(t)
        six = np.concatenate([T, T + e.cutter.D * A], axis=1)  # the tip and a point one diameter up the axis
        idx = douglas_peucker(six, chordal_tolerance)
        err = max(err, chord_error(six, idx))
        if len(tips) % 2 == 1:
            idx = idx[::-1]
        tips.append(T[idx])
        axes.append(A[idx])
        extras.append({"t": t[idx]})
    tools = sorted({e.cutter.spec() for e in chain.passes})
    return ToolPath.from_passes(
        tips,
        axes,
        extras=extras,
        clearance=clearance,
        cutter=chain.passes[0].cutter,
        name="envelope_passes",
        info={"chordal_tolerance_mm": float(chordal_tolerance), "chordal_error_measured_mm": err, "tools": tools},
    )


@renamed(theta_deg="theta")
def envelope(
    tool: ToolLike,
    motion: Motion,
    *,
    passes: int = 1,
    continuity: Continuity = "g1",
    theta: ArrayLike = 0.0,
    tolerance: float = 1e-3,
    side: int = 1,
    theta_scan: bool = False,
    compare: bool = False,
    chordal_tolerance: float = 0.01,
    clearance: float = 5.0,
    progress: ProgressLike = None,
) -> EnvelopeResult:
    """Swept envelopes of a rotational tool along a motion, chained G1 or G0 (Aranda Bassegoda, eq. (21)).

    Parameters
    ----------
    tool : str or Cutter
        Cylinder (``cyl:D=..``), cone, drum, barrel or ball.
    motion : Motion
        Tip path and axis of the first pass.
    passes : int
        Number of passes (>= 1).
    continuity : {"g1", "g0"}
        Between adjacent passes.
    theta : float or sequence of float
        Turn of each next axis about the seam normal, degrees (one, or one per seam).
    tolerance : float
        Fit tolerance of each pass's face, max-norm mm (measured on unseen points).
    side : {1, -1}
        Envelope sheet of the first pass.
    theta_scan : bool
        Also scan the largest admissible abs(theta) (5 deg steps).
    compare : bool
        Also build the chain with the other continuity (for a G0/G1 comparison).
    chordal_tolerance, clearance : float
        Of the tool path along the passes, mm.
    progress : callable, optional
        :data:`~machsurf_cad.results.Progress`, called after each refinement of a pass's fit (no total known).

    Returns
    -------
    EnvelopeResult

    Examples
    --------
    >>> from machsurf_cad import envelope, examples
    >>> res = envelope("cyl:D=10", examples.line_motion(), tolerance=1e-3)
    >>> res.chain.fits[0].max_error <= 1e-3, res.toolpath.n_passes
    (True, 1)
    """
    from .. import checks

    t0 = time.perf_counter()
    if not isinstance(motion, Motion):
        raise InputError(
            f"envelope needs a Motion (ms.example(name, 'motion') or a path file), got {type(motion).__name__}"
        )
    tool = checks.tool(tool)
    passes = checks.index("passes", passes, low=1)
    checks.positive("tolerance", tolerance)
    checks.positive("chordal tolerance", chordal_tolerance)
    checks.positive("clearance", clearance)
    if continuity not in ("g0", "g1"):
        raise InputError("continuity must be 'g0' or 'g1'")
    thetas = np.atleast_1d(np.asarray(theta, float))
    if np.any(~np.isfinite(thetas)) or np.any(np.abs(thetas) >= 180):
        raise InputError(f"theta must be in (-180, 180) degrees, got {theta!r}")
    if thetas.size not in (1, max(passes - 1, 1)):
        raise InputError(f"theta needs one angle or one per new pass ({passes - 1}); got {thetas.size}")
    th = thetas.tolist() if thetas.size > 1 else float(thetas[0])
    first = make_envelope(motion, tool, side=side)
    chain = build_chain(first, passes, continuity=continuity, theta_deg=th, tolerance=tolerance, progress=progress)
    other = None
    if compare and passes > 1:
        other = build_chain(
            first, passes, continuity="g0" if continuity == "g1" else "g1", theta_deg=th, tolerance=tolerance
        )
    mt = max_theta(first, continuity=continuity) if (theta_scan and passes > 1) else None
    tp = chain_toolpath(chain, chordal_tolerance=chordal_tolerance, clearance=clearance)
    return EnvelopeResult(chain, tp, other, mt, {"total_s": time.perf_counter() - t0})


def fitted_normals(chain: PassChain, n_a: int = 60, n_t: int = 120) -> list[tuple[np.ndarray, np.ndarray]]:
    """Points and unit normals of each pass's fitted face on an ``n_a x n_t`` grid (for zebra pictures)."""
    out = []
    for fit in chain.fits:
        s = fit.surface
        us, vs = s.sample_grid(n_a, n_t)
        d = s.derivatives_grid(us, vs, 1)
        nn = np.cross(d.su, d.sv)
        out.append((d.point, nn / np.linalg.norm(nn, axis=-1, keepdims=True)))
    return out


__all__ = ["envelope", "EnvelopeResult", "chain_toolpath", "fitted_normals", "Continuity"]
