"""Type aliases of the public API's parameters: what each kind of argument may be given as.

Imports only the standard library and :mod:`numpy.typing`; the package's own classes are named under
``TYPE_CHECKING`` (every module annotates with ``from __future__ import annotations``, so importing
these aliases at run time pulls in no other module of machsurf_cad and makes no import cycle).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any, TypeAlias, Union

from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from .cutters import Cutter
    from .geometry.bspline import BSplineSurface
    from .geometry.face import Face
    from .machining.strategies import IsoFeed, PlanesFeed

ToolLike: TypeAlias = Union["Cutter", str]
"""A cutter, or its text (``"ball:D=10"``, ``"bull:D=28,r=4"``: :func:`~machsurf_cad.parse_cutter`)."""

FaceLike: TypeAlias = Union["Face", "BSplineSurface"]
"""A trimmed face, or a B-spline surface (taken as the face of its whole parameter box)."""

FacesLike: TypeAlias = Sequence[FaceLike]
"""Several faces (a list or tuple of them)."""

PartLike: TypeAlias = FaceLike | FacesLike
"""A part's faces: one face, or a list or tuple of them."""

Vector3: TypeAlias = Sequence[float] | NDArray[Any]
"""Three floats ``(x, y, z)`` (a tuple, list or array), e.g. a tool axis (normalised where used)."""

PathLike: TypeAlias = str | os.PathLike[str]
"""A file or folder: its name as text or a :class:`pathlib.Path`."""

MapChunks: TypeAlias = Callable[..., Iterable[Any]] | None
"""``map``-like callable, ``map_chunks(fn, pieces, *more) -> results in order`` (the built-in ``map``, or
:func:`machsurf_cad.batchrun.dask_map` over a Dask cluster); ``None``: the chunks run here one after the other."""

ProgressLike: TypeAlias = Callable[[int, int | None, str], None] | None
"""A :data:`~machsurf_cad.results.Progress` callable ``progress(done, total, message)``, or ``None``."""

StrategyLike: TypeAlias = Union[str, "PlanesFeed", "IsoFeed"]
"""A feed (:class:`~machsurf_cad.PlanesFeed`, :class:`~machsurf_cad.IsoFeed`) or its text: ``"planes:x"``,
``"planes:a,b,c"``, ``"iso:u"``."""

__all__ = [
    "ArrayLike",
    "FaceLike",
    "FacesLike",
    "MapChunks",
    "PartLike",
    "PathLike",
    "ProgressLike",
    "StrategyLike",
    "ToolLike",
    "Vector3",
]
