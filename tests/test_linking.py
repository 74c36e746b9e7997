"""Links that never cross the part (issue 28, item 1): direct where clear, over the clearance surface
else, a stretch no clear link reaches left out and reported.

The part is a floor with a bridge over it (a plate 12 mm up over 0 <= x <= 20): a short tool (ball D6,
body 10 mm long) cuts under the bridge, where nothing may come down from above. The links are checked
by the tool-body check and by a closed form written here: the body against the plate.
"""

from __future__ import annotations

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad import BallEndMill, builders
from machsurf_cad.cam.toolpath import Move
from machsurf_cad.linking import link_runs

TOOL = BallEndMill(6, length=10.0)


def _part():
    floor = builders.plane_patch((-30, -30, 0), (80, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((0, -30, 12), (20, 0, 0), (0, 60, 0), name="bridge")
    return [floor, bridge]


def _runs():
    ys = np.linspace(-20, 20, 21)
    out = []
    for k, x in enumerate((-10.0, 10.0, 30.0)):
        y = ys if k % 2 == 0 else ys[::-1]
        tips = np.column_stack([np.full(y.size, x), y, np.zeros(y.size)])
        out.append((tips, np.tile([0.0, 0, 1], (y.size, 1)), tips.copy()))
    return out


def _through_bridge(tp, step=0.1, length=10.0, xs=(0.0, 20.0), ys=(-np.inf, np.inf)) -> float:
    """Deepest the body (radius 3, from the tip up ``length`` mm) overlaps the plate 12 mm up over
    ``xs`` x ``ys``, over every move sampled every ``step`` mm (closed form: the axis's plan distance to the
    plate's footprint)."""
    worst = 0.0
    for a, b in zip(tp.tip[:-1], tp.tip[1:]):
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / step)) + 1)
        for t in a + np.linspace(0, 1, n)[:, None] * (b - a):
            d = np.hypot(max(xs[0] - t[0], t[0] - xs[1], 0.0), max(ys[0] - t[1], t[1] - ys[1], 0.0))
            if d < 3.0 and t[2] < 12.0 < t[2] + length:
                worst = max(worst, min(3.0 - d, t[2] + length - 12.0))
    return worst


def test_direct_links_under_the_bridge():
    tp = link_runs(_runs(), _part(), TOOL, clearance=1.0)
    assert tp.info["links_direct"] == 2 and tp.info["runs_left_out"] == []
    low = link_runs(_runs(), _part(), TOOL, clearance=5.0)  # a 5 mm lift hits the bridge: the 1 mm one does not
    assert low.info["links_direct"] == 2 and low.info["runs_left_out"] == [] and _through_bridge(low) == 0.0
    assert ms.verify(_part(), tp).clean
    assert _through_bridge(tp) == 0.0
    assert tp.n_cut == 63


def test_a_run_no_link_reaches_is_left_out_not_crossed():
    """A body 11.5 mm long fits under the bridge (12 mm up) but any lift (5 mm, or the 1 mm of the low
    direct link) takes it into the bridge: the middle run cannot be reached or left, and is left out."""
    tool = BallEndMill(6, length=11.5)
    tp = link_runs(_runs(), _part(), tool, clearance=5.0)
    assert tp.info["runs_left_out"] == [1]
    assert len(tp.info["gaps_not_linked"]) == 1
    assert tp.info["gaps_not_linked"][0]["to_mm"] == [10.0, 20.0, 0.0]
    assert ms.verify(_part(), tp, tool).clean
    assert _through_bridge(tp, length=11.5) == 0.0
    assert tp.n_cut == 42
    rapid = tp.move == Move.RAPID
    assert tp.tip[rapid, 2].max() == pytest.approx(17.0)  # over the plane 5 mm above the part


def test_nothing_reachable_is_an_input_error():
    runs = [r for k, r in enumerate(_runs()) if k == 1]
    with pytest.raises(ms.InputError, match="crossing the part"):
        link_runs(runs, _part(), TOOL, clearance=5.0)


