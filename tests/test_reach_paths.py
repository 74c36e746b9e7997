"""Fixed-axis paths cut down to the tool's reach and skim-linked (issue 28, items 1, 3 and 5).

The figures are checked against a closed form (the floor area a ball can reach beside a boss) and the
written path against a brute force written here: the tool body against dense samples of every face,
every move interpolated.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import needs_kernel

import machsurf_cad as ms
from machsurf_cad import BallEndMill, builders
from machsurf_cad.cam.toolpath import Move, ToolPath

R = 3.0


def _pocket_with_boss():
    """A floor 60 x 60 at z = 0 with a boss 10 x 20, 8 high, on it (its top and four walls)."""
    floor = builders.plane_patch((-30, -30, 0), (60, 0, 0), (0, 60, 0), name="floor")
    x0, x1, y0, y1, h = 0.0, 10.0, -10.0, 10.0, 8.0
    top = builders.plane_patch((x0, y0, h), (x1 - x0, 0, 0), (0, y1 - y0, 0), name="boss top")
    walls = [
        builders.plane_patch((x0, y0, 0), (0, y1 - y0, 0), (0, 0, h), name="wall -x"),
        builders.plane_patch((x1, y0, 0), (0, 0, h), (0, y1 - y0, 0), name="wall +x"),
        builders.plane_patch((x0, y0, 0), (0, 0, h), (x1 - x0, 0, 0), name="wall -y"),
        builders.plane_patch((x0, y1, 0), (x1 - x0, 0, 0), (0, 0, h), name="wall +y"),
    ]
    return floor, [floor, top, *walls]


def _samples(faces, step):
    pts = []
    for f in faces:
        P = np.asarray(f.poles, float).reshape(-1, 3)
        size = np.ptp(P, axis=0).max()
        n = int(math.ceil(size / step)) + 1
        u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij")
        pts.append(f.evaluate(u.ravel(), v.ravel()))
    return np.concatenate(pts)


def _brute_force(tp: ToolPath, faces, step=0.25):
    """Per move: the least signed distance (mm) of the part's samples to the ball-ended tool over the move,
    every ``step`` mm; the body is the ball continued upwards by an infinite cylinder (a capsule), in
    closed form."""
    from scipy.spatial import cKDTree

    P = _samples(faces, step)
    tree = cKDTree(P[:, :2])
    moves, tips = [], []
    for i in range(1, tp.n_positions):
        a, b = tp.tip[i - 1], tp.tip[i]
        n = max(2, int(math.ceil(np.linalg.norm(b - a) / step)) + 1)
        w = np.linspace(0, 1, n)[:, None]
        tips.append(a * (1 - w) + b * w)
        moves.append(np.full(n, i))
    T, mv = np.concatenate(tips), np.concatenate(moves)
    out = np.full(tp.n_positions, np.inf)
    for k, near in enumerate(tree.query_ball_point(T[:, :2], R + 0.5)):
        if near:
            q = P[near] - T[k]
            rho = np.hypot(q[:, 0], q[:, 1])
            d = np.where(q[:, 2] <= R, np.sqrt(rho**2 + (q[:, 2] - R) ** 2) - R, rho - R)
            out[mv[k]] = min(out[mv[k]], float(d.min()))
    return out


@pytest.fixture(scope="module")
def boss_paths():
    floor, part = _pocket_with_boss()
    tool = BallEndMill(2 * R, length=20.0)
    surf = ms.machining_surface(floor, tool, axes=3, axis=(0, 0, 1))
    planned = ms.tool_paths(surf, stepover=2.0, safe_plane=ms.part_plane(part, clearance=5.0))
    out = ms.trim_to_reach(planned, part, gouge_tolerance=0.01, clearance=5.0, face=floor)
    return floor, part, planned, out


def test_planned_path_gouges_the_boss(boss_paths):
    _, part, planned, _ = boss_paths
    assert not ms.verify(part, planned).clean


def test_trimmed_path_is_clean_by_verify_and_by_brute_force(boss_paths):
    _, part, _, out = boss_paths
    assert ms.verify(part, out, gouge_tolerance=0.01).clean
    d = _brute_force(out, part)
    cutting = (out.move == Move.CUT) | (out.move == Move.APPROACH)
    assert d[cutting].min() > -0.01  # the cutting part at most the gouge tolerance into the part
    assert d[out.move == Move.RAPID].min() > 5.0 - 1e-9  # rapids keep the whole tool the clearance away
    assert d[out.move == Move.RETRACT].min() > -0.01  # a retract leaves a contact


def test_machined_area_against_closed_form(boss_paths):
    """A ball reaches the floor except within R of the boss's footprint (a rounded rectangle)."""
    _, _, _, out = boss_paths
    blocked = 10 * 20 + 2 * R * (10 + 20) + math.pi * R**2
    expected = 1 - blocked / 3600.0
    assert abs(out.info["machined_area_fraction"] - expected) < 0.03
    kept = out.extras["planned_index"]
    assert np.all(np.diff(kept[kept >= 0]) > 0)  # the kept positions in their planned order


