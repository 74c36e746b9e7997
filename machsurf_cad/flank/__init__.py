"""Flank (side) milling of ruled surfaces with a cylindrical cutter (numpy/scipy only)."""

from .ruled import EXAMPLES, RuledSurface
from .settings import (SETTINGS, Interference, NoAdmissibleSetting, Setting, interference, minimax_setting,
                       optimum_setting, rule_frame, standard_setting, tool_setting)

__all__ = ["RuledSurface", "EXAMPLES", "Setting", "Interference", "NoAdmissibleSetting", "interference",
           "standard_setting", "optimum_setting", "minimax_setting", "tool_setting", "rule_frame", "SETTINGS"]
