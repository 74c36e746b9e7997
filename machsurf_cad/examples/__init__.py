"""The papers' test surfaces, example parts and tool motions: one registry (mm, degrees).

Each example is defined once; :data:`EXAMPLES` names them and says which views exist:
a B-spline ``surface`` (machining surfaces, effective radius, inspection), a ``ruled``
surface with exact directrices (flank milling) or a tool ``motion`` (swept envelopes).

Examples
--------
>>> from machsurf_cad.examples import example
>>> example("liu", "ruled").u_range
(0.0, 23.014)
>>> sorted(n for n, e in EXAMPLES.items() if e.motion is not None)
['helix', 'line', 'sine']
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from ..errors import InputError
from .motions import helix_motion, line_motion, sine_motion
from .surfaces import (
    FittedSurface,
    bezier5_patch,
    eq18_directrix_maps,
    eq18_ruled,
    eq18_surface,
    hypar_directrices,
    hypar_ruled,
    hyperbolic_paraboloid,
    liu_directrices,
    liu_ruled,
    liu_surface,
    propeller_blade,
)

ExampleView = Literal["surface", "ruled", "motion"]


@dataclass(frozen=True)
class Example:
    """A named example and its builders (each ``None`` where the view does not exist)."""

    name: str
    description: str
    surface: Callable[[], Any] | None = None
    ruled: Callable[[], Any] | None = None
    motion: Callable[[], Any] | None = None

    def views(self) -> list[str]:
        """The views this example has: ``surface``, ``ruled``, ``motion``."""
        return [v for v in ("surface", "ruled", "motion") if getattr(self, v) is not None]


EXAMPLES: dict[str, Example] = {
    e.name: e
    for e in (
        Example("bezier5", "degree-5 Bezier bump of 100 mm (machining-surface paper's example)", surface=bezier5_patch),
        Example(
            "blade", "400 mm propeller-blade pressure face (effective-radius paper's case)", surface=propeller_blade
        ),
        Example(
            "hypar",
            "hyperbolic paraboloid, alpha0 = 30 deg, h_p = 80 mm (flank paper, section 3.2)",
            surface=hyperbolic_paraboloid,
            ruled=hypar_ruled,
        ),
        Example("liu", "Liu's ruled surface, 0 <= u <= 23.014 (flank paper)", surface=liu_surface, ruled=liu_ruled),
        Example(
            "eq18",
            "ruled surface of the flank paper's eq. (18) (sqrt(u) directrix; fitted as a B-spline)",
            surface=lambda: eq18_surface().surface,
            ruled=eq18_ruled,
        ),
        Example("sine", "100 mm sine-wave tip path, turning axis", motion=sine_motion),
        Example("line", "straight 100 mm path along X, axis Z", motion=line_motion),
        Example("helix", "quarter helix of radius 60 mm, axis tilted 15 deg", motion=helix_motion),
    )
}
"""Every example by name."""


def example(name: str, view: ExampleView = "surface"):
    """Build the example ``name`` in the given ``view``.

    Parameters
    ----------
    name : str
        A key of :data:`EXAMPLES`.
    view : {"surface", "ruled", "motion"}
        ``surface`` gives a :class:`~machsurf_cad.geometry.BSplineSurface`, ``ruled`` a
        :class:`~machsurf_cad.flank_milling.RuledSurface`, ``motion`` a :class:`~machsurf_cad.sweep.Motion`.

    Returns
    -------
    BSplineSurface, RuledSurface or Motion

    Raises
    ------
    InputError
        Unknown name, or the example has no such view; the message lists the known ones.

    Examples
    --------
    >>> example("bezier5").degree_u, example("sine", "motion").t_range
    (5, (0.0, 1.0))
    """
    known = sorted(n for n, e in EXAMPLES.items() if getattr(e, view, None) is not None)
    e = EXAMPLES.get(name)
    build = getattr(e, view, None) if e is not None else None
    if build is None:
        raise InputError(f"unknown {view} example {name!r}; known: {', '.join(known)}")
    return build()


__all__ = [
    "EXAMPLES",
    "Example",
    "example",
    "bezier5_patch",
    "propeller_blade",
    "hyperbolic_paraboloid",
    "hypar_ruled",
    "hypar_directrices",
    "liu_surface",
    "liu_ruled",
    "liu_directrices",
    "eq18_surface",
    "eq18_ruled",
    "eq18_directrix_maps",
    "FittedSurface",
    "sine_motion",
    "line_motion",
    "helix_motion",
]
