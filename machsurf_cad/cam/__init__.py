"""Tool paths: the one :class:`ToolPath` type and its writer/reader (CSV, APT CLDATA, JSON)."""

from .cldata import PostOptions, apt_lines, write_apt, write_csv, write_json
from .readers import read_apt, read_csv
from .toolpath import Move, ToolPath

__all__ = [
    "Move",
    "ToolPath",
    "PostOptions",
    "write_csv",
    "write_apt",
    "write_json",
    "apt_lines",
    "read_apt",
    "read_csv",
]
