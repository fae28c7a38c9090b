# SPDX-License-Identifier: LGPL-2.1-or-later
"""View provider of the hex-dominant mesh: icon, source as child, colour by element type, and the
task panel in edit mode (as FEM's view_mesh_gmsh.py opens task_mesh_gmsh)."""

import FreeCAD
import FreeCADGui
from PySide import QtCore

from . import colors
from .resources import resource_path
from .task_mesh_hexdominant import TaskPanelHexDominant

ICON = resource_path("icons", "HexMerge_MeshHexDominant.svg")


def scene_nodes(vobj):
    """The mesh view's (SoMaterial, SoMaterialBinding, SoIndexedFaceSet) of its faces, from the
    Coin scene graph (the group holding the face set holds its material and binding)."""
    from pivy import coin
    search = coin.SoSearchAction()
    search.setType(coin.SoIndexedFaceSet.getClassTypeId())
    search.setInterest(coin.SoSearchAction.FIRST)
    search.setSearchingAll(True)  # a hidden object too, so it is right when shown
    search.apply(vobj.RootNode)
    path = search.getPath()
    if path is None:
        return None
    group = path.getNodeFromTail(1)
    material = binding = None
    for i in range(group.getNumChildren()):
        child = group.getChild(i)
        if child.isOfType(coin.SoMaterial.getClassTypeId()):
            material = child
        elif child.isOfType(coin.SoMaterialBinding.getClassTypeId()):
            binding = child
    return material, binding, path.getTail()


def drawn_triangles(face_set):
    """Number of triangles of an indexed face set (faces end with -1)."""
    return sum(1 for i in face_set.coordIndex.getValues() if i < 0)


def color_by_type(vobj):
    """Colours each drawn triangle by the type of its element (colors.face_colors), on the
    scene graph: FreeCAD 0.20's ElementColor misplaces colours on quadratic faces."""
    from pivy import coin
    nodes = scene_nodes(vobj)
    if nodes is None or None in nodes:
        raise RuntimeError("the mesh view has no face set with a material")
    material, binding, face_set = nodes
    femmesh = vobj.Object.FemMesh
    rgb = colors.face_colors(vobj.VisibleElementFaces, femmesh.getElementNodes)
    triangles = drawn_triangles(face_set)
    if len(rgb) != triangles:
        raise RuntimeError("{} triangles drawn, {} coloured: the mesh view's face order is not "
                           "the one HexMerge knows".format(triangles, len(rgb)))
    binding.value = coin.SoMaterialBinding.PER_FACE
    material.diffuseColor.setValues(0, len(rgb), [coin.SbColor(*c) for c in rgb])
    material.diffuseColor.setNum(len(rgb))


class VPMeshHexDominant:

    def __init__(self, vobj):
        vobj.Proxy = self
        self.add_properties(vobj)

    @staticmethod
    def add_properties(vobj):
        if "ColorByType" not in vobj.PropertiesList:
            vobj.addProperty("App::PropertyBool", "ColorByType", "HexMerge",
                             "Colour elements by type: " + colors.legend())
            vobj.ColorByType = True

    def attach(self, vobj):
        self.Object = vobj.Object
        self.add_properties(vobj)

    def getIcon(self):
        return ICON

    def claimChildren(self):
        src = getattr(self.Object, "SourceMesh", None)
        # Its mesh regions and boundary layer objects under it, as under a Gmsh mesh.
        own = [o for name in ("MeshRegionList", "MeshBoundaryLayerList")
               for o in (getattr(self.Object, name, None) or [])]
        return ([src] if src is not None else []) + own

    def updateData(self, obj, prop):
        # FreeCAD calls this proxy before the C++ view provider, which then rebuilds the drawn
        # faces and resets their colours: colouring here would be wiped at once. Colour when
        # the event loop next runs, after the rebuild.
        if prop == "FemMesh":
            self.apply_colors_later(obj.ViewObject)

    def onChanged(self, vobj, prop):
        if prop == "ColorByType":
            self.apply_colors(vobj)
        elif prop in ("ShowInner", "ShapeColor", "Transparency", "DisplayMode"):
            # the C++ side redraws the faces or resets the material: colour them again
            self.apply_colors_later(vobj)

    def apply_colors_later(self, vobj):
        if vobj is None:
            return
        name = vobj.Object.Name
        doc = vobj.Object.Document.Name

        def apply():
            if doc not in FreeCAD.listDocuments():  # the document was closed meanwhile
                return
            obj = FreeCAD.getDocument(doc).getObject(name)
            if obj is not None and obj.ViewObject is not None:
                self.apply_colors(obj.ViewObject)

        QtCore.QTimer.singleShot(0, apply)

    def apply_colors(self, vobj):
        if vobj is None or "ColorByType" not in vobj.PropertiesList:
            return
        try:
            if vobj.ColorByType and vobj.Object.FemMesh.VolumeCount:
                color_by_type(vobj)
            else:
                vobj.ElementColor = {}
        except Exception as e:  # colouring must never break a recompute
            FreeCAD.Console.PrintWarning("HexMerge: colour by type failed: {}\n".format(e))

    def setEdit(self, vobj, mode=0):
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

    # Nothing to save: Python 3.11 gives every object a __getstate__ returning its __dict__
    # (self.Object here), which FreeCAD 0.20 prefers to dumps() and cannot write as JSON.
    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None

    def dumps(self):
        return None

    def loads(self, state):
        return None
