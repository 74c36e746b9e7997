"""Tool paths on the machining surface and cutter-location (CL) output (mm, degrees).

Curves C1 on the guiding surface S1 are intersections with parallel planes (a step-over
apart) or iso-parametric lines; the matching C2 on S2 comes from the shared parameters.
Each curve is traced densely, each point projected exactly onto its plane by Newton's
method, then sampled with a chordal tolerance on the tool-tip path (Douglas-Peucker: every
dense point within the tolerance of the chords). Output: CSV and APT CLDATA.

Vocabulary (after OpenCAMLib): CC cutter-contact point on F, K torus centre-circle point on
S1, CL axis point in the torus plane on S2, tip = CL - r u the tool-tip point written to
GOTO statements, u the tool axis.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..geometry.bspline import unit_normals
from .strategies import IsoFeed, PlanesFeed
from .surfaces import MachiningSurface, recover_axis, tool_radii


@dataclass(frozen=True)
class Pass:
    """One tool pass: parameters and positions, all (n, 3) in mm except ``uv`` and ``axis``."""

    uv: np.ndarray
    cc: np.ndarray
    k: np.ndarray
    cl: np.ndarray
    tip: np.ndarray
    axis: np.ndarray
    level: float


@dataclass(frozen=True)
class ToolPath:
    passes: tuple
    kind: str
    stepover: float
    chordal_tolerance: float
    chordal_error_measured: float
    axis_error_deg: float | None
    n_points: int

    def report(self) -> dict:
        return {"kind": self.kind, "n_passes": len(self.passes), "n_points": self.n_points,
                "stepover_mm": self.stepover, "chordal_tolerance_mm": self.chordal_tolerance,
                "chordal_error_measured_mm": self.chordal_error_measured,
                "axis_error_deg_measured": self.axis_error_deg}


def _douglas_peucker(pts: np.ndarray, tol: float) -> np.ndarray:
    """Indices of points kept so that every point is within ``tol`` of its chord."""
    n = pts.shape[0]
    if n <= 2:
        return np.arange(n)
    keep = np.zeros(n, bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = pts[b] - pts[a]
        L2 = float(seg @ seg)
        rel = pts[a + 1:b] - pts[a]
        if L2 > 0:
            t = np.clip(rel @ seg / L2, 0, 1)
            d = np.linalg.norm(rel - t[:, None] * seg, axis=1)
        else:
            d = np.linalg.norm(rel, axis=1)
        i = int(np.argmax(d))
        if d[i] > tol:
            m = a + 1 + i
            keep[m] = True
            stack += [(a, m), (m, b)]
    return np.nonzero(keep)[0]


def _chord_error(dense: np.ndarray, kept_idx: np.ndarray) -> float:
    err = 0.0
    for a, b in zip(kept_idx[:-1], kept_idx[1:]):
        if b - a < 2:
            continue
        seg = dense[b] - dense[a]
        L2 = float(seg @ seg)
        rel = dense[a + 1:b] - dense[a]
        t = np.clip(rel @ seg / L2, 0, 1) if L2 > 0 else np.zeros(len(rel))
        err = max(err, float(np.linalg.norm(rel - t[:, None] * seg, axis=1).max()))
    return err


def tool_paths(ms: MachiningSurface, *, stepover: float, chordal_tolerance: float = 0.01, strategy=None,
               grid: int = 401, zigzag: bool = True) -> ToolPath:
    """Tool paths on S1: plane sections (``PlanesFeed``) or iso-parametric lines (``IsoFeed``).

    ``stepover`` is the distance between planes (mm) or, for iso lines, the approximate
    distance between lines measured on S1. ``strategy`` defaults to the machining surface's
    feed. Points outside the trimmed face are dropped (a pass is split there).
    """
    if not stepover > 0 or not chordal_tolerance > 0:
        raise InputError("stepover and chordal tolerance must be > 0 mm")
    feed = strategy if strategy is not None else getattr(ms.strategy, "feed", None)
    if feed is None:
        feed = IsoFeed("u")
    s1 = ms.s1.surface
    u0, u1, v0, v1 = ms.s1.uv_bounds
    us, vs = np.linspace(u0, u1, grid), np.linspace(v0, v1, grid)
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = ms.s1.contains_uv(U, V)  # the trimmed face, loop holes included
    if isinstance(feed, PlanesFeed):
        N = np.asarray(feed.plane_normal)
        g = np.einsum("ijk,k->ij", s1.evaluate_grid(us, vs), N)
        kind = "planes"
    elif isinstance(feed, IsoFeed):
        # iso lines: v = const for a feed along u; levels spaced by the S1 arc length across them
        across = vs if feed.direction == "u" else us
        d = s1.derivatives_grid(us, vs, 1)
        speed = np.linalg.norm(d.sv if feed.direction == "u" else d.su, axis=-1).mean(axis=0 if feed.direction == "u" else 1)
        s_len = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(across))])
        g = np.broadcast_to(V if feed.direction == "u" else U, U.shape).copy()
        kind = f"iso-{feed.direction}"
    else:
        raise InputError("tool paths need a planes or iso-parametric strategy")
    g_masked = np.where(inside, g, np.nan)
    if kind == "planes":
        lo, hi = np.nanmin(g_masked), np.nanmax(g_masked)
        levels = np.arange(math.floor(lo / stepover) * stepover + stepover, hi, stepover)
    else:
        total = s_len[-1]
        n_lines = max(1, int(math.floor(total / stepover)))
        targets = (np.arange(n_lines) + 0.5) * total / n_lines
        levels = np.interp(targets, s_len, across)
    import contourpy

    gen = contourpy.contour_generator(x=vs, y=us, z=g_masked, line_type="Separate")
    passes = []
    chord_err = 0.0
    axis_err = 0.0
    for li, level in enumerate(levels):
        for line in gen.lines(float(level)):
            if len(line) < 2:
                continue
            uv = np.stack([line[:, 1], line[:, 0]], 1)
            uv = _densify(uv, ms, float(level), kind, N if kind == "planes" else None)
            if uv.shape[0] < 2:
                continue
            p = _positions(ms, uv)
            idx = _douglas_peucker(p["tip"], chordal_tolerance)
            chord_err = max(chord_err, _chord_error(p["tip"], idx))
            axis_err = max(axis_err, p["axis_err"])
            sel = {k: v[idx] for k, v in p.items() if k != "axis_err"}
            if zigzag and len(passes) % 2 == 1:
                sel = {k: v[::-1] for k, v in sel.items()}
            passes.append(Pass(uv[idx] if not (zigzag and len(passes) % 2 == 1) else uv[idx][::-1],
                               sel["cc"], sel["k"], sel["cl"], sel["tip"], sel["axis"], float(level)))
    if not passes:
        raise InputError("no tool pass crosses the face: reduce the step-over")
    n_pts = sum(p.tip.shape[0] for p in passes)
    return ToolPath(tuple(passes), kind, float(stepover), float(chordal_tolerance), chord_err,
                    axis_err if ms.axes == 5 else None, n_pts)


def _densify(uv: np.ndarray, ms: MachiningSurface, level: float, kind: str, N) -> np.ndarray:
    """Put the contour's points exactly on the level (Newton on S1 . N = level) and double them."""
    mid = 0.5 * (uv[1:] + uv[:-1])
    dense = np.empty((uv.shape[0] + mid.shape[0], 2))
    dense[0::2] = uv
    dense[1::2] = mid
    if kind != "planes":
        k = 1 if kind == "iso-u" else 0
        dense[:, k] = level
        return dense
    s1 = ms.s1.surface
    u0, u1, v0, v1 = ms.s1.uv_bounds
    for _ in range(6):
        d = s1.derivatives(dense[:, 0], dense[:, 1], 1)
        r = d.point @ N - level
        gu, gv = d.su @ N, d.sv @ N
        g2 = gu * gu + gv * gv
        step = np.where(g2 > 0, r / np.where(g2 > 0, g2, 1), 0.0)
        dense[:, 0] = np.clip(dense[:, 0] - step * gu, u0, u1)
        dense[:, 1] = np.clip(dense[:, 1] - step * gv, v0, v1)
        if np.abs(r).max() < 1e-11:
            break
    d = s1.derivatives(dense[:, 0], dense[:, 1], 0)
    on_plane = np.abs(d.point @ N - level) < 1e-9 * max(1.0, abs(level))
    return dense[on_plane]  # points clipped at the domain edge could not reach the plane


