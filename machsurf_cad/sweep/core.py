"""Swept envelopes of rotational tools as envelopes of sphere families (mm, degrees).

After Aranda Bassegoda (2024), following Zhu et al. (2009) and Zhu & Lu (2015):

* the tool is the envelope of spheres centred on its axis, ``q(a) = a`` along the axis from the
  tool tip, radius ``r(a)`` (one segment of :meth:`machsurf_cad.cutters.Cutter.sphere_family`);
* the motion is the tool-tip path ``T(t)`` and the unit axis ``A(t)``; the sphere centres sweep
  ``S(a, t) = T(t) + a A(t)`` (the paper's ``P(t) + (a - a0) A(t)`` with ``P = T + a0 A``);
* the envelope is ``X(a, t) = S + r(a) n`` with eq. (21):
  ``n = -A11 r' S_a - A21 r' S_t + s sqrt(1 - r'^2 A11) n_s``, ``A`` the inverse Gram matrix of
  ``(S_a, S_t)``, ``n_s = S_a x S_t / |S_a x S_t|``. The sign ``s`` picks the sheet: ``side = +1``
  is the sheet on the side of ``n_s``; normals point away from the axis by construction (the
  sphere's outward normal at its grazing point).

A ball end (a single sphere, ``a0 == a1``) sweeps a canal surface, parameterised by an angle
``phi`` (degrees) around the path in its normal plane instead of ``a``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..cutters import Cutter, SphereFamilySegment
from ..errors import DegenerateGeometryError, InputError
from ..results import Result
from ..toolspec import parse_cutter

_FD = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0  # 5-point first-derivative stencil, O(h^4)


def _finite_array(values, what: str) -> np.ndarray:
    """``values`` as a float array of finite numbers, or a one-line :class:`InputError`."""
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be numbers in rows of equal length") from None
    if not np.all(np.isfinite(a)):
        raise InputError(f"{what} must be finite numbers (NaN or inf found)")
    return a


def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / n


@dataclass(frozen=True)
class Motion:
    """Tool motion: tip path ``tip(t) -> (n, 3)`` mm and axis ``axis(t) -> (n, 3)`` (normalised here).

    Derivatives are taken by a 5-point central difference of step ``h`` (exact to O(h^4); with
    the default step they agree with analytic derivatives to about 1e-11 relative).
    """

    tip: Callable
    axis: Callable
    t_range: tuple = (0.0, 1.0)
    label: str = "motion"
    dtip: Callable | None = None
    daxis: Callable | None = None

    def __post_init__(self):
        t0, t1 = self.t_range
        if not t1 > t0:
            raise InputError("motion parameter range must be increasing")
        a = np.asarray(self.axis(np.linspace(t0, t1, 5)), float)
        if np.any(np.linalg.norm(a, axis=-1) < 1e-12):
            raise InputError("the tool axis vector has zero length")

    @property
    def h(self) -> float:
        return 1e-4 * (self.t_range[1] - self.t_range[0])

    def T(self, t):
        return np.asarray(self.tip(np.asarray(t, float)), float)

    def A(self, t):
        return _unit(np.asarray(self.axis(np.asarray(t, float)), float))

    def dT(self, t):
        if self.dtip is not None:
            return np.asarray(self.dtip(np.asarray(t, float)), float)
        return self._d(self.T, t)

    def dA(self, t):
        if self.daxis is not None:
            a = np.asarray(self.axis(np.asarray(t, float)), float)
            da = np.asarray(self.daxis(np.asarray(t, float)), float)
            na = np.linalg.norm(a, axis=-1, keepdims=True)
            u = a / na
            return (da - np.einsum("...i,...i->...", u, da)[..., None] * u) / na
        return self._d(self.A, t)

    def frozen(self, n: int = 2001, k: int = 7) -> Motion:
        """The same motion as interpolating splines of degree ``k`` through ``n`` samples, with exact
        spline derivatives: chained passes then cost the same as the first (no nested differences).
        The interpolation error is measured and kept in the label."""
        from scipy.interpolate import make_interp_spline

        t0, t1 = self.t_range
        ts = np.linspace(t0, t1, n)
        T, A = self.T(ts), self.A(ts)
        sT = make_interp_spline(ts, T, k=k, axis=0)
        sA = make_interp_spline(ts, A, k=k, axis=0)
        dT_, dA_ = sT.derivative(), sA.derivative()
        mid = 0.5 * (ts[1:] + ts[:-1])
        err = float(np.linalg.norm(sT(mid) - self.T(mid), axis=1).max())
        return Motion(
            lambda t: sT(np.clip(t, t0, t1)),
            lambda t: sA(np.clip(t, t0, t1)),
            self.t_range,
            f"{self.label} (spline, interpolation error {err:.2g} mm)",
            lambda t: dT_(np.clip(t, t0, t1)),
            lambda t: dA_(np.clip(t, t0, t1)),
        )

    def _d(self, f, t):
        t = np.asarray(t, float)
        h = self.h
        vals = [f(t + k * h) for k in (-2, -1, 0, 1, 2)]
        return sum(c * v for c, v in zip(_FD, vals)) / h

    # ------------------------------------------------------------------ builders
    @classmethod
    def line(cls, start, end, axis=(0.0, 0.0, 1.0), label="line") -> Motion:
        """Straight tip path from ``start`` to ``end`` (t in [0, 1]) with a constant axis."""
        s, e, a = (np.asarray(x, float) for x in (start, end, axis))
        if np.linalg.norm(a) == 0:
            raise InputError("zero-length axis vector")
        return cls(
            lambda t: s + np.asarray(t)[..., None] * (e - s),
            lambda t: np.broadcast_to(a, np.shape(t) + (3,)),
            (0.0, 1.0),
            label,
        )

    @classmethod
    def from_points(cls, points, axes=None, axis=(0.0, 0.0, 1.0), label="CL points") -> Motion:
        """Cubic interpolation of cutter-location (tip) points, with per-point axes or a constant one.

        The motion's derivatives are the interpolating splines' exact derivatives (no finite
        differences, so they are right up to the ends of the path).
        """
        from ..geometry.builders import interpolate_curve

        pts = _finite_array(points, "path points")
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 4:
            raise InputError("a path needs at least 4 points (x, y, z)")
        d = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(d < 1e-9):
            raise InputError("the path has repeated points (a cusp: P'(t) = 0)")
        c = interpolate_curve(pts, 3)

        def tip(t):
            return c.evaluate(np.clip(t, 0, 1))

        def dtip(t):
            return c.derivatives(np.clip(np.asarray(t, float), 0, 1), 1)[..., 1, :]

        if axes is None:
            a = _finite_array(axis, "axis")
            if a.shape != (3,) or np.linalg.norm(a) == 0:
                raise InputError("zero-length axis vector" if a.shape == (3,) else "the axis needs 3 components")
            return cls(
                tip,
                lambda t: np.broadcast_to(a, np.shape(t) + (3,)),
                (0.0, 1.0),
                label,
                dtip,
                lambda t: np.zeros(np.shape(t) + (3,)),
            )
        ax = _finite_array(axes, "axes")
        if ax.shape != pts.shape or np.any(np.linalg.norm(ax, axis=1) == 0):
            raise InputError("one non-zero axis vector per path point is needed")
        params = np.concatenate([[0.0], np.cumsum(d)]) / d.sum()
        ca = interpolate_curve(ax / np.linalg.norm(ax, axis=1, keepdims=True), 3, params=params)
        return cls(
            tip,
            lambda t: ca.evaluate(np.clip(t, 0, 1)),
            (0.0, 1.0),
            label,
            dtip,
            lambda t: ca.derivatives(np.clip(np.asarray(t, float), 0, 1), 1)[..., 1, :],
        )

    @classmethod
    def interpolated_axis(cls, tip, axis0, axis1, t_range=(0.0, 1.0), label="motion") -> Motion:
        """Axis turning uniformly (great-circle) from ``axis0`` to ``axis1`` over the t range."""
        a0, a1 = (_unit(np.asarray(x, float)) for x in (axis0, axis1))
        om = math.acos(float(np.clip(a0 @ a1, -1, 1)))
        t0, t1 = t_range

        def axis(t):
            s = (np.asarray(t, float) - t0) / (t1 - t0)
            if om < 1e-12:
                return np.broadcast_to(a0, s.shape + (3,))
            return (np.sin((1 - s) * om)[..., None] * a0 + np.sin(s * om)[..., None] * a1) / math.sin(om)

        return cls(tip, axis, t_range, label)


@dataclass(frozen=True, eq=False)
class Envelope(Result):
    """Envelope of one pass: exact map ``X(a, t)`` and normals ``n(a, t)``; ``a`` in mm (or phi in
    degrees for a ball), ``t`` the motion parameter."""

    motion: Motion
    cutter: Cutter
    segment: SphereFamilySegment
    side: int = 1
    a_range: tuple = ()
    name: str = "pass"

    def __post_init__(self):
        super().__post_init__()
        if self.side not in (1, -1):
            raise InputError("side must be +1 or -1")
        if not self.a_range:
            if self.is_ball:
                object.__setattr__(self, "a_range", (-90.0, 90.0))
            else:
                object.__setattr__(self, "a_range", (self.segment.a0, self.segment.a1))

    @property
    def is_ball(self) -> bool:
        return self.segment.kind == "point"

    @property
    def bounds(self):
        return (*self.a_range, *self.motion.t_range)

    def frame(self, a, t):
        """Sphere centres S, S_a, S_t and radii r, r' on the broadcast (a, t) arrays."""
        a, t = np.broadcast_arrays(np.asarray(a, float), np.asarray(t, float))
        m = self.motion
        T, A, dT, dA = m.T(t), m.A(t), m.dT(t), m.dA(t)
        if self.is_ball:
            c = self.segment.z_c
            S = T + c * A
            return S, None, dT + c * dA, np.full(a.shape, self.segment.radius), np.zeros(a.shape), A
        S = T + a[..., None] * A
        St = dT + a[..., None] * dA
        return S, A, St, self.segment.r(a), self.segment.r_a(a), A

    def normals(self, a, t, *, check: bool = True):
        """Unit envelope normals (eq. (21)) and a mask of where the envelope exists."""
        a, t = np.broadcast_arrays(np.asarray(a, float), np.asarray(t, float))
        S, Sa, St, r, ra, A = self.frame(a, t)
        if self.is_ball:
            # canal surface: n normal to the path, at angle phi from the axis's normal component
            tau = _unit(St)
            e1 = A - np.einsum("...i,...i->...", A, tau)[..., None] * tau
            ne = np.linalg.norm(e1, axis=-1, keepdims=True)
            if np.any(ne < 1e-12):
                raise DegenerateGeometryError(
                    "the ball's path is parallel to the tool axis: the angle reference around the path is undefined"
                )
            e1 = e1 / ne
            e2 = np.cross(tau, e1) * self.side
            ph = np.radians(a)[..., None]
            return np.cos(ph) * e1 + np.sin(ph) * e2, np.ones(a.shape, bool)
        g11 = np.einsum("...i,...i->...", Sa, Sa)
        g12 = np.einsum("...i,...i->...", Sa, St)
        g22 = np.einsum("...i,...i->...", St, St)
        det = g11 * g22 - g12 * g12
        if np.any(det <= 1e-24 * g11 * np.maximum(g22, 1e-300)):
            bad = det <= 1e-24 * g11 * np.maximum(g22, 1e-300)
            raise DegenerateGeometryError(
                f"S_a and S_t are parallel at {int(bad.sum())} sample(s) (the path runs along the tool axis, or "
                f"P'(t) = 0), e.g. t = {float(t[bad][0]):.6g}: the envelope degenerates"
            )
        A11 = g22 / det
        A21 = -g12 / det
        disc = 1.0 - ra * ra * A11
        ok = disc >= 0
        if check and not np.all(ok):
            bad = ~ok
            raise DegenerateGeometryError(
                f"no real envelope at {int(bad.sum())} sample(s): 1 - r'^2 A11 < 0 "
                f"(e.g. a = {float(a[bad][0]):.6g} mm, "
                f"t = {float(t[bad][0]):.6g}); the motion runs too close to the axis for this "
                f"{'cone' if self.segment.kind == 'cone' else 'profile'}",
                {"at": np.stack([a[bad], t[bad]], 1)[:20].tolist()},
            )
        ns = _unit(np.cross(Sa, St))
        n = (
            (-A11 * ra)[..., None] * Sa
            + (-A21 * ra)[..., None] * St
            + (self.side * np.sqrt(np.maximum(disc, 0)))[..., None] * ns
        )
        return n, ok

    def points(self, a, t):
        """Envelope points X(a, t) (mm) on broadcast arrays."""
        S, _, _, r, _, _ = self.frame(a, t)
        n, _ = self.normals(a, t)
        return S + r[..., None] * n

    def grid(self, as_, ts):
        """X on the grid of ``as_`` by ``ts``, shape ``(len(as_), len(ts), 3)`` (for the approximation engine)."""
        A_, T_ = np.meshgrid(np.asarray(as_, float), np.asarray(ts, float), indexing="ij")
        return self.points(A_, T_)


