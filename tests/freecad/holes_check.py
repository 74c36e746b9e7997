"""Runs inside FreeCADCmd: faces with inner wires (a plate with a round hole; a plate with a circle, an
ellipse and a closed spline hole; a cylinder's side pierced by a cross hole; the block's bottom face)
converted to machsurf_cad and back. Writes, per face, the wire counts, the meshed areas (FreeCAD's own
``Area`` integrates trimmed NURBS faces only roughly) and the in/out answers of the core at points in the
holes and in the material, to the JSON file named by MACHSURF_FC_OUT."""

import json
import os
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
root = os.environ["MACHSURF_ROOT"]
result = {"ok": False}


def mesh_area(face, tol=0.001):
    import numpy as np

    pts, tris = face.tessellate(tol)
    P = np.array([[p.x, p.y, p.z] for p in pts])
    T = np.array(tris)
    return float(0.5 * np.linalg.norm(np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]), axis=1).sum())


try:
    import FreeCAD
    import numpy as np
    import Part
    from freecad.machsurf import features
    from freecad.machsurf.convert import face_to_numpy, face_to_part

    V = FreeCAD.Vector
    cases = {}
    plate = Part.makeBox(100, 80, 10).cut(Part.makeCylinder(10, 10, V(50, 40, 0)))
    cases["round_hole"] = (plate, [(50, 40, 10)], [(20, 20, 10)])
    ell = Part.Face(Part.Wire(Part.Ellipse(V(75, 40, 0), 12, 6).toShape())).extrude(V(0, 0, 10))
    spl = Part.BSplineCurve()
    ang = np.linspace(0, 2 * np.pi, 9)[:-1]
    spl.interpolate([V(40 + 8 * np.cos(a), 20 + 5 * np.sin(a) + 2 * np.sin(3 * a), 0) for a in ang], PeriodicFlag=True)
    sp = Part.Face(Part.Wire(spl.toShape())).extrude(V(0, 0, 10))
    three = Part.makeBox(100, 80, 10).cut(Part.makeCylinder(8, 10, V(20, 60, 0))).cut(ell).cut(sp)
    cases["three_holes"] = (three, [(20, 60, 10), (75, 40, 10), (40, 20, 10)], [(5, 5, 10), (60, 70, 10)])
    cyl = Part.makeCylinder(30, 100).cut(Part.makeCylinder(5, 80, V(0, -40, 50), V(0, 1, 0)))
    cases["pierced_cylinder"] = (cyl, [(0, 30, 50), (0, -30, 50)], [(-30, 0, 50), (0, 30, 20)])
    block = Part.read(os.path.join(root, "example_parts", "freeform_block.step"))
    cases["block_bottom"] = (block, [], [])
    for name, (shape, in_holes, in_material) in cases.items():
        if name == "block_bottom":
            face = min(shape.Faces, key=lambda f: f.CenterOfMass.z)
        elif name == "pierced_cylinder":
            face = max(shape.Faces, key=lambda f: f.Area)
        else:
            face = [f for f in shape.Faces if abs(f.CenterOfMass.z - 10) < 1e-6][0]
        nf = face_to_numpy(face, name)
        back = face_to_part(nf)

        def inside(points, face=face, nf=nf):
            if not points:
                return []
            uv = []
            for p in points:
                u, v = face.Surface.parameter(V(*p))
                uv.append((u, v))
            uv = np.array(uv, float)
            # parameters of FreeCAD's surface are those of the converted NURBS face for these surfaces
            return [bool(x) for x in nf.contains_uv(uv[:, 0], uv[:, 1])]

        result[name] = {
            "wires": len(face.Wires),
            "loops": len(nf.loops),
            "back_wires": len(back.Wires),
            "back_valid": bool(back.isValid()),
            "area": mesh_area(face),
            "back_area": mesh_area(back),
            "hole_points_inside": inside(in_holes),
            "material_points_inside": inside(in_material),
        }
    # a trimming loop with gaps, as CATIA writes them (3.4e-5 mm on the propeller's face 42): a 60 x 40 square
    # on a plane whose four sides miss each other by 3e-5; FreeCAD's wire would not close without closing them
    from machsurf_cad.geometry import BSplineCurve, builders
    from machsurf_cad.geometry.face import Face

    plane = builders.plane_patch((0, 0, 0), (100, 0, 0), (0, 100, 0))
    corners = np.array([[0.2, 0.3], [0.8, 0.3], [0.8, 0.7], [0.2, 0.7]])
    gap = np.array([3e-7, -2e-7])  # parameter units: 3e-5 / 100 mm
    sides = [
        BSplineCurve(1, np.array([0.0, 1.0]), np.array([2, 2]), np.array([corners[i] + gap, corners[(i + 1) % 4]]))
        for i in range(4)
    ]
    gapped = Face(plane, [sides], "gapped")
    back = face_to_part(gapped)
    result["gapped_loop"] = {"valid": bool(back.isValid()), "wires": len(back.Wires), "area": back.Area,
                             "closed": bool(back.Wires[0].isClosed())}  # fmt: skip
    doc = FreeCAD.newDocument("holes")
    obj = doc.addObject("Part::Feature", "Plate")
    obj.Shape = plate
    top = [i for i, f in enumerate(plate.Faces) if abs(f.CenterOfMass.z - 10) < 1e-6][0]
    ms = features.make(
        "MachiningSurface", doc, (obj, [f"Face{top + 1}"]), Tool="ball:D=10", Axes="3"
    )  # Lead keeps its 5-axis default
    doc.recompute()
    result["feature"] = {"valid": ms.isValid(), "status": ms.Status, "wires": [len(f.Wires) for f in ms.Shape.Faces]}
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
with open(out_path, "w") as fh:
    json.dump(result, fh, indent=1)
