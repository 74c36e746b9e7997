"""Links between the clear stretches of a tool path that never cross the part.

Each gap between two runs of cutting positions gets the first of these links the tool-body check finds
clear (all candidates of all gaps are checked in one :func:`~machsurf_cad.verify` call):

1. **direct**: retract ``clearance`` along the axis, straight across to ``clearance`` above the next run
   along its axis, approach - the short link that stays down on the part; then the same with a 1 mm lift
   (in a channel a full retract would leave); not tried where the axis turns by more than 120 deg;
2. **over the clearance surface**: out along the axis to the plane above the part (a fixed axis) or to the
   sphere or cylinder around it (the axis turning; :mod:`machsurf_cad.cam.clearance`), over it, and back in
   along the next run's axis.

A run that no clear link enters at its start is tried reversed, entered at its end (the same moves
backwards; reported in ``runs_reversed``); a run still left out is visited later, between two runs whose
links to and from it are clear (``runs_visited_later``). A gap no link clears is not bridged by a crossing
move: the run after it is left out and the gap reported (where it is), and the next run is tried from the
same end; a run whose way out to the clearance surface at the end of the path is not clear is left out
too. The path's first approach and last retract come from and go to the clearance surface, checked the
same way.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np

from .cam.clearance import beyond, exit_cylinder, exit_sphere, on_cylinder, over_cylinder, over_sphere
from .cam.toolpath import Move, ToolPath
from .errors import InputError
from .gougecheck import CLEAR, verify


def surface_for(faces, fixed_axis, clearance: float, kind: str = "auto", axis=None):
    """What links travel on: ``("plane", (height, axis))`` above the part along a fixed axis
    (:func:`~machsurf_cad.part_plane`), ``("sphere", (centre, radius))`` around it
    (:func:`~machsurf_cad.part_sphere`) or ``("cylinder", (point, axis, radius, half_length))``
    (:func:`~machsurf_cad.part_cylinder`, about ``axis``). ``fixed_axis`` is the tool axis of a 3-axis or
    3+2 path, None when it turns. ``auto``: the plane for a fixed axis, else a cylinder when ``axis`` is
    given or the part is at least twice as long as it is wide (a blade, a shaft), else the sphere."""
    from .machining.toolpath import part_cylinder, part_plane, part_sphere

    if kind not in ("auto", "plane", "sphere", "cylinder"):
        raise InputError(f"a clearance surface is auto, plane, sphere or cylinder, got {kind!r}")
    if kind == "plane" and fixed_axis is None:
        raise InputError("a clearance plane needs a fixed tool axis (3 axes, 3+2): use sphere or cylinder")
    if kind == "auto":
        kind = "plane" if fixed_axis is not None else "cylinder" if axis is not None or _elongated(faces) else "sphere"
    if kind == "plane":
        a = np.asarray(fixed_axis, float) / np.linalg.norm(fixed_axis)
        return "plane", (part_plane(faces, a, clearance), a)
    if kind == "cylinder":
        return "cylinder", part_cylinder(faces, axis, clearance)
    return "sphere", part_sphere(faces, clearance)


def _elongated(faces, ratio: float = 2.0) -> bool:
    """Whether the poles' bounding box is at least ``ratio`` times longer than it is wide."""
    from .machining.toolpath import part_poles

    e = np.sort(np.ptp(part_poles(faces), axis=0))
    return bool(e[2] >= ratio * e[1])


def _exits(q, a, surface) -> np.ndarray:
    """The way out from ``q`` along ``a`` to a sphere or cylinder: (k, 3), ending on it."""
    kind, geo = surface[:2]
    if kind == "cylinder":
        return exit_cylinder(q, a, geo)
    return exit_sphere(q, a, np.asarray(geo[0], float), geo[1])[None, :]


