# SPDX-License-Identifier: LGPL-2.1-or-later
"""Recombination of a FemMesh with no GUI (the role of FEM's femmesh/netgentools.py).

A run has three steps so that a GUI can keep the middle one off its thread:
    job = RecombineJob.prepare(femmesh, ...)   # FreeCAD thread: FemMesh -> arrays, regions
    job.run(progress)                          # any thread: numpy and the engine only
    femmesh, report = job.finish()             # FreeCAD thread: arrays -> new FemMesh
recombine_femmesh() chains them.
"""

import os
import sys
import time

import numpy as np

from . import femmesh_arrays
from . import regions as regions_mod

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# Options of the add-on itself (not engine parameters).
PYRAMIDS_AS_HEXAHEDRA_DOC = (
    "FreeCAD 0.20's CalculiX writer leaves pyramids out of the input file. When on, every "
    "pyramid is stored as a collapsed hexahedron (base, apex four times), which the writer emits "
    "as C3D8 (C3D20 for quadratic meshes), so the solver sees every element.")


class Cancelled(Exception):
    """The user cancelled the run through the progress callback."""


def engine():
    """The hexmerge Python module, with a clear message when it is not built or not importable."""
    try:
        import hexmerge
    except ImportError:
        # A checkout linked into FreeCAD's Mod folder: the module is built into src/python.
        built = os.path.join(REPO, "src", "python")
        if os.path.isdir(os.path.join(built, "hexmerge")) and built not in sys.path:
            sys.path.append(built)
    try:
        import hexmerge
    except ImportError as e:
        raise ImportError(
            "the HexMerge engine (Python module 'hexmerge') cannot be imported into FreeCAD's "
            "Python: build it with the README's setup command ({})".format(e)) from e
    return hexmerge


def parameter_table():
    """The engine's parameter table as a list of dicts (name, type, default, unit, min, max,
    choices, label, doc), whatever the module returns rows as."""
    rows = []
    for r in engine().parameters():
        get = (lambda k, r=r: r.get(k)) if isinstance(r, dict) else (lambda k, r=r: getattr(r, k, None))
        rows.append({k: get(k) for k in
                     ("name", "type", "default", "unit", "min", "max", "choices", "label", "doc")})
    return rows


def mesh_parameter_table():
    """The mesher's options (hexmerge.mesh_parameters()), in parameter_table()'s row format."""
    return [{k: r.get(k) for k in ("name", "type", "default", "unit", "min", "max", "choices",
                                   "label", "doc")}
            for r in engine().mesh_parameters()]


def engine_options(options):
    """Keeps the options the engine knows, with their table types; rejects unknown names."""
    table = {r["name"]: r for r in parameter_table()}
    out = {}
    for name, value in options.items():
        if name not in table:
            raise ValueError("unknown HexMerge option '{}' (known: {})"
                             .format(name, ", ".join(table)))
        kind = table[name]["type"]
        out[name] = (float(value) if kind == "float" else int(value) if kind == "int"
                     else bool(value) if kind == "bool" else str(value))
    return out


