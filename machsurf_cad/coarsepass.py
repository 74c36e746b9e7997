"""The sampled pass of the tool-body check (:func:`machsurf_cad.verify`): per tool placement, the part
samples near the tool (a k-d tree: spheres along the axis of a bare cutter, the bounding sphere of a body
with shank or holder) measured against the body in its (rho, z) half-plane. Each placement's figures
depend on no other placement, so the pass runs in chunks or threads, and the placements of the last
checks are kept by their exact bits: a path checked again after a few of its moves changed measures only
the new placements.
"""

from __future__ import annotations

import functools
import math
import os
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from .arrays import concat_ranges, unique_sorted
from .chunking import check_chunks, split_map, threaded_split_map


def _blocks(tree, centers, reach: float, count: bool, chunk: int = 256, pairs: int = 4_000_000):
    """Slices of the placements, ``chunk`` at most; with ``count`` (a clearance of tens of mm puts much of the
    part in every placement's window) cut smaller where their samples within ``reach`` would pass
    ``pairs``."""
    for start in range(0, centers.shape[0], chunk):
        stop = min(centers.shape[0], start + chunk)
        if not count:
            yield slice(start, stop)
            continue
        counts = np.asarray(tree.query_ball_point(centers[start:stop], reach, workers=-1, return_length=True))
        if counts.sum() <= pairs:
            yield slice(start, stop)
            continue
        a, total = 0, 0
        for k, n in enumerate(counts.tolist()):
            if total + n > pairs and k > a:  # a placement over the budget alone goes on its own
                yield slice(start + a, start + k)
                a, total = k, 0
            total += n
        yield slice(start + a, stop)


