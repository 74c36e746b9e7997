"""Issue 28 on a real part: the impeller's hub (face 87 of the public turbo3d STEP, a full revolution under
ten blades) machined in 5 axes by tilting away and linking round the blades, run as a user runs the
command. The written path is checked again here by a brute force independent of the project's check:
every face sampled on a parameter grid inside its trimming, the tool body in closed form, every move
interpolated. Skipped where ../shared/real-parts is not present (its licences keep it out of the
repository)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import needs_kernel
from helpers import run, shared_part, trimmed_grid

import machsurf_cad as ms

pytestmark = [needs_kernel, pytest.mark.slow]


def _samples(faces, spacing: float) -> np.ndarray:
    """Every face on a parameter grid about ``spacing`` mm apart (by its poles' polygon, no shorter than the
    face), inside its trimming."""
    pts = []
    for f in faces:
        P = np.asarray(f.surface.poles, float)
        lengths = (np.linalg.norm(np.diff(P, axis=0), axis=-1).sum(axis=0).max(),
                   np.linalg.norm(np.diff(P, axis=1), axis=-1).sum(axis=1).max())  # fmt: skip
        pts.append(f.surface.evaluate(*trimmed_grid(f, lengths, spacing, 4, 4000)))
    return np.concatenate(pts)


def _bull_depth(P, tips, axes, R: float, r: float, L: float, tree) -> np.ndarray:
    """Per placement the deepest part sample inside a bull-nose body (radius ``R``, corner ``r``, ``L`` long):
    below its flat end at L the body is every point within ``r`` of its core (the disc of radius R - r from
    r up above the tip), so a sample's depth is the lesser of r less its distance to the core and its depth
    below L (closed form); -inf where no sample is near."""
    out = np.full(tips.shape[0], -np.inf)
    centres = tips + axes * (L / 2)
    for k, near in enumerate(tree.query_ball_point(centres, math.hypot(L / 2, R) + 0.5)):
        if not near:
            continue
        q = P[near] - tips[k]
        z = q @ axes[k]
        rho = np.linalg.norm(q - np.outer(z, axes[k]), axis=1)
        d = np.hypot(np.maximum(rho - (R - r), 0.0), np.maximum(r - z, 0.0))
        out[k] = float(np.minimum(r - d, L - z).max())  # the body ends flat at L (no shank beyond it)
    return out


def _placements(tp, kinds, step: float):
    """Tips and axes along the moves into the positions of move ``kinds``, every ``step`` mm and 1 deg, and
    which placements lie on a move between two cutting positions."""
    T, A, on = [], [], []
    is_cut = (tp.move == ms.Move.CUT) | (tp.move == ms.Move.APPROACH)
    for i in np.flatnonzero(np.isin(tp.move[1:], kinds)) + 1:
        a0, a1 = tp.axis[i - 1], tp.axis[i]
        turn = math.degrees(math.acos(float(np.clip(a0 @ a1, -1, 1))))
        n = int(max(np.linalg.norm(tp.tip[i] - tp.tip[i - 1]) / step, turn, 1)) + 1
        w = np.linspace(0, 1, n)[:, None]
        ax = a0 * (1 - w) + a1 * w
        T.append(tp.tip[i - 1] * (1 - w) + tp.tip[i] * w)
        A.append(ax / np.linalg.norm(ax, axis=1, keepdims=True))
        on.append(np.full(n, bool(is_cut[i - 1] and is_cut[i])))
    return np.concatenate(T), np.concatenate(A), np.concatenate(on)


def test_impeller_hub_between_the_blades_is_machined_by_tilting_away_and_linking_round_them(tmp_path):
    """Face 87, bull D4 r1, lead 5 deg, tilt away within lead 40 deg and tilt +-90 deg: the path is written,
    covers more than half of the face, is clean under the whole-part check against all 92 faces, and no
    sample of any face (0.3 mm apart) lies deeper than the gouge tolerance in the tool on a move at feed
    (cutting, approaching, retracting), nor touches the tool at all on a rapid."""
    from scipy.spatial import cKDTree

    from machsurf_cad.occ import read_step_faces

    step = shared_part("turbo3d_impeller.step")
    res = run("machining-surface", step, "--face", 87, "--axes", 5, "--tool", "bull:D=4,r=1", "--lead", 5,
                         "--max-lead", 40, "--max-tilt", 90, "--toolpath", "-o", tmp_path / "out")  # fmt: skip
    assert res.returncode == 0, res.stderr
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert rep["machined_area_fraction"] > 0.5
    assert rep["verify"]["verdict"] == "trimmed" and rep["verify"]["trimmed"]["recheck"]["clean"]
    tp = ms.read_csv(tmp_path / "out" / "toolpath.csv")
    faces = read_step_faces(step)
    P = _samples(faces, 0.3)
    tree = cKDTree(P)
    M = ms.Move
    T, A, on = _placements(tp, [M.CUT, M.APPROACH, M.RETRACT], 0.25)
    depth = _bull_depth(P, T, A, 2.0, 1.0, 12.0, tree)
    assert depth.max() <= 0.01  # samples only under-read a depth: none deeper than the tolerance
    assert np.mean(depth[on] > -0.05) > 0.95  # and the tool is at the part along the cuts
    T, A, _ = _placements(tp, [M.RAPID], 1.0)
    assert _bull_depth(P, T, A, 2.0, 1.0, 12.0, tree).max() < 0.0  # a rapid touches nothing
