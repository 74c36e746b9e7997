"""Triangulation and STL through OCCT (linear deflection in mm, angular deflection in degrees)."""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.RWStl import RWStl
from OCP.StlAPI import StlAPI_Writer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Compound

from ..errors import InputError
from ..geometry.face import Face
from .convert import face_from_surface
from .quiet import quiet_occt


def _compound(faces: list[Face]):
    b = BRep_Builder()
    comp = TopoDS_Compound()
    b.MakeCompound(comp)
    topo = [face_from_surface(f.surface, [list(lp) for lp in f.loops] or None) for f in faces]
    for t in topo:
        b.Add(comp, t)
    return comp, topo


def triangulate_face(face: Face, *, linear_deflection: float = 0.05, angular_deflection: float = 10.0):
    """Triangulate a trimmed face: returns ``(points (n,3) mm, triangles (m,3) int, uv (n,2))``."""
    if not linear_deflection > 0:
        raise InputError("linear deflection must be > 0 mm")
    tf = face_from_surface(face.surface, [list(lp) for lp in face.loops] or None)
    BRepMesh_IncrementalMesh(tf, linear_deflection, False, math.radians(angular_deflection), True)
    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(tf, loc)
    if tri is None:
        raise InputError(f"OCCT could not triangulate face '{face.name}'")
    n = tri.NbNodes()
    pts = np.array([[tri.Node(i).X(), tri.Node(i).Y(), tri.Node(i).Z()] for i in range(1, n + 1)])
    uv = np.array([[tri.UVNode(i).X(), tri.UVNode(i).Y()] for i in range(1, n + 1)]) if tri.HasUVNodes() else None
    tris = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], dtype=np.int64) - 1
    return pts, tris, uv


def write_stl(path, faces: list[Face], *, linear_deflection: float = 0.01, angular_deflection: float = 5.0) -> Path:
    """Write faces as one binary STL meshed with the stated deflections (mm, degrees).

    Refused in one line, before meshing, when the mesh would exceed
    :data:`~machsurf_cad.geometry.meshsize.MAX_TRIANGLES` triangles (estimated from the faces' area and
    curvature), with a deflection that fits.
    """
    from ..geometry.meshsize import check_mesh_size

    if not linear_deflection > 0:
        raise InputError("linear deflection must be > 0 mm")
    what = f"{len(faces)} face(s) for {Path(path).name}"
    triangles = check_mesh_size(faces, linear_deflection, angular_deflection, what=what)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".stl", dir=str(path.parent))
    os.close(fd)
    try:
        args = (list(faces), linear_deflection, angular_deflection, tmp)
        err = _stoppable(_mesh_and_write, *args) if triangles > INLINE_TRIANGLES else _mesh_and_write(*args)
        if err:
            raise InputError(f"OCCT failed to write STL file {path}: {err}")
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


def _mesh_and_write(faces, linear_deflection: float, angular_deflection: float, tmp: str) -> str:
    """Mesh the faces and write the binary STL ``tmp``; an error text, empty on success."""
    comp, _ = _compound(faces)
    BRepMesh_IncrementalMesh(comp, linear_deflection, False, math.radians(angular_deflection), True)
    w = StlAPI_Writer()
    w.ASCIIMode = False
    with quiet_occt():
        ok = w.Write(comp, tmp)
    return "" if ok else "the writer failed"


INLINE_TRIANGLES = 200_000
"""Meshes estimated under this many triangles are made in this process (a second or so); larger ones in a
child process that Ctrl-C or SIGTERM stop at once."""


def _stoppable(fn, *args) -> str:
    """Run ``fn(*args)`` (which returns an error text) in a spawned child process and wait for it while
    signals are handled: a long OCCT call holds the interpreter and would delay Python's signal handlers
    until it ends. Spawned, not forked: a fork copies the locks of OCCT's and BLAS's own threads but not
    the threads, and the child can wait for ever (seen beside Dask and in pytest workers)."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    mine, theirs = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_child, args=(theirs, fn, args), daemon=True)
    child.start()
    theirs.close()
    try:
        while child.is_alive() and not mine.poll(0.2):
            pass
        msg = mine.recv() if mine.poll() else f"the meshing process ended with status {child.exitcode}"
        child.join()
        return msg
    except BaseException:
        child.kill()
        child.join()
        raise
    finally:
        mine.close()


def _child(conn, fn, args) -> None:
    """The spawned meshing process: ``fn(*args)``'s error text (or the exception's) back through ``conn``."""
    try:
        msg = fn(*args)
    except BaseException as exc:  # reported to the parent
        msg = f"{type(exc).__name__}: {exc}"
    conn.send(msg)
    conn.close()


def read_stl(path):
    """Read an STL file: ``(points (n,3), triangles (m,3))``; raises :class:`InputError` if unreadable."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"STL file not found: {p}")
    if p.stat().st_size == 0:
        raise InputError(f"STL file is empty: {p}")
    with quiet_occt():
        tri = RWStl.ReadFile_s(str(p))
    if tri is None or tri.NbNodes() == 0:
        raise InputError(f"could not read STL file {p} (corrupt or empty)")
    n = tri.NbNodes()
    pts = np.array([[tri.Node(i).X(), tri.Node(i).Y(), tri.Node(i).Z()] for i in range(1, n + 1)])
    tris = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], dtype=np.int64) - 1
    return pts, tris


def triangulate_step(path, *, linear_deflection: float = 0.01, angular_deflection: float = 5.0):
    """Mesh every face of a STEP part as read (no conversion): ``(points (n,3) mm, triangles (m,3) int)``.

    The mesh of the original B-rep, for references such as OpenCAMLib that work on triangles."""
    from OCP.TopAbs import TopAbs_REVERSED

    from .step import iter_faces, read_step_shape

    if not linear_deflection > 0:
        raise InputError("linear deflection must be > 0 mm")
    shape, _ = read_step_shape(path)
    BRepMesh_IncrementalMesh(shape, linear_deflection, False, math.radians(angular_deflection), True)
    P, T, base = [], [], 0
    for f in iter_faces(shape):
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(f, loc)
        if tri is None:
            raise InputError("OCCT could not triangulate a face of the part")
        trsf = loc.Transformation()
        n = tri.NbNodes()
        pts = []
        for i in range(1, n + 1):
            p = tri.Node(i).Transformed(trsf)
            pts.append((p.X(), p.Y(), p.Z()))
        t = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], dtype=np.int64) - 1
        if f.Orientation() == TopAbs_REVERSED:
            t = t[:, ::-1]
        P.append(np.array(pts))
        T.append(t + base)
        base += n
    return np.concatenate(P), np.concatenate(T)