def _positions(ms: MachiningSurface, uv: np.ndarray) -> dict:
    kind, r, Rt = tool_radii(ms.cutter)
    F = ms.nominal.surface
    d = F.derivatives(uv[:, 0], uv[:, 1], 1)
    n = unit_normals(d.su, d.sv, F.scale)
    if ms.nominal.reversed:
        n = -n
    k = ms.s1.surface.evaluate(uv[:, 0], uv[:, 1])
    maps = ms.maps
    if ms.axes == 5:
        cl = ms.s2.surface.evaluate(uv[:, 0], uv[:, 1])
        axis = recover_axis(k, cl, n, ball_length=ms.axis_length if kind == "ball" else None)
        if kind == "ball":
            cl = k  # the ball's CL is its centre; S2 only orients the axis
        # measured against the exact axis
        exact = np.stack([maps.tool_axis(np.array([a]), np.array([b]))[0, 0] for a, b in uv[:: max(1, len(uv) // 16)]])
        got = axis[:: max(1, len(uv) // 16)]
        axis_err = float(np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", exact, got), -1, 1))).max())
    else:
        axis = np.broadcast_to(np.asarray(ms.strategy.direction), k.shape).copy()
        cl = k + r * axis if ms.tip else k
        axis_err = 0.0
    tip = cl - r * axis
    return {"cc": d.point, "k": k, "cl": cl, "tip": tip, "axis": axis, "axis_err": axis_err}


def write_csv(path, tp: ToolPath) -> Path:
    """One row per CL point: pass, index, u, v, tip xyz, axis ijk, K, C_L, C_C (mm)."""
    path = Path(path)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["pass", "index", "u", "v", "tip_x", "tip_y", "tip_z", "i", "j", "k", "K_x", "K_y", "K_z",
                    "CL_x", "CL_y", "CL_z", "CC_x", "CC_y", "CC_z"])
        for pi, p in enumerate(tp.passes):
            for j in range(p.tip.shape[0]):
                w.writerow([pi, j, f"{p.uv[j, 0]:.10g}", f"{p.uv[j, 1]:.10g}", *(f"{x:.6f}" for x in p.tip[j]),
                            *(f"{x:.9f}" for x in p.axis[j]), *(f"{x:.6f}" for x in p.k[j]),
                            *(f"{x:.6f}" for x in p.cl[j]), *(f"{x:.6f}" for x in p.cc[j])])
    return path


def apt_cutter(cutter) -> str:
    """APT 7-parameter CUTTER statement (d, r, e, f, alpha, beta, h) in mm and degrees."""
    kind, r, Rt = tool_radii(cutter)
    return f"CUTTER/{cutter.D:.4f},{r:.4f},{Rt:.4f},{r:.4f},0.0000,0.0000,{cutter.length:.4f}"


def write_apt(path, tp: ToolPath, ms: MachiningSurface, *, clearance: float = 10.0, partno: str = "MACHSURF") -> Path:
    """APT CLDATA: UNITS/MM, CUTTER/..., MULTAX/ON for 5 axes, GOTO/x,y,z[,i,j,k] at the tool tip.

    Between passes the tool retracts ``clearance`` mm along its axis (RAPID moves).
    """
    path = Path(path)
    five = ms.axes == 5
    lines = [f"$$ machsurf_cad tool path: {tp.kind}, {len(tp.passes)} passes, chordal tol {tp.chordal_tolerance:g} mm",
             f"PARTNO/{partno}", "UNITS/MM", apt_cutter(ms.cutter), "MULTAX/ON" if five else "MULTAX/OFF"]

    def goto(p, a):
        if five:
            return "GOTO/{:.5f},{:.5f},{:.5f},{:.7f},{:.7f},{:.7f}".format(*p, *a)
        return "GOTO/{:.5f},{:.5f},{:.5f}".format(*p)

    for ps in tp.passes:
        lines += ["RAPID", goto(ps.tip[0] + clearance * ps.axis[0], ps.axis[0])]
        lines += [goto(ps.tip[j], ps.axis[j]) for j in range(ps.tip.shape[0])]
        lines += ["RAPID", goto(ps.tip[-1] + clearance * ps.axis[-1], ps.axis[-1])]
    lines.append("FINI")
    path.write_text("\n".join(lines) + "\n")
    return path