def _candidates(p0, a0, p1, a1, clearance: float, surface) -> list[tuple[np.ndarray, np.ndarray, list, str]]:
    """The links from position ``p0`` (axis ``a0``; None at the path's start) to ``p1`` (axis ``a1``; None at
    its end), in order of preference: (tips, axes, moves, kind) without ``p0``, with ``p1``; the direct link
    also with a 1 mm lift (a narrow channel that a full retract would leave). ``surface``: (kind, geometry,
    rotary limit)."""
    kind, geo = surface[:2]
    out = []
    up0 = None if p0 is None else p0 + clearance * a0
    up1 = None if p1 is None else p1 + clearance * a1
    if p0 is not None and p1 is not None and float(a0 @ a1) > -0.5:  # no direct link turning the axis over
        for lift in sorted({clearance, min(clearance, 1.0)}, reverse=True):
            q0, q1 = p0 + lift * a0, p1 + lift * a1
            out.append((np.array([q0, q1, p1]), np.array([a0, a1, a1]), [Move.RETRACT, Move.RAPID, Move.APPROACH],
                        "direct"))  # fmt: skip
    if kind == "plane":
        a = a0 if a0 is not None else a1
        pts = [q for q in (up0, up1) if q is not None]
        lifted = [q + max(geo[0] - float(q @ a), 0.0) * a for q in pts]
        tips = np.array([pts[0], lifted[0], *lifted[1:], *pts[1:]] if up0 is not None else [lifted[0], pts[0]])
        axes = np.tile(a, (len(tips), 1))
    elif up0 is None or up1 is None:  # the path's start or end: along the axis to the surface
        q, a = (up1, a1) if up0 is None else (up0, a0)
        ex = _exits(q, a, surface)
        tips = np.vstack([ex[::-1], q]) if up0 is None else np.vstack([q, ex])
        axes = np.tile(a, (len(tips), 1))
    else:
        over = over_cylinder if kind == "cylinder" else over_sphere
        tips, axes = over(up0, a0, up1, a1, geo, limit=surface[2])
        # the clearance points themselves: the retract and the approach are the clearance long, the legs
        # between them and the surface rapids (made feed moves where the tool comes near the part)
        if np.linalg.norm(tips[-1] - up1) > 1e-9:
            tips, axes = np.vstack([tips, up1]), np.vstack([axes, a1])
        if np.linalg.norm(tips[0] - up0) > 1e-9:
            tips, axes = np.vstack([up0, tips]), np.vstack([a0, axes])
    if p0 is not None:  # leave along the axis at the plunge feed, then rapid
        moves = [Move.RETRACT] + [Move.RAPID] * (len(tips) - 1)
    else:
        moves = [Move.RAPID] * len(tips)
    if p1 is not None:
        tips, axes, moves = np.vstack([tips, p1]), np.vstack([axes, a1]), moves + [Move.APPROACH]
    out.append((tips, axes, moves, "surface"))
    return out


