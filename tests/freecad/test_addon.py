# SPDX-License-Identifier: LGPL-2.1-or-later
"""The add-on with the engine, headless (freecadcmd -t test_addon): FreeCAD's examples meshed by
Gmsh, recombined, solved with CalculiX; save and reopen; Netgen input; bad cases."""

import os
import subprocess
import unittest

import numpy as np

import FreeCAD

import helpers
import freecad.hexmerge as hm
from freecad.hexmerge import femmesh_arrays as fa
from freecad.hexmerge import mesh_hexdominant, results

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def tearDownModule():
    helpers.bench.remove_work_directories()  # the CalculiX runs' files


def close_all():
    for name in list(FreeCAD.listDocuments()):
        FreeCAD.closeDocument(name)


box_doc = helpers.box_doc


def inp_count(femmesh):
    path = os.path.join(helpers.bench.work_directory("addon_"), "m.inp")
    femmesh.writeABAQUS(path, 1, False)
    return sum(helpers.bench.inp_counts(path)[0].values())


class Box(unittest.TestCase):

    def tearDown(self):
        close_all()

    def check(self, order, cell):
        doc, mesh = box_doc(order)
        before = mesh.FemMesh.VolumeCount
        nodes_before = mesh.FemMesh.NodeCount
        obj = hm.make_hexdominant_mesh(doc, mesh)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["input_tets"], before)
        m = obj.FemMesh
        self.assertEqual(m.VolumeCount, report["output_cells"])
        self.assertLess(m.VolumeCount, before)
        self.assertGreater(m.PrismCount + m.HexaCount, 0)
        self.assertEqual(inp_count(m), m.VolumeCount)  # no element left out of the .inp
        self.assertEqual(mesh.FemMesh.VolumeCount, before)  # source untouched
        self.assertEqual(mesh.FemMesh.NodeCount, nodes_before)
        blocks = fa.femmesh_to_arrays(m).blocks
        self.assertTrue(all(name.endswith(cell) or name in cell for name, _ in blocks), blocks)
        return report

    def test_tet4(self):
        self.check("1st", ("tetra", "pyramid", "wedge", "hexahedron"))

    def test_tet10_gives_quadratic_output(self):
        self.check("2nd", ("tetra10", "wedge15", "hexahedron20"))

    def test_recombine_femmesh_macro(self):
        doc, mesh = box_doc()
        before = (mesh.FemMesh.NodeCount, mesh.FemMesh.VolumeCount)
        femmesh, report = hm.recombine_femmesh(mesh.FemMesh, min_scaled_jacobian=0.5)
        self.assertEqual(femmesh.VolumeCount, report["output_cells"])
        self.assertEqual(report["freecad"]["pyramids_as_collapsed_hexahedra"], True)
        self.assertEqual(femmesh.PyramidCount, 0)
        # The CalculiX defaults (issue 15), the user's options over them: no pyramid with a node
        # on the boundary; with the engine's own placement, pyramids there.
        self.assertEqual(report["options"], {"pyramid_placement": "no_boundary_node",
                                             "min_scaled_jacobian": 0.5})
        pyramids, touching = helpers.collapsed_pyramids(mesh.FemMesh, femmesh)
        self.assertEqual(touching, 0)
        anywhere, _ = hm.recombine_femmesh(mesh.FemMesh, pyramid_placement="anywhere")
        _, touching = helpers.collapsed_pyramids(mesh.FemMesh, anywhere)
        self.assertGreater(touching, 0)
        self.assertEqual((mesh.FemMesh.NodeCount, mesh.FemMesh.VolumeCount), before)  # untouched

    def test_post_merge_node_moves_reach_the_femmesh(self):
        """same_nodes off (issue 19): the FemMesh has the engine's node positions (a moved node
        at its new place, not the source's), and the nodes contracted away are left out."""
        from freecad.hexmerge import jobs
        doc, mesh = box_doc("1st", size=6.0)
        source = fa.femmesh_to_arrays(mesh.FemMesh)
        job = jobs.RecombineJob.prepare(mesh.FemMesh, {"same_nodes": False}, regions="none")
        job.run()
        femmesh, report = job.finish()
        result = job.result[0]
        self.assertEqual(report["post_merge"], "kept")
        self.assertGreater(report["node_moves"], 0)
        blocks = results.result_blocks(job.result)[0]
        used = np.unique(np.concatenate([cells.reshape(-1) for _, cells in blocks]))
        self.assertEqual(femmesh.NodeCount, len(used))
        ids = source.point_ids[np.asarray(result.point_map)[used]]
        nodes = femmesh.Nodes
        got = np.array([tuple(nodes[int(i)]) for i in ids])
        np.testing.assert_array_equal(got, result.points[used])
        moved = np.linalg.norm(got - source.points[np.asarray(result.point_map)[used]], axis=1)
        self.assertGreater(int((moved > 1e-9).sum()), 0)
        self.assertEqual(femmesh.VolumeCount, report["output_cells"])


