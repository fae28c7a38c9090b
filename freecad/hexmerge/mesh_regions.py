# SPDX-License-Identifier: LGPL-2.1-or-later
"""FEM mesh regions (Fem::MeshRegion) and boundary layers (Fem::MeshBoundaryLayer) honoured in
shape mode: local sizes on faces and edges, layers on faces.

FreeCAD's Gmsh tool reads the mesh regions in its mesh object's MeshRegionList. A hex-dominant
mesh object meshing a shape takes the regions on that shape from its own MeshRegionList
(ObjectsFem.makeMeshRegion(doc, hexmesh_object, length) fills it), from its analysis and from the
MeshRegionList of the analysis' other mesh objects, and passes their faces and edges with their
CharacteristicLength to hexmerge.mesh_shape() as `local_sizes`; the boundary layer objects found
the same way (MeshBoundaryLayerList) give their faces with NumberOfLayers, MinimumThickness and
GrowthRate as `face_layers`. What cannot be honoured (a whole solid, vertices, edges for layers,
a length not finer than the target size, elements of another shape) is said in a warning, never
left out silently.
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


def _items(kind, label, references, source, kinds, warnings):
    """The element names in the source's shape ("Face5") that an object's References name, of
    the kinds allowed ("Face", "Edge"); what cannot be honoured goes to warnings."""
    items = []
    for linked, elements in references or []:
        if linked is None:
            continue
        if not elements or elements == ("",):
            warnings.append(
                "{} {}: a reference to the whole of {} is not supported in shape mode: reference "
                "its {}".format(kind, label, linked.Label, " or ".join(k.lower() + "s" for k in kinds)))
            continue
        for element in elements:
            match = _ELEMENT.match(element)
            if match is None or match.group(1) not in kinds:
                warnings.append(
                    "{} {}: {} of {} is not supported in shape mode ({} only): left out".format(
                        kind, label, element, linked.Label,
                        " and ".join(k.lower() + "s" for k in kinds)))
                continue
            name = _element_in(source, linked, element)
            if name is None:
                warnings.append(
                    "{} {}: {} of {} is not part of the shape meshed ({}): left out"
                    .format(kind, label, element, linked.Label, source.Label))
                continue
            items.append(name)
    if not items:
        warnings.append("{} {}: {}".format(
            kind, label, "none of its references can be honoured" if references
            else "no references: left out"))
    return items


def local_sizes(obj, source, analysis, target_size):
    """The mesh regions for a shape source.

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
        items = _items("mesh region", region.Label, getattr(region, "References", None), source,
                       ("Face", "Edge"), warnings)
        if items:
            entries.append("{}:{!r}".format(",".join(items), size))
            found.append("{}: {} {:g} mm".format(region.Label, ", ".join(items), size))
    return entries, found, warnings


def face_layers(obj, source, analysis, target_size):
    """The boundary layer objects (Fem::MeshBoundaryLayer) for a shape source.

    Returns (entries, found, warnings): entries, mesh_shape()'s face_layers texts
    ("Face3:3:0.5:1.5": NumberOfLayers, MinimumThickness, GrowthRate); found, one line per object
    honoured; warnings, what is not honoured and why (no thickness, a thickness above the target
    size, edges or vertices referenced, a growth rate outside 1 to 3)."""
    entries, found, warnings = [], [], []
    for layer in _objects(obj, analysis, "MeshBoundaryLayerList", BOUNDARY_LAYER_TYPE):
        count = int(getattr(layer, "NumberOfLayers", 0) or 0)
        thickness = _length(getattr(layer, "MinimumThickness", 0.0))
        growth = float(getattr(layer, "GrowthRate", 1.0) or 1.0)
        if count < 1 or count > 10:
            warnings.append("boundary layer {}: NumberOfLayers {} is not from 1 to 10: left out"
                            .format(layer.Label, count))
            continue
        if thickness <= 0:
            warnings.append("boundary layer {}: no MinimumThickness set: left out".format(layer.Label))
            continue
        if thickness > target_size:
            warnings.append(
                "boundary layer {}: MinimumThickness {:g} mm is larger than the target size {:g} mm: "
                "left out (layers are finer than the mesh)".format(layer.Label, thickness, target_size))
            continue
        if not 1 <= growth <= 3:
            warnings.append("boundary layer {}: GrowthRate {:g} is not from 1 to 3: left out"
                            .format(layer.Label, growth))
            continue
        items = _items("boundary layer", layer.Label, getattr(layer, "References", None), source,
                       ("Face",), warnings)
        if items:
            entries.append("{}:{}:{!r}:{!r}".format(",".join(items), count, thickness, growth))
            found.append("{}: {} {} layers from {:g} mm, growth {:g}".format(
                layer.Label, ", ".join(items), count, thickness, growth))
    return entries, found, warnings