def link_runs(runs, part, cutter, *, clearance: float = 5.0, gouge_tolerance: float = 0.01,
              link_clearance: float = 0.01, name: str = "toolpath", info=None, clearance_surface: str = "auto",
              clearance_axis=None, axis_limit=None) -> ToolPath:  # fmt: skip
    """Join ``runs`` (each ``(tips, axes)`` of consecutive cutting positions, optionally with their contact
    points and their indices in the planned path as third and fourth items) by links the tool-body check
    finds clear (module docstring). ``clearance_surface`` (``auto``, ``plane``, ``sphere`` or ``cylinder``,
    about ``clearance_axis``) is what links travel on (:func:`surface_for`); ``axis_limit`` =
    ``(machine_axis, max_axis_angle)`` is a rotary limit no link's axis passes
    (:func:`~machsurf_cad.cam.clearance.beyond`).

    Returns
    -------
    ToolPath
        ``extras["planned_index"]`` (given the indices; -1 on links); ``info`` adds ``links_direct``,
        ``links_over_surface``, ``runs_left_out``, ``gaps_not_linked`` (where: the two ends, mm),
        ``clearance_surface`` (``plane``, ``sphere`` or ``cylinder``), ``n_rapids_at_feed`` and
        ``rapid_distance_min_mm`` (:func:`rapids_kept_clear`: rapids keep the whole tool ``clearance``
        from the part, else are made feed moves).
    """
    runs = [r for r in runs if len(r[0]) >= 1]
    if not runs:
        raise InputError("no run of cutting positions to link")
    faces = list(part)
    runs = _liftable(runs, faces, cutter, gouge_tolerance, link_clearance)
    n = len(runs)
    axes = np.concatenate([np.asarray(r[1]) for r in runs])
    fixed = axes[0] if np.abs(axes - axes[0]).max() <= 1e-9 else None
    surface = (*surface_for(faces, fixed, clearance, clearance_surface, clearance_axis), axis_limit)
    ends = [(np.asarray(t[0], float), np.asarray(a[0], float), np.asarray(t[-1], float), np.asarray(a[-1], float))
            for t, a, *_ in runs]  # fmt: skip

    def entry(node):  # a run entered at its start (o = 0) or, reversed, at its end (o = 1)
        j, o = node
        return (None, None) if j >= n else (ends[j][:2] if o == 0 else ends[j][2:])

    def exit_(node):
        i, o = node
        return (None, None) if i < 0 else (ends[i][2:] if o == 0 else ends[i][:2])

    cand: dict[tuple, list] = {}
    ok: dict[tuple, bool] = {}

    def candidates(key):
        if key not in cand:
            (p0, a0), (p1, a1) = exit_(key[0]), entry(key[1])
            cand[key] = _candidates(p0, a0, p1, a1, clearance, surface)
        return cand[key]

    def check(keys, c):
        """Candidate ``c`` of the gaps ``keys`` (those that have one and are not known), checked together."""
        todo = {k: candidates(k)[c] for k in keys if c < len(candidates(k)) and (k, c) not in ok}
        if todo:
            starts = {k: exit_(k[0]) for k in todo}
            ok.update(_clear(todo, c, starts, faces, cutter, gouge_tolerance, link_clearance, surface))

    def check_all(keys):
        """The candidates of ``keys`` in order, all keys together per candidate, each until one is clear."""
        for c in range(max((len(candidates(k)) for k in keys), default=0)):
            check([k for k in keys if not any(ok.get((k, x), False) for x in range(c))], c)

    def known_clear(key):
        """The first candidate of ``key`` found clear so far, or None."""
        return next((c for c in range(len(candidates(key))) if ok.get((key, c), False)), None)

    def first_clear(key):
        check_all([key])
        return known_clear(key)

    # the direct links between neighbours in one check, then the links over the surface where they collide
    check_all([((i, 0), (i + 1, 0)) for i in range(-1, n)])

    def near_direct(cur, pending, k: int = 4):
        """The first clear direct link from ``cur`` to one of the ``k`` run ends not yet cut nearest its exit
        (no farther than 20 tool radii), all checked together; ``(node, candidate)`` or None."""
        p0 = exit_(cur)[0]
        nodes = [(j, o) for j in pending for o in (0, 1)]
        d = np.array([np.linalg.norm(entry(nd)[0] - p0) for nd in nodes])
        near = [nodes[i] for i in np.argsort(d, kind="stable")[:k] if d[i] <= 20.0 * cutter.radius]
        keys = [(cur, nd) for nd in near]
        for c in (0, 1):
            check([key for key in keys if c < len(candidates(key)) and candidates(key)[c][3] == "direct"], c)
        for key in keys:
            for c, cd in enumerate(candidates(key)):
                if cd[3] == "direct" and ok.get((key, c), False):
                    return key[1], c
        return None

    chosen, left_out, not_linked = _walk(n, first_clear, exit_, entry, near_direct)
    inserted = _insert_left_out(chosen, left_out, ends, check_all, known_clear)
    inserted += _chains_at_end(chosen, left_out, n, check_all, known_clear, near_direct)
    info = dict(info or {}, runs_visited_later=inserted)
    tp = _assemble(runs, chosen, cand, cutter, name, info, surface, sorted(left_out), not_linked)
    return rapids_kept_clear(tp, faces, cutter, clearance, surface)