def tool_segment(cutter: Cutter, which: str | int = "side") -> SphereFamilySegment:
    """The sphere-family segment of a cutter that sweeps the envelope.

    ``"side"``: the flank (cylinder/cone side, the drum/barrel arc, the ball's sphere); an
    integer picks a segment of :meth:`Cutter.sphere_family` by index.
    """
    fam = cutter.sphere_family()
    if isinstance(which, int):
        if not 0 <= which < len(fam):
            raise InputError(f"segment index {which} out of range ({len(fam)} segment(s))")
        return fam[which]
    return cutter.sweep_segment()


def make_envelope(motion: Motion, tool, *, side: int = 1, segment="side", a_range=None, name: str = "pass") -> Envelope:
    c = parse_cutter(tool) if isinstance(tool, str) else tool
    seg = tool_segment(c, segment)
    return Envelope(motion, c, seg, side, tuple(a_range) if a_range else (), name)


# ----------------------------------------------------------------------------- adjacent passes
def next_pass(
    prev: Envelope,
    tool=None,
    *,
    continuity: str = "g1",
    theta_deg: float = 0.0,
    kink_deg: float = 10.0,
    side: int | None = None,
    name: str | None = None,
) -> Envelope:
    """The next pass, whose ``a0`` end joins ``prev``'s ``a1`` end (Corollaries 5.2, 5.3, 5.5).

    G1: ``T2(t) + a0 A2(t) = S1(a1, t) + (r1(a1) - r2(a0)) n1(a1, t)`` (eq. (39)/(35)) and
    ``A2 . n1(a1, t) = -r2'(a0)`` (eq. (40)/(36)); among those axes, ``theta`` (degrees) turns A2
    about ``n1`` from the one nearest ``A1``. G0 (eq. (41)): the G1 axis turned by ``kink_deg``
    about the seam tangent, and the tip placed so the new tool still touches the seam curve.
    The new pass's sheet is chosen so that its normals agree with the previous ones at the seam.
    """
    if prev.is_ball:
        raise InputError("chaining passes needs a tool with an axial sphere family (not a ball's single sphere)")
    c2 = prev.cutter if tool is None else (parse_cutter(tool) if isinstance(tool, str) else tool)
    seg2 = tool_segment(c2)
    if seg2.kind == "point":
        raise InputError("the next pass needs a tool with an axial sphere family (not a ball)")
    if continuity not in ("g0", "g1"):
        raise InputError("continuity must be 'g0' or 'g1'")
    th = float(theta_deg)
    if not math.isfinite(th) or abs(th) >= 180.0:
        raise InputError(f"theta = {theta_deg!r} deg is outside (-180, 180)")
    a1 = prev.a_range[1]
    a0 = seg2.a0
    m1 = prev.motion
    motion2 = _joined_motion(prev, seg2, continuity, th, kink_deg)
    env2 = Envelope(motion2, c2, seg2, 1, (), name or f"{prev.name}+1")
    # pick the sheet whose normal agrees with the previous pass's at the seam
    tt = np.linspace(*m1.t_range, 7)
    n_prev = prev.normals(np.full(7, a1), tt)[0]
    n_new = env2.normals(np.full(7, a0), tt, check=False)[0]
    s = 1 if np.mean(np.einsum("ij,ij->i", n_prev, n_new)) >= 0 else -1
    if side is not None:
        s = side
    return Envelope(motion2, c2, seg2, s, (), env2.name)


