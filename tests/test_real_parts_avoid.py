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
    """Per placement the deepest part sample inside an end mill's body (radius ``R``, corner ``r``: a ball
    for r = R, a flat end for r = 0; ``L`` long): for r > 0, below its flat end at L the body is every point
    within ``r`` of its core (the disc of radius R - r at r above the tip), so a sample's depth is the lesser
    of r less its distance to the core and its depth below L; for r = 0 the cylinder's depth
    min(R - rho, z, L - z) (closed forms; negative outside); -inf where no sample is near."""
    out = np.full(tips.shape[0], -np.inf)
    centres = tips + axes * (L / 2)
    for k, near in enumerate(tree.query_ball_point(centres, math.hypot(L / 2, R) + 0.5)):
        if not near:
            continue
        q = P[near] - tips[k]
        z = q @ axes[k]
        rho = np.linalg.norm(q - np.outer(z, axes[k]), axis=1)
        if r > 0:
            d = np.hypot(np.maximum(rho - (R - r), 0.0), np.maximum(r - z, 0.0))
            out[k] = float(np.minimum(r - d, L - z).max())  # the body ends flat at L (no shank beyond it)
        else:
            out[k] = float(np.minimum(np.minimum(R - rho, z), L - z).max())
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


def _brute_force(faces, tp, R: float, r: float, L: float, spacing: float, tol: float) -> None:
    """Every move of ``tp`` at feed: no face sample deeper than ``tol`` in the body (samples only under-read
    a depth) and the tool at the part along most cuts; every rapid: no sample in the body at all."""
    from scipy.spatial import cKDTree

    P = _samples(faces, spacing)
    tree = cKDTree(P)
    M = ms.Move
    T, A, on = _placements(tp, [M.CUT, M.APPROACH, M.RETRACT], 0.25)
    depth = _bull_depth(P, T, A, R, r, L, tree)
    assert depth.max() <= tol, depth.max()
    assert np.mean(depth[on] > -0.05 - spacing) > 0.9  # the tool is at the part along the cuts
    if np.any(tp.move[1:] == M.RAPID):
        T, A, _ = _placements(tp, [M.RAPID], 1.0)
        assert _bull_depth(P, T, A, R, r, L, tree).max() < 0.0  # a rapid touches nothing


def _machining_surface(tmp_path, part: str, *args):
    from machsurf_cad.occ import read_step_faces

    step = shared_part(part)
    res = run("machining-surface", step, *args, "--toolpath", "-o", tmp_path / "out")
    assert res.returncode == 0, res.stderr
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    return rep, ms.read_csv(tmp_path / "out" / "toolpath.csv"), read_step_faces(step), res.stdout


def test_propeller_blade_in_3_plus_2_is_trimmed_to_what_the_ball_reaches(tmp_path):
    """Face 42 of the public propeller (a blade), ball D10 along a fixed axis tilted 58 deg from +Z: the
    positions where the ball would reach into the hub or the next blade are cut out and the stretches linked
    clear; written, clean against all 77 faces, almost all of the face, and clean under the brute force."""
    rep, tp, faces, _ = _machining_surface(tmp_path, "ampath_propeller.stp", "--face", 42, "--axes", 3,
                                           "--tool", "ball:D=10", "--axis", "0.83,-0.181,-0.528")  # fmt: skip
    assert rep["verify"]["verdict"] == "clean" and rep["verify"]["n_faces"] == 77
    assert rep["toolpath"]["machined_area_fraction"] > 0.9  # 97.8 % measured
    assert rep["toolpath"]["reach_positions_trimmed"] > 0 and rep["toolpath"]["links_skim"] > 0
    assert rep["verify"]["rapids"]["rapid_distance_min_mm"] >= 5.0 - 1e-6
    _brute_force(faces, tp, 5.0, 5.0, rep["tool"]["length"], 0.5, 0.01 + 0.005)


def test_propeller_blade_in_5_axes_with_a_bull_is_trimmed_where_no_tilt_clears(tmp_path):
    """Face 42, bull D16 r3 at lead 10 deg, tilt away within lead 30 and tilt +-30 deg: the planned path
    runs 8 mm into the hub; no orientation within the limits clears the hub's corner (one region reported),
    so that stretch is cut out and the rest linked clear: written, clean, more than 90 % of the face, and
    clean under the brute force."""
    args = ("--face", 42, "--tool", "bull:D=16,r=3", "--lead", 10, "--max-lead", 30, "--max-tilt", 30)
    rep, tp, faces, out = _machining_surface(tmp_path, "ampath_propeller.stp", *args)
    ta = rep["tilt_away"]
    assert ta["n_regions_clear_nowhere"] >= 1 and ta["lattice_points_clear_nowhere"] > 0
    assert "lattice points tilted" in out and "region(s) no orientation clears" in out
    v = rep["verify"]
    assert v["verdict"] == "trimmed" and v["max_gouge_mm"] > 1.0 and v["trimmed"]["recheck"]["clean"]
    assert v["trimmed"]["links_direct"] + v["trimmed"]["links_over_surface"] > 0
    assert rep["machined_area_fraction"] > 0.9  # 96.0 % measured
    _brute_force(faces, tp, 8.0, 3.0, rep["tool"]["length"], 0.5, 0.01 + 0.01)


def test_impeller_blade_side_is_flank_milled_clear_of_the_hub(tmp_path):
    """Face 2 of the impeller (a ruled blade side), cylinder D6 at its optimum setting: the rules whose
    cylinder would enter the hub are lifted along the axis or left out, written clean against all 92 faces,
    more than half of the rules' length in contact, and clean under the brute force (the setting's own error
    into face 2 is within the 0.05 mm tolerance)."""
    from machsurf_cad.occ import read_step_faces

    step = shared_part("turbo3d_impeller.step")
    res = run("flank", step, "--face", 2, "--tool", "cyl:D=6", "--whole", "--tolerance", 0.05, "-o", tmp_path / "o")
    assert res.returncode == 0, res.stderr
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    w = rep["whole"]
    assert w["verify"]["verdict"] == "clean" and w["verify"]["n_faces"] == 92
    cl = w["clear_of_part"]
    assert cl["machined_fraction"] > 0.5 and cl["n_rules_lifted"] > 0 and cl["rules_left_out"]
    tp = ms.read_csv(tmp_path / "o" / "toolpath.csv")
    _brute_force(read_step_faces(step), tp, 3.0, 0.0, w["tool_length_mm"], 0.3, 0.05 + 0.005)


def test_pump_bore_is_machined_in_its_own_solid(tmp_path):
    """Face 731 of the pump (a conical bore of body 5 of 6 solids, facing down), ball D6 along -Z, checked
    against its own solid (--check-faces body; the shaft's and the housing's solids fill the bore in the
    assembly): written, clean against the solid's 33 faces, more than half of the face, and clean under the
    brute force against those faces."""
    rep, tp, faces, out = _machining_surface(tmp_path, "ventpump.stp", "--face", 731, "--axes", 3, "--axis",
                                             "0,0,-1", "--tool", "ball:D=6", "--check-faces", "body")  # fmt: skip
    assert "--check-faces body" in out and rep["verify"]["n_faces"] == 33 and rep["verify"]["verdict"] == "clean"
    assert rep["toolpath"]["machined_area_fraction"] > 0.5  # 60.7 % measured
    body = faces[731].body
    _brute_force([f for f in faces if f.body == body], tp, 3.0, 3.0, rep["tool"]["length"], 0.3, 0.01 + 0.005)
