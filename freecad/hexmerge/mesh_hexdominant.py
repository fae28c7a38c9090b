# SPDX-License-Identifier: LGPL-2.1-or-later
"""The "hex-dominant mesh" document object (proxy of a Fem::FemMeshObjectPython).

It links a source: a tetrahedral FEM mesh object, whose FemMesh recompute recombines, or a
solid (a Part feature, any object with a solid Shape), which recompute meshes with HexMerge's
mesher (hexmerge.mesh_shape: lattice-seeded tets, OpenCASCADE and TetGen) at TargetSize and then
recombines ("shape mode"; FEM mesh regions on the shape give local sizes, see mesh_regions). The
result goes into the object's own FemMesh property; the source
is never modified. Because the link is an ordinary App::PropertyLink, a change to the source
(a new mesh, a new shape) marks this object for recompute.
"""

import json

import FreeCAD

from . import calculix
from . import jobs
from . import mesh_regions
from . import properties
from . import regions as regions_mod
from . import results

TYPE = "HexMerge::MeshHexDominant"


class MeshHexDominant:
    """Stateless proxy: everything lives in the object's properties."""

    Type = TYPE

    def __init__(self, obj):
        obj.Proxy = self
        self.add_properties(obj)
        # The .inp gets the element types of LinearHexahedron / QuadraticHexahedron.
        calculix.install_writer_hook()

    @staticmethod
    def add_properties(obj):
        for spec in properties.all_specs():
            spec.add_to(obj)
        if "Report" not in obj.PropertiesList:
            # read-only in the editor, and an output: setting it does not touch the object
            obj.addProperty("App::PropertyString", "Report", "Report",
                            "The engine's report of the last recompute (JSON)", 8, True)
        if "Part" not in obj.PropertiesList:
            # FreeCAD's solver writers read a mesh object's shape from its Part (as Gmsh's).
            obj.addProperty("App::PropertyLink", "Part", "Source",
                            "The shape this mesh is made from (set from the source: the shape "
                            "itself, or the source mesh's shape); read by FreeCAD's solver "
                            "writers", 0, True)
        for name, what in (("MeshRegionList", "mesh regions (Fem::MeshRegion)"),
                           ("MeshBoundaryLayerList", "boundary layer objects")):
            if name not in obj.PropertiesList:
                # As Gmsh's mesh object: ObjectsFem.makeMeshRegion(doc, this object) fills it.
                obj.addProperty("App::PropertyLinkList", name, "Source",
                                "Shape mode: the {} of this mesh (those of its analysis count "
                                "too)".format(what))
        if "Summary" not in obj.PropertiesList:
            obj.addProperty("App::PropertyString", "Summary", "Report",
                            "One-line summary of the last recompute", 8, True)

    def onDocumentRestored(self, obj):
        # New engine parameters (or add-on options) get their default on old documents.
        self.add_properties(obj)
        link_part(obj)
        calculix.install_writer_hook()

    def onChanged(self, obj, prop):
        if prop == "SourceMesh":
            link_part(obj)

    # Stateless (Python 3.11's default __getstate__ would return the instance's __dict__).
    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None

    def dumps(self):
        return None

    def loads(self, state):
        return None

    def execute(self, obj):
        femmesh, report = run(obj)
        store(obj, femmesh, report)


def is_shape_source(source):
    """True for a source meshed from its shape: not a FEM mesh, and a Shape with a solid."""
    if source is None or source.isDerivedFrom("Fem::FemMeshObject"):
        return False
    shape = getattr(source, "Shape", None)
    return shape is not None and not shape.isNull() and len(shape.Solids) > 0


def source_of(obj):
    """The source object (FEM mesh or solid shape), or a ValueError with a message for the user."""
    source = obj.SourceMesh
    if source is None:
        raise ValueError("{}: no source mesh (it was deleted or never set); set SourceMesh to a "
                         "tetrahedral FEM mesh object or a solid".format(obj.Label))
    if not source.isDerivedFrom("Fem::FemMeshObject") and not is_shape_source(source):
        raise ValueError("{}: the source {} is not a FEM mesh object, and its shape has no solid"
                         .format(obj.Label, source.Label))
    return source


