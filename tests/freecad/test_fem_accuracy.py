# SPDX-License-Identifier: LGPL-2.1-or-later
"""Issue 15 (freecadcmd -t test_fem_accuracy): a recombined mesh solved in CalculiX through
FreeCAD is at least as accurate as the tets it came from, on the same nodes (small cases of
bench/fem_accuracy.py, whose functions it uses: the plate with a hole, Tet10 at 12 mm, peak
principal stress at the hole against the converged 570.6 MPa; the cantilever's tip at 200 mm);
second-order meshes from the shape take pressure on curved faces; the CalculiX element type of
the add-on's hexahedra (LinearHexahedron, QuadraticHexahedron) reaches the .inp through
FreeCAD's own writer and gives the accuracy measured in docs/fem-accuracy.md."""

import os
import unittest

import FreeCAD

import freecad.hexmerge as hm
from freecad.hexmerge import femmesh_arrays as fa
from freecad.hexmerge import calculix, engine, jobs

import helpers

bench = helpers.bench


def tearDownModule():
    helpers.bench.remove_work_directories()  # the CalculiX runs' files


def close_all():
    for name in list(FreeCAD.listDocuments()):
        FreeCAD.closeDocument(name)


class RecombinedNotWorse(unittest.TestCase):
    """The add-on's CalculiX defaults (engine.calculix_options()) against the source."""

    def tearDown(self):
        close_all()

    def compare(self, case, size, order, key, merges):
        doc, mesh = bench.build_case(case)
        source = bench.gmsh(mesh, size, order).copy()
        result, _, _ = bench.solve(doc)
        tet = bench.measure(case, result, source)[key]
        femmesh, report = jobs.recombine_femmesh(
            source, regions="none", **engine.calculix_options())
        if order == "1st":
            self.assertEqual(femmesh.NodeCount, source.NodeCount)  # the same nodes
        else:  # the mid-edge nodes inside merged elements go
            self.assertLessEqual(femmesh.NodeCount, source.NodeCount)
        if merges:
            self.assertGreater(femmesh.HexaCount + femmesh.PrismCount, 0)
        self.assert_no_pyramid_on_the_boundary(source, femmesh)
        mesh.FemMesh = femmesh
        result, inp, _ = bench.solve(doc)
        counts, _ = bench.inp_counts(inp)
        self.assertEqual(sum(counts.values()), femmesh.VolumeCount)  # every element solved
        merged = bench.measure(case, result, femmesh)[key]
        ref = bench.REFERENCES[case][key]
        FreeCAD.Console.PrintMessage(
            "HexMerge {} {} {} mm: tets {:.2f} ({:+.2f} %), recombined {:.2f} ({:+.2f} %), "
            "reference {}; .inp {}\n".format(case, order, size, tet, 100 * (tet / ref - 1),
                                             merged, 100 * (merged / ref - 1), ref, counts))
        self.assertLessEqual(abs(merged - ref), abs(tet - ref))

    def assert_no_pyramid_on_the_boundary(self, source, femmesh):
        """What pyramid_placement = no_boundary_node promises: no pyramid (collapsed hexahedron)
        has a node on the boundary."""
        pyramids, touching = helpers.collapsed_pyramids(source, femmesh)
        self.assertEqual(touching, 0)
        return pyramids

    def test_cantilever_tip_tet4(self):
        # recombined 1,455 nodes: tip -11.5 % against the tets' -12.1 % (docs/fem-accuracy.md)
        self.compare("cantilever", 200.0, "1st", "tip", merges=True)

    def test_plate_with_hole_peak_stress_tet10(self):
        # with pyramids anywhere the peak was +2.9 % against the tets' -0.7 %
        self.compare("plate", 12.0, "2nd", "P1", merges=False)