def test_check_toolpath_trims_and_links_without_crossing():
    """A path through the bridge's pillar-free span, planned too low under it: trimmed and relinked."""
    part = _part()
    runs = _runs()
    tips = [r[0] for r in runs]
    tips[1] = tips[1] + [0, 0, 3.0]  # the middle pass 3 mm up: its body reaches into the bridge
    planned = ms.ToolPath.from_passes(tips, [r[1] for r in runs], cutter=TOOL, clearance=1.0)
    pc = ms.check_toolpath(planned, part, on_gouge="trim", clearance=1.0)
    assert pc.verdict == "trimmed"
    assert pc.recheck.clean and _through_bridge(pc.toolpath) == 0.0
    cut = pc.toolpath.tip[(pc.toolpath.move == Move.CUT) | (pc.toolpath.move == Move.APPROACH)]
    assert set(cut[:, 0].tolist()) == {-10.0, 30.0}  # the middle pass, under the bridge, is cut out
    assert pc.toolpath.n_cut == 2 * 41  # the 2 mm moves of the two others split in two to trim finely


def test_trimmed_machined_area_against_closed_form():
    """Dense passes over a floor with a boss, trimmed by the body check: the share of the floor kept is
    the area a ball D6 reaches, all but the boss's footprint grown by R = 3 (a rounded rectangle)."""
    from test_reach_paths import _pocket_with_boss

    from machsurf_cad.pathcheck import machined_area_fraction

    floor, part = _pocket_with_boss()
    tool = BallEndMill(6, length=20.0)
    ys = np.arange(-29.0, 29.01, 0.5)
    tips = [np.column_stack([np.full(ys.size, x), ys if k % 2 == 0 else ys[::-1], np.zeros(ys.size)])
            for k, x in enumerate(np.arange(-29.0, 29.01, 2.0))]  # fmt: skip
    planned = ms.ToolPath.from_passes(tips, [np.tile([0.0, 0, 1], (ys.size, 1))] * len(tips), cc=tips, cutter=tool)
    pc = ms.check_toolpath(planned, part, on_gouge="trim", clearance=5.0)
    assert pc.verdict == "trimmed" and pc.recheck.clean
    kept = pc.toolpath.extras["planned_index"]
    frac = machined_area_fraction(floor, pc.trimmed_from or planned, kept[kept >= 0], step=0.25)
    expected = 1 - (10 * 20 + 2 * 3 * (10 + 20) + np.pi * 9) / 3600.0
    assert abs(frac - expected) < 0.02
    assert pc.toolpath.info["links_direct"] > 0 and pc.toolpath.info["runs_left_out"] == []


