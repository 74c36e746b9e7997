"""Architecture rules: one door to the kernel, one user of pyvista, no numpy-2-only calls in the core."""

import ast
from pathlib import Path

from conftest import ROOT

PKG = ROOT / "machsurf_cad"


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module.split(".")[0])
    return out


def test_only_occ_imports_the_kernel_only_viz_imports_pyvista_only_batch_imports_dask():
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).parts
        mods = _imports(path)
        if rel[0] != "occ":
            assert not mods & {"OCP", "cadquery"}, f"{path} imports the kernel"
        if rel[0] != "viz":
            assert not mods & {"pyvista", "vtk", "vtkmodules"}, f"{path} imports pyvista/vtk"
        if rel[0] != "batchrun":
            assert not mods & {"dask", "distributed"}, f"{path} imports dask"


def test_core_avoids_numpy2_only_api():
    banned = ["np.trapezoid", "np.vecdot", "np.matrix_transpose", "np.unstack", "np.concat(", "np.astype(", "copy=None"]
    for path in PKG.rglob("*.py"):
        text = path.read_text()
        for b in banned:
            assert b not in text, f"{path} uses {b}, missing from numpy 1.24"


def test_no_order_for_degree_in_public_names():
    for path in PKG.rglob("*.py"):
        text = path.read_text()
        assert "spline order" not in text.lower() and "order_u" not in text


def test_one_version():
    """The version lives in machsurf_cad/_version.py; the FreeCAD add-on's package.xml says the same."""
    import re

    import machsurf_cad

    for xml in ((ROOT / "workbench" / "package.xml").read_text(), (ROOT / "package.xml").read_text()):
        assert re.search(r"<version>([^<]+)</version>", xml).group(1) == machsurf_cad.__version__
        icon = re.search(r"<icon>([^<]+)</icon>", xml).group(1)
        assert "example.invalid" not in xml and icon.endswith("machsurf.svg")
    assert (ROOT / "LICENSE").is_file() and (
        ROOT / "workbench" / "freecad" / "machsurf" / "resources" / "machsurf.svg"
    ).is_file()
    assert 'dynamic = ["version"]' in (ROOT / "pyproject.toml").read_text()
