"""Progress bars on a terminal, silence elsewhere (tqdm when available; optional).

Algorithms take an optional ``progress`` callable and stay free of any UI; the CLI passes
one of these. Nothing is shown when stderr is not a terminal (CI, pipes, FreeCAD).
"""

from __future__ import annotations

import sys


def _tqdm():
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is optional (FreeCAD's Python may lack it)
        return None
    return tqdm


def enabled() -> bool:
    return sys.stderr.isatty() and _tqdm() is not None


class Bar:
    """A bar with a known total (``update(done)``) or an open-ended one (``step(text)``)."""

    def __init__(self, desc: str, total: int | None = None):
        self._bar = _tqdm()(desc=desc, total=total, leave=False, file=sys.stderr) if enabled() else None
        self._done = 0

    def update(self, done: int, total: int | None = None):
        if self._bar is None:
            return
        if total is not None and self._bar.total != total:
            self._bar.total = total
        self._bar.update(done - self._done)
        self._done = done

    def step(self, text: str = ""):
        if self._bar is None:
            return
        self._bar.update(1)
        if text:
            self._bar.set_postfix_str(text)

    def close(self):
        if self._bar is not None:
            self._bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def fit_progress(desc: str):
    """A ``progress(iteration, n_poles, max_error)`` callback for :func:`machsurf_cad.approx.fit_surface`."""
    bar = Bar(desc)

    def cb(it, n_poles, err):
        bar.step(f"{n_poles} poles, error {err:.3g} mm")

    cb.close = bar.close
    return cb
