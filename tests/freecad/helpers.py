# SPDX-License-Identifier: LGPL-2.1-or-later
"""Shared set-up for the FreeCAD tests: Gmsh meshes of FreeCAD's FEM examples, CalculiX runs."""

import importlib.util
import os

import FreeCAD
import ObjectsFem

BEAM_THEORY_TIP_MM = 88.84  # ccx_cantilever_faceload, Timoshenko beam with shear (DESIGN.md)


def load_bench():
    """bench/fem_accuracy.py as a module: the FreeCAD tests take its cases, its Gmsh meshing
    (bench.gmsh) and its CalculiX runs and measures from there."""
    spec = importlib.util.spec_from_file_location(
        "fem_accuracy", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                     "bench", "fem_accuracy.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


bench = load_bench()


def shape_from_file(doc, name, path):
    """A Part::Feature `name` in `doc` holding the shape of a BREP or STEP file."""
    import Part
    obj = doc.addObject("Part::Feature", name)
    obj.Shape = Part.read(path)
    return obj


def cantilever(order="1st", size=200.0):
    """FreeCAD's ccx_cantilever_faceload with its mesh remade by Gmsh; returns the document."""
    from femexamples.ccx_cantilever_faceload import setup
    doc = setup()
    bench.gmsh(doc.getObject(mesh_name(doc)), size, order)
    doc.recompute()
    return doc


def cantilever_from_shape(size=250.0, second_order=True):
    """FreeCAD's ccx_cantilever_faceload with its Gmsh mesh replaced by a hex-dominant mesh made
    from the box itself (shape mode); returns the document."""
    from femexamples.ccx_cantilever_faceload import setup
    import freecad.hexmerge as hm
    doc = setup()
    hm.make_hexdominant_mesh(doc, doc.Box, target_size=size, second_order=second_order,
                             analysis=doc.Analysis)
    doc.recompute()
    return doc


def mesh_name(doc):
    for o in doc.Analysis.Group:
        if o.isDerivedFrom("Fem::FemMeshObject"):
            return o.Name
    raise LookupError("no mesh in the analysis")


def tip_displacement(result):
    """Largest displacement magnitude of a result (the cantilever's tip), mm."""
    return max(result.DisplacementLengths)


def box_doc(order="1st", size=10.0, name="HexMergeBox"):
    """A new document with a 60 x 40 x 30 box meshed by Gmsh (tets of the given order and size):
    returns the document and its mesh object."""
    doc = FreeCAD.newDocument(name)
    box = doc.addObject("Part::Box", "Box")
    box.Length, box.Width, box.Height = 60, 40, 30
    doc.recompute()
    mesh = ObjectsFem.makeMeshGmsh(doc, "BoxMesh")
    mesh.Part = box
    doc.recompute()
    bench.gmsh(mesh, size, order)
    return doc, mesh


def collapsed_pyramids(source, femmesh):
    """The pyramids of a recombined FemMesh (stored as collapsed hexahedra: the apex on the last
    four corners) and how many of them have a node on the boundary of the tetrahedral `source`
    (a node of a triangle that one source tet alone has). Pyramid blocks proper are not
    expected: an assertion error names one."""
    import numpy as np
    from freecad.hexmerge import femmesh_arrays as fa
    source_arrays = fa.femmesh_to_arrays(source)
    _, tets, _ = fa.tetrahedra(source_arrays)
    faces = np.sort(np.concatenate([tets[:, f] for f in fa.FACES["tetra"]]), axis=1)
    keys, counts = np.unique(faces, axis=0, return_counts=True)
    boundary_ids = source_arrays.point_ids[keys[counts == 1]].ravel()
    arrays = fa.femmesh_to_arrays(femmesh)
    on_boundary = np.isin(arrays.point_ids, boundary_ids)
    pyramids = touching = 0
    for name, cells in arrays.blocks:
        assert name not in ("pyramid", "pyramid13"), "a pyramid block: " + name
        if name in ("hexahedron", "hexahedron20"):
            collapsed = (cells[:, 4] == cells[:, 5]) & (cells[:, 5] == cells[:, 6]) \
                & (cells[:, 6] == cells[:, 7])
            pyramids += int(collapsed.sum())
            touching += int(on_boundary[cells[collapsed][:, :5]].any(axis=1).sum())
    return pyramids, touching

