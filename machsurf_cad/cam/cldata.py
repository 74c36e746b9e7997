"""The one writer (CSV, APT CLDATA, JSON) and reader (APT, CSV) of tool paths (mm, mm/min).

APT CLDATA as posts need it: ``PARTNO``, ``UNITS/MM``, ``CUTTER/d,r,e,f,alpha,beta,h`` (the same
7-parameter convention for every tool: :meth:`~machsurf_cad.cutters.Cutter.apt_parameters`),
``LOADTL/n``, ``SPINDL/RPM,s,CLW``, ``FEDRAT/f,MMPM`` (cutting and plunge feeds), ``RAPID``,
``MULTAX/ON`` whenever an axis is not +Z (3+2 included: the axis is never dropped),
``GOTO/x,y,z,i,j,k`` with unit axes (``GOTO/x,y,z`` only when every axis is +Z), approach and
retract along the tool axis from the shank side (they are in the :class:`ToolPath`), ``FINI``.

The reader (:mod:`machsurf_cad.cam.readers`) takes our files and CLDATA from other CAM systems.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..glossary import renamed, renamed_fields
from ..results import strict_json
from ..typing import PathLike
from .toolpath import Move, ToolPath


@renamed_fields(feed_mm_min="feed", plunge_mm_min="plunge_feed", spindle_rpm="spindle")
@dataclass(frozen=True)
class PostOptions:
    """What a post-processor needs besides the positions.

    Parameters
    ----------
    feed : float
        Cutting feed, mm/min.
    plunge_feed : float
        Approach and retract feed along the axis, mm/min.
    spindle : float
        Spindle speed, rev/min (clockwise).
    tool_number : int
        Tool loaded by ``LOADTL``.
    partno : str
        ``PARTNO`` text.
    """

    feed: float = 1000.0
    plunge_feed: float = 300.0
    spindle: float = 10000.0
    tool_number: int = 1
    partno: str = "MACHSURF"

    def __post_init__(self) -> None:
        for name in ("feed", "plunge_feed", "spindle"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"{name} must be > 0, got {v!r}")
        if int(self.tool_number) < 1:
            raise InputError("tool_number must be >= 1")


# ----------------------------------------------------------------------------- writers
@renamed(tp="toolpath")
def write_csv(path: PathLike, toolpath: ToolPath) -> Path:
    """Write the tool path as CSV, one row per position.

    Columns ``pass,index,move,tip_x,tip_y,tip_z,i,j,k,cc_x,cc_y,cc_z,feed_mm_min,tool`` (``tool``: the
    cutter's text, e.g. ``bull:D=16,r=3``, on every row, read back by
    :func:`~machsurf_cad.cam.readers.read_csv`) and the producer's extra columns (``name`` or
    ``name_0, name_1, ...``); empty cells for NaN. Lengths in mm. A plain CSV: any spreadsheet or
    ``csv.DictReader`` reads it.

    Parameters
    ----------
    path : str or Path
        File to write.
    toolpath : ToolPath
        The tool path.

    Returns
    -------
    Path
        The file written; read it back with :func:`read_csv`.
    """
    path = Path(path)
    _check_toolpath(toolpath)
    extra_cols, extra_data = [], []
    for k, v in toolpath.extras.items():
        a = np.asarray(v).reshape(toolpath.n_positions, -1)
        extra_cols += [k] if a.shape[1] == 1 else [f"{k}_{j}" for j in range(a.shape[1])]
        extra_data.append(a)
    X = np.concatenate(extra_data, axis=1) if extra_data else np.zeros((toolpath.n_positions, 0))
    cc = toolpath.cc if toolpath.cc is not None else np.full((toolpath.n_positions, 3), np.nan)
    feed = toolpath.feed if toolpath.feed is not None else np.full(toolpath.n_positions, np.nan)
    counter: dict[int, int] = {}
    tool = toolpath.cutter.spec() if toolpath.cutter is not None else ""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            [
                "pass",
                "index",
                "move",
                "tip_x",
                "tip_y",
                "tip_z",
                "i",
                "j",
                "k",
                "cc_x",
                "cc_y",
                "cc_z",
                "feed_mm_min",
                "tool",
                *extra_cols,
            ]
        )
        for n in range(toolpath.n_positions):
            p = int(toolpath.pass_index[n])
            j = counter.get(p, 0)
            counter[p] = j + 1
            w.writerow(
                [
                    p,
                    j,
                    Move(int(toolpath.move[n])).name.lower(),
                    *(f"{x:.6f}" for x in toolpath.tip[n]),
                    *(f"{x:.9f}" for x in toolpath.axis[n]),
                    *(_num(x, 6) for x in cc[n]),
                    _num(feed[n], 3),
                    tool,
                    *(_num(x, 10) for x in X[n]),
                ]
            )
    return path


def _num(x, digits: int) -> str:
    x = float(x)
    return "" if math.isnan(x) else f"{x:.{digits}f}" if digits <= 9 else f"{x:.{digits}g}"


@renamed(tp="toolpath")
def write_json(path: PathLike, toolpath: ToolPath) -> Path:
    """Write the tool path as JSON: its ``report()`` plus per-position arrays (mm, NaN as null).

    Parameters
    ----------
    path : str or Path
        File to write.
    toolpath : ToolPath
        The tool path.

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    _check_toolpath(toolpath)
    data = {
        "report": toolpath.report(),
        "tip_mm": toolpath.tip,
        "axis": toolpath.axis,
        "move": [Move(int(m)).name.lower() for m in toolpath.move],
        "pass": toolpath.pass_index,
        "cc_mm": None if toolpath.cc is None else _nan_to_none(toolpath.cc),
        "feed_mm_min": None if toolpath.feed is None else _nan_to_none(toolpath.feed),
        "extras": {k: np.asarray(v).tolist() for k, v in toolpath.extras.items()},
    }
    path.write_text(strict_json(data, indent=None) + "\n")
    return path


