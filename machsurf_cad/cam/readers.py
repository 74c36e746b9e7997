"""The one reader of tool paths: APT CLDATA (ours and other CAM systems') and CSV (mm, unit axes).

APT, as a CAM system reads it:

- ``GOTO/x,y,z,i,j,k`` (6 values) is a 5-axis position whether or not ``MULTAX/ON`` was given (NX writes
  these without it); ``GOTO/x,y,z`` keeps the current tool axis: the last ``TLAXIS/i,j,k`` or the axis of
  the last 6-value GOTO (+Z at the start). ``FROM`` is a start position, ``GODLTA/dx,dy,dz`` a move
  relative to the last position.
- ``UNITS/INCHES`` scales every later length; ``MSYS/x0,y0,z0,xi,xj,xk,yi,yj,yk`` (CATIA) maps later
  positions and axes from that coordinate system to the part's.
- ``CUTTER/d,r,e,f,alpha,beta,h`` (also ``CUTTER/d`` and ``CUTTER/d,r``) and NX's ``TLDATA/MILL,d,r,h``
  give the cutter; an inconsistent set (the corner arc not tangent to the bottom and side lines that the
  diameter ``d`` defines: for ball, bull and flat ``d = 2(e + r)``, ``f = r``) is refused.
- Statements that change the geometry and are not honoured (``TRACUT``, ``COPY``, ``CIRCLE``/``MOVARC``,
  ``CYCLE``, ``CUTCOM``, ``ROTABL``, ``ROTHED``, ``INDEX``, ``ORIGIN``) are refused with their line
  number; known statements without geometry (feeds aside) are ignored; any other statement is skipped
  and listed (``ToolPath.info["skipped_statements"]``, and the reports of verify and simulate).

CSV: ours (:func:`~machsurf_cad.cam.cldata.write_csv`, whose ``tool`` column names the cutter) or a
spreadsheet's: columns in any order, named ``tip_x, tip_y, tip_z`` or ``x, y, z`` and
``i, j, k`` (or ``axis_x, axis_y, axis_z``; without them every axis is +Z, noted in ``info``),
``move`` and ``pass`` optional, UTF-8 with or without BOM or UTF-16, LF or CRLF, separated by ``,``
``;`` or tabs (with ``;``, a decimal comma is read as a point).
"""

from __future__ import annotations

import csv
import io
import math
import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from .toolpath import Move, ToolPath

_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d*,\d+([eE][+-]?\d+)?\s*$")
_NUM = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+)?$")

_GEOMETRY_REFUSED = {"TRACUT", "COPY", "CIRCLE", "MOVARC", "CYCLE", "CUTCOM", "ROTABL", "ROTHED", "INDEX", "ORIGIN"}
_NO_GEOMETRY = {
    "PARTNO", "LOADTL", "SPINDL", "COOLNT", "PPRINT", "MACHIN", "CLPRNT", "INSERT", "OPSKIP", "STOP", "OPSTOP",
    "PAUSE", "DELAY", "SELCTL", "TOOLNO", "TPRINT", "DISPLY", "AUTOPS", "SEQNO", "INTOL", "OUTTOL", "TOLER",
    "PAINT", "TOOL PATH", "OPERATION NAME", "END-OF-PATH", "CLEARP", "RETRCT", "HEAD", "MODE", "SET",
}  # fmt: skip
_SIZE_LIMIT = 2_000_000  # positions read before a tool-path file is refused as too large


def _statements(text: str):
    """(line number, statement) with continuation lines (ending in ``$``) joined and ``$$`` comments removed."""
    buf, first = "", 0
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.split("$$", 1)[0].rstrip()
        if not line.strip():
            continue
        if not buf:
            first = no
        if line.endswith("$"):
            buf += line[:-1]
            continue
        yield first, (buf + line).strip()
        buf = ""
    if buf.strip():
        yield first, buf.strip()


def _floats(args: list[str], where: str) -> list[float]:
    out = []
    for a in args:
        a = a.strip()
        if _NUM.match(a):
            out.append(float(a.replace("D", "E").replace("d", "e")))
    if not out:
        raise InputError(f"APT {where} has no numbers")
    if not all(math.isfinite(x) for x in out):
        raise InputError(f"APT {where} has a value that is not finite")
    return out