def _liftable(runs, faces, cutter, gouge_tolerance: float, link_clearance: float, lift: float = 1.0,
              backs: tuple = (1, 2, 4, 8, 16)) -> list:  # fmt: skip
    """``runs`` with each end moved in, where lifting the tool ``lift`` mm along its axis there enters the part
    (a stretch that ends against a blade, its axis leaning towards it), to the nearest of ``backs``
    positions in from which the lift is clear: every way out of a run starts with such a lift. All the
    lifts checked in one tool-body check; an end no lift clears is left as it is."""
    rows: list = []
    for i, r in enumerate(runs):
        t, a = np.asarray(r[0], float), np.asarray(r[1], float)
        for e in (0, 1):
            for b in (0, *backs):
                if b >= len(t) - 1:
                    break
                k = b if e == 0 else len(t) - 1 - b
                rows.append((i, e, b, t[k], a[k]))
    if not rows:
        return runs
    T = np.array([x for *_, p, a in rows for x in (p, p + lift * a)])
    A = np.array([x for *_, _p, a in rows for x in (a, a)])
    mv = np.tile([Move.RAPID, Move.RETRACT], len(rows))
    tp = ToolPath(T, A, mv, np.repeat(np.arange(len(rows)), 2), cutter=cutter)
    res = verify(faces, tp, cutter, gouge_tolerance=gouge_tolerance, clearance=link_clearance,
                 jumps=np.arange(2 * len(rows)) % 2 == 0)  # fmt: skip
    ok = np.asarray(res.status)[1::2] == CLEAR
    cut: dict[tuple, int] = {}
    for (i, e, b, *_), good in zip(rows, ok):  # the fewest positions in (rows go outwards in) whose lift is clear
        if good:
            cut.setdefault((i, e), b)
    out = []
    for i, r in enumerate(runs):
        b0, b1 = cut.get((i, 0), 0), cut.get((i, 1), 0)
        n = len(r[0])
        if b0 + b1 >= n - 1:  # nothing would be left: as it was
            b0 = b1 = 0
        out.append(tuple(None if x is None else x[b0 : n - b1] for x in r))
    return out


def _insert_left_out(chosen, left_out, ends, check_all, clear, near: int = 6, rounds: int = 3) -> list[int]:
    """Visit left-out runs later: a link ``a -> b`` of the path replaced by ``a -> L -> b`` (``L`` either way
    round) where both links are clear, trying the ``near`` links whose ends are nearest ``L``'s; every
    candidate of every try checked together, in ``rounds`` rounds (a run put in opens links for the next).
    Changes ``chosen`` and ``left_out``; returns the runs visited."""
    done: list[int] = []
    nan = np.full(3, np.nan)
    for _ in range(rounds):
        if not left_out:
            break
        src = np.array([nan if a[0] < 0 else ends[a[0]][2] if a[1] == 0 else ends[a[0]][0] for (a, _), _c in chosen])
        dst = np.array([nan if b[0] >= len(ends) else ends[b[0]][0] if b[1] == 0 else ends[b[0]][2]
                        for (_, b), _c in chosen])  # fmt: skip
        tries = {}
        for L in left_out:
            d = np.full(len(chosen), np.inf)
            for p in (ends[L][0], ends[L][2]):
                for q in (src, dst):
                    e = np.linalg.norm(q - p, axis=1)
                    d = np.fmin(d, np.where(np.isfinite(e), e, np.inf))
            tries[L] = [int(k) for k in np.argsort(d, kind="stable")[:near] if np.isfinite(d[k])]
        keys = list(dict.fromkeys(key for L, ks in tries.items() for k in ks for o in (0, 1)
                                  for key in ((chosen[k][0][0], (L, o)), ((L, o), chosen[k][0][1]))))  # fmt: skip
        check_all(keys)
        put: dict[int, tuple] = {}
        for L in list(left_out):
            for k in tries[L]:
                if k in put:
                    continue
                (a, b), _ = chosen[k]
                for o in (0, 1):
                    c1, c2 = clear((a, (L, o))), clear(((L, o), b))
                    if c1 is not None and c2 is not None:
                        put[k] = (((a, (L, o)), c1), (((L, o), b), c2))
                        left_out.remove(L)
                        done.append(int(L))
                        break
                if L in done:
                    break
        if not put:
            break
        chosen[:] = [x for k, link in enumerate(chosen) for x in (put[k] if k in put else (link,))]
    return done