class RecombineJob:
    """One recombination of a tetrahedral FemMesh; see the module docstring."""

    def __init__(self, arrays, cell_name, tets, regions, options, pyramids_as_hexahedra):
        self.arrays = arrays
        self.cell_name = cell_name
        self.tets = tets
        self.regions = regions
        self.options = options
        self.pyramids_as_hexahedra = pyramids_as_hexahedra
        self.result = None
        self.seconds = {}

    @classmethod
    def prepare(cls, femmesh, options=None, regions="auto", shape=None, material_solids=None,
                materials=(), pyramids_as_hexahedra=True):
        """Reads the FemMesh and finds the regions.

        regions: "auto" (mesh groups, else solids of `shape`), "none", or a Regions object.
        Raises NotTetrahedralError (with a message for the user) for an empty or mixed mesh.
        """
        t = time.perf_counter()
        arrays = femmesh_arrays.femmesh_to_arrays(femmesh)
        name, tets, element_ids = femmesh_arrays.tetrahedra(arrays)
        read = time.perf_counter() - t

        t = time.perf_counter()
        if regions == "auto":
            found = regions_mod.from_groups(femmesh, element_ids, materials)
            if found is None and shape is not None:
                found = regions_mod.from_solids(shape, arrays.points, tets, material_solids)
            regions = found
        elif regions == "none":
            regions = None
        job = cls(arrays, name, tets, regions, engine_options(options or {}),
                  pyramids_as_hexahedra)
        job.seconds = {"read FemMesh": read, "regions": time.perf_counter() - t}
        return job

    def run(self, progress=None):
        """Runs the engine. progress(phase, fraction) -> False cancels (raises Cancelled)."""
        hexmerge = engine()
        t = time.perf_counter()
        region_ids = self.regions.ids if self.regions is not None else None
        if region_ids is not None and "respect_regions" in self.options \
                and not self.options["respect_regions"]:
            region_ids = None
        kwargs = dict(self.options)
        if progress is not None:
            kwargs["progress"] = progress
        try:
            self.result = hexmerge.recombine(self.arrays.points, self.tets, region_ids, **kwargs)
        except hexmerge.Cancelled as e:
            raise Cancelled(str(e) or "cancelled") from e
        self.seconds["engine"] = time.perf_counter() - t

    def finish(self):
        """The new FemMesh and the report (the engine's, plus what the add-on did)."""
        t = time.perf_counter()
        blocks, block_regions, point_index = result_blocks(self.result)
        points, point_ids = self.arrays.points, self.arrays.point_ids
        if point_index is not None:
            points, point_ids = points[point_index], point_ids[point_index]
        names = self.regions.names if self.regions is not None else None
        femmesh, _ = femmesh_arrays.arrays_to_femmesh(
            points, point_ids, blocks, block_regions, names, self.pyramids_as_hexahedra)
        self.seconds["write FemMesh"] = time.perf_counter() - t

        report = dict(result_report(self.result))
        report["freecad"] = {
            "input_cells": self.cell_name,
            "regions": (self.regions.source if self.regions is not None else "none"),
            "region_count": (self.regions.count if self.regions is not None else 0),
            "material_groups": sorted((names or {}).values()),
            "pyramids_as_collapsed_hexahedra": bool(self.pyramids_as_hexahedra),
            "femmesh_volumes": femmesh.VolumeCount,
            "seconds": self.seconds,
        }
        return femmesh, report


