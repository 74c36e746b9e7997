"""The one writer (CSV, APT CLDATA, JSON) and reader (APT, CSV) of tool paths (mm, mm/min).

APT CLDATA as posts need it: ``PARTNO``, ``UNITS/MM``, ``CUTTER/d,r,e,f,alpha,beta,h`` (the same
7-parameter convention for every tool: :meth:`~machsurf_cad.cutters.Cutter.apt_parameters`),
``LOADTL/n``, ``SPINDL/RPM,s,CLW``, ``FEDRAT/f,MMPM`` (cutting and plunge feeds), ``RAPID``,
``MULTAX/ON`` whenever an axis is not +Z (3+2 included: the axis is never dropped),
``GOTO/x,y,z,i,j,k`` with unit axes (``GOTO/x,y,z`` only when every axis is +Z), approach and
retract along the tool axis from the shank side (they are in the :class:`ToolPath`), ``FINI``.

The reader takes our files and common CLDATA from other systems: ``GOTO`` with 3 or 6 values,
``FROM``, ``MULTAX``, ``CUTTER``, ``FEDRAT``, ``RAPID``, continuation lines ending in ``$``,
``$$`` comments; other statements are skipped with one warning naming them.
"""

from __future__ import annotations

import csv
import json
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..results import json_default
from .toolpath import Move, ToolPath


@dataclass(frozen=True)
class PostOptions:
    """What a post-processor needs besides the positions.

    Parameters
    ----------
    feed_mm_min : float
        Cutting feed, mm/min.
    plunge_mm_min : float
        Approach and retract feed along the axis, mm/min.
    spindle_rpm : float
        Spindle speed, rev/min (clockwise).
    tool_number : int
        Tool loaded by ``LOADTL``.
    partno : str
        ``PARTNO`` text.
    """

    feed_mm_min: float = 1000.0
    plunge_mm_min: float = 300.0
    spindle_rpm: float = 10000.0
    tool_number: int = 1
    partno: str = "MACHSURF"

    def __post_init__(self) -> None:
        for name in ("feed_mm_min", "plunge_mm_min", "spindle_rpm"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"{name} must be > 0, got {v!r}")
        if int(self.tool_number) < 1:
            raise InputError("tool_number must be >= 1")


# ----------------------------------------------------------------------------- writers
def write_csv(path, tp: ToolPath) -> Path:
    """Write the tool path as CSV, one row per position.

    Columns ``pass,index,move,tip_x,tip_y,tip_z,i,j,k,cc_x,cc_y,cc_z,feed_mm_min`` then the
    producer's extra columns (``name`` or ``name_0, name_1, ...``); empty cells for NaN. Lengths in mm.

    Parameters
    ----------
    path : str or Path
        File to write.
    tp : ToolPath
        The tool path.

    Returns
    -------
    Path
        The file written; read it back with :func:`read_csv`.
    """
    path = Path(path)
    extra_cols, extra_data = [], []
    for k, v in tp.extras.items():
        a = np.asarray(v).reshape(tp.n_positions, -1)
        extra_cols += [k] if a.shape[1] == 1 else [f"{k}_{j}" for j in range(a.shape[1])]
        extra_data.append(a)
    X = np.concatenate(extra_data, axis=1) if extra_data else np.zeros((tp.n_positions, 0))
    cc = tp.cc if tp.cc is not None else np.full((tp.n_positions, 3), np.nan)
    feed = tp.feed if tp.feed is not None else np.full(tp.n_positions, np.nan)
    counter: dict[int, int] = {}
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
                *extra_cols,
            ]
        )
        for n in range(tp.n_positions):
            p = int(tp.pass_index[n])
            j = counter.get(p, 0)
            counter[p] = j + 1
            w.writerow(
                [
                    p,
                    j,
                    Move(int(tp.move[n])).name.lower(),
                    *(f"{x:.6f}" for x in tp.tip[n]),
                    *(f"{x:.9f}" for x in tp.axis[n]),
                    *(_num(x, 6) for x in cc[n]),
                    _num(feed[n], 3),
                    *(_num(x, 10) for x in X[n]),
                ]
            )
    return path


def _num(x, digits: int) -> str:
    x = float(x)
    return "" if math.isnan(x) else f"{x:.{digits}f}" if digits <= 9 else f"{x:.{digits}g}"


