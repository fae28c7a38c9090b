# SPDX-License-Identifier: LGPL-2.1-or-later
"""FEM mesh regions in shape mode (freecadcmd -t test_mesh_regions): a Fem::MeshRegion on a face
of the shape makes the hex-dominant mesh finer there, a Fem::MeshBoundaryLayer makes layers of
nodes at the thicknesses it asks; what cannot be honoured is warned about.

The shape is FreeCAD's plate with a hole (resources/examples, 400 x 200 x 10 mm, hole radius 50):
Face5 is the hole's wall, Vertex1 a corner."""

import math
import os
import unittest

import FreeCAD
import ObjectsFem
import helpers

import freecad.hexmerge as hm
from freecad.hexmerge import mesh_hexdominant

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
PLATE = os.path.join(ROOT, "resources", "examples", "material_nl_platewithhole.brep")
H = 10.0


def hole_nodes(femmesh):
    """The mesh's nodes on the hole's wall (radius 50), as (angle, z) pairs."""
    out = []
    for n in femmesh.Nodes:
        p = femmesh.getNodeById(n)
        if abs(math.hypot(p.x, p.y) - 50) < 1e-6:
            out.append((math.atan2(p.y, p.x), p.z))
    return out


def widest_gap(nodes, z):
    """The largest arc between consecutive nodes on the hole's circle at height z (mm)."""
    angles = sorted(a for a, nz in nodes if abs(nz - z) < 1e-6)
    gaps = [b - a for a, b in zip(angles, angles[1:])] + [2 * math.pi - angles[-1] + angles[0]]
    return 50 * max(gaps)


