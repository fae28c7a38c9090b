# SPDX-License-Identifier: LGPL-2.1-or-later
"""The engine's result read in one place: its mesh as cell blocks, its report as the panel's
results table and as a one-line summary. Nothing here touches FreeCAD or Qt."""

import numpy as np

CELL_LABELS = ("tetrahedra", "pyramids", "prisms", "hexahedra")
# What the shorter row names of results_rows() mean (the panel's tooltips).
ROW_DOCS = {
    "quads on tets": "Quad faces against two triangles of tetrahedra (non-conforming faces left)",
    "min. Jacobian": "Smallest scaled Jacobian of any element (1: perfect, > 0: valid)",
    "boundary dist.": "Largest distance from the mesh's boundary to the shape",
    "hex volume": "Share of the volume in hexahedra",
    "prism volume": "Share of the volume in prisms",
    "regions": "Regions kept apart (materials, solids)",
}

_LABELS = {"tet": "tetrahedra", "tetra": "tetrahedra", "tetra10": "tetrahedra",
           "pyramid": "pyramids", "pyramid13": "pyramids", "prism": "prisms", "wedge": "prisms",
           "wedge15": "prisms", "hex": "hexahedra", "hexahedron": "hexahedra",
           "hexahedron20": "hexahedra"}


def cell_label(key):
    """"hexahedra" for "hex", "hexahedron20", ...; other keys unchanged."""
    return _LABELS.get(str(key).lower(), str(key))


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


def _by_label(value):
    if isinstance(value, (list, tuple)):
        value = dict(zip(CELL_LABELS, value))
    return {cell_label(k): v for k, v in (value or {}).items()}


def regions_text(freecad_report):
    """"Short text of the region count: "1", "3 groups", "2 solids" (report["freecad"])."""
    count = freecad_report.get("region_count", 0)
    source = str(freecad_report.get("regions"))
    if not count:
        return "1"
    if source.startswith("mesh groups"):
        return "{} groups".format(count)
    if source.startswith("solids"):
        return "{} solids".format(count)
    return str(count)


def results_rows(report):
    """(quantity, before, after) rows of the results table from an engine report."""
    counts = _by_label(report.get("output_counts"))
    before = report.get("input_tets", "")
    rows = [("tetrahedra", str(before), str(counts.get("tetrahedra", 0)))]
    for label in CELL_LABELS[1:]:
        rows.append((label, "0", str(counts.get(label, 0))))
    rows.append(("elements", str(before), str(report.get("output_cells", sum(counts.values())))))
    if "element_reduction_percent" in report:
        rows.append(("reduction", "", "{:.1f} %".format(report["element_reduction_percent"])))
    fractions = _by_label(report.get("volume_fraction"))
    for label in ("hexahedra", "prisms"):
        if label in fractions:
            rows.append(("{} volume".format(label[:-1] if label == "prisms" else "hex"), "",
                         "{:.1f} %".format(100 * fractions[label])))
    if "nonconforming_quads" in report:
        rows.append(("quads on tets", "", str(report["nonconforming_quads"])))
    mins = _by_label(report.get("min_scaled_jacobian"))
    present = [v for k, v in mins.items() if counts.get(k)]
    if present:
        rows.append(("min. Jacobian", "", "{:.3f}".format(min(present))))
    meshing = report.get("meshing")
    if meshing:
        rows.append(("target size", "", "{:g} mm".format(meshing["parameters"]["size"])))
        rows.append(("boundary dist.", "", "{:.2g} mm".format(meshing["max_boundary_distance"])))
        if meshing.get("shape_volume"):
            rows.append(("volume vs. shape", "", "{:+.2f} %".format(
                100 * (meshing["mesh_volume"] / meshing["shape_volume"] - 1))))
        rows.append(("meshing time", "", "{:.2f} s".format(meshing["seconds"])))
    fc = report.get("freecad", {})
    if fc:
        rows.append(("regions", "", regions_text(fc)))
    return rows


def summary(report):
    """"shape at h 250 mm: 512 hex (...)" -- one line for the object's Summary."""
    counts = report.get("output_counts") or report.get("counts") or {}
    before = report.get("input_tets") or report.get("input_cells")
    parts = []
    if isinstance(counts, dict):
        parts = ["{} {}".format(v, k) for k, v in counts.items() if v]
    red = report.get("element_reduction_percent")
    text = "{} tets -> {}".format(before, ", ".join(parts)) if before is not None else ", ".join(parts)
    meshing = report.get("meshing")
    if meshing:
        text = "shape at h {:g} mm: ".format(meshing["parameters"]["size"]) + text
    if red is not None:
        text += " ({:.1f} % fewer elements)".format(red)
    return text
