"""Exact drop-cutter on the B-rep: the lowest tool position above ``(x, y)`` that touches no face.

For a tool whose axis is +z (the :class:`~machsurf_cad.threeaxis.faceset.FaceSet` frame) and whose lower
surface is ``z = tip_z + h(rho)`` (:func:`~machsurf_cad.cutter_profiles.lower_height`, out to the profile's
largest radius ``R``), the tip height at ``c = (x, y)`` is

    tip_z(c) = sup over part points p with |p_xy - c| < R of  p_z - h(|p_xy - c|),

the lowest height at which the tool does not enter the part. Points exactly on the tool's circle count as
limits of points inside (a fillet tangent to a wall exactly ``R`` away does); a face or edge that only
touches the circle from outside (a plane wall exactly ``R`` from the axis) touches the tool's side without
entering it and does not lift the tool (:func:`~machsurf_cad.threeaxis.solves._enters_face`).

The maximum is reached at one of these contacts, each found by a local solve on the exact NURBS:

* ``FACE``: inside a face, where ``g(u, v) = S_z - h(|S_xy - c|)`` is stationary (damped Newton with a
  trust region; it also finds flat spots under a flat bottom, ``h' = 0``);
* ``RIM``: the profile's outer circle ``rho = R`` on a face (Newton on the Lagrange system of
  ``max S_z`` subject to ``|S_xy - c| = R``): walls, steep faces, a flat end mill's edge;
* ``EDGE``: on a trimming edge or at a vertex, or on a crease (an iso-parameter line where a face is only
  C0: a peak there is no stationary point of either side); a safeguarded Newton search along the edge's
  exact curve, cut back to the circle where the maximum lies outside it;
* ``TIP``: the point below a pointed tip (profiles with ``h'(0) > 0``);
* ``SAMPLE``: a seed sample itself, when no refinement beats it (counted in the report).

Two engines run the same algorithm: the numpy reference (vectorised over the queries of a batch) and a
compiled kernel (numba, :mod:`~machsurf_cad.threeaxis.compiled`: one query at a time, in parallel); they
give the same heights (tested to 1e-9 mm). Face sets and heights are cached
(:mod:`~machsurf_cad.threeaxis.cache`).

Seeds come from a k-d tree over the face and edge samples in plan; per query the best sample of each
face and edge in five sectors of the disc (centre, four quadrants) seeds the solves. Every candidate
is a point of the part inside the disc, so the result never lies above the exact value; it equals it
when a seed lies in the basin of the highest contact (checked against brute force and OpenCAMLib in
the tests).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..glossary import DropEngine, renamed
from ..results import Progress, Result
from ..typing import ArrayLike, FacesLike, ToolLike, Vector3
from . import cache
from .faceset import FaceSet
from .faceset import face_set as build_face_set
from .solves import (
    _ON_CIRCLE,
    _edge_search,
    _enters_face,
    _face_newton,
    _inside,
    _into_disc,
    _Profile,
    _rim_newton,
    _surface_eval,
    _tip_solve,
)


class Contact(IntEnum):
    """Where the tool touches the part at a CL point (OpenCAMLib's CC types, for any profile)."""

    NONE = 0
    """No face under the tool: the height is NaN."""
    FACE = 1
    """The profile tangent to a face's interior (includes flat spots under a flat bottom)."""
    RIM = 2
    """The profile's outer circle on a face (walls, steep faces)."""
    EDGE = 3
    """A trimming edge or vertex of a face, or a crease of it (an iso-parameter line where it is only C0)."""
    TIP = 4
    """The point below a pointed tip."""
    SAMPLE = 5
    """A seed sample (no refinement beat it)."""


@dataclass(frozen=True, eq=False)
class DropCutterResult(Result):
    """Exact drop-cutter heights at query points (mm).

    Attributes
    ----------
    xy : ndarray (n, 2)
        Query points in the tool frame (``x`` along ``frame[0]``, ``y`` along ``frame[1]``).
    height : ndarray (n,)
        Tip height along the axis (tool frame z), NaN where no face lies under the tool.
    tip : ndarray (n, 3)
        CL points (tool tips) in world coordinates.
    contact : ndarray (n, 3)
        The contact (CC) points in world coordinates.
    face : ndarray (n,)
        Index of the contact face in the given faces (-1: none).
    kind : ndarray (n,)
        :class:`Contact` of each point.
    axis : ndarray (3,)
        Tool axis (world, unit).
    frame : ndarray (3, 3)
        World -> tool frame rotation (rows e1, e2, axis).
    cutter : str
        The cutter's spec.
    time_s : dict
        Stage timings (seconds).
    engine : str
        The engine that computed the heights ("compiled" or "numpy").
    n_cached : int
        Points answered from the heights computed earlier for the same faces, tool and engine
        (:mod:`~machsurf_cad.threeaxis.cache`).
    """

    xy: np.ndarray
    height: np.ndarray
    tip: np.ndarray
    contact: np.ndarray
    face: np.ndarray
    kind: np.ndarray
    axis: np.ndarray
    frame: np.ndarray
    cutter: str
    time_s: dict
    engine: str = "numpy"
    n_cached: int = 0

    @property
    def n_points(self) -> int:
        return int(self.height.shape[0])

    def report(self) -> dict:
        kinds = {k.name.lower(): int(np.count_nonzero(self.kind == k)) for k in Contact}
        ok = np.isfinite(self.height)
        return {
            "cutter": self.cutter,
            "n_points": self.n_points,
            "n_without_face": int((~ok).sum()),
            "contacts": kinds,
            "height_min_mm": float(self.height[ok].min()) if ok.any() else None,
            "height_max_mm": float(self.height[ok].max()) if ok.any() else None,
            "axis": [float(a) for a in self.axis],
            "engine": self.engine,
            "n_cached": self.n_cached,
            "time_s": dict(self.time_s),
        }


# ----------------------------------------------------------------------------- the query
MAX_PAIRS_PER_CHUNK = 4_000_000
"""(query, sample) pairs solved at once (about 200 bytes each across the seed arrays: under 1 GB)."""
MAX_PAIRS = 500_000_000
"""Most (query, sample) pairs a drop-cutter call takes on before it refuses (measured about 6.5 us a pair on
this 2-core machine, bezier5 and a D200 ball: about an hour)."""
SECONDS_PER_PAIR = 6.5e-6


def _chunk_size(fs: FaceSet, prof: _Profile, n: int, chunk: int) -> int:
    """Queries per batch so that a batch's pairs fit :data:`MAX_PAIRS_PER_CHUNK`; a call whose pairs exceed
    :data:`MAX_PAIRS` (a tool much larger than the part's sample spacing: every query sees every sample)
    is refused with the figure."""
    n_pool, lo, hi, size = fs.pool_extent
    if n_pool == 0 or n == 0:
        return max(1, chunk)
    if 2 * prof.R > 10 * max(size, 1e-9):
        raise InputError(
            f"the tool (D = {2 * prof.R:g} mm) is more than 10 times the part's size ({size:.4g} mm across): "
            "check the units of the tool and the part"
        )
    reach = prof.R + fs.spacing
    box = float(np.prod(np.maximum(hi - lo, 0) + 2 * reach))
    per_query = min(float(n_pool), n_pool * math.pi * reach * reach / box)
    if per_query * n > MAX_PAIRS:
        raise InputError(
            f"drop-cutter: about {per_query * n:.3g} (point, part sample) pairs ({n:,} points, the tool's disc of "
            f"radius {prof.R:g} mm over about {per_query:.3g} samples each; about "
            f"{per_query * n * SECONDS_PER_PAIR / 60:.0f} min), more than {MAX_PAIRS:.3g}: "
            "use fewer points or a tool closer to the part's size (check the units)"
        )
    return int(max(1, min(chunk, MAX_PAIRS_PER_CHUNK // max(per_query, 1.0))))


def _seeds(fs: FaceSet, prof: _Profile, C: np.ndarray):
    """Pairs (query, sample) within the tool's disc (plus a margin), the best feasible sample per query,
    and per (query, face or edge, sector) the best sample as a seed."""
    n_int = fs.sample_xyz.shape[0]
    margin = fs.spacing
    qtree = cKDTree(C)
    sdm = qtree.sparse_distance_matrix(fs.tree, prof.R + margin, output_type="ndarray")
    qi = sdm["i"].astype(np.int64)
    sj = sdm["j"].astype(np.int64)
    xyz = fs.pool_xyz[sj]
    d = xyz[:, :2] - C[qi]
    rho = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])  # as the compiled path computes it (ties match)
    h = prof(np.minimum(rho, prof.R))[0]
    val = xyz[:, 2] - h
    feasible = rho <= prof.R
    # the centre (sector 0), else the quadrant of the sample around the axis (1 to 4, counter-clockwise from -x-y)
    quadrant = np.where(d[:, 1] < 0, np.where(d[:, 0] < 0, 1, 2), np.where(d[:, 0] > 0, 3, 4))
    sector = np.where(rho < 0.5 * prof.R, 0, quadrant)
    is_edge = sj >= n_int
    group = np.where(is_edge, len(fs.faces) + fs.edge_id[np.maximum(sj - n_int, 0)], fs.pool_face[sj])
    return qi, sj, rho, xyz, val, feasible, sector, is_edge, group


def _best_per(key, val, tie=None):
    """Index of the largest ``val`` per distinct ``key``; among equal values the smallest ``tie`` (the pool
    sample's index: the compiled path breaks ties the same way), else the first."""
    if key.size == 0:
        return np.zeros(0, int)
    order = np.lexsort((-val, key)) if tie is None else np.lexsort((tie, -val, key))
    k = key[order]
    first = np.ones(k.size, bool)
    first[1:] = k[1:] != k[:-1]
    return order[first]


class _Candidates:
    """Contact candidates of a chunk: query, value (tip height), kind, face, point, edge (-1: none)."""

    def __init__(self):
        self.parts: list = []

    def add(self, q, g, kind, fid, P, ok=None, eid=None):
        if ok is None:
            ok = np.isfinite(g)
        e = np.full(int(ok.sum()), -1) if eid is None else eid[ok]
        self.parts.append((q[ok], g[ok], np.full(int(ok.sum()), kind), fid[ok], P[ok], e))

    def best(self, m: int, edge: bool = False):
        """Per query the best candidate's height, kind, face and point (and its edge, with ``edge``)."""
        q, v, k, f, p, e = (np.concatenate([pt[i] for pt in self.parts]) for i in range(6))
        # the highest value; among equal values a solved contact before a bare sample
        v_rank = v - np.where(k == Contact.SAMPLE, 1e-12 * (1 + np.abs(v)), 0.0)
        win = _best_per(q, v_rank)
        height = np.full(m, np.nan)
        kind = np.zeros(m, np.int8)
        face = np.full(m, -1)
        point = np.full((m, 3), np.nan)
        on_edge = np.full(m, -1)
        height[q[win]], kind[q[win]], face[q[win]], point[q[win]] = v[win], k[win], f[win], p[win]
        on_edge[q[win]] = e[win]
        return (height, kind, face, point, on_edge) if edge else (height, kind, face, point)


def _start(fs, sj):
    """Face index and (u, v) of pool samples (face samples, then edge samples)."""
    n_int = fs.sample_xyz.shape[0]
    is_edge = sj >= n_int
    ke = np.where(is_edge, sj - n_int, 0)
    uv = fs.pool_uv[sj]
    return fs.pool_face[sj], uv[:, 0], uv[:, 1], is_edge, ke


def _solve(fs, prof, C, cand: _Candidates, q, sj, kind: str, kink: int | None = None):
    """Local solves of one kind from seed samples ``sj`` for queries ``q``."""
    if q.size == 0:
        return
    fid, u0, v0, is_edge, ke = _start(fs, sj)
    c = C[q]
    if kind == "face":
        P0 = _surface_eval(fs, fid, u0, v0, 0)[0]
        out = np.nonzero(np.hypot(*(P0[:, :2] - c).T) > prof.R * (1 - 1e-3))[0]
        starts = [(u0, v0)]
        if out.size:  # starts outside the disc or at its rim: towards the axis, onto a circle just inside
            # the rim where the face reaches it (1e-3 R: a ball's profile turns vertical at the rim, where
            # Newton would crawl), else to the face's point nearest the axis (a sliver under the rim); and a
            # second start further in, towards that point, from which Newton may reach a higher maximum
            u0, v0 = u0.copy(), v0.copy()
            u1, v1 = u0[out], v0[out]
            u0[out], v0[out] = _into_disc(fs, prof.R, c[out], fid[out], u1, v1)
            starts = [(u0, v0), _into_disc(fs, prof.R, c[out], fid[out], u1.copy(), v1.copy(), deeper=True)]
        for k, (us, vs) in enumerate(starts):
            sel = slice(None) if k == 0 else out
            u, v, g, P = _face_newton(fs, prof, c[sel], fid[sel], us, vs)
            ok = np.isfinite(g) & _inside(fs, fid[sel], u, v)
            ok[ok] = _enters_face(fs, prof.R, c[sel][ok], fid[sel][ok], u[ok], v[ok], P[ok])
            cand.add(q[sel], g, Contact.FACE, fid[sel], P, ok)
        if prof.pointed:
            u, v, ok, P = _tip_solve(fs, c, fid, u0.copy(), v0.copy())
            g = P[:, 2] - prof(np.zeros(P.shape[0]))[0]
            cand.add(q, g, Contact.TIP, fid, P, ok & _inside(fs, fid, u, v))
    elif kind == "rim":
        rk, hk = (None, None) if kink is None else prof.kinks[kink]
        u, v, g, P = _rim_newton(fs, prof, c, fid, u0, v0, radius=rk, h_at=hk)
        ok = np.isfinite(g) & _inside(fs, fid, u, v)
        ok[ok] = _enters_face(fs, prof.R, c[ok], fid[ok], u[ok], v[ok], P[ok])
        cand.add(q, g, Contact.RIM, fid, P, ok)
    else:
        eid = fs.edge_id[ke]
        g, P = _edge_search(fs, prof, c, eid, fs.edge_t[ke], fs.edge_dt[ke])
        cand.add(q, g, Contact.EDGE, fs.edge_face[eid], P, eid=eid)


def _drop_chunk(fs: FaceSet, prof: _Profile, C: np.ndarray):
    """Branch and bound over seed groups (per query, face or edge, and sector of the disc).

    The best sample is a lower bound of the tip height; each sample bounds from above what its
    neighbourhood can reach (``z + rise - h(rho - cover)``). Three kinds of seeds: per group the best
    sample inside the disc starts a face solve (from an edge sample only where the face has no inside
    sample: a sliver between its last grid row and its boundary), the highest sample near the rim a rim
    solve, the best edge sample an edge search. Each query's best face and rim seeds are solved first,
    then every seed whose group bound still beats the best contact found, except face seeds of the
    found contact's face within two cover radii of it (its own basin)."""
    m = C.shape[0]
    qi, sj, rho, xyz, val, feasible, sector, is_edge, group = _seeds(fs, prof, C)
    cand = _Candidates()
    fid_all = _start(fs, sj)[0]

    def pick(sel, key, score):
        return sel[_best_per(key[sel], score[sel], sj[sel])]

    # the best sample inside the disc (not on its circle: see _enters_face) is a lower bound
    best = pick(np.nonzero(rho < prof.R * (1 - _ON_CIRCLE))[0], qi, val)
    cand.add(qi[best], val[best], Contact.SAMPLE, fid_all[best], xyz[best])
    cover = fs.cover[sj]
    reach = rho - cover
    ub = np.where(reach <= prof.R, xyz[:, 2] + fs.rise[sj] - prof.floor(reach), -np.inf)
    n_f = len(fs.faces)
    n_g = n_f + len(fs.edges)
    # group bounds: per (query, face, sector) and per (query, edge, sector)
    fkey = (qi * n_f + fid_all) * 5 + sector
    ekey = (qi * n_g + group) * 5 + sector

    def group_max(key, x, sel):
        k = key[sel]
        top = sel[_best_per(k, x[sel])]
        order = np.argsort(key[top])
        return key[top][order], x[top][order]

    fb_keys, fb = group_max(fkey, ub, np.arange(qi.size))

    def bound_of(idx):
        return fb[np.searchsorted(fb_keys, fkey[idx])]

    # face seeds: best feasible per face group (interior samples; edge samples where none)
    interior = np.nonzero(feasible & ~is_edge)[0]
    f_seed = pick(interior, fkey, val)
    edge_in = np.nonzero(feasible & is_edge)[0]
    e_only = edge_in[~np.isin(fkey[edge_in], fkey[f_seed])]
    f_seed = np.concatenate([f_seed, pick(e_only, fkey, val)])
    # and where a face group has no sample inside the disc but one within a cover radius outside it
    # (a sliver of the face under the tool), its sample nearest the disc, moved onto the circle
    outside = np.nonzero(~feasible & (rho - cover <= prof.R))[0]
    outside = outside[~np.isin(fkey[outside], fkey[f_seed])]
    f_seed = np.concatenate([f_seed, pick(outside, fkey, -rho)])
    # no interior contact near a sample steeper than any slope of the profile (within its cover)
    f_seed = f_seed[fs.min_tilt[sj[f_seed]] <= prof.max_tilt + 1e-9]
    # rim seeds: the highest sample within a cover radius inside the rim per face group, and the one
    # nearest the rim outside it
    near = np.nonzero(feasible & (rho >= prof.R - cover))[0]
    out = np.nonzero(~feasible & (rho <= prof.R + cover))[0]
    r_seed = np.concatenate([pick(near, fkey, xyz[:, 2]), pick(out, fkey, -rho)])
    # edge seeds: best edge sample per edge group, inside and just outside the disc apart
    ed = np.nonzero(is_edge)[0]
    ekey = ekey * 2 + feasible
    # inside the disc the best sample; outside it the one nearest the disc (an edge grazing the
    # circle between samples reaches into the disc there)
    e_in, e_out = ed[feasible[ed]], ed[~feasible[ed]]
    e_seed = np.concatenate([pick(e_in, ekey, val), pick(e_out, ekey, -rho)])
    n_int = fs.sample_xyz.shape[0]
    e_cov = fs.edge_cover[np.maximum(sj - n_int, 0)]
    e_reach = rho - e_cov
    e_rise = fs.edge_rise[np.maximum(sj - n_int, 0)]
    e_ub = np.where(e_reach <= prof.R, xyz[:, 2] + e_rise - prof.floor(e_reach), -np.inf)
    eb_keys, eb = group_max(ekey, e_ub, ed)
    # phase 1: each query's best face seed and best rim seed
    f1 = pick(f_seed, qi, val)
    r1 = pick(r_seed, qi, xyz[:, 2])
    _solve(fs, prof, C, cand, qi[f1], sj[f1], "face")
    _solve(fs, prof, C, cand, qi[r1], sj[r1], "rim")
    h1, k1, c_face, p1 = cand.best(m)
    low = np.nan_to_num(h1, nan=-np.inf) + _BOUND_TIE_MM
    solved = k1 == Contact.FACE
    # phase 2: the seeds whose group can still beat the contact found (by more than a tie)
    f2 = f_seed[~np.isin(f_seed, f1)]
    f2 = f2[bound_of(f2) > low[qi[f2]]]
    own = solved[qi[f2]] & (fid_all[f2] == c_face[qi[f2]])
    own &= np.linalg.norm(xyz[f2] - p1[qi[f2]], axis=1) <= 2 * cover[f2]
    f2 = f2[~own]
    # a rim contact is within a cover radius of a sample near the rim: bound z + rise - h(R)
    rim_ub = np.where(np.abs(rho - prof.R) <= cover, xyz[:, 2] + fs.rise[sj] - prof.h_R, -np.inf)
    rb_keys, rb = group_max(fkey, rim_ub, np.arange(qi.size))
    r2 = r_seed[~np.isin(r_seed, r1)]
    r2 = r2[rb[np.searchsorted(rb_keys, fkey[r2])] > low[qi[r2]]]
    e2 = e_seed[eb[np.searchsorted(eb_keys, ekey[e_seed])] > low[qi[e_seed]]]
    _solve(fs, prof, C, cand, qi[f2], sj[f2], "face")
    _solve(fs, prof, C, cand, qi[r2], sj[r2], "rim")
    _solve(fs, prof, C, cand, qi[e2], sj[e2], "edge")
    low = _more_face_rounds(fs, prof, C, cand, m, (qi, sj, xyz, feasible, is_edge), f_seed, ub, fkey, fid_all, cover)
    _more_edge_rounds(fs, prof, C, cand, m, (qi, sj, xyz), ed, e2, e_ub, e_cov, ekey)
    _kink_solves(fs, prof, C, cand, (qi, sj, rho, xyz), fkey, cover, low)
    return cand.best(m)


def _more_face_rounds(fs, prof, C, cand, m, pairs, f_seed, ub, fkey, fid_all, cover) -> np.ndarray:
    """Further rounds of face solves: a face seed is the best sample of its group, whose ascent may end
    on a lower local maximum (a flat bottom over a wavy face has many) while another sample of the group
    still bounds above the best contact: the untried sample of highest bound per group, away from the
    best contact, until no bound beats it. Returns the best heights found (-inf where none)."""
    qi, sj, xyz, feasible, is_edge = pairs
    tried = np.zeros(qi.size, bool)
    tried[f_seed] = True
    pool = np.nonzero(feasible & ~is_edge & (fs.min_tilt[sj] <= prof.max_tilt + 1e-9))[0]
    low = np.full(m, -np.inf)
    for _ in range(_EXTRA_ROUNDS):
        h_b, k_b, f_b, p_b = cand.best(m)
        low = np.nan_to_num(h_b, nan=-np.inf)
        p3 = pool[~tried[pool] & (ub[pool] > low[qi[pool]] + _BOUND_MARGIN_MM)]
        far = (k_b[qi[p3]] != Contact.FACE) | (fid_all[p3] != f_b[qi[p3]])
        far |= np.linalg.norm(xyz[p3] - p_b[qi[p3]], axis=1) > cover[p3]
        p3 = p3[far]
        if p3.size == 0:
            break
        p3 = p3[_best_per(fkey[p3], ub[p3], sj[p3])]
        tried[p3] = True
        _solve(fs, prof, C, cand, qi[p3], sj[p3], "face")
    return low


def _more_edge_rounds(fs, prof, C, cand, m, pairs, ed, e2, e_ub, e_cov, ekey) -> None:
    """Further rounds of edge searches: an edge seed is the best sample of its group, and an edge can have
    another local maximum in the same group (a hole's circle under a flat bottom wider than the hole: the
    bottom's rim reaches the circle on two sides, the higher side only in a sliver between samples): the
    untried edge sample of highest bound per group, away from the best contact on its own edge, until no bound
    beats it. (A sample of another edge near the best contact is searched: two faces' edges meet there, or a
    crease ends on a trimming edge, and the higher of them may be the other one.)"""
    qi, sj, xyz = pairs
    tried = np.zeros(qi.size, bool)
    tried[e2] = True
    pool = ed[np.isfinite(e_ub[ed])]
    n_int = fs.sample_xyz.shape[0]
    for _ in range(_EXTRA_ROUNDS):
        h_b, _, _, p_b, e_b = cand.best(m, edge=True)
        low = np.nan_to_num(h_b, nan=-np.inf)
        p = pool[~tried[pool] & (e_ub[pool] > low[qi[pool]] + _BOUND_MARGIN_MM)]
        near = np.linalg.norm(xyz[p] - p_b[qi[p]], axis=1) <= 2 * e_cov[p]  # NaN (nothing found yet): far
        near &= fs.edge_id[sj[p] - n_int] == e_b[qi[p]]
        p = p[~near]
        if p.size == 0:
            break
        p = p[_best_per(ekey[p], e_ub[p], sj[p])]
        tried[p] = True
        _solve(fs, prof, C, cand, qi[p], sj[p], "edge")


def _kink_solves(fs, prof, C, cand, pairs, fkey, cover, low) -> None:
    """Circles inside the rim where the profile's slope jumps (a cone's or APT tool's bottom edge): per group,
    inside the circle and outside it apart, the highest sample near each, where its bound can still beat
    ``low`` (from inside, the solve reaches a sliver of the face just across the circle); then rounds of the
    untried samples whose bound beats the best height (a face can meet the circle in two places of one group)."""
    qi, sj, rho, xyz = pairs
    m = C.shape[0]
    for k, (rk, hk) in enumerate(prof.kinks):
        near_k = np.nonzero(np.abs(rho - rk) <= cover)[0]
        bound = xyz[:, 2] + fs.rise[sj] - hk
        key = fkey * 2 + (rho < rk)
        tried = np.zeros(qi.size, bool)
        seeds_k = near_k[bound[near_k] >= low[qi[near_k]]]
        seeds_k = seeds_k[_best_per(key[seeds_k], xyz[seeds_k, 2], sj[seeds_k])]
        for _ in range(1 + _EXTRA_ROUNDS):
            if seeds_k.size == 0:
                break
            tried[seeds_k] = True
            _solve(fs, prof, C, cand, qi[seeds_k], sj[seeds_k], "rim", kink=k)
            best = np.nan_to_num(cand.best(m)[0], nan=-np.inf)
            p = near_k[~tried[near_k] & (bound[near_k] > best[qi[near_k]] + _BOUND_MARGIN_MM)]
            seeds_k = p[_best_per(key[p], bound[p], sj[p])]


_EXTRA_ROUNDS = 4
_BOUND_MARGIN_MM = 1e-7
_BOUND_TIE_MM = 1e-10
"""Phase 2 solves a seed only when its group's bound is above the best height by more than this: a bound that
ties it (a flat end on a horizontal floor: the floor's edges and rim at its height) cannot raise it more."""


def default_seed_spacing(cutter) -> float:
    """Seed sample spacing (mm): a third of the tool radius, within [0.2, 2] mm."""
    return float(np.clip(cutter.radius / 3, 0.2, 2.0))


def machining_face_set(faces, check_faces, cutter, *, axis, seed_spacing=None, what: str = "a 3-axis job"):
    """The face set of the faces to machine followed by the faces to avoid (frame of ``axis``), and the
    plan box ``(x0, x1, y0, y1)`` of the machined faces' samples in that frame (mm)."""
    machined = list(faces)
    if not machined:
        raise InputError(f"{what} needs at least one face to machine")
    spacing = default_seed_spacing(cutter) if seed_spacing is None else float(seed_spacing)
    fs = cache.face_set(build_face_set, machined + list(check_faces), axis=axis, spacing=spacing)
    on_edge = fs.edge_face[fs.edge_id]  # a vertical face has no samples inside it: its edges' samples
    xy = np.concatenate([fs.sample_xyz[fs.sample_face < len(machined), :2],
                         fs.edge_xyz[(on_edge < len(machined)) & fs.face_vertical[on_edge], :2]])  # fmt: skip
    return fs, (float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max()))


@renamed(cutter="tool", seed_spacing_mm="seed_spacing", face_set_="face_set", chunk="batch_size")
def drop_cutter(
    faces: FacesLike | None,
    tool: ToolLike,
    xy: ArrayLike,
    *,
    axis: Vector3 = (0.0, 0.0, 1.0),
    seed_spacing: float | None = None,
    face_set: FaceSet | None = None,
    batch_size: int = 8192,
    engine: DropEngine = "auto",
    progress: Progress | None = None,
) -> DropCutterResult:
    """Exact drop-cutter heights of ``tool`` on ``faces`` at the points ``xy`` (module docstring).

    Parameters
    ----------
    faces : sequence of Face or BSplineSurface
        The faces the tool must not cut into (trimmed regions respected).
    tool : Cutter or str
        Any profile cutter (ball, flat, bull, cone, drum, APT), or its string (``ball:D=10``).
    xy : array_like (n, 2)
        Query points in the tool frame (for ``axis = +z``: world x, y), mm.
    axis : 3-vector
        Fixed tool axis (3+2 machining); queries and heights are in its frame
        (:func:`~machsurf_cad.threeaxis.faceset.axis_frame`).
    seed_spacing : float, optional
        Seed sample spacing on faces and edges (default :func:`default_seed_spacing`). Contacts are
        solved on the exact surfaces; a smaller spacing only seeds more local solves.
    face_set : FaceSet, optional
        A prepared face set (reused across calls with the same faces, axis and spacing).
    batch_size : int
        Queries per vectorised batch (bounds memory).
    engine : {"auto", "compiled", "numpy"}
        The compiled kernel (:mod:`~machsurf_cad.threeaxis.compiled`, numba: the same branch and bound and
        local solves, one point at a time, in parallel; 5 to 10 times faster), the numpy reference, or the
        kernel when numba is installed and every face's degrees are at most 7 (``auto``). Both engines give
        the same heights (tested to 1e-9 mm).
    progress : Progress, optional
        ``progress(done, total, message)`` over the queries.

    Returns
    -------
    DropCutterResult

    Examples
    --------
    >>> from machsurf_cad import BallEndMill, builders, drop_cutter
    >>> plane = builders.plane_patch((-20, -20, 0), (40, 0, 0), (0, 40, 0))
    >>> r = drop_cutter([plane], BallEndMill(10), [[0.0, 0.0]])
    >>> round(float(r.height[0]), 9)
    0.0
    """
    from .. import checks

    t0 = time.perf_counter()
    tool = checks.tool(tool)
    xy = checks.points("drop-cutter query points (x, y in mm)", xy, 2)
    if not np.all(np.isfinite(xy)):
        raise InputError("drop-cutter query points must be a finite (n, 2) array of x, y in mm")
    spacing = default_seed_spacing(tool) if seed_spacing is None else checks.positive("seed spacing", seed_spacing)
    fs = face_set if face_set is not None else cache.face_set(build_face_set, faces, axis=axis, spacing=spacing)
    t1 = time.perf_counter()
    prof = _Profile(tool)
    chunk_fn = _engine(engine, fs)
    engine_name = "numpy" if chunk_fn is _drop_chunk else "compiled"
    n = xy.shape[0]
    height = np.full(n, np.nan)
    kind = np.zeros(n, np.int8)
    face = np.full(n, -1)
    point = np.full((n, 3), np.nan)
    memo = cache.HeightMemo.of(fs, repr(tool), engine_name)  # every field at full precision
    rows, keys = memo.lookup(xy)
    known = np.nonzero(rows >= 0)[0]
    if known.size:  # points solved before with this face set, tool and engine: the same numbers
        height[known], kind[known], face[known], point[known] = memo.take(rows[known])
    todo = np.nonzero(rows < 0)[0]
    m = todo.size
    batch_size = _chunk_size(fs, prof, m, int(batch_size))
    for s in range(0, m, batch_size):
        sel = todo[s : min(m, s + batch_size)]
        height[sel], kind[sel], face[sel], point[sel] = chunk_fn(fs, prof, xy[sel])
        memo.store(keys[sel], height[sel], kind[sel], face[sel], point[sel])
        if progress is not None:
            progress(known.size + s + sel.size, n, "drop-cutter")
    t2 = time.perf_counter()
    tip_f = np.column_stack([xy, height])
    return DropCutterResult(
        xy,
        height,
        fs.to_world(tip_f),
        fs.to_world(point),
        face,
        kind,
        fs.frame[2].copy(),
        fs.frame.copy(),
        tool.spec(),
        {"prepare_s": t1 - t0, "drop_s": t2 - t1},
        engine_name,
        int(known.size),
    )


def _engine(engine: str, fs: FaceSet):
    """The chunk function of ``engine`` (see :func:`drop_cutter`)."""
    from . import compiled

    if engine not in ("auto", "compiled", "numpy"):
        raise InputError(f"drop-cutter engine must be 'auto', 'compiled' or 'numpy', got {engine!r}")
    if engine == "numpy":
        return _drop_chunk
    ok = compiled.available() and compiled.supports(fs)
    if ok and engine == "auto" and compiled.build_error() is not None:  # an older numba, say: said, not hidden
        warnings.warn(f"drop-cutter: the compiled kernel does not build ({compiled.build_error()}); "
                      "using the numpy path", RuntimeWarning, stacklevel=3)  # fmt: skip
        return _drop_chunk
    if engine == "compiled" and not ok:
        raise InputError(
            "the compiled drop-cutter needs numba (pip install numba) and faces of degree at most 7"
            if compiled.available()
            else "the compiled drop-cutter needs numba: pip install numba, or use engine='numpy'"
        )
    return compiled.drop if ok else _drop_chunk
