"""Exact OCCT solids of cutters (revolved profiles), for viewing and export."""

from __future__ import annotations

import math

import numpy as np
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeWire,
    BRepBuilderAPI_Transform,
)
from OCP.BRepGProp import BRepGProp
from OCP.BRepPrimAPI import BRepPrimAPI_MakeRevol
from OCP.GC import GC_MakeArcOfCircle, GC_MakeSegment
from OCP.gp import gp_Ax1, gp_Ax3, gp_Dir, gp_Pnt, gp_Trsf
from OCP.GProp import GProp_GProps

from ..cutters import Cutter, LineSegment
from ..errors import InputError
from .convert import check_valid


def _p(rho, z):
    return gp_Pnt(float(rho), 0.0, float(z))


def cutter_solid(cutter: Cutter, *, tip=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)):
    """Solid of revolution of the cutter's profile, tip at ``tip`` (mm), axis along ``axis``."""
    mk = BRepBuilderAPI_MakeWire()
    segs = cutter.profile()
    for seg in segs:
        if isinstance(seg, LineSegment):
            if math.hypot(seg.rho1 - seg.rho0, seg.z1 - seg.z0) < 1e-12:
                continue
            curve = GC_MakeSegment(_p(seg.rho0, seg.z0), _p(seg.rho1, seg.z1)).Value()
        else:
            pts = seg.points(3)
            curve = GC_MakeArcOfCircle(_p(*pts[0]), _p(*pts[1]), _p(*pts[2])).Value()
        mk.Add(BRepBuilderAPI_MakeEdge(curve).Edge())
    # close along the axis
    first = segs[0].points(2)[0]
    last = segs[-1].points(2)[-1]
    if last[0] > 1e-12:
        mk.Add(BRepBuilderAPI_MakeEdge(GC_MakeSegment(_p(*last), _p(0.0, last[1])).Value()).Edge())
    if abs(last[1] - first[1]) > 1e-12:
        mk.Add(BRepBuilderAPI_MakeEdge(GC_MakeSegment(_p(0.0, last[1]), _p(*first)).Value()).Edge())
    if not mk.IsDone():
        raise InputError(f"could not close the profile of {cutter.spec()}")
    face = BRepBuilderAPI_MakeFace(mk.Wire(), True).Face()
    solid = BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2 * math.pi).Shape()
    a = np.asarray(axis, float)
    if np.linalg.norm(a) == 0:
        raise InputError("tool axis must be non-zero")
    a = a / np.linalg.norm(a)
    trsf = gp_Trsf()
    ref = np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 1.0, 0])
    trsf.SetTransformation(gp_Ax3(gp_Pnt(*map(float, tip)), gp_Dir(*map(float, a)), gp_Dir(*map(float, ref))), gp_Ax3())
    solid = BRepBuilderAPI_Transform(solid, trsf.Inverted(), True).Shape()
    check_valid(solid, what=f"cutter solid {cutter.spec()}")
    return solid


def solid_volume(shape) -> float:
    """Volume (mm^3) of a solid as computed by OCCT."""
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return float(props.Mass())
