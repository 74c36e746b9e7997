"""``machsurf inspect`` on the real parts' main faces against OCCT's BRepExtrema (the inspect table).

For every main face named in ``shared/real-parts/README.md`` (propeller face 42, impeller faces 87
and 2, pump face 731, the pump in centimetres and read in mm) a +0.05 mm offset is built with OCP
(``Geom_OffsetSurface`` approximated by ``GeomConvert_ApproxSurface``, the approximation checked
against the offset surface at the same parameters on a 101 x 101 grid, to 1e-6 mm) and written to
STEP in a temporary folder, never into the repository:

* ``face``: the offset surface bounded like the nominal (its loops): every point reads +0.05 mm;
* ``box``: the offset of the face's whole parameter box (trimmed faces only): points beyond the
  trimming are measured to the face's boundary edges;
* ``derived``: impeller face 87 against the shared ``derived/turbo3d_impeller_face87_offset005.step``
  (the reported case). That file is not a uniform 0.05 mm offset: its surface is up to 0.43 mm from
  the offset surface at the same parameters, and BRepExtrema reads 0.018..0.057 mm on it
  (``GeomConvert_ApproxSurface`` C2 degree 11 makes such a surface while reporting 2e-7 mm).

BRepExtrema is run on the face as read and on the same face rebuilt by ``face_from_surface`` (edges'
3-D curves made from their curves on the surface): some edges of these files lie off their surface
by more than 1e-4 mm (pump face 731: 2e-3 mm, impeller face 2: 1.6e-4 mm), and BRepExtrema measures
to those 3-D curves, inspect to the face's surface bounded by its loops.

``inspect`` (the job the CLI runs) measures the candidate; BRepExtrema_DistShapeShape (point vertex
against the nominal ``TopoDS_Face``) measures a strided subset of the same points plus inspect's
extreme points. Run: ``python -m benchmarks.inspect_real_parts [--parts DIR] [--occ-points N]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
FACES = [
    ("ampath_propeller.stp", 42),
    ("turbo3d_impeller.step", 87),
    ("turbo3d_impeller.step", 2),
    ("ventpump.stp", 731),
]
OFFSET = 0.05


def real_parts_dir(given: str | None = None) -> Path | None:
    for cand in [given, "/work/shared/real-parts", ROOT.parent / "shared" / "real-parts"]:
        if cand and (Path(cand) / "README.md").is_file():
            return Path(cand)
    return None


def occ_face(path: Path, index: int):
    """The ``TopoDS_Face`` number ``index`` of a STEP file (the order ``read_step_face`` uses)."""
    from machsurf_cad.occ.step import iter_faces, read_step_shape

    shape, _ = read_step_shape(path)
    return list(iter_faces(shape))[index]


def offset_surface(tface, distance: float, box):
    """``Geom_BSplineSurface`` within 1e-6 mm of the face's surface offset by ``distance`` along its
    outward normal, checked at the same parameters over ``box``; returns ``(surface, error_mm)``."""
    from OCP.BRep import BRep_Tool
    from OCP.Geom import Geom_OffsetSurface
    from OCP.GeomAbs import GeomAbs_C1, GeomAbs_C2
    from OCP.GeomConvert import GeomConvert_ApproxSurface
    from OCP.TopAbs import TopAbs_REVERSED

    sign = -1.0 if tface.Orientation() == TopAbs_REVERSED else 1.0
    # isNotCheckC0: impeller face 2 has triple knots (C0 by its knots) but is C1 by its poles
    off = Geom_OffsetSurface(BRep_Tool.Surface_s(tface), sign * distance, True)
    u0, u1, v0, v1 = box
    uv = [(u, v) for u in np.linspace(u0, u1, 101) for v in np.linspace(v0, v1, 101)]
    exact = np.array([[p.X(), p.Y(), p.Z()] for p in (off.Value(u, v) for u, v in uv)])
    best = None
    # OCCT's MaxError is not trusted: a C2 degree-11 approximation of impeller face 87's offset reports
    # 2e-7 mm and is far off (BRepExtrema reads 0.025..0.055 mm on it, like the shared derived file)
    for cont, deg, seg in ((GeomAbs_C1, 9, 1000), (GeomAbs_C2, 9, 1000), (GeomAbs_C1, 7, 4000)):
        ap = GeomConvert_ApproxSurface(off, 1e-7, cont, cont, deg, deg, seg, 1)
        if not ap.HasResult():
            continue
        s = ap.Surface()
        got = np.array([[p.X(), p.Y(), p.Z()] for p in (s.Value(u, v) for u, v in uv)])
        err = float(np.linalg.norm(got - exact, axis=1).max())
        if best is None or err < best[1]:
            best = (s, err)
        if err <= 1e-6:
            return best
    raise RuntimeError(f"no approximation of the offset within 1e-6 mm (best {best and best[1]:.3g} mm)")


def brep_distances(tface, points) -> np.ndarray:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.gp import gp_Pnt

    out = np.empty(len(points))
    for i, p in enumerate(points):
        ds = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, p))).Vertex(), tface)
        if not ds.IsDone():
            raise RuntimeError(f"BRepExtrema failed at {p}")
        out[i] = ds.Value()
    return out


def _checked_points(signed: np.ndarray, n: int) -> np.ndarray:
    """A strided subset of about ``n`` points plus the 20 smallest and 20 largest readings."""
    stride = max(1, signed.size // n)
    order = np.argsort(signed)
    return np.unique(np.concatenate([np.arange(0, signed.size, stride), order[:20], order[-20:]]))


def inspect_row(nominal: Path, index: int, candidate: Path, label: str, tfaces, occ_points: int, samples: int):
    from machsurf_cad.jobs import InspectJob, run_job

    with tempfile.TemporaryDirectory() as out:
        t = time.perf_counter()
        job = InspectJob(nominal=str(nominal), candidate=str(candidate), face=index, candidate_face=0, render=False,
                         samples=samples)  # fmt: skip
        res = run_job(job, Path(out) / "inspect").result
        t_inspect = time.perf_counter() - t
    sel = _checked_points(res.signed, occ_points)
    t = time.perf_counter()
    occ = brep_distances(tfaces[0], res.points[sel])
    t_occ = time.perf_counter() - t
    rebuilt = brep_distances(tfaces[1], res.points[sel])
    mine = np.abs(res.signed[sel])
    return {
        "face": f"{nominal.stem} {index}",
        "candidate": label,
        "n_points": int(res.signed.size),
        "inspect_min_mm": float(res.signed.min()),
        "inspect_max_mm": float(res.signed.max()),
        "n_outside_trim": int(res.outside_trim.sum()) if res.outside_trim is not None else 0,
        "n_checked": int(sel.size),
        "occ_min_mm": float(occ.min()),
        "occ_max_mm": float(occ.max()),
        "max_abs_diff_mm": float(np.abs(mine - occ).max()),
        "max_abs_diff_rebuilt_mm": float(np.abs(mine - rebuilt).max()),
        "inspect_s": t_inspect,
        "occ_s": t_occ,
    }


def face_rows(parts: Path, name: str, index: int, tmp: Path, occ_points: int, samples: int) -> list[dict]:
    from machsurf_cad.geometry.face import Face
    from machsurf_cad.occ import face_from_surface, from_geom_surface, read_step_face, write_step

    nominal = parts / name
    face = read_step_face(nominal, index)
    tface = occ_face(nominal, index)
    # the same face with its edges' 3-D curves rebuilt from their curves on the surface: some edges of
    # these files lie off their surface by more than their tolerance (pump face 731: 2e-3 mm)
    rebuilt = face_from_surface(face.surface, [list(lp) for lp in face.loops] or None)
    geom, err = offset_surface(tface, OFFSET, face.uv_bounds)
    surf = from_geom_surface(geom, name="offset")
    rows = []
    variants = [("face", face.loops)] + ([("box", ())] if face.is_trimmed else [])
    for label, loops in variants:
        path = tmp / f"{nominal.stem}_{index}_{label}.step"
        write_step(path, [Face(surf, loops, f"offset_{label}", uv_bounds=face.uv_bounds)])
        row = inspect_row(nominal, index, path, label, (tface, rebuilt), occ_points, samples)
        row["offset_approx_error_mm"] = err
        rows.append(row)
    return rows


_COLUMNS = [  # (title, width, format of a row)
    ("face", 22, lambda r: r["face"]),
    ("candidate", 9, lambda r: r["candidate"]),
    ("points", 6, lambda r: str(r["n_points"])),
    ("inspect min / max (mm)", 23, lambda r: f"{r['inspect_min_mm']:.6f} / {r['inspect_max_mm']:.6f}"),
    ("checked", 7, lambda r: str(r["n_checked"])),
    ("BRepExtrema min / max (mm)", 26, lambda r: f"{r['occ_min_mm']:.6f} / {r['occ_max_mm']:.6f}"),
    ("max abs diff (mm)", 17, lambda r: f"{r['max_abs_diff_mm']:.2e}"),
    ("rebuilt edges: max abs diff", 27, lambda r: f"{r['max_abs_diff_rebuilt_mm']:.2e}"),
    ("inspect s", 9, lambda r: f"{r['inspect_s']:.2f}"),
    ("BRepExtrema s", 13, lambda r: f"{r['occ_s']:.1f}"),
]


def print_table(rows: list[dict]) -> None:
    """The rows as a Markdown table."""
    print("| " + " | ".join(f"{t:>{w}}" for t, w, _ in _COLUMNS) + " |")
    print("|" + "|".join("-" * (w + 2) for _, w, _ in _COLUMNS) + "|")
    for r in rows:
        print("| " + " | ".join(f"{f(r):>{w}}" for _, w, f in _COLUMNS) + " |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.inspect_real_parts", description=__doc__.split("\n")[0])
    ap.add_argument("--parts", default=None, help="folder of the real parts (default: shared/real-parts)")
    ap.add_argument("--occ-points", type=int, default=2000, help="points measured by BRepExtrema per row")
    ap.add_argument("--samples", type=int, default=200, help="inspect grid size per direction")
    args = ap.parse_args(argv)
    parts = real_parts_dir(args.parts)
    if parts is None:
        print("real parts not found (shared/real-parts)", file=sys.stderr)
        return 1
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for name, index in FACES:
            rows += face_rows(parts, name, index, Path(d), args.occ_points, args.samples)
    derived = parts / "derived" / "turbo3d_impeller_face87_offset005.step"
    if derived.is_file():  # the reported case, on the shared file (not a uniform offset: see the docstring)
        from machsurf_cad.occ import read_step_face
        from machsurf_cad.occ.convert import face_from_surface

        nominal = parts / "turbo3d_impeller.step"
        face = read_step_face(nominal, 87)
        tfaces = (occ_face(nominal, 87), face_from_surface(face.surface, None))
        rows.append(inspect_row(nominal, 87, derived, "derived", tfaces, args.occ_points, args.samples))
    print_table(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