def write_json(path, tp: ToolPath) -> Path:
    """Write the tool path as JSON: its ``report()`` plus per-position arrays (mm, NaN as null).

    Parameters
    ----------
    path : str or Path
        File to write.
    tp : ToolPath
        The tool path.

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    data = {
        "report": tp.report(),
        "tip_mm": tp.tip,
        "axis": tp.axis,
        "move": [Move(int(m)).name.lower() for m in tp.move],
        "pass": tp.pass_index,
        "cc_mm": None if tp.cc is None else _nan_to_none(tp.cc),
        "feed_mm_min": None if tp.feed is None else _nan_to_none(tp.feed),
        "extras": {k: np.asarray(v).tolist() for k, v in tp.extras.items()},
    }
    path.write_text(json.dumps(data, default=json_default) + "\n")
    return path


def _nan_to_none(a: np.ndarray) -> list:
    """Nested lists with NaN as ``None`` (JSON ``null``)."""
    return np.where(np.isnan(a), np.array(None, dtype=object), a.astype(object)).tolist()


def apt_lines(tp: ToolPath, options: PostOptions = PostOptions()) -> list[str]:
    """The APT CLDATA statements of ``tp`` (see the module docstring)."""
    if tp.cutter is None:
        raise InputError("APT output needs the tool path's cutter (CUTTER/ statement)")
    multax = tp.is_multiaxis
    from .. import __version__

    params = tp.cutter.apt_parameters()
    lines = [
        f"$$ machsurf_cad {__version__} tool path {tp.name}: {tp.n_passes} pass(es), {tp.n_positions} positions, "
        f"tool {tp.cutter.spec()}",
        f"PARTNO/{options.partno}",
        "UNITS/MM",
        "CUTTER/" + ",".join(f"{x:.4f}" for x in params),
        f"LOADTL/{int(options.tool_number)}",
        f"SPINDL/RPM,{options.spindle_rpm:.4f},CLW",
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
                else (options.feed_mm_min if m == Move.CUT else options.plunge_mm_min)
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


def write_apt(path, tp: ToolPath, options: PostOptions = PostOptions()) -> Path:
    """Write APT CLDATA (see the module docstring for the statements).

    Parameters
    ----------
    path : str or Path
        File to write.
    tp : ToolPath
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
    path.write_text("\n".join(apt_lines(tp, options)) + "\n")
    return path


# ----------------------------------------------------------------------------- readers
_NUM = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+)?$")


def _statements(text: str):
    """APT statements with continuation lines joined and ``$$`` comments removed."""
    buf = ""
    for raw in text.splitlines():
        line = raw.split("$$", 1)[0].rstrip()
        if not line.strip():
            continue
        if line.endswith("$"):
            buf += line[:-1]
            continue
        yield (buf + line).strip()
        buf = ""
    if buf.strip():
        yield buf.strip()


def _floats(args: list[str], what: str) -> list[float]:
    out = []
    for a in args:
        a = a.strip()
        if _NUM.match(a):
            out.append(float(a.replace("D", "E").replace("d", "e")))
    if not out:
        raise InputError(f"APT: {what} has no numbers")
    return out


