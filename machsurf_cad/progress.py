"""Progress bars on a terminal, silence elsewhere (tqdm when available; optional).

Algorithms take an optional :data:`~machsurf_cad.results.Progress` callable,
``progress(done, total, message)``, and stay free of any UI; the CLI passes a :class:`Bar`
(callable with that signature). Nothing is shown when stderr is not a terminal (CI, pipes,
FreeCAD, which passes its own callable).
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
    """A terminal bar; call it as ``bar(done, total, message)`` (total ``None`` when unknown)."""

    def __init__(self, desc: str, total: int | None = None):
        tq = _tqdm()
        self._bar = tq(desc=desc, total=total, leave=False, file=sys.stderr) if (enabled() and tq) else None
        self._done = 0

    def __call__(self, done: int, total: int | None = None, message: str = "") -> None:
        if self._bar is None:
            return
        if total is not None and self._bar.total != total:
            self._bar.total = total
        self._bar.update(max(0, done - self._done))
        self._done = done
        if message:
            self._bar.set_postfix_str(message, refresh=False)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