def _capsule_pairs(tree, T, A, length: float, radius: float, pad: float):
    """(placement, sample) pairs, sorted, of every sample within ``pad`` of the cylinder of ``radius`` and
    ``length`` on each placement's axis from its tip (and some further ones): the samples within spheres
    centred on the axis at most 1.5 ``(radius + pad)`` apart that cover it (instead of one sphere around the
    whole body, several times as many samples on a long tool)."""
    n_s = max(1, math.ceil(length / (1.5 * (radius + pad))))
    a = length / (2 * n_s)
    # a point of the padded cylinder is within hypot(a + pad, radius + pad) <= hypot(a, radius) + pad * sqrt(2)
    # of the nearest centre (a hair more: the spheres' test is in floating point)
    reach = (math.hypot(a, radius) + pad * math.sqrt(2)) * (1 + 1e-9) + 1e-9
    zs = a * (2 * np.arange(n_s) + 1)
    centres = (T[:, None, :] + A[:, None, :] * zs[None, :, None]).reshape(-1, 3)
    near = cKDTree(centres).sparse_distance_matrix(tree, reach, output_type="ndarray")
    key = unique_sorted((near["i"] // n_s).astype(np.int64) * tree.n + near["j"].astype(np.int64))
    return key // tree.n, key % tree.n


def coarse(c, tree, P, h, tolerance, T, A, progress=None, clear=0.0):
    """The sampled pass over placements ``(T, A)``: per placement the smallest signed distance of a part
    sample to the cutting part, to shank and holder, and that sample; the samples inside the cutting
    part with their depth (indices, depths). Samples up to ``clear`` mm beyond the body are seen (a
    clearance of several mm asked for a rapid is measured, not read as clear). Module level: chunks of
    placements travel to workers."""
    m = T.shape[0]
    L_cut = float(c.length)
    r_cut = float(c.profile_points(16)[:, 0].max())
    L_all, r_all = c.body_length(), c.max_radius()
    has_holder = bool(c.body_parts())
    pad = h + tolerance + max(0.0, float(clear))
    reach = math.hypot(L_all / 2 + pad, r_all + pad) * (1 + 1e-9)  # the padded body's corners too
    cut_d = np.full(m, np.inf)
    hold_d = np.full(m, np.inf)
    seed = np.full(m, -1)
    hold_seed = np.full(m, -1)
    d_idx: list = []
    d_val: list = []
    d_pl: list = []
    for sl in _blocks(tree, T + A * (L_all / 2), reach, count=clear > max(2.0, 4.0 * h)):
        if has_holder:  # every sample in the body's bounding sphere: shank and holder get a distance however far
            lists = tree.query_ball_point(T[sl] + A[sl] * (L_all / 2), reach, workers=-1)
            counts = np.fromiter((len(x) for x in lists), int, len(lists))
            if counts.sum() == 0:
                continue
            pl = np.repeat(np.arange(sl.start, sl.stop), counts)
            pi = np.concatenate([np.asarray(x, int) for x in lists if x])
        else:  # only the samples the cutting part's figures can use: those within ``pad`` of it
            pl, pi = _capsule_pairs(tree, T[sl], A[sl], L_all, r_all, pad)
            if pl.size == 0:
                continue
            counts = np.bincount(pl, minlength=sl.stop - sl.start)
            pl = pl + sl.start
        rel = P[pi] - T[pl]
        z = np.einsum("ij,ij->i", rel, A[pl])
        rho = np.linalg.norm(rel - z[:, None] * A[pl], axis=1)
        near = (z > -pad) & (z < L_cut + pad) & (rho < r_cut + pad)
        sd = np.full(pi.size, np.inf)
        sd[near] = c.cutting_distance_rz(rho[near], z[near])
        inside = sd < 0
        d_idx.append(pi[inside])
        d_val.append(-sd[inside])
        d_pl.append(pl[inside])
        # per placement (pairs are grouped by placement): the smallest distance and its sample
        nz = counts > 0
        starts = np.r_[0, np.cumsum(counts[nz])[:-1]]
        mins = np.minimum.reduceat(sd, starts)
        first = np.flatnonzero(sd == np.repeat(mins, counts[nz]))
        grp = np.searchsorted(starts, first, side="right") - 1
        _, take = np.unique(grp, return_index=True)
        owners = np.arange(sl.start, sl.stop)[nz]
        better = mins < cut_d[owners]
        cut_d[owners[better]] = mins[better]
        seed[owners[better]] = pi[first[take]][better]
        if has_holder:  # the smallest distance to shank and holder, and its sample
            hd = c.holder_distance_rz(rho, z)
            hmins = np.minimum.reduceat(hd, starts)
            hfirst = np.flatnonzero(hd == np.repeat(hmins, counts[nz]))
            _, htake = np.unique(np.searchsorted(starts, hfirst, side="right") - 1, return_index=True)
            hbetter = hmins < hold_d[owners]
            hold_d[owners[hbetter]] = hmins[hbetter]
            hold_seed[owners[hbetter]] = pi[hfirst[htake]][hbetter]
        if progress is not None:
            progress(sl.stop, m, "tool placements")
    idx = np.concatenate(d_idx) if d_idx else np.empty(0, int)
    val = np.concatenate(d_val) if d_val else np.empty(0)
    pl_ = np.concatenate(d_pl) if d_pl else np.empty(0, int)
    return cut_d, hold_d, seed, idx, val, hold_seed, pl_


class _Memo(NamedTuple):
    """One check's sampled pass: its inputs' key, each placement's exact bits (tip, axis) and hash, the
    figures per placement, and the inside pairs (placement, sample, depth) sorted by placement."""

    key: str
    rows: np.ndarray
    hashes: np.ndarray
    order: np.ndarray
    figures: tuple
    pairs: tuple


_LAST: OrderedDict = OrderedDict()
_MAX_LAST = 2
MEMO_PLACEMENTS = 2_000_000
"""Most placements a check keeps for the next one (about 100 bytes each: 200 MB)."""
_MIX = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9, 0xD6E8FEB86659FD93,
                 0xFF51AFD7ED558CCD, 0xC4CEB9FE1A85EC53], dtype=np.uint64)  # fmt: skip


def _rows(T, A):
    """Each placement's tip and axis as their 6 float64s' bits, and a hash of them."""
    rows = np.ascontiguousarray(np.hstack([T, A]), dtype=np.float64).view(np.uint64)
    with np.errstate(over="ignore"):
        h = (rows * _MIX).sum(axis=1, dtype=np.uint64)
        h ^= h >> np.uint64(31)
    return rows, h