def read_apt(path, *, name: str | None = None) -> ToolPath:
    """Read APT CLDATA into a :class:`ToolPath` (mm; ``UNITS/INCHES`` is converted).

    Moves after ``RAPID`` are rapids; in each run of feed moves between rapids, a first move
    whose feed differs from the next one is the approach and a last move whose feed differs
    from the previous one is the retract (our files write them at the plunge feed); the
    others are cuts. Passes are counted at each rapid that follows feed moves. Without
    ``MULTAX/ON`` (or with 3-value GOTOs) the axis is +Z. The ``CUTTER`` statement gives the
    cutter (:func:`~machsurf_cad.cutters.cutter_from_apt`).

    Parameters
    ----------
    path : str or Path
        APT CLDATA text file.
    name : str, optional
        Name of the tool path (default: the file's stem).

    Returns
    -------
    ToolPath
        Positions, axes, moves, passes, feeds (mm/min) and the cutter; ``info`` holds the raw
        ``CUTTER`` values and the statements skipped.

    Raises
    ------
    InputError
        Missing file, no GOTO, or a malformed statement.
    """
    from ..cutters import cutter_from_apt

    p = Path(path)
    if not p.is_file():
        raise InputError(f"APT file not found: {p}")
    try:
        text = p.read_text()
    except UnicodeDecodeError:
        raise InputError(f"{p} is not a text APT file") from None
    scale, multax, rapid_next = 1.0, False, False
    feed = math.nan
    cutter_params = None
    tips, axes, moves, feeds = [], [], [], []
    skipped: dict[str, int] = {}
    for st in _statements(text):
        word, _, rest = st.partition("/")
        word = word.strip().upper()
        args = [a for a in rest.split(",")] if rest else []
        if word == "GOTO" or word == "FROM":
            v = _floats(args, st)
            if len(v) not in (3, 6):
                raise InputError(f"APT: {st!r} needs 3 or 6 values")
            xyz = np.array(v[:3]) * scale
            ax = np.array(v[3:6]) if (len(v) == 6 and multax) else np.array([0.0, 0.0, 1.0])
            nrm = np.linalg.norm(ax)
            if nrm == 0:
                raise InputError(f"APT: {st!r} has a zero tool axis")
            tips.append(xyz)
            axes.append(ax / nrm)
            moves.append(Move.RAPID if (rapid_next or word == "FROM") else Move.CUT)
            feeds.append(math.nan if moves[-1] == Move.RAPID else feed)
            rapid_next = False
        elif word == "RAPID":
            rapid_next = True
        elif word == "MULTAX":
            multax = "OFF" not in rest.upper()
        elif word == "FEDRAT":
            feed = _floats(args, st)[0] * scale
        elif word == "UNITS":
            scale = 25.4 if rest.strip().upper().startswith("INCH") else 1.0
        elif word == "CUTTER":  # d, r, e, f and h are lengths; alpha and beta (5th, 6th) angles
            cutter_params = [x * (scale if i not in (4, 5) else 1.0) for i, x in enumerate(_floats(args, st))]
        elif word in ("PARTNO", "FINI", "END", "LOADTL", "SPINDL", "COOLNT", "PPRINT", "TLAXIS", "MACHIN", "CLPRNT"):
            if word in ("FINI", "END"):
                break
        else:
            skipped[word] = skipped.get(word, 0) + 1
    if skipped:
        warnings.warn(
            f"{p.name}: skipped APT statements: " + ", ".join(f"{k} x{n}" for k, n in sorted(skipped.items())),
            stacklevel=2,
        )
    if not tips:
        raise InputError(f"{p} has no GOTO statement")
    mv = np.array(moves, dtype=np.int8)
    fd = np.array(feeds, float)
    pidx = np.zeros(mv.size, np.int64)
    k, cur, seen_feed = 0, 0, False
    n = mv.size
    while k < n:
        if mv[k] == Move.RAPID:
            if seen_feed:
                cur += 1
                seen_feed = False
            pidx[k] = cur
            k += 1
            continue
        j = k
        while j < n and mv[j] != Move.RAPID:
            j += 1
        run = np.arange(k, j)  # feed moves k..j-1
        pidx[run] = cur
        seen_feed = True
        if run.size >= 2 and k > 0 and fd[run[0]] != fd[run[1]]:
            mv[run[0]] = Move.APPROACH
        if run.size >= 3 and fd[run[-1]] != fd[run[-2]]:
            mv[run[-1]] = Move.RETRACT
        k = j
    cutter = cutter_from_apt(cutter_params) if cutter_params is not None else None
    info = {"source": str(p), "apt_cutter": cutter_params, "skipped_statements": skipped}
    return ToolPath(np.array(tips), np.array(axes), mv, pidx, None, fd, cutter, name or p.stem, {}, info)


def read_csv(path) -> ToolPath:
    """Read a tool path written by :func:`write_csv` (positions, axes, moves, passes, CC, feeds).

    Parameters
    ----------
    path : str or Path
        A CSV file with at least the columns ``pass,index,move,tip_x,tip_y,tip_z,i,j,k``.

    Returns
    -------
    ToolPath
        Without a cutter (CSV has none); axes renormalised.

    Raises
    ------
    InputError
        Missing file, other columns, malformed rows.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"CSV tool path not found: {p}")
    with open(p, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows or rows[0][:9] != ["pass", "index", "move", "tip_x", "tip_y", "tip_z", "i", "j", "k"]:
        raise InputError(f"{p} is not a machsurf_cad tool-path CSV (columns pass,index,move,tip_x,tip_y,tip_z,i,j,k)")
    head, body = rows[0], rows[1:]
    if not body:
        raise InputError(f"{p} has no positions")
    col = {h: i for i, h in enumerate(head)}

    def f(h):
        return np.array([float(r[col[h]]) if r[col[h]] != "" else np.nan for r in body])

    try:
        tip = np.stack([f("tip_x"), f("tip_y"), f("tip_z")], 1)
        axis = np.stack([f("i"), f("j"), f("k")], 1)
        move = np.array([Move[r[col["move"]].upper()] for r in body], np.int8)
        pidx = np.array([int(r[col["pass"]]) for r in body])
        cc = np.stack([f("cc_x"), f("cc_y"), f("cc_z")], 1) if "cc_x" in col else None
        feed = f("feed_mm_min") if "feed_mm_min" in col else None
    except (ValueError, KeyError, IndexError) as exc:
        raise InputError(f"{p}: malformed tool-path CSV ({exc})") from None
    axis = axis / np.linalg.norm(axis, axis=1, keepdims=True)  # 9 decimals: renormalise
    return ToolPath(tip, axis, move, pidx, cc, feed, None, p.stem, {}, {"source": str(p)})


__all__ = ["PostOptions", "write_csv", "write_apt", "write_json", "apt_lines", "read_apt", "read_csv"]
