"""The one tool-path type and its writer/reader: APT round trips for every producer, 3+2 keeps its axis,
linking moves along the axis, foreign CLDATA, CSV and JSON."""

import json
import math
import warnings

import numpy as np
import pytest
from helpers import assert_points_close

import machsurf_cad as ms
from machsurf_cad.geometry import builders


def _round_trip(tp, tmp_path, options=None):
    apt = ms.write_apt(tmp_path / f"{tp.name}.apt", tp, options or ms.PostOptions())
    back = ms.read_apt(apt)
    assert_points_close(back.tip, tp.tip, atol=1e-5, what="tips")  # 5 decimals in mm
    assert_points_close(back.axis, tp.axis, atol=2e-9, what="axes")  # 9 decimals, renormalised
    assert (back.move == tp.move).all() and (back.pass_index == tp.pass_index).all()
    return apt.read_text().splitlines(), back


def _check_linking(tp, clearance):
    """Every pass: rapid to clearance above its start along the axis, approach, cuts, retract along the axis."""
    for i in np.unique(tp.pass_index):
        idx = np.nonzero(tp.pass_index == i)[0]
        m = tp.move[idx]
        assert m[0] == ms.Move.RAPID and m[1] == ms.Move.APPROACH and m[-1] == ms.Move.RETRACT
        assert (m[2:-1] == ms.Move.CUT).all()
        a, b = idx[0], idx[1]
        assert_points_close(tp.tip[a] - tp.tip[b], clearance * tp.axis[b], atol=1e-12)
        c, d = idx[-2], idx[-1]
        assert_points_close(tp.tip[d] - tp.tip[c], clearance * tp.axis[c], atol=1e-12)


def test_machining_surface_path_has_post_statements_and_round_trips(tmp_path):
    res = ms.machining_surface(ms.example("bezier5"), "bull:D=28,r=4", axes=5, lead=20, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=10.0, clearance=8.0)
    _check_linking(tp, 8.0)
    opts = ms.PostOptions(feed=1500, plunge_feed=250, spindle=12000, tool_number=7, partno="BEZ")
    lines, back = _round_trip(tp, tmp_path, opts)
    assert lines[1:7] == [
        "PARTNO/BEZ",
        "UNITS/MM",
        "CUTTER/28.0000,4.0000,10.0000,4.0000,0.0000,0.0000,84.0000",
        "LOADTL/7",
        "SPINDL/RPM,12000.0000,CLW",
        "MULTAX/ON",
    ]
    assert "FEDRAT/250.0000,MMPM" in lines and "FEDRAT/1500.0000,MMPM" in lines and lines[-1] == "FINI"
    assert lines.index("LOADTL/7") < next(i for i, ln in enumerate(lines) if ln.startswith("GOTO/"))
    cut = back.move == ms.Move.CUT
    assert np.all(back.feed[cut] == 1500) and np.all(back.feed[back.move == ms.Move.APPROACH] == 250)
    assert back.cutter == ms.BullNoseEndMill(28, 4, 84)


def test_three_plus_two_keeps_its_axis(tmp_path):
    axis = np.array([math.sin(math.radians(8)), 0.0, math.cos(math.radians(8))])
    res = ms.machining_surface(ms.example("bezier5"), "ball:D=10", axes=3, axis=tuple(axis), tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=15.0)
    assert tp.is_multiaxis
    assert_points_close(tp.axis, np.broadcast_to(axis, tp.axis.shape), atol=1e-15)
    lines, back = _round_trip(tp, tmp_path)
    assert "MULTAX/ON" in lines and all(len(ln.split(",")) == 6 for ln in lines if ln.startswith("GOTO/"))
    assert_points_close(back.axis, np.broadcast_to(axis, tp.axis.shape), atol=2e-9)
    # plain 3 axes: +Z everywhere, MULTAX/OFF and 3-value GOTOs, read back as +Z
    tp3 = ms.tool_paths(ms.machining_surface(ms.example("bezier5"), "ball:D=10", axes=3, tolerance=1e-3), stepover=15)
    lines3, back3 = _round_trip(tp3, tmp_path)
    assert not tp3.is_multiaxis and "MULTAX/OFF" in lines3
    assert all(len(ln.split(",")) == 3 for ln in lines3 if ln.startswith("GOTO/"))


