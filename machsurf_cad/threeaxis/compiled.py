"""The compiled drop-cutter path: a :class:`FaceSet` and a cutter packed into flat arrays for the numba
kernel (:mod:`._jit_drop`), and the call that runs it.

The numpy path (:func:`.dropcutter._drop_chunk`) is the reference: the kernel runs the same branch and
bound with the same local solves one query at a time (in parallel over the queries), and the tests check
that both give the same heights. The kernel is used when numba imports and every face's degrees are at most
7 (the power-basis patches both paths evaluate); otherwise the numpy path runs.
"""

from __future__ import annotations

import contextlib
import math
from functools import lru_cache

import numpy as np

from ..arrays import concat_ranges
from ..cutter_profiles import ArcSegment, LineSegment
from ..geometry.bspline import _POWER_MAX_DEGREE
from ..geometry.face import TRIM_TOLERANCE
from .cells import fine_cells
from .faceset import FaceSet


@lru_cache(maxsize=1)
def available() -> bool:
    """Whether numba imports (the compiled kernel can run)."""
    try:
        import numba  # noqa: F401
    except Exception:
        return False
    return True


@lru_cache(maxsize=1)
def build_error() -> str | None:
    """None when the kernel compiles (once per process, :func:`warm_up`), else why it does not (an older
    numba, say): the drop-cutter's ``auto`` engine then runs the numpy path and says so."""
    try:
        warm_up()
    except Exception as e:
        return f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
    return None


def warm_up() -> float:
    """Compile the kernel (or load it from numba's cache beside the sources) on a small plane; the seconds it
    took. The first compilation on a machine takes about a minute; later processes load it in under one."""
    import time

    from ..cutters import BallEndMill
    from ..geometry.builders import plane_patch
    from .faceset import face_set
    from .solves import _Profile

    t = time.perf_counter()
    fs = face_set([plane_patch((-5, -5, 0), (10, 0, 0), (0, 10, 0))], spacing=1.0)
    drop(fs, _Profile(BallEndMill(2.0)), np.zeros((1, 2)))
    return time.perf_counter() - t


def kernel_stamp() -> str:
    """A hash of the kernel's callee sources. numba re-compiles a cached function when its own file changes,
    not when a function it calls changes in another file: :data:`._jit_drop.KERNEL_SOURCES` must equal this
    (a test checks it), so that any change of the callees changes the entry point's file too."""
    import hashlib
    from pathlib import Path

    here = Path(__file__).parent
    h = hashlib.sha256()
    for name in ("_jit_geom.py", "_jit_solve.py", "_jit_cert.py"):
        h.update((here / name).read_bytes())
    return h.hexdigest()[:16]


def supports(fs: FaceSet) -> bool:
    """Whether the kernel handles every face of ``fs`` (degrees at most 7 in u and v)."""
    return all(f.surface.degree_u <= _POWER_MAX_DEGREE and f.surface.degree_v <= _POWER_MAX_DEGREE for f in fs.faces)


