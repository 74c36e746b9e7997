"""Envelope of one pass: 200 x 200 evaluation of eq. (21) and the certified fit at 1e-3 mm (goal < 1 s),
against brute force: the envelope of 200 discrete tool positions sampled densely (the reference way)."""

from __future__ import annotations

import time

import numpy as np

from machsurf_cad.examples import sine_motion
from machsurf_cad.sweep import make_envelope
from machsurf_cad.sweep.passes import fit_pass


def envelope_rows(quick=False):
    rows = []
    for tool in ("cone:D=10,angle=10,L=20", "drum:D=20,Rp=40,L=20"):
        env = make_envelope(sine_motion(), tool)
        a = np.linspace(*env.a_range, 200)
        t = np.linspace(0, 1, 200)
        best = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            env.grid(a, t)  # the 200 x 200 evaluation, timed with the fit
            fit = fit_pass(env, 1e-3)
            best = min(best, time.perf_counter() - t0)
        # brute force: for 200 positions, the tool's grazing points found by sampling each tool's
        # surface densely and keeping those whose normal is orthogonal to the local velocity
        t0 = time.perf_counter()
        m = env.motion
        err = 0.0
        for tk in t[::20]:
            T, A, dT, dA = (
                m.T(np.array([tk]))[0],
                m.A(np.array([tk]))[0],
                m.dT(np.array([tk]))[0],
                m.dA(np.array([tk]))[0],
            )
            aa = np.linspace(*env.a_range, 400)
            ph = np.linspace(0, 2 * np.pi, 2000)
            ref = np.array([1.0, 0, 0]) if abs(A[0]) < 0.9 else np.array([0, 1.0, 0])
            e1 = np.cross(A, ref)
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(A, e1)
            g = env.segment.grazing_points(aa)  # (rho, z) on the profile
            P = (T + g[:, 1, None] * A)[:, None, :] + g[:, 0, None, None] * (
                np.cos(ph)[None, :, None] * e1 + np.sin(ph)[None, :, None] * e2
            )
            c = T + aa[:, None] * A
            nrm = P - c[:, None, :]
            vel = dT + np.cross(np.cross(A, dA), P - T)  # rigid motion: translation + rotation of the axis
            f = np.abs(np.einsum("ijk,ijk->ij", nrm, vel)) / np.linalg.norm(nrm, axis=-1) / np.linalg.norm(vel, axis=-1)
            j = np.argmin(np.where(np.einsum("ijk,k->ij", nrm, np.cross(A, dT)) > 0, f, np.inf), axis=1)
            brute = P[np.arange(400), j]
            exact = env.points(aa, np.full(400, tk))
            err = max(err, float(np.linalg.norm(brute - exact, axis=1).max()))
        t_b = (time.perf_counter() - t0) * 20  # 10 positions measured, scaled to 200
        rows.append(
            {
                "name": f"envelope 200^2 + fit 1e-3, {tool.split(',')[0]} ({fit.n_poles} poles)",
                "n": 40000,
                "ours_s": best,
                "ref_s": t_b,
                "ref": "brute grazing search*",
                "max_diff": err,
            }
        )
    return rows
