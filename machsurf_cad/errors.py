"""Exceptions of machsurf_cad.

Every error a user can cause derives from :class:`MachsurfError`; the CLI turns
it into a one-line message and an exit code (1 for bad input, 2 for a tolerance
that was not met). Programming errors stay ordinary Python exceptions.
"""

from __future__ import annotations


class MachsurfError(Exception):
    """Base class of the errors machsurf_cad raises on purpose."""

    exit_code = 1


class InputError(MachsurfError, ValueError):
    """Bad input: a missing or corrupt file, an out-of-range index, a bad parameter."""

    exit_code = 1


class DegenerateGeometryError(InputError):
    """Geometry on which the asked quantity does not exist (zero normal, collapsed edge...).

    ``region`` optionally holds where it happens, e.g. ``{"uv": [[u, v], ...]}``.
    """

    def __init__(self, message: str, region: dict | None = None):
        super().__init__(message)
        self.region = region or {}


class ToleranceError(MachsurfError):
    """A stated tolerance could not be met; ``reached`` is the error actually measured (mm)."""

    exit_code = 2

    def __init__(self, message: str, reached: float | None = None):
        super().__init__(message)
        self.reached = reached
