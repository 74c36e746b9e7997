"""Unit normals of parametric surfaces, with limits where ``su x sv`` vanishes (poles, collapsed edges)."""

from __future__ import annotations

import numpy as np

from ..errors import DegenerateGeometryError

LIMIT_NORMAL_AGREEMENT_DEG = 1e-3
"""Neighbouring normals around a degenerate point must agree within this angle for their limit to
be its normal (a sphere's pole: they do; a cone's tip: they do not, and the normal stays undefined)."""


def unit_normals(su, sv, scale, u=None, v=None, *, check=True, surface=None) -> np.ndarray:
    """Normalised ``su x sv``; raises on (near) zero normals when ``check``.

    With ``surface`` (and ``u``, ``v``), a point where ``su x sv`` vanishes (a pole of a sphere, a
    revolved face touching its axis, a collapsed edge) gets the limit of the normals around it,
    when that limit exists (:func:`limit_normals`).
    """
    n = _cross(su, sv)
    norm = np.sqrt(np.einsum("...i,...i->...", n, n))
    bad = ~(norm > 1e-12 * scale * scale)
    if np.any(bad) and surface is not None and u is not None:
        uu, vv = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        lim = limit_normals(surface, uu[bad], vv[bad])
        ok = np.all(np.isfinite(lim), axis=-1)
        n = n / np.where(bad, 1.0, norm)[..., None]
        idx = np.nonzero(bad)
        fill = n[idx]
        fill[ok] = lim[ok]
        n[idx] = fill
        still = np.zeros(bad.shape, bool)
        still[tuple(i[~ok] for i in idx)] = True
        if not np.any(still):
            return n
        n = _cross(su, sv)
        bad = still
        norm = np.where(bad, 0.0, norm)
    if np.any(bad):
        if check:
            region = {}
            if u is not None:
                uu, vv = np.broadcast_arrays(u, v)
                region = {"uv": np.stack([uu[bad], vv[bad]], axis=-1)[:20].tolist()}
            raise DegenerateGeometryError(
                f"surface normal undefined (su x sv = 0) at {int(bad.sum())} point(s), e.g. (u, v) = "
                f"{region.get('uv', [['?', '?']])[0]}: collapsed edge or singular parameterisation"
                + (" where the normals around disagree (a cone's tip or a crease: no limit normal)" if surface else ""),
                region,
            )
        norm = np.where(bad, np.nan, norm)
    return n / norm[..., None]


def limit_normals(surface, u, v, rel_step: float = 1e-6) -> np.ndarray:
    """Limits of the unit normal at degenerate points ``(u, v)``.

    The normals at the neighbours ``(u +- du, v)``, ``(u, v +- dv)`` (inside the domain, steps
    ``rel_step`` of its size) that exist must agree within :data:`LIMIT_NORMAL_AGREEMENT_DEG`; their
    mean at steps h and 2h is extrapolated to h = 0 (Richardson: error O(h^2)). NaN where they
    disagree (no limit: a cone's tip) or none exists.
    """
    u = np.asarray(u, float).ravel()
    v = np.asarray(v, float).ravel()

    def mean_at(k):
        c, ok = _neighbour_normals(surface, u, v, k * rel_step)
        m = np.nansum(np.where(ok[..., None], c, 0.0), axis=1)
        mn = np.linalg.norm(m, axis=1)
        have = ok.any(axis=1) & (mn > 0)
        m = np.where(have[:, None], m / np.where(have, mn, 1.0)[:, None], np.nan)
        cos_lim = np.cos(np.radians(LIMIT_NORMAL_AGREEMENT_DEG))
        agree = np.all(~ok | (np.einsum("mkj,mj->mk", np.nan_to_num(c), np.nan_to_num(m)) >= cos_lim), axis=1)
        m[~agree] = np.nan
        return m

    m1, m2 = mean_at(1.0), mean_at(2.0)
    ext = 2.0 * m1 - m2
    en = np.linalg.norm(ext, axis=1, keepdims=True)
    return np.where(np.isfinite(en) & (en > 0), ext / np.where(en > 0, en, 1.0), np.nan)


def _neighbour_normals(surface, u, v, rel: float):
    """Normals around degenerate points, ``(m, k, 3)`` with a validity mask ``(m, k)``.

    Where a whole iso-line collapses to the point (``sv = 0``: moving in v does not move it, as at a
    sphere's pole or a cone's tip) the probes are ``(u +- du, v_k)`` for v_k across the whole v range,
    so a normal that depends on the approach (a cone's tip) shows as disagreement; likewise for
    ``su = 0``; otherwise the four neighbours ``(u +- du, v)``, ``(u, v +- dv)``.
    """
    u0, u1, v0, v1 = surface.bounds
    du, dv = rel * (u1 - u0), rel * (v1 - v0)
    d0 = surface.derivatives(u, v, 1)
    small = 1e-9 * surface.scale
    su_zero = np.linalg.norm(d0.su, axis=1) <= small
    sv_zero = np.linalg.norm(d0.sv, axis=1) <= small
    ring = np.linspace(0.0, 1.0, 9)
    probes = []
    for a, b in ((du, 0.0), (-du, 0.0), (0.0, dv), (0.0, -dv)):
        probes.append((u + a, v + b))
    for t in ring:  # along the collapsed iso-line, stepping off it
        vv = v0 + t * (v1 - v0)
        for a in (du, -du):
            probes.append((np.where(sv_zero, u + a, np.nan), np.where(sv_zero, vv, np.nan)))
        uu = u0 + t * (u1 - u0)
        for b in (dv, -dv):
            probes.append((np.where(su_zero, uu, np.nan), np.where(su_zero, v + b, np.nan)))
    cands, oks = [], []
    for pu, pv in probes:
        inside = np.isfinite(pu) & (pu >= u0) & (pu <= u1) & (pv >= v0) & (pv <= v1)
        uu = np.where(inside, pu, u)
        vv = np.where(inside, pv, v)
        d = surface.derivatives(uu, vv, 1)
        n = _cross(d.su, d.sv)
        nn = np.sqrt(np.einsum("ij,ij->i", n, n))
        good = inside & (nn > 1e-9 * surface.scale * surface.scale)
        cands.append(n / np.where(good, nn, 1.0)[:, None])
        oks.append(good)
    return np.stack(cands, 1), np.stack(oks, 1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of (..., 3) arrays; faster than np.cross on large arrays."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out
