"""The machined region of a simulated cut and the unmachined border around it (mm).

The material a tool path leaves between its passes (the scallops) is one figure; the material around
the passes, which the path never meant to machine (the strip beyond the outermost pass, past the ends of
the passes, the walls beside them), is another. A sample reached by the simulation is in the
**machined region** when, in its tangent plane:

* it lies **under a pass**: on the contact path of a cutting move (for a tool with a flat bottom
  parallel to the tangent plane, anywhere under that bottom), or
* it lies **between two passes**: the nearest contact path on one side and another one on the opposite
  side (more than 120 deg away as seen from the sample), the two gaps adding up to no more than the
  tool's cutting diameter (passes farther apart leave a strip that no pass reaches: border).

Every other reached sample is the **border**. The contact path of a cutting move as seen from a sample
of outward normal ``n`` is the path of the tool body's support point in the direction ``-n`` (the point
of the body that would touch the sample's tangent plane: ``centre - R n`` for a ball), projected on that
plane. Only a pass that touches the face counts: its support point no more than ``touch`` (the gouge
tolerance) above the tangent plane, plus what the face bends away over the distance across (its
sampled curvature), and no more than ``depth`` below (a pass hovering over a recess it cannot reach
does not machine it: the recess is border). Only ``CUT`` moves count; approaches, retracts and rapids
do not. A footprint beyond the start or the end of a cutting run does not count as beside the pass: the
strip past the ends of the passes is border. On a curved face a footprint counts only as far as the face
turns by less than :data:`MAX_TURN_RAD` (its sampled curvature). On a plane the contact paths are exact;
on a curved face the tangent plane holds to second order in the distance.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..cam.toolpath import Move
from .nbuffer import motion_poses

OPPOSITE_COS = -0.5
"""A second contact path counts as the other side when seen more than 120 deg away from the nearest."""
JOINT_DEG = 15.0
"""A sample beside two chords of a cutting run that meet at an angle sees its foot past their joint by less."""
MAX_TURN_RAD = 0.5
"""Farthest a footprint counts, as the angle the face turns over the distance (its sampled curvature)."""
FLAT_TOL_MM = 1e-4
"""A flat bottom lies in the tangent plane when its rim rises less than this above it (mm)."""


def cutting_extent(cutter) -> tuple[float, float]:
    """Widest radius of the cutting part and the radius of its flat bottom (mm)."""
    pts = np.concatenate([seg.points(256) for seg in cutter.profile()])
    zmin = float(pts[:, 1].min())
    flat = pts[np.abs(pts[:, 1] - zmin) <= 1e-12, 0]
    return float(pts[:, 0].max()), float(flat.max()) if flat.size else 0.0


def support_offsets(cutter, A, U, qz=None) -> tuple[np.ndarray, np.ndarray]:
    """Offsets from the tip (mm) of the body's support points in unit directions ``U`` for unit axes ``A``
    (the point of the cutting part farthest along ``U``), and the radius of the flat disc that supports it
    too (the flat bottom where ``U`` is within :data:`FLAT_TOL_MM` of ``-A`` over its radius, else 0).
    Where ``U`` is square to the axis within that tolerance over the side's height, the whole side supports
    it: the point at height ``qz`` (mm above the tip, the sample's; clipped to the side) is taken."""
    ua = np.einsum("ij,ij->i", U, A)
    up = U - ua[:, None] * A
    npp = np.linalg.norm(up, axis=1)
    core = cutter._rounded_core()
    R_flat = cutting_extent(cutter)[1]
    flat = (ua < 0) & (npp * R_flat <= FLAT_TOL_MM)
    e = np.where((npp > 1e-15)[:, None] & ~flat[:, None], up / np.where(npp > 0, npp, 1.0)[:, None], 0.0)
    if core is not None:
        R_t, r, L = core
        z = np.where(ua > 0, L, r)
        if qz is not None:
            side = np.abs(ua) * (L - r) <= FLAT_TOL_MM
            z = np.where(side, np.clip(qz, r, L), z)
        off = z[:, None] * A + R_t * e + r * U
    else:  # any revolved profile: the sampled outline's farthest point
        pts = np.concatenate([seg.points(512) for seg in cutter._outline()])
        score = pts[None, :, 0] * np.where(flat, 0.0, npp)[:, None] + pts[None, :, 1] * ua[:, None]
        k = np.argmax(score, axis=1)
        off = pts[k, 1, None] * A + pts[k, 0, None] * e
    return off, np.where(flat, R_flat, 0.0)


def _side_height(cutter) -> float:
    core = cutter._rounded_core()
    return float(core[2] - core[1]) if core is not None else float(cutter.length)


def cut_segments(toolpath, cutter, step: float, turn_deg: float = 10.0):
    """Start and end tips and axes of the cutting motions, as chords about ``step`` mm long: the positions
    are thinned to one every ``step`` mm of path, keeping where the path turns by more than ``turn_deg``
    or a cutting run starts or ends, and long motions are cut so that no point of the cutting part moves
    more than ``step`` along one (the contact path is taken as the chord of each). Also (k, 2) flags: the
    chord starts a cutting run, ends one."""
    tip = np.asarray(toolpath.tip, float)
    axis = np.asarray(toolpath.axis, float)
    n = tip.shape[0]
    empty = np.empty((0, 3))
    if n < 2:
        return empty, empty, empty, empty, np.empty((0, 2), bool)
    seg_cut = np.asarray(toolpath.move)[1:] == Move.CUT  # the move ending at j + 1
    d = np.diff(tip, axis=0)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(d, axis=1))])
    keep = np.zeros(n, bool)
    keep[[0, -1]] = True
    keep[1:-1] |= seg_cut[1:] != seg_cut[:-1]  # a cutting run starts or ends
    keep[1:] |= np.floor(s[1:] / step) != np.floor(s[:-1] / step)
    u = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
    keep[1:-1] |= np.einsum("ij,ij->i", u[1:], u[:-1]) < np.cos(np.radians(turn_deg))
    keep[1:-1] |= np.einsum("ij,ij->i", axis[1:-1], axis[:-2]) < np.cos(np.radians(0.5 * turn_deg))
    K = np.flatnonzero(keep)
    cut_k = seg_cut[K[1:] - 1]  # every motion between two kept positions is cut or none is
    T, A, owner = motion_poses(tip[K], axis[K], step, float(max(cutter.length, cutter.radius)))
    cut = cut_k[owner[1:] - 1]
    # where a cutting run starts and ends: a footprint beyond those is past the pass, not beside it
    ends = np.zeros((cut.size, 2), bool)
    ends[:, 0] = cut & ~np.r_[False, cut[:-1]]
    ends[:, 1] = cut & ~np.r_[cut[1:], False]
    return T[:-1][cut], A[:-1][cut], T[1:][cut], A[1:][cut], ends[cut]