def _chains_at_end(chosen, left_out, n, check_all, clear, near_direct) -> list[int]:
    """Runs still left out, strung into chains at the path's end: a chain enters a left-out run where a link
    from the clearance surface is clear, goes on by direct links to the nearest left-out runs (the stretches
    of one channel, none of which the surface reaches at both ends), backs off a run that leads nowhere, and
    ends where the way out to the surface is clear; the chains follow the path's last run over the
    surface. Changes ``chosen`` and ``left_out``; returns the runs put in."""
    if not left_out or not chosen:
        return []
    nodes = [(L, o) for L in left_out for o in (0, 1)]
    check_all([((-1, 0), nd) for nd in nodes] + [(nd, (n, 0)) for nd in nodes])
    avail = set(left_out)
    chains: list[list] = []
    for L in sorted(left_out):
        starts = [(L, o) for o in (0, 1) if L in avail and clear(((-1, 0), (L, o))) is not None]
        if not starts:
            continue
        chain: list = [(starts[0], None)]
        skip: set[int] = set()
        avail.discard(L)
        while chain:
            cur = chain[-1][0]
            got = near_direct(cur, sorted(avail - skip))
            if got is not None:
                chain.append(got)
                avail.discard(got[0][0])
                continue
            if clear((cur, (n, 0))) is not None:
                break
            skip.add(cur[0])  # leads nowhere: backed off, free for another chain
            avail.add(cur[0])
            chain.pop()
        if chain:
            chains.append(chain)
    last, c_end = chosen.pop()
    cur = last[0]
    put: list[int] = []
    for chain in chains:
        key = (cur, chain[0][0])
        check_all([key])
        c0 = clear(key)
        if c0 is None:
            continue
        chosen.append((key, c0))
        for (a, _), (b, cb) in zip(chain[:-1], chain[1:]):
            chosen.append(((a, b), cb))
        cur = chain[-1][0]
        put += [int(nd[0]) for nd, _ in chain]
    chosen.append(((cur, (n, 0)), clear((cur, (n, 0))) if put else c_end))
    for L in put:
        left_out.remove(L)
    return put


def _walk(n, first_clear, exit_, entry, near_direct):
    """Runs in order, each entered at its start or else, reversed, at its end, by the first clear link from
    the last one kept. Where the next run cannot be reached, a direct link to one of the nearest runs not
    yet cut is tried (:func:`link_runs`' ``near_direct``: in a channel, the stretch beside it); where none is
    clear either, the last run kept is a dead end if no clear link leaves it for the clearance surface (it
    is left out, its way in dropped, and the walk goes on from the run before); else the next run is left
    out. A run no clear link leaves at the path's end is left out too (and its way in dropped)."""
    chosen: list[tuple[tuple, int]] = []
    left_out: list[int] = []
    not_linked: list[dict] = []
    pending = list(range(n))
    cur = (-1, 0)

    def drop_cur(to):
        nonlocal cur
        p0 = exit_(cur)[0]
        not_linked.append({"from_mm": p0.tolist(), "to_mm": to})
        left_out.append(cur[0])
        chosen.pop()
        cur = chosen[-1][0][1] if chosen else (-1, 0)

    while True:
        if not pending:
            if cur[0] < 0:
                raise InputError("no run of the path can be reached and left without crossing the part")
            c = first_clear((cur, (n, 0)))
            if c is not None:
                chosen.append(((cur, (n, 0)), c))
                break
            drop_cur(None)  # no clear way out of the last run to the end
            continue
        j = pending[0]
        got = next(((node, c) for node in [(j, 0), (j, 1)] for c in [first_clear((cur, node))] if c is not None), None)
        if got is None and cur[0] >= 0:
            got = near_direct(cur, pending)
        if got is not None:
            chosen.append(((cur, got[0]), got[1]))
            pending.remove(got[0][0])
            cur = got[0]
            continue
        p1 = entry((j, 0))[0]
        if cur[0] >= 0 and first_clear((cur, (n, 0))) is None:
            drop_cur(p1.tolist())  # a dead end: nothing reached from it, not even the clearance surface
            continue
        p0 = exit_(cur)[0]
        not_linked.append({"from_mm": None if p0 is None else p0.tolist(), "to_mm": p1.tolist()})
        left_out.append(j)  # no clear way into run j: it is left out
        pending.remove(j)
    return chosen, left_out, not_linked