def test_flank_path_approaches_and_retracts_sideways(tmp_path):
    res = ms.flank(ms.example("liu", "ruled"), "cyl:D=20", whole=True, tolerance=0.5, clearance=6.0)
    tp = res.toolpath
    assert tp.n_passes == 1 and tp.n_cut == len(res.path.settings)
    # sideways, away from the rule: normal to the axis, towards the axis from the contact M2
    for a, b, s in ((0, 1, res.path.settings[0]), (-1, -2, res.path.settings[-1])):
        w = tp.tip[a] - tp.tip[b]
        assert abs(np.linalg.norm(w) - 6.0) < 1e-12 and abs(w @ tp.axis[b]) < 1e-12
        assert w @ (s.q - np.asarray(s.contacts["M2"])) > 0
    clear = ms.verify(ms.example("liu"), tp, gouge_tolerance=0.5)
    assert clear.report()["n_collisions"] == 0
    lines, back = _round_trip(tp, tmp_path)
    assert lines[3] == f"CUTTER/20.0000,0.0000,10.0000,0.0000,0.0000,0.0000,{tp.cutter.length:.4f}"
    # the cutting positions are the settings: tip on the axis, axis unit and along the setting's axis
    cut = tp.cutting_passes()[0]
    for k, s in enumerate(res.path.settings):
        assert abs(abs(cut.axis[k] @ s.a) - 1) < 1e-12
        w = cut.tip[k] - s.q
        assert np.linalg.norm(w - (w @ s.a) * s.a) < 1e-9


def test_envelope_passes_as_one_tool_path(tmp_path):
    res = ms.envelope("cone:D=10,angle=10", ms.example("sine", "motion"), passes=3, theta=0.0)
    tp = res.toolpath
    assert tp.n_passes == 3 and tp.info["chordal_error_measured_mm"] <= 0.01
    _check_linking(tp, 5.0)
    _round_trip(tp, tmp_path)
    # each pass's cutting positions lie on its motion: tip T(t) and axis A(t) at the stored t
    for p, e in zip(tp.cutting_passes(), res.chain.passes):
        t = p.extras["t"]
        assert_points_close(p.tip, e.motion.T(t), atol=1e-12)
        assert_points_close(p.axis, e.motion.A(t), atol=1e-12)


def test_reader_takes_foreign_cldata(tmp_path):
    f = tmp_path / "other.cls"
    f.write_text(
        "\n".join(
            [
                "$$ from another CAM system",
                "PARTNO / TEST PART",
                "UNITS/INCHES",
                "CUTTER/ 0.5, 0.125",
                "MACHIN/ MILL, 1",
                "LOADTL/3",
                "FEDRAT/ 20.0, IPM",
                "RAPID",
                "GOTO / 0.0, 0.0, 1.0",
                "FEDRAT/ 5.0",
                "GOTO / 0.0, 0.0, 0.0",
                "FEDRAT/ 20.0",
                "GOTO / 1.0, 0.0, $",
                "   0.0",
                "GOTO/ 2.0, 0.5, 0.0",
                "FEDRAT/5.0",
                "GOTO/2.0,0.5,1.0",
                "MULTAX/ON",
                "RAPID",
                "GOTO/ 3.0, 0.0, 1.0, 0.0, 0.6, 0.8",
                "FEDRAT/ 20.0",
                "GOTO/3.0,0.0,0.0,0.0,0.6,0.8",
                "GOTO/4.0,0.0,0.0,0.0,0.6,0.8",
                "COOLNT/ON",
                "INDIRV/ 1, 0, 0",
                "FINI",
            ]
        )
        + "\n"
    )
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        tp = ms.read_apt(f)
    assert any("INDIRV x1" in str(x.message) and "MACHIN" not in str(x.message) for x in w)
    assert tp.n_positions == 8 and tp.n_passes == 2
    assert_points_close(tp.tip[2], [25.4, 0.0, 0.0], atol=1e-12)  # continuation line joined, inches converted
    assert [ms.Move(m).name for m in tp.move[:5]] == ["RAPID", "APPROACH", "CUT", "CUT", "RETRACT"]
    assert_points_close(tp.axis[:5], np.broadcast_to([0, 0, 1.0], (5, 3)), atol=0)
    assert_points_close(tp.axis[5:], np.broadcast_to([0, 0.6, 0.8], (3, 3)), atol=1e-15)
    assert isinstance(tp.cutter, ms.BullNoseEndMill)  # CUTTER/d,r in inches: a bull-nose D 12.7 r 3.175 mm
    assert (tp.cutter.D, tp.cutter.r) == pytest.approx((12.7, 3.175), abs=1e-12)
    assert tp.feed[2] == pytest.approx(20.0 * 25.4)


def test_csv_and_json_round_trip(tmp_path):
    res = ms.machining_surface(ms.example("bezier5"), "bull:D=28,r=4", axes=5, lead=20, tolerance=1e-3)
    tp = ms.tool_paths(res, stepover=20.0)
    back = ms.read_csv(ms.write_csv(tmp_path / "p.csv", tp))
    assert_points_close(back.tip, tp.tip, atol=1e-6)
    assert_points_close(back.axis, tp.axis, atol=2e-9)
    assert (back.move == tp.move).all() and (back.pass_index == tp.pass_index).all()
    cut = ~np.isnan(tp.cc[:, 0])
    assert_points_close(back.cc[cut], tp.cc[cut], atol=1e-6) and np.isnan(back.cc[~cut]).all()
    data = json.loads(ms.write_json(tmp_path / "p.json", tp).read_text())
    assert data["report"]["n_positions"] == tp.n_positions and len(data["tip_mm"]) == tp.n_positions
    assert data["cc_mm"][0] == [None, None, None] and data["move"][:2] == ["rapid", "approach"]


