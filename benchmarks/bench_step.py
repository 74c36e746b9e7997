"""Reading a large part: ``info`` (face summaries, no NURBS conversion) against reading every face
converted to NURBS (what ``info`` and every ``--face N`` command did before), on a cadquery plate
with 256 holes (262 faces: 256 cylinders and the box). Goal: ``info`` under 5 s."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path


def _plate(path: Path, holes: int = 256) -> int:
    import cadquery as cq

    n = int(round(holes**0.5))
    pts = [(-95 + 190 * i / (n - 1), -95 + 190 * j / (n - 1)) for i in range(n) for j in range(n)][:holes]
    plate = cq.Workplane("XY").box(220, 220, 10).faces(">Z").workplane().pushPoints(pts).hole(6)
    cq.exporters.export(plate, str(path))
    return len(plate.val().Faces())


def step_rows(quick=False):
    from machsurf_cad.occ import read_step_face, read_step_faces, step_face_summaries

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "plate.step"
        n_faces = _plate(path, 64 if quick else 256)
        t = time.perf_counter()
        rows_info = step_face_summaries(path)
        t_info = time.perf_counter() - t
        t = time.perf_counter()
        read_step_face(path, len(rows_info) - 1)
        t_one = time.perf_counter() - t
        t = time.perf_counter()
        allf = read_step_faces(path)
        t_all = time.perf_counter() - t
    assert len(rows_info) == len(allf) == n_faces
    return [
        {
            "name": f"info, plate with holes ({n_faces} faces)",
            "n": n_faces,
            "ours_s": t_info,
            "ref_s": t_all,
            "ref": "convert every face",
            "max_diff": 0.0,
        },
        {
            "name": f"one face of {n_faces} (--face N)",
            "n": 1,
            "ours_s": t_one,
            "ref_s": t_all,
            "ref": "convert every face",
            "max_diff": 0.0,
        },
    ]
