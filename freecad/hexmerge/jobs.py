# SPDX-License-Identifier: LGPL-2.1-or-later
"""Jobs that make a hex-dominant FemMesh, with no GUI (the role of FEM's femmesh/gmshtools.py).

A run has three steps so that a GUI can keep the middle one off its thread:
    job = RecombineJob.prepare(femmesh, ...)   # FreeCAD thread: FemMesh -> arrays, regions
    job.run(progress)                          # any thread: numpy and the engine only
    femmesh, report = job.finish()             # FreeCAD thread: arrays -> new FemMesh
ShapeJob does the same for a solid (mesher, then engine). recombine_femmesh() chains them.
"""

import time

import numpy as np

from . import engine
from . import femmesh_arrays
from . import regions as regions_mod
from . import results


def addon_report(input_cells, regions, region_count, group_names, pyramids_as_hexahedra,
                 femmesh, seconds, warnings=()):
    """The report's "freecad" part: what the add-on did around the engine."""
    return {
        "input_cells": input_cells,
        "warnings": list(warnings),
        "regions": regions,
        "region_count": region_count,
        "material_groups": sorted((group_names or {}).values()),
        "pyramids_as_collapsed_hexahedra": bool(pyramids_as_hexahedra),
        "femmesh_volumes": femmesh.VolumeCount,
        "seconds": seconds,
    }


def changed_nodes(mesh, point_ids, point_index, blocks):
    """The nodes of an engine result whose post-merge stage (same_nodes off) changed nodes:
    (points, point_ids, blocks). Positions are the engine's (a moved node at its new place, not
    the source's), a node past the source's gets an id after the largest, and a changed node
    that no cell uses (contracted away) is left out; the other ids stay the source's."""
    points = np.asarray(mesh.points, dtype=np.float64)
    known = point_ids if point_index is None else point_ids[point_index]
    ids = np.empty(len(points), dtype=np.int64)
    ids[:len(known)] = known
    first = int(point_ids.max()) + 1 if len(point_ids) else 1
    ids[len(known):] = np.arange(first, first + len(points) - len(known))
    keep = np.ones(len(points), dtype=bool)
    keep[np.asarray(mesh.changed_nodes, dtype=np.int64)] = False
    for _, cells in blocks:
        keep[cells.reshape(-1)] = True
    if keep.all():
        return points, ids, blocks
    new_id = np.cumsum(keep) - 1
    return points[keep], ids[keep], [(name, new_id[cells]) for name, cells in blocks]


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
        job = cls(arrays, name, tets, regions, engine.typed_options(options or {}),
                  pyramids_as_hexahedra)
        job.seconds = {"read FemMesh": read, "regions": time.perf_counter() - t}
        return job

    def run(self, progress=None):
        """Runs the engine. progress(phase, fraction) -> False cancels (raises Cancelled)."""
        hexmerge = engine.module()
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
            raise engine.Cancelled(str(e) or "cancelled") from e
        self.seconds["engine"] = time.perf_counter() - t

    def finish(self):
        """The new FemMesh and the report (the engine's, plus what the add-on did)."""
        t = time.perf_counter()
        blocks, block_regions, point_index = results.result_blocks(self.result)
        points, point_ids = self.arrays.points, self.arrays.point_ids
        changed = self.result[0].changed_nodes
        if changed is not None and len(changed):
            points, point_ids, blocks = changed_nodes(self.result[0], point_ids, point_index,
                                                      blocks)
        elif point_index is not None:
            points, point_ids = points[point_index], point_ids[point_index]
        names = self.regions.names if self.regions is not None else None
        femmesh, _ = femmesh_arrays.arrays_to_femmesh(
            points, point_ids, blocks, block_regions, names, self.pyramids_as_hexahedra)
        self.seconds["write FemMesh"] = time.perf_counter() - t

        report = dict(self.result[1])
        report["freecad"] = addon_report(
            self.cell_name, self.regions.source if self.regions is not None else "none",
            self.regions.count if self.regions is not None else 0, names,
            self.pyramids_as_hexahedra, femmesh, self.seconds)
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
        self.warnings = []

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
        box = shape.BoundBox
        thinnest = min(box.XLength, box.YLength, box.ZLength)
        warnings = []
        if size > thinnest:
            warnings.append(
                "the target size {:g} mm is larger than the thinnest side of the shape's "
                "bounding box ({:g} mm): "
                "the mesh has fewer than one element across it; a size of {:.2g} mm or less "
                "follows the shape".format(size, thinnest, thinnest / 2))
        t = time.perf_counter()
        brep = shape.exportBrepToString()
        job = cls(brep, len(solids), dict(mesher, size=size), engine.typed_options(options or {}),
                  dict(material_names or {}), pyramids_as_hexahedra)
        job.seconds = {"export shape": time.perf_counter() - t}
        job.warnings = warnings
        return job

    def run(self, progress=None):
        """Meshes and recombines. progress(phase, fraction) -> False cancels (raises Cancelled)."""
        hexmerge = engine.module()
        t = time.perf_counter()
        kwargs = dict(self.mesher)
        kwargs.update(self.options)
        size = kwargs.pop("size")
        try:
            self.result = hexmerge.mesh_shape(self.brep, size, progress=progress, **kwargs)
        except hexmerge.Cancelled as e:
            raise engine.Cancelled(str(e) or "cancelled") from e
        self.seconds["mesh and recombine"] = time.perf_counter() - t

    def finish(self):
        """The new FemMesh and the report (the engine's with the mesher's under "meshing", plus
        what the add-on did)."""
        t = time.perf_counter()
        mesh = self.result[0]
        blocks, block_regions, _ = results.result_blocks(self.result)
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
        report = dict(self.result[1])
        # What the command line notes (the ways TetGen failed on, faces left coarse, the CAD's
        # corners and edges too sharp for usable elements, ...): in the console and the report.
        for note in engine.module().mesh_notes(report["meshing"]):
            if note not in self.warnings:
                self.warnings.append(note)
        report["freecad"] = addon_report(
            "shape", ("solids of the shape ({} solids, mesher)".format(self.nb_solids)
                      if block_regions is not None else "none"),
            count if block_regions is not None else 0, names, self.pyramids_as_hexahedra,
            femmesh, self.seconds, self.warnings)
        return femmesh, report


def recombine_femmesh(femmesh, regions="auto", shape=None, pyramids_as_hexahedra=True,
                      progress=None, **options):
    """Recombines a tetrahedral FemMesh into a new hex-dominant FemMesh; returns (femmesh, report).

    The input is not modified. Options are the engine's parameters (hexmerge.parameters()).
    regions: "auto" (from "Volume" mesh groups, else per solid of `shape`), "none", or a
    regions.Regions. pyramids_as_hexahedra: see engine.PYRAMIDS_AS_HEXAHEDRA_DOC.
    """
    job = RecombineJob.prepare(femmesh, options, regions, shape,
                               pyramids_as_hexahedra=pyramids_as_hexahedra)
    job.run(progress)
    return job.finish()