class Cantilever(unittest.TestCase):
    """FreeCAD's ccx_cantilever_faceload, Gmsh Tet4 (h = 200 mm), solved with CalculiX."""

    def tearDown(self):
        close_all()

    def test_recombined_tip_is_closer_to_beam_theory(self):
        doc = helpers.cantilever("1st", 200.0)
        src = doc.getObject(helpers.mesh_name(doc))
        res, inp, _ = helpers.bench.solve(doc)
        tet_tip = helpers.tip_displacement(res)
        self.assertEqual(sum(helpers.bench.inp_counts(inp)[0].values()), src.FemMesh.VolumeCount)
        obj = hm.make_hexdominant_mesh(doc, src)
        self.assertIn(obj, doc.Analysis.Group)
        self.assertNotIn(src, doc.Analysis.Group)
        res, inp, _ = helpers.bench.solve(doc)
        counts = helpers.bench.inp_counts(inp)[0]
        self.assertEqual(sum(counts.values()), obj.FemMesh.VolumeCount)
        hex_tip = helpers.tip_displacement(res)
        FreeCAD.Console.PrintMessage(
            "HexMerge cantilever: Tet4 {:.2f} mm, recombined {:.2f} mm, beam theory {} mm; "
            ".inp {} ({})\n".format(tet_tip, hex_tip, helpers.BEAM_THEORY_TIP_MM, counts,
                                    obj.Summary))
        self.assertLess(abs(hex_tip - helpers.BEAM_THEORY_TIP_MM),
                        abs(tet_tip - helpers.BEAM_THEORY_TIP_MM))


class CantileverFromShape(unittest.TestCase):
    """The same cantilever, meshed from its box (shape mode, second order) instead of Gmsh's
    tets, solved with CalculiX through FreeCAD's FEM workflow."""

    def tearDown(self):
        close_all()

    def test_tip_within_3_percent_of_beam_theory(self):
        doc = helpers.cantilever_from_shape()
        obj = doc.getObject("HexDominantMesh")
        self.assertIn(obj, doc.Analysis.Group)
        self.assertEqual([o for o in doc.Analysis.Group if o.isDerivedFrom("Fem::FemMeshObject")],
                         [obj])
        report = mesh_hexdominant.report_dict(obj)
        self.assertLessEqual(report["meshing"]["max_boundary_distance"], 1e-3 * obj.TargetSize.Value)
        # The beam (a box): the tets' volume is the shape's, and the results table says so.
        self.assertIn(("volume vs. shape", "", "+0.00 %"), results.results_rows(report))
        res, inp, _ = helpers.bench.solve(doc)
        counts = helpers.bench.inp_counts(inp)[0]
        self.assertEqual(sum(counts.values()), obj.FemMesh.VolumeCount)
        self.assertIn("C3D20", counts)  # second order: Hexa20
        tip = helpers.tip_displacement(res)
        FreeCAD.Console.PrintMessage(
            "HexMerge cantilever from shape (h {} mm, second order): tip {:.2f} mm, beam theory "
            "{} mm ({:+.2f} %); .inp {} ({})\n".format(
                obj.TargetSize.Value, tip, helpers.BEAM_THEORY_TIP_MM,
                100 * (tip / helpers.BEAM_THEORY_TIP_MM - 1), counts, obj.Summary))
        self.assertLess(abs(tip - helpers.BEAM_THEORY_TIP_MM), 0.03 * helpers.BEAM_THEORY_TIP_MM)


