"""Flank (side) milling of ruled surfaces with a cylindrical cutter (numpy/scipy only)."""

from .api import FlankResult, SettingKind, compare_settings, flank, mean_normal
from .path import FlankPath, envelope_deviation, envelope_surface, flank_path, radius_range
from .ruled import RuledSurface
from .settings import (
    SETTINGS,
    Interference,
    NoAdmissibleSetting,
    Setting,
    interference,
    minimax_setting,
    optimum_setting,
    rule_frame,
    standard_setting,
    tool_setting,
)
from .smooth import axis_turn_rates, compare_with_rule_optima, smooth_minimax_path

__all__ = [
    "RuledSurface",
    "Setting",
    "Interference",
    "NoAdmissibleSetting",
    "interference",
    "standard_setting",
    "optimum_setting",
    "minimax_setting",
    "tool_setting",
    "rule_frame",
    "SETTINGS",
    "compare_settings",
    "flank",
    "FlankResult",
    "SettingKind",
    "FlankPath",
    "flank_path",
    "envelope_surface",
    "envelope_deviation",
    "radius_range",
    "mean_normal",
    "smooth_minimax_path",
    "compare_with_rule_optima",
    "axis_turn_rates",
]
