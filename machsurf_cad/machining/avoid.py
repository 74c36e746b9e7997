"""Tilt away: a 5-axis axis field that keeps the whole tool clear of the part (degrees, mm).

On a ``grid x grid`` lattice of the face (inside its trimming) the tool is placed by the exact maps of
Table 1 - its contact with the face and the surface normal kept, only the axis turning - with the nominal
lead and tilt, and each placement is checked alone against every check face (:func:`machsurf_cad.verify`:
the cutting part at most ``gouge_tolerance`` into a face, shank, holder and non-cutting parts clear).
Where it is not clear, the orientations within the limits are tried nearest first: lead from the nominal
up to ``max_lead`` (a ball end mill, which has no lead to keep, also down to ``-max_lead``, leaning back)
and tilt within ``+-max_tilt``, in ``step`` degree steps, ordered by the distance of their lean from the
nominal's (all the lattice's candidates of a round in one check). The chosen axes are smoothed so the
guiding and orientation surfaces rebuilt from the field stay fittable and free of folds: the change of
the lean at the tilted points tapers off around them at most ``max_turn`` degrees per mm (a Lipschitz
envelope), towards the nearest tilted point's side; the smoothed placements are checked again and counted
(those not clear are cut out of the path by its check). Lattice points no orientation clears keep the nominal
axis; the path's check cuts them out (``check_toolpath(on_gouge="trim")``).

The report gives the lattice points tilted, the largest change of the axis from the nominal (degrees),
its largest turn per mm between neighbouring lattice points, and the points no orientation clears.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .strategies import AxisField, LeadTilt, as_feed


def _candidates(lead: float, lowest: float, max_lead: float, max_tilt: float, step: float) -> list:
    """(lead, tilt) pairs within the limits about ``step`` degrees of lean apart (fewer tilts at small
    leads; one axis at lead 0), nearest the nominal ``(lead, 0)`` first (distance of the leans
    ``sin(lead) (cos tilt, sin tilt)``)."""
    top = min(max(max_lead, lead), 85.0)
    leads = np.unique(np.r_[np.arange(lead, top + 1e-9, step), np.arange(lead, lowest - 1e-9, -step)])

    def lean(lt, tl):
        r = np.sin(np.radians(lt))
        return np.array([r * np.cos(np.radians(tl)), r * np.sin(np.radians(tl))])

    out = set()
    for a in leads:
        k = int(np.ceil(max_tilt * np.sin(np.radians(abs(a))) / step)) if max_tilt > 0 else 0
        for b in np.linspace(-max_tilt, max_tilt, 2 * k + 1) if k > 0 else [0.0]:
            out.add((round(float(a), 9), round(float(b), 9)))
    w0 = lean(lead, 0.0)
    return sorted(out, key=lambda c: (round(float(np.linalg.norm(lean(*c) - w0)), 12), abs(c[1]), -c[1], -c[0]))


def _placements(face, cutter, feed, lead, tilt, us, vs):
    from .surfaces import MachiningMaps

    maps = MachiningMaps(face, cutter, 5, LeadTilt(lead, tilt, feed), cutter.D, False)
    return maps.tool_placements(us, vs)


def _clear(faces, cutter, tips, axes, gouge_tolerance) -> np.ndarray:
    """Whether each placement (rows of ``tips``/``axes``) is clear, each checked alone."""
    from ..cam.toolpath import Move, ToolPath
    from ..gougecheck import CLEAR, verify

    if tips.shape[0] == 0:
        return np.zeros(0, bool)
    tp = ToolPath(tips, axes, np.full(tips.shape[0], Move.CUT), np.arange(tips.shape[0]), cutter=cutter)
    res = verify(faces, tp, cutter, gouge_tolerance=gouge_tolerance, step=1e9, angle_step=180.0,
                 jumps=np.ones(tips.shape[0], bool))  # fmt: skip
    return np.asarray(res.status) == CLEAR


def _angle_deg(a, b) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.einsum("...i,...i->...", a, b), -1.0, 1.0)))


def clear_axis_field(
    face,
    cutter,
    strategy,
    check_faces,
    *,
    lead: float,
    tilt: float = 0.0,
    max_lead: float,
    max_tilt: float,
    gouge_tolerance: float = 0.01,
    grid: int = 31,
    step: float = 5.0,
    max_turn: float = 2.0,
    max_candidates: int = 60,
    max_axis_angle: float | None = None,
    machine_axis=(0.0, 0.0, 1.0),
) -> tuple[AxisField, dict]:
    """The tilt-away axis field of ``cutter`` on ``face`` (module docstring) and its report.

    Parameters
    ----------
    face : Face
        The machined face.
    cutter : Cutter
        Ball, bull-nose or flat end mill (with its shank and holder, checked too).
    strategy : str or feed
        The feed (``planes:x``, ``iso:u``, ...).
    check_faces : sequence of Face
        Every face the tool must clear (the part, the machined face included).
    lead, tilt : float
        The nominal orientation, degrees.
    max_lead, max_tilt : float
        The limits, degrees: lead from ``lead`` up to ``max_lead``, tilt within ``+-max_tilt``.
    gouge_tolerance : float
        Deepest the cutting part may go into a face, mm.
    grid : int
        Lattice points per parameter direction.
    step : float
        Angle step of the candidate orientations, degrees.
    max_candidates : int
        Orientations tried at most per lattice point, nearest the nominal first (the rest of the limits
        is not searched: reported as ``candidates`` against ``candidates_within_limits``).
    max_turn : float
        Largest change of the axis's angle from the normal per mm across the face (deg/mm), and at most
        half of ``1 / D`` radian per mm: the rebuilt orientation surface, ``D`` up the axis, folds at that.
    max_axis_angle : float, optional
        The machine's rotary limit, degrees: an orientation more than this from ``machine_axis`` is not
        clear (:func:`~machsurf_cad.cam.clearance.beyond`).
    """
    from ..cam.clearance import beyond

    limit = None
    if max_axis_angle is not None:
        if not (np.isfinite(max_axis_angle) and 0.0 < max_axis_angle <= 180.0):
            raise InputError(f"max_axis_angle must be within 0..180 deg, got {max_axis_angle!r}")
        limit = (np.asarray(machine_axis, float), float(max_axis_angle))
    for name, x in (("max_lead", max_lead), ("max_tilt", max_tilt)):
        if not (np.isfinite(x) and 0.0 <= x <= 90.0):
            raise InputError(f"{name} must be within 0..90 deg, got {x!r}")
    if max_lead < lead:
        raise InputError(f"max_lead ({max_lead:g} deg) is below the lead ({lead:g} deg)")
    if not (step > 0 and int(grid) >= 4 and max_turn > 0):
        raise InputError("the tilt-away lattice needs grid >= 4 and an angle step > 0")
    feed = as_feed(strategy)
    u0, u1, v0, v1 = face.uv_bounds
    us, vs = np.linspace(u0, u1, int(grid)), np.linspace(v0, v1, int(grid))
    U, V = np.meshgrid(us, vs, indexing="ij")
    inside = face.contains_uv(U, V) if face.is_trimmed else np.ones(U.shape, bool)
    ball = cutter.end_mill_radii("tilt away").is_ball
    within = _candidates(lead, -max_lead if ball else lead, max_lead, max_tilt, step)
    cands = within[: max(1, int(max_candidates))]
    _, nominal_axes = _placements(face, cutter, feed, lead, tilt, us, vs)
    axes = nominal_axes.copy()
    choice = np.full(U.shape, -1)  # candidate index per lattice point, -1: none clears
    todo = np.argwhere(inside)
    per_round = 6
    for k0 in range(0, len(cands), per_round):
        if todo.size == 0:
            break
        batch = cands[k0 : k0 + per_round]
        placed = [_placements(face, cutter, feed, lt, tl + tilt, us, vs) for lt, tl in batch]
        T = np.concatenate([t[todo[:, 0], todo[:, 1]] for t, _ in placed])
        A = np.concatenate([a[todo[:, 0], todo[:, 1]] for _, a in placed])
        ok = (_clear(check_faces, cutter, T, A, gouge_tolerance) & ~beyond(A, limit)).reshape(len(batch), -1)
        first = np.where(ok.any(axis=0), ok.argmax(axis=0), -1)
        for m, (i, j) in enumerate(todo):
            if first[m] >= 0:
                choice[i, j] = k0 + first[m]
                axes[i, j] = placed[first[m]][1][i, j]
        todo = todo[first < 0]
    raw = axes.copy()
    lead_min = 0.0 if ball else lead
    max_turn = min(max_turn, 0.5 * np.degrees(1.0 / cutter.D))  # S2 is D up the axis: 1 / D rad/mm folds it
    smooth, not_clear, turn, own = _smoothed(
        face, cutter, feed, raw, nominal_axes, choice, inside, check_faces, gouge_tolerance, us, vs,
        (max_turn, lead_min, max_lead, limit),
    )  # fmt: skip
    change = _angle_deg(smooth, nominal_axes)[inside]
    tilted = inside & (choice > 0)
    nowhere = inside & (choice < 0)
    report = {
        "grid": [int(grid), int(grid)],
        "candidates": len(cands),
        "candidates_within_limits": len(within),
        "angle_step_deg": float(step),
        "max_lead_deg": float(max_lead),
        "max_tilt_deg": float(max_tilt),
        "max_axis_angle_deg": None if limit is None else limit[1],
        "max_turn_deg_per_mm": float(max_turn),
        "lattice_points": int(inside.sum()),
        "lattice_points_tilted": int(tilted.sum()),
        "lattice_points_clear_nowhere": int(nowhere.sum()),
        "nowhere_uv": np.stack([U[nowhere], V[nowhere]], -1)[:20].tolist(),
        **_regions(face, nowhere, us, vs),
        "axis_change_max_deg": float(change.max(initial=0.0)),
        "axis_turn_max_deg_per_mm": turn,
        "nominal_axis_turn_max_deg_per_mm": own,
        "axis_turn_bound_deg_per_mm": float(max(max_turn, own)),
        "lattice_points_not_clear_smoothed": not_clear,
    }
    from ..geometry.builders import interpolate_grid

    surf = interpolate_grid(smooth, 3, 3, us, vs)
    field = AxisField(lambda u, v: surf.evaluate(u, v), feed, "tilt-away axis field")
    return field, report


def _regions(face, mask, us, vs, most: int = 20) -> dict:
    """The connected regions of lattice points ``mask`` (no orientation clears them), largest first (``most``
    of them; their number and total area besides): each one's uv box (its points' cells, half the way to
    their neighbours), the mean of its points on the face (xyz, mm) and its area (mm^2, the cells'
    |S_u x S_v| du dv summed)."""
    from scipy import ndimage

    if not mask.any():
        return {"regions_clear_nowhere": [], "n_regions_clear_nowhere": 0, "area_clear_nowhere_mm2": 0.0}
    labels, n = ndimage.label(mask)
    d = face.surface.derivatives_grid(us, vs, 1)

    def halves(x):  # each lattice point's cell: half the way to its neighbours, inside the domain
        mid = (x[1:] + x[:-1]) / 2
        return np.r_[x[0], mid], np.r_[mid, x[-1]]

    (ua, ub), (va, vb) = halves(us), halves(vs)
    cell = np.linalg.norm(np.cross(d.su, d.sv), axis=-1) * (ub - ua)[:, None] * (vb - va)[None, :]
    out = []
    for k in range(1, n + 1):
        i, j = np.nonzero(labels == k)
        a = float(cell[i, j].sum())
        box = [float(ua[i.min()]), float(ub[i.max()]), float(va[j.min()]), float(vb[j.max()])]
        centre = d.point[i, j].mean(axis=0)
        out.append({"uv_box": box, "xyz_mm": centre.tolist(), "area_mm2": a, "lattice_points": int(i.size)})
    out.sort(key=lambda r: -r["area_mm2"])
    return {"regions_clear_nowhere": out[:most], "n_regions_clear_nowhere": n,
            "area_clear_nowhere_mm2": float(sum(r["area_mm2"] for r in out))}  # fmt: skip


def _smoothed(face, cutter, feed, raw, nominal, choice, inside, check_faces, gouge_tolerance, us, vs, limits):
    """The raw choice made smooth. In the plane of leans (the axis's components along the feed and along
    normal x feed) each tilted lattice point moved the nominal lean by a vector; its length is raised to the
    smallest field that changes by at most ``rate`` degrees per mm (so it tapers off around the tilted
    points instead of jumping) and its direction is that of the nearest tilted point, blurred; the lean is kept
    within ``lead_min`` and ``max_lead`` of the normal (``limits = (rate, lead_min, max_lead, rotary limit)``).
    The field is blurred further where it still turns faster than ``rate``, or than the nominal axes where the
    face is curved tighter (tilted regions leaning different ways meeting); the points no orientation clears,
    cut out of the path, do not count. The smoothed placements of the lattice points that had a clear
    orientation are checked again. Returns the smoothed axes, the lattice points they do not clear, their
    largest turn and the nominal axes' (degrees per mm)."""
    from scipy.ndimage import distance_transform_edt, gaussian_filter

    from .autolead import lipschitz_envelope
    from .surfaces import MachiningMaps

    rate, lo, hi = limits[0], np.sin(np.radians(limits[1])), np.sin(np.radians(min(limits[2], 85.0)))
    maps = MachiningMaps(face, cutter, 5, LeadTilt(1.0, 0.0, feed), cutter.D, False)
    frame = maps.frame(us, vs)
    n, f = frame.normal, feed.feed(frame)
    g = np.cross(n, f)
    lean = lambda a: np.stack([np.einsum("...i,...i->...", a, f), np.einsum("...i,...i->...", a, g)], -1)  # noqa: E731
    w_nom = lean(nominal)
    delta = lean(raw) - w_nom
    size = np.linalg.norm(delta, axis=-1)
    tilted = inside & (choice > 0) & (size > 1e-12)
    w = w_nom
    if tilted.any():
        du_mm = np.linalg.norm(np.diff(frame.point, axis=0), axis=-1)
        dv_mm = np.linalg.norm(np.diff(frame.point, axis=1), axis=-1)
        env = np.radians(lipschitz_envelope(np.where(tilted, np.degrees(size), 0.0), du_mm, dv_mm, rate))
        _, (ii, jj) = distance_transform_edt(~tilted, return_indices=True)
        direction = delta[ii, jj] / size[ii, jj][..., None]
        direction = np.stack([gaussian_filter(direction[..., k], 2.0, mode="nearest") for k in range(2)], -1)
        direction /= np.maximum(np.linalg.norm(direction, axis=-1, keepdims=True), 1e-12)
        w = w_nom + env[..., None] * direction
    kept = inside & (choice >= 0)  # the points no orientation clears are cut out: their turn does not count
    own = _turn_max(nominal, frame.point, kept)
    bound = max(rate, own)  # a face curved tighter turns the nominal faster
    for _ in range(40):  # where tilted regions leaning different ways meet: blurred until the turn is in bound
        m = np.linalg.norm(w, axis=-1)
        scale = np.clip(m, lo, hi) / np.maximum(m, 1e-300)
        w = np.where((m > 1e-12)[..., None], w * scale[..., None], np.stack([np.full(m.shape, lo), 0 * m], -1))
        h = np.sqrt(np.maximum(1.0 - (w**2).sum(-1), 0.0))[..., None]
        smooth = h * n + w[..., :1] * f + w[..., 1:] * g
        smooth /= np.linalg.norm(smooth, axis=-1, keepdims=True)
        if _turn_max(smooth, frame.point, kept) <= bound * (1 + 1e-6) or not tilted.any():
            break
        w = np.stack([gaussian_filter(w[..., k], 1.0, mode="nearest") for k in range(2)], -1)
    idx = np.argwhere(inside & (choice >= 0))
    tips, axes = MachiningMaps(face, cutter, 5, _GridAxes(smooth, feed), cutter.D, False).tool_placements(us, vs)
    from ..cam.clearance import beyond

    A = axes[idx[:, 0], idx[:, 1]]
    ok = _clear(check_faces, cutter, tips[idx[:, 0], idx[:, 1]], A, gouge_tolerance) & ~beyond(A, limits[3])
    return smooth, int((~ok).sum()), _turn_max(smooth, frame.point, kept), own


def _turn_max(axes, points, inside) -> float:
    """The largest turn of ``axes`` between neighbouring lattice points inside the face, degrees per mm."""
    out = 0.0
    for k in (0, 1):
        da = np.diff(axes, axis=k)
        dp = np.linalg.norm(np.diff(points, axis=k), axis=-1)
        a0 = axes[:-1] if k == 0 else axes[:, :-1]
        a1 = a0 + da
        both = (inside[1:] & inside[:-1]) if k == 0 else (inside[:, 1:] & inside[:, :-1])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = _angle_deg(a0, a1) / dp
        t = t[both & np.isfinite(t)]
        out = max(out, float(t.max(initial=0.0)))
    return out


class _GridAxes:
    """The axes of a lattice as a strategy at the lattice's own points (no interpolation needed there)."""

    def __init__(self, axes, feed):
        self.axes, self.feed = axes, feed

    def axis(self, frame) -> np.ndarray:
        return self.axes.reshape(frame.normal.shape)

    def describe(self) -> str:
        return "tilt-away lattice"


__all__ = ["clear_axis_field"]
