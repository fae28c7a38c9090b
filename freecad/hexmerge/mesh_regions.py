# SPDX-License-Identifier: LGPL-2.1-or-later
"""FEM mesh regions (Fem::MeshRegion) honoured in shape mode: local sizes on faces and edges.

FreeCAD's Gmsh tool reads the mesh regions in its mesh object's MeshRegionList. A hex-dominant
mesh object meshing a shape takes the regions on that shape from its own MeshRegionList
(ObjectsFem.makeMeshRegion(doc, hexmesh_object, length) fills it), from its analysis and from the
MeshRegionList of the analysis' other mesh objects, and passes their faces and edges with their
CharacteristicLength to hexmerge.mesh_shape() as `local_sizes`. What cannot be honoured (a whole
solid, vertices, a length not finer than the target size, elements of another shape, boundary
layer objects) is said in a warning, never left out silently.
"""

import re

REGION_TYPE = "Fem::MeshRegion"
BOUNDARY_LAYER_TYPE = "Fem::MeshBoundaryLayer"

_ELEMENT = re.compile(r"^(Face|Edge|Vertex|Solid)(\d+)$")


def _type_of(obj):
    proxy = getattr(obj, "Proxy", None)
    return getattr(proxy, "Type", "") if proxy is not None else ""


def _linked(holder, name):
    return list(getattr(holder, name, None) or [])


def _objects(obj, analysis, list_name, type_name):
    """The objects of one type in obj's list, the analysis and the analysis' mesh objects' lists,
    each once, in that order."""
    found = _linked(obj, list_name)
    if analysis is not None:
        for member in analysis.Group:
            if _type_of(member) == type_name:
                found.append(member)
            elif member is not obj:
                found.extend(_linked(member, list_name))
    out, seen = [], set()
    for o in found:
        if o is not None and _type_of(o) == type_name and o.Name not in seen:
            seen.add(o.Name)
            out.append(o)
    return out


def _length(quantity):
    return float(getattr(quantity, "Value", quantity) or 0.0)


def _element_in(source, linked, element):
    """The element's name in the source's shape ("Face5"), or None: the same object, an object of
    the same shape, or an element of another object found in the source's shape by geometry."""
    if linked is source or linked.Shape.isSame(source.Shape):
        return element
    try:
        from femtools import geomtools
        found = geomtools.find_element_in_shape(source.Shape, geomtools.get_element(linked, element))
    except Exception:  # FreeCAD's finder fails on elements it cannot read: not found
        found = None
    return found or None


def local_sizes(obj, source, analysis, target_size):
    """The mesh regions and boundary layer objects for a shape source.

    Returns (entries, found, warnings): entries, mesh_shape()'s local_sizes texts ("Face5:1.5");
    found, one line per region honoured ("MeshRegion: Face5 1.5 mm"); warnings, what is not
    honoured and why."""
    entries, found, warnings = [], [], []
    for region in _objects(obj, analysis, "MeshRegionList", REGION_TYPE):
        size = _length(getattr(region, "CharacteristicLength", 0.0))
        if size <= 0:
            warnings.append("mesh region {}: no CharacteristicLength set: left out".format(region.Label))
            continue
        if size >= target_size:
            warnings.append(
                "mesh region {}: CharacteristicLength {:g} mm is not finer than the target size "
                "{:g} mm: left out (shape mode refines only)".format(region.Label, size, target_size))
            continue
        items = []
        for linked, elements in getattr(region, "References", None) or []:
            if linked is None:
                continue
            if not elements or elements == ("",):
                warnings.append(
                    "mesh region {}: a reference to the whole of {} is not supported in shape "
                    "mode: reference its faces or edges".format(region.Label, linked.Label))
                continue
            for element in elements:
                match = _ELEMENT.match(element)
                if match is None or match.group(1) in ("Vertex", "Solid"):
                    warnings.append(
                        "mesh region {}: {} of {} is not supported in shape mode (faces and edges "
                        "only): left out".format(region.Label, element, linked.Label))
                    continue
                name = _element_in(source, linked, element)
                if name is None:
                    warnings.append(
                        "mesh region {}: {} of {} is not part of the shape meshed ({}): left out"
                        .format(region.Label, element, linked.Label, source.Label))
                    continue
                items.append(name)
        if items:
            entries.append("{}:{!r}".format(",".join(items), size))
            found.append("{}: {} {:g} mm".format(region.Label, ", ".join(items), size))
        elif region.References:
            warnings.append("mesh region {}: none of its references can be honoured".format(region.Label))
        else:
            warnings.append("mesh region {}: no references: left out".format(region.Label))
    for layer in _objects(obj, analysis, "MeshBoundaryLayerList", BOUNDARY_LAYER_TYPE):
        warnings.append(
            "boundary layer {} is not honoured in shape mode: HexMerge's boundary layers are "
            "global (BoundaryLayers, LayerThickness), not per face".format(layer.Label))
    return entries, found, warnings
