"""FreeCAD's entry point for the GUI: the workbench lives in :mod:`freecad.machsurf.gui`."""

from .gui import workbench  # noqa: F401
