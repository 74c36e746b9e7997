"""Flank milling beside other faces (issue 28, item 4): a blade standing on a floor with a wall beside it.
The cylinder's end is lifted clear of the floor by the closed-form height, the rules whose cylinder would
enter the wall are left out (their range against the closed form), and the written path is clean under the
whole-part check and under a brute force written here (the cylinder against dense samples of every face)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import machsurf_cad as ms
from machsurf_cad.flank_milling import RuledSurface, flank_path
from machsurf_cad.flank_milling.clear import clear_flank
from machsurf_cad.geometry.builders import line_segment, plane_patch
from machsurf_cad.geometry.face import Face

R, H, OVERHANG = 3.0, 20.0, 1.0


def _blade():
    return RuledSurface.from_curves(line_segment([0, 0, 0], [0, 40, 0]), line_segment([0, 0, H], [0, 40, H]))


def _floor():
    return Face(plane_patch((-30, -10, 0), (60, 0, 0), (0, 60, 0)), name="floor")


def _wall(y0=25.0, x=5.0):
    """A wall x = ``x`` from y = ``y0`` on, facing the blade (2 mm from the tool's side at x = 6 - R... )."""
    return Face(plane_patch((x, y0, -5), (0, 40 - y0 + 10, 0), (0, 0, 40)), name="wall")


def _brute_depth(tip, axis, faces, step=0.05):
    """Deepest point of any face inside the cylinder of radius R from ``tip`` upwards (dense samples)."""
    worst = 0.0
    for f in faces:
        u0, u1, v0, v1 = f.uv_bounds
        u, v = np.meshgrid(np.linspace(u0, u1, 400), np.linspace(v0, v1, 400))
        P = f.surface.evaluate(u.ravel(), v.ravel())
        for t0, a in zip(tip, axis):
            d = P - t0
            t = d @ a
            rho = np.linalg.norm(d - np.outer(t, a), axis=1)
            inside = (t > 0) & (rho < R)
            if inside.any():
                worst = max(worst, float((R - rho[inside]).max()))
    return worst


def test_the_tool_is_lifted_clear_of_the_floor_by_the_closed_form_height():
    path = flank_path(_blade(), R, "standard-distributed", side=1, n_rules=9, overhang=OVERHANG)
    # the planned cylinder's end is OVERHANG below the floor: the floor is inside it
    assert np.allclose(path.tip[:, 2], -OVERHANG)
    res = clear_flank(path, [_floor()], gouge_tolerance=0.01, clearance=0.1)
    h = res.sample_spacing
    assert res.kept.all() and not res.rules_left_out
    # the floor (z = 0) is OVERHANG above the tip: lifted by OVERHANG + clearance + the samples' spacing
    np.testing.assert_allclose(res.lift, OVERHANG + 0.1 + h, atol=1e-9)
    np.testing.assert_allclose(res.path.tip[:, 2], 0.1 + h, atol=1e-9)
    np.testing.assert_allclose(res.contact_fraction, (H - 0.1 - h) / H, atol=1e-9)
    assert _brute_depth(res.path.tip, res.path.axis, [_floor()]) == 0.0
    rep = res.report()
    assert rep["n_rules_lifted"] == 9 and rep["max_lift_mm"] == pytest.approx(OVERHANG + 0.1 + h)


def test_rules_whose_cylinder_enters_a_wall_are_left_out_and_the_path_is_clean():
    blade = _blade()
    path = flank_path(blade, R, "standard-distributed", side=1, n_rules=41, overhang=OVERHANG)
    faces = [_floor(), _wall()]
    res = clear_flank(path, faces, gouge_tolerance=0.01, clearance=0.1)
    # the cylinder (axis x = R) reaches the wall x = 5 within |y - y_wall| < sqrt(R^2 - (5 - R)^2)
    reach = math.sqrt((R - 0.01) ** 2 - (5 - R) ** 2)
    y_rule = path.tip[:, 1]
    expect_out = y_rule > 25.0 - reach + res.sample_spacing
    expect_in = y_rule < 25.0 - reach - res.sample_spacing
    assert np.all(~res.kept[expect_out]) and np.all(res.kept[expect_in])
    assert len(res.rules_left_out) == 1
    lo, hi = res.rules_left_out[0]["u_range"]
    assert hi == pytest.approx(path.u[-1])
    assert abs(40 * lo - (25.0 - reach)) <= 40 / 40 + res.sample_spacing  # within a rule step of the closed form
    assert res.rules_left_out[0]["deepest_intrusion_mm"] == pytest.approx(R - (5 - R), abs=0.05)
    # the brute force: no face of the part inside any kept cylinder, nor between neighbouring rules
    s = np.linspace(0, 1, 11)[:, None, None]
    tips = ((1 - s) * res.path.tip[:-1] + s * res.path.tip[1:]).reshape(-1, 3)
    axes = ((1 - s) * res.path.axis[:-1] + s * res.path.axis[1:]).reshape(-1, 3)
    assert _brute_depth(tips, axes / np.linalg.norm(axes, axis=1, keepdims=True), faces) == 0.0
    # the whole-part check on the written path (the blade itself is the flank face: its own error is the
    # flank setting's, zero on a plane)
    tp = res.path.toolpath(ms.FlatEndMill(2 * R, 40.0), clearance=5.0)
    v = ms.verify([*faces, Face(blade.to_bspline().surface, name="blade")], tp, gouge_tolerance=0.01)
    assert v.clean, v.report()


def test_bad_arguments_are_refused():
    path = flank_path(_blade(), R, "standard-distributed", side=1, n_rules=5)
    for kw in ({"gouge_tolerance": -1}, {"gouge_tolerance": 0.01, "clearance": -1},
               {"gouge_tolerance": 0.01, "min_contact": 0}):  # fmt: skip
        with pytest.raises(ms.InputError):
            clear_flank(path, [_floor()], **kw)


def test_flank_with_check_faces_lifts_links_and_writes_a_clean_path():
    """The API as the CLI runs it: ``flank(whole=True, check_faces=...)`` lifts the rules, leaves out those
    by the wall, links the segment clear of the part, and the whole-part check of the path is clean."""
    blade = _blade()
    faces = [_floor(), _wall()]
    res = ms.flank(blade, f"cyl:D={2 * R:g}", setting="standard-distributed", whole=True, check_faces=faces,
                   gouge_tolerance=0.01)  # fmt: skip
    cl = res.cleared
    assert cl is not None and 0.5 < cl.machined_fraction < 1.0 and cl.rules_left_out
    assert res.report()["whole"]["clear_of_part"]["n_rules_kept"] == len(res.path.settings)
    v = ms.verify([*faces, Face(blade.to_bspline().surface, name="blade")], res.toolpath, gouge_tolerance=0.01)
    assert v.clean, v.report()
    # every position's cylinder clear of the floor and wall by the brute force (links included)
    assert _brute_depth(res.toolpath.tip, res.toolpath.axis, faces) == 0.0


def test_several_diameters_each_stretch_by_the_largest_that_clears():
    """Cylinders D6 and D4 beside the wall: the D6 (axis at x = 3, side at x = 6) cannot pass the wall at
    x = 5 beyond y = 25 - sqrt(2.99^2 - 2^2), the D4 (side at x = 4) passes it everywhere; the D6 machines the
    blade up to there, the D4 the rest (closed forms within a rule step), together all of it. Each tool's
    path is checked clean and its cylinder kept out of the wall by the brute force."""
    blade = _blade()
    wall = _wall()
    res = ms.flank(blade, ["cyl:D=4", "cyl:D=6"], setting="standard-distributed", whole=True, check_faces=[wall],
                   gouge_tolerance=0.01)  # fmt: skip
    big, small = res.by_diameter
    assert big.cutter.D == 6 and small.cutter.D == 4 and res.toolpath is big.toolpath
    edge = (25.0 - math.sqrt(2.99**2 - 2.0**2)) / 40.0  # u of the last rule the D6 clears
    step = float(np.diff(big.cleared.path.u).max())
    (a0, b0), (a1, b1) = big.u_machined[0], small.u_machined[0]
    assert len(big.u_machined) == len(small.u_machined) == 1
    assert a0 == 0.0 and abs(b0 - edge) <= step and a1 == b0 and b1 == 1.0
    assert big.machined_fraction == pytest.approx(b0, abs=1e-3) and small.machined_fraction == pytest.approx(
        1 - b0, abs=1e-3
    )
    rep = res.report()["whole"]
    assert rep["machined_fraction_all_tools"] == pytest.approx(1.0, abs=1e-3) and rep["u_left_out"] == []
    part = [wall, Face(blade.to_bspline().surface, name="blade")]
    for p in (big, small):
        v = ms.verify(part, p.toolpath, gouge_tolerance=0.01)
        assert v.clean, v.report()
        tip, axis = p.toolpath.tip, p.toolpath.axis
        d = wall.surface.evaluate(*np.meshgrid(np.linspace(0, 1, 300), np.linspace(0, 1, 300))).reshape(-1, 3)
        for t0, a in zip(tip, axis):
            q = d - t0
            s = q @ a
            rho = np.linalg.norm(q - np.outer(s, a), axis=1)
            assert not np.any((s > 0) & (rho < p.cutter.D / 2 - 1e-9))  # no wall point inside its cylinder
    with pytest.raises(ms.InputError, match="several diameters"):
        ms.flank(blade, ["cyl:D=4", "cyl:D=6"], whole=True)
