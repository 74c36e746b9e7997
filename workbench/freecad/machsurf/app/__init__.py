"""App-level features of the machsurf add-on: no GUI import, they recompute headless in FreeCADCmd."""
