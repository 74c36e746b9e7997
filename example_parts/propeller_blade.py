"""Propeller-blade pressure face of about 400 mm span (effective-radius paper's industrial case).

Run ``python example_parts/propeller_blade.py`` to rebuild ``propeller_blade.step``.
"""

from pathlib import Path

from machsurf_cad.examples import propeller_blade
from machsurf_cad.geometry.face import Face
from machsurf_cad.occ import write_step


def build(out_dir: Path) -> list[Path]:
    return [write_step(Path(out_dir) / "propeller_blade.step", [Face(propeller_blade(), name="blade_pressure_face")])]


if __name__ == "__main__":
    for p in build(Path(__file__).resolve().parent):
        print(p)
