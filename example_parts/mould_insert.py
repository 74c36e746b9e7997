"""A mould insert of 51 faces for 3-axis machining, made with cadquery.

100 x 80 x 25 mm block with R 8 corners; a 60 x 44 x 10 mm pocket (R 5 corners, R 3 floor fillet)
holding four D 10 bosses with R 2 top fillets; a 6 mm slot (narrower than a D 10 tool); a spherical
dome on one corner. Walls, flat floors, bosses and a channel: the drop-cutter's test and benchmark
part. Run ``python example_parts/mould_insert.py`` to rebuild ``mould_insert.step``.
"""

from pathlib import Path

from machsurf_cad.occ.parts import write_mould_insert


def build(out_dir: Path) -> list[Path]:
    path = Path(out_dir) / "mould_insert.step"
    write_mould_insert(path)
    return [path]


if __name__ == "__main__":
    for p in build(Path(__file__).resolve().parent):
        print(p)
