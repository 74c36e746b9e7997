"""Tool-body verification: a 5-axis path of 10^4 positions over a 262-face part (the plate with 256 holes),
against the brute-force way at about the same accuracy: every face sampled every 0.2 mm (chord sag of a
D10 ball about 1e-3 mm), the signed distance of every sample within reach of every placement, no
refinement. Goal: under 5 s for ours."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np


def _path(n: int):
    import machsurf_cad as ms

    rows = int(np.sqrt(n))
    tips, axes = [], []
    for k in range(rows):
        y = -100 + 200 * k / (rows - 1)
        x = np.linspace(-100, 100, n // rows)
        if k % 2:
            x = x[::-1]
        t = np.stack([x, np.full_like(x, y), np.full_like(x, 5.0)], 1)
        tilt = np.radians(10 * np.sin(x / 40.0))
        a = np.stack([np.sin(tilt), np.zeros_like(x), np.cos(tilt)], 1)
        tips.append(t)  # a ball touching the top face z = 5 whatever the axis: the tip is its lowest point only
        axes.append(a)  # for the vertical axis; with a tilt the ball's centre stays r above the surface
    centre = [t + 5.0 * np.array([0, 0, 1.0]) for t in tips]
    tips = [c - 5.0 * a for c, a in zip(centre, axes)]  # tip = centre - r * axis: the ball touches z = 5
    return ms.ToolPath.from_passes(tips, axes, cutter=ms.BallEndMill(10))


def _brute(faces, tp, spacing=0.2):
    from scipy.spatial import cKDTree

    from machsurf_cad.gougecheck import _placements, _sample_face

    P = np.concatenate([_sample_face(f, spacing)[0] for f in faces])
    tree = cKDTree(P)
    T, A, owner = _placements(tp, 1.0, 1.0)
    c = tp.cutter
    worst = np.inf
    for s in range(0, T.shape[0], 256):
        lists = tree.query_ball_point(T[s : s + 256] + A[s : s + 256] * (c.length / 2), np.hypot(c.length / 2, c.D / 2))
        for j, idx in enumerate(lists):
            if not idx:
                continue
            rel = P[idx] - T[s + j]
            z = rel @ A[s + j]
            rho = np.linalg.norm(rel - z[:, None] * A[s + j], axis=1)
            worst = min(worst, float(c.cutting_distance_rz(rho, z).min()))
    return worst, P.shape[0]


def verify_rows(quick=False):
    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_faces

    from .bench_step import _plate

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "plate.step"
        _plate(path, 256)
        faces = read_step_faces(path)
    n = 1000 if quick else 10000
    tp = _path(n)
    t = time.perf_counter()
    res = ms.verify(faces, tp, gouge_tolerance=0.01)
    t_ours = time.perf_counter() - t
    t = time.perf_counter()
    brute, n_pts = _brute(faces, tp, 0.4 if quick else 0.2)
    t_ref = time.perf_counter() - t
    ours = float(res.cut_distance.min())
    return [
        {
            "name": f"verify {tp.n_positions} positions, {len(faces)} faces",
            "n": tp.n_positions,
            "ours_s": t_ours,
            "ref_s": t_ref,
            "ref": f"brute cloud ({n_pts} pts)",
            "max_diff": abs(ours - brute),
        }
    ]
