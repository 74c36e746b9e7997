"""A real part made with cadquery: a 120 x 90 mm block whose top is a trimmed free-form face.

The bicubic top face (named ``freeform_top``) is trimmed by a D = 24 mm through hole and a
R = 25 mm corner notch; the other faces are planes and cylinders. This is the default part
of ``make demo``. Run ``python example_parts/freeform_block.py`` to rebuild ``freeform_block.step``.
"""

from pathlib import Path

from machsurf_cad.occ.parts import write_freeform_block


def build(out_dir: Path) -> list[Path]:
    path = Path(out_dir) / "freeform_block.step"
    write_freeform_block(path)
    return [path]


if __name__ == "__main__":
    for p in build(Path(__file__).resolve().parent):
        print(p)
