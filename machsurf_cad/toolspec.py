"""Cutters from text: the command line's strings (``ball:D=10``) and APT's ``CUTTER/`` parameters.

Lengths in mm, angles in degrees; every bad string or inconsistent parameter set is a one-line
:class:`~machsurf_cad.errors.InputError`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable

from .cutters import (
    APTCutter,
    BallEndMill,
    BullNoseEndMill,
    ConicalCutter,
    Cutter,
    DrumCutter,
    FlatEndMill,
    _num,
)
from .errors import InputError


def apt_mismatch(d: float, r: float, e: float, f: float, alpha: float, beta: float) -> float:
    """How far (mm) the corner arc ``(e, f, r)`` is from tangent to the bottom and side lines that ``d`` defines.

    The bottom line leaves the tip on the axis at the angle ``alpha``; the side line passes through the
    point of the bottom line at radius ``d/2`` at the taper ``beta`` (degrees). Zero for a consistent set
    (ball, bull and flat: ``d = 2(e + r)`` and ``f = r``).
    """
    al, be = math.radians(alpha), math.radians(beta)
    bottom = f * math.cos(al) - e * math.sin(al) - r
    z_d = d / 2 * math.tan(al)
    side = (d / 2 - e) * math.cos(be) + (f - z_d) * math.sin(be) - r
    return max(abs(bottom), abs(side))


def cutter_from_apt(params: Iterable[float]) -> Cutter:
    """The cutter of an APT ``CUTTER/`` statement (1, 2 or 7 values, mm and degrees).

    Ball, flat and bull-nose end mills are recognised from the 7 parameters (the convention of
    :meth:`Cutter.apt_parameters`), a conical cutter from ``r = 0, alpha = 0, beta != 0``, a drum or barrel
    from its arc spanning the height; other consistent sets give an :class:`APTCutter`.

    Parameters
    ----------
    params : sequence of float
        ``d[, r[, e, f[, alpha, beta[, h]]]]`` (mm, degrees).

    Returns
    -------
    Cutter

    Raises
    ------
    InputError
        A set that is not a cutter: not 1, 2, 4, 6 or 7 finite numbers, or inconsistent (the corner arc not
        tangent to the bottom and side lines that ``d`` defines, :func:`apt_mismatch` over 0.001 mm), or out
        of range.

    Examples
    --------
    >>> cutter_from_apt([20, 4, 6, 4, 0, 0, 60]).spec()
    'bull:D=20,r=4'
    """
    try:
        v = [float(x) for x in params]
    except (TypeError, ValueError):
        raise InputError(f"APT cutter parameters must be numbers, got {params!r}") from None
    if len(v) not in (1, 2, 4, 6, 7) or not all(math.isfinite(x) for x in v):
        raise InputError(f"APT cutter needs 1, 2, 4, 6 or 7 finite values (d, r, e, f, alpha, beta, h), got {v}")
    d = v[0]
    r = v[1] if len(v) > 1 else 0.0
    e, f = (v[2], v[3]) if len(v) >= 4 else (d / 2 - r, r)
    alpha, beta = (v[4], v[5]) if len(v) >= 6 else (0.0, 0.0)
    h = v[6] if len(v) >= 7 else 0.0
    text = "CUTTER/" + ",".join(f"{x:g}" for x in v)
    if h > 0 and alpha == 0 and beta == 0 and r > 0 and abs(f - h / 2) < 1e-3 and abs(f - r) > 1e-3:
        if abs(abs(d / 2 - e) - r) < 1e-3:  # the arc spans the height: a drum (e < d/2) or barrel
            return DrumCutter(d, r, h, concave=e > d / 2)
    miss = apt_mismatch(d, r, e, f, alpha, beta)
    if miss > 1e-3:
        raise InputError(
            f"{text} is inconsistent: its corner arc is {miss:.4g} mm off the bottom and side lines of the "
            f"diameter d = {d:g} mm (a ball, bull or flat end mill has d = 2(e + r) = {2 * (e + r):g} mm and f = r)"
        )
    if alpha == 0 and beta == 0:
        if r == 0:
            return FlatEndMill(d, h)
        if abs(r - d / 2) < 1e-9:
            return BallEndMill(d, h)
        return BullNoseEndMill(d, r, h)
    if r == 0 and alpha == 0 and f == 0:
        return ConicalCutter(d, beta, h)
    return APTCutter(d, r, e, f, alpha, beta, h)


# ----------------------------------------------------------------------------- strings
_KINDS = {
    "ball": (BallEndMill, {"D": "D", "L": "length"}),
    "flat": (FlatEndMill, {"D": "D", "L": "length"}),
    "cyl": (FlatEndMill, {"D": "D", "L": "length"}),  # a cylindrical (flank) cutter is a flat end mill
    "bull": (BullNoseEndMill, {"D": "D", "r": "r", "L": "length"}),
    "torus": (BullNoseEndMill, {"D": "D", "r": "r", "L": "length"}),
    "cone": (ConicalCutter, {"D": "D", "angle": "angle", "L": "length"}),
    "drum": (DrumCutter, {"D": "D", "Rp": "R_p", "L": "length"}),
    "barrel": (DrumCutter, {"D": "D", "Rp": "R_p", "L": "length"}),
    "apt": (APTCutter, {"D": "D", "r": "r", "e": "e", "f": "f", "alpha": "alpha", "beta": "beta", "h": "h"}),
}


def parse_cutter(text: str) -> Cutter:
    """Cutter from its CLI string, e.g. ``ball:D=10``, ``bull:D=20,r=4``, ``cone:D=10,angle=6``.

    Parameters
    ----------
    text : str
        ``kind:K=V,...`` with kind ball, flat, cyl, bull (torus), cone, drum, barrel or apt;
        lengths in mm, angles in degrees (``L`` the cutting length).

    Returns
    -------
    Cutter

    Raises
    ------
    InputError
        Unknown kind or parameter, missing or bad value (one-line message).

    Examples
    --------
    >>> parse_cutter("bull:D=20,r=4").R_t
    6.0
    >>> parse_cutter("cone:D=10,angle=6").spec()
    'cone:D=10,angle=6'
    """
    if not isinstance(text, str):
        raise InputError(f"a cutter string like ball:D=10 is text, got {type(text).__name__}")
    m = re.fullmatch(r"\s*([A-Za-z]+)\s*:(.*)", text or "")
    if not m:
        raise InputError(f"cutter string {text!r} is not of the form kind:K=V,... (e.g. ball:D=10)")
    kind, rest = m.group(1).lower(), m.group(2)
    if kind not in _KINDS:
        raise InputError(f"unknown cutter kind {kind!r}; known: {', '.join(sorted(_KINDS))}")
    cls, names = _KINDS[kind]
    kwargs = {}
    seen: set[str] = set()
    for part in filter(None, (p.strip() for p in rest.split(","))):
        if "=" not in part:
            raise InputError(f"cutter parameter {part!r} is not K=V")
        k, v = (s.strip() for s in part.split("=", 1))
        if k in seen:
            raise InputError(f"cutter parameter {k} is given twice in {text!r}")
        seen.add(k)
        if k not in names:
            raise InputError(f"unknown parameter {k!r} for {kind} cutter; expected {', '.join(names)}")
        kwargs[names[k]] = _num(k, v)
    if kind == "barrel":
        kwargs["concave"] = True
    try:
        return cls(**kwargs)
    except TypeError:
        missing = [k for k, v in names.items() if v not in kwargs and v != "length"]
        raise InputError(f"{kind} cutter needs parameters: {', '.join(missing)}") from None


__all__ = ["parse_cutter", "cutter_from_apt", "apt_mismatch"]