def sample_curvature(P: np.ndarray, N: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Per sample, the largest turn of the normal per mm along the grid edges it is an end of (1/mm; 0 where
    it is in no grid quad): a bound of the face's normal curvature there, up to the sampling."""
    out = np.zeros(P.shape[0])
    if Q.size == 0:
        return out
    q = np.asarray(Q, int)
    e = np.concatenate([q[:, [0, 1]], q[:, [1, 2]], q[:, [2, 3]], q[:, [3, 0]]])
    k = np.linalg.norm(N[e[:, 0]] - N[e[:, 1]], axis=1) / np.maximum(
        np.linalg.norm(P[e[:, 0]] - P[e[:, 1]], axis=1), 1e-300
    )
    np.maximum.at(out, e[:, 0], k)
    np.maximum.at(out, e[:, 1], k)
    return out


def machined_region(
    cutter, toolpath, P, N, reached, *, depth: float, stock: float, touch: float, curvature=None, chunk: int = 4000
):
    """Per sample: True in the machined region (see the module docstring), False on the border or where
    nothing reached it. ``P``, ``N``: samples and outward unit normals (mm); ``touch`` (mm): a footprint
    touches the face when it lies within ``touch`` of the sample's tangent plane plus what the face's
    ``curvature`` (1/mm per sample, :func:`sample_curvature`; 0: planes) bends it over the distance across.

    The contact paths are searched within a distance ``D`` across the tangent plane that doubles from a
    quarter of the tool radius up to what the test can need (``2 R_cut + R_flat``); a sample is settled
    as soon as the footprints within ``D`` decide it (the nearest one lies within ``D`` and so does the
    whole opposite side it can pair with), so the passes of a raster are looked at near each sample only.
    """
    out = np.zeros(P.shape[0], bool)
    kappa = np.zeros(P.shape[0]) if curvature is None else np.asarray(curvature, float)
    R_cut, R_flat = cutting_extent(cutter)
    T0, A0, T1, A1, ends = cut_segments(toolpath, cutter, 0.5 * R_cut)
    todo = np.flatnonzero(reached)
    if T0.shape[0] == 0 or todo.size == 0:
        return out
    half = 0.5 * float(np.linalg.norm(T1 - T0, axis=1).max())
    off = _offset_bound(cutter, np.concatenate([A0, A1]), N, R_cut)
    tree = cKDTree(0.5 * (T0 + T1))
    full = 2.0 * R_cut + R_flat
    for D in (0.25 * R_cut + R_flat, 0.5 * R_cut + R_flat, R_cut + R_flat, full):
        D = min(D, full)
        left = []
        for s in range(0, todo.size, chunk):
            rows = todo[s : s + chunk]
            # the tip of a motion whose footprint lies within D across and the blade along: within this
            reach = half + off[rows] + max(depth, stock) + D + 1e-9
            hits = tree.query_ball_point(P[rows], reach)
            lens = np.fromiter((len(h) for h in hits), int, count=len(hits))
            si = np.repeat(np.arange(rows.size), lens)
            ki = np.concatenate([np.asarray(h, int) for h in hits if h] or [np.empty(0, int)])
            motions = (T0, A0, T1, A1, ends)
            lim = (depth, stock, touch, kappa[rows])
            inside, settled = _classify(cutter, P[rows], N[rows], si, ki, motions, lim, R_cut, D)
            out[rows] = inside
            left.append(rows[~settled])
        todo = np.concatenate(left)
        if todo.size == 0 or D >= full:
            break
    return out


def _offset_bound(cutter, axes, N, R_cut) -> np.ndarray:
    """Per sample, a bound (mm) of the distance from the tip to the support point of any placement of the path
    in the direction ``-n``: ``r |a - n| + R_t`` with the angle between ``n`` and the axes bounded by the
    sample's angle to their mean plus their spread; the side's height ``L`` where ``n`` may lie square to an
    axis (the side supports it at the sample's height)."""
    core = cutter._rounded_core()
    L = float(max(cutter.length, R_cut))
    if core is None:
        return np.full(N.shape[0], float(np.hypot(R_cut, L)))
    R_t, r, L = core
    mean = axes.mean(axis=0)
    mean /= np.linalg.norm(mean)
    spread = float(np.arccos(np.clip(axes @ mean, -1.0, 1.0)).max())
    ang = np.arccos(np.clip(N @ mean, -1.0, 1.0)) + spread + 1e-9
    off = r * 2.0 * np.sin(np.minimum(ang, np.pi) / 2.0) + R_t
    side = ang >= np.pi / 2 - np.arcsin(min(1.0, FLAT_TOL_MM / max(L - r, 1e-12))) - 1e-9
    return np.where(side, np.hypot(R_t + r, L), off)


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def _classify(cutter, P, N, si, ki, motions, lim, R_cut, D):
    """Under a pass or between two, for samples ``P`` given the pairs (sample ``si``, sorted, motion ``ki``)
    that hold every footprint within ``D`` across the tangent plane; and whether that settles it."""
    T0, A0, T1, A1, ends = motions
    depth, stock, touch, kappa = lim
    m = P.shape[0]
    if si.size == 0:
        return np.zeros(m, bool), np.full(m, D >= 2.0 * R_cut)
    n = N[si]
    o0, f0 = support_offsets(cutter, A0[ki], -n, _dot(P[si] - T0[ki], A0[ki]))
    o1, f1 = support_offsets(cutter, A1[ki], -n, _dot(P[si] - T1[ki], A1[ki]))
    r0 = T0[ki] + o0 - P[si]
    r1 = T1[ki] + o1 - P[si]
    h0, h1 = _dot(r0, n), _dot(r1, n)
    v0, v1 = r0 - h0[:, None] * n, r1 - h1[:, None] * n
    dv = v1 - v0
    lam = -_dot(v0, dv) / np.maximum(_dot(dv, dv), 1e-300)
    lam = np.where(_dot(dv, dv) > 0, lam, 0.5)
    lc = np.clip(lam, 0.0, 1.0)
    w = v0 + lc[:, None] * dv
    dist = np.sqrt(_dot(w, w))
    # beside the chord: the foot of the sample on its line lies on it; past a joint inside a cutting run by
    # less than JOINT_DEG as seen from the sample (the next chord turns); never past a run's start or end
    over = np.maximum(-lam, lam - 1.0) * np.sqrt(_dot(dv, dv))
    slack = np.where(((lam < 0) & ends[ki, 0]) | ((lam > 1) & ends[ki, 1]), 0.0, np.sin(np.radians(JOINT_DEG)) * dist)
    beside = over <= slack + 1e-9
    lam = lc
    h = h0 + lam * (h1 - h0)
    flat = np.minimum(f0, f1)
    gap = np.maximum(dist - flat, 0.0)  # to the footprint: a point, or the flat bottom's disc
    # touching: at most ``touch`` above the tangent plane, plus what the contact path bends over the distance
    # across (the face's curvature, tightened by the tool's radius on a concave face), and not farther than the
    # face turns by MAX_TURN_RAD (beyond, its tangent plane tells nothing); the cutting part faces the sample
    k = kappa[si]
    bend = 0.5 * k / (1.0 - np.minimum(k * R_cut, 0.9)) * dist * dist
    ok = (h >= -depth - 1e-9) & (h <= np.minimum(stock, touch + bend) + 1e-9) & (k * dist <= MAX_TURN_RAD)
    ok &= _dot(n, A0[ki]) >= -FLAT_TOL_MM / max(_side_height(cutter), 1e-12)
    gap = np.where(ok, gap, np.inf)
    # the nearest footprint of each sample (pairs come grouped by sample)
    starts = np.flatnonzero(np.r_[True, si[1:] != si[:-1]])
    g1 = np.full(m, np.inf)
    g1[si[starts]] = np.minimum.reduceat(gap, starts)
    at = np.flatnonzero(gap == g1[si])
    at = at[np.r_[True, si[at][1:] != si[at][:-1]]]
    w1 = np.zeros((m, 3))
    w1[si[at]] = w[at]
    beside1 = np.zeros(m, bool)
    beside1[si[at]] = beside[at]
    under = g1 <= 1e-9 + 1e-12 * R_cut
    d1 = np.sqrt(_dot(w1, w1))
    cos = _dot(w, w1[si]) / np.maximum(dist * d1[si], 1e-300)
    opp = ok & beside & (cos <= OPPOSITE_COS) & (gap + g1[si] <= 2.0 * R_cut)
    between = (np.bincount(si[opp], minlength=m) > 0) & beside1
    R_flat = cutting_extent(cutter)[1]
    # a footprint beyond D may be missing: the nearest is known when within D, the far side when 2 R_cut - g1 is
    settled = under | between | (g1 + R_flat <= D) & (2.0 * R_cut - g1 + R_flat <= D) | (D >= 2.0 * R_cut + R_flat)
    return under | (between & np.isfinite(g1)), settled


__all__ = ["machined_region", "support_offsets", "cut_segments", "cutting_extent"]