def _joined_motion(prev: Envelope, seg2, continuity: str, th: float, kink_deg: float) -> Motion:
    """The next pass's motion along ``prev``'s seam: its axis and tip (G1: eqs. (39), (40); G0: eq. (41))."""
    a1 = prev.a_range[1]
    a0 = seg2.a0
    c = -float(seg2.r_a(a0))  # required A2 . n1
    r1a1 = float(prev.segment.r(a1))
    r2a0 = float(seg2.r(a0))
    m1 = prev.motion

    def seam(t):
        t = np.asarray(t, float)
        aa = np.full(t.shape, a1)
        S, _, _, r, _, A1 = prev.frame(aa, t)
        n1, _ = prev.normals(aa, t)
        return S, n1, A1, S + r[..., None] * n1

    def axis2(t):
        S, n1, A1, X = seam(t)
        m = A1 - np.einsum("...i,...i->...", A1, n1)[..., None] * n1
        m = _unit(m)
        k = np.cross(n1, m)
        m_th = math.cos(math.radians(th)) * m + math.sin(math.radians(th)) * k
        a2 = c * n1 + math.sqrt(max(0.0, 1 - c * c)) * m_th
        if continuity == "g0":
            tau = _unit(m1._d(lambda s: seam(s)[3], t))
            kk = math.radians(kink_deg)
            a2 = (
                a2 * math.cos(kk)
                + np.cross(tau, a2) * math.sin(kk)
                + tau * np.einsum("...i,...i->...", tau, a2)[..., None] * (1 - math.cos(kk))
            )
        return a2

    def tip2(t):
        S, n1, A1, X = seam(t)
        a2 = axis2(t)
        if continuity == "g1":
            centre = S + (r1a1 - r2a0) * n1
        else:
            # the sphere at a0 must touch the seam point X with a normal n2 orthogonal to the seam
            # tangent and with n2 . A2 = -r2'(a0) (envelope conditions (10), (12)): solve for n2
            tau = _unit(m1._d(lambda s: seam(s)[3], t))
            ap = a2 - np.einsum("...i,...i->...", a2, tau)[..., None] * tau
            na = np.linalg.norm(ap, axis=-1, keepdims=True)
            e = ap / na
            cc = np.clip(c / na[..., 0], -1, 1)
            w = np.cross(tau, e)
            w = w * np.sign(np.einsum("...i,...i->...", w, n1))[..., None]
            n2 = cc[..., None] * e + np.sqrt(1 - cc * cc)[..., None] * w
            centre = X - r2a0 * n2
        return centre - a0 * a2

    return Motion(tip2, axis2, m1.t_range, f"{m1.label} -> next ({continuity}, theta {th:g})").frozen()