def _surfaces(fs: FaceSet):
    n = len(fs.faces)
    fi = np.zeros((n, 15), np.int64)
    ff = np.zeros((n, 12))
    ust, hus, vst, hvs, coefs, loops, px, py = [], [], [], [], [], [], [], []
    nu = nv = nc = nl = npt = 0
    for f, face in enumerate(fs.faces):
        s = face.surface
        tu, tv, hp = s._eval_data
        flat, mapu, mapv, hu, hv, nsv = s._power_data
        p, q, dim = s.degree_u, s.degree_v, hp.shape[2]
        blocks = flat.reshape(-1, p + 1, q + 1, dim)
        if dim == 3:
            w = np.zeros(blocks.shape[:3] + (1,))
            w[:, 0, 0, 0] = 1.0
            blocks = np.concatenate([blocks, w], axis=3)
        su, sv = np.nonzero(mapu >= 0)[0], np.nonzero(mapv >= 0)[0]
        trimmed = bool(face.is_trimmed)
        polys = face.trim_polygons(TRIM_TOLERANCE) if trimmed else []
        fi[f] = (p, q, su.size, sv.size, nu, nv, nc, s.periodic_u, s.periodic_v, *fs.closed[f], trimmed, nl,
                 nl + len(polys), dim == 4)  # fmt: skip
        ff[f, :4] = tu[p], tu[hp.shape[0]], tv[q], tv[hp.shape[1]]
        ff[f, 4:8] = s.knots_u[0], s.knots_u[-1], s.knots_v[0], s.knots_v[-1]
        ff[f, 8:12] = fs.bounds[f]
        ust.append(tu[su])
        hus.append(hu)
        vst.append(tv[sv])
        hvs.append(hv)
        coefs.append(blocks.ravel())
        for poly in polys:
            loops.append((npt, poly.shape[0]))
            px.append(poly[:, 0])
            py.append(poly[:, 1])
            npt += poly.shape[0]
        nu, nv, nc, nl = nu + su.size, nv + sv.size, nc + blocks.size, nl + len(polys)
    S = (fi, ff, *(np.ascontiguousarray(np.concatenate(a), dtype=float) for a in (ust, hus, vst, hvs, coefs)))
    return S, _slabs(fi, np.array(loops, np.int64).reshape(-1, 2), np.concatenate(px) if px else np.zeros(0),
                     np.concatenate(py) if py else np.zeros(0))  # fmt: skip