class SecondOrderFromShape(unittest.TestCase):
    """A pressure on a curved face of a second-order mesh from the shape reaches CalculiX: the
    mesher puts the bore's mid-edge nodes on the CAD, so FreeCAD's writer finds the faces."""

    def tearDown(self):
        close_all()

    def test_cylinder_pressure_on_the_bore_tet10_from_shape(self):
        # With the mid nodes on the chords (r 49.92 mm) the writer found no face and wrote no
        # *DLOAD: the hoop stress read 0. On the CAD: 168.3 MPa, +1.0 % (docs/fem-accuracy.md).
        doc, mesh = bench.build_case("cylinder")
        job = jobs.ShapeJob.prepare(doc.getObject(mesh.Part.Name).Shape,
                                    {"size": 8.0, "second_order": True})
        job.run()
        femmesh, report = job.finish()
        self.assertEqual(report["meshing"]["nb_straight_mid_nodes"], 0)
        self.assertGreater(report["meshing"]["nb_projected_mid_nodes"], 0)
        mesh.FemMesh = femmesh
        result, inp, _ = bench.solve(doc)
        with open(inp) as f:
            text = f.read()
        self.assertIn("*DLOAD", text)
        # Every element face on the bore is loaded: the .inp's pressure lines name faces of
        # elements, at least one per boundary face the bore has (the quarter's bore, h 8 mm).
        loads = [line for line in text.split("*DLOAD", 1)[1].splitlines()[1:]
                 if line.strip() and not line.startswith("*") and ",P" in line.replace(" ", "")]
        self.assertGreater(len(loads), 20)
        hoop = bench.measure("cylinder", result, femmesh)["hoop"]
        ref = bench.REFERENCES["cylinder"]["hoop"]
        FreeCAD.Console.PrintMessage(
            "HexMerge cylinder from shape 8 mm second order: hoop {:.2f} MPa ({:+.2f} %), "
            "{} pressure lines\n".format(hoop, 100 * (hoop / ref - 1), len(loads)))
        self.assertLess(abs(hoop / ref - 1), 0.02)


class QuadraticPyramids(unittest.TestCase):
    """Second-order pyramids reach CalculiX as two C3D10 whose split diagonal is tied to the face
    behind (QuadraticPyramid's default, calculix.split_pyramids_in_input), not as collapsed
    C3D20 (docs/fem-accuracy.md)."""

    def tearDown(self):
        close_all()

    def test_quadratic_patch_test(self):
        # A C3D20 cube beside a cube of six pyramids, the outside held at pure bending's exact
        # (quadratic) displacement: split and tied, reproduced to round-off; collapsed C3D20,
        # displacements off by 1.3 % and stresses by 14 %; split but not tied, 11 % and 25 %.
        displacement, stress = bench.pyramid_patch_test(split=True)
        self.assertLess(displacement, 1e-6)
        self.assertLess(stress, 1e-6)
        displacement, stress = bench.pyramid_patch_test(split=False)
        self.assertGreater(displacement, 0.5)
        self.assertGreater(stress, 5.0)

    def test_plate_with_hole_unswept_from_shape(self):
        # The plate made from its shape without the sweep, 8 mm, second order. The shape mode's
        # default (pyramids off the nodes of curved faces): -0.16 % either way. Pyramids only
        # off the curved faces (nodes on the hole allowed): two tied C3D10 -0.32 %, collapsed
        # C3D20 +12.22 %; 96 % of the volume hexahedra (docs/fem-accuracy.md).
        doc, mesh = bench.build_case("plate")
        obj = hm.make_hexdominant_mesh(doc, mesh.Part, target_size=8.0, second_order=True,
                                       sweep=False, analysis=doc.Analysis)
        self.assertEqual(obj.PyramidPlacement, "no_curved_boundary_node")
        self.assertEqual(obj.QuadraticPyramid, calculix.SPLIT_PYRAMID)
        for placement in ("no_curved_boundary_node", "no_curved_boundary_face"):
            obj.PyramidPlacement = placement
            doc.recompute()
            femmesh = obj.FemMesh
            pyramids = sum(1 for e in femmesh.Volumes if len(set(femmesh.getElementNodes(e))) == 13)
            self.assertGreater(pyramids, 50)
            self.assertGreater(femmesh.HexaCount - pyramids, 1000)
            errors = {}
            for choice in calculix.QUADRATIC_PYRAMID:
                obj.QuadraticPyramid = choice
                result, inp, _ = bench.solve(doc)
                counts, collapsed = bench.inp_counts(inp)
                with open(inp) as f:
                    text = f.read()
                if choice == calculix.SPLIT_PYRAMID:
                    self.assertEqual(collapsed, 0)
                    self.assertEqual(sum(counts.values()), femmesh.VolumeCount + pyramids)
                    self.assertEqual(text.count("*EQUATION"), 3 * pyramids)  # a tie per direction
                else:
                    self.assertEqual(collapsed, pyramids)
                    self.assertNotIn("*EQUATION", text)
                errors[choice] = error("plate", "P1", bench.measure("plate", result, femmesh)["P1"])
            obj.QuadraticPyramid = calculix.SPLIT_PYRAMID
            print_errors("plate from shape unswept 8 mm, second order, {}, peak".format(placement),
                         errors)
            self.assertLess(abs(errors[calculix.SPLIT_PYRAMID]), 0.01)
            if placement == "no_curved_boundary_face":
                self.assertGreater(errors["collapsed C3D20"], 0.03)
            else:
                self.assertLess(abs(errors["collapsed C3D20"]), 0.01)

    def test_cylinder_unswept_from_shape(self):
        # The thick cylinder made from its shape without the sweep, 5 mm, second order: the
        # bore's hoop stress +0.32 % with the shape mode's default (no pyramid node on the
        # bore), +2.90 % with pyramids only off the curved faces (docs/fem-accuracy.md).
        doc, mesh = bench.build_case("cylinder")
        obj = hm.make_hexdominant_mesh(doc, mesh.Part, target_size=5.0, second_order=True,
                                       sweep=False, analysis=doc.Analysis)
        errors = {}
        for placement in ("no_curved_boundary_node", "no_curved_boundary_face"):
            obj.PyramidPlacement = placement
            doc.recompute()
            self.assertGreater(obj.FemMesh.HexaCount, 500)
            result, _, _ = bench.solve(doc)
            errors[placement] = error("cylinder", "hoop",
                                      bench.measure("cylinder", result, obj.FemMesh)["hoop"])
        print_errors("cylinder from shape unswept 5 mm, second order, bore's hoop stress", errors)
        self.assertLess(abs(errors["no_curved_boundary_node"]), 0.01)
        self.assertGreater(abs(errors["no_curved_boundary_face"]), 0.02)


