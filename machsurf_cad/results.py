"""The result protocol shared by every job (mm, degrees, seconds).

Every result type of machsurf_cad is a frozen dataclass with ``eq=False`` (results hold
arrays: identity is the only honest equality, and they are not hashable by value), whose
numpy arrays are read-only views, and whose ``report()`` returns a JSON-ready dict with
unit-suffixed keys: ``_mm`` lengths, ``_deg`` angles, ``_s`` seconds, ``_mm2`` areas,
``_mm_min`` feeds. Timings are one dict ``time_s`` of named stages in seconds.

Long operations take one progress callback, :data:`Progress`:
``progress(done, total, message)`` with ``total`` ``None`` when it is not known.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

Progress = Callable[[int, int | None, str], None]
"""``progress(done, total, message)``: ``done`` work units of ``total`` (``None`` if unknown)."""


def no_progress(done: int, total: int | None = None, message: str = "") -> None:
    """The default :data:`Progress`: does nothing."""


def readonly(a) -> np.ndarray:
    """A read-only view of ``a`` (no copy when ``a`` is already an array)."""
    v = np.asarray(a).view()
    v.flags.writeable = False
    return v


class Result:
    """Base of result dataclasses: arrays become read-only on construction.

    Subclasses are ``@dataclass(frozen=True, eq=False)``; a subclass with its own
    ``__post_init__`` calls ``super().__post_init__()`` first.
    """

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                object.__setattr__(self, f.name, readonly(v))

    def report(self) -> dict:  # pragma: no cover - every result overrides it
        raise NotImplementedError


class Stopwatch:
    """Named stage timings in seconds, reported as ``{"<stage>_s": ...}``.

    >>> sw = Stopwatch()
    >>> with sw("fit"):
    ...     pass
    >>> sorted(sw.report())
    ['fit_s', 'total_s']
    """

    def __init__(self) -> None:
        self._t0 = time.perf_counter()
        self.stages: dict[str, float] = {}

    def __call__(self, stage: str) -> _Stage:
        return _Stage(self, stage)

    def report(self) -> dict:
        out = {f"{k}_s": v for k, v in self.stages.items()}
        out["total_s"] = time.perf_counter() - self._t0
        return out


class _Stage:
    def __init__(self, sw: Stopwatch, name: str):
        self.sw, self.name = sw, name

    def __enter__(self) -> None:
        self.t = time.perf_counter()

    def __exit__(self, *exc) -> None:
        self.sw.stages[self.name] = self.sw.stages.get(self.name, 0.0) + time.perf_counter() - self.t


def json_default(o: Any) -> Any:
    """``json.dumps`` hook for numpy values and paths."""
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o)}")


def write_json(path, data: dict) -> Path:
    """Write ``data`` as indented JSON (numpy values converted); returns the path."""
    path = Path(path)
    path.write_text(json.dumps(data, indent=2, default=json_default) + "\n")
    return path


__all__ = ["Progress", "no_progress", "readonly", "Result", "Stopwatch", "json_default", "write_json"]