class ShapeMode(unittest.TestCase):
    """A hex-dominant mesh whose source is a solid: made, recomputed on a shape change, saved."""

    def tearDown(self):
        close_all()

    def box(self):
        doc = FreeCAD.newDocument("HexMergeShape")
        box = doc.addObject("Part::Box", "Box")
        box.Length, box.Width, box.Height = 60, 40, 30
        doc.recompute()
        return doc, box

    def test_box_is_hexahedra_and_follows_the_shape(self):
        doc, box = self.box()
        obj = hm.make_hexdominant_mesh(doc, box, target_size=10, second_order=False)
        self.assertTrue(mesh_hexdominant.is_shape_source(box))
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["output_counts"], {"tet": 0, "pyramid": 0, "prism": 0, "hex": 72})
        self.assertEqual(obj.FemMesh.HexaCount, 72)
        self.assertEqual(report["meshing"]["parameters"]["size"], 10.0)
        self.assertIn("shape at h 10", obj.Summary)
        # A new shape marks the mesh for recompute, and recompute meshes it.
        box.Height = 50
        doc.recompute()
        self.assertNotIn("Touched", obj.State)
        self.assertEqual(obj.FemMesh.HexaCount, 6 * 4 * 5)
        zs = [obj.FemMesh.getNodeById(n).z for n in obj.FemMesh.Nodes]
        self.assertAlmostEqual(max(zs), 50.0)
        # So does a new target size.
        obj.TargetSize = 5
        doc.recompute()
        self.assertEqual(obj.FemMesh.HexaCount, 12 * 8 * 10)

    def test_cylinder_is_swept_into_hexahedra_and_prisms(self):
        doc = FreeCAD.newDocument("HexMergeShape")
        cylinder = doc.addObject("Part::Cylinder", "Cylinder")
        cylinder.Radius, cylinder.Height = 20, 50
        doc.recompute()
        obj = hm.make_hexdominant_mesh(doc, cylinder, target_size=4, second_order=False)
        self.assertTrue(obj.Sweep)
        report = mesh_hexdominant.report_dict(obj)
        self.assertGreaterEqual(report["meshing"]["sweep_axis"], 0)
        counts = report["output_counts"]
        self.assertEqual(counts["tet"] + counts["pyramid"], 0, counts)
        self.assertGreaterEqual(report["volume_fraction"]["hex"], 0.85)
        self.assertEqual(obj.FemMesh.HexaCount, counts["hex"])
        self.assertEqual(obj.FemMesh.PrismCount, counts["prism"])
        obj.Sweep = False
        doc.recompute()
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["meshing"]["sweep_axis"], -1)
        self.assertGreater(report["output_counts"]["pyramid"], 0)

    def test_plate_with_hole_at_its_default_size(self):
        """FreeCAD's FEM example material_nl_platewithhole at its own default size, 2.5 mm: TetGen
        1.5 failed on its own triangulation of the lattice faces at 2.25 to 2.5 mm (the mesher
        then took the lattice at 1.1 of the size); given them as triangles, it meshes at the size
        asked, in the first way: a swept, almost all-hexahedral mesh (99.7 % of the volume)."""
        doc = FreeCAD.newDocument("HexMergePlate")
        plate = helpers.shape_from_file(
            doc, "Plate", os.path.join(ROOT, "resources", "examples", "material_nl_platewithhole.brep"))
        doc.recompute()
        obj = hm.make_hexdominant_mesh(doc, plate, target_size=2.5, second_order=False)
        report = mesh_hexdominant.report_dict(obj)
        meshing = report["meshing"]
        self.assertGreaterEqual(meshing["sweep_axis"], 0)
        self.assertEqual(meshing["strategy"], "lattice")
        self.assertEqual(meshing["failed_strategies"], [])
        self.assertEqual(meshing["nb_tetgen_restarts"], 0)
        self.assertGreaterEqual(report["volume_fraction"]["hex"], 0.95)
        self.assertEqual(obj.FemMesh.HexaCount, report["output_counts"]["hex"])
        self.assertGreaterEqual(min(report["min_scaled_jacobian"][k] for k, n in report["output_counts"].items() if n), 0.2)

    def test_the_mesher_s_notes_are_the_add_on_s_warnings(self):
        """What the command line notes about how the tets were made reaches the add-on's user:
        a cone BRepMesh cannot triangulate (its apex a degenerated edge, as a KiCad connector
        model has it) is triangulated as a surface of revolution, and the add-on says so."""
        doc = FreeCAD.newDocument("HexMergeApexCone")
        cone = helpers.shape_from_file(doc, "Cone", os.path.join(ROOT, "tests", "data", "apex_cone.brep"))
        doc.recompute()
        obj = hm.make_hexdominant_mesh(doc, cone, target_size=0.25, second_order=False)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["meshing"]["nb_revolution_faces"], 1)
        self.assertTrue(any("as surfaces of revolution" in w for w in report["freecad"]["warnings"]),
                        report["freecad"]["warnings"])
        self.assertGreater(obj.FemMesh.VolumeCount, 0)

    def test_the_voids_of_femexamples_two_balls_stay_empty(self):
        """FreeCAD's FEM example equation_electrostatics_capacitance_two_balls: a ball of radius
        5000 less two balls of 500 inside it. TetGen filled the two voids (it carves from the
        convex hull only): the balls were meshed as material, with flat tets in them."""
        import math
        from femexamples.equation_electrostatics_capacitance_two_balls import setup
        doc = setup()
        solid = next(o for o in doc.Objects if o.Name == "Cut")
        obj = hm.make_hexdominant_mesh(doc, solid, target_size=500, second_order=False)
        report = mesh_hexdominant.report_dict(obj)
        self.assertGreater(report["meshing"]["nb_void_tets"], 0)
        expected = 4 / 3 * math.pi * (5000 ** 3 - 2 * 500 ** 3)
        self.assertLess(abs(report["input_volume"] - expected), 0.01 * expected)
        m = obj.FemMesh
        for eid in m.Volumes:
            nodes = [m.getNodeById(n) for n in m.getElementNodes(eid)]
            c = [sum(getattr(p, a) for p in nodes) / len(nodes) for a in "xyz"]
            for x0 in (-1000, 1000):
                self.assertGreater(math.dist(c, (x0, 0, 0)), 450, eid)
        self.assertGreaterEqual(min(report["min_scaled_jacobian"][k]
                                    for k, n in report["output_counts"].items() if n), 0.2)

    def test_sharp_cad_is_named(self):
        """A prism over a triangle with a 5-degree corner: no element at that corner or along
        its edge can reach a scaled Jacobian of 0.2, and the console says where, in FreeCAD's
        numbers (issue 13: the CAD-forced exceptions named with their angle)."""
        import math
        import Part
        doc = FreeCAD.newDocument("HexMergeWedge")
        a = math.radians(5)
        triangle = Part.makePolygon([FreeCAD.Vector(0, 0, 0), FreeCAD.Vector(50, 0, 0),
                                     FreeCAD.Vector(50 * math.cos(a), 50 * math.sin(a), 0),
                                     FreeCAD.Vector(0, 0, 0)])
        wedge = doc.addObject("Part::Feature", "Wedge")
        wedge.Shape = Part.Face(triangle).extrude(FreeCAD.Vector(0, 0, 10))
        doc.recompute()
        obj = hm.make_hexdominant_mesh(doc, wedge, target_size=2, second_order=False)
        report = mesh_hexdominant.report_dict(obj)
        sharp = report["meshing"]["sharp_features"]
        self.assertEqual(sorted(f["kind"] for f in sharp), ["corner", "corner", "edge"])
        for f in sharp:
            self.assertAlmostEqual(f["angle"], 5, places=6)
            self.assertAlmostEqual(f["point"][0], 0, places=9)
            self.assertAlmostEqual(f["point"][1], 0, places=9)
        [warning] = [w for w in report["freecad"]["warnings"] if "sharper than 8.13 degrees" in w]
        self.assertIn("the CAD has 3 corner(s) or edge(s)", warning)
        edge = next(f for f in sharp if f["kind"] == "edge")["edges"][0]
        self.assertIn("Edge{} between Face".format(edge), warning)
        self.assertGreater(obj.FemMesh.VolumeCount, 0)

    def test_second_order_default_and_options(self):
        doc, box = self.box()
        obj = hm.make_hexdominant_mesh(doc, box, boundary_layers=0, min_scaled_jacobian=0.4)
        self.assertTrue(obj.SecondOrder)
        self.assertAlmostEqual(obj.TargetSize.Value, 7.5)  # a quarter of the 30 mm side
        self.assertEqual(obj.BoundaryLayers, 0)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["meshing"]["parameters"]["boundary_layers"], 0)
        self.assertTrue(report["meshing"]["parameters"]["second_order"])
        self.assertEqual(obj.FemMesh.VolumeCount, report["output_cells"])
        self.assertEqual(inp_count(obj.FemMesh), obj.FemMesh.VolumeCount)
        blocks = fa.femmesh_to_arrays(obj.FemMesh).blocks
        self.assertTrue(all(name in ("tetra10", "wedge15", "hexahedron20") for name, _ in blocks), blocks)

    def test_properties_are_the_compiled_tables(self):
        """The object's options are exactly the rows of the engine's and the mesher's compiled
        tables that name a FreeCAD property, with the tables' defaults, plus the add-on's own."""
        import hexmerge
        doc, box = self.box()
        obj = hm.make_hexdominant_mesh(doc, box, recompute=False)
        rows = [r for r in hexmerge.parameters() + hexmerge.mesh_parameters() if r["freecad_property"]]
        own = {"SourceMesh", "Part", "PyramidsAsHexahedra", "SecondOrder", "LinearHexahedron",
               "QuadraticHexahedron", "QuadraticPyramid", "MeshRegionList", "MeshBoundaryLayerList"}
        report_group = {p for p in obj.PropertiesList if obj.getGroupOfProperty(p) == "Report"}
        fem_mesh = set(doc.addObject("Fem::FemMeshObjectPython", "Plain").PropertiesList)
        ours = set(obj.PropertiesList) - fem_mesh - report_group
        self.assertEqual(ours, {r["freecad_property"] for r in rows} | own)
        for r in rows:
            value = getattr(obj, r["freecad_property"])
            if r["type"] in ("int", "bool") or (r["type"] == "float" and r["unit"] not in ("deg", "mm")):
                self.assertEqual(value, r["default"], r["name"])
            elif r["type"] == "choice" and r["name"] != "pyramid_placement":  # CalculiX's default
                self.assertEqual(value, r["default"], r["name"])
            self.assertTrue(obj.getDocumentationOfProperty(r["freecad_property"]).startswith(r["doc"]))
        # A mesh made from the shape starts from CALCULIX_SHAPE_DEFAULTS: pyramids off the nodes
        # of the curved parts of the boundary (the second-order ones written as two tied C3D10);
        # one from tets from no_boundary_node.
        self.assertEqual(obj.PyramidPlacement, "no_curved_boundary_node")
        self.assertEqual(obj.QuadraticPyramid, "two C3D10, tied")

    def test_save_reopen(self):
        doc, box = self.box()
        name = hm.make_hexdominant_mesh(doc, box, target_size=10, second_order=False).Name
        path = os.path.join(helpers.bench.work_directory("addon_"), "shape.FCStd")
        doc.saveAs(path)
        FreeCAD.closeDocument(doc.Name)
        doc = FreeCAD.openDocument(path)
        obj = doc.getObject(name)
        self.assertEqual(obj.FemMesh.HexaCount, 72)
        self.assertAlmostEqual(obj.TargetSize.Value, 10.0)
        doc.getObject("Box").Length = 70
        doc.recompute()
        self.assertEqual(obj.FemMesh.HexaCount, 84)

    def test_target_size_above_the_thinnest_side_is_warned(self):
        doc, box = self.box()
        obj = hm.make_hexdominant_mesh(doc, box, target_size=35, second_order=False)
        warnings = mesh_hexdominant.report_dict(obj)["freecad"]["warnings"]
        self.assertEqual(len(warnings), 1, warnings)
        self.assertIn("thinnest side", warnings[0])
        self.assertIn("30 mm", warnings[0])
        obj.TargetSize = 10
        doc.recompute()
        self.assertEqual(mesh_hexdominant.report_dict(obj)["freecad"]["warnings"], [])

    def test_a_size_at_which_the_surface_crosses_itself_names_the_faces(self):
        # A tube 0.05 thick (walls of radius 1.5375 and 1.5875): at 40 mm its walls' triangles
        # cross (the chord deflection, 0.8 mm, and a quarter of it, the finer surface tried
        # next, are wider than the wall), which the mesher finds before TetGen and reports,
        # naming the faces, in every way of placing the points.
        import Part

        doc = FreeCAD.newDocument("HexMergeTube")
        tube = doc.addObject("Part::Feature", "Tube")
        outer = Part.makeCylinder(1.5875, 100, FreeCAD.Vector(0, 0, 0), FreeCAD.Vector(1, 0, 0))
        inner = Part.makeCylinder(1.5375, 102, FreeCAD.Vector(-1, 0, 0), FreeCAD.Vector(1, 0, 0))
        tube.Shape = outer.cut(inner)
        doc.recompute()
        with self.assertRaisesRegex(RuntimeError,
                                    r"the surface's triangles at this size cross \(Face\d+ and "
                                    r"Face\d+ near .*a smaller size keeps them apart"):
            hm.make_hexdominant_mesh(doc, tube, target_size=40, second_order=False)
        # At 5 mm the first surface is too coarse for the wall (its swaps against slivers carry
        # the bore's side into the bore) and the finer one (0.025 mm) meshes.
        obj = hm.make_hexdominant_mesh(doc, tube, target_size=5, second_order=False)
        self.assertGreater(obj.FemMesh.VolumeCount, 0)

    def test_bad_shapes(self):
        doc, box = self.box()
        with self.assertRaisesRegex(RuntimeError, "larger than the shape"):
            hm.make_hexdominant_mesh(doc, box, target_size=500)
        face = doc.addObject("Part::Plane", "Plane")
        doc.recompute()
        n = len(doc.Objects)
        with self.assertRaisesRegex(ValueError, "has no solid"):
            hm.make_hexdominant_mesh(doc, face)
        self.assertEqual(len(doc.Objects), n)
        with self.assertRaisesRegex(ValueError, "unknown HexMerge option"):
            hm.make_hexdominant_mesh(doc, box, no_such_option=1)


