"""The drop-cutter on the impeller of ../shared/real-parts where two faces' edges and creases meet near the
rim of a flat end mill (slow tier: reading the part and the brute force take about half a minute)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import needs_kernel
from helpers import shared_part, trimmed_grid

import machsurf_cad as ms
from machsurf_cad.gougecheck import face_size
from machsurf_cad.threeaxis import compiled

pytestmark = [needs_kernel, pytest.mark.slow]

POINTS = np.array([[44.292261130300005, 32.592185435606446], [3.686473553400006, 33.29814840496576]])


@pytest.mark.parametrize("engine", ["numpy", pytest.param("compiled", marks=pytest.mark.skipif(
    not compiled.available(), reason="numba is not installed"))])  # fmt: skip
def test_a_flat_end_mill_where_blade_edges_meet_near_its_rim(engine):
    """Two points of the 61 x 61 benchmark grid where the compiled engine sat 0.045 and 0.026 mm below
    OpenCAMLib: the best contact found first lay on one face's edge (or a crease), and the other face's edge
    0.08 mm away, higher, was skipped as 'near the best contact'. Now only samples of the best contact's own
    edge are skipped: the height is at least every face sample's within the disc (0.02 mm apart on the faces
    that reach the tool) and at most 5e-3 mm above them (0.02 mm samples on a blade steeper than 80 degrees miss
    up to that much at the rim, where the contact lies)."""
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(shared_part("turbo3d_impeller.step"))
    r = ms.drop_cutter(faces, ms.FlatEndMill(10), POINTS, engine=engine)
    for q, h in zip(POINTS, r.height):
        brute = -np.inf
        for f in faces:
            box = f.surface.evaluate(*trimmed_grid(f, face_size(f), 2.0, 2, 400))
            if box.size and np.hypot(box[:, 0] - q[0], box[:, 1] - q[1]).min() > 5.0 + 2.0:
                continue
            p = f.surface.evaluate(*trimmed_grid(f, face_size(f), 0.02, 2, 4000))
            inside = np.hypot(p[:, 0] - q[0], p[:, 1] - q[1]) <= 5.0
            if inside.any():
                brute = max(brute, float(p[inside, 2].max()))
        assert brute - 1e-9 <= h <= brute + 5e-3, (q, h, brute)