def _unit(v, where: str) -> np.ndarray:
    a = np.asarray(v, float)
    n = float(np.linalg.norm(a))
    if not n > 1e-12:
        raise InputError(f"APT {where} has a zero tool axis")
    return a / n


def _path(path) -> Path:
    if not isinstance(path, (str, Path)):
        raise InputError(f"a tool-path file is a path, got {type(path).__name__}")
    return Path(path)


def _read_text(p: Path) -> str:
    """The file's text: UTF-8 (with or without BOM) or UTF-16 (with BOM); anything else is refused."""
    data = p.read_bytes()
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        enc = "utf-16"
    elif data[:3] == b"\xef\xbb\xbf":
        enc = "utf-8-sig"
    else:
        enc = "utf-8"
    try:
        text = data.decode(enc)
    except UnicodeDecodeError:  # an older system's Latin-1 (accented comments): every byte decodes
        if b"\x00" in data:
            raise InputError(f"{p.name} is not a text file (neither UTF-8 nor UTF-16)") from None
        text = data.decode("latin-1")
    if "\x00" in text:
        raise InputError(f"{p.name} is not a text file (it holds NUL bytes)")
    return text


class _AptState:
    """What the statements read so far have set: units, axis, coordinate system, feed, cutter."""

    def __init__(self) -> None:
        self.scale = 1.0
        self.axis = np.array([0.0, 0.0, 1.0])
        self.frame: tuple[np.ndarray, np.ndarray] | None = None  # (origin, rotation) of MSYS
        self.feed = math.nan
        self.rapid_next = False
        self.cutter: list[float] | None = None
        self.cutter_where = ""
        self.tips: list[np.ndarray] = []
        self.axes: list[np.ndarray] = []
        self.moves: list[int] = []
        self.feeds: list[float] = []
        self.skipped: dict[str, int] = {}
        self.multiaxis_statements = 0

    def to_part(self, xyz: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.frame is None:
            return xyz, axis
        o, R = self.frame
        return o + R @ xyz, R @ axis

    def add(self, xyz: np.ndarray, axis: np.ndarray, rapid: bool) -> None:
        if len(self.tips) >= _SIZE_LIMIT:
            raise InputError(f"more than {_SIZE_LIMIT:,} positions: split the tool path into files")
        tip, ax = self.to_part(xyz, axis)
        self.tips.append(tip)
        self.axes.append(ax)
        self.moves.append(Move.RAPID if (rapid or self.rapid_next) else Move.CUT)
        self.feeds.append(math.nan if self.moves[-1] == Move.RAPID else self.feed)
        self.rapid_next = False


def _msys(v: list[float], where: str) -> tuple[np.ndarray, np.ndarray] | None:
    if len(v) != 9:
        raise InputError(f"APT {where}: MSYS needs 9 values (origin, x axis, y axis)")
    o, x, y = np.array(v[:3]), np.array(v[3:6]), np.array(v[6:9])
    if abs(np.linalg.norm(x) - 1) > 1e-6 or abs(np.linalg.norm(y) - 1) > 1e-6 or abs(x @ y) > 1e-6:
        raise InputError(f"APT {where}: MSYS axes are not orthonormal")
    R = np.column_stack([x, y, np.cross(x, y)])
    if np.allclose(o, 0) and np.allclose(R, np.eye(3)):
        return None
    return o, R


def _statement(state: _AptState, word: str, rest: str, where: str) -> bool:
    """Apply one statement; False at FINI/END."""
    args = rest.split(",") if rest else []
    if word in ("GOTO", "FROM"):
        v = _floats(args, where)
        if len(v) not in (3, 6):
            raise InputError(f"APT {where}: GOTO needs 3 or 6 values, got {len(v)}")
        if len(v) == 6:
            state.axis = _unit(v[3:6], where)
            state.multiaxis_statements += 1
        state.add(np.array(v[:3]) * state.scale, state.axis, word == "FROM")
    elif word == "GODLTA":
        v = _floats(args, where)
        if len(v) != 3 or not state.tips:
            raise InputError(f"APT {where}: GODLTA needs 3 values and a position before it")
        last = state.tips[-1] if state.frame is None else state.frame[1].T @ (state.tips[-1] - state.frame[0])
        state.add(last + np.array(v) * state.scale, state.axis, False)
    elif word == "TLAXIS":
        state.axis = _unit(_floats(args, where)[:3], where)
        state.multiaxis_statements += 1
    elif word == "RAPID":
        state.rapid_next = True
    elif word == "FEDRAT":
        state.feed = _floats(args, where)[0] * state.scale
    elif word == "UNITS":
        u = rest.strip().upper()
        if not (u.startswith("INCH") or u.startswith("MM") or u.startswith("MILLIM")):
            raise InputError(f"APT {where}: unknown units {rest.strip()!r} (MM or INCHES)")
        state.scale = 25.4 if u.startswith("INCH") else 1.0
    elif word == "MSYS":
        state.frame = _msys(_floats(args, where), where)
        if state.frame is not None:
            state.frame = (state.frame[0] * state.scale, state.frame[1])
    elif word == "CUTTER":  # d, r, e, f and h are lengths; alpha and beta (5th, 6th) angles
        state.cutter = [x * (state.scale if i not in (4, 5) else 1.0) for i, x in enumerate(_floats(args, where))]
        state.cutter_where = where
    elif word == "TLDATA":
        state.cutter, state.cutter_where = _tldata(rest, where, state.scale), where
    elif word in ("MULTAX",):
        pass  # a 6-value GOTO is 5-axis with or without it; a 3-value GOTO keeps the current axis
    elif word in _GEOMETRY_REFUSED:
        raise InputError(f"APT {where}: {word} changes the tool path's geometry and is not supported")
    elif word in ("FINI", "END"):
        return False
    elif word not in _NO_GEOMETRY:
        state.skipped[word] = state.skipped.get(word, 0) + 1
    return True


def _tldata(rest: str, where: str, scale: float) -> list[float]:
    """NX's ``TLDATA/MILL,d,r,h[,taper,tip]`` as APT cutter parameters."""
    parts = [a.strip().upper() for a in rest.split(",")]
    if not parts or parts[0] != "MILL":
        raise InputError(f"APT {where}: only TLDATA/MILL,d,r,h is supported")
    v = _floats(parts[1:], where)
    if len(v) < 3 or any(x != 0 for x in v[3:]):
        raise InputError(f"APT {where}: TLDATA/MILL needs d,r,h with no taper or tip angle")
    d, r, h = (x * scale for x in v[:3])
    return [d, r, d / 2 - r, r, 0.0, 0.0, h]


def _most_common(f: np.ndarray) -> float:
    """The most common of the feeds ``f`` (a tie to the faster; NaN for none)."""
    vals, counts = np.unique(f, return_counts=True)
    return float(vals[counts == counts.max()].max()) if vals.size else math.nan


def _passes(mv: np.ndarray, fd: np.ndarray) -> np.ndarray:
    """Pass index per position (a new pass at each rapid after feed moves); approach and retract marked."""
    pidx = np.zeros(mv.size, np.int64)
    k, cur, seen_feed = 0, 0, False
    n = mv.size
    cutting = _most_common(fd[(mv != Move.RAPID) & np.isfinite(fd)])  # the file's cutting feed
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
        if 0 < k and j < n and np.isfinite(cutting) and np.all(fd[run] != cutting):
            mv[run] = Move.RETRACT  # between two rapids and none at the cutting feed: a link's stretch near the part
            pidx[run] = cur
            k = j
            continue
        seen_feed = True
        if run.size >= 2 and k > 0 and fd[run[0]] != fd[run[1]]:
            mv[run[0]] = Move.APPROACH
        if run.size >= 3 and fd[run[-1]] != fd[run[-2]]:
            mv[run[-1]] = Move.RETRACT
        # moves at another feed than the cutting one are a link made at the plunge feed: the last of them,
        # onto the next pass, is its approach (a new pass after cutting), the others retracts
        new = np.zeros(run.size, np.int64)
        f = fd[run]
        if run.size >= 3 and np.unique(f).size >= 2 and np.isfinite(f).all():
            cut = f == _most_common(f[1:-1])  # the cutting feed: the interior's most common
            for i in np.flatnonzero(~cut):
                onto = i + 1 < run.size and cut[i + 1]
                mv[run[i]] = Move.APPROACH if onto else Move.RETRACT
                new[i] = int(onto and cut[:i].any())  # onto another pass after cutting: a new pass
        pidx[run] = cur + np.cumsum(new)
        cur += int(new.sum())
        k = j
    return pidx


def read_apt(path: str | Path, *, name: str | None = None) -> ToolPath:
    """Read APT CLDATA into a :class:`ToolPath` (mm; see the module docstring for the statements).

    Moves after ``RAPID`` are rapids; in each run of feed moves between rapids, a first move
    whose feed differs from the next one is the approach and a last move whose feed differs
    from the previous one is the retract (our files write them at the plunge feed); inside a
    run, moves at another feed than the cutting one (its interior's most common) are a link
    made at feed: the last, onto a pass, its approach, the others retracts; the rest are cuts.
    Passes are counted at each rapid that follows feed moves and at each such approach; feed moves between
    two rapids none of which is at the file's cutting feed (its most common) are a link's stretch near the
    part (retracts, no pass).

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
        Missing or binary file, no GOTO, a malformed statement, an inconsistent ``CUTTER``, or a
        statement that changes the geometry and is not supported.
    """
    from ..toolspec import cutter_from_apt

    p = _path(path)
    if not p.is_file():
        raise InputError(f"APT file not found: {p}")
    state = _AptState()
    for no, st in _statements(_read_text(p)):
        word, _, rest = st.partition("/") if "/" in st else (st.split()[0], "", "")
        if not _statement(state, word.strip().upper(), rest, f"line {no} ({st[:40]!r})"):
            break
    if state.skipped:
        warnings.warn(
            f"{p.name}: skipped APT statements: " + ", ".join(f"{k} x{n}" for k, n in sorted(state.skipped.items())),
            stacklevel=2,
        )
    if not state.tips:
        raise InputError(f"{p} has no GOTO statement")
    mv = np.array(state.moves, dtype=np.int8)
    fd = np.array(state.feeds, float)
    pidx = _passes(mv, fd)
    cutter = None
    if state.cutter is not None:
        try:
            cutter = cutter_from_apt(state.cutter)
        except InputError as exc:
            raise InputError(f"{p.name} {state.cutter_where}: {exc}") from None
    info = {"source": str(p), "apt_cutter": state.cutter, "skipped_statements": state.skipped}
    return ToolPath(np.array(state.tips), np.array(state.axes), mv, pidx, None, fd, cutter, name or p.stem, {}, info)


# ----------------------------------------------------------------------------- CSV
_CSV_NAMES = {
    "tip_x": ("tipx", "x", "tip_x", "clx", "posx"),
    "tip_y": ("tipy", "y", "tip_y", "cly", "posy"),
    "tip_z": ("tipz", "z", "tip_z", "clz", "posz"),
    "i": ("i", "axisi", "axisx", "toolaxisi", "toolaxisx"),
    "j": ("j", "axisj", "axisy", "toolaxisj", "toolaxisy"),
    "k": ("k", "axisk", "axisz", "toolaxisk", "toolaxisz"),
}


def _key(cell: str) -> str:
    return re.sub(r"[\s_\-/()\[\]]|mm$", "", cell.strip().lower())


def _csv_columns(head: list[str], p: Path) -> dict[str, int]:
    keys = [_key(h) for h in head]
    col: dict[str, int] = {}
    for name, aliases in _CSV_NAMES.items():
        hits = [i for i, k in enumerate(keys) if k in {_key(a) for a in aliases}]
        if len(hits) > 1:
            raise InputError(f"{p.name}: more than one column could be {name}: {', '.join(head[i] for i in hits)}")
        if hits:
            col[name] = hits[0]
    for extra in ("pass", "move", "cc_x", "cc_y", "cc_z", "feed_mm_min", "tool"):
        if _key(extra) in keys:
            col[extra] = keys.index(_key(extra))
    if not {"tip_x", "tip_y", "tip_z"} <= set(col):
        raise InputError(
            f"{p.name}: no tip columns (a header naming tip_x,tip_y,tip_z or x,y,z, and i,j,k for the axis); "
            f"found {', '.join(head[:12])}"
        )
    axis_cols = {"i", "j", "k"} & set(col)
    if axis_cols and axis_cols != {"i", "j", "k"}:
        raise InputError(f"{p.name}: the axis needs all three columns i,j,k; found only {', '.join(sorted(axis_cols))}")
    return col


def _csv_rows(text: str, p: Path) -> tuple[list[str], list[list[str]]]:
    """Header and rows (``#`` comment lines and blank lines skipped)."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{p.name} has no header and no positions")
    head_line = lines[0]
    sep = max((";", ",", "\t"), key=head_line.count)
    rows = list(csv.reader(io.StringIO("\n".join(lines)), delimiter=sep))
    if sep == ";":  # a spreadsheet with decimal commas: numbers only (a tool cell bull:D=16,r=3 keeps its comma)
        rows = [rows[0]] + [[c.replace(",", ".") if _DECIMAL_COMMA.match(c) else c for c in r] for r in rows[1:]]
    return rows[0], rows[1:]


def read_csv(path: str | Path) -> ToolPath:
    """Read a CSV tool path: ours (:func:`~machsurf_cad.cam.cldata.write_csv`) or a spreadsheet's.

    Parameters
    ----------
    path : str or Path
        A CSV file whose header names the tip (``tip_x,tip_y,tip_z`` or ``x,y,z``) and optionally the axis
        (``i,j,k``), ``move`` (``rapid|approach|cut|retract``), ``pass``, ``cc_x,cc_y,cc_z`` and
        ``feed_mm_min``, in any order (see the module docstring for encodings and separators).

    Returns
    -------
    ToolPath
        With the cutter named in the ``tool`` column (else ``None``); axes
        renormalised; ``info["assumed"]`` lists what the file did not say (axis +Z, every move a cut,
        one pass).

    Raises
    ------
    InputError
        Missing or binary file, no tip columns, malformed rows.
    """
    from ..toolspec import parse_cutter

    p = _path(path)
    if not p.is_file():
        raise InputError(f"CSV tool path not found: {p}")
    head, body = _csv_rows(_read_text(p), p)
    if not body:
        raise InputError(f"{p.name} has no positions")
    if len(body) > _SIZE_LIMIT:
        raise InputError(f"{p.name} has {len(body):,} positions, more than {_SIZE_LIMIT:,}: split it into files")
    col = _csv_columns(head, p)
    assumed = []

    def num(name: str) -> np.ndarray:
        c = col[name]
        return np.array([float(r[c]) if r[c].strip() != "" else np.nan for r in body])

    try:
        tip = np.stack([num("tip_x"), num("tip_y"), num("tip_z")], 1)
        if "i" in col:
            axis = np.stack([num("i"), num("j"), num("k")], 1)
        else:
            axis = np.tile([0.0, 0.0, 1.0], (len(body), 1))
            assumed.append("axis +Z (no i,j,k columns)")
        if "move" in col:
            move = np.array([Move[r[col["move"]].strip().upper()] for r in body], np.int8)
        else:
            move = np.full(len(body), Move.CUT, np.int8)
            assumed.append("every move a cut (no move column)")
        if "pass" in col:
            pidx = np.array([int(float(r[col["pass"]])) for r in body])
        else:
            pidx = np.zeros(len(body), np.int64)
            assumed.append("one pass (no pass column)")
        cc = np.stack([num("cc_x"), num("cc_y"), num("cc_z")], 1) if "cc_x" in col else None
        feed = num("feed_mm_min") if "feed_mm_min" in col else None
    except (ValueError, KeyError, IndexError) as exc:
        raise InputError(f"{p.name}: malformed tool-path CSV ({type(exc).__name__}: {exc})") from None
    if not np.isfinite(tip).all() or not np.isfinite(axis).all():
        bad = int(np.flatnonzero(~(np.isfinite(tip).all(1) & np.isfinite(axis).all(1)))[0])
        raise InputError(f"{p.name}: row {bad + 1} has an empty or non-finite tip or axis value")
    nrm = np.linalg.norm(axis, axis=1, keepdims=True)
    if (nrm < 1e-12).any():
        raise InputError(f"{p.name}: row {int(np.flatnonzero(nrm[:, 0] < 1e-12)[0]) + 1} has a zero tool axis")
    if "tool" in col:
        named = {r[col["tool"]].strip() for r in body if len(r) > col["tool"] and r[col["tool"]].strip()}
        if len(named) > 1:
            raise InputError(f"{p.name} names more than one tool ({', '.join(sorted(named)[:3])}): one tool per path")
        tool = named.pop() if named else None
    else:
        tool = None
    cutter = parse_cutter(tool) if tool else None
    info = {"source": str(p), "assumed": assumed}
    return ToolPath(tip, axis / nrm, move, pidx, cc, feed, cutter, p.stem, {}, info)


__all__ = ["read_apt", "read_csv"]