def print_errors(what, errors):
    """One line in the report view: the relative error per choice."""
    FreeCAD.Console.PrintMessage("HexMerge {} error: {}\n".format(
        what, {k: "{:+.2%}".format(v) for k, v in errors.items()}))


def error(case, key, value):
    return value / bench.REFERENCES[case][key] - 1.0


class HexahedronElementTypes(unittest.TestCase):
    """LinearHexahedron / QuadraticHexahedron reach the .inp through FreeCAD's own CalculiX writer
    (the add-on's hook on write_mesh), only for true hexahedra, and solve to the accuracy
    measured in docs/fem-accuracy.md."""

    def tearDown(self):
        close_all()

    def solve_as(self, doc, obj, prop, choice):
        setattr(obj, prop, choice)
        result, inp, _ = bench.solve(doc)
        return result, bench.inp_counts(inp)

    def test_linear_hexahedra_cantilever_from_shape(self):
        # 1,000 cubes of 200 mm (all parallelepipeds): C3D8 locks in bending, -2.42 %; C3D8I
        # -0.24 % (docs/fem-accuracy.md).
        doc = helpers.cantilever_from_shape(size=200.0, second_order=False)
        obj = doc.getObject("HexDominantMesh")
        self.assertEqual(obj.LinearHexahedron, calculix.C3D8I_IF_PARALLELEPIPED)  # the default
        hexes = obj.FemMesh.HexaCount
        self.assertEqual(hexes, obj.FemMesh.VolumeCount)
        tips = {}
        for choice, written in ((calculix.C3D8I_IF_PARALLELEPIPED, "C3D8I"), ("C3D8I", "C3D8I"),
                                ("C3D8", "C3D8")):
            result, counts = self.solve_as(doc, obj, "LinearHexahedron", choice)
            self.assertEqual(counts, ({written: hexes}, 0), choice)
            tips[choice] = error("cantilever", "tip", bench.measure("cantilever", result, None)["tip"])
        print_errors("cantilever from shape 200 mm, first order, tip", tips)
        self.assertLess(abs(tips[calculix.C3D8I_IF_PARALLELEPIPED]), 0.01)
        self.assertLess(abs(tips["C3D8I"]), 0.01)
        self.assertGreater(abs(tips["C3D8"]), 0.015)
        # The split input file (the mesh in a file of its own) is retyped too.
        solver = bench.solver_of(doc)
        solver.SplitInputWriter = True
        obj.LinearHexahedron = "C3D8I"
        _, inp, _ = bench.solve(doc)
        mesh_file = os.path.join(os.path.dirname(inp), obj.Name + "_femesh.inp")
        self.assertEqual(bench.inp_counts(mesh_file), ({"C3D8I": hexes}, 0))

    def test_linear_hexahedra_plate_with_hole_from_shape(self):
        # At the hole the hexahedra are distorted: CalculiX's C3D8I fails the patch test there
        # and overstates the peak (+3.7 % at 6 mm, +24 % at 4 mm); C3D8I only on parallelepipeds
        # keeps C3D8's answer (-0.06 %): +0.07 % (docs/fem-accuracy.md).
        doc, mesh = bench.build_case("plate")
        obj = hm.make_hexdominant_mesh(doc, mesh.Part, target_size=6.0, second_order=False,
                                       analysis=doc.Analysis)
        femmesh = obj.FemMesh
        errors = {}
        for choice in (calculix.C3D8I_IF_PARALLELEPIPED, "C3D8I"):
            result, (counts, collapsed) = self.solve_as(doc, obj, "LinearHexahedron", choice)
            self.assertEqual(sum(counts.values()), femmesh.VolumeCount)
            self.assertEqual(counts.get("C3D6", 0), femmesh.PrismCount)
            if choice == "C3D8I":
                self.assertEqual(counts.get("C3D8I"), femmesh.HexaCount)
            else:  # a mixed mesh: C3D8I inside, C3D8 on the distorted hexahedra at the hole
                self.assertGreater(counts.get("C3D8", 0), 0)
                self.assertGreater(counts.get("C3D8I", 0), counts["C3D8"])
                self.assertEqual(counts["C3D8I"] + counts["C3D8"], femmesh.HexaCount)
            errors[choice] = error("plate", "P1", bench.measure("plate", result, femmesh)["P1"])
        print_errors("plate from shape 6 mm, first order, peak", errors)
        self.assertLess(abs(errors[calculix.C3D8I_IF_PARALLELEPIPED]), 0.01)
        self.assertGreater(errors["C3D8I"], 0.02)

    def test_mixed_recombined_mesh_c3d8i_c3d8_c3d6_c3d4(self):
        # Gmsh Tet4 at 200 mm recombined with pyramids anywhere: true hexahedra as C3D8I,
        # pyramids as collapsed C3D8, prisms C3D6, tets C3D4, in one run; the tip is no worse
        # than the tets' (-9.1 % against -11.9 %, docs/fem-accuracy.md).
        doc = helpers.cantilever("1st", 200.0)
        src = doc.getObject(helpers.mesh_name(doc))
        result, _, _ = bench.solve(doc)
        tet_tip = error("cantilever", "tip", bench.measure("cantilever", result, None)["tip"])
        obj = hm.make_hexdominant_mesh(doc, src, pyramid_placement="anywhere",
                                       linear_hexahedron="C3D8I")
        result, inp, _ = bench.solve(doc)
        counts, collapsed = bench.inp_counts(inp)
        arrays = fa.femmesh_to_arrays(obj.FemMesh)
        pyramids = sum(int(((c[:, 4] == c[:, 5]) & (c[:, 5] == c[:, 6]) & (c[:, 6] == c[:, 7])).sum())
                       for name, c in arrays.blocks if name == "hexahedron")
        self.assertGreater(pyramids, 0)
        self.assertEqual(counts["C3D8"], pyramids)  # the collapsed ones stay C3D8
        self.assertEqual(collapsed, pyramids)
        self.assertEqual(counts["C3D8I"], obj.FemMesh.HexaCount - pyramids)
        self.assertEqual(counts["C3D6"], obj.FemMesh.PrismCount)
        self.assertEqual(counts["C3D4"], obj.FemMesh.TetraCount)
        tip = error("cantilever", "tip", bench.measure("cantilever", result, None)["tip"])
        FreeCAD.Console.PrintMessage("HexMerge cantilever Tet4 200 mm: tets {:+.2%}, recombined "
                                     "C3D8I/C3D8/C3D6/C3D4 {:+.2%}; .inp {}\n"
                                     .format(tet_tip, tip, counts))
        self.assertLessEqual(abs(tip), abs(tet_tip))

    def test_quadratic_hexahedra_c3d20r(self):
        # C3D20R, reduced integration: tip -0.05 % at 200 mm (C3D20 -0.08 %).
        doc = helpers.cantilever_from_shape(size=250.0, second_order=True)
        obj = doc.getObject("HexDominantMesh")
        self.assertEqual(obj.QuadraticHexahedron, "C3D20")  # the default
        hexes = obj.FemMesh.HexaCount
        result, counts = self.solve_as(doc, obj, "QuadraticHexahedron", "C3D20R")
        self.assertEqual(counts, ({"C3D20R": hexes}, 0))
        self.assertLess(abs(error("cantilever", "tip",
                                  bench.measure("cantilever", result, None)["tip"])), 0.01)


