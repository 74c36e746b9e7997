"""The README's examples run as printed: the Python block as a script, the shell examples in order after
the demo (each writes what the next reads), in a scratch folder (nothing lands in the repository)."""

import json
import os
import re
import shlex
import subprocess
import sys

import pytest
from conftest import ROOT, needs_kernel, needs_pyvista

pytestmark = [needs_kernel, needs_pyvista, pytest.mark.slow]

README = (ROOT / "README.md").read_text()


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, flags=re.S)


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT), PATH=f"{os.path.dirname(sys.executable)}:{os.environ['PATH']}")


def test_the_python_block_runs_as_a_script(tmp_path):
    (py,) = _blocks("python")
    (tmp_path / "example.py").write_text(py)
    r = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, env=_env(),
                       stdin=subprocess.DEVNULL, timeout=900)  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    lines = r.stdout.strip().splitlines()
    assert len(lines) == 6, lines
    assert float(lines[0]) <= 1e-3  # S1 within its tolerance, on points the fit never saw
    assert float(lines[1]) <= 0.01  # the path does not gouge the face
    assert int(lines[2]) > 10 and (tmp_path / "out" / "path.apt").is_file()
    assert float(lines[4]) < 0.5  # the flank path within its tolerance
    assert int(lines[5]) == 1  # the batch job ran
    assert not (ROOT / "path.apt").exists() and not (ROOT / "out" / "path.apt").exists()


def test_the_shell_examples_chain_after_the_demo(tmp_path):
    sh = _blocks("sh")[1]  # the block after the set-up's make commands
    cmds, cur = [], ""
    for line in sh.splitlines():
        line = line.split("#", 1)[0].rstrip() if line.lstrip().startswith("#") else line.rstrip()
        if not line:
            continue
        cur += line[:-1] + " " if line.endswith("\\") else line
        if not line.endswith("\\"):
            cmds.append(cur)
            cur = ""
    assert len(cmds) == 5 and all(c.startswith("machsurf ") for c in cmds), cmds
    (tmp_path / "example_parts").symlink_to(ROOT / "example_parts")
    run = [sys.executable, "-m", "machsurf_cad"]
    r = subprocess.run([*run, "demo", "-o", "out/demo"], cwd=tmp_path, capture_output=True, text=True, env=_env(),
                       stdin=subprocess.DEVNULL, timeout=900)  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    for c in cmds:
        argv = shlex.split(c)[1:]
        r = subprocess.run([*run, *argv], cwd=tmp_path, capture_output=True, text=True, env=_env(),
                           stdin=subprocess.DEVNULL, timeout=900)  # fmt: skip
        assert r.returncode == 0, (c, r.stdout[-1500:], r.stderr[-1500:])
        out = tmp_path / argv[argv.index("-o") + 1]
        text = (out / "report.json").read_text()
        assert "NaN" not in text and "Infinity" not in text, out  # strict JSON
    assert json.loads((tmp_path / "out/verify/report.json").read_text())["verify"]["clean"]


def test_the_guides_python_block_runs_as_a_script(tmp_path):
    """docs/guide.md's API overview, as printed, in a scratch folder: no DeprecationWarning of ours."""
    text = (ROOT / "docs" / "guide.md").read_text()
    (py,) = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    (tmp_path / "guide.py").write_text(py)
    r = subprocess.run([sys.executable, "-W", "error::DeprecationWarning:__main__", "guide.py"], cwd=tmp_path,
                       capture_output=True, text=True, env=_env(), stdin=subprocess.DEVNULL, timeout=900)  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    lines = r.stdout.strip().splitlines()
    assert float(lines[0]) <= 1e-3 and float(lines[1]) <= 0.01 and lines[-1] == "1"
    assert (tmp_path / "path.apt").is_file() and (tmp_path / "out" / "flank" / "report.json").is_file()