def source_shape(source):
    """The CAD shape a mesh object was made from (Gmsh: Part, Netgen: Shape), or None."""
    for name in ("Part", "Shape"):
        linked = getattr(source, name, None)
        if linked is not None and hasattr(linked, "Shape"):
            return linked
    return None


def link_part(obj):
    """Sets obj.Part to the shape obj's mesh is made from: the shape source itself, or the
    source mesh's Part/Shape (None when there is none)."""
    if "Part" not in obj.PropertiesList:
        return
    source = obj.SourceMesh
    part = source if is_shape_source(source) else (source_shape(source) if source else None)
    if obj.Part != part:
        obj.Part = part


def found_mesh_regions(obj):
    """(lines, warnings) of the mesh regions and boundary layers a shape-mode object honours (for
    the task panel)."""
    source = obj.SourceMesh
    if not is_shape_source(source):
        return [], []
    analysis = containing_analysis(obj) or containing_analysis(source)
    size = float(properties.mesher_values(obj).get("size") or 0.0)
    _, found, warnings = mesh_regions.local_sizes(obj, source, analysis, size)
    _, layers_found, layers_warnings = mesh_regions.face_layers(obj, source, analysis, size)
    return found + layers_found, warnings + layers_warnings


def containing_analysis(obj):
    for o in obj.InList:
        if o.isDerivedFrom("Fem::FemAnalysis"):
            return o
    return None


def prepare(obj):
    """A RecombineJob (or a ShapeJob for a shape source) for the object's current source and
    properties (FreeCAD thread)."""
    source = source_of(obj)
    analysis = containing_analysis(obj) or containing_analysis(source)
    if is_shape_source(source):
        mesher = properties.mesher_values(obj)
        size = float(mesher.get("size") or 0.0)
        entries, _, warnings = mesh_regions.local_sizes(obj, source, analysis, size)
        if entries:
            mesher["local_sizes"] = "; ".join(entries)
        layer_entries, _, layer_warnings = mesh_regions.face_layers(obj, source, analysis, size)
        if layer_entries:
            mesher["face_layers"] = "; ".join(layer_entries)
        warnings = warnings + layer_warnings
        job = jobs.ShapeJob.prepare(
            source.Shape, mesher, properties.engine_values(obj),
            material_names=regions_mod.material_solids(analysis, source),
            pyramids_as_hexahedra=obj.PyramidsAsHexahedra)
        job.warnings.extend(warnings)
        return job
    part = source_shape(source)
    options = properties.engine_values(obj)
    regions = "auto" if options.get("respect_regions", True) else "none"
    return jobs.RecombineJob.prepare(
        source.FemMesh, options, regions,
        shape=part.Shape if part is not None else None,
        material_solids=regions_mod.material_solids(analysis, part),
        materials=regions_mod.analysis_materials(analysis),
        pyramids_as_hexahedra=obj.PyramidsAsHexahedra)


def run(obj, progress=None):
    job = prepare(obj)
    job.run(progress)
    femmesh, report = job.finish()
    report["freecad"]["source"] = obj.SourceMesh.Name
    return femmesh, report


def store(obj, femmesh, report):
    for warning in report.get("freecad", {}).get("warnings", []):
        FreeCAD.Console.PrintWarning("HexMerge: {}: {}\n".format(obj.Label, warning))
    obj.FemMesh = femmesh
    obj.Report = json.dumps(report, indent=1, sort_keys=True, default=_plain)
    obj.Summary = results.summary(report)


def _plain(x):
    try:
        import numpy as np
        if isinstance(x, np.generic):
            return x.item()
        if isinstance(x, np.ndarray):
            return x.tolist()
    except ImportError:
        pass
    return str(x)


def report_dict(obj):
    return json.loads(obj.Report) if obj.Report else {}
