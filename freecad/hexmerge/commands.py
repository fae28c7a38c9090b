# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI commands. Each acts only through FreeCADGui.doCommand, so every step shows in the Python
console and can be replayed, inside one undo transaction closed by the task panel."""

import os

import FreeCAD
import FreeCADGui

from .view_mesh_hexdominant import RESOURCES


def selected_tet_mesh():
    """The single selected FEM mesh object holding only tetrahedra, or (None, reason)."""
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


class CommandBase:
    """Declarative base: subclasses set resources and is_active ("with_tet_mesh" or "with_document")."""

    resources = {}
    is_active = "with_document"

    def GetResources(self):
        return self.resources

    def IsActive(self):
        if FreeCAD.ActiveDocument is None or FreeCADGui.ActiveDocument is None:
            return False
        if FreeCADGui.Control.activeDialog():
            return False
        if self.is_active == "with_tet_mesh":
            return selected_tet_mesh()[0] is not None
        return True


class HexDominantFromTetrahedra(CommandBase):
    resources = {
        "Pixmap": os.path.join(RESOURCES, "icons", "HexMerge_MeshHexDominant.svg"),
        "MenuText": "Hex-dominant mesh from tetrahedra",
        "ToolTip": "Merge the tetrahedra of the selected FEM mesh into hexahedra, prisms and "
                   "pyramids: a new hex-dominant FEM mesh object linked to it (the source is not "
                   "modified)",
    }
    is_active = "with_tet_mesh"

    def Activated(self):
        source, reason = selected_tet_mesh()
        if source is None:
            FreeCAD.Console.PrintError("HexMerge: {}\n".format(reason))
            return
        doc = source.Document
        doc.openTransaction("Hex-dominant mesh from tetrahedra")
        FreeCADGui.addModule("freecad.hexmerge")
        FreeCADGui.doCommand(
            "hexmesh = freecad.hexmerge.make_hexdominant_mesh("
            "App.getDocument('{}'), App.getDocument('{}').getObject('{}'), recompute=False)"
            .format(doc.Name, doc.Name, source.Name))
        FreeCADGui.Selection.clearSelection()
        FreeCADGui.doCommand("Gui.getDocument('{}').setEdit(hexmesh.Name)".format(doc.Name))


COMMANDS = {"HexMerge_MeshHexDominant": HexDominantFromTetrahedra}


def register():
    for name, cls in COMMANDS.items():
        if name not in FreeCADGui.listCommands():
            FreeCADGui.addCommand(name, cls())
    return list(COMMANDS)


register()
