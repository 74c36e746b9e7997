"""Progress bars on a terminal, silence elsewhere (tqdm when available; optional)."""

from __future__ import annotations

import sys


def progress(iterable, *, desc: str = "", total: int | None = None, enabled: bool | None = None):
    """Wrap ``iterable`` in a progress bar shown only when stderr is a terminal.

    ``enabled=None`` decides from the terminal; tqdm is optional (FreeCAD's Python may not
    have it), without it the iterable is returned unchanged.
    """
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return iterable
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        return iterable
    return tqdm(iterable, desc=desc, total=total, leave=False, file=sys.stderr)