def test_a_run_whose_start_is_blocked_is_entered_reversed():
    """A bridge over the start side of every pass (y <= -10): the first pass's start cannot be approached from
    the plane above the part, its end can; entered at its end and cut backwards, it is kept, and the others are
    joined by 1 mm lifts under the bridge."""
    floor = builders.plane_patch((-30, -30, 0), (80, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((-20, -30, 12), (60, 0, 0), (0, 20, 0), name="bridge")
    part = [floor, bridge]
    tp = link_runs(_runs(), part, TOOL, clearance=5.0)
    assert tp.info["runs_left_out"] == [] and tp.info["runs_reversed"] == [0]
    assert ms.verify(part, tp).clean and tp.n_cut == 63
    cut = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)
    first = tp.tip[cut][:21]
    assert first[0].tolist() == [-10.0, 20.0, 0.0] and first[-1].tolist() == [-10.0, -20.0, 0.0]
    assert _through_bridge(tp, xs=(-20.0, 40.0), ys=(-30.0, -10.0)) == 0.0


def test_a_run_reached_only_from_another_is_visited_later():
    """A bridge over the whole first pass (x <= 0): nothing comes down onto it from the plane above the part,
    either way round; a 1 mm lift from the second pass reaches it under the bridge, and another leaves it
    for the third: the passes are cut in the order 1, 0, 2."""
    floor = builders.plane_patch((-30, -30, 0), (80, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((-20, -30, 12), (20, 0, 0), (0, 60, 0), name="bridge")
    part = [floor, bridge]
    tp = link_runs(_runs(), part, TOOL, clearance=5.0)
    assert tp.info["runs_left_out"] == [] and tp.info["runs_visited_later"] == [0]
    assert ms.verify(part, tp).clean and tp.n_cut == 63
    cut = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)
    order = [int(x) for x in dict.fromkeys(tp.tip[cut][:, 0].tolist())]
    assert order == [10, -10, 30]
    assert _through_bridge(tp, xs=(-20.0, 0.0)) == 0.0


def _capsule_clearance(tp, pts, R, step=0.25):
    """Least distance (mm) of ``pts`` to a ball-ended tool of radius ``R`` with an endless shank over every
    rapid move of ``tp``, tip and axis interpolated every ``step`` mm or 1 deg (closed form)."""
    worst = np.inf
    for i in np.flatnonzero(tp.move[1:] == Move.RAPID) + 1:
        t0, t1, a0, a1 = tp.tip[i - 1], tp.tip[i], tp.axis[i - 1], tp.axis[i]
        turn = np.degrees(np.arccos(np.clip(a0 @ a1, -1, 1)))
        n = int(max(np.linalg.norm(t1 - t0) / step, turn, 1)) + 1
        for w in np.linspace(0, 1, n):
            a = (1 - w) * a0 + w * a1
            a /= np.linalg.norm(a)
            c = (1 - w) * t0 + w * t1 + R * a
            q = pts - c
            s = q @ a
            d = np.where(s <= 0, np.linalg.norm(q, axis=1), np.linalg.norm(q - s[:, None] * a, axis=1)) - R
            worst = min(worst, float(d.min()))
    return worst


def test_links_over_a_cylinder_around_a_long_part():
    """A bar 100 x 10 mm along x: passes on its top, under it and at its end with the axis along the bar.
    The cylinder around it has the closed-form radius 5 + clearance and half length 50 + clearance; links
    over it clear the bar (closed form, every move interpolated), are far shorter than over the sphere, and
    the axis along the bar leaves beyond the end."""
    from machsurf_cad.cam.clearance import exit_cylinder

    bar = builders.plane_patch((0, -5, 0), (100, 0, 0), (0, 10, 0), name="bar")
    point, axis, radius, half = ms.part_cylinder([bar], clearance=5.0)
    assert np.allclose(point, [50, 0, 0]) and np.allclose(axis, [1, 0, 0])
    assert radius == pytest.approx(10.0) and half == pytest.approx(55.0)
    x = np.linspace(10, 90, 9)
    top = np.column_stack([x, np.zeros(9), np.zeros(9)])
    passes = [(top, np.tile([0.0, 0, 1], (9, 1))), (top[::-1], np.tile([0.0, 0, -1], (9, 1))),
              (np.array([[100.0, -3, 0], [100, 3, 0]]), np.tile([1.0, 0, 0], (2, 1)))]  # fmt: skip
    tips, axes = zip(*passes)
    cyl = ms.ToolPath.from_passes(tips, axes, safe_cylinder=(point, axis, radius, half))
    sph = ms.ToolPath.from_passes(tips, axes, safe_sphere=ms.part_sphere([bar], 5.0))
    u, v = np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 41), indexing="ij")
    pts = bar.evaluate(u.ravel(), v.ravel())
    assert _capsule_clearance(cyl, pts, 3.0) > 1.9  # clearance 5 less the ball's radius 3 at the pass ends
    assert cyl.link_length() < 0.6 * sph.link_length()
    ups = np.array([t[k] + 5.0 * a[k] for t, a in passes for k in (0, -1)])  # clearance off the passes' ends
    rapid = cyl.move == Move.RAPID
    rapid &= np.linalg.norm(cyl.tip[:, None, :] - ups[None], axis=2).min(axis=1) > 1e-9
    q = cyl.tip[rapid] - point
    rho = np.linalg.norm(q - np.outer(q @ axis, axis), axis=1)
    assert np.all((rho >= radius - 1e-9) | (np.abs(q @ axis) >= half - 1e-9))  # on the cylinder or past an end
    # an axis along the bar: out beyond the end's plane first, then out to the radius
    way = exit_cylinder(np.array([105.0, 0, 0]), np.array([1.0, 0, 0]), (point, axis, radius, half))
    assert np.allclose(way, [[105, 0, 0], [105, 10, 0]]) or np.allclose(way[0], [105, 0, 0])
    way = exit_cylinder(np.array([90.0, 1, 0]), np.array([1.0, 0, 0]), (point, axis, radius, half))
    assert np.allclose(way, [[105, 1, 0], [105, 10, 0]])