def _on_surface(tips: np.ndarray, surface) -> np.ndarray:
    """Which link positions lie on the clearance surface (a move between two of them cannot meet the part:
    the whole tool is above the plane, or outside the sphere pointing out of it)."""
    kind, geo = surface[:2]
    if kind == "plane":
        return tips @ geo[1] >= geo[0] - 1e-9
    if kind == "cylinder":
        return on_cylinder(tips, geo)
    return np.linalg.norm(tips - geo[0], axis=1) >= geo[1] - 1e-9


def _clear(todo, c, starts, faces, cutter, gouge_tolerance, link_clearance, surface) -> dict:
    """Whether candidate ``c`` of each gap in ``todo`` (gap -> its candidate) is clear: all in one tool-body
    check, each from its own start, moves on the clearance surface left out. Placements every 2 mm keep
    ``link_clearance`` plus what a motion of 2 mm can hide (``2^2 / (8 R)``). A candidate turning the axis
    past the rotary limit is not clear."""
    T: list = []
    over_limit: set[int] = set()
    A: list = []
    M: list = []
    P: list = []
    first: list = []
    keys: list[tuple] = []
    for key, (tips, axes, moves, _) in todo.items():
        start = starts[key] if starts[key][0] is not None else (tips[0], axes[0])
        X, Y = np.vstack([start[0], tips]), np.vstack([start[1], axes])
        mv = np.concatenate([[Move.RAPID], np.asarray(moves, np.int8)])
        if beyond(axes, surface[2]).any():
            over_limit.add(len(keys))
        on = _on_surface(X, surface)
        check = ~(on[:-1] & on[1:])  # move k: X[k] -> X[k + 1]
        for seg in np.split(np.arange(check.size), np.nonzero(np.diff(check.astype(int)))[0] + 1):
            if not check[seg[0]]:
                continue
            rows = np.arange(seg[0], seg[-1] + 2)
            T.append(X[rows])
            A.append(Y[rows])
            M.append(mv[rows])
            P.append(np.full(rows.size, len(keys)))
            first.append(np.r_[True, np.zeros(rows.size - 1, bool)])
        keys.append((key, c))
    tp = ToolPath(np.vstack(T), np.vstack(A), np.concatenate(M), np.concatenate(P), cutter=cutter)
    step = 2.0
    hidden = step**2 / (8.0 * max(cutter.radius, 1e-3))
    jumps = np.concatenate(first)  # each segment on its own: no motion from the one before
    res = verify(faces, tp, cutter, gouge_tolerance=gouge_tolerance, clearance=link_clearance + hidden, step=step,
                 jumps=jumps)  # fmt: skip
    bad = (np.asarray(res.status) != CLEAR) & ~jumps
    bad_keys = set(np.unique(tp.pass_index[bad]).tolist()) | over_limit
    return {key: k not in bad_keys for k, key in enumerate(keys)}


