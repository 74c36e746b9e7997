"""Runs inside FreeCADCmd (benchmarks/bench_freecad.py): the CAM operation's raster on the example block at
its defaults, timed from the operation's creation to the end of the document's recompute, the numba kernel
loaded first (compiled on a machine's first run); then a second operation with another step-over (the
part's caches reused). Writes the figures as JSON to MACHSURF_BENCH_OUT."""

import json
import os
import time

result = {}
try:
    import FreeCAD
    import Part
    from freecad.machsurf import features

    try:
        import numba

        result["numba"] = numba.__version__
    except ImportError:
        result["numba"] = None
    doc = FreeCAD.newDocument("bench")
    part = doc.addObject("Part::Feature", "Block")
    part.Shape = Part.read(os.path.join(os.environ["MACHSURF_ROOT"], "example_parts", "freeform_block.step"))
    faces = part.Shape.Faces
    spline = [i for i, f in enumerate(faces) if isinstance(f.Surface, Part.BSplineSurface)]
    top = max(spline, key=lambda i: faces[i].Area)
    from machsurf_cad.threeaxis import compiled

    result["kernel_s"] = compiled.warm_up() if compiled.available() else 0.0  # compiled once, else loaded
    t = time.perf_counter()
    op = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster")
    doc.recompute()
    result["raster_s"] = time.perf_counter() - t  # the part's faces converted, sampled, solved, checked
    t = time.perf_counter()
    again = features.make("CamOperation", doc, (part, [f"Face{top + 1}"]), Pattern="raster", StepOver=2.5)
    doc.recompute()
    result["other_stepover_s"] = time.perf_counter() - t  # the same part and tool: its caches reused
    result.update(
        face=top,
        tool=op.CutterUsed,
        stepover=op.StepOver.Value,
        status=op.Status,
        verdict=op.Verdict,
        cut_points=op.CutPoints,
        max_gouge=op.MaxGouge.Value,
        chordal=op.ChordalTolerance.Value,
        gouge_tolerance=op.GougeTolerance.Value,
        clearance=op.Clearance.Value,
    )
except Exception:
    import traceback

    result["error"] = traceback.format_exc()
finally:
    with open(os.environ["MACHSURF_BENCH_OUT"], "w") as fh:
        json.dump(result, fh, indent=1, default=str)
    os._exit(0)
