# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI entry point, imported by FreeCAD at start-up (new-style namespace add-on): the HexMerge
workbench, the commands, and the commands' place in FEM's Mesh menu and toolbar."""

from freecad import app, gui
from PySide import QtCore, QtGui

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


class FemMenuEntries:
    """The HexMerge commands as QActions for FEM's Mesh menu and toolbar.

    FreeCAD 0.20 has no API for an add-on to extend another workbench's menus, and creates a
    command's own QAction only when its workbench is first shown. These actions run the commands
    (FreeCADGui.runCommand) and follow their availability: enabled or not, with the reason in
    the tooltip and status tip, updated when the selection changes, when a menu opens and when
    the pointer comes to a toolbar (a task panel opened or closed changes no selection)."""

    def __init__(self, window):
        self.watched = []  # menus and toolbars whose opening or hovering refreshes the entries
        self.pointer_filter = PointerFilter(self.refresh, window)
        self.commands = {cls.name: cls() for cls in commands.COMMANDS}
        self.actions = {}
        for name, command in self.commands.items():
            res = command.GetResources()
            action = QtGui.QAction(QtGui.QIcon(res["Pixmap"]), res["MenuText"], window)
            action.setObjectName(name)
            action.triggered.connect(lambda checked=False, n=name: gui.runCommand(n))
            self.actions[name] = action
        self.refresh()

    def refresh(self):
        for name, action in self.actions.items():
            command = self.commands[name]
            reason = command.unavailable()
            tip = command.tooltip(reason)
            action.setEnabled(not reason)
            action.setToolTip(tip)
            action.setStatusTip(tip.replace("\n\n", " "))

    # selection observer (FreeCADGui.Selection.addObserver)
    def addSelection(self, *args):
        self.refresh()

    def removeSelection(self, *args):
        self.refresh()

    def setSelection(self, *args):
        self.refresh()

    def clearSelection(self, *args):
        self.refresh()

    def insert_into(self, container):
        """Inserts the actions into a QMenu or QToolBar after FEM's Gmsh and Netgen entries, if
        it has them and not ours yet. Returns True when it holds ours."""
        present = container.actions()
        fem = [i for i, a in enumerate(present)
               if a.objectName() in FEM_MESHERS or _command_of(a) in FEM_MESHERS]
        if not fem:
            return False
        before = present[max(fem) + 1] if max(fem) + 1 < len(present) else None
        for action in self.actions.values():
            if action in present:
                continue
            if before is None:
                container.addAction(action)
            else:
                container.insertAction(before, action)
        if container not in self.watched:
            if isinstance(container, QtGui.QMenu):
                container.aboutToShow.connect(self.refresh)
            else:  # a toolbar: refresh when the pointer comes to it
                container.installEventFilter(self.pointer_filter)
            self.watched.append(container)
        return True


class PointerFilter(QtCore.QObject):
    """Calls back when the pointer enters a watched widget (the availability of a command can
    change without a selection change: a task panel opened or closed)."""

    def __init__(self, callback, parent):
        super().__init__(parent)
        self.callback = callback

    def eventFilter(self, widget, event):
        if event.type() == QtCore.QEvent.Enter:
            self.callback()
        return False


def _command_of(action):
    """The FreeCAD command name of one of FreeCAD's own QActions (by identity), or ""."""
    for name in FEM_MESHERS:
        command = gui.Command.get(name)
        if command is not None and action in command.getAction():
            return name
    return ""


ENTRIES = None


def add_to_fem_menus(workbench=None):
    """Puts both commands into FEM's Mesh menu and Mesh toolbar, beside Gmsh and Netgen. FreeCAD
    rebuilds a workbench's menus on each activation, so this runs on every activation of the FEM
    workbench (the main window's workbenchActivated signal). Returns True when they are there."""
    global ENTRIES
    if workbench is None:
        try:
            workbench = gui.activeWorkbench().name()
        except AssertionError:  # none yet: FreeCAD is starting
            return False
    if workbench != FEM_WORKBENCH:
        return False
    window = gui.getMainWindow()
    if ENTRIES is None:
        ENTRIES = FemMenuEntries(window)
        gui.Selection.addObserver(ENTRIES)
    found = False
    for menu in window.menuBar().findChildren(QtGui.QMenu):
        found = ENTRIES.insert_into(menu) or found
    for bar in window.findChildren(QtGui.QToolBar):
        found = ENTRIES.insert_into(bar) or found
    ENTRIES.refresh()
    return found


def remove_old_fem_toolbar():
    """Removes the custom "HexMerge" FEM toolbar that earlier versions wrote into the user
    parameters (the commands are in FEM's own Mesh menu and toolbar now)."""
    base = app.ParamGet("User parameter:BaseApp/Workbench/FemWorkbench/Toolbar")
    ours = {"Name", "Active"} | set(commands.COMMAND_NAMES)
    old = []
    for group in base.GetGroups():
        bar = base.GetGroup(group)
        if bar.GetString("Name") == OLD_FEM_TOOLBAR_NAME and \
                {entry[1] for entry in (bar.GetContents() or [])} <= ours:
            old.append(group)
        del bar  # RemGroup only empties a group someone still holds
    for group in old:
        base.RemGroup(group)


gui.addWorkbench(HexMergeWorkbench())
commands.register()  # the commands exist before any workbench loads
remove_old_fem_toolbar()
gui.getMainWindow().workbenchActivated.connect(add_to_fem_menus)
add_to_fem_menus()  # FEM may be the start-up workbench, active before this module loads
