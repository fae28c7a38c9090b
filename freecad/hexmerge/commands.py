# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI commands. Each acts only through FreeCADGui.doCommand, so every step shows in the Python
console and can be replayed, inside one undo transaction closed by the task panel. When a
command is not available its tooltip and status tip say why."""

import FreeCAD
import FreeCADGui

from .mesh_hexdominant import is_shape_source
from .resources import resource_path


def selected_tet_mesh():
    """(the single selected FEM mesh object holding only tetrahedra, "") or (None, reason)."""
    sel = FreeCADGui.Selection.getSelection()
    if len(sel) != 1:
        return None, "select exactly one tetrahedral FEM mesh object"
    obj = sel[0]
    if not obj.isDerivedFrom("Fem::FemMeshObject"):
        return None, "{} is not a FEM mesh object".format(obj.Label)
    m = obj.FemMesh
    if m.VolumeCount == 0:
        return None, "{} has no volume elements".format(obj.Label)
    if m.VolumeCount != m.TetraCount:
        return None, "{} is not tetrahedral".format(obj.Label)
    return obj, ""


def selected_solid():
    """(the single selected object with a solid Shape, not a FEM mesh, "") or (None, reason)."""
    sel = FreeCADGui.Selection.getSelection()
    if len(sel) != 1:
        return None, "select exactly one solid (a Part feature or any object with a solid)"
    if not is_shape_source(sel[0]):
        return None, "{} has no solid".format(sel[0].Label)
    return sel[0], ""


def active_analysis():
    """FEM's active analysis, or None (FemGui is absent without the FEM GUI)."""
    try:
        import FemGui
    except ImportError:
        return None
    return FemGui.getActiveAnalysis()


class CommandBase:
    """Declarative base (as FEM's CommandManager): subclasses set name, resources and
    is_active: "with_document", "with_tet_mesh" or "with_solid"."""

    name = ""
    resources = {}
    is_active = "with_document"

    def GetResources(self):
        return self.resources

    def unavailable(self):
        """Why the command cannot run now, or "" when it can."""
        if FreeCAD.ActiveDocument is None or FreeCADGui.ActiveDocument is None:
            return "open or create a document first"
        if FreeCADGui.Control.activeDialog():
            return "close the open task panel first"
        if self.is_active == "with_tet_mesh":
            return selected_tet_mesh()[1]
        if self.is_active == "with_solid":
            return selected_solid()[1]
        return ""

    def tooltip(self, reason):
        """The tooltip, with the reason the command is not available when there is one."""
        tip = self.resources["ToolTip"]
        return "{}\n\nNot available: {}.".format(tip, reason) if reason else tip

    def IsActive(self):
        reason = self.unavailable()
        self.show_reason(reason)
        return not reason

    def show_reason(self, reason):
        """Puts the reason into the tooltip and status tip of the command's own QActions (the
        HexMerge workbench's greyed-out toolbar button and menu entry)."""
        if reason == getattr(self, "_shown_reason", None):
            return
        self._shown_reason = reason
        tip = self.tooltip(reason)
        command = FreeCADGui.Command.get(self.name)
        for action in (command.getAction() if command is not None else []):
            action.setToolTip(tip)
            action.setStatusTip(tip.replace("\n\n", " "))


class HexDominantFromTetrahedra(CommandBase):
    name = "HexMerge_MeshHexDominant"
    resources = {
        "Pixmap": resource_path("icons", "HexMerge_MeshHexDominant.svg"),
        "MenuText": "Hex-dominant mesh from tetrahedra",
        "ToolTip": "Merge the tetrahedra of the selected FEM mesh into hexahedra, prisms and "
                   "pyramids: a new hex-dominant FEM mesh object linked to it (the source is not "
                   "modified)",
    }
    is_active = "with_tet_mesh"

    def Activated(self):
        reason = self.unavailable()
        if reason:
            FreeCAD.Console.PrintError("HexMerge: {}\n".format(reason))
            return
        source = selected_tet_mesh()[0]
        doc = source.Document
        doc.openTransaction("Hex-dominant mesh from tetrahedra")
        FreeCADGui.addModule("freecad.hexmerge")
        FreeCADGui.doCommand(
            "hexmesh = freecad.hexmerge.make_hexdominant_mesh("
            "App.getDocument('{}'), App.getDocument('{}').getObject('{}'), recompute=False)"
            .format(doc.Name, doc.Name, source.Name))
        FreeCADGui.Selection.clearSelection()
        FreeCADGui.doCommand("Gui.getDocument('{}').setEdit(hexmesh.Name)".format(doc.Name))


class HexDominantFromShape(CommandBase):
    name = "HexMerge_MeshHexDominantFromShape"
    resources = {
        "Pixmap": resource_path("icons", "HexMerge_MeshHexDominantFromShape.svg"),
        "MenuText": "Hex-dominant mesh from shape",
        "ToolTip": "Mesh the selected solid with tetrahedra on a lattice (OpenCASCADE, TetGen) at a "
                   "target size and merge them into hexahedra, prisms and pyramids: a new FEM mesh "
                   "object linked to the shape, recomputed when the shape changes. In the active "
                   "analysis it takes the place of the analysis's mesh",
    }
    is_active = "with_solid"

    def Activated(self):
        reason = self.unavailable()
        if reason:
            FreeCAD.Console.PrintError("HexMerge: {}\n".format(reason))
            return
        source = selected_solid()[0]
        doc = source.Document
        analysis = active_analysis()
        doc.openTransaction("Hex-dominant mesh from shape")
        FreeCADGui.addModule("freecad.hexmerge")
        FreeCADGui.doCommand(
            "hexmesh = freecad.hexmerge.make_hexdominant_mesh("
            "App.getDocument('{0}'), App.getDocument('{0}').getObject('{1}'), recompute=False{2})"
            .format(doc.Name, source.Name,
                    "" if analysis is None or analysis.Document != doc else
                    ", analysis=App.getDocument('{}').getObject('{}')".format(doc.Name, analysis.Name)))
        FreeCADGui.Selection.clearSelection()
        FreeCADGui.doCommand("Gui.getDocument('{}').setEdit(hexmesh.Name)".format(doc.Name))


COMMANDS = [HexDominantFromShape, HexDominantFromTetrahedra]  # menu and toolbar order
COMMAND_NAMES = [c.name for c in COMMANDS]


def register():
    """Adds the commands to FreeCAD (once); returns their names."""
    for cls in COMMANDS:
        if cls.name not in FreeCADGui.listCommands():
            FreeCADGui.addCommand(cls.name, cls())
    return COMMAND_NAMES
