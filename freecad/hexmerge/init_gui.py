# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI entry point, imported by FreeCAD at start-up (new-style namespace add-on)."""

import os

from freecad import app, gui

ICON = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(__file__))),
                    "resources", "icons", "HexMerge_Workbench.svg")
COMMANDS = ["HexMerge_MeshHexDominant", "HexMerge_MeshHexDominantFromShape"]
FEM_TOOLBAR_NAME = "HexMerge"


class HexMergeWorkbench(gui.Workbench):
    MenuText = "HexMerge"
    ToolTip = "Hex-dominant FEM meshes from tetrahedral meshes or solids"
    Icon = ICON

    def GetClassName(self):
        return "Gui::PythonWorkbench"

    def Initialize(self):
        from . import commands  # noqa: F401  (registers the commands)
        self.appendToolbar("HexMerge", COMMANDS)
        self.appendMenu("HexMerge", COMMANDS)

    def Activated(self):
        pass

    def Deactivated(self):
        pass


def add_fem_toolbar():
    """Puts the command in a "HexMerge" toolbar of the FEM workbench.

    FreeCAD 0.20 has no API for an add-on to extend another workbench's menus or toolbars; it does
    restore custom toolbars (Tools > Customize > Toolbars) from the user parameters, loading the
    module named beside each command. Writing one such entry, once, makes the command reachable
    from the FEM workbench; the user can remove it in that same dialog.
    """
    base = app.ParamGet("User parameter:BaseApp/Workbench/FemWorkbench/Toolbar")
    for group in base.GetGroups():
        if base.GetGroup(group).GetString("Name") == FEM_TOOLBAR_NAME:
            return
    n = 1
    while "Custom_{}".format(n) in base.GetGroups():
        n += 1
    bar = base.GetGroup("Custom_{}".format(n))
    bar.SetString("Name", FEM_TOOLBAR_NAME)
    bar.SetBool("Active", True)
    for cmd in COMMANDS:
        bar.SetString(cmd, "freecad.hexmerge.commands")


gui.addWorkbench(HexMergeWorkbench())
from . import commands as _commands  # noqa: E402,F401  (commands exist before any workbench loads)
add_fem_toolbar()
