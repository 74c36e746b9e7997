"""Scallop-driven raster lines: each next line of a 3-axis raster as far from the last one as the cusp the
two leave on the part allows.

Between two adjacent lines at offsets ``ta < tb`` (across the feed) the tool sweeps, along each line, a
lower surface (:class:`SweptLine`: the lowest the tool gets over its positions on the line, ``h`` the
cutter's lower profile, the positions the exact drop-cutter heights). The two swept surfaces cross at
the cusp, searched by bisection between the two tools' contacts (on a slope a contact lies uphill of its
tip, so the cusp may lie beyond the next line's tip). What is left there is the cusp's height above the
part at its plan position (the part's height solved on the exact faces, :func:`part_heights`):
vertically, and along the part's normal (the vertical height times the normal's axis component: the
scallop height CAM programmers mean, and the one the target applies to). On planes at any slope this
is the closed form (tests); on the free-form example the N-buffer simulation of the planned path finds
no more than the target.

The planner starts at the first line and tries the next one at the closed-form step-over of a flat
floor (:func:`~machsurf_cad.threeaxis.paths.scallop_stepover`), shrinking it until the largest cusp
along the line is within the target (down to 1/32 of that step, then the pair is reported), and aims
the next guess at the target (the cusp grows about as the step squared; at most 25 % wider). Material
the tool cannot reach (a wall's foot, a corner narrower than it) or that a closer line would not remove
is the cutter's, not the step-over's: it is counted, not planned for, and the simulation reports it.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .solves import _clamp_uv, _inside, _Profile


class SweptLine:
    """The lower surface of the tool swept along one raster line, in the line's frame: at ``(s, t)`` (along
    the line, across it from the line) the lowest the tool gets over all its positions on the line,
    ``min over s' of z(s') + h(sqrt((s - s')^2 + t^2))``. The tool's positions are the line's drop-cutter
    heights at ``s`` interpolated ``refine`` times (the path moves straight between its positions); where
    no face lies under the tool (NaN) it does not cut."""

    def __init__(self, prof: _Profile, s, z, refine: int = 4):
        s, z = np.asarray(s, float), np.asarray(z, float)
        self.prof, self.refine = prof, refine
        self.ds = (s[1] - s[0]) / refine if s.size > 1 else 1.0
        w = np.arange(refine) / refine
        zr = (z[:-1, None] * (1 - w) + z[1:, None] * w).ravel()
        self.z = np.append(np.where(np.isfinite(zr), zr, np.inf), z[-1] if np.isfinite(z[-1]) else np.inf)
        self.K = int(math.ceil(prof.R / self.ds))
        self.k = np.arange(-self.K, self.K + 1)
        # a lower bound of each position's profile term: h on [|s - s'|, R] (rho is at least |s - s'|)
        self.floor = prof.floor(np.abs(self.k) * self.ds) - 1e-9

    def __call__(self, i, t):
        """Swept lower surface at the line's sample ``i`` (array) and offset ``t`` (array, same shape).

        Each position's term is bounded below by its height plus the profile's floor beyond ``|s - s'|``
        (:meth:`_Profile.floor`): the term of the position of least bound is computed first, then only the
        positions whose bound is below it (the same minimum, bit for bit, from a few terms a row where the
        profile rises outwards)."""
        idx = self.refine * np.asarray(i)[:, None] + self.k[None, :]
        inside = (idx >= 0) & (idx < self.z.size)
        zs = np.where(inside, self.z[np.clip(idx, 0, self.z.size - 1)], np.inf)
        t = np.asarray(t, float)
        bound = zs + self.floor[None, :]
        rows = np.arange(zs.shape[0])
        j0 = np.argmin(bound, axis=1)
        first = self._terms(zs[rows, j0], np.hypot(self.k[j0] * self.ds, t))
        r, c = np.nonzero(bound < first[:, None])  # by row
        out = first.copy()
        if r.size:
            starts = np.flatnonzero(np.r_[True, r[1:] != r[:-1]])
            terms = self._terms(zs[r, c], np.hypot(self.k[c] * self.ds, t[r]))
            out[r[starts]] = np.minimum(out[r[starts]], np.minimum.reduceat(terms, starts))
        return out

    def _terms(self, zs, rho):
        """The swept surface's terms: a position's height plus the profile at ``rho`` (inf beyond the rim)."""
        h = self.prof.height(rho)
        return zs + np.where(np.isfinite(h), h, np.inf)


def cusp_points(a: SweptLine, ta: float, b: SweptLine, tb: float, rows, lo, hi, iters: int = 40):
    """Cusp offset ``t*`` and height ``z*`` between the swept lower surfaces of lines ``a`` (at ``ta``) and
    ``b`` (at ``tb``) at the samples ``rows``, searched between ``lo`` and ``hi`` (the two contacts' offsets:
    ``a`` touches the part at ``lo``, ``b`` at ``hi``): where ``a`` stops being the lower (a switch from
    ``a <= b`` to ``a > b``). NaN where they do not cross there.

    A swept surface ends at its tool's rim, ``R`` from its line (inf beyond): where ``a`` is still below
    ``b`` at ``ta + R`` the cusp is there, at ``b``'s height (and where ``b`` is below ``a`` at ``tb - R``,
    there at ``a``'s). Otherwise the bracket between those ends, where both are finite, shrinks to
    ``2**-iters`` of the first one's width by false position (Illinois), with a halving step after any step
    that did not halve it: at most twice the ``iters`` steps of bisection, far fewer on smooth surfaces. A
    step landing exactly where the two are equal (a crossing hit exactly, or a stretch where both tools'
    flats stand at one height) looks ``2**-iters`` of the width above it for the switch."""
    rows = np.asarray(rows)
    lo = np.array(lo, float)
    hi = np.array(hi, float)

    def f(k, t):
        return np.nan_to_num(a(rows[k], t - ta) - b(rows[k], tb - t), posinf=1e300, neginf=-1e300)

    every = np.arange(rows.size)
    f_lo, f_hi = f(every, lo), f(every, hi)
    crosses = (f_lo <= 0) & (f_hi >= 0)
    tol = (hi - lo) * 2.0**-iters
    lo_c, hi_c = np.maximum(lo, tb - b.prof.R), np.minimum(hi, ta + a.prof.R)  # b, a finite (but NaN stretches)
    fc_lo, fc_hi = f_lo.copy(), f_hi.copy()
    for cut, f_cut, end in ((lo_c, fc_lo, lo), (hi_c, fc_hi, hi)):
        moved = np.nonzero(cut != end)[0]  # (most ends are within reach already: not evaluated again)
        if moved.size:
            f_cut[moved] = f(moved, cut[moved])
    clip = crosses & (lo_c <= hi_c)
    at_hi = clip & (fc_hi < 0) & (fc_hi > -1e300)  # a finite and still below b at a's rim
    at_lo = clip & ~at_hi & (fc_lo > 0) & (fc_lo < 1e300)  # b finite and below a at b's rim
    for end, f_end, cut, f_cut, keep in ((lo, f_lo, lo_c, fc_lo, fc_lo <= 0), (hi, f_hi, hi_c, fc_hi, fc_hi >= 0)):
        use = clip & keep  # a clipped end where it still brackets the switch
        end[use], f_end[use] = cut[use], f_cut[use]
    lo[at_hi], f_lo[at_hi] = hi_c[at_hi], fc_hi[at_hi]
    hi[at_hi] = hi_c[at_hi]
    hi[at_lo], f_hi[at_lo] = lo_c[at_lo], fc_lo[at_lo]
    lo[at_lo] = lo_c[at_lo]
    width1 = np.full(rows.size, np.inf)  # the bracket's width before the last step
    halved = np.zeros(rows.size, bool)  # whether the last step was a halving
    keep_lo = np.zeros(rows.size, bool)  # which end the last step kept (Illinois halves its value)
    keep_hi = np.zeros(rows.size, bool)
    for _ in range(2 * iters):
        k = np.nonzero(crosses & (hi - lo > tol))[0]
        if k.size == 0:
            break
        l, h, fl, fh = lo[k], hi[k], f_lo[k], f_hi[k]
        w = h - l
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            x = l - fl * w / (fh - fl)
        halve = ~((x > l) & (x < h)) | (~halved[k] & (w > 0.5 * width1[k]))
        x = np.where(halve, 0.5 * (l + h), x)
        fx = f(k, x)
        up = fx > 0  # the switch lies below x: x is the new upper end
        width1[k], halved[k] = w, halve
        hi[k] = np.where(up, x, h)
        lo[k] = np.where(up, l, x)
        f_hi[k] = np.where(up, fx, np.where(keep_hi[k] & ~halve, 0.5 * fh, fh))
        f_lo[k] = np.where(up, np.where(keep_lo[k] & ~halve, 0.5 * fl, fl), fx)
        keep_lo[k], keep_hi[k] = up, ~up
        z0 = np.nonzero(fx == 0)[0]
        if z0.size:  # equal at x: the switch just above it ends the search there
            kz = k[z0]
            xp = np.minimum(x[z0] + tol[kz], h[z0])
            fp = f(kz, xp)
            there = np.nonzero(fp > 0)[0]
            hi[kz[there]], f_hi[kz[there]] = xp[there], fp[there]
    t = 0.5 * (lo + hi)
    z = np.maximum(a(rows, t - ta), b(rows, tb - t))
    return np.where(crosses & np.isfinite(z), t, np.nan), np.where(crosses & np.isfinite(z), z, np.nan)


def part_heights(fs, xy, k: int = 12, iters: int = 16):
    """Height of the part (tool frame) and its unit normal (tool frame, pointing up the axis) under the plan
    points ``xy``: per face near each point (its nearest of the ``k`` nearest seed samples), Newton on the
    exact surface for ``S_xy(u, v) = xy`` inside the trimmed face; the highest face wins. NaN where no
    face lies under a point (or only a vertical one)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    n_int = fs.sample_xyz.shape[0]
    z_best = np.full(xy.shape[0], -np.inf)
    n_best = np.tile([0.0, 0.0, 1.0], (xy.shape[0], 1))
    if xy.shape[0] == 0:
        return z_best, n_best
    _, nb = fs.tree.query(xy, k=min(k, fs.tree.n))
    nb = np.atleast_2d(nb)
    q = np.repeat(np.arange(xy.shape[0]), nb.shape[1])
    j = nb.ravel()
    keep = j < n_int  # face samples (edge samples follow them in the tree)
    q, j = q[keep], j[keep]
    if q.size == 0:  # no face sample near any point (only vertical faces: they have none)
        return np.full(xy.shape[0], np.nan), n_best
    fid = fs.sample_face[j]
    first = np.unique(q * (len(fs.faces) + 1) + fid, return_index=True)[1]  # nearest sample per (point, face)
    q, j, fid = q[first], j[first], fid[first]
    u, v = fs.sample_uv[j, 0].copy(), fs.sample_uv[j, 1].copy()
    target = xy[q]
    scale = max(fs.spacing, 1.0)
    live = np.arange(q.size)  # the points still moving (a step of more than 1e-13 of the scale)
    for _ in range(iters):
        P, Su, Sv = fs.atlas.derivatives(fid[live], u[live], v[live], 1)
        r = target[live] - P[:, :2]
        a, b, c, d = Su[:, 0], Sv[:, 0], Su[:, 1], Sv[:, 1]
        det = a * d - b * c
        ok = np.abs(det) > 1e-12 * (np.abs(a * d) + np.abs(b * c) + 1e-300)
        det = np.where(ok, det, 1.0)
        du = np.where(ok, (d * r[:, 0] - b * r[:, 1]) / det, 0.0)
        dv = np.where(ok, (-c * r[:, 0] + a * r[:, 1]) / det, 0.0)
        u0, v0 = u[live], v[live]
        u[live], v[live] = _clamp_uv(fs, fid[live], u0 + du, v0 + dv)
        moved = np.hypot(u[live] - u0, v[live] - v0) > 0
        live = live[moved & (np.abs(r).max(axis=1) > 1e-13 * scale)]
        if live.size == 0:
            break
    P, Su, Sv = fs.atlas.derivatives(fid, u, v, 1)
    n = np.cross(Su, Sv)
    nn = np.linalg.norm(n, axis=1)
    hit = (np.linalg.norm(target - P[:, :2], axis=1) < 1e-9 * scale) & (nn > 0) & _inside(fs, fid, u, v)
    z = np.where(hit, P[:, 2], -np.inf)
    n = n / np.where(nn > 0, nn, 1.0)[:, None]
    n = np.where((n[:, 2] < 0)[:, None], -n, n)
    order = np.lexsort((z, q))  # per point, its highest face last
    last = np.r_[q[order][1:] != q[order][:-1], True]
    sel = order[last]
    z_best[q[sel]] = z[sel]
    n_best[q[sel]] = n[sel]
    return np.where(np.isfinite(z_best), z_best, np.nan), n_best


def _interior(valid, margin: int):
    """``valid`` positions at least ``margin`` samples from an invalid one or the ends."""
    bad = np.r_[-1, np.nonzero(~valid)[0], valid.size]
    i = np.arange(valid.size)
    nxt = bad[np.searchsorted(bad, i)]
    prv = bad[np.searchsorted(bad, i) - 1]
    return valid & (i - prv > margin) & (nxt - i > margin)


def cusp_left(
    fs,
    a: SweptLine,
    ta,
    b: SweptLine,
    tb,
    s,
    d,
    nrm,
    za,
    zb,
    ca,
    cb,
    reach=None,
    target=None,
    drop=None,
    cutter_of_reach=None,
    prof=None,
):
    """Per position along the lines: (material left at the cusp along the normal, vertically, the cusp's plan
    point); NaN where it is not measured. The cusp is where the two swept lower surfaces cross between the
    two tools' contacts (offsets ``ca``, ``cb`` across the lines; on a slope a contact lies uphill of its
    tip, so the cusp may lie beyond the next line's tip): from a contact to the cusp the material left under
    one tool grows, then falls under the other, wherever the tool fits the part. Where it does not (a
    corner narrower than the tool) the material left under one tool is the cutter's, not the step-over's:
    no step-over removes it, so it is not measured here (the simulation reports it): with ``reach`` (the
    drop-cutter) a cusp over ``target`` is checked by placing the tool right above it; when that leaves
    more than ``target`` too (a wall's foot seen from its top, a pocket narrower than the tool), or when a
    line halfway between would not lower it by a quarter, the position is not the step-over's to control
    and is counted in the fourth value instead. Positions less than the
    tool's radius from the end of a line (or of a stretch with a face under the tool) are not measured
    either: the material there is the path's end."""
    valid = np.isfinite(za) & np.isfinite(zb) & np.isfinite(ca) & np.isfinite(cb)
    rows = np.nonzero(_interior(valid, a.K // a.refine) & (cb > ca))[0]
    normal = np.full(s.size, np.nan)
    vert = np.full(s.size, np.nan)
    where = np.zeros((s.size, 2))
    if rows.size == 0:
        return normal, vert, where, 0
    tc, zc = cusp_points(a, ta, b, tb, rows, ca[rows], cb[rows])
    ok = np.isfinite(tc)
    rows, tc, zc = rows[ok], tc[ok], zc[ok]
    xy = s[rows, None] * d + tc[:, None] * nrm
    zp, pn = part_heights(fs, xy)
    nz = pn[:, 2]
    vert[rows] = zc - zp
    normal[rows] = vert[rows] * nz
    where[rows] = xy
    limit = 0
    if reach is not None and target is not None:
        over = np.nonzero(normal[rows] > target)[0]
        if over.size:  # the tool placed to touch the part at the cusp: does it reach it?
            single = reach(xy[over], zp[over], pn[over]) * nz[over]
            cutter_limit = ~(single <= target)
            # a line halfway between: if the tool there does not lower what is left at the cusp by a quarter,
            # the step-over does not control it (e.g. a flat bottom resting on a plateau over its rounded
            # edge: the lines beyond it machine that, not a closer line here)
            keep = np.nonzero(~cutter_limit)[0]
            if keep.size:
                i = over[keep]
                tm = 0.5 * (ta + tb)
                swept_mid = SweptLine(prof, s, drop(fs, cutter_of_reach, s[:, None] * d + tm * nrm).height)
                zm = swept_mid(rows[i], tc[i] - tm)
                left_now = zc[i] - zp[i]
                cutter_limit[keep] = ~(np.nan_to_num(zm, nan=np.inf) < zc[i] - 0.25 * left_now)
            normal[rows[over[cutter_limit]]] = np.nan
            vert[rows[over[cutter_limit]]] = np.nan
            limit = int(cutter_limit.sum())
    return normal, vert, where, limit


def plan_lines(fs, cutter, scallop_mm: float, d, nrm, t_range, s, drop, first_step: float, progress=None):
    """Offsets of the raster lines and their drop-cutter heights and contacts, each line as far from the
    previous as ``scallop_mm`` (material left along the normal) allows; ``info`` with the figures."""
    prof = _Profile(cutter)
    t0, t1 = t_range
    min_step = first_step / 32

    def line(t):
        r = drop(fs, cutter, s[:, None] * d + t * nrm)
        return r.height, r.contact

    def across(contact):  # a contact's offset across the lines (tool frame)
        return fs.to_frame(contact)[:, :2] @ nrm

    def reach(xy, zp, n):
        """Vertical gap between the part at ``xy`` (height ``zp``, normal ``n``) and the tool placed to touch it
        there: the profile point with the part's slope over it (0 wherever the tool reaches the point)."""
        slope = np.hypot(n[:, 0], n[:, 1]) / np.maximum(n[:, 2], 1e-12)
        rho = prof.radius_of_slope(slope)
        horiz = np.hypot(n[:, 0], n[:, 1])
        dxy = np.where(horiz[:, None] > 1e-12, n[:, :2] / np.maximum(horiz, 1e-300)[:, None], 0.0)
        tip = drop(fs, cutter, xy + rho[:, None] * dxy).height
        return tip + prof(rho)[0] - zp

    h, c = line(t0)
    offsets, heights, contacts, swept = [t0], [h], [c], [SweptLine(prof, s, h)]
    worst = {"left_mm": 0.0, "left_vertical_mm": 0.0, "at_xy_mm": None}
    unmet = []  # pairs still over the target at the smallest step
    guess = first_step
    trials = 0
    at_limit = 0  # cusp positions the step-over does not control (the tool cannot touch there, or a closer line
    # would not lower them)
    while offsets[-1] < t1 - 1e-9:
        ta, za = offsets[-1], heights[-1]
        step = min(guess, t1 - ta)
        while True:
            trials += 1
            tb = ta + step
            zb, cb = line(tb)
            sb = SweptLine(prof, s, zb)
            left, vert, xy, limit = cusp_left(fs, swept[-1], ta, sb, tb, s, d, nrm, za, zb, across(contacts[-1]),
                                              across(cb), reach, scallop_mm, drop, cutter, prof)  # fmt: skip
            known = ~np.isnan(left)
            peak = float(np.max(left[known])) if known.any() else 0.0  # inf: a strip neither tool reaches
            if peak <= scallop_mm * (1 + 1e-9) or step <= min_step * (1 + 1e-9):
                break
            # the cusp grows about as the step squared: aim at the target, a little inside it
            shrink = math.sqrt(scallop_mm / peak) * (1 - 1e-6) if math.isfinite(peak) else 0.5
            step = max(min_step, step * min(max(shrink, 0.3), 1 - 1e-6))
        k = int(np.argmax(np.where(known, left, -np.inf))) if known.any() else 0
        if peak > scallop_mm * (1 + 1e-9):
            unmet.append({"between_mm": [float(ta), float(tb)], "left_mm": peak, "at_xy_mm": xy[k].tolist()})
        if known.any():
            if left[k] > worst["left_mm"]:
                worst = {"left_mm": float(left[k]), "left_vertical_mm": float(vert[k]), "at_xy_mm": xy[k].tolist()}
        at_limit += limit
        offsets.append(tb)
        swept.append(sb)
        heights.append(zb)
        contacts.append(cb)
        # the cusp grows about as the step squared: aim the next line at the target (at most 25 % wider)
        grow = math.sqrt(scallop_mm / peak) * (1 - 1e-6) if 0 < peak < math.inf else 1.25
        guess = step * min(max(grow, 1.0), 1.25)
        guess = min(guess, 4 * first_step, 2 * prof.R * 0.95)
        if progress is not None:
            progress(int(1000 * (tb - t0) / max(t1 - t0, 1e-12)), 1000, "scallop-driven raster lines")
    if len(offsets) < 2:
        raise InputError("the raster's extent is narrower than one line")
    gaps = np.diff(offsets)
    info = {
        "scallop_measure": "cusp of the swept lower surfaces of adjacent lines, its height above the part along "
        "the part's normal",
        "scallop_planned_max_mm": worst["left_mm"],
        "scallop_planned_max_vertical_mm": worst["left_vertical_mm"],
        "scallop_planned_worst_xy_mm": worst["at_xy_mm"],
        "stepover_min_mm": float(gaps.min()),
        "stepover_max_mm": float(gaps.max()),
        "stepover_flat_floor_mm": float(first_step),
        "n_line_trials": trials,
        "scallop_unmet": unmet[:20],
        "n_scallop_unmet": len(unmet),
        "n_cusps_at_cutter_limit": at_limit,
    }
    return np.array(offsets), np.array(heights), np.array(contacts), info
