"""Work split into independent chunks, run here one after the other or by any ``map``-like callable
(a Dask cluster in a batch: :func:`machsurf_cad.batchrun.dask_map`)."""

from __future__ import annotations

import numpy as np

from .errors import InputError


def check_chunks(chunks) -> int:
    """``chunks`` as an int >= 1 (one-line error otherwise)."""
    n = int(chunks)
    if n < 1:
        raise InputError(f"chunks must be >= 1, got {chunks!r}")
    return n


def map_pieces(fn, pieces, map_chunks=None, *more) -> list:
    """``fn`` over the pieces (and the matching ``more`` lists) by ``map_chunks``; a single piece runs here."""
    runner = map_chunks if (map_chunks is not None and len(pieces) > 1) else map
    return list(runner(fn, pieces, *more))


def split_map(fn, arrays, chunks, map_chunks=None) -> list:
    """Cut ``arrays`` (same length) into ``chunks`` contiguous pieces and return ``fn(*pieces)`` per chunk,
    in order."""
    n = min(check_chunks(chunks), max(len(arrays[0]), 1))
    cuts = np.linspace(0, len(arrays[0]), n + 1).astype(int)
    pieces = [[a[i:j] for i, j in zip(cuts[:-1], cuts[1:])] for a in arrays]
    return map_pieces(fn, pieces[0], map_chunks, *pieces[1:])


def threaded_split_map(fn, arrays, progress=None, message: str = "", pieces_per_core: int = 8) -> list:
    """``fn(*pieces)`` over contiguous pieces of ``arrays`` (same length) in a thread per core (at most 8),
    in order; ``progress(done, total, message)`` from the calling thread as pieces finish. For work that
    spends its time in numpy and scipy calls, which release Python's lock."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    n = len(arrays[0])
    cores = max(1, min(os.cpu_count() or 1, 8))
    cuts = np.linspace(0, n, cores * pieces_per_core + 1).astype(int)
    spans = [(i, j) for i, j in zip(cuts[:-1], cuts[1:]) if j > i]
    with ThreadPoolExecutor(max_workers=cores, thread_name_prefix="machsurf") as pool:
        futures = [pool.submit(fn, *(a[i:j] for a in arrays)) for i, j in spans]
        out = []
        try:
            for (_, j), f in zip(spans, futures):
                out.append(f.result())
                if progress is not None:
                    progress(int(j), int(n), message)
        except BaseException:  # cancelled or failed: the pieces not started are dropped, running ones end
            for f in futures:
                f.cancel()
            raise
    return out