class Progress(unittest.TestCase):
    """The panel's one progress bar across the engine's and the mesher's phases."""

    def test_one_bar_across_phases(self):
        from freecad.hexmerge.task_mesh_hexdominant import PHASES, overall_progress
        for shape_mode, phases in ((False, ["topology", "candidates", "selection", "bound", "done"]),
                                   (True, ["mesh shape", "topology", "candidates", "selection",
                                           "done"])):
            values = []
            for phase in phases:
                for f in (0.0, 0.5, 1.0):
                    value, name = overall_progress(phase, f, shape_mode)
                    self.assertEqual(name, PHASES[phase][0])
                    self.assertNotEqual(name, phase)  # a readable name, not the engine's
                    values.append(value)
            self.assertEqual(values, sorted(values), (shape_mode, values))
            self.assertEqual(values[0], 0.0)
            self.assertEqual(values[-1], 1.0)
            self.assertGreater(values[3], 0.0)  # the second phase does not restart at 0

    def test_mesher_steps_have_readable_names_within_the_meshing_share(self):
        from freecad.hexmerge.task_mesh_hexdominant import (MESHER_STEPS, SHAPE_MESHING_SHARE,
                                                            overall_progress)
        for step, readable in MESHER_STEPS.items():
            for way in ("", " (surface only)"):
                value, name = overall_progress(f"mesh shape: {step}{way}", 0.5, True)
                self.assertEqual(name, f"Meshing the shape: {readable}{way}")
                self.assertAlmostEqual(value, 0.5 * SHAPE_MESHING_SHARE)