def _matches(memo: _Memo, rows, hashes) -> np.ndarray:
    """Per placement, a placement of ``memo`` with the very same bits (its index), else -1."""
    if memo.hashes.size == 0:
        return np.full(rows.shape[0], -1)
    srt = memo.hashes[memo.order]
    pos = np.minimum(np.searchsorted(srt, hashes), srt.size - 1)
    cand = memo.order[pos]
    same = (srt[pos] == hashes) & np.all(memo.rows[cand] == rows, axis=1)
    return np.where(same, cand, -1)


def _run(c, tree, P, h, gouge_tolerance, T, A, chunks, map_chunks, progress, threaded_from, clear):
    """:func:`coarse` over the placements in chunks (a thread per core from ``threaded_from`` placements in
    one chunk): the figures per placement and the inside pairs with their placement's index in ``T``."""
    one = check_chunks(chunks) == 1
    work = functools.partial(coarse, c, tree, P, h, gouge_tolerance, clear=clear)
    if one and map_chunks is None and T.shape[0] >= threaded_from and (os.cpu_count() or 1) > 1:
        parts = threaded_split_map(work, [T, A], progress, "tool placements")
    else:
        parts = split_map(functools.partial(work, progress=progress if one else None), [T, A], chunks, map_chunks)
    starts = np.cumsum([0] + [q[0].size for q in parts])[:-1]
    figures = tuple(np.concatenate([q[k] for q in parts]) for k in (0, 1, 2, 5))  # cut_d, hold_d, seed, hold_seed
    pl = np.concatenate([q[6] + s for q, s in zip(parts, starts)])
    return figures, (pl, np.concatenate([q[3] for q in parts]), np.concatenate([q[4] for q in parts]))


def coarse_pass(c, tree, P, h, gouge_tolerance, T, A, chunks=1, map_chunks=None, progress=None, threaded_from=4096,
                clear=0.0, memo_key: str = ""):  # fmt: skip
    """The sampled pass (:func:`coarse`) over the placements; per placement the smallest distances and
    their samples, per sample the deepest depth: ``(cut_d, hold_d, seed, hold_seed, depth)``. Each
    placement's figures are its own (the same in any chunking or batch), so with ``memo_key`` (the
    part's samples, the tool and the parameters) the placements of the last checks under the same key
    with the very same bits are not measured again: a path checked again after a few moves were split
    costs only its new placements. The figures are the same to the last bit either way (tests)."""
    rows, hashes = _rows(T, A)
    memo = _LAST.get(memo_key) if memo_key else None
    old = _matches(memo, rows, hashes) if memo is not None else np.full(T.shape[0], -1)
    new = np.flatnonzero(old < 0)
    f_new, (pl_new, idx_new, val_new) = _run(c, tree, P, h, gouge_tolerance, T[new], A[new], chunks, map_chunks,
                                             progress, threaded_from, clear)  # fmt: skip
    if memo is None or new.size == T.shape[0]:
        figures, pl, idx, val = f_new, pl_new, idx_new, val_new
    else:
        hit = np.flatnonzero(old >= 0)
        figures = tuple(np.empty(T.shape[0], f.dtype) for f in f_new)
        for out, fo, fn in zip(figures, memo.figures, f_new):
            out[new] = fn
            out[hit] = fo[old[hit]]
        o_pl, o_idx, o_val = memo.pairs  # sorted by the memo's placement
        lo = np.searchsorted(o_pl, old[hit], side="left")
        cnt = np.searchsorted(o_pl, old[hit], side="right") - lo
        take = concat_ranges(lo, cnt)
        pl = np.concatenate([np.repeat(hit, cnt), new[pl_new]])
        idx = np.concatenate([o_idx[take], idx_new])
        val = np.concatenate([o_val[take], val_new])
    if memo_key and T.shape[0] <= MEMO_PLACEMENTS:
        srt = np.argsort(pl, kind="stable")
        _LAST[memo_key] = _Memo(memo_key, rows, hashes, np.argsort(hashes, kind="stable"), figures,
                                (pl[srt], idx[srt], val[srt]))  # fmt: skip
        _LAST.move_to_end(memo_key)
        while len(_LAST) > _MAX_LAST:
            _LAST.popitem(last=False)
    depth = np.zeros(P.shape[0])
    np.maximum.at(depth, idx, val)
    cut_d, hold_d, seed, hold_seed = (f.copy() for f in figures)  # the caller refines them in place
    return cut_d, hold_d, seed, hold_seed, depth