def test_kept_positions_are_exactly_the_reachable_ones(boss_paths):
    """A floor position is kept iff the tool's disc there misses the boss's footprint (open disc)."""
    _, _, planned, out = boss_paths
    cutting = (planned.move == Move.CUT) | (planned.move == Move.APPROACH)
    t = planned.tip
    dx = np.maximum(np.maximum(0.0 - t[:, 0], t[:, 0] - 10.0), 0.0)
    dy = np.maximum(np.maximum(-10.0 - t[:, 1], t[:, 1] - 10.0), 0.0)
    reach = np.hypot(dx, dy) >= R - 1e-9
    kept = np.zeros(planned.n_positions, bool)
    kept[out.extras["planned_index"][out.extras["planned_index"] >= 0]] = True
    runs_of_one = cutting & reach & ~kept  # a lone reachable position between blocked ones is dropped
    assert not np.any(kept & ~reach)
    assert runs_of_one.sum() <= 2 * planned.n_passes


def test_links_go_over_the_boss_not_through(boss_paths):
    _, _, _, out = boss_paths
    rapid = out.move == Move.RAPID
    over = rapid & (np.abs(out.tip[:, 1]) < 10) & (out.tip[:, 0] > -R) & (out.tip[:, 0] < 10 + R)
    assert np.all(out.tip[over, 2] >= 8.0 + 5.0)
    assert out.info["links_skim"] == out.info["reach_runs"] - 1


def test_bad_input():
    floor, part = _pocket_with_boss()
    tp = ToolPath.from_passes([np.array([[0.0, 0, 0], [5, 0, 0]])], [np.array([[0.0, 0.6, 0.8]] * 2)])
    tilted = ToolPath.from_passes(
        [np.array([[0.0, 0, 0], [5, 0, 0]])], [np.array([[0.0, 0.6, 0.8], [0.0, 0, 1]])], cutter=BallEndMill(6)
    )
    with pytest.raises(ms.InputError, match="fixed tool axis"):
        ms.trim_to_reach(tilted, part)
    with pytest.raises(ms.InputError, match="reaches none"):  # every position inside the boss
        ms.trim_to_reach(
            ToolPath.from_passes([np.array([[2.0, 0, 0], [8, 0, 0]])], [np.array([[0.0, 0, 1]] * 2)],
                                 cutter=BallEndMill(6)), part)  # fmt: skip
    with pytest.raises(ms.InputError):
        ms.trim_to_reach(tp, part, tool="ball:D=6", clearance=-1)


@needs_kernel
def test_a_face_of_an_assembly_is_checked_against_every_solid_or_its_own(tmp_path):
    """A STEP of two solids: a plate and a lid 1 mm over it (another part of an assembly, like the pump's face
    731 and the shaft's body). The plate's top face checked against every face of the file: the lid leaves the
    ball no room, nothing is written, and the message says how to machine the face in its own solid; with
    --check-faces body it is machined against the plate alone: every position kept, clean by the brute force."""
    import json

    import cadquery as cq
    from helpers import run

    from machsurf_cad.occ import read_step_faces

    plate = cq.Workplane().box(40, 40, 5, centered=(True, True, False)).val()
    lid = cq.Workplane().workplane(offset=6).box(40, 40, 2, centered=(True, True, False)).val()
    step = tmp_path / "assembly.step"
    cq.exporters.export(cq.Compound.makeCompound([plate, lid]), str(step))
    faces = read_step_faces(step)
    assert [f.body for f in faces] == [0] * 6 + [1] * 6
    top = next(
        f.index for f in faces if f.body == 0 and np.allclose(np.ptp(f.surface.poles[..., 2]), 0)
        and abs(f.surface.poles[0, 0, 2] - 5) < 1e-9
    )  # fmt: skip
    args = ["machining-surface", step, "--face", top, "--axes", "3", "--tool", "ball:D=6", "--toolpath"]
    r = run(*args, "--stepover", 4, "-o", tmp_path / "all")
    assert r.returncode == 1 and "reaches none" in r.stderr and "--check-faces body" in r.stderr, r.stderr
    r = run(*args, "--stepover", 4, "--check-faces", "body", "-o", tmp_path / "own")
    assert r.returncode == 0, r.stderr
    assert "the 6 faces of body 0" in r.stdout
    rep = json.loads((tmp_path / "own" / "report.json").read_text())
    assert rep["verify"]["clean"] and rep["toolpath"]["reach_positions_trimmed"] == 0
    tp = ms.read_csv(tmp_path / "own" / "toolpath.csv")
    cut = tp.tip[tp.move == ms.Move.CUT]
    assert np.allclose(cut[:, 2], 5.0, atol=1e-6) and np.abs(cut[:, :2]).max() <= 20 + 1e-6
    assert _brute_force(tp, [f.surface for f in faces if f.body == 0]).min() > -0.01
    r = run(*args, "--check-faces", "0,1", "-o", tmp_path / "bad")
    assert r.returncode == 1 and "rest (every other face of the file) or body" in r.stderr