def test_clearance_surface_choice_and_bad_input():
    bar = builders.plane_patch((0, -5, 0), (100, 0, 0), (0, 10, 0), name="bar")
    plate = builders.plane_patch((0, 0, 0), (100, 0, 0), (0, 80, 0), name="plate")
    from machsurf_cad.linking import surface_for

    assert surface_for([bar], None, 5.0)[0] == "cylinder"
    assert surface_for([plate], None, 5.0)[0] == "sphere"
    assert surface_for([plate], (0, 0, 1), 5.0)[0] == "plane"
    assert surface_for([plate], None, 5.0, "cylinder", (0, 0, 1))[1][2] == pytest.approx(np.hypot(50, 40) + 5)
    with pytest.raises(ms.InputError, match="fixed tool axis"):
        surface_for([plate], None, 5.0, "plane")
    with pytest.raises(ms.InputError, match="auto, plane, sphere or cylinder"):
        surface_for([plate], None, 5.0, "cone")
    with pytest.raises(ms.InputError, match="non-zero"):
        ms.part_cylinder([plate], (0, 0, 0))


def _body_to_bridge(tip, parts, xs=(0.0, 20.0)) -> float:
    """Least distance (mm) of a vertical tool at ``tip`` to the floor (z = 0) and the bridge's plate (z = 12
    over ``xs``, |y| <= 30), closed form: the ball and each cylinder of the body (radius, z from, z to above
    the tip) against the plate's rectangle, the tip against the floor."""
    best = float(tip[2])
    plan = max(xs[0] - tip[0], tip[0] - xs[1], 0.0)
    for rad, z0, z1 in parts:
        dz = max(tip[2] + z0 - 12.0, 12.0 - tip[2] - z1, 0.0)
        best = min(best, float(np.hypot(max(plan - rad, 0.0), dz)))
    centre_z = tip[2] + 3.0  # the ball of radius 3
    best = min(best, float(np.hypot(plan, max(12.0 - centre_z, centre_z - 12.0, 0.0)) - 3.0))
    return best


