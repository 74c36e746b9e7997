"""The machsurf workbench: toolbar and menu, one command per feature, export (GUI only)."""

import os

import FreeCADGui as Gui

from . import commands, session


class MachsurfWorkbench(Gui.Workbench):
    MenuText = "machsurf"
    ToolTip = "Free-form machining geometry: machining surfaces, effective radius, flank milling, envelopes"
    Icon = commands.ICON

    def Initialize(self):
        commands.register()
        session.install()  # exact lengths in the property editor; the GUI live while recomputing
        self.appendToolbar("machsurf", commands.NAMES)
        self.appendMenu("machsurf", commands.NAMES)

    def GetClassName(self):
        return "Gui::PythonWorkbench"


Gui.addWorkbench(MachsurfWorkbench())
# Edit > Preferences > machsurf: default tolerance and grid of new features, the tool library (its icon is
# resources/preferences-machsurf.svg, found on the icon path by the page group's name)
Gui.addIconPath(commands.RESOURCES)
Gui.addPreferencePage(os.path.join(commands.RESOURCES, "preferences.ui"), "machsurf")
