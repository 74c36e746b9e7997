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

    assert not (ROOT / "workbench" / "package.xml").exists()  # one package.xml: the root's
    for xml in ((ROOT / "package.xml").read_text(),):
        assert re.search(r"<version>([^<]+)</version>", xml).group(1) == machsurf_cad.__version__
        icon = re.search(r"<icon>([^<]+)</icon>", xml).group(1)
        assert "example.invalid" not in xml and icon.endswith("machsurf.svg")
    assert (ROOT / "LICENSE").is_file() and (
        ROOT / "workbench" / "freecad" / "machsurf" / "resources" / "machsurf.svg"
    ).is_file()
    assert 'dynamic = ["version"]' in (ROOT / "pyproject.toml").read_text()


APP = ("machsurf_cad.jobs", "machsurf_cad.cli", "machsurf_cad.cliargs", "machsurf_cad.batchrun", "machsurf_cad._start",
       "machsurf_cad.__main__")  # fmt: skip
"""The app layer: orchestration of the core for the command line, the batch runner and the add-on."""


def _module_graph() -> dict[str, set[str]]:
    """machsurf_cad module -> the machsurf_cad modules it imports, function-level imports included,
    ``if TYPE_CHECKING:`` blocks excluded (they never run)."""
    mods = {}
    for p in PKG.rglob("*.py"):
        name = ".".join(p.relative_to(ROOT).with_suffix("").parts)
        mods[name.removesuffix(".__init__")] = p

    def targets(cur: str, node) -> list[str]:
        pkg = cur if mods[cur].name == "__init__.py" else cur.rsplit(".", 1)[0]
        if isinstance(node, ast.Import):
            return [a.name for a in node.names if a.name in mods]
        base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)] if node.level else []
        mod = ".".join(base + ([node.module] if node.module else [])) if node.level else (node.module or "")
        return [f"{mod}.{a.name}" if f"{mod}.{a.name}" in mods else mod for a in node.names if mod in mods]

    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, p in mods.items():
        tree = ast.parse(p.read_text())
        skip = {id(n) for blk in ast.walk(tree) if isinstance(blk, ast.If) and getattr(blk.test, "id", "") ==
                "TYPE_CHECKING" for b in blk.body for n in ast.walk(b)}  # fmt: skip
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in skip:
                graph[m].update(t for t in targets(m, node) if t != m)
    return graph


def test_no_import_cycles_counting_function_level_imports():
    graph = _module_graph()
    cycles = []
    for start in graph:  # a path back to ``start`` through the graph is a cycle
        seen, stack = set(), [(start, [start])]
        while stack:
            node, path = stack.pop()
            for nxt in graph[node]:
                if nxt == start:
                    cycles.append(" -> ".join(path + [start]))
                elif nxt not in seen:
                    seen.add(nxt)
                    stack.append((nxt, path + [nxt]))
    assert not cycles, "import cycles:\n" + "\n".join(sorted(set(cycles))[:10])


def test_the_core_never_imports_the_app_layer():
    graph = _module_graph()
    for m, deps in graph.items():
        if m == "machsurf_cad" or m.startswith(APP):
            continue
        bad = sorted(d for d in deps if d.startswith(APP))
        assert not bad, f"{m} (core) imports the app layer: {bad}"


def test_help_imports_no_kernel_pyvista_dask_or_scipy():
    import subprocess
    import sys

    heavy = "('OCP', 'cadquery', 'pyvista', 'dask', 'distributed', 'scipy')"
    code = (
        "import sys; from machsurf_cad.cliargs import build_parser; build_parser(); "
        f"print(sorted(m for m in {heavy} if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True).stdout
    assert out.strip() == "[]", out


def test_the_architecture_page_lists_every_module_with_its_layer():
    page = (ROOT / "docs" / "architecture.md").read_text()
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).as_posix()
        assert f"| `{rel}` |" in page, f"docs/architecture.md does not list {rel}"