def _slabs(fi, loops, px, py):
    """The trimming polygons' edges bucketed in horizontal slabs of v per face, so that the even-odd test of a
    point visits the edges of its slab only (a face's polygons may have tens of thousands of vertices). The
    slabs' bounds are quantiles of the edges' ends, so that a run of short edges (a loop along a side of the
    parameter box, level but for rounding) fills thin slabs of its own instead of one slab every point near
    that side visits. A slab ``(b_k, b_k+1]`` holds the edges with ``lo < b_k+1`` and ``hi > b_k``: every edge
    that crosses a ray in it (``lo < v <= hi``); a level edge crosses none and is in none. Each slab's edges
    are copied in its order (their ends' u, v), so that a test reads one run of memory instead of the
    polygons' vertices scattered over tens of thousands."""
    n = fi.shape[0]
    tf = np.zeros((n, 2), np.int64)
    tl = np.zeros((n, 3))
    starts, items, ea, eb, tb = [np.zeros(1, np.int64)], [], [], [], []
    n_edges = n_slab = n_bounds = 0
    for f in range(n):
        a_, b_ = [], []
        for s, m in loops[fi[f, 12] : fi[f, 13]]:
            i = np.arange(m)
            a_.append(s + i)
            b_.append(s + (i + 1) % m)
        if not a_:
            continue
        a, b = np.concatenate(a_), np.concatenate(b_)
        lo, hi = np.minimum(py[a], py[b]), np.maximum(py[a], py[b])
        vmin, vmax = float(lo.min()), float(hi.max())
        ends = np.sort(np.concatenate([lo[hi > lo], hi[hi > lo], [vmin, vmax]]))
        ns = int(max(1, min(4096, a.size // 4)))
        bounds = np.unique(ends[np.round(np.linspace(0, ends.size - 1, ns + 1)).astype(np.int64)])
        if bounds.size < 2:
            bounds = np.array([vmin, vmax if vmax > vmin else vmin + 1.0])
        ns = bounds.size - 1
        s0 = np.clip(np.searchsorted(bounds[1:], lo, side="right"), 0, ns - 1)
        s1 = np.clip(np.searchsorted(bounds, hi, side="left") - 1, 0, ns - 1)
        cnt = np.where(hi > lo, np.maximum(s1 - s0 + 1, 0), 0)
        slab = concat_ranges(s0, cnt)
        edge = np.repeat(np.arange(a.size), cnt)
        order = np.argsort(slab, kind="stable")
        starts.append(starts[-1][-1] + np.cumsum(np.bincount(slab, minlength=ns)))
        items.append(n_edges + edge[order])
        ea.append(a)
        eb.append(b)
        tb.append(bounds)
        tf[f] = n_slab, ns
        tl[f] = vmin, n_bounds, vmax  # (the face's slab bounds are tb[n_bounds:][:ns + 1])
        n_bounds += ns + 1
        n_edges += a.size
        n_slab += ns
    cat = np.concatenate
    it = cat(items).astype(np.int64) if items else np.zeros(0, np.int64)
    a, b = (cat(x).astype(np.int64)[it] if x else np.zeros(0, np.int64) for x in (ea, eb))
    seg = np.ascontiguousarray(np.column_stack([px[a], py[a], px[b], py[b]]) if it.size else np.zeros((0, 4)))
    return tf, tl, cat(starts).astype(np.int64), seg, cat(tb) if tb else np.zeros(0)


def _curves(fs: FaceSet):
    n = len(fs.edges)
    ei = np.zeros((max(n, 1), 7), np.int64)
    loop = fs.edge_loop
    ef = np.zeros((max(n, 1), 2))
    knots, poles = [], []
    nk = npol = 0
    for e, c in enumerate(fs.edges):
        t, hp = c._eval_data
        if hp.shape[1] == 2:
            hp = np.column_stack([hp, np.ones(hp.shape[0])])
        ei[e] = c.degree, nk, t.size, npol, hp.shape[0], fs.edge_face[e], int(loop[e])
        ef[e] = c.bounds
        knots.append(t)
        poles.append(hp)
        nk, npol = nk + t.size, npol + hp.shape[0]
    knots_a = np.concatenate(knots) if knots else np.zeros(1)
    return ei, ef, knots_a, np.concatenate(poles) if poles else np.zeros((1, 3))


def _profile(prof):
    rows = []
    for seg in prof.segs:
        if isinstance(seg, LineSegment):
            rows.append((0.0, seg.rho0, seg.z0, seg.rho1, seg.z1, 0.0))
        elif isinstance(seg, ArcSegment):
            rows.append((1.0, seg.rho_c, seg.z_c, seg.radius, seg.start_deg, seg.end_deg))
        else:  # pragma: no cover - cutters give lines and arcs
            raise TypeError(f"profile segment {type(seg).__name__} is not supported by the compiled kernel")
    segs = np.array(rows, float).reshape(-1, 6)
    # lower_height at the disc's rim and axis, where the pieces stop short (PIECE_MARGIN) and every sample
    # beyond the rim or within its cover of the axis would search the segments again
    from ._jit_geom import lower_height

    at_R, at_0 = lower_height(segs, float(prof.R)), lower_height(segs, 0.0)
    consts = np.array([prof.R, prof.h_R, prof.h_min, 1.0 if prof.monotone else 0.0, *at_R, *at_0])
    return segs, consts, _pieces_of(segs.tobytes(), segs.shape[0], float(prof.R))


@lru_cache(maxsize=32)
def _pieces_of(key: bytes, n: int, R: float) -> np.ndarray:
    """:func:`_pieces` of the segments whose bits are ``key``, once per cutter and process (4.5 ms a call: a
    raster's 95 drop-cutter calls spent 0.43 s on it). The kernel only reads it."""
    return _pieces(np.frombuffer(key, float).reshape(n, 6).copy(), R)


def _pieces(segs: np.ndarray, R: float) -> np.ndarray:
    """The profile's lower surface as pieces of ``[0, R]`` on each of which one segment (one arc branch) is
    the lowest: rows ``lo, hi, kind (0 line, 1 arc, -1 none), r0, z0, r1, z1`` (lines) or ``rho_c, z_c, r,
    branch`` (arcs), for :func:`._jit_geom.piece_height`. Ends: every segment's ends in ``rho`` and its arcs'
    extremes. Checked against ``lower_height`` on 500 points of every piece and at its first and last radii
    (to the bit); a profile where they differ anywhere (segments crossing inside a piece, an arc of over
    57 mm) gets no pieces: ``lower_height`` runs everywhere."""
    from ._jit_geom import PIECE_MARGIN, lower_height, lowest_segment, piece_height

    ends = [0.0, R]
    for typ, a, _b, c, d, e in segs:
        if typ == 0.0:
            ends += [a, c]
        else:
            ends += [a - c, a + c] + [a + c * math.cos(math.radians(x)) for x in (d, e)]
    cuts = np.unique(np.clip(np.array(ends, float), 0.0, R))
    rows = []
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        if hi - lo <= 4e-9:
            continue
        s, sgn = lowest_segment(segs, 0.5 * (lo + hi))[3:]
        if s < 0:
            rows.append((lo, hi, -1.0, 0.0, 0.0, 0.0, 0.0))
        elif segs[s, 0] == 0.0:
            rows.append((lo, hi, 0.0, *segs[s, 1:5]))
        else:
            rows.append((lo, hi, 1.0, *segs[s, 1:4], sgn))
    tb = np.array(rows, float).reshape(-1, 7)
    for lo, hi in tb[:, :2]:
        # and the first and last radii a piece takes (PIECE_MARGIN in): lower_height runs an arc 1e-9 degrees
        # past its ends, more than the margin on arcs of over 57 mm (a long drum's side: no pieces then)
        inner = np.nextafter([lo + PIECE_MARGIN, hi - PIECE_MARGIN], [hi, lo])
        for x in np.r_[inner, np.linspace(lo + 2e-9, hi - 2e-9, 500)]:
            fast = piece_height(tb, x)
            if not fast[3] or fast[:3] != lower_height(segs, x):
                return np.zeros((0, 7))
    return tb


def _pool(fs: FaceSet):
    c = fine_cells(fs)
    n_int = fs.sample_xyz.shape[0]
    xyz, pf, puv = (np.ascontiguousarray(a) for a in (fs.pool_xyz, fs.pool_face, fs.pool_uv))
    return (xyz, pf, puv, n_int, fs.edge_id.astype(np.int64), fs.edge_t.astype(float), fs.edge_dt.astype(float),
            fs.cover.astype(float), fs.rise.astype(float), fs.min_tilt.astype(float),
            fs.edge_cover.astype(float), c.start, c.xyz, c.rise, c.cover, c.radius, c.top,
            fs.edge_rise.astype(float))  # fmt: skip


def _grid(xyz: np.ndarray, reach: float, top: np.ndarray):
    """A plan grid of the pool samples with cells of about half ``reach`` (at most 2048 a side): meta (x0, y0,
    cell size), dims, each cell's start in ``items``, the items (pool indices) and their ``top`` (the highest a
    sample can raise or bound: its z plus its rise, or its z; NaN last). A cell's items run from the highest
    ``top`` down, so that a query stops reading a cell where the rest are below the height it already knows
    (:func:`._jit_drop._gather`)."""
    xy = xyz[:, :2]
    lo = xy.min(axis=0) if xy.size else np.zeros(2)
    hi = xy.max(axis=0) if xy.size else np.zeros(2)
    cs = max(reach / 2, float((hi - lo).max()) / 2048, 1e-9)
    nx, ny = (int(math.floor((hi[k] - lo[k]) / cs)) + 1 for k in range(2))
    ix = np.clip(((xy[:, 0] - lo[0]) // cs).astype(np.int64), 0, nx - 1)
    iy = np.clip(((xy[:, 1] - lo[1]) // cs).astype(np.int64), 0, ny - 1)
    cell = ix * ny + iy
    key = np.where(np.isnan(top), np.inf, -top)  # (descending top, NaN last; ties by pool index)
    items = np.lexsort((np.arange(cell.size), key, cell)).astype(np.int64)
    start = np.zeros(nx * ny + 1, np.int64)
    np.cumsum(np.bincount(cell, minlength=nx * ny), out=start[1:])
    return np.array([lo[0], lo[1], cs]), np.array([nx, ny], np.int64), start, items, np.ascontiguousarray(top[items])


PARALLEL_CHUNK = 32
"""Query points per chunk of the kernel's parallel loop (measured on the mould and the block, 40,000 points:
about a tenth less wall time than the two fixed halves); a chunk's points share its solves' scratch."""

MAX_WINDOW_BYTES = 64 * 2**20
"""The edge search windows' points are kept when they take at most this much memory (else evaluated)."""


def _packed(fs: FaceSet):
    """The face set's arrays for the kernel (cached on the face set)."""
    from ._jit_solve import WINDOW, edge_windows

    cache = fs.__dict__.setdefault("_compiled", {})
    if "fs" not in cache:
        S, T = _surfaces(fs)
        E = _curves(fs)
        pool = _pool(fs)
        n_e = fs.edge_id.shape[0]
        EW = np.empty((0, WINDOW, 3))
        if 0 < n_e * WINDOW * 24 <= MAX_WINDOW_BYTES:
            EW = np.empty((n_e, WINDOW, 3))
            edge_windows(S, E, pool[4], pool[5], pool[6], EW)
        c = fine_cells(fs)
        cache["fs"] = (S, E, T, (*pool, EW, c.uv, c.steps))
    return cache["fs"]


def drop(fs: FaceSet, prof, C: np.ndarray):
    """Heights, contact kinds, faces and contact points of the queries ``C`` (n, 2): the outputs of
    :func:`.dropcutter._drop_chunk`, from the compiled kernel."""
    from ._jit_drop import drop_batch

    S, E, T, SM = _packed(fs)
    cache = fs.__dict__["_compiled"]
    cells = fine_cells(fs)
    reach = prof.R + max(fs.spacing, float(cells.radius.max(initial=0.0)) if cells.contained else 0.0)
    key = ("grid", round(reach, 12))
    if key not in cache:
        n_int, rise, erise = SM[3], SM[8], SM[17]
        r = rise.copy()
        r[n_int:] = np.fmax(rise[n_int:], erise)  # (as _prune's: an edge sample's face or edge rise)
        cache[key] = _grid(SM[0], reach, SM[0][:, 2] + np.maximum(r, 0.0))
    G = cache[key]
    PR = _profile(prof)
    h0 = float(prof(np.zeros(1))[0][0])
    K = np.array([prof.R, fs.spacing, prof.max_tilt, prof.h_R, 1.0 if prof.pointed else 0.0, len(fs.faces),
                  max(len(fs.edges), 1), h0, reach, 1.0 if cells.contained else 0.0,
                  1.0 if prof.h_min == prof.h_R and not prof.pointed else 0.0])  # fmt: skip
    kinks = np.array(prof.kinks, float).reshape(-1, 2)
    m = C.shape[0]
    height = np.full(m, np.nan)
    kind = np.zeros(m, np.int8)
    face = np.full(m, -1, np.int64)
    point = np.full((m, 3), np.nan)
    import numba

    # the points in chunks handed to whichever thread is free (numba >= 0.57): the points' costs differ by
    # region and so do the two cores' speeds under load; without it each thread takes a fixed half
    chunks = getattr(numba, "parallel_chunksize", None)
    with chunks(1) if chunks is not None else contextlib.nullcontext():
        drop_batch(np.ascontiguousarray(C, dtype=float), S, E, T, PR, SM, G, K, kinks, height, kind, face, point,
                   PARALLEL_CHUNK)  # fmt: skip
    return height, kind, face, point


if __name__ == "__main__":  # pragma: no cover - `make venv` compiles the kernel once
    if available():
        import time as _time

        _t = _time.perf_counter()
        _err = build_error()
        if _err is None:
            print(f"machsurf_cad: drop-cutter kernel ready ({_time.perf_counter() - _t:.1f} s)")
        else:  # the numpy path runs instead (drop_cutter says so): set-up goes on
            print(f"machsurf_cad: the drop-cutter kernel does not build ({_err}); the numpy path runs")
    else:
        print("machsurf_cad: numba is not installed: the drop-cutter runs its numpy path")
