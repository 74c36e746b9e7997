"""Shared fixtures. Nothing here imports the kernel or pyvista at module level, so the
numpy-only tests also run where those are missing (FreeCAD's Python, the numpy-1.24 job)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent

HAS_OCP = importlib.util.find_spec("OCP") is not None
HAS_PYVISTA = importlib.util.find_spec("pyvista") is not None

needs_kernel = pytest.mark.skipif(not HAS_OCP, reason="cadquery-ocp (the OCCT kernel) is not installed")
needs_pyvista = pytest.mark.skipif(not HAS_PYVISTA, reason="pyvista is not installed")


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


# scripts run inside FreeCAD's own Python by tests/test_freecad.py, not by pytest
collect_ignore_glob = ["freecad/*"]
