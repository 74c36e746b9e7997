"""Test helpers shared by several modules (numpy only)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def random_surface(rng, rational=False, degree=(3, 2), n=(7, 5), size=100.0):
    """A wavy clamped B-spline surface with non-uniform knots (and random weights if rational)."""
    from machsurf_cad.geometry import BSplineSurface

    p, q = degree
    nu, nv = n
    x = np.linspace(0, size, nu)
    y = np.linspace(0, size * 0.8, nv)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = 10 * np.sin(X / size * 3) * np.cos(Y / size * 2) + rng.normal(scale=2.0, size=X.shape)
    poles = np.stack([X + rng.normal(scale=1.0, size=X.shape), Y, Z], axis=-1)

    def knots(nn, d):
        inner = np.sort(rng.uniform(0.05, 0.95, nn - d - 1))
        k = np.concatenate([[0.0], inner, [1.0]])
        m = np.ones(k.size, dtype=int)
        m[0] = m[-1] = d + 1
        return k, m

    ku, mu = knots(nu, p)
    kv, mv = knots(nv, q)
    w = rng.uniform(0.6, 1.8, size=(nu, nv)) if rational else None
    return BSplineSurface(p, q, ku, mu, kv, mv, poles, w)


def shared_part(name: str) -> Path:
    """A public STEP part of ../shared/real-parts (kept out of the repository by its licence); the test is
    skipped where it is not present."""
    import pytest

    for d in (Path("/work/shared/real-parts"), ROOT.parent / "shared" / "real-parts"):
        if (d / name).is_file():
            return d / name
    pytest.skip("shared/real-parts (public STEP parts) not present")


def trimmed_grid(face, lengths, spacing: float, lo: int, hi: int):
    """The face's parameter grid about ``spacing`` mm apart along its ``lengths`` (mm along u and v; ``lo`` to
    ``hi`` samples each way), kept inside its trimming: ``(u, v)``."""
    import math

    u0, u1, v0, v1 = face.uv_bounds
    nu, nv = (int(np.clip(math.ceil(x / spacing) + 1, lo, hi)) for x in lengths)
    U, V = np.meshgrid(np.linspace(u0, u1, nu), np.linspace(v0, v1, nv), indexing="ij")
    u, v = U.ravel(), V.ravel()
    keep = face.contains_uv(u, v) if face.is_trimmed else np.ones(u.size, bool)
    return u[keep], v[keep]


def assert_points_close(actual, expected, atol, what="points"):
    """Every point (row) of ``actual`` within ``atol`` (mm, Euclidean) of ``expected``; reports the worst."""
    a = np.asarray(actual, float)
    b = np.asarray(expected, float)
    assert a.shape == b.shape, f"{what}: shapes {a.shape} and {b.shape} differ"
    d = np.linalg.norm(np.atleast_2d(a - b), axis=-1) if a.ndim >= 1 and a.shape[-1:] in ((2,), (3,)) else np.abs(a - b)
    worst = float(np.max(d)) if d.size else 0.0
    assert worst <= atol, f"{what}: max distance {worst:.3g} > {atol:.3g} at index {int(np.argmax(d))}"


def assert_close(actual, expected, atol, what="value"):
    """``|actual - expected| <= atol`` elementwise, reporting the worst difference."""
    d = np.abs(np.asarray(actual, float) - np.asarray(expected, float))
    worst = float(np.max(d)) if d.size else 0.0
    assert worst <= atol, f"{what}: max difference {worst:.3g} > {atol:.3g}"


def run(*args):
    """The CLI in-process through ``main(argv)``: exit code, stdout and stderr."""
    import contextlib
    import io
    from types import SimpleNamespace

    from machsurf_cad._start import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:  # argparse usage errors
            code = exc.code
    return SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())


def run_process(*args, cwd=None):
    """The CLI as a user runs it (a new process): keeps exit codes and 'no traceback' honest."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-m", "machsurf_cad", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        timeout=600,
    )
