"""The result protocol shared by every job (mm, degrees, seconds).

Every result type of machsurf_cad is a frozen dataclass with ``eq=False`` (results hold
arrays: identity is the only honest equality, and they are not hashable by value), whose
numpy arrays are read-only views, and whose ``report()`` returns a JSON-ready dict with
unit-suffixed keys: ``_mm`` lengths, ``_deg`` angles, ``_s`` seconds, ``_mm2`` areas,
``_mm_min`` feeds. Timings are one dict ``time_s`` of named stages ``<stage>_s`` in seconds.

Long operations take one progress callback, :data:`Progress`:
``progress(done, total, message)`` with ``total`` ``None`` when it is not known.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

Progress = Callable[[int, int | None, str], None]
"""``progress(done, total, message)``: ``done`` work units of ``total`` (``None`` if unknown)."""


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


def json_default(o: Any) -> Any:
    """``json.dumps`` hook for numpy values and paths."""
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o)}")


def json_ready(o: Any) -> Any:
    """``o`` with numpy values as Python ones and every NaN or infinity as ``None`` (JSON's null: no value)."""
    if isinstance(o, dict):
        return {str(k): json_ready(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_ready(v) for v in o]
    if isinstance(o, np.ndarray):
        return json_ready(o.tolist())
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        o = o.item()
    if isinstance(o, float) and not np.isfinite(o):
        return None
    if isinstance(o, Path):
        return str(o)
    return o


def strict_json(data: Any, indent: int | None = 2) -> str:
    """Strict JSON text (RFC 8259: no NaN or Infinity, which become null), numpy values converted."""
    return json.dumps(json_ready(data), indent=indent, allow_nan=False, default=json_default)


def write_json(path, data: dict) -> Path:
    """Write ``data`` as indented strict JSON (numpy values converted, NaN/infinity as null)."""
    path = Path(path)
    path.write_text(strict_json(data) + "\n")
    return path


__all__ = ["Progress", "readonly", "Result", "json_default", "json_ready", "strict_json", "write_json"]
