"""Runs inside FreeCADCmd: Import.insert of each STEP file in MACHSURF_STEP_FILES (os.pathsep-separated);
writes, per file, the labels FreeCAD shows and the number of faces it imported, to MACHSURF_FC_OUT."""

import json
import os
import traceback

out_path = os.environ["MACHSURF_FC_OUT"]
result = {"ok": False, "files": {}}
try:
    import FreeCAD
    import Import

    for path in os.environ["MACHSURF_STEP_FILES"].split(os.pathsep):
        doc = FreeCAD.newDocument("imp")
        Import.insert(path, doc.Name)
        faces = sum(len(o.Shape.Faces) for o in doc.Objects if hasattr(o, "Shape") and o.TypeId == "Part::Feature")
        result["files"][os.path.basename(path)] = {"labels": [o.Label for o in doc.Objects], "faces": faces}
        FreeCAD.closeDocument(doc.Name)
    result["ok"] = True
except Exception:
    result["error"] = traceback.format_exc()
finally:
    with open(out_path, "w") as fh:
        json.dump(result, fh, indent=1)
    os._exit(0)
