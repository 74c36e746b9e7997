"""``mill3``: 3-axis (and 3+2) tool paths on a whole part, checked against every face before use.

The API entry of the whole-part engine (``machsurf mill3`` and the FreeCAD CAM operation call it):
choose the machined faces (``top``, ``all`` or indices) and the check faces (the rest of the part by
default), plan a raster or waterline path with the exact drop-cutter on the B-rep, then check the
tool body against every face of the part (:func:`machsurf_cad.pathcheck.check_toolpath`).
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import checks
from ..cam.toolpath import ToolPath
from ..errors import InputError
from ..gougecheck import _faces
from ..pathcheck import OnGouge, PathCheck, check_toolpath
from ..results import Progress, Result
from ..typing import PartLike, ToolLike, Vector3
from .paths import raster
from .reach import reachable_area
from .select import faces_away, select_faces
from .zlevel import waterline


@dataclass(frozen=True, eq=False)
class Mill3Result(Result):
    """A whole-part 3-axis path: the faces machined and checked, and the verdict of the body check.

    ``toolpath`` is what may be cut (``None`` when the check refused the path); ``planned`` the path as
    generated; ``check`` the :class:`~machsurf_cad.pathcheck.PathCheck`.
    """

    planned: ToolPath
    check: PathCheck
    faces_machined: tuple[int, ...]
    faces_checked: tuple[int, ...]
    axis: tuple[float, float, float]
    reach: tuple = ()
    """Per machined face: the area the tool can touch along the axis and what the dropped tool touches
    (:func:`~machsurf_cad.threeaxis.reach.reachable_area`)."""

    @property
    def toolpath(self) -> ToolPath | None:
        return self.check.toolpath

    @property
    def verdict(self) -> str:
        return self.check.verdict

    def report(self) -> dict:
        return {
            "axis": list(self.axis),
            "faces_machined": list(self.faces_machined),
            "faces_checked": list(self.faces_checked),
            "toolpath": self.planned.report(),
            "verify": self.check.report(),
            "verdict": self.verdict,
            "reach": list(self.reach),
            **self.reach_summary(),
        }

    def reach_summary(self) -> dict:
        """Area-weighted fractions over the machined faces, and the faces the tool can barely touch (< 5 %)."""
        return _reach_summary(self.reach)


def _reach_summary(reach) -> dict:
    area = sum(r["area_mm2"] for r in reach)
    if not area:
        return {}
    return {
        "reachable_fraction": sum(r["reachable_mm2"] for r in reach) / area,
        "touched_fraction": sum(r["touched_mm2"] for r in reach) / area,
        "faces_out_of_reach": [r["face"] for r in reach if r["reachable_fraction"] < 0.05],
    }


def machined_and_checked(part, faces: str, check_faces: str, axis) -> tuple[list[int], list[int]]:
    """Indices of the machined faces and of the check faces (``rest``/``all``: the others; ``none``; indices)."""
    machined = select_faces(part, faces or "all", axis=axis, what="--faces")
    chk = str(check_faces).strip().lower()
    if chk in ("rest", "all"):
        checked = [i for i in range(len(part)) if i not in machined]
    else:
        checked = [i for i in select_faces(part, chk, axis=axis, what="--check-faces") if i not in machined]
    return machined, checked


def mill3(
    part: PartLike,
    tool: ToolLike,
    *,
    faces: str = "top",
    check_faces: str = "rest",
    axis: Vector3 = (0.0, 0.0, 1.0),
    pattern: str = "raster",
    stepover: float | None = None,
    scallop: float | None = None,
    angle: float = 0.0,
    direction: str = "zigzag",
    stepdown: float | None = None,
    grid_step: float | None = None,
    chordal_tolerance: float = 0.005,
    clearance: float = 5.0,
    gouge_tolerance: float = 0.01,
    on_gouge: OnGouge = "refuse",
    progress: Progress | None = None,
) -> Mill3Result:
    """A raster or waterline path on the chosen faces of a whole part, checked against all its faces.

    Parameters
    ----------
    part : sequence of Face
        Every face of the part (``ms.occ.read_step(path)`` reads them from a STEP file).
    tool : Cutter or str
        Any cutter (ball, flat, bull, cone, drum, APT) with its shank and holder.
    faces : str
        Faces to machine: ``top`` (seen along the axis), ``all`` or indices ``"0,3,5"``.
    check_faces : str
        Faces the tool must not cut into while machining: ``rest`` (the default), ``none`` or indices.
        The final check is against every face whatever this says.
    axis : 3-vector
        Fixed tool axis (3+2 machining), default +Z.
    pattern : {"raster", "waterline"}
    stepover, scallop : float, optional
        Distance between raster lines, or the cusp height that sets it (not both; default step-over 2).
    angle : float
        Raster direction in the plane, degrees.
    direction : {"zigzag", "one-way"}
    stepdown, grid_step : float, optional
        Waterline: distance between levels (default the step-over) and plan grid of heights, mm.
    chordal_tolerance, clearance, gouge_tolerance : float
        Chordal error of the positions, retract height above the part, deepest gouge allowed (mm).
    on_gouge : {"refuse", "trim", "allow"}
        What the body check does with a gouging path (:func:`~machsurf_cad.pathcheck.check_toolpath`).
    progress : Progress, optional

    Returns
    -------
    Mill3Result

    Raises
    ------
    InputError
        Bad arguments, or a tool along the axis that touches none of the machined faces (other faces in
        front of them): nothing to machine, before any planning.

    Examples
    --------
    >>> import machsurf_cad as ms
    >>> r = ms.mill3([ms.example("bezier5")], "ball:D=10", faces="all", stepover=8.0)
    >>> r.verdict, r.toolpath is not None
    ('clean', True)
    """
    part = _faces(part, "mill3")
    tool = checks.tool(tool)
    axis = tuple(float(a) for a in axis)
    if pattern not in ("raster", "waterline"):
        raise InputError(f"pattern must be raster or waterline, got {pattern!r}")
    machined, checked = machined_and_checked(part, faces, check_faces, axis)
    if pattern == "raster" and str(faces).strip().lower() not in ("all", "top"):
        vertical = [i for i in machined if faces_away(part[i], axis, below=0.01)]
        if vertical and len(vertical) == len(machined):
            raise InputError(
                f"face {vertical[0]} is parallel to the tool axis: a raster along it touches the face only at its "
                "edges; use --pattern waterline (or another --axis)"
            )
    mf, cf = [part[i] for i in machined], [part[i] for i in checked]
    both = machined + checked
    reach = reachable_area([part[i] for i in both], range(len(machined)), tool, axis=axis)
    for r in reach:
        r["face"] = machined[r["face"]]
    if reach and not any(r["reachable_mm2"] > 0.0 for r in reach):  # (a wall is reached, not touched by a drop)
        names = ", ".join(str(i) for i in machined)
        if all(faces_away(part[i], axis, below=0.01) for i in machined):  # walls only (a tube, a fin)
            raise InputError(
                f"face(s) {names} are parallel to the tool axis {list(axis)} or face away from it: a tool coming "
                "down the axis touches them only at their edges, and reaches none of them: nothing to machine "
                "along this axis"
            )
        raise InputError(
            f"the tool along {list(axis)} reaches none of face(s) {names}: other faces stand in front of them: "
            "nothing to machine along this axis"
        )
    step = 2.0 if stepover is None else float(stepover)
    common = dict(check_faces=cf, chordal_tolerance=chordal_tolerance, clearance=clearance, axis=axis,
                  gouge_tolerance=gouge_tolerance, progress=progress)  # fmt: skip
    if pattern == "raster":
        tp = raster(mf, tool, stepover=None if scallop is not None else step, scallop=scallop, angle=angle,
                    direction=direction, **common)  # fmt: skip
    else:
        tp = waterline(mf, tool, stepdown=stepdown or step, grid_step=grid_step, **common)
    pc = check_toolpath(tp, part, gouge_tolerance=gouge_tolerance, on_gouge=on_gouge, clearance=clearance)
    return Mill3Result(tp, pc, tuple(machined), tuple(checked), axis, tuple(reach))  # type: ignore[arg-type]
