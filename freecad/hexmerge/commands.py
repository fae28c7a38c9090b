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


def selected_solid():
    """The single selected object with a solid Shape (not a FEM mesh), or (None, reason)."""
    from .mesh_hexdominant import is_shape_source
    sel = FreeCADGui.Selection.getSelection()
    if len(sel) != 1:
        return None, "select exactly one solid (a Part feature or any object with a solid)"
    if not is_shape_source(sel[0]):
        return None, "{} has no solid".format(sel[0].Label)
    return sel[0], ""


def active_analysis():
    try:
        import FemGui
        return FemGui.getActiveAnalysis()
    except Exception:
        return None


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
        if self.is_active == "with_solid":
            return selected_solid()[0] is not None
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


class HexDominantFromShape(CommandBase):
    resources = {
        "Pixmap": os.path.join(RESOURCES, "icons", "HexMerge_MeshHexDominant.svg"),
        "MenuText": "Hex-dominant mesh from shape",
        "ToolTip": "Mesh the selected solid with tetrahedra on a lattice (OpenCASCADE, TetGen) at a "
                   "target size and merge them into hexahedra, prisms and pyramids: a new FEM mesh "
                   "object linked to the shape, recomputed when the shape changes. In the active "
                   "analysis it takes the place of the analysis's mesh",
    }
    is_active = "with_solid"

    def Activated(self):
        source, reason = selected_solid()
        if source is None:
            FreeCAD.Console.PrintError("HexMerge: {}\n".format(reason))
            return
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


COMMANDS = {"HexMerge_MeshHexDominant": HexDominantFromTetrahedra,
            "HexMerge_MeshHexDominantFromShape": HexDominantFromShape}


def register():
    for name, cls in COMMANDS.items():
        if name not in FreeCADGui.listCommands():
            FreeCADGui.addCommand(name, cls())
    return list(COMMANDS)


register()
