"""The experiment behind the engine's default acceptance thresholds: merge rate against quality.

For every combination of min_dihedral_angle, max_face_angle and min_scaled_jacobian given, on
every mesh given, runs hexmerge.recombine with otherwise default options and the independent
checker, and prints one Markdown row per run: element reduction, hex and prism volume, the
minimum scaled Jacobian of the elements made, the relative volume difference the checker sees
(bilinear quad faces against the tets' triangles: it measures how far quads are from flat), and
the time.

  /usr/bin/python3.11 bench/sweep_defaults.py bench/meshes/box-delaunay-100k.msh ...
      [--dihedral 170,160,150,140] [--boundary 175,178] [--face 135,150,160,170]
      [--sj 0.2,0.3,0.5]
"""

import argparse
import itertools
import os
import sys
import time

import meshio
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src", "python"))
import hexmerge  # noqa: E402


def floats(text):
    return [float(x) for x in text.split(",")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--dihedral", type=floats, default=[170, 160, 150, 140, 130])
    parser.add_argument("--face", type=floats, default=[160])
    parser.add_argument("--sj", type=floats, default=[0.3])
    parser.add_argument("--boundary", type=floats, default=[179],
                        help="min_boundary_dihedral_angle values")
    args = parser.parse_args()
    print("| mesh | dangle | boundary | fangle | min SJ | reduction % | hex vol % | prism vol % "
          "| min SJ made | vol. diff | s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for path in args.meshes:
        m = meshio.read(path)
        tets = np.vstack([c.data for c in m.cells if c.type == "tetra"])
        for dangle, boundary, fangle, sj in itertools.product(args.dihedral, args.boundary,
                                                              args.face, args.sj):
            start = time.perf_counter()
            mesh, report = hexmerge.recombine(m.points, tets, min_dihedral_angle=dangle,
                                              min_boundary_dihedral_angle=boundary,
                                              max_face_angle=fangle, min_scaled_jacobian=sj)
            seconds = time.perf_counter() - start
            check = hexmerge.check(mesh, m.points, tets)
            made = [report["min_scaled_jacobian"][t] for t in ("hex", "prism", "pyramid")
                    if report["output_counts"][t] > 0]
            print(f"| {os.path.basename(path)} | {dangle:g} | {boundary:g} | {fangle:g} | {sj:g} "
                  f"| {report['element_reduction_percent']:.1f} "
                  f"| {100 * report['volume_fraction']['hex']:.1f} "
                  f"| {100 * report['volume_fraction']['prism']:.1f} "
                  f"| {min(made) if made else float('nan'):.2f} "
                  f"| {check['relative_volume_difference']:.1e} | {seconds:.2f} |", flush=True)


if __name__ == "__main__":
    main()
