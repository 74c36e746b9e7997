"""The flank-milling paper's ruled test surfaces: hyperbolic paraboloid, Liu's surface, eq. (18).

Run ``python example_parts/ruled_surfaces.py`` to rebuild ``hypar.step``, ``liu.step`` and
``eq18.step``. The first two are exact; eq. (18) has a sqrt(u) directrix and is fitted
within 1e-4 mm (the error measured on unseen points is printed).
"""

from pathlib import Path

from machsurf_cad.examples import eq18_surface, hyperbolic_paraboloid, liu_surface
from machsurf_cad.geometry.face import Face
from machsurf_cad.occ import write_step


def build(out_dir: Path) -> list[Path]:
    out_dir = Path(out_dir)
    eq18 = eq18_surface(tolerance=1e-4)
    print(f"eq18 fitted: max error {eq18.max_error:.3g} mm on {eq18.n_check} unseen points")
    return [
        write_step(out_dir / "hypar.step", [Face(hyperbolic_paraboloid(30.0, 80.0), name="hypar_a30_h80")]),
        write_step(out_dir / "liu.step", [Face(liu_surface(), name="liu")]),
        write_step(out_dir / "eq18.step", [Face(eq18.surface, name="eq18")]),
    ]


if __name__ == "__main__":
    for p in build(Path(__file__).resolve().parent):
        print(p)
