"""The normal-vector (N-buffer) cut simulation engine (mm).

After Jerard, Drysdale et al.: every sample of the nominal surface carries a "blade" along its
outward unit normal ``n``, from ``-depth`` (inside the part) to ``+stock`` (outside). Every tool
placement removes the part of the blade inside the tool's cutting body; what is left is the blade
from ``-depth`` up to the lowest point where it enters a tool body. The signed result per sample is
that entry parameter ``t`` (mm along ``n``): ``t > 0`` is material left (a scallop, an undercut).

Where the tool cut below the nominal (``t < 0``) the gouge is measured as the depth of the nominal point
inside the swept cutting body (its signed distance to the body, :func:`inside_depth`), the figure
:func:`~machsurf_cad.gougecheck.verify` measures: along the normal the cut can be far longer than deep.
At a convex edge the blade of a wall runs just under the neighbouring face; a tool that dips 2 um into
that face (a chord's sag) holds the edge's nominal point and meets the wall's blade all along its
flat bottom: 1 mm "deep" along the wall's normal, 2 um deep in fact. For a gouge inside a smooth face
the two agree to first order (the distance is never more than the length along the normal).

Exactness:

* **Against one placement** the entry is found on the exact revolved profile. Ball, flat and bull
  bodies are cylinders, a sphere and a torus: the entry is a closed form (quadratics) but for the
  torus (:mod:`~machsurf_cad.simulation.rays`). Any other profile: the signed distance of a blade
  point to the body is exact for line and arc profiles
  (:meth:`~machsurf_cad.cutters.Cutter.cutting_distance_rz`), and the ray is marched by that
  distance (sphere tracing: each step is the distance to the body, so no step passes through it)
  until the distance is below ``1e-7`` mm. A torus march that has not converged in ten times
  ``max_steps`` (a ray grazing the torus) is solved exactly on the ray-torus quartic instead. A march
  that still has no entry (a general profile after ``max_steps``) is never taken as a cut: its lower
  bound is kept aside, and a sample whose entry found is not below it is **not measured** (reported
  apart, counted in neither the material left nor the gouges).
* **The motion between placements** is sampled ``motion_step`` mm apart (tip and every point of the
  cutting part, axis interpolated linearly and normalised, as :func:`~machsurf_cad.gougecheck.verify`
  does). For each sample the best placement and its two neighbours are then refined by four rounds of
  parabolic interpolation over the continuous motion; the change made by the last round is reported
  (``motion_residual_mm``). For a profile without sharp corners the sampled result alone is within
  ``motion_step^2 / (8 rho_min)`` of the swept one (``rho_min`` the smallest profile radius).

A placement that meets a blade only below the nominal, without holding the nominal point itself,
entered the material through another face (a blade running under the top face near a convex edge,
say): it does not cut this blade; the samples of that other face see it.

Candidate pairs (sample, placement) come from a k-d tree over the samples queried with spheres that
cover the cutting part (one per slab of the profile, radius measured on the profile); a pair is
marched only when its distance at ``t = 0`` is below the best entry found so far for that sample.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ..arrays import unique_sorted
from ..errors import InputError
from .rays import ray_core, ray_entry, sphere_trace

GOLDEN_ITERATIONS = 16
"""Golden-section steps over the motion for profiles with a sharp corner (bracket 2 placements x 0.618^16)."""
REFINE_ROUNDS = 4
"""Rounds of parabolic interpolation over the motion (the change made by the last one is reported)."""
NEAR_REACH_MM = 0.1
"""Reach of the first sweep of candidate pairs (mm)."""


def cover_spheres(cutter, n_profile: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Heights on the axis (mm above the tip) and radii (mm) of spheres covering the cutting part.

    The part is cut into slabs about one tool radius high; each slab's sphere centre is the height
    that needs the smallest radius (measured on ``n_profile`` points per segment), plus 1e-6 mm.
    """
    pts = np.concatenate([seg.points(n_profile) for seg in cutter._outline()])
    zmin, zmax = float(pts[:, 1].min()), float(pts[:, 1].max())
    rmax = max(float(pts[:, 0].max()), 1e-6)
    n_slabs = max(1, math.ceil((zmax - zmin) / rmax - 1e-9))
    edges = np.linspace(zmin, zmax, n_slabs + 1)
    heights, radii = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = pts[(pts[:, 1] >= lo - 1e-12) & (pts[:, 1] <= hi + 1e-12)]
        # the profile crossing the slab's planes belongs to the slab too
        w_lo, w_hi = float(cutter.width(max(lo, zmin + 1e-12))), float(cutter.width(min(hi, zmax - 1e-12)))
        sel = np.concatenate([sel, [[w_lo, lo], [w_hi, hi], [0.0, lo], [0.0, hi]]])
        cands = np.linspace(lo, hi, 33)
        r = np.sqrt(sel[None, :, 0] ** 2 + (sel[None, :, 1] - cands[:, None]) ** 2).max(axis=1)
        k = int(np.argmin(r))
        heights.append(cands[k])
        radii.append(r[k] + 1e-6)
    return np.array(heights), np.array(radii)


