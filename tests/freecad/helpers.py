# SPDX-License-Identifier: LGPL-2.1-or-later
"""Shared set-up for the FreeCAD tests: Gmsh meshes of FreeCAD's FEM examples, CalculiX runs."""

import re
import tempfile

import FreeCAD
import ObjectsFem

BEAM_THEORY_TIP_MM = 88.84  # ccx_cantilever_faceload, Timoshenko beam with shear (DESIGN.md)


def gmsh_mesh(mesh_obj, size, order="1st"):
    """Meshes a MeshGmsh object with Gmsh (first or second order); returns the FemMesh."""
    from femmesh.gmshtools import GmshTools
    mesh_obj.CharacteristicLengthMax = size
    mesh_obj.CharacteristicLengthMin = 0
    mesh_obj.ElementOrder = order
    mesh_obj.SecondOrderLinear = False
    error = GmshTools(mesh_obj).create_mesh()
    if error:
        raise RuntimeError("Gmsh failed: {}".format(error))
    return mesh_obj.FemMesh


def cantilever(order="1st", size=200.0):
    """FreeCAD's ccx_cantilever_faceload with its mesh remade by Gmsh; returns the document."""
    from femexamples.ccx_cantilever_faceload import setup
    doc = setup()
    gmsh_mesh(doc.getObject(mesh_name(doc)), size, order)
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


def solve(doc, workdir=None):
    """Writes the .inp, runs CalculiX, loads the results; returns (inp path, result object)."""
    from femtools import ccxtools
    analysis = doc.Analysis
    solver = [o for o in analysis.Group if o.isDerivedFrom("Fem::FemSolverObjectPython")][0]
    workdir = workdir or tempfile.mkdtemp(prefix="hexmerge_ccx_")
    fea = ccxtools.FemToolsCcx(analysis, solver)
    fea.update_objects()
    fea.setup_working_dir(workdir)
    fea.setup_ccx()
    message = fea.check_prerequisites()
    if message:
        raise RuntimeError("CalculiX prerequisites: " + message)
    fea.write_inp_file()
    fea.ccx_run()
    fea.load_results()
    results = [o for o in analysis.Group if o.isDerivedFrom("Fem::FemResultObject")]
    if not results:
        raise RuntimeError("CalculiX gave no results (see {})".format(workdir))
    return fea.inp_file_name, results[-1]


NODES_PER_CCX_ELEMENT = {"C3D4": 4, "C3D6": 6, "C3D8": 8, "C3D10": 10, "C3D15": 15, "C3D20": 20}


def inp_element_count(path):
    """Number of volume elements in a CalculiX .inp file, by element type. An element may take
    several lines (C3D20), so the numbers are counted: id + nodes per element."""
    numbers = {}
    kind = None
    with open(path) as f:
        for line in f:
            if line.startswith("*"):
                m = re.match(r"\*ELEMENT\s*,\s*TYPE\s*=\s*(\w+)", line, re.I)
                kind = m.group(1).upper() if m else None
                continue
            if kind in NODES_PER_CCX_ELEMENT:
                numbers[kind] = numbers.get(kind, 0) + len(re.findall(r"\d+", line))
    return {k: n // (NODES_PER_CCX_ELEMENT[k] + 1) for k, n in numbers.items()}


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
    gmsh_mesh(mesh, size, order)
    return doc, mesh
