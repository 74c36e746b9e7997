"""GUI of the machsurf add-on: workbench, commands, task panel, view providers (imports FreeCADGui)."""