class WriterLink(unittest.TestCase):
    """FreeCAD's CalculiX writer reads the mesh object's shape from its Part (or Shape) link and
    warns "A finite mesh without a link to a Shape" when there is none."""

    def tearDown(self):
        close_all()

    def shape_seen_by_writer(self, doc, mesh):
        from femmesh.meshsetsgetter import MeshSetsGetter
        from femtools.membertools import AnalysisMember
        solver = [o for o in doc.Analysis.Group
                  if o.isDerivedFrom("Fem::FemSolverObjectPython")][0]
        return MeshSetsGetter(doc.Analysis, solver, mesh, AnalysisMember(doc.Analysis)).theshape

    def test_shape_mode_links_the_shape(self):
        doc = helpers.cantilever_from_shape(size=500.0, second_order=False)
        mesh = doc.getObject(helpers.mesh_name(doc))
        self.assertEqual(mesh.Proxy.Type, mesh_hexdominant.TYPE)
        self.assertEqual(self.shape_seen_by_writer(doc, mesh), doc.Box)

    def test_tet_mode_links_the_source_meshs_shape_after_reopen(self):
        doc = helpers.cantilever("1st", 400.0)
        gmsh = doc.getObject(helpers.mesh_name(doc))
        name = hm.make_hexdominant_mesh(doc, gmsh).Name
        self.assertEqual(self.shape_seen_by_writer(doc, doc.getObject(name)), doc.Box)
        path = os.path.join(helpers.bench.work_directory("addon_"), "link.FCStd")
        doc.saveAs(path)
        FreeCAD.closeDocument(doc.Name)
        doc = FreeCAD.openDocument(path)
        self.assertEqual(self.shape_seen_by_writer(doc, doc.getObject(name)), doc.Box)
        # the link follows the source
        doc.getObject(name).SourceMesh = None
        self.assertIsNone(doc.getObject(name).Part)