def _assemble(runs, chosen, cand, cutter, name, info, surface, left_out, not_linked) -> ToolPath:
    T, A, M, P, C, X = [], [], [], [], [], []
    n_direct = n_over = 0
    has_cc = all(len(r) > 2 and r[2] is not None for r in runs)
    has_idx = all(len(r) > 3 and r[3] is not None for r in runs)
    reversed_runs = []
    for key, c in chosen:  # in the path's order
        (i, _), (j, oj) = key
        tips, axes, moves, kind = cand[key][c]
        if 0 <= i and j < len(runs):
            direct = kind == "direct"
            n_direct += int(direct)
            n_over += int(not direct)
        T.append(tips)
        A.append(axes)
        M.append(np.asarray(moves, np.int8))
        P.append(np.full(len(tips), max(i, 0) if j >= len(runs) else j))
        C.append(np.full((len(tips), 3), np.nan))
        X.append(np.full(len(tips), -1))
        if j >= len(runs):
            continue
        order = slice(None, None, -1 if oj else 1)  # the run itself, its first position the link's approach end
        if oj:
            reversed_runs.append(int(j))
        t, a = np.asarray(runs[j][0], float)[order], np.asarray(runs[j][1], float)[order]
        if has_idx:
            idx = np.asarray(runs[j][3], int)[order]
            X[-1][-1] = idx[0]
            X.append(idx[1:])
        T.append(t[1:])
        A.append(a[1:])
        M.append(np.full(len(t) - 1, Move.CUT, np.int8))
        P.append(np.full(len(t) - 1, j))
        if has_cc:
            cc = np.asarray(runs[j][2], float)[order]
            C[-1][-1] = cc[0]
            C.append(cc[1:])
        else:
            C.append(np.full((len(t) - 1, 3), np.nan))
    n_cut = int(sum(len(runs[j][0]) for ((_, (j, _o)), _c) in chosen if j < len(runs)))
    info = dict(info or {}, n_cut_positions=n_cut, links_direct=int(n_direct), links_over_surface=int(n_over),
                runs_left_out=[int(x) for x in left_out], runs_reversed=reversed_runs, gaps_not_linked=not_linked,
                clearance_surface=surface[0])  # fmt: skip
    return ToolPath(np.vstack(T), np.vstack(A), np.concatenate(M), np.concatenate(P),
                    np.vstack(C) if has_cc else None, None, cutter, name,
                    {"planned_index": np.concatenate(X)} if has_idx else {}, info)  # fmt: skip


def rapids_kept_clear(toolpath: ToolPath, part, cutter, clearance: float, surface, *, step: float = 1.0) -> ToolPath:
    """``toolpath`` with each rapid move along which the whole tool (cutting part, shank and holder) comes
    closer than ``clearance`` mm to the part made a feed move that does not cut (:attr:`Move.RETRACT`, at
    the plunge feed). Rapid, approach and retract distances are so
    measured from the whole tool, holder included, not from the tip. Rapids between two positions on the
    clearance ``surface`` (:func:`surface_for`) keep it by construction and are not measured; the others
    are, by one tool-body check with placements ``step`` mm apart (between two the tool can come closer by
    ``step^2 / (8 R)``). Along a fixed axis the rapids and the long retracts and approaches of the links
    (the tool straight up from a pass's end, or down onto the next) are measured in ``step`` mm pieces and
    split: at the plunge feed only where the whole tool is within ``clearance`` of the part, rapid
    elsewhere (:func:`_split`).
    ``info`` adds ``n_rapids_at_feed``, ``rapid_distance_min_mm`` (the least distance measured over the
    rapids left; None when every rapid is on the surface) and ``n_links_split``."""
    mv = np.asarray(toolpath.move)
    X = toolpath.tip
    on = _on_surface(X, surface)
    k = np.flatnonzero((mv == Move.RAPID) & ~(on & np.roll(on, 1)))
    k = k[k > 0]
    a = toolpath.axis
    fixed = a.shape[0] > 0 and np.abs(a - a[0]).max() <= 1e-12
    if fixed:  # long straight retracts and approaches of a link (not a pass's own moves)
        ln = np.r_[0.0, np.linalg.norm(np.diff(X, axis=0), axis=1)]
        prev = np.r_[Move.CUT, mv[:-1]]
        link = (mv == Move.RETRACT) | ((mv == Move.APPROACH) & ((prev == Move.RAPID) | (prev == Move.RETRACT)))
        k = np.union1d(k, np.flatnonzero(link & (ln > 2.0 * clearance + step)))
    info = dict(toolpath.info, n_rapids_at_feed=0, rapid_distance_min_mm=None, n_links_split=0)
    if not k.size:
        return replace(toolpath, info=info)
    # a turning axis's rapids stay whole (the written path keeps the checked path's positions)
    pieces = [max(1, math.ceil(np.linalg.norm(X[i] - X[i - 1]) / step)) if fixed else 1 for i in k]
    pts = [X[i - 1] + np.linspace(0.0, 1.0, n + 1)[:, None] * (X[i] - X[i - 1]) for i, n in zip(k, pieces)]
    starts = np.cumsum([0] + [p.shape[0] for p in pts])[:-1]
    P = np.concatenate(pts)
    A = np.repeat(np.concatenate([toolpath.axis[i][None] for i in k]), [p.shape[0] for p in pts], axis=0)
    jumps = np.zeros(P.shape[0], bool)
    jumps[starts] = True
    moves = ToolPath(P, A, np.full(P.shape[0], Move.RAPID), np.repeat(np.arange(k.size), [p.shape[0] for p in pts]),
                     cutter=cutter)  # fmt: skip
    with warnings.catch_warnings():  # rapids far from the part are the point, not a wrong part
        warnings.simplefilter("ignore")
        res = verify(part, moves, cutter, clearance=clearance, step=step, jumps=jumps)
    d = np.minimum(res.cut_distance, res.holder_distance)  # at each piece's end (a piece is one placement)
    out, n_slow, n_split, left = _split(toolpath, k, pts, starts, d, clearance * (1.0 - 1e-9))
    info.update(n_rapids_at_feed=n_slow, n_links_split=n_split)
    if left.size and np.isfinite(left.min()):  # nothing of the part within the measured reach: None
        info["rapid_distance_min_mm"] = float(left.min())
    return replace(out, info=info)


