# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI entry point, imported by FreeCAD at start-up (new-style namespace add-on): the HexMerge
workbench, the commands, and the commands' place in FEM's Mesh menu and toolbar."""

from freecad import app, gui

from . import commands
from .resources import resource_path

FEM_WORKBENCH = "FemWorkbench"
# FEM's own mesh commands; ours go right after the last of them found in a menu or toolbar.
FEM_MESHERS = ("FEM_MeshNetgenFromShape", "FEM_MeshGmshFromShape")
OLD_FEM_TOOLBAR_NAME = "HexMerge"  # a custom FEM toolbar written by add-on versions up to 0.1


class HexMergeWorkbench(gui.Workbench):
    MenuText = "HexMerge"
    ToolTip = "Hex-dominant FEM meshes from tetrahedral meshes or solids"
    Icon = resource_path("icons", "HexMerge_Workbench.svg")

    def GetClassName(self):
        return "Gui::PythonWorkbench"

    def Initialize(self):
        self.appendToolbar("HexMerge", commands.COMMAND_NAMES)
        self.appendMenu("HexMerge", commands.COMMAND_NAMES)

    def Activated(self):
        pass

    def Deactivated(self):
        pass


def command_actions(name):
    command = gui.Command.get(name)
    return list(command.getAction()) if command is not None else []


def insert_after_fem_meshers(container):
    """Inserts the HexMerge commands' actions into a QMenu or QToolBar after FEM's Gmsh and
    Netgen entries, if it has them and not ours yet. Returns True when it holds ours."""
    present = container.actions()
    fem = [a for name in FEM_MESHERS for a in command_actions(name) if a in present]
    if not fem:
        return False
    ours = [a for name in commands.COMMAND_NAMES for a in command_actions(name)]
    if all(a in present for a in ours):
        return True
    last = max(present.index(a) for a in fem)
    before = present[last + 1] if last + 1 < len(present) else None
    for action in ours:
        if action in present:
            continue
        if before is None:
            container.addAction(action)
        else:
            container.insertAction(before, action)
    return True


def add_to_fem_menus(workbench=None):
    """Puts both commands into FEM's Mesh menu and Mesh toolbar, beside Gmsh and Netgen.

    FreeCAD 0.20 has no API for an add-on to extend another workbench's menus; FreeCAD rebuilds
    them on each activation, so this runs on every activation of the FEM workbench (connected to
    the main window's workbenchActivated) and inserts the commands' own QActions, which FreeCAD
    keeps enabled, disabled and tipped (commands.CommandBase.show_reason)."""
    from PySide import QtGui
    if (workbench or gui.activeWorkbench().name()) != FEM_WORKBENCH:
        return False
    window = gui.getMainWindow()
    found = False
    for menu in window.menuBar().findChildren(QtGui.QMenu):
        found = insert_after_fem_meshers(menu) or found
    for bar in window.findChildren(QtGui.QToolBar):
        found = insert_after_fem_meshers(bar) or found
    return found


def remove_old_fem_toolbar():
    """Removes the custom "HexMerge" FEM toolbar that earlier versions wrote into the user
    parameters (the commands are in FEM's own Mesh menu and toolbar now)."""
    base = app.ParamGet("User parameter:BaseApp/Workbench/FemWorkbench/Toolbar")
    for group in base.GetGroups():
        bar = base.GetGroup(group)
        names = {entry[1] for entry in (bar.GetContents() or [])}
        if bar.GetString("Name") == OLD_FEM_TOOLBAR_NAME and \
                names <= {"Name", "Active"} | set(commands.COMMAND_NAMES):
            base.RemGroup(group)


gui.addWorkbench(HexMergeWorkbench())
commands.register()  # the commands exist before any workbench loads
remove_old_fem_toolbar()
gui.getMainWindow().workbenchActivated.connect(add_to_fem_menus)
