"""The faces a 3-axis job drops the tool on, in the tool-axis frame, with seed samples and edges.

A :class:`FaceSet` holds the part's faces rotated so that the tool axis is +z (the rotation is exact:
B-spline poles rotate), a trim-aware grid of samples on each face (none on a vertical face,
:func:`is_vertical`: its edges hold its every contact) and samples along every trimming edge (the
parameter box's sides for an untrimmed face) and every crease (an iso-parameter line at a knot
where the surface is only C0, inside the trimming: ``z - h`` can peak there with no stationary point on
either side, so the crease is searched as an edge is). The samples only seed the exact contact search of
:mod:`machsurf_cad.threeaxis.dropcutter`; no result is read off them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..geometry.atlas import SurfaceAtlas
from ..geometry.bspline import BSplineCurve, BSplineSurface
from ..geometry.builders import line_segment
from ..geometry.face import Face
from ..gougecheck import face_size


def axis_frame(axis) -> np.ndarray:
    """Rotation matrix whose rows are ``(e1, e2, axis)``: world -> tool frame (tool axis = +z).

    For ``axis = +z`` it is the identity; otherwise ``e1`` is the world x (or y) made orthogonal to
    the axis, so that 3+2 results keep a predictable in-plane orientation."""
    a = np.asarray(axis, float).reshape(3)
    n = float(np.linalg.norm(a))
    if not np.isfinite(n) or n < 1e-12:
        raise InputError("the tool axis must be a non-zero vector")
    a = a / n
    ref = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = ref - (ref @ a) * a
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return np.stack([e1, e2, a])


def rotated_surface(s: BSplineSurface, frame: np.ndarray) -> BSplineSurface:
    """The surface with its poles mapped by ``frame`` (exact for a rotation)."""
    if np.allclose(frame, np.eye(3), atol=0, rtol=0):
        return s
    return s.with_poles(np.asarray(s.poles) @ frame.T, s.weights)


def _box_edges(face: Face) -> list[BSplineCurve]:
    u0, u1, v0, v1 = face.uv_bounds
    return [
        line_segment([u0, v0], [u1, v0]),
        line_segment([u1, v0], [u1, v1]),
        line_segment([u1, v1], [u0, v1]),
        line_segment([u0, v1], [u0, v0]),
    ]


def _creases(face: Face, n: int = 257) -> list[BSplineCurve]:
    """The face's creases: its iso-parameter lines at interior knots of multiplicity at least the degree
    (the surface only C0 there, so ``z - h`` can peak on the line with no stationary point on either side),
    as uv segments, cut to where the line lies inside the trimmed face: ``n`` samples per line (a run inside
    between two neighbouring samples, both outside, is not found: there the face's own solves remain), each
    run's ends refined to about 1e-11 of the line by :func:`_last_inside`. The drop-cutter searches them as
    it does edges. All lines of the face share each trimming test."""
    s = face.surface
    u0, u1, v0, v1 = face.uv_bounds
    lines = []  # (knot, 0: u fixed / 1: v fixed, lo, hi)
    for knots, mults, p, along in ((s.knots_u, s.mults_u, s.degree_u, 0), (s.knots_v, s.mults_v, s.degree_v, 1)):
        vals, counts = np.asarray(knots, float), np.asarray(mults)
        for k in vals[1:-1][counts[1:-1] >= p]:
            if (u0 < k < u1) if along == 0 else (v0 < k < v1):
                lines.append((float(k), along, *((v0, v1) if along == 0 else (u0, u1))))
    if not lines:
        return []
    L = np.array(lines, float)
    runs: list[tuple[int, float, float]] = []
    if not face.is_trimmed:
        runs = [(i, L[i, 2], L[i, 3]) for i in range(len(L))]
    else:
        t = L[:, 2:3] + (L[:, 3:4] - L[:, 2:3]) * np.linspace(0.0, 1.0, n)
        ok = face.contains_uv(*_iso_uv(L, np.arange(len(L))[:, None], t)).reshape(t.shape)
        found = []  # (line, start or stop index, outside t, inside t)
        spans = []
        for i in range(len(L)):
            starts = np.flatnonzero(ok[i] & ~np.r_[False, ok[i, :-1]])
            stops = np.flatnonzero(ok[i] & ~np.r_[ok[i, 1:], False])
            spans.append((starts, stops))
            found += [(i, a, t[i, a - 1], t[i, a]) for a in starts if a > 0]
            found += [(i, b, t[i, b + 1], t[i, b]) for b in stops if b < n - 1]
        ends = {}
        if found:
            F = np.array(found, float)
            for (i, a, _, _), x in zip(found, _last_inside(face, L, F[:, 0].astype(int), F[:, 2], F[:, 3])):
                ends[(i, a)] = x
        for i, (starts, stops) in enumerate(spans):
            for a, b in zip(starts, stops):
                ta = t[i, a] if a == 0 else ends[(i, a)]
                tb = t[i, b] if b == n - 1 else ends[(i, b)]
                if tb > ta:
                    runs.append((i, float(ta), float(tb)))
    out = []
    for i, ta, tb in runs:
        u, v = _iso_uv(L, np.array([i, i]), np.array([ta, tb]))
        out.append(line_segment([u[0], v[0]], [u[1], v[1]]))
    return out


def _iso_uv(L: np.ndarray, line, t):
    """``(u, v)`` of parameters ``t`` on iso-lines ``line`` (rows of ``L``: knot, fixed, lo, hi), flattened."""
    line, t = np.broadcast_arrays(np.asarray(line), np.asarray(t, float))
    k, fixed_v = L[line, 0], L[line, 1] == 1
    return np.where(fixed_v, t, k).ravel(), np.where(fixed_v, k, t).ravel()


def _last_inside(face: Face, L, line, out_t, in_t, m: int = 65, rounds: int = 5) -> np.ndarray:
    """Per iso-line ``line`` with a parameter ``out_t`` outside the trimmed face and ``in_t`` inside, the last
    parameter inside between them: ``rounds`` rounds of ``m`` points between the current ends, one trimming
    test per round for all of them."""
    out_t, in_t = np.array(out_t, float), np.array(in_t, float)
    f = np.linspace(0.0, 1.0, m)
    rows = np.arange(in_t.size)
    for _ in range(rounds):
        ts = in_t[:, None] + (out_t - in_t)[:, None] * f  # from inside (f = 0) towards outside (f = 1)
        ok = face.contains_uv(*_iso_uv(L, line[:, None], ts)).reshape(ts.shape)
        ok[:, 0] = True
        k = np.where(ok.all(axis=1), m - 2, np.argmin(ok, axis=1) - 1)  # the last inside before the first out
        in_t, out_t = ts[rows, k], ts[rows, k + 1]
    return in_t


def _length_3d(s: BSplineSurface, c: BSplineCurve) -> float:
    t = np.linspace(*c.bounds, 33)
    uv = c.evaluate(t)
    p = s.evaluate(uv[:, 0], uv[:, 1])
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def _edge_rise(c: BSplineCurve, t, de, half: float) -> np.ndarray:
    """Per edge sample: how much z can rise along the edge within ``half`` of it (mm): its tangent's slope
    there plus the tangent's largest turn per mm between samples (1.5 times, as the faces' bound), over an arc
    a tenth longer than the chord; never more than ``half`` (``|dz| <= |dP|``)."""
    duv = c.derivatives(t, 1)[:, 1, :]
    tan = de.su * duv[:, :1] + de.sv * duv[:, 1:2]
    ln = np.linalg.norm(tan, axis=1)
    with np.errstate(all="ignore"):
        u = tan / ln[:, None]
        tz = np.abs(u[:, 2])
        seg = np.linalg.norm(np.diff(de.point, axis=0), axis=1)
        turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[1:], u[:-1]), -1, 1)) / seg
    if not (np.all(np.isfinite(tz)) and np.all(np.isfinite(turn))):
        return np.full(len(t), half)  # a degenerate tangent somewhere: the chord's bound
    kappa = 1.5 * float(turn.max(initial=0.0))
    return np.minimum(half, 1.1 * half * (tz + kappa * half))


def _stray(face: Face) -> np.ndarray:
    """How far (parameter units, u then v) the face's parameter box and trimming curves reach outside its
    surface's knot domain: 0 where a curve's poles (which hold it) lie inside, else from 1025 points along
    the curve plus the bulge of the curve between them (an eighth of its largest second difference)."""
    s = face.surface
    k = np.array(s.bounds, float)  # the spline's domain (an open knot vector's is inside its first and last knot)
    out = np.zeros(2)

    def reach(lo_u, hi_u, lo_v, hi_v, pad=(0.0, 0.0)):  # np.max: a NaN parameter gives NaN, then inf
        out[0] = np.max([out[0], k[0] - lo_u + pad[0], hi_u - k[1] + pad[0]])
        out[1] = np.max([out[1], k[2] - lo_v + pad[1], hi_v - k[3] + pad[1]])

    reach(*face.uv_bounds)
    for loop in face.loops if face.is_trimmed else ():
        for c in loop:
            P = np.asarray(c.poles, float).reshape(-1, 2)
            if P[:, 0].min() >= k[0] and P[:, 0].max() <= k[1] and P[:, 1].min() >= k[2] and P[:, 1].max() <= k[3]:
                continue
            uv = c.evaluate(np.linspace(*c.bounds, 1025))
            bulge = np.abs(np.diff(uv, 2, axis=0)).max(axis=0) / 8 if uv.shape[0] > 2 else np.zeros(2)
            reach(uv[:, 0].min(), uv[:, 0].max(), uv[:, 1].min(), uv[:, 1].max(), tuple(bulge))
    return np.where(np.isfinite(out), out, np.inf)


def hull_top(face: Face, stray: np.ndarray | None = None) -> float:
    """A height no point of the face reaches above (mm, the tool frame's z): its surface's highest pole (the
    convex hull property of a B-spline; its weights are positive), raised by twice the most z can climb
    over the stretch (:func:`_stray`) by which its parameter box or trimming curves leave the knot domain,
    where the surface is extrapolated. ``inf`` when that stretch is over a thousandth of the shortest knot
    span (there the climb is not bounded so). ``stray``: the face's :func:`_stray`, when known."""
    s = face.surface
    Z = np.asarray(s.poles, float)[..., 2]
    w = np.ones_like(Z) if s.weights is None else np.asarray(s.weights, float).reshape(Z.shape)
    top = float(Z.max())
    stray = _stray(face) if stray is None else stray
    if not np.any(stray > 0):
        return top
    margin = 0.0
    for d, knots, p in ((0, s.knots_u, s.degree_u), (1, s.knots_v, s.degree_v)):
        if stray[d] == 0:
            continue
        spans = np.diff(np.asarray(knots, float))
        short = float(spans[spans > 0].min()) if np.any(spans > 0) else 0.0
        if not (stray[d] <= 1e-3 * short):
            return math.inf
        # |dz/du| <= 2 p (w_max / w_min) (z_max - z_min) / (shortest span): the rational derivative's bound
        margin += 2.0 * (2 * p * float(w.max() / w.min()) * float(np.ptp(Z)) / short) * float(stray[d])
    return top + margin


def is_vertical(face: Face, stray: np.ndarray | None = None) -> bool:
    """Whether the face stands along the tool axis (z) so that no point inside it can carry a contact: its
    surface's plan position ``(x, y)`` does not depend on one parameter, along which z rises strictly.

    Exact on the poles: along that parameter (not periodic) every row of poles keeps its x, y and weight, and
    every row's z strictly rises (or every row's strictly falls). Then the surface's z along it is a
    B-spline of strictly monotone coefficients (the weights of the other parameter, positive, mix the
    rows), so from any point inside the face the tool's axis distance stays and z rises: the highest value
    of ``z - h(rho)`` over the face, and of z on any circle, lies on its trimming edges (sampled and
    searched as edges). Where the face's box or trimming curves leave the spline's domain (:func:`_stray`;
    a CAD system's rounding), the surface is extrapolated: taken along that parameter only at degree 1 (z
    stays linear), across it only where each row's z is one value (z then does not depend on the other
    parameter), and never by more than a thousandth of the shortest knot span. A vertical plane, a hole's
    cylinder and a wall extruded along z are vertical faces. ``stray``: the face's :func:`_stray`, when
    known."""
    s = face.surface
    P = np.asarray(s.poles, float)
    if P.ndim != 3 or not np.all(np.isfinite(P)):
        return False
    W = np.ones(P.shape[:2]) if s.weights is None else np.asarray(s.weights, float).reshape(P.shape[:2])
    stray = None
    for d, degree, periodic in ((0, s.degree_u, s.periodic_u), (1, s.degree_v, s.periodic_v)):
        Q, Wq = np.moveaxis(P, d, 0), np.moveaxis(W, d, 0)
        if periodic or Q.shape[0] < 2 or np.any(Q[:, :, :2] != Q[:1, :, :2]) or np.any(Wq != Wq[:1]):
            continue  # (a periodic row wraps from its last pole back to its first: z climbs, then falls)
        dz = np.diff(Q[:, :, 2], axis=0)
        if not (np.all(dz > 0) or np.all(dz < 0)):
            continue
        stray = _stray(face) if stray is None else stray
        if not np.any(stray > 0):
            return True
        spans = [np.diff(np.asarray(k, float)) for k in (s.knots_u, s.knots_v)]
        short = min(float(x[x > 0].min()) if np.any(x > 0) else 0.0 for x in spans)
        along_ok = stray[d] == 0 or degree == 1
        across_ok = stray[1 - d] == 0 or bool(np.all(Q[:, :, 2] == Q[:, :1, 2]))
        if along_ok and across_ok and bool(np.all(stray <= 1e-3 * short)):
            return True
    return False


def capped_rise(rise: np.ndarray, z: np.ndarray, top: float) -> np.ndarray:
    """``rise`` (how much higher than ``z`` the face gets near each sample, mm) cut to what the face's
    :func:`hull_top` allows (nothing is cut where it is ``inf``): the bounds of the samples at the top of a
    face (a wall's upper edge, a plateau's rim) then stop at its height instead of rising by the sample
    spacing above it."""
    return np.minimum(rise, np.maximum(top - z, 0.0))


def _closed(P) -> tuple[bool, bool]:
    """Whether the face's parameter box closes on itself along u and along v (a full revolution: a
    cylinder, torus or revolved face whose seam is inside the face), from its sample grid."""
    tol = 1e-7 * max(float(np.ptp(P.reshape(-1, 3), axis=0).max()), 1.0)
    cu = bool(np.abs(P[0] - P[-1]).max() <= tol)
    cv = bool(np.abs(P[:, 0] - P[:, -1]).max() <= tol)
    return cu, cv


def _slope(su, sv) -> np.ndarray:
    """``|n_xy|``: the largest rise of z per mm along the surface (1 where the normal is undefined)."""
    n = np.cross(su, sv)
    ln = np.linalg.norm(n, axis=-1)
    with np.errstate(all="ignore"):
        out = np.hypot(n[..., 0], n[..., 1]) / ln
    return np.where(np.isfinite(out), out, 1.0).reshape(-1)


def _slopes(d, nu: int, nv: int):
    """Per grid sample ``|n_xy|``; the grid's cover radius (mm: the longest cell diagonal, so every face
    point lies within it of a sample or of an edge sample); a bound on the normal's turning per mm."""
    P = d.point
    du = np.linalg.norm(np.diff(P, axis=0), axis=-1)
    dv = np.linalg.norm(np.diff(P, axis=1), axis=-1)
    delta = float(math.hypot(du.max(), dv.max()))
    n = np.cross(d.su, d.sv)
    with np.errstate(all="ignore"):
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        tu = np.arccos(np.clip(np.einsum("ijk,ijk->ij", n[1:], n[:-1]), -1, 1)) / np.maximum(du, 1e-12)
        tv = np.arccos(np.clip(np.einsum("ijk,ijk->ij", n[:, 1:], n[:, :-1]), -1, 1)) / np.maximum(dv, 1e-12)
    turns = np.concatenate([tu[np.isfinite(tu)].ravel(), tv[np.isfinite(tv)].ravel(), [0.0]])
    kappa = 1.5 * float(turns.max()) if np.all(np.isfinite(n)) else 1.0 / max(delta, 1e-9)
    return _slope(d.su, d.sv), delta, kappa


@dataclass(frozen=True, eq=False)
class FaceSet:
    """Faces in the tool frame with seed samples (see module docstring).

    Attributes
    ----------
    faces : tuple of Face
        The faces, surfaces rotated into the tool frame (trimming unchanged: same parameters).
    frame : ndarray (3, 3)
        World -> tool frame rotation (rows e1, e2, axis).
    spacing : float
        Seed sample spacing on the faces and edges (mm).
    closed : ndarray (n_faces, 2)
        Whether each face closes on itself along u, v (local solves wrap across its seam).
    bounds : ndarray (n_faces, 4)
        Each face's parameter box.
    min_tilt : ndarray
        Per sample: a lower bound of ``|n_xy|`` (the sine of the surface's slope) within its cover radius.
    edge_cover : ndarray
        Per edge sample: half the largest distance between neighbouring samples of its edge (every
        point of the edge lies within it of a sample; z rises by at most as much along it).
    edge_rise : ndarray
        Per edge sample: how much z can rise along the edge within its ``edge_cover`` (mm; at most that).
    cover, rise : ndarray
        Per sample (face samples, then edge samples): a radius (mm) within which of some sample every
        face point lies, and a bound on how much higher z gets within it (mm), from the sample's slope
        and the face's largest normal turning between samples, and at most up to the face's ``face_top``.
        They bound what a local solve can gain over a sample, so seeds that cannot beat a known contact
        are skipped.
        The edge samples of a vertical face have a cover of ``-inf`` (and rise ``-inf``, ``min_tilt``
        ``inf``): they seed and bound no face or rim solve, only their edge's search.
    face_top : ndarray (n_faces,)
        Per face: no point of it is higher (mm, :func:`hull_top`; ``inf`` where that is not known).
    face_vertical : ndarray (n_faces,) of bool
        Per face: whether it is vertical (:func:`is_vertical`): its trimming edges hold its every contact,
        and it has no samples inside it.
    names : tuple of str
        The faces' names, as given.
    """

    faces: tuple
    frame: np.ndarray
    spacing: float
    names: tuple
    sample_xyz: np.ndarray = field(repr=False)
    sample_uv: np.ndarray = field(repr=False)
    sample_face: np.ndarray = field(repr=False)
    edges: tuple = field(repr=False)
    edge_face: np.ndarray = field(repr=False)
    edge_xyz: np.ndarray = field(repr=False)
    edge_t: np.ndarray = field(repr=False)
    edge_uv: np.ndarray = field(repr=False)
    edge_id: np.ndarray = field(repr=False)
    edge_dt: np.ndarray = field(repr=False)
    tree: cKDTree = field(repr=False)
    cover: np.ndarray = field(repr=False)
    rise: np.ndarray = field(repr=False)
    closed: np.ndarray = field(repr=False)
    bounds: np.ndarray = field(repr=False)
    edge_cover: np.ndarray = field(repr=False)
    min_tilt: np.ndarray = field(repr=False)
    edge_rise: np.ndarray = field(repr=False)
    face_top: np.ndarray = field(repr=False)
    face_vertical: np.ndarray = field(repr=False)

    @cached_property
    def edge_loop(self) -> np.ndarray:
        """Per edge: whether it closes on itself (a loop of one curve, a hole's circle): its parameter then
        runs on across the seam (a search window at the seam sees both sides)."""
        out = np.zeros(len(self.edges), bool)
        for e, c in enumerate(self.edges):
            uv = c.evaluate(np.array(c.bounds, float))
            P = self.faces[self.edge_face[e]].surface.evaluate(uv[:, 0], uv[:, 1])
            out[e] = bool(np.linalg.norm(P[0] - P[1]) <= 1e-9 * max(1.0, float(np.abs(P).max())))
        return out

    @cached_property
    def edge_bounds(self) -> np.ndarray:
        """Per edge its parameter range, ``(n_edges, 2)``."""
        return np.array([e.bounds for e in self.edges], float).reshape(-1, 2)

    def on_edge(self, eid, t) -> np.ndarray:
        """Parameters ``t`` of edges ``eid`` kept within their ranges; a closed edge's run on (its seam)."""
        b = self.edge_bounds[eid]
        return np.where(self.edge_loop[eid], t, np.clip(t, b[..., 0], b[..., 1]))

    @cached_property
    def atlas(self) -> SurfaceAtlas:
        """The faces' surfaces, evaluated together (one vectorised pass per degree pair)."""
        return SurfaceAtlas([f.surface for f in self.faces])

    @cached_property
    def pool_xyz(self) -> np.ndarray:
        """The pool's samples: face samples, then edge samples (the k-d tree's order), ``(n, 3)``."""
        return np.concatenate([self.sample_xyz, self.edge_xyz])

    @cached_property
    def pool_face(self) -> np.ndarray:
        """The face of each pool sample (an edge sample's: its edge's face)."""
        return np.concatenate([self.sample_face, self.edge_face[self.edge_id]]).astype(np.int64)

    @cached_property
    def pool_uv(self) -> np.ndarray:
        """The face parameters ``(u, v)`` of each pool sample."""
        return np.concatenate([self.sample_uv, self.edge_uv])

    @cached_property
    def pool_extent(self) -> tuple[int, np.ndarray, np.ndarray, float]:
        """Number of face and edge samples, their plan box (``lo``, ``hi``) and the diagonal of their 3-D box
        (mm): what the drop-cutter sizes its work by."""
        xyz = self.pool_xyz
        if xyz.shape[0] == 0:
            return 0, np.zeros(2), np.zeros(2), 0.0
        return (int(xyz.shape[0]), xyz[:, :2].min(axis=0), xyz[:, :2].max(axis=0),
                float(np.linalg.norm(np.ptp(xyz, axis=0))))  # fmt: skip

    @property
    def n_samples(self) -> int:
        return int(self.sample_xyz.shape[0] + self.edge_xyz.shape[0])

    def to_world(self, p) -> np.ndarray:
        """Tool-frame points back to world coordinates."""
        return np.asarray(p, float) @ self.frame

    def to_frame(self, p) -> np.ndarray:
        """World points in the tool frame."""
        return np.asarray(p, float) @ self.frame.T


def grid_counts(face: Face, spacing: float) -> tuple[int, int]:
    """The seed grid's numbers of samples along u and v of ``face`` (``spacing`` mm apart, at least 5): the
    samples are ``linspace(u0, u1, nu)`` x ``linspace(v0, v1, nv)`` over its parameter bounds."""
    lu, lv = (max(x, 1e-9) for x in face_size(face))
    return int(max(5, math.ceil(lu / spacing) + 1)), int(max(5, math.ceil(lv / spacing) + 1))


def face_set(faces, *, axis=(0.0, 0.0, 1.0), spacing: float, max_samples: int = 5_000_000) -> FaceSet:
    """Rotate ``faces`` into the frame of ``axis`` and sample them ``spacing`` mm apart (at least 5 x 5
    per face and 4 per edge, so small faces and short edges are seeded too)."""
    spacing = float(spacing)
    if not (spacing > 0 and math.isfinite(spacing)):
        raise InputError(f"seed spacing must be > 0 mm, got {spacing}")
    frame = axis_frame(axis)
    out_faces, names = [], []
    P, UV, F = [], [], []
    edges: list[BSplineCurve] = []
    EF, EP, ET, EI, EDT, EUV = [], [], [], [], [], []
    COV, RISE, ECOV, ERISE, CLOSED, EALONG, FLAT, EFLAT, EZ, TOP = [], [], [], [], [], [], [], [], [], []
    VERT: list[bool] = []
    total = 0
    for i, f in enumerate(faces):
        if isinstance(f, BSplineSurface):
            f = Face(f, name=f.name or f"face_{i}")
        if not isinstance(f, Face):
            raise InputError("the 3-axis job needs the part's faces (Face or BSplineSurface objects)")
        s = rotated_surface(f.surface, frame)
        face = Face(s, f.loops, f.name, f.index, f.reversed, f.source_type, f.uv_bounds, f.area)
        out_faces.append(face)
        names.append(f.name or f"face_{i}")
        u0, u1, v0, v1 = face.uv_bounds
        nu, nv = grid_counts(face, spacing)
        total += nu * nv
        if total > max_samples:
            raise InputError(
                f"seed spacing {spacing:g} mm needs more than {max_samples:,} samples: use a larger spacing"
            )
        us, vs = np.linspace(u0, u1, nu), np.linspace(v0, v1, nv)
        U, V = np.meshgrid(us, vs, indexing="ij")
        d = s.derivatives_grid(us, vs, 1)
        CLOSED.append(_closed(d.point))
        pts = d.point.reshape(-1, 3)
        slope, delta, kappa = _slopes(d, nu, nv)
        stray = _stray(face)  # (both read it: it evaluates the trimming curves that leave the knot domain)
        top = hull_top(face, stray)
        TOP.append(top)
        keep = face.contains_uv_grid(us, vs).ravel() if face.is_trimmed else np.ones(U.size, bool)
        vertical = is_vertical(face, stray)
        VERT.append(vertical)
        if vertical:  # its edges hold every contact: no sample inside it seeds or bounds one
            keep[:] = False
        P.append(pts[keep])
        UV.append(np.stack([U.ravel()[keep], V.ravel()[keep]], axis=1))
        F.append(np.full(int(keep.sum()), i))
        COV.append(np.full(int(keep.sum()), delta))
        RISE.append(capped_rise(delta * np.minimum(1.0, slope[keep] + kappa * delta), pts[keep, 2], top))
        FLAT.append(np.maximum(slope[keep] - kappa * delta, 0.0))
        curves = [c for loop in face.loops for c in loop] if face.is_trimmed else _box_edges(face)
        curves += _creases(face)
        for c in curves:
            n = int(max(4, math.ceil(_length_3d(s, c) / spacing) + 1))
            t = np.linspace(*c.bounds, n)
            uv = c.evaluate(t)
            de = s.derivatives(uv[:, 0], uv[:, 1], 1)
            EP.append(de.point)
            e_slope = _slope(de.su, de.sv)
            if vertical:  # nor do its edge samples, but as its edges' seeds and bounds
                ECOV.append(np.full(n, -np.inf))
                ERISE.append(np.full(n, -np.inf))
                EFLAT.append(np.full(n, np.inf))
            else:
                ECOV.append(np.full(n, delta))
                ERISE.append(capped_rise(delta * np.minimum(1.0, e_slope + kappa * delta), de.point[:, 2], top))
                EFLAT.append(np.maximum(e_slope - kappa * delta, 0.0))
            half = 0.5 * float(np.linalg.norm(np.diff(de.point, axis=0), axis=1).max())
            EALONG.append(np.full(n, half))
            EZ.append(capped_rise(_edge_rise(c, t, de, half), de.point[:, 2], top))
            ET.append(t)
            EUV.append(uv)
            EI.append(np.full(n, len(edges)))
            EDT.append(np.full(n, (t[-1] - t[0]) / (n - 1)))
            EF.append(i)
            edges.append(c)
    if not out_faces:
        raise InputError("the 3-axis job needs at least one face")
    sample_xyz = np.concatenate(P)
    edge_xyz = np.concatenate(EP)
    tree = cKDTree(np.concatenate([sample_xyz[:, :2], edge_xyz[:, :2]]))
    return FaceSet(
        tuple(out_faces),
        frame,
        spacing,
        tuple(names),
        sample_xyz,
        np.concatenate(UV),
        np.concatenate(F),
        tuple(edges),
        np.asarray(EF, int),
        edge_xyz,
        np.concatenate(ET),
        np.concatenate(EUV),
        np.concatenate(EI),
        np.concatenate(EDT),
        tree,
        np.concatenate(COV + ECOV),
        np.concatenate(RISE + ERISE),
        np.array(CLOSED, bool).reshape(-1, 2),
        np.array([f.uv_bounds for f in out_faces], float),
        np.concatenate(EALONG),
        np.concatenate(FLAT + EFLAT),
        np.concatenate(EZ),
        np.array(TOP, float),
        np.array(VERT, bool),
    )