class ShapeJob:
    """Meshing of a solid shape with hexmerge.mesh_shape() and recombination, in the same three
    steps as RecombineJob (prepare on FreeCAD's thread, run on any, finish on FreeCAD's)."""

    def __init__(self, brep, nb_solids, mesher, options, material_names, pyramids_as_hexahedra):
        self.brep = brep
        self.nb_solids = nb_solids
        self.mesher = mesher
        self.options = options
        self.material_names = material_names
        self.pyramids_as_hexahedra = pyramids_as_hexahedra
        self.result = None
        self.seconds = {}

    @classmethod
    def prepare(cls, shape, mesher, options=None, material_names=None, pyramids_as_hexahedra=True):
        """shape: a Part shape with at least one solid; mesher: {size, boundary_layers, ...,
        second_order} (mesh_shape()'s keywords); options: engine parameters.
        Raises ValueError with a message for the user."""
        solids = list(getattr(shape, "Solids", []) or [])
        if not solids:
            raise ValueError("the shape has no solid: HexMerge meshes closed solids")
        size = float(mesher.get("size") or 0.0)
        if size <= 0:
            raise ValueError("set the target size (TargetSize) to a positive length")
        t = time.perf_counter()
        brep = shape.exportBrepToString()
        job = cls(brep, len(solids), dict(mesher, size=size), engine_options(options or {}),
                  dict(material_names or {}), pyramids_as_hexahedra)
        job.seconds = {"export shape": time.perf_counter() - t}
        return job

    def run(self, progress=None):
        """Meshes and recombines. progress(phase, fraction) -> False cancels (raises Cancelled)."""
        hexmerge = engine()
        t = time.perf_counter()
        kwargs = dict(self.mesher)
        kwargs.update(self.options)
        size = kwargs.pop("size")
        try:
            self.result = hexmerge.mesh_shape(self.brep, size, progress=progress, **kwargs)
        except hexmerge.Cancelled as e:
            raise Cancelled(str(e) or "cancelled") from e
        self.seconds["mesh and recombine"] = time.perf_counter() - t

    def finish(self):
        """The new FemMesh and the report (the engine's with the mesher's under "meshing", plus
        what the add-on did)."""
        t = time.perf_counter()
        mesh = self.result[0]
        blocks, block_regions, _ = result_blocks(self.result)
        # Regions are the solids (0-based): tets of different solids were never merged. With one
        # solid there is nothing to tell apart, as for a tet mesh of one solid.
        names, count = None, 1
        if self.nb_solids > 1 and block_regions is not None and self.options.get("respect_regions", True):
            block_regions = [r + 1 for r in block_regions]
            names = self.material_names
            count = len(np.unique(mesh.regions))
        else:
            block_regions = None
        femmesh, _ = femmesh_arrays.arrays_to_femmesh(
            mesh.points, np.arange(1, mesh.nb_points + 1), blocks, block_regions, names,
            self.pyramids_as_hexahedra)
        self.seconds["write FemMesh"] = time.perf_counter() - t
        report = dict(result_report(self.result))
        report["freecad"] = {
            "input_cells": "shape",
            "regions": ("solids of the shape ({} solids, mesher)".format(self.nb_solids)
                        if block_regions is not None else "none"),
            "region_count": count if block_regions is not None else 0,
            "material_groups": sorted((names or {}).values()),
            "pyramids_as_collapsed_hexahedra": bool(self.pyramids_as_hexahedra),
            "femmesh_volumes": femmesh.VolumeCount,
            "seconds": self.seconds,
        }
        return femmesh, report


def recombine_femmesh(femmesh, regions="auto", shape=None, pyramids_as_hexahedra=True,
                      progress=None, **options):
    """Recombines a tetrahedral FemMesh into a new hex-dominant FemMesh; returns (femmesh, report).

    The input is not modified. Options are the engine's parameters (hexmerge.parameters()).
    regions: "auto" (from "Volume" mesh groups, else per solid of `shape`), "none", or a
    regions.Regions. pyramids_as_hexahedra: see PYRAMIDS_AS_HEXAHEDRA_DOC.
    """
    job = RecombineJob.prepare(femmesh, options, regions, shape,
                               pyramids_as_hexahedra=pyramids_as_hexahedra)
    job.run(progress)
    return job.finish()


# ---- defaults for CalculiX (issue 15, docs/fem-accuracy.md) -----------------------------------

# Engine options whose table default is not the accurate choice for CalculiX. CalculiX has no
# pyramid element: a pyramid goes out as a collapsed hexahedron, and one with a node on the
# boundary overstated the peak stress by up to 16 % where the tets were within 1 %.
CALCULIX_DEFAULTS = {"pyramid_placement": "no_boundary_node"}


def calculix_options(options=None):
    """The engine options for a mesh that CalculiX will solve: `options` (the user's choices,
    kept as given) over CALCULIX_DEFAULTS."""
    return dict(CALCULIX_DEFAULTS, **(options or {}))


# ---- the engine's result, read in one place ------------------------------------------------

def result_blocks(result):
    """[(cell name, VTK-ordered cells)], [regions per block] (or None) and the index into the
    input points of each output point, from hexmerge.recombine()'s (MixedMesh, report)."""
    mesh = result[0]
    blocks, regs = [], []
    for block in mesh.cell_blocks():
        blocks.append((block.type, np.asarray(block.data, dtype=np.int64)))
        if mesh.regions is not None:
            regs.append(np.asarray(mesh.regions)[block.cells])
    index = None if mesh.point_map is None else np.asarray(mesh.point_map, dtype=np.int64)
    return blocks, (regs if mesh.regions is not None else None), index


def result_report(result):
    return result[1]