def seam_report(e1: Envelope, e2: Envelope, n: int = 401) -> dict:
    """G0 gap (mm) and G1 angle (degrees) along the seam e1(a1, t) ~ e2(a0, t), on the exact maps."""
    t = np.linspace(*e1.motion.t_range, n)
    x1 = e1.points(np.full(n, e1.a_range[1]), t)
    x2 = e2.points(np.full(n, e2.a_range[0]), t)
    n1 = e1.normals(np.full(n, e1.a_range[1]), t)[0]
    n2 = e2.normals(np.full(n, e2.a_range[0]), t)[0]
    gap = np.linalg.norm(x1 - x2, axis=1)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n1, n2), -1, 1)))
    return {
        "max_gap_mm": float(gap.max()),
        "max_normal_angle_deg": float(ang.max()),
        "n_samples": n,
        "worst_t_gap": float(t[np.argmax(gap)]),
        "worst_t_angle": float(t[np.argmax(ang)]),
    }


def fold_check(e1: Envelope, e2: Envelope, n: int = 201) -> dict:
    """Does the next pass fold back over the previous one, or lose its real envelope?

    Fold back: the new surface leaves the seam backwards, ``X1_a(a1, t) . X2_a(a0, t) < 0``.
    No real envelope: ``1 - r'^2 A11 < 0`` anywhere on the new pass (checked on a grid).
    """
    t = np.linspace(*e1.motion.t_range, n)
    A, T = np.meshgrid(np.linspace(*e2.a_range, 41), t, indexing="ij")
    _, ok = e2.normals(A, T, check=False)
    if not ok.all():
        return {
            "folds_back": False,
            "fold_t": [],
            "min_cos_between_strips": None,
            "real_envelope": False,
            "n_no_envelope": int((~ok).sum()),
        }
    h1 = 1e-4 * (e1.a_range[1] - e1.a_range[0])
    h2 = 1e-4 * (e2.a_range[1] - e2.a_range[0])
    a1, a0 = e1.a_range[1], e2.a_range[0]
    d1 = (e1.points(np.full(n, a1), t) - e1.points(np.full(n, a1 - h1), t)) / h1
    d2 = (e2.points(np.full(n, a0 + h2), t) - e2.points(np.full(n, a0), t)) / h2
    cosang = np.einsum("ij,ij->i", _unit(d1), _unit(d2))
    folds = cosang < 0
    return {
        "folds_back": bool(folds.any()),
        "fold_t": t[folds].tolist()[:20],
        "min_cos_between_strips": float(cosang.min()),
        "real_envelope": True,
        "n_no_envelope": 0,
    }