def _split(tp: ToolPath, k, pts, starts, d, clearance: float):
    """``tp`` with each move ``k[j]`` (its points ``pts[j]``, their distances to the part from ``starts[j]``
    in ``d``) cut where its pieces change between near the part (either end closer than ``clearance``: a
    feed move that does not cut, :attr:`Move.RETRACT`; an approach's last stretch stays
    :attr:`Move.APPROACH`) and clear (a rapid). Returns the path, the rapids made feed moves (whole or in
    part), the moves split and the distances of the rapid pieces left."""
    mv = np.asarray(tp.move).copy()
    at, tips, kinds_in, left = [], [], [], []
    n_slow = n_split = 0
    for j, i in enumerate(k):
        m = pts[j].shape[0] - 1
        dist = d[starts[j] : starts[j] + 1 + m]  # the move's start, then each piece's end
        slow = (dist[1:] < clearance) | (dist[:-1] < clearance)
        left.append(np.minimum(dist[1:], dist[:-1])[~slow])
        ends = np.r_[np.flatnonzero(slow[1:] != slow[:-1]), m - 1]  # last piece of each run
        kinds = np.where(slow[ends], Move.RETRACT, Move.RAPID)
        if mv[i] == Move.APPROACH:
            kinds[-1] = Move.APPROACH  # onto the pass (near the part by construction, whatever was measured)
        elif mv[i] == Move.RETRACT and slow.all():
            kinds[:] = Move.RETRACT
        n_slow += int(mv[i] == Move.RAPID and slow.any())
        n_split += int(ends.size > 1)
        at.append(np.full(ends.size - 1, i))  # the runs' ends before the move's own end, inserted before it
        tips.append(pts[j][ends[:-1] + 1])
        kinds_in.append(kinds[:-1])
        mv[i] = kinds[-1]
    a = np.concatenate(at).astype(np.int64)
    # an inserted position is a link's: the pass and axis of the move's end, no contact, the default feed
    out = ToolPath(
        np.insert(tp.tip, a, np.concatenate(tips), axis=0),
        np.insert(tp.axis, a, tp.axis[a], axis=0),
        np.insert(mv, a, np.concatenate(kinds_in).astype(mv.dtype)),
        np.insert(tp.pass_index, a, tp.pass_index[a]),
        None if tp.cc is None else np.insert(tp.cc, a, np.nan, axis=0),
        None if tp.feed is None else np.insert(tp.feed, a, np.nan),
        tp.cutter,
        tp.name,
        {key: np.insert(val, a, -1 if np.issubdtype(val.dtype, np.integer) else np.nan, axis=0)
         for key, val in tp.extras.items()},
        tp.info,
    )  # fmt: skip
    return out, n_slow, n_split, np.concatenate(left) if left else np.empty(0)


__all__ = ["link_runs", "rapids_kept_clear", "surface_for"]