class MeshRegions(unittest.TestCase):

    def setUp(self):
        self.doc = FreeCAD.newDocument("HexMergeRegions")
        self.plate = helpers.shape_from_file(self.doc, "Plate", PLATE)
        self.analysis = ObjectsFem.makeAnalysis(self.doc, "Analysis")
        self.doc.recompute()

    def tearDown(self):
        FreeCAD.closeDocument(self.doc.Name)

    def test_a_mesh_region_makes_the_mesh_finer_where_it_points(self):
        obj = hm.make_hexdominant_mesh(self.doc, self.plate, target_size=H, second_order=False,
                                       analysis=self.analysis)
        plain = hole_nodes(obj.FemMesh)
        self.assertGreater(widest_gap(plain, 0.0), H / 4)
        # As for Gmsh's mesh object: ObjectsFem.makeMeshRegion fills the mesh's MeshRegionList,
        # and a change of the region recomputes the mesh.
        region = ObjectsFem.makeMeshRegion(self.doc, obj, H / 4, "HoleRegion")
        region.References = [(self.plate, "Face5")]
        self.doc.recompute()
        self.assertNotIn("Invalid", obj.State)
        fine = hole_nodes(obj.FemMesh)
        self.assertGreater(len(fine), 8 * len(plain))
        for z in (0.0, 10.0):
            self.assertLessEqual(widest_gap(fine, z), H / 4 * (1 + 1e-6))
        report = mesh_hexdominant.report_dict(obj)
        (applied,) = report["meshing"]["local_sizes"]
        self.assertEqual((applied["faces"], applied["size"]), ([5], H / 4))
        self.assertLessEqual(applied["max_side"], H / 4 * (1 + 1e-9))
        self.assertEqual(report["meshing"]["parameters"]["local_sizes"], "Face5:2.5")
        # Local sizes turn the sweep off (one size along the axis), which the mesher notes (as the
        # command line does); the cells are all there.
        (note,) = report["freecad"]["warnings"]
        self.assertIn("not swept, though an extrusion: the local size 2.5 on Face5", note)
        self.assertEqual(report["meshing"]["sweep_axis"], -1)
        self.assertEqual(obj.FemMesh.VolumeCount, sum(report["output_counts"].values()))
        self.assertEqual(mesh_hexdominant.found_mesh_regions(obj), (["HoleRegion: Face5 2.5 mm"], []))
        # Finer than the target size only: a coarser region is left out, with a warning.
        region.CharacteristicLength = 2 * H
        self.doc.recompute()
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["meshing"]["local_sizes"], [])
        self.assertIn("not finer than the target size", " ".join(report["freecad"]["warnings"]))
        self.assertEqual(len(hole_nodes(obj.FemMesh)), len(plain))

    def test_regions_of_the_analysis_and_what_is_not_honoured(self):
        from femobjects import mesh_boundarylayer, mesh_region
        # A region in the analysis (not in the mesh's list), on the hole's wall and a vertex.
        region = self.doc.addObject("Fem::FeaturePython", "AnalysisRegion")
        mesh_region.MeshRegion(region)
        region.CharacteristicLength = 5.0
        region.References = [(self.plate, ("Face5", "Vertex1"))]
        layer = self.doc.addObject("Fem::FeaturePython", "Layers")
        mesh_boundarylayer.MeshBoundaryLayer(layer)
        layer.References = [(self.plate, "Face5")]
        self.analysis.addObject(region)
        self.analysis.addObject(layer)
        obj = hm.make_hexdominant_mesh(self.doc, self.plate, target_size=H, second_order=False,
                                       analysis=self.analysis)
        report = mesh_hexdominant.report_dict(obj)
        (applied,) = report["meshing"]["local_sizes"]
        self.assertEqual((applied["faces"], applied["size"]), ([5], 5.0))
        self.assertLessEqual(widest_gap(hole_nodes(obj.FemMesh), 0.0), 5.0 * (1 + 1e-6))
        warnings = report["freecad"]["warnings"]
        self.assertEqual(len(warnings), 3, warnings)
        self.assertIn("Vertex1 of Plate is not supported in shape mode", warnings[0])
        # Its MinimumThickness is FreeCAD's default, 0: left out, said so.
        self.assertIn("boundary layer Layers: no MinimumThickness set: left out", warnings[1])
        # And the mesher's note: the local size turned the sweep off.
        self.assertIn("not swept, though an extrusion: the local size 5 on Face5", warnings[2])
        self.assertEqual(report["meshing"]["face_layers"], [])

    def test_a_boundary_layer_object_makes_layers_on_its_face(self):
        """A Fem::MeshBoundaryLayer on a face of a box (Face1, x = 0; 100 x 40 x 30 mm, h 10):
        3 layers from 1 mm, growth 1.5: nodes at 1, 2.5 and 4.75 mm from the face (within the
        mesher's 10 % variation), straight over the face's nodes (tests/python/test_face_layers.py
        checks the same mesh's volume and recombination)."""
        from femobjects import mesh_boundarylayer
        box = self.doc.addObject("Part::Box", "Box")
        box.Length, box.Width, box.Height = 100, 40, 30
        self.doc.recompute()
        obj = hm.make_hexdominant_mesh(self.doc, box, target_size=H, second_order=False,
                                       analysis=self.analysis)
        self.assertNotIn("Invalid", obj.State)
        layer = self.doc.addObject("Fem::FeaturePython", "WallLayers")
        mesh_boundarylayer.MeshBoundaryLayer(layer)
        layer.NumberOfLayers = 3
        layer.MinimumThickness = 1.0
        layer.GrowthRate = 1.5
        layer.References = [(box, "Face1")]
        obj.MeshBoundaryLayerList = [layer]
        obj.touch()
        self.doc.recompute()
        self.assertNotIn("Invalid", obj.State)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["freecad"]["warnings"], [])
        self.assertEqual(report["meshing"]["parameters"]["face_layers"], "Face1:3:1.0:1.5")
        (applied,) = report["meshing"]["face_layers"]
        self.assertEqual(applied["faces"], [1])
        self.assertEqual(mesh_hexdominant.found_mesh_regions(obj)[0],
                         ["WallLayers: Face1 3 layers from 1 mm, growth 1.5"])
        points = [obj.FemMesh.getNodeById(n) for n in obj.FemMesh.Nodes]
        face = {(round(p.y, 6), round(p.z, 6)) for p in points if abs(p.x) < 1e-9}
        over = [p for p in points if 0 < p.x < 6 and (round(p.y, 6), round(p.z, 6)) in face]
        for k, depth in enumerate([1.0, 2.5, 4.75]):
            at = [p for p in over if abs(p.x - depth) <= 0.1 * depth + 1e-9]
            self.assertEqual(len(at), applied["nb_per_layer"][k], (depth, applied))
            self.assertGreater(len(at), 0.5 * applied["nb_nodes"])
        # Nothing between the face and its first layer over the face's nodes.
        self.assertGreaterEqual(min(p.x for p in over), 0.9 - 1e-9)
        self.assertEqual(obj.FemMesh.VolumeCount, sum(report["output_counts"].values()))


if __name__ == "__main__":
    unittest.main()