class MultiMaterial(unittest.TestCase):
    """material_multiple_bendingbeam_fiveboxes: five solids, three materials."""

    def tearDown(self):
        close_all()

    def test_no_element_spans_two_materials_and_solve_runs(self):
        from femexamples.material_multiple_bendingbeam_fiveboxes import setup
        doc = setup()
        src = doc.getObject(helpers.mesh_name(doc))
        helpers.bench.gmsh(src, 4.0, "1st")
        obj = hm.make_hexdominant_mesh(doc, src)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["freecad"]["region_count"], 5)
        # no volume groups in the Gmsh mesh: the regions come from the solids, in C++
        self.assertIn("OpenCASCADE", report["freecad"]["regions"])
        m = obj.FemMesh
        groups = {m.getGroupName(g): m.getGroupElements(g) for g in m.Groups}
        self.assertEqual(sorted(groups), ["FemMaterial1_Solids", "FemMaterial2_Solids",
                                          "FemMaterial3_Solids"])
        self.assertEqual(sum(len(v) for v in groups.values()), m.VolumeCount)
        # each box is 20 mm long in x: every element lies within one box
        for eid in m.Volumes:
            xs = [m.getNodeById(n).x for n in m.getElementNodes(eid)]
            self.assertEqual(int(min(xs) // 20 + 1e-9), int((max(xs) - 1e-9) // 20), eid)
        # the material of each box, by group
        expected = {0: "FemMaterial3", 1: "FemMaterial2", 2: "FemMaterial1", 3: "FemMaterial2",
                    4: "FemMaterial3"}
        for name, elements in groups.items():
            for eid in elements[:50]:
                xs = [m.getNodeById(n).x for n in m.getElementNodes(eid)]
                self.assertEqual(expected[int(np.mean(xs) // 20)] + "_Solids", name)
        res, inp, _ = helpers.bench.solve(doc)
        self.assertEqual(sum(helpers.bench.inp_counts(inp)[0].values()), m.VolumeCount)
        self.assertGreater(helpers.tip_displacement(res), 0)


class SaveReopen(unittest.TestCase):

    def tearDown(self):
        close_all()

    def test_save_reopen_recompute(self):
        doc, mesh = box_doc()
        mesh_name = mesh.Name
        obj = hm.make_hexdominant_mesh(doc, mesh, min_dihedral_angle=150, min_scaled_jacobian=0.4,
                                       make_pyramids=False)
        count = obj.FemMesh.VolumeCount
        name = obj.Name
        path = os.path.join(helpers.bench.work_directory("addon_"), "hexmerge.FCStd")
        doc.saveAs(path)
        FreeCAD.closeDocument(doc.Name)
        doc = FreeCAD.openDocument(path)
        obj = doc.getObject(name)
        self.assertEqual(obj.Proxy.Type, mesh_hexdominant.TYPE)
        self.assertEqual(obj.FemMesh.VolumeCount, count)
        self.assertAlmostEqual(obj.MinDihedralAngle.getValueAs("deg"), 150)
        self.assertAlmostEqual(obj.MinScaledJacobian, 0.4)
        self.assertFalse(obj.MakePyramids)
        self.assertTrue(mesh_hexdominant.report_dict(obj))
        self.assertEqual(obj.SourceMesh.Name, mesh_name)
        # a new source mesh marks the object for recompute, and recompute uses it
        helpers.bench.gmsh(doc.getObject(mesh_name), 6.0, "1st")
        doc.recompute()
        self.assertNotEqual(obj.FemMesh.VolumeCount, count)
        self.assertEqual(mesh_hexdominant.report_dict(obj)["input_tets"],
                         doc.getObject(mesh_name).FemMesh.VolumeCount)


class Netgen(unittest.TestCase):

    def tearDown(self):
        close_all()

    def test_netgen_mesh_imported_and_recombined(self):
        import meshio
        vol = os.path.join(helpers.bench.work_directory("addon_"), "cyl.vol")
        subprocess.run(["/usr/bin/python3.11", os.path.join(HERE, "make_netgen_mesh.py"), vol],
                       check=True, capture_output=True)
        mio = meshio.read(vol)
        tets = np.concatenate([c.data for c in mio.cells if c.type == "tetra"])
        femmesh, _ = fa.arrays_to_femmesh(mio.points, np.arange(1, len(mio.points) + 1),
                                          [("tetra", tets)], with_faces=False)
        doc = FreeCAD.newDocument("HexMergeNetgen")
        src = doc.addObject("Fem::FemMeshObject", "NetgenMesh")
        src.FemMesh = femmesh
        obj = hm.make_hexdominant_mesh(doc, src)
        report = mesh_hexdominant.report_dict(obj)
        self.assertEqual(report["input_tets"], len(tets))
        self.assertEqual(inp_count(obj.FemMesh), obj.FemMesh.VolumeCount)
        self.assertLess(obj.FemMesh.VolumeCount, len(tets))


class BadCases(unittest.TestCase):

    def tearDown(self):
        close_all()

    def test_not_tetrahedral(self):
        doc, mesh = box_doc()
        hexmesh = hm.make_hexdominant_mesh(doc, mesh)
        n = len(doc.Objects)
        with self.assertRaisesRegex(ValueError, "not tetrahedral"):
            hm.make_hexdominant_mesh(doc, hexmesh)
        self.assertEqual(len(doc.Objects), n)

    def test_empty_mesh(self):
        doc = FreeCAD.newDocument("HexMergeEmpty")
        src = doc.addObject("Fem::FemMeshObject", "Empty")
        with self.assertRaisesRegex(ValueError, "no volume elements"):
            hm.make_hexdominant_mesh(doc, src)
        self.assertEqual(len(doc.Objects), 1)

    def test_not_a_mesh(self):
        doc = FreeCAD.newDocument("HexMergeNotMesh")
        box = doc.addObject("Part::Box", "Box")
        with self.assertRaisesRegex(ValueError, "not a FEM mesh"):
            hm.make_hexdominant_mesh(doc, box)
        with self.assertRaisesRegex(ValueError, "no mesh selected"):
            hm.make_hexdominant_mesh(doc, None)

    def test_unknown_option(self):
        doc, mesh = box_doc()
        with self.assertRaisesRegex(ValueError, "unknown HexMerge option"):
            hm.make_hexdominant_mesh(doc, mesh, no_such_option=1)
        self.assertEqual([o.Name for o in doc.Objects if o.Name.startswith("HexDom")], [])

    def test_source_deleted(self):
        doc, mesh = box_doc()
        obj = hm.make_hexdominant_mesh(doc, mesh)
        count = obj.FemMesh.VolumeCount
        doc.removeObject(mesh.Name)
        obj.touch()
        doc.recompute()
        self.assertIn("Invalid", obj.State)
        self.assertIn("no source mesh", obj.getStatusString())
        self.assertEqual(obj.FemMesh.VolumeCount, count)  # last result kept


if __name__ == "__main__":
    unittest.main()