def test_bad_paths_are_refused():
    with pytest.raises(ms.InputError, match="unit vectors"):
        ms.ToolPath(np.zeros((2, 3)), [[0, 0, 2.0]] * 2, [0, 2], [0, 0])
    with pytest.raises(ms.InputError, match="clearance"):
        ms.ToolPath.from_passes([np.zeros((2, 3))], [np.array([[0, 0, 1.0]] * 2)], clearance=0)
    with pytest.raises(ms.InputError, match="feed must be > 0"):
        ms.PostOptions(feed=-1)
    tp = ms.ToolPath.from_passes([np.zeros((2, 3))], [np.array([[0, 0, 1.0]] * 2)])
    with pytest.raises(ms.InputError, match="cutter"):
        ms.write_apt("never.apt", tp)


def test_passes_linked_over_a_sphere_around_the_part():
    """``safe_sphere``: between passes the tool leaves along its axis to the sphere, goes over it with the
    axis pointing out and comes back along the next pass's axis; every such position and every chord
    between them stays outside the sphere asked for; the cutting positions are those of the straight
    linking; the path is clean against the face."""
    bez = ms.example("bezier5")
    m = ms.machining_surface(bez, "ball:D=10", axes=5, lead=10, tolerance=1e-2)
    plain = ms.tool_paths(m, stepover=15.0, zigzag=False)
    centre, radius = ms.part_sphere([bez], 5.0)
    tp = ms.tool_paths(m, stepover=15.0, zigzag=False, safe_sphere=(centre, radius))
    cut = tp.move == ms.Move.CUT
    assert np.array_equal(tp.tip[cut], plain.tip[plain.move == ms.Move.CUT])
    assert tp.info["safe_sphere_radius_mm"] == radius and tp.n_positions > plain.n_positions
    d = np.linalg.norm(tp.tip - centre, axis=1)
    link = np.zeros(tp.n_positions, bool)  # the positions between a retract and the next pass's first rapid
    ret = np.nonzero(tp.move == ms.Move.RETRACT)[0]
    for r in ret[:-1]:
        k = r + 1
        while tp.move[k + 1] == ms.Move.RAPID:
            link[k] = True
            k += 1
    assert link.sum() >= 3 * (len(ret) - 1) and np.all(d[link] >= radius * (1 - 1e-12))
    mid = 0.5 * (tp.tip[1:] + tp.tip[:-1])
    both = link[1:] & link[:-1]
    assert np.all(np.linalg.norm(mid[both] - centre, axis=1) >= radius * (1 - 1e-12))  # chords too
    ax = tp.axis[link]
    radial = (tp.tip[link] - centre) / d[link, None]
    assert np.all(np.einsum("ij,ij->i", ax, radial) > 0)  # the axis points out: the body stays outside
    assert ms.verify([bez], tp, gouge_tolerance=0.01).clean


def test_fixed_axis_passes_are_linked_in_a_plane_above_the_whole_part():
    """Two passes either side of a dome 20 mm high: linked straight 5 mm above their ends, the rapid runs
    through the dome (the body check finds the collision); linked in the plane 5 mm above the part's
    poles, it clears it, and the path starts and ends on that plane (issue 28's linking)."""
    floor = builders.plane_patch((0.0, 0.0, 0.0), (100.0, 0.0, 0.0), (0.0, 100.0, 0.0), name="floor")
    dome = builders.sphere_patch(20.0, (0.0, 90.0), 360.0, name="dome")
    dome = dome.with_poles(np.asarray(dome.poles) + [50.0, 50.0, 0.0], dome.weights)
    dome = ms.Face(dome, name="dome", reversed=True)  # su x sv points to the sphere's centre: outward is -
    tips = [np.array([[10.0, 0.0, 0.0], [10.0, 100.0, 0.0]]), np.array([[90.0, 0.0, 0.0], [90.0, 100.0, 0.0]])]
    axes = [np.array([[0.0, 0.0, 1.0]] * 2)] * 2
    ball = ms.BallEndMill(10)
    straight = ms.ToolPath.from_passes(tips, axes, cutter=ball, clearance=5.0)
    h = ms.part_plane([floor, dome], clearance=5.0)
    assert abs(h - 25.0) < 1e-9  # the dome's top pole at 20
    linked = ms.ToolPath.from_passes(tips, axes, cutter=ball, clearance=5.0, safe_plane=h)
    assert linked.tip[0, 2] == h and linked.tip[-1, 2] == h
    rapid = linked.move == ms.Move.RAPID
    assert np.all((linked.tip[rapid, 2] == h) | (linked.tip[rapid, 2] == 5.0))  # on the plane, or its way down
    assert linked.report()["safe_plane_height_mm"] == h
    assert not ms.verify([floor, dome], straight).clean  # the straight rapid meets the dome
    v = ms.verify([floor, dome], linked)
    assert v.clean and v.report()["n_collisions"] == 0
