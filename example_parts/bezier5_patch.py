"""Degree-5 Bezier patch of about 100 mm (machining-surface paper's kind of example).

Run ``python example_parts/bezier5_patch.py`` to rebuild ``bezier5_patch.step``.
"""

from pathlib import Path

from machsurf_cad.examples import bezier5_patch
from machsurf_cad.geometry.face import Face
from machsurf_cad.occ import write_step


def build(out_dir: Path) -> list[Path]:
    return [write_step(Path(out_dir) / "bezier5_patch.step", [Face(bezier5_patch(), name="bezier5")])]


if __name__ == "__main__":
    for p in build(Path(__file__).resolve().parent):
        print(p)
