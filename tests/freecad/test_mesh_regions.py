# SPDX-License-Identifier: LGPL-2.1-or-later
"""FEM mesh regions in shape mode (freecadcmd -t test_mesh_regions): a Fem::MeshRegion on a face
of the shape makes the hex-dominant mesh finer there; what cannot be honoured is warned about.

The shape is FreeCAD's plate with a hole (resources/examples, 400 x 200 x 10 mm, hole radius 50):
Face5 is the hole's wall, Vertex1 a corner."""

import math
import os
import unittest

import FreeCAD
import ObjectsFem
import Part

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
        self.plate = self.doc.addObject("Part::Feature", "Plate")
        self.plate.Shape = Part.read(PLATE)
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
        self.assertEqual(report["freecad"]["warnings"], [])
        # Local sizes turn the sweep off (one size along the axis); the cells are all there.
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
        self.assertEqual(len(warnings), 2, warnings)
        self.assertIn("Vertex1 of Plate is not supported in shape mode", warnings[0])
        self.assertIn("boundary layer Layers is not honoured in shape mode", warnings[1])


if __name__ == "__main__":
    unittest.main()
