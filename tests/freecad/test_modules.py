# SPDX-License-Identifier: LGPL-2.1-or-later
"""The add-on's module graph (freecadcmd -t test_modules): imports run one way, as in FreeCAD
FEM (the view provider imports the task panel, never the reverse); each module imports on its
own in a fresh interpreter, in dependency order; the modules without GUI need neither Qt nor
FreeCADGui."""

import ast
import os
import subprocess
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
PACKAGE = os.path.join(ROOT, "freecad", "hexmerge")
GUI_MODULES = {"FreeCADGui", "PySide", "PySide2", "pivy", "FemGui"}
# Modules that must not import FreeCAD's GUI nor Qt (engine access, jobs, results, colours...).
HEADLESS = ("resources", "calculix", "engine", "regions", "femmesh_arrays", "results", "colors", "jobs",
            "properties", "mesh_hexdominant", "makers")


def module_imports(name):
    """(modules of the package, other top-level modules) imported anywhere in a module, also
    inside functions."""
    tree = ast.parse(open(os.path.join(PACKAGE, name + ".py")).read())
    ours, others = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1:  # from . import x / from .x import y
                if node.module:
                    ours.add(node.module.split(".")[0])
                else:
                    ours.update(a.name for a in node.names)
            elif node.level == 0 and node.module:
                others.add(node.module.split(".")[0])
        elif isinstance(node, ast.Import):
            others.update(a.name.split(".")[0] for a in node.names)
    return ours, others


def modules():
    return sorted(f[:-3] for f in os.listdir(PACKAGE) if f.endswith(".py"))


def dependency_order(graph):
    """The modules, each after those it imports; AssertionError naming a cycle if there is one."""
    order, state = [], {}

    def visit(m, path):
        if state.get(m) == "done":
            return
        if state.get(m) == "open":
            cycle = path[path.index(m):] + [m]
            raise AssertionError("import cycle: " + " -> ".join(cycle))
        state[m] = "open"
        for d in sorted(graph[m]):
            visit(d, path + [m])
        state[m] = "done"
        order.append(m)

    for m in sorted(graph):
        visit(m, [])
    return order


class ModuleGraph(unittest.TestCase):

    def setUp(self):
        self.graph = {m: module_imports(m)[0] - {"__init__"} for m in modules()}

    def test_every_import_names_a_module(self):
        for m, deps in self.graph.items():
            for d in deps:
                self.assertIn(d, self.graph, "{} imports .{}, which does not exist".format(m, d))

    def test_no_cycle(self):
        order = dependency_order(self.graph)
        self.assertEqual(sorted(order), sorted(self.graph))

    def test_cycle_is_found(self):
        # the check itself: a graph with a cycle is refused, naming it
        with self.assertRaises(AssertionError) as e:
            dependency_order({"a": {"b"}, "b": {"c"}, "c": {"a"}})
        self.assertIn("a -> b -> c -> a", str(e.exception))

    def test_fem_direction(self):
        self.assertIn("task_mesh_hexdominant", self.graph["view_mesh_hexdominant"])
        for m, deps in self.graph.items():
            if m != "makers":  # makes the view provider when the GUI is up, as ObjectsFem
                self.assertNotIn("view_mesh_hexdominant", deps, m)
        self.assertNotIn("commands", self.graph["task_mesh_hexdominant"])

    def test_headless_modules_need_no_gui(self):
        for m in HEADLESS:
            others = module_imports(m)[1]
            self.assertFalse(others & GUI_MODULES, "{} imports {}".format(m, others & GUI_MODULES))

    def test_one_resources_path(self):
        for m in modules():
            if m == "resources":
                continue
            text = open(os.path.join(PACKAGE, m + ".py")).read()
            self.assertNotIn('"resources"', text, "{} builds a resources path itself".format(m))

    def test_each_module_imports_alone_in_dependency_order(self):
        order = [m for m in dependency_order(self.graph) if m != "init_gui"]
        code = ("import importlib, sys\n"
                "for m in {!r}:\n"
                "    importlib.import_module('freecad.hexmerge.' + m)\n"
                "    print('imported', m)\n").format(order)
        for m in order:  # each in a fresh interpreter, alone
            out = subprocess.run(
                ["freecadcmd", "-c", "import importlib; importlib.import_module("
                 "'freecad.hexmerge.{}'); print('imported {}')".format(m, m), "-M", ROOT],
                capture_output=True, text=True, timeout=120,
                env=dict(os.environ, QT_QPA_PLATFORM="offscreen"))
            self.assertIn("imported " + m, out.stdout, "{}: {}{}".format(m, out.stdout[-400:],
                                                                         out.stderr[-400:]))
        out = subprocess.run(["freecadcmd", "-c", code, "-M", ROOT], capture_output=True,
                             text=True, timeout=120, env=dict(os.environ, QT_QPA_PLATFORM="offscreen"))
        self.assertIn("imported " + order[-1], out.stdout, out.stdout[-400:] + out.stderr[-400:])


if __name__ == "__main__":
    unittest.main()
