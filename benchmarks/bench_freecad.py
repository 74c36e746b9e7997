"""The FreeCAD add-on (issue 29): the CAM operation's raster on the example block at its defaults, in
FreeCADCmd with FreeCAD's own Python (Debian's numba when installed: ``python3-numba``), beside the same
raster and check through the API in this environment (the reference), in one run. Skipped without FreeCAD."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def freecad_rows(quick: bool = False) -> list[dict]:
    fc = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
    if fc is None:
        return []
    with tempfile.TemporaryDirectory() as tmp:
        mod = Path(tmp) / "home" / ".local" / "share" / "FreeCAD" / "Mod"
        mod.mkdir(parents=True)
        (mod / "machsurf_cad").symlink_to(ROOT)
        out = Path(tmp) / "bench.json"
        cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "machsurf_cad" / "freecad-numba"
        env = dict(os.environ, HOME=str(Path(tmp) / "home"), MACHSURF_ROOT=str(ROOT), MACHSURF_BENCH_OUT=str(out),
                   NUMBA_CACHE_DIR=str(cache))  # fmt: skip
        env.pop("PYTHONPATH", None)
        subprocess.run([fc, str(ROOT / "benchmarks" / "freecad" / "raster_time.py")], env=env, cwd=tmp,
                       stdin=subprocess.DEVNULL, capture_output=True, timeout=1800)  # fmt: skip
        r = json.loads(out.read_text())
    if "error" in r:
        raise RuntimeError(r["error"])
    ref_s, ref_gouge = _reference(r)
    engine = f"numba {r['numba']}" if r["numba"] else "numpy"
    return [{"name": f"FreeCAD CAM raster, block ({engine})", "n": r["cut_points"], "ours_s": r["raster_s"],
             "ref_s": ref_s, "ref": "API raster + check", "max_diff": abs(r["max_gouge"] - ref_gouge),
             "kernel_load_s": r["kernel_s"], "other_stepover_s": r["other_stepover_s"], "tool": r["tool"]}]  # fmt: skip


def _reference(r: dict) -> tuple[float, float]:
    """The same raster through the API here: the block's top face, the rest as check faces, then the
    whole-part check; wall seconds and its max gouge."""
    import machsurf_cad as ms
    from machsurf_cad.occ import read_step_faces

    faces = read_step_faces(ROOT / "example_parts" / "freeform_block.step")
    top = [f for f in faces if f.index == r["face"]]
    others = [f for f in faces if f.index != r["face"]]
    t = time.perf_counter()
    tp = ms.raster(top, ms.parse_cutter(r["tool"]), stepover=r["stepover"], check_faces=others,
                   chordal_tolerance=r["chordal"], gouge_tolerance=r["gouge_tolerance"],
                   clearance=r["clearance"])  # fmt: skip
    v = ms.verify(faces, tp, gouge_tolerance=r["gouge_tolerance"])
    return time.perf_counter() - t, float(v.max_gouge)


if __name__ == "__main__":
    for row in freecad_rows():
        print(row)
