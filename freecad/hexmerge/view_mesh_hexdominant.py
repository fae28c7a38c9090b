# SPDX-License-Identifier: LGPL-2.1-or-later
"""View provider of the hex-dominant mesh: icon, source as child, colour by element type."""

import os

import FreeCAD
import FreeCADGui

from . import femmesh_arrays

RESOURCES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(__file__))), "resources")
ICON = os.path.join(RESOURCES, "icons", "HexMerge_MeshHexDominant.svg")

# RGB per number of nodes of a stored volume; collapsed pyramids (8 or 20 nodes with a repeated
# node) are found by their nodes. Tet grey, pyramid yellow, prism green, hexahedron blue.
TYPE_COLORS = {
    "tetra": (0.75, 0.75, 0.75),
    "pyramid": (0.95, 0.80, 0.20),
    "wedge": (0.35, 0.75, 0.35),
    "hexahedron": (0.30, 0.50, 0.90),
}


def element_kind(nodes):
    """Linear kind of a stored volume from its node ids (SMESH order)."""
    corners = {4: 4, 10: 4, 5: 5, 13: 5, 6: 6, 15: 6, 8: 8, 20: 8}[len(nodes)]
    if corners == 8 and len(set(nodes[:8])) == 5:
        return "pyramid"
    return {4: "tetra", 5: "pyramid", 6: "wedge", 8: "hexahedron"}[corners]


def colors_by_type(femmesh):
    return {e: TYPE_COLORS[element_kind(femmesh.getElementNodes(e))] for e in femmesh.Volumes}


class VPMeshHexDominant:

    def __init__(self, vobj):
        vobj.Proxy = self
        self.add_properties(vobj)

    @staticmethod
    def add_properties(vobj):
        if "ColorByType" not in vobj.PropertiesList:
            vobj.addProperty("App::PropertyBool", "ColorByType", "HexMerge",
                             "Colour elements by type: hexahedra blue, prisms green, pyramids "
                             "yellow, tetrahedra grey")
            vobj.ColorByType = True

    def attach(self, vobj):
        self.Object = vobj.Object
        self.add_properties(vobj)

    def getIcon(self):
        return ICON

    def claimChildren(self):
        src = getattr(self.Object, "SourceMesh", None)
        return [src] if src is not None else []

    def updateData(self, obj, prop):
        if prop == "FemMesh":
            self.apply_colors(obj.ViewObject)

    def onChanged(self, vobj, prop):
        if prop == "ColorByType":
            self.apply_colors(vobj)

    def apply_colors(self, vobj):
        if vobj is None or "ColorByType" not in vobj.PropertiesList:
            return
        try:
            if vobj.ColorByType and vobj.Object.FemMesh.VolumeCount:
                vobj.ElementColor = colors_by_type(vobj.Object.FemMesh)
            else:
                vobj.ElementColor = {}
        except Exception as e:  # colouring must never break a recompute
            FreeCAD.Console.PrintWarning("HexMerge: colour by type failed: {}\n".format(e))

    def setEdit(self, vobj, mode=0):
        from .task_mesh_hexdominant import TaskPanelHexDominant
        FreeCADGui.Control.showDialog(TaskPanelHexDominant(vobj.Object))
        return True

    def unsetEdit(self, vobj, mode=0):
        FreeCADGui.Control.closeDialog()
        return True

    def doubleClicked(self, vobj):
        if FreeCADGui.Control.activeDialog():
            FreeCAD.Console.PrintWarning("HexMerge: close the active task dialog first.\n")
            return True
        FreeCADGui.ActiveDocument.setEdit(vobj.Object.Name)
        return True

    def dumps(self):
        return None

    def loads(self, state):
        return None
