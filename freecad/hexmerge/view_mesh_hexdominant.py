# SPDX-License-Identifier: LGPL-2.1-or-later
"""View provider of the hex-dominant mesh: icon, source as child, colour by element type."""

import os

import FreeCAD
import FreeCADGui

from . import femmesh_arrays

RESOURCES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(__file__))), "resources")
ICON = os.path.join(RESOURCES, "icons", "HexMerge_MeshHexDominant.svg")

# RGB per element type; collapsed pyramids (8 or 20 nodes with a repeated node) are found by
# their nodes. Tet light grey, pyramid red, prism green, hexahedron blue: none near FreeCAD's
# default mesh orange, so an uncoloured view is not mistaken for a coloured one.
TYPE_COLORS = {
    "tetra": (0.80, 0.80, 0.80),
    "pyramid": (0.85, 0.25, 0.25),
    "wedge": (0.30, 0.70, 0.30),
    "hexahedron": (0.25, 0.45, 0.90),
}
TYPE_COLOR_NAMES = {"tetra": "grey", "pyramid": "red", "wedge": "green", "hexahedron": "blue"}

# FreeCAD 0.20's mesh view keeps element ids in 16 bits when it colours by element: the colour
# of id e is looked up as e mod 65536. The add-on numbers the volumes it draws (those on the
# boundary) first, so colouring ids up to this limit colours what is seen.
VIEW_ID_LIMIT = 65535


def element_kind(nodes):
    """Linear kind of a stored volume from its node ids (SMESH order)."""
    corners = {4: 4, 10: 4, 5: 5, 13: 5, 6: 6, 15: 6, 8: 8, 20: 8}[len(nodes)]
    if corners == 8 and len(set(nodes[:8])) == 5:
        return "pyramid"
    return {4: "tetra", 5: "pyramid", 6: "wedge", 8: "hexahedron"}[corners]


def colors_by_type(femmesh):
    """{element id: RGB} for the volumes with ids up to VIEW_ID_LIMIT (see there)."""
    return {e: TYPE_COLORS[element_kind(femmesh.getElementNodes(e))]
            for e in femmesh.Volumes if e <= VIEW_ID_LIMIT}


def legend():
    """"hexahedra blue, prisms green, pyramids red, tetrahedra grey"."""
    plural = {"hexahedron": "hexahedra", "wedge": "prisms", "pyramid": "pyramids",
              "tetra": "tetrahedra"}
    return ", ".join("{} {}".format(plural[k], TYPE_COLOR_NAMES[k])
                     for k in ("hexahedron", "wedge", "pyramid", "tetra"))


class VPMeshHexDominant:

    def __init__(self, vobj):
        vobj.Proxy = self
        self.add_properties(vobj)

    @staticmethod
    def add_properties(vobj):
        if "ColorByType" not in vobj.PropertiesList:
            vobj.addProperty("App::PropertyBool", "ColorByType", "HexMerge",
                             "Colour elements by type: " + legend())
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
        # FreeCAD calls this proxy before the C++ view provider, which then rebuilds the drawn
        # faces and resets their colours: colouring here would be wiped at once. Colour when
        # the event loop next runs, after the rebuild.
        if prop == "FemMesh":
            self.apply_colors_later(obj.ViewObject)

    def onChanged(self, vobj, prop):
        if prop == "ColorByType":
            self.apply_colors(vobj)
        elif prop == "ShowInner":  # the C++ side redraws other faces: colour them again
            self.apply_colors_later(vobj)

    def apply_colors_later(self, vobj):
        from PySide import QtCore

        name = vobj.Object.Name if vobj is not None else None
        doc = vobj.Object.Document.Name if vobj is not None else None

        def apply():
            try:
                obj = FreeCAD.getDocument(doc).getObject(name)
            except Exception:  # the document was closed meanwhile
                return
            if obj is not None and obj.ViewObject is not None:
                self.apply_colors(obj.ViewObject)

        QtCore.QTimer.singleShot(0, apply)

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