MAX_POSES = 5_000_000
"""Most tool placements a simulation takes on before it refuses (each one is solved against the samples
near it: about a gigabyte and tens of minutes at this count)."""


def motion_poses(tip, axis, step_mm: float, cut_length: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Placements along a path, no point of the cutting part moving more than ``step_mm`` between two.

    Returns tips, unit axes and the owning position index (the position each motion ends at).
    """
    tip = np.asarray(tip, float)
    axis = np.asarray(axis, float)
    if tip.shape[0] == 0:
        raise InputError("the tool path has no positions")
    d_tip = np.linalg.norm(np.diff(tip, axis=0), axis=1)
    d_ax = np.linalg.norm(np.diff(axis, axis=0), axis=1) * cut_length
    need = float(np.maximum(1.0, np.ceil((d_tip + d_ax) / step_mm)).sum()) + 1
    if need > MAX_POSES:
        raise InputError(
            f"simulating this path every {step_mm:g} mm needs {need:.3g} tool placements ({tip.shape[0]:,} "
            f"positions, {float(d_tip.sum()):.4g} mm of motion), more than {MAX_POSES:,}: give a larger motion step"
        )
    n = np.maximum(1, np.ceil((d_tip + d_ax) / step_mm).astype(int))
    total = 1 + int(n.sum())
    owner = np.concatenate([[0], np.repeat(np.arange(1, tip.shape[0]), n)])
    # fraction along each motion
    start = np.concatenate([[0], np.cumsum(n)])
    k = np.arange(1, total)
    seg = owner[1:] - 1
    frac = (k - start[seg]) / n[seg]
    T = np.empty((total, 3))
    A = np.empty((total, 3))
    T[0], A[0] = tip[0], axis[0]
    T[1:] = tip[seg] * (1 - frac)[:, None] + tip[seg + 1] * frac[:, None]
    a = axis[seg] * (1 - frac)[:, None] + axis[seg + 1] * frac[:, None]
    nrm = np.linalg.norm(a, axis=1)
    if np.any(nrm < 1e-9):
        raise InputError("the axis turns by 180 deg between two positions: no linear motion")
    A[1:] = a / nrm[:, None]
    return T, A, owner


def _distance(cutter, P, N, t, T, A):
    q = P + t[:, None] * N - T
    z = np.einsum("ij,ij->i", q, A)
    rho = np.sqrt(np.maximum(np.einsum("ij,ij->i", q, q) - z * z, 0.0))
    return cutter.cutting_distance_rz(rho, z)


def march(cutter, P, N, T, A, t_start, t_end: float, max_steps: int = 60):
    """Entry parameter of each ray ``P + t N`` (t from ``t_start`` up to ``t_end``) into the placed body.

    Returns ``(t, status)``: status 0 entered at ``t``, 1 inside already at ``t_start`` (``t`` =
    ``t_start``), 2 no entry before ``t_end`` (``t`` = inf), 3 not converged (``t`` a lower bound).
    """
    core = ray_core(cutter)
    if core is not None:  # ball, flat, bull: closed-form entry (sphere tracing only on a bull's torus)
        return ray_entry(core, P, N, T, A, t_start, t_end, max_steps)
    return _sphere_trace(cutter, P, N, T, A, t_start, t_end, max_steps)


def _sphere_trace(cutter, P, N, T, A, t_start, t_end: float, max_steps: int = 60):
    """:func:`march` by sphere tracing on the body's exact signed distance (any profile)."""
    m = P.shape[0]
    t = np.array(t_start, float, copy=True) if np.ndim(t_start) else np.full(m, float(t_start))
    return sphere_trace(lambda i, tt: _distance(cutter, P[i], N[i], tt, T[i], A[i]), t, t_end, max_steps)


def candidate_pairs(tree: cKDTree, T, A, heights, radii, reach: float, chunk: int = 4000):
    """Yield ``(sample_index, pose_index)`` arrays of pairs that may touch within ``reach`` mm."""
    n = T.shape[0]
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        c = T[s:e, None, :] + heights[None, :, None] * A[s:e, None, :]
        r = np.broadcast_to(radii[None, :] + reach, c.shape[:2])
        hits = tree.query_ball_point(c.reshape(-1, 3), r.ravel(), return_sorted=False, workers=-1)
        lens = np.fromiter((len(h) for h in hits), int, count=len(hits))
        if lens.sum() == 0:
            yield s, e, np.empty(0, int), np.empty(0, int)
            continue
        samp = np.concatenate([np.asarray(h, int) for h in hits if h])
        pose = np.repeat(np.arange(s, e).repeat(len(heights)), lens)
        key = samp.astype(np.int64) * n + pose
        if len(heights) > 1:  # one placement's slabs may find a sample twice
            key.sort()
            key = key[np.r_[True, key[1:] != key[:-1]]]
        yield s, e, key // n, key % n


def nbuffer(
    cutter,
    P: np.ndarray,
    N: np.ndarray,
    T: np.ndarray,
    A: np.ndarray,
    *,
    depth: float,
    stock: float,
    margin: float,
    sharp: bool = False,
    progress=None,
    max_steps: int = 60,
) -> dict:
    """Entry of every blade into the discrete placements ``(T, A)``, then refined over the motion.

    ``sharp``: the profile has a sharp corner (golden-section refinement instead of parabolic).
    ``margin`` (mm) bounds how much lower the swept motion can cut than its sampled placements: every
    placement within it of a sample's best is kept and refined over the motion around it (one per
    local minimum along the path: the neighbouring passes each get theirs).

    Returns a dict of arrays per sample: ``t`` (mm, ``+stock`` where nothing reached; where negative, the
    depth of the nominal point inside the swept body), ``t_normal`` (the entry along the normal, also
    below the nominal), ``reached``, ``measured`` (see the module docstring), ``clamped`` (cut below
    ``-depth`` along the normal), ``pose`` (best placement, fractional), and figures ``n_pairs``,
    ``n_marched``, ``n_refined``, ``n_unconverged`` (rays at placements), ``n_unconverged_motion``
    (probes over the motion), ``motion_residual_mm``.
    """
    m = P.shape[0]
    best = np.full(m, np.inf)
    clamped = np.zeros(m, bool)
    stats: dict = {"unconv": 0, "unconv_motion": 0, "marched": 0, "unconv_lb": []}
    records: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    n_pairs = 0
    heights, radii = cover_spheres(cutter)
    n_poses = T.shape[0]
    # two sweeps: a short reach settles the samples cut close to the nominal (a placement farther than the
    # reach cannot beat them), the full reach only the others
    near = min(stock, NEAR_REACH_MM)
    todo = np.arange(m)
    for sweep, reach in enumerate((near, max(depth, stock)) if stock > near else (max(depth, stock),)):
        if sweep:
            todo = np.flatnonzero(~(best + margin <= near))
            if todo.size == 0:
                break
        tree = cKDTree(P[todo])
        for _s, e, si, pi in candidate_pairs(tree, T, A, heights, radii, reach):
            if progress is not None:
                progress(e + sweep * n_poses, 2 * n_poses, "simulating the cut")
            if si.size == 0:
                continue
            si = todo[si]
            n_pairs += si.size
            _settle(cutter, P, N, T, A, si, pi, best, clamped, depth, stock, margin, max_steps, stats, records)
    reached = np.isfinite(best)
    pose, residual, n_refined = _refine_candidates(
        cutter, P, N, T, A, records, best, clamped, depth, stock, margin, sharp, stats
    )
    if progress is not None:
        progress(1, 1, "simulating the cut")
    out = _finish(cutter, P, T, A, best, reached, stats, heights, radii, margin, stock)
    out.update(
        clamped=clamped,
        pose=pose,
        n_pairs=int(n_pairs),
        n_marched=int(stats["marched"]),
        n_refined=n_refined,
        motion_residual_mm=float(residual),
    )
    return out


def _refine_candidates(cutter, P, N, T, A, records, best, clamped, depth, stock, margin, sharp, stats):
    """Refine over the motion the sampled entries within ``margin`` of their sample's best (``best`` in place)."""
    m = P.shape[0]
    n_poses = T.shape[0]
    pose = np.full(m, np.nan)
    residual = 0.0
    n_refined = 0
    if records and n_poses > 1:
        rs = np.concatenate([r[0] for r in records])
        rp = np.concatenate([r[1] for r in records])
        rt = np.concatenate([r[2] for r in records])
        known = None if sharp else _Known(rs, rp, rt, n_poses)
        keep = (rt <= best[rs] + margin) & ~clamped[rs]
        rs, rp, rt = rs[keep], rp[keep], rt[keep]
        rs, rp, rt = _local_minima(rs, rp, rt)
        # the lowest sampled candidate of each sample first; the others only where they can still beat it
        o = np.lexsort((rt, rs))
        rs, rp, rt = rs[o], rp[o], rt[o]
        lead = np.ones(rs.size, bool)
        lead[1:] = rs[1:] != rs[:-1]
        residual = 0.0
        n_refined = 0
        for stage in (lead, ~lead):
            if stage is not lead:
                stage = stage & (rt - margin < best[rs])
            if not stage.any():
                continue
            s_s, s_p, s_t = rs[stage], rp[stage], rt[stage]
            n_refined += int(s_s.size)
            if sharp:  # the search probes inside the bracket only
                t_ref, x_ref, res_, lb_ = _refine_golden(cutter, P[s_s], N[s_s], T, A, s_p, s_t, depth, stock)
            else:  # the bracket's ends are the neighbouring placements, mostly marched already
                assert known is not None
                nb = known.neighbours(s_s, s_p)
                t_ref, x_ref, res_, lb_ = _refine_motion(cutter, P[s_s], N[s_s], T, A, s_p, s_t, depth, stock, nb)
            unc = np.isfinite(lb_)  # probes that did not converge: their lower bounds are kept aside
            if unc.any():
                stats["unconv_motion"] += int(unc.sum())
                stats["unconv_lb"].append((s_s[unc], lb_[unc]))
            residual = max(residual, res_)
            o2 = np.lexsort((t_ref, s_s))
            s_s, t_ref, x_ref = s_s[o2], t_ref[o2], x_ref[o2]
            first = np.ones(s_s.size, bool)
            first[1:] = s_s[1:] != s_s[:-1]
            better = t_ref[first] < best[s_s[first]]
            best[s_s[first][better]] = t_ref[first][better]
            pose[s_s[first][better]] = x_ref[first][better]
    return pose, residual, n_refined


def _finish(cutter, P, T, A, best, reached, stats, heights, radii, margin, stock) -> dict:
    """Per sample: the thickness along the normal ``t_normal``; the signed value ``t`` (the same, but the
    depth of the nominal point inside the swept body where the tool cut below it); ``measured`` (False
    where a march that did not converge could still lie below the entry found)."""
    m = P.shape[0]
    lb = np.full(m, np.inf)
    for s_, t_ in stats["unconv_lb"]:
        np.minimum.at(lb, s_, t_)
    measured = ~(lb < best - 1e-9)
    t_normal = np.where(reached, best, stock)
    value = t_normal.copy()
    below = np.flatnonzero(reached & (best < 0))
    if below.size:
        value[below] = np.minimum(inside_depth(cutter, P[below], T, A, heights, radii, margin), 0.0)
    return {
        "t": value,
        "t_normal": t_normal,
        "reached": reached,
        "measured": measured,
        "n_unconverged": int(stats["unconv"]),
        "n_unconverged_motion": int(stats["unconv_motion"]),
    }


def inside_depth(cutter, P, T, A, heights, radii, margin: float, iterations: int = GOLDEN_ITERATIONS + 4):
    """Signed distance (mm) of points to the swept cutting body, negative inside; ``inf`` where no placement
    comes within ``margin``.

    Per placement the distance is exact (:meth:`~machsurf_cad.cutters.Cutter.cutting_distance_rz`); the
    motion between placements can come up to ``margin`` closer (the sagitta bound of the simulation), so the
    motion on each side of every placement within ``margin`` of a point's smallest value is searched by
    golden section. Between two placements the tool translates along a line (3 axes; nearly so with a
    turning axis), and the signed distance of a point to a translating convex body is convex along it: one
    minimum per interval, which the search closes on (to ``0.618^iterations`` of the interval). The lowest
    value seen is kept.
    """
    m = P.shape[0]
    recs = []
    for _s, _e, si, pi in candidate_pairs(cKDTree(P), T, A, heights, radii, margin):
        if si.size:
            g = _distance(cutter, P[si], P[si], np.zeros(si.size), T[pi], A[pi])
            keep = g <= margin
            recs.append((si[keep], pi[keep], g[keep]))
    best = np.full(m, np.inf)
    n = T.shape[0]
    if not recs:
        return best
    rs, rp, rg = (np.concatenate(x) for x in zip(*recs))
    np.minimum.at(best, rs, rg)
    keep = rg <= best[rs] + margin
    rs, rp = rs[keep], rp[keep]
    # the intervals [j, j + 1] on each side of the candidates, each once
    key = unique_sorted(np.concatenate([rs * n + rp - 1, rs * n + rp]).astype(np.int64))
    js, jp = key // n, key % n
    ok = (jp >= 0) & (jp < n - 1) & (key >= 0)
    js, jp = js[ok], jp[ok]
    if js.size == 0:
        return best
    Pi = P[js]
    zero = np.zeros(js.size)

    def f(x):
        tip, ax = _pose_at(T, A, x)
        return _distance(cutter, Pi, Pi, zero, tip, ax)

    gr = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = jp.astype(float), jp + 1.0
    x1, x2 = b - gr * (b - a), a + gr * (b - a)
    f1, f2 = f(x1), f(x2)
    low = np.minimum(f1, f2)
    for _ in range(iterations):
        left = f1 <= f2  # the lowest value lies in [a, x2]
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
        nx1 = np.where(left, b - gr * (b - a), x2)
        nx2 = np.where(left, x1, a + gr * (b - a))
        fp = f(np.where(left, nx1, nx2))
        f1, f2 = np.where(left, fp, f2), np.where(left, f1, fp)
        x1, x2 = nx1, nx2
        low = np.minimum(low, fp)
    np.minimum.at(best, js, low)
    return best


def _local_minima(rs, rp, rt):
    """The (sample, placement, value) records that are local minima along the path: a placement whose
    neighbour on the path has a lower value for the same sample is dropped (one per valley: the
    neighbouring passes each keep theirs)."""
    o = np.lexsort((rp, rs))
    rs, rp, rt = rs[o], rp[o], rt[o]
    same_next = np.zeros(rs.size, bool)
    same_next[:-1] = (rs[1:] == rs[:-1]) & (rp[1:] == rp[:-1] + 1)
    lower_next = np.zeros(rs.size, bool)
    lower_next[:-1] = same_next[:-1] & (rt[1:] < rt[:-1])
    lower_prev = np.zeros(rs.size, bool)
    lower_prev[1:] = same_next[:-1] & (rt[:-1] < rt[1:])
    loc = ~(lower_next | lower_prev)
    return rs[loc], rp[loc], rt[loc]


def _settle(cutter, P, N, T, A, si, pi, best, clamped, depth, stock, margin, max_steps, stats, records):
    """March the pairs that can still come within ``margin`` of their sample's best entry; update the
    best in place and record every entry that does."""
    # a cheap lower bound of the distance first: below the tip plane, beside the widest radius, above the top
    limit = np.minimum(best[si] + margin, stock)
    rel = P[si] - T[pi]
    z = np.einsum("ij,ij->i", rel, A[pi])
    rho = np.sqrt(np.maximum(np.einsum("ij,ij->i", rel, rel) - z * z, 0.0))
    r_max, top = _extent(cutter)
    lower = np.maximum.reduce([-z, rho - r_max, z - top])
    near = lower < limit
    si, pi, limit = si[near], pi[near], limit[near]
    g0 = cutter.cutting_distance_rz(rho[near], z[near])
    keep = g0 < limit
    si, pi, g0 = si[keep], pi[keep], g0[keep]
    # the most promising pair per sample first, then the others that can still come near it
    order = np.lexsort((g0, si))
    si, pi, g0 = si[order], pi[order], g0[order]
    first = np.ones(si.size, bool)
    first[1:] = si[1:] != si[:-1]
    for sel in (first, ~first):
        if not sel.any():
            continue
        a_s, a_p, a_g = si[sel], pi[sel], g0[sel]
        ok = a_g < best[a_s] + margin
        a_s, a_p, a_g = a_s[ok], a_p[ok], a_g[ok]
        if a_s.size == 0:
            continue
        stats["marched"] += a_s.size
        # a placement away from the nominal point (g0 > 0) can only count at t >= g0 (see the docstring): start there
        t, st = march(cutter, P[a_s], N[a_s], T[a_p], A[a_p], np.where(a_g > 0, a_g, -depth), stock, max_steps)
        unc = st == 3  # not converged: its lower bound is kept aside, never taken as the entry
        if unc.any():
            stats["unconv"] += int(unc.sum())
            stats["unconv_lb"].append((a_s[unc], t[unc]))
            t = np.where(unc, np.inf, t)
        t = np.where((t < 0) & (a_g > 0), np.inf, t)  # cuts below the nominal only: see the docstring
        fin = np.isfinite(t)
        records.append((a_s[fin], a_p[fin], t[fin]))
        np.minimum.at(best, a_s[fin], t[fin])
        cl = fin & (st == 1) & (a_g <= 0)  # inside at -depth (a start at g0 > 0 is only on the boundary)
        clamped[a_s[cl]] = True


def _extent(cutter) -> tuple[float, float]:
    """Widest radius and height of the cutting part (mm)."""
    pts = np.concatenate([seg.points(64) for seg in cutter._outline()])
    return float(pts[:, 0].max()) + 1e-9, float(pts[:, 1].max()) + 1e-9


def _pose_at(T, A, x):
    j = np.clip(np.floor(x).astype(int), 0, T.shape[0] - 2)
    f = (x - j)[:, None]
    tip = T[j] * (1 - f) + T[j + 1] * f
    a = A[j] * (1 - f) + A[j + 1] * f
    return tip, a / np.linalg.norm(a, axis=1, keepdims=True)


def _entry_at(cutter, P, N, T, A, x, t_hint, depth, stock, lb=None):
    """Entry of each blade into the placement at fractional index ``x`` (``inf``: none that counts).

    A march that has not converged gives no entry here; its lower bound goes into ``lb`` (per row, in
    place: the sample is then not measured unless its final entry lies below that bound)."""
    tip, a = _pose_at(T, A, x)
    # warm start a little below the current best entry; from -depth where that start is inside
    start = np.maximum(t_hint - 0.05 * (depth + stock) - 1e-3, -depth)
    t, st = march(cutter, P, N, tip, a, start, stock)
    redo = (st == 1) & (start > -depth)
    if redo.any():
        t2, st2 = march(cutter, P[redo], N[redo], tip[redo], a[redo], -depth, stock)
        t[redo], st[redo] = t2, st2
    unc = st == 3
    if unc.any():
        if lb is not None:
            lb[unc] = np.minimum(lb[unc], t[unc])
        t[unc] = np.inf
    below = t < 0
    if below.any():  # a cut below the nominal counts only when the tool holds the nominal point itself
        g0 = _distance(cutter, P[below], N[below], np.zeros(int(below.sum())), tip[below], a[below])
        t[np.flatnonzero(below)[g0 > 0]] = np.inf
    return np.where(np.isfinite(t), t, np.inf)


class _Known:
    """Entries already marched, looked up by sample and placement."""

    def __init__(self, samples: np.ndarray, poses: np.ndarray, t: np.ndarray, n_poses: int):
        self.n_poses = n_poses
        keys = samples.astype(np.int64) * n_poses + poses
        o = np.argsort(keys)
        self.keys, self.t = keys[o], t[o]

    def _get(self, s: np.ndarray, p: np.ndarray) -> np.ndarray:
        out = np.full(s.shape, np.nan)
        ok = (p >= 0) & (p < self.n_poses)
        if self.keys.size == 0 or not ok.any():
            return out
        keys = s[ok].astype(np.int64) * self.n_poses + p[ok]
        j = np.minimum(np.searchsorted(self.keys, keys), self.keys.size - 1)
        out[ok] = np.where(self.keys[j] == keys, self.t[j], np.nan)
        return out

    def neighbours(self, s: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Entries at placements ``p - 1`` and ``p + 1`` of samples ``s`` (NaN where not marched)."""
        return self._get(s, p - 1), self._get(s, p + 1)


def _entry_or_known(cutter, P, N, T, A, x, t_hint, depth, stock, known, lb):
    if known is None:
        return _entry_at(cutter, P, N, T, A, x, t_hint, depth, stock, lb)
    out = np.array(known, float, copy=True)
    # the path's ends clamp x to the neighbour index itself: recompute there as well
    miss = np.isnan(out)
    if miss.any():
        sub = lb[miss]
        out[miss] = _entry_at(cutter, P[miss], N[miss], T, A, x[miss], t_hint[miss], depth, stock, sub)
        lb[miss] = sub
    return out


def _refine_golden(cutter, P, N, T, A, k, t_k, depth, stock, iterations: int = GOLDEN_ITERATIONS):
    """Golden-section search of the entry over the placement index in ``[k - 1, k + 1]``: for profiles with
    a sharp corner, whose entry jumps where the corner passes (no parabola fits there; a search that
    keeps the lower side of every comparison still closes on the lowest value). The residual reported
    is the largest gap between the lower of the two last inner values and the best value found."""
    n = T.shape[0]
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a = np.maximum(k - 1.0, 0.0)
    b = np.minimum(k + 1.0, n - 1.0)
    x1, x2 = b - g * (b - a), a + g * (b - a)
    lb = np.full(P.shape[0], np.inf)
    f1 = _entry_at(cutter, P, N, T, A, x1, t_k, depth, stock, lb)
    f2 = _entry_at(cutter, P, N, T, A, x2, t_k, depth, stock, lb)
    best_f, best_x = t_k.copy(), k.astype(float)
    for _ in range(iterations):
        left = f1 <= f2  # the lowest value lies in [a, x2]
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
        nx1 = np.where(left, b - g * (b - a), x2)
        nx2 = np.where(left, x1, a + g * (b - a))
        nf1 = np.where(left, np.nan, f2)
        nf2 = np.where(left, f1, np.nan)
        probe = np.where(left, nx1, nx2)
        fp = _entry_at(cutter, P, N, T, A, probe, np.minimum(best_f, t_k), depth, stock, lb)
        f1 = np.where(left, fp, nf1)
        f2 = np.where(left, nf2, fp)
        x1, x2 = nx1, nx2
        for f_, x_ in ((f1, x1), (f2, x2)):
            better = f_ < best_f
            best_f = np.where(better, f_, best_f)
            best_x = np.where(better, x_, best_x)
    inner = np.fmin(f1, f2)
    fin = np.isfinite(inner)
    residual = float((inner - best_f)[fin].max()) if fin.any() else 0.0
    return best_f, best_x, residual, lb


def _refine_motion(cutter, P, N, T, A, k, t_k, depth, stock, neighbours=None):
    """Rounds of safeguarded parabolic interpolation of the entry over the placement index.

    ``neighbours``: the entries already marched at placements ``k - 1`` and ``k + 1`` (NaN where not
    known; those are marched here). Returns the best entry, its index, the last round's change and the
    lowest lower bound of the marches that did not converge (per row, ``inf`` where none)."""
    n = T.shape[0]
    x0 = k.astype(float)
    xl, xr = np.maximum(x0 - 1, 0.0), np.minimum(x0 + 1, n - 1.0)
    lb = np.full(P.shape[0], np.inf)
    nl, nr = (None, None) if neighbours is None else neighbours
    fl = _entry_or_known(cutter, P, N, T, A, xl, t_k, depth, stock, nl, lb)
    fr = _entry_or_known(cutter, P, N, T, A, xr, t_k, depth, stock, nr, lb)
    xb, fb = x0.copy(), t_k.copy()
    residual = 0.0
    for _ in range(REFINE_ROUNDS):
        xv = _parabola_vertex(xl, fl, xb, fb, xr, fr)
        fv = _entry_at(cutter, P, N, T, A, xv, fb, depth, stock, lb)
        gain = np.where(np.isfinite(fv), np.maximum(fb - fv, 0.0), 0.0)
        residual = float(gain.max()) if gain.size else 0.0
        # keep a bracket around the best of the four points
        better = fv < fb
        left = xv < xb
        # new bracket: if the vertex is better, it becomes the middle and the old middle a side
        nxl = np.where(better, np.where(left, xl, xb), np.where(left, xv, xl))
        nfl = np.where(better, np.where(left, fl, fb), np.where(left, fv, fl))
        nxr = np.where(better, np.where(left, xb, xr), np.where(left, xr, xv))
        nfr = np.where(better, np.where(left, fb, fr), np.where(left, fr, fv))
        xb = np.where(better, xv, xb)
        fb = np.where(better, fv, fb)
        xl, fl, xr, fr = nxl, nfl, nxr, nfr
    return fb, xb, residual, lb


def _parabola_vertex(x1, f1, x2, f2, x3, f3):
    """Vertex of the parabola through three points, kept inside ``[x1, x3]`` (the midpoint of the
    larger half where the three points give no minimum)."""
    f1 = np.where(np.isfinite(f1), f1, 1e9)
    f3 = np.where(np.isfinite(f3), f3, 1e9)
    num = (x2 - x1) ** 2 * (f2 - f3) - (x2 - x3) ** 2 * (f2 - f1)
    den = (x2 - x1) * (f2 - f3) - (x2 - x3) * (f2 - f1)
    with np.errstate(divide="ignore", invalid="ignore"):
        xv = x2 - 0.5 * num / den
    half = np.where(x2 - x1 > x3 - x2, 0.5 * (x1 + x2), 0.5 * (x2 + x3))
    ok = np.isfinite(xv) & (den < 0) & (xv > x1) & (xv < x3) & (np.abs(xv - x2) > 1e-9)
    return np.where(ok, xv, half)