def test_rapids_keep_the_clearance_from_the_holder():
    """Rapid distances are the whole tool's, holder included (issue 28, item 1). A ball D6 with a holder D20
    from 10 mm above its tip cuts the floor beside the bridge: at x = -13 the holder passes 3 mm from the
    bridge's edge while the cutting part is 10 mm away, so the moves up to the plane over the part and back
    down (4 of them) are made at the plunge feed where the holder is within 5 mm of the bridge: their first
    (last) 1 mm, up to a tip 6 mm high, where the holder's rim is 3 mm beside and 4 mm above the bridge's
    edge (5 mm, closed form), rapid beyond; at x = -17 (7 mm) they stay rapids, and the least rapid
    distance is the floor's 5 mm under the retract point. Every rapid left keeps 5 mm by the closed form,
    every move sampled every 0.1 mm."""
    floor = builders.plane_patch((-40, -30, 0), (100, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((0, -30, 12), (20, 0, 0), (0, 60, 0), name="bridge")
    part = [floor, bridge]
    tool = BallEndMill(6, length=10.0, holder=ms.Shank(20, 30))
    body = [(3.0, 3.0, 10.0), (10.0, 10.0, 40.0)]
    ys = np.linspace(-20, 20, 21)
    for xs, at_feed in (((-13.0, 33.0), 4), ((-17.0, 37.0), 0)):
        runs = []
        for k, x in enumerate(xs):
            t = np.column_stack([np.full(ys.size, x), ys if k == 0 else ys[::-1], np.zeros(ys.size)])
            runs.append((t, np.tile([0.0, 0, 1], (ys.size, 1)), t.copy()))
        pc = ms.check_toolpath(link_runs(runs, part, tool, clearance=5.0), part, clearance=5.0)
        tp = pc.toolpath
        assert pc.verdict == "clean" and tp.info["n_rapids_at_feed"] == at_feed
        assert pc.report()["rapids"]["n_rapids_at_feed"] == at_feed
        worst = np.inf
        for i in np.flatnonzero(tp.move[1:] == Move.RAPID) + 1:
            for w in np.linspace(0, 1, int(np.linalg.norm(tp.tip[i] - tp.tip[i - 1]) / 0.1) + 2):
                worst = min(worst, _body_to_bridge(tp.tip[i - 1] * (1 - w) + tp.tip[i] * w, body))
        assert worst >= 5.0 - 1e-9
        if at_feed:  # the feed moves are the ones the holder takes within 5 mm of the bridge
            slow = np.flatnonzero((tp.move[1:] != Move.RAPID) & (tp.move[1:] != Move.CUT)) + 1
            assert any(_body_to_bridge(tp.tip[i], body) < 5.0 for i in slow)
            assert tp.info["n_links_split"] == 4
            z = [sorted((tp.tip[i - 1, 2], tp.tip[i, 2])) for i in slow if tp.move[i] == Move.RETRACT]
            assert sum(1 for a, b in z if abs(a - 5.0) < 1e-9 and abs(b - 6.0) < 1e-9) == 4  # z 5 -> 6, or back
            assert 5.0 <= tp.info["rapid_distance_min_mm"] < 5.03  # the rapid pieces from 6 mm up
        else:  # measured on the part's samples: over the true 5 mm by less than the sampling's 0.03 mm
            assert 5.0 <= tp.info["rapid_distance_min_mm"] < 5.03


def test_a_run_ending_against_a_wall_its_axis_leans_to_is_shortened_until_it_can_lift():
    """A ball D6 (10 mm long) leaning 30 deg towards a wall at x = 10 cuts the floor in two passes up to
    x = 2, where the body's far side (its top rim, x + 5 + 2.6, closed form) is 0.4 mm from the wall.
    Lifting along the leaning axis moves it 0.5 mm towards the wall per mm: no link can leave either pass
    at x = 2 (before, the second pass was left out). Each pass's end is moved in one position (x = 1.5),
    where the 1 mm lift is clear, and the passes are joined there; the body never reaches the wall (closed
    form over every move sampled every 0.05 mm) and the check is clean."""
    floor = builders.plane_patch((-30, -10, 0), (40, 0, 0), (0, 20, 0), name="floor")
    wall = builders.plane_patch((10, -10, -5), (0, 0, 30), (0, 20, 0), name="wall")  # material at x > 10
    a = np.array([np.sin(np.radians(30.0)), 0.0, np.cos(np.radians(30.0))])
    tool = BallEndMill(6, length=10.0)
    x = np.arange(-20.0, 2.01, 0.5)
    runs = []
    for k, y in enumerate((0.0, 2.0)):
        t = np.column_stack([x if k == 0 else x[::-1], np.full(x.size, y), np.full(x.size, 3.0 - 3.0 * a[2])])
        runs.append((t, np.tile(a, (x.size, 1)), t.copy()))  # the ball on the floor: its tip 0.4 mm up
    tp = link_runs(runs, [floor, wall], tool, clearance=5.0)
    assert tp.info["runs_left_out"] == [] and tp.info["links_direct"] == 1
    cut = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)
    assert tp.n_cut == 2 * (x.size - 1) and tp.tip[cut, 0].max() == 1.5
    assert ms.verify([floor, wall], tp).clean
    far = max(3.0 * a[0] + 3.0, 10.0 * a[0] + 3.0 * a[2])  # the body's largest x for a tip at x = 0: 7.6
    worst = max(float(max(p[0], q[0])) for p, q in zip(tp.tip[:-1], tp.tip[1:]))  # tips move straight
    assert worst + far <= 10.0 - 0.4 + 1e-9


def test_rapids_made_feed_moves_read_back_from_apt(tmp_path):
    """Our APT file of a path whose links run partly at the plunge feed (the holder beside the bridge) reads
    back with the same move kinds, and each pass is entered by its approach: the reader tells the feed links
    (moves at the plunge feed between cutting moves) from the cuts."""
    floor = builders.plane_patch((-40, -30, 0), (100, 0, 0), (0, 60, 0), name="floor")
    bridge = builders.plane_patch((0, -30, 12), (20, 0, 0), (0, 60, 0), name="bridge")
    tool = BallEndMill(6, length=10.0, holder=ms.Shank(20, 30))
    ys = np.linspace(-20, 20, 21)
    runs = []
    for k, x in enumerate((-13.0, 33.0, 36.0)):
        t = np.column_stack([np.full(ys.size, x), ys if k % 2 == 0 else ys[::-1], np.zeros(ys.size)])
        runs.append((t, np.tile([0.0, 0, 1], (ys.size, 1)), t.copy()))
    tp = ms.check_toolpath(link_runs(runs, [floor, bridge], tool, clearance=5.0), [floor, bridge]).toolpath
    assert tp.info["n_rapids_at_feed"] > 0 and tp.info["links_direct"] == 1  # one link at feed all the way
    back = ms.read_apt(ms.write_apt(tmp_path / "linked.apt", tp))
    np.testing.assert_array_equal(back.move, tp.move)
    np.testing.assert_array_equal(back.pass_index[back.move == Move.APPROACH], [0, 1, 2])


def test_long_retracts_run_at_the_plunge_feed_only_within_the_clearance():
    """A one-way raster on a floor beside a shelf 30 mm up: every line ends with a retract to the plane 5 mm
    over the shelf (35 mm) and starts with the approach down from it. At the plunge feed only where the
    whole tool is within the 5 mm clearance of the part: the ball's tip within 5 mm of the floor (closed
    form), so each is split into 5 mm at feed and 30 mm rapid; every rapid left keeps 5 mm (closed form:
    the ball's lowest point over the floor, the shelf 40 mm away in plan)."""
    floor = ms.Face(builders.plane_patch((0, 0, 0), (60, 0, 0), (0, 40, 0)), name="floor")
    shelf = ms.Face(builders.plane_patch((100, 0, 30), (20, 0, 0), (0, 40, 0)), name="shelf")
    r = ms.mill3([floor, shelf], "ball:D=6", faces="0", stepover=10.0, direction="one-way", clearance=5.0)
    assert r.verdict == "clean"
    tp, rapids = r.toolpath, r.check.report()["rapids"]
    n_lines = int(np.sum(tp.move == Move.APPROACH))
    assert n_lines == 5 and rapids["n_links_split"] == 2 * n_lines
    assert rapids["link_length_at_feed_mm"] == pytest.approx(2 * 5.0 * n_lines, abs=1e-9)
    seg = np.linalg.norm(np.diff(tp.tip, axis=0), axis=1)
    slow = np.isin(tp.move[1:], (Move.RETRACT, Move.APPROACH))
    assert np.allclose(seg[slow], 5.0) and np.allclose(np.sort(tp.tip[1:][slow, 2]), np.r_[[0.0] * 5, [5.0] * 5])
    fast = np.flatnonzero(tp.move == Move.RAPID)
    fast = fast[fast > 0]
    assert min(tp.tip[fast, 2].min(), tp.tip[fast - 1, 2].min()) >= 5.0 - 1e-9  # the ball 5 mm over the floor
    assert tp.tip[fast, 0].max() <= 60.0 + 1e-9  # 40 mm from the shelf in plan: far more than 5


def test_a_link_stretch_at_the_plunge_feed_between_two_rapids_reads_back_as_a_link(tmp_path):
    """A split retract (feed near the part, rapid, feed again past a wall, rapid over) written to APT reads
    back with the same move kinds and passes: feed moves between two rapids, none at the cutting feed, are a
    link's stretch (retracts), not a pass of their own."""
    x = np.linspace(0.0, 20.0, 11)
    cut0 = np.column_stack([x, np.zeros(11), np.zeros(11)])
    cut1 = np.column_stack([x[::-1], np.full(11, 10.0), np.zeros(11)])
    tips = np.vstack([[0, 0, 30.0], cut0, [[20, 0, 5], [20, 0, 12], [20, 0, 14], [20, 0, 30], [20, 10, 30],
                                           [20, 10, 5]], cut1, [[0, 10, 5], [0, 10, 30]]])  # fmt: skip
    M = Move
    mv = np.r_[M.RAPID, M.APPROACH, [M.CUT] * 10, M.RETRACT, M.RAPID, M.RETRACT, M.RAPID, M.RAPID, M.RAPID,
               M.APPROACH, [M.CUT] * 10, M.RETRACT, M.RAPID]  # fmt: skip
    passes = np.r_[[0] * 18, [1] * 13]
    tp = ms.ToolPath(tips, np.tile([0.0, 0, 1], (tips.shape[0], 1)), mv, passes, cutter=BallEndMill(6))
    back = ms.read_apt(ms.write_apt(tmp_path / "split.apt", tp))
    np.testing.assert_array_equal(back.move, tp.move)
    cutting = (tp.move == Move.CUT) | (tp.move == Move.APPROACH)  # (a link's rapids open the next pass)
    np.testing.assert_array_equal(back.pass_index[cutting], tp.pass_index[cutting])
