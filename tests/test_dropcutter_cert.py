"""The compiled drop-cutter's certificate of a flat end's rim contact (:mod:`._jit_cert`), checked by brute force:
every point of the face in the certified parameter box and inside the tool's disc lies at most
``CERT_SLACK`` above the contact."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

import machsurf_cad as ms
from machsurf_cad.geometry.builders import surface_from_grid
from machsurf_cad.threeaxis import compiled
from machsurf_cad.threeaxis.dropcutter import Contact

needs_numba = pytest.mark.skipif(not compiled.available(), reason="numba is not installed")
ROOT = Path(__file__).resolve().parents[1]
R = 5.0


def _certify(fs, f, xyz, cx, cy):
    """The certificate at the contact ``xyz`` of face ``f``: (found, box, u, v)."""
    from machsurf_cad.threeaxis._jit_cert import rim_certificate

    s = fs.faces[f].surface
    u0, u1, v0, v1 = fs.faces[f].uv_bounds
    us, vs = np.linspace(u0, u1, 201), np.linspace(v0, v1, 201)
    P = s.evaluate_grid(us, vs).reshape(-1, 3)
    k = int(np.argmin(np.linalg.norm(P - xyz, axis=1)))
    start = np.array([us[k // 201], vs[k % 201]])
    sol = least_squares(lambda w: s.evaluate(w[:1], w[1:])[0] - xyz, start, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    u, v = sol.x
    box = np.full(4, -1.0)
    S = compiled._packed(fs)[0]
    ok = rim_certificate(S, f, float(u), float(v), float(cx), float(cy), R, float(xyz[2]), box)
    return ok, box, u, v


def _brute_top(fs, f, box, cx, cy, n=401):
    """The highest point of face ``f`` in ``box`` (clipped to its bounds) inside the disc, on an n x n grid over
    the part of the box that holds the disc's points (found on a 201 x 201 grid of the whole box first: a box
    that runs on across knot lines can be several times the disc)."""
    u0, u1, v0, v1 = fs.faces[f].uv_bounds
    lo_u, hi_u, lo_v, hi_v = max(box[0], u0), min(box[1], u1), max(box[2], v0), min(box[3], v1)
    us, vs = np.linspace(lo_u, hi_u, 201), np.linspace(lo_v, hi_v, 201)
    P = fs.faces[f].surface.evaluate_grid(us, vs).reshape(201, 201, 3)
    iu, iv = np.nonzero(np.hypot(P[..., 0] - cx, P[..., 1] - cy) <= R)
    if iu.size == 0:
        return -np.inf
    us = np.linspace(us[max(iu.min() - 1, 0)], us[min(iu.max() + 1, 200)], n)
    vs = np.linspace(vs[max(iv.min() - 1, 0)], vs[min(iv.max() + 1, 200)], n)
    P = fs.faces[f].surface.evaluate_grid(us, vs).reshape(-1, 3)
    inside = np.hypot(P[:, 0] - cx, P[:, 1] - cy) <= R
    return P[inside, 2].max() if inside.any() else -np.inf


def _patch(f, half=40.0):
    """A bicubic patch with poles on ``z = f(x, y)`` over ``[-half, half]^2`` (7 x 7 poles: four knot spans)."""
    g = np.linspace(-half, half, 7)
    X, Y = np.meshgrid(g, g, indexing="ij")
    return surface_from_grid(np.stack([X, Y, f(X, Y)], axis=2))


@needs_numba
def test_certificate_on_a_tilted_plane_holds_and_refuses_where_it_must():
    plane = _patch(lambda x, y: 0.2 * x)  # (the poles lie on the plane: so does the patch)
    fs = ms.threeaxis.faceset.face_set([plane], spacing=10 / 6)
    r = ms.drop_cutter(None, ms.FlatEndMill(10), [[1.0, 2.0]], face_set=fs)
    assert r.kind[0] == Contact.RIM and abs(r.height[0] - 0.2 * 6.0) <= 1e-9  # the uphill point of the rim
    ok, box, u, v = _certify(fs, 0, fs.to_frame(r.contact)[0], 1.0, 2.0)
    assert ok and box[0] < u < box[1] and box[2] < v < box[3]
    top = _brute_top(fs, 0, box, 1.0, 2.0)
    # the box holds the contact (above); its grid's highest point in the disc lies within a sample spacing of
    # it (0.03 mm: 0.006 mm lower on this slope)
    assert top <= r.height[0] + 5e-11 and top >= r.height[0] - 1e-2
    # the downhill point of the same circle is no rim maximum: no certificate
    ok, _, _, _ = _certify(fs, 0, np.array([-4.0, 2.0, -0.8]), 1.0, 2.0)
    assert not ok


@needs_numba
def test_certificate_refuses_a_point_that_is_a_minimum_along_the_circle():
    """A patch near ``z = 0.2 x + 0.5 y^2``: at its point ``p`` on the circle of radius R about ``p - (R, 0)``
    the face rises outwards (``mu > 0``) but also both ways along the circle: no rim maximum, no certificate."""
    s = _patch(lambda x, y: 0.2 * x + 0.5 * y**2, half=20.0)
    fs = ms.threeaxis.faceset.face_set([s], spacing=1.0)
    p = s.evaluate(np.array([0.6]), np.array([0.5]))[0]
    cx, cy = p[0] - R, p[1]
    # the premise, by brute force: the face on the circle 1 degree either side of p is higher than p
    for deg in (-1.0, 1.0):
        q = np.array([cx + R * np.cos(np.radians(deg)), cy + R * np.sin(np.radians(deg))])
        w = least_squares(lambda w, q=q: s.evaluate(w[:1], w[1:])[0, :2] - q, [0.6, 0.5], xtol=1e-15, ftol=1e-15).x
        on = s.evaluate(w[:1], w[1:])[0]
        assert np.linalg.norm(on[:2] - q) < 1e-9 and on[2] > p[2] + 1e-3
    ok, _, _, _ = _certify(fs, 0, p, cx, cy)
    assert not ok


@needs_numba
def test_certificates_on_the_example_block_hold_by_brute_force():
    """Rim contacts of a flat D10 on the block's curved top: most are certified, and in every certified box
    the face inside the disc is at most 5e-11 mm above the contact (401 x 401 samples of the box); and asked
    for a height 1e-3 mm below a contact (which the contact itself exceeds), the certificate refuses."""
    pytest.importorskip("OCP")
    from machsurf_cad.occ import read_step_faces
    from machsurf_cad.threeaxis._jit_cert import rim_certificate

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    cutter = ms.FlatEndMill(10)
    fs = ms.threeaxis.faceset.face_set(faces, spacing=ms.threeaxis.dropcutter.default_seed_spacing(cutter))
    rng = np.random.default_rng(3)
    _, lo, hi, _ = fs.pool_extent
    xy = lo + (hi - lo) * rng.random((60, 2))
    r = ms.drop_cutter(None, cutter, xy, face_set=fs)
    rim = np.nonzero((r.kind == Contact.RIM) & (r.face == 0))[0][:24]
    assert rim.size >= 20
    found = 0
    S = compiled._packed(fs)[0]
    for k in rim:
        ok, box, u, v = _certify(fs, 0, fs.to_frame(r.contact[k : k + 1])[0], *xy[k])
        low = float(r.height[k]) - 1e-3
        assert not rim_certificate(S, 0, float(u), float(v), float(xy[k, 0]), float(xy[k, 1]), R, low, box.copy())
        if ok:
            found += 1
            assert _brute_top(fs, 0, box, *xy[k]) <= r.height[k] + 5e-11
    assert found >= 0.8 * rim.size


@needs_numba
def test_certificates_across_knot_lines_hold_by_brute_force():
    """On a bumpy bicubic patch of 4 x 4 pieces (random poles), boxes of rim contacts near a knot line go on
    across it where the neighbouring piece's polynomial bounds the face there (:func:`._jit_cert._neighbour`):
    at least 5 of them cross a knot line, and in every box the face inside the disc is at most 5e-11 mm above
    the contact. These contacts are the disc's highest points, so that brute force holds for any box; what
    can fail is the certificate's own test, asked here for a height 1e-3 mm below each contact, which the
    contact itself (on the disc's rim, in its box) exceeds: it must refuse. Whether a box leaves out a higher
    neighbouring piece: :func:`test_a_box_crosses_a_knot_line_only_where_the_next_piece_stays_below`."""
    from machsurf_cad.threeaxis._jit_cert import rim_certificate

    rng = np.random.default_rng(11)
    bumps = rng.normal(0.0, 1.2, (7, 7))
    s = _patch(lambda x, y: 0.15 * x + 0.1 * y + bumps)
    fs = ms.threeaxis.faceset.face_set([s], spacing=10 / 6)
    xy = rng.uniform(-28.0, 28.0, (80, 2))
    r = ms.drop_cutter(None, ms.FlatEndMill(10), xy, face_set=fs)
    rim = np.nonzero(r.kind == Contact.RIM)[0]
    assert rim.size >= 40
    ku, kv = (np.unique(k)[1:-1] for k in (s.knots_u, s.knots_v))  # the interior knot lines
    certified = crossing = 0
    S = compiled._packed(fs)[0]
    for k in rim:
        ok, box, u, v = _certify(fs, 0, fs.to_frame(r.contact[k : k + 1])[0], *xy[k])
        low = float(r.height[k]) - 1e-3
        assert not rim_certificate(S, 0, float(u), float(v), float(xy[k, 0]), float(xy[k, 1]), R, low, box.copy())
        if ok:
            certified += 1
            crossing += bool(np.any((ku > box[0]) & (ku < box[1])) or np.any((kv > box[2]) & (kv < box[3])))
            assert _brute_top(fs, 0, box, *xy[k]) <= r.height[k] + 5e-11
    assert certified >= 0.6 * rim.size and crossing >= 5


def _creased(rise):
    """A bicubic patch over [-20, 20]^2 with a C0 knot line at x = 0 (a triple knot) between two pieces:
    ``z = 0.2 y`` on the left piece, ``z = 0.2 y + rise x`` on the right one (its poles on that plane)."""
    from machsurf_cad.geometry.bspline import BSplineSurface

    x, y = np.linspace(-20, 20, 7), np.linspace(-20, 20, 4)
    X, Y = np.meshgrid(x, y, indexing="ij")
    P = np.stack([X, Y, 0.2 * Y + rise * np.maximum(X, 0.0)], axis=2)
    return BSplineSurface(3, 3, [0.0, 1.0, 2.0], [4, 3, 4], [0.0, 1.0], [4, 4], P)


@needs_numba
@pytest.mark.parametrize("rise", [0.0, -0.05, 0.2])
def test_a_box_crosses_a_knot_line_only_where_the_next_piece_stays_below(rise):
    """A flat D10 at (-0.5, 0) on :func:`_creased`: its rim contact (-0.5, 5) is the highest point of the left
    piece in the disc, 0.5 mm from the crease. Where the right piece is the same plane, or falls away from the
    crease, the certified box goes on across the knot line into it; where it rises (0.2 mm/mm: inside the
    disc it gets 0.3 mm above the contact) the box stops at the knot line. Either way no point of the disc
    in the box is above the contact (brute force)."""
    s = _creased(rise)
    fs = ms.threeaxis.faceset.face_set([s], spacing=10 / 6)
    cx, cy = -0.5, 0.0
    xyz = np.array([cx, cy + R, 0.2 * (cy + R)])
    ok, box, u, v = _certify(fs, 0, xyz, cx, cy)
    assert ok and np.linalg.norm(s.evaluate(np.array([u]), np.array([v]))[0] - xyz) < 1e-9
    G = s.evaluate_grid(np.linspace(1.0, 2.0, 201), np.linspace(0.0, 1.0, 201)).reshape(-1, 3)
    right_top = G[np.hypot(G[:, 0] - cx, G[:, 1] - cy) <= R, 2].max()  # the right piece's highest in the disc
    assert (right_top > xyz[2] + 0.05) == (rise > 0)
    assert (box[1] > 1.0) == (rise <= 0)  # across the knot line (u = 1) where the right piece stays below
    assert _brute_top(fs, 0, box, cx, cy) <= xyz[2] + 5e-11


def _cornered(rise, corner=2.15):
    """A bicubic patch over ``s, t`` in [-20, 20] with C0 knot lines at ``s = t = corner`` (triple knots), in plan
    ``x = s - t, y = s + t`` (its knot lines run at 45 degrees): ``z = 0.2 y`` on three pieces and ``0.2 y + rise
    (corner - s)(corner - t)`` on the fourth (``s, t < corner``; bilinear there, so its poles lie on it)."""
    from machsurf_cad.geometry.bspline import BSplineSurface

    g = np.concatenate([np.linspace(-20, corner, 4), np.linspace(corner, 20, 4)[1:]])
    Sg, Tg = np.meshgrid(g, g, indexing="ij")
    P = np.stack([Sg - Tg, Sg + Tg, 0.2 * (Sg + Tg) + rise * np.maximum(corner - Sg, 0) * np.maximum(corner - Tg, 0)],
                 axis=2)  # fmt: skip
    return BSplineSurface(3, 3, [-20.0, corner, 20.0], [4, 3, 4], [-20.0, corner, 20.0], [4, 3, 4], P)


@needs_numba
@pytest.mark.parametrize("rise", [0.0, -0.005, 0.2])
def test_a_box_takes_in_the_diagonal_piece_only_where_it_stays_below(rise):
    """A flat D10 at the origin on :func:`_cornered`: its rim contact (0, 5) lies 0.35 from both knot lines, on
    the piece past both, so the disc reaches the two side pieces and the diagonal one. The side pieces are the
    same plane; the diagonal one is too (rise 0), falls away (-0.005) or rises (0.2: 3.3 mm above the contact
    inside the disc). The box crosses both knot lines where the diagonal piece stays below and only the u one
    where it rises; either way no point of the disc in the box is above the contact (brute force). (A diagonal
    piece that falls away steeply is refused too: the bound takes its cross term ``st`` into ``lam`` and its
    linear terms one at a time, which leaves the falling piece's rise along each knot line; refusing is safe.)"""
    s = _cornered(rise)
    fs = ms.threeaxis.faceset.face_set([s], spacing=10 / 6)
    xyz = np.array([0.0, R, 0.2 * R])
    ok, box, u, v = _certify(fs, 0, xyz, 0.0, 0.0)
    assert ok and abs(u - 2.5) < 1e-9 and abs(v - 2.5) < 1e-9
    G = s.evaluate_grid(np.linspace(-20, 2.15, 201), np.linspace(-20, 2.15, 201)).reshape(-1, 3)
    diagonal_top = G[np.hypot(G[:, 0], G[:, 1]) <= R, 2].max()  # the diagonal piece's highest in the disc
    assert (diagonal_top > xyz[2] + 1.0) == (rise > 0)
    assert box[0] < 2.15  # across the u knot line: the side piece is the same plane
    assert (box[2] < 2.15) == (rise <= 0)  # across the v one too where the diagonal piece stays below
    assert _brute_top(fs, 0, box, 0.0, 0.0) <= xyz[2] + 5e-11