def _nan_to_none(a: np.ndarray) -> list:
    """Nested lists with NaN as ``None`` (JSON ``null``)."""
    return np.where(np.isnan(a), np.array(None, dtype=object), a.astype(object)).tolist()


def _check_toolpath(tp) -> None:
    if not isinstance(tp, ToolPath):
        raise InputError(f"a ToolPath is written, got {type(tp).__name__}")


def apt_lines(tp: ToolPath, options: PostOptions = PostOptions()) -> list[str]:
    """The APT CLDATA statements of ``tp`` (see the module docstring)."""
    _check_toolpath(tp)
    if not isinstance(options, PostOptions):
        raise InputError(f"options must be PostOptions, got {type(options).__name__}")
    if tp.cutter is None:
        raise InputError("APT output needs the tool path's cutter (CUTTER/ statement)")
    multax = tp.is_multiaxis
    from .._version import __version__

    params = tp.cutter.apt_parameters()
    lines = [
        f"$$ machsurf_cad {__version__} tool path {tp.name}: {tp.n_passes} pass(es), {tp.n_positions} positions, "
        f"tool {tp.cutter.spec()}",
        f"PARTNO/{options.partno}",
        "UNITS/MM",
        "CUTTER/" + ",".join(f"{x:.4f}" for x in params),
        f"LOADTL/{int(options.tool_number)}",
        f"SPINDL/RPM,{options.spindle:.4f},CLW",
        "MULTAX/ON" if multax else "MULTAX/OFF",
    ]
    cur_feed = None
    for n in range(tp.n_positions):
        m = int(tp.move[n])
        p, a = tp.tip[n], tp.axis[n]
        if m == Move.RAPID:
            lines.append("RAPID")
        else:
            f = (
                tp.feed[n]
                if tp.feed is not None and not math.isnan(tp.feed[n])
                else (options.feed if m == Move.CUT else options.plunge_feed)
            )
            if f != cur_feed:
                lines.append(f"FEDRAT/{f:.4f},MMPM")
                cur_feed = f
        if multax:
            lines.append("GOTO/{:.5f},{:.5f},{:.5f},{:.9f},{:.9f},{:.9f}".format(*p, *a))
        else:
            lines.append("GOTO/{:.5f},{:.5f},{:.5f}".format(*p))
    lines += ["SPINDL/OFF", "FINI"]
    return lines


@renamed(tp="toolpath")
def write_apt(path: PathLike, toolpath: ToolPath, options: PostOptions = PostOptions()) -> Path:
    """Write APT CLDATA (see the module docstring for the statements).

    Parameters
    ----------
    path : str or Path
        File to write.
    toolpath : ToolPath
        The tool path; it must carry its cutter (``CUTTER/``).
    options : PostOptions
        Feeds, spindle speed, tool number, part name.

    Returns
    -------
    Path
        The file written; read it back with :func:`read_apt`.

    Raises
    ------
    InputError
        The tool path has no cutter.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from machsurf_cad import BallEndMill, ToolPath, read_apt
    >>> tp = ToolPath.from_passes([np.array([[0.0, 0, 0], [10, 0, 0]])], [np.array([[0.0, 0.6, 0.8]] * 2)],
    ...                           cutter=BallEndMill(10))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     lines = write_apt(os.path.join(d, "p.apt"), tp).read_text().splitlines()
    ...     back = read_apt(os.path.join(d, "p.apt"))
    >>> lines[3:7]
    ['CUTTER/10.0000,5.0000,0.0000,5.0000,0.0000,0.0000,30.0000', 'LOADTL/1', 'SPINDL/RPM,10000.0000,CLW', 'MULTAX/ON']
    >>> bool(np.abs(back.tip - tp.tip).max() < 1e-5), back.cutter == tp.cutter
    (True, True)
    """
    path = Path(path)
    path.write_text("\n".join(apt_lines(toolpath, options)) + "\n")
    return path


__all__ = ["PostOptions", "write_csv", "write_apt", "write_json", "apt_lines"]
