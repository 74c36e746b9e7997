"""Flank (side) milling of ruled surfaces with a cylindrical cutter (numpy/scipy only)."""

from .ruled import RuledSurface
from .settings import (SETTINGS, Interference, NoAdmissibleSetting, Setting, interference, minimax_setting,
                       optimum_setting, rule_frame, standard_setting, tool_setting)

__all__ = ["RuledSurface", "Setting", "Interference", "NoAdmissibleSetting", "interference",
           "standard_setting", "optimum_setting", "minimax_setting", "tool_setting", "rule_frame", "SETTINGS"]


def compare_settings(surface, u_p: float, R: float, *, side: int = 1) -> dict:
    """Max gouge / undercut (mm) of every setting on one rule; ``None`` where a setting does not exist."""
    out = {}
    for kind in SETTINGS:
        try:
            e = interference(surface, tool_setting(surface, u_p, R, kind, side=side))
            out[kind] = {"max_gouge_mm": e.max_gouge, "max_undercut_mm": e.max_undercut, "max_abs_mm": e.max_abs}
        except NoAdmissibleSetting as exc:
            out[kind] = {"admissible": False, "reason": str(exc)}
    return out


def flank(surface, tool, *, rule: float = 0.5, setting: str = "optimum", side: int = 1, whole: bool = False,
          tolerance: float = 0.01):
    """Python form of ``machsurf flank``: setting and interference on the rule at ``rule`` (fraction
    of the u range), optionally the whole-surface path. ``tool`` is ``"cyl:D=.."`` or a radius in mm.

    Returns ``(setting, interference, path_or_None)``.
    """
    from ..cutters import FlatEndMill, parse_cutter
    from ..errors import InputError

    if isinstance(tool, (int, float)):
        R = float(tool)
    else:
        c = parse_cutter(tool) if isinstance(tool, str) else tool
        if not isinstance(c, FlatEndMill):
            raise InputError("flank milling needs a cylindrical cutter: cyl:D=..")
        R = c.D / 2
    if not 0.0 <= rule <= 1.0:
        raise InputError(f"rule {rule:g} is outside [0, 1] (fraction of the u range)")
    lo, hi = surface.u_range
    st = tool_setting(surface, lo + rule * (hi - lo), R, setting, side=side)
    e = interference(surface, st)
    path = None
    if whole:
        from .path import flank_path

        path = flank_path(surface, R, setting, side=side, tolerance=tolerance)
    return st, e, path


__all__ += ["compare_settings", "flank"]