class PatchTest(unittest.TestCase):
    """Why C3D8I goes on parallelepipeds only: CalculiX 2.20's C3D8I fails the patch test on
    distorted hexahedra (bench.patch_test: uniform tension, the middle node of 2 x 2 x 2 moved),
    by about 0.66 x calculix.distortion(); C3D8 passes whatever the distortion."""

    def test_c3d8_passes_c3d8i_fails_off_parallelepipeds(self):
        for shift in (0.0, 0.2, 0.5):
            self.assertLess(bench.patch_test("C3D8", shift)[1], 1e-6)
        self.assertLess(bench.patch_test("C3D8I", 0.0)[1], 1e-6)
        distorted, error = bench.patch_test("C3D8I", 0.5)
        self.assertGreater(distorted, 0.05)
        self.assertGreater(error, 3.0)  # % of the applied stress (measured 3.98)
        # at the bound the default accepts, the error stays under half a percent
        at_bound, error = bench.patch_test("C3D8I", 0.045)
        self.assertLessEqual(at_bound, calculix.MAX_C3D8I_DISTORTION)
        self.assertLess(error, 0.5)


class Retype(unittest.TestCase):
    """calculix.retype_lines on a written .inp: 20-node elements over two lines, a block of true
    and collapsed hexahedra split in two, the rest untouched."""

    def test_collapsed_quadratic_hexahedron_stays_c3d20(self):
        cube = [((1 + a) / 2, (1 + b) / 2, (1 + c) / 2) for a, b, c in calculix._CORNERS]
        points = cube + [(0.5, 0.5, 2.0)] + [(i, 9.0, 9.0) for i in range(20)]
        lines = ["*Node, NSET=Nall"] + ["{}, {}, {}, {}".format(i + 1, *p)
                                        for i, p in enumerate(points)]
        true_hex = [1] + list(range(1, 9)) + list(range(10, 22))
        pyramid = [2] + [9, 9, 9, 9, 5, 6, 7, 8] + list(range(10, 22))
        lines += ["*Element, TYPE=C3D20, ELSET=Evolumes"]
        for e in (true_hex, pyramid):
            lines += [", ".join(map(str, e[:16])) + ",", ", ".join(map(str, e[16:]))]
        lines += ["*Element, TYPE=C3D4, ELSET=Evolumes", "3, 1, 2, 3, 9", "*ELSET,ELSET=Eall",
                  "1, 2, 3"]
        out, counts = calculix.retype_lines(lines, {"C3D20": "C3D20R"})
        self.assertEqual(counts, {"C3D20R": 1})
        blocks = bench.read_inp_elements(out)
        self.assertEqual([(kind, [e[0] for e in elements]) for _, _, kind, elements in blocks],
                         [("C3D20", [2]), ("C3D20R", [1]), ("C3D4", [3])])
        self.assertEqual([list(e[1]) for e in blocks[1][3]], [true_hex[1:]])
        self.assertEqual(out[-2:], ["*ELSET,ELSET=Eall", "1, 2, 3"])
        self.assertTrue(all(line.startswith("*Element, TYPE=") and line.endswith("ELSET=Evolumes")
                            for line in out if line.startswith("*Element")))

    def test_distortion(self):
        cube = [((1 + a) / 2, (1 + b) / 2, (1 + c) / 2) for a, b, c in calculix._CORNERS]
        sheared = [(2 * x + 0.5 * y, 3 * y, z + 0.2 * x) for x, y, z in cube]
        self.assertLess(calculix.distortion(sheared), 1e-12)  # a parallelepiped
        moved = list(cube)
        moved[6] = (1.1, 1.0, 1.0)  # one corner moved by 10 % of the edge
        self.assertAlmostEqual(calculix.distortion(moved), 0.025, delta=1e-3)


if __name__ == "__main__":
    unittest.main()
