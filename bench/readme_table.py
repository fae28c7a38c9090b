"""Prints the README's benchmark table from run_bench.py result files.

  /usr/bin/python3.11 bench/readme_table.py bench/results/A.json [B.json ...]
"""

import json
import sys


def main():
    print("| mesh | tets | total s | candidates s | pruning s | selection s | peak MB (B/tet) | hex vol % "
          "| prism vol % | reduction % | non-conf. quads | cracks | min SJ made | vol. diff |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for path in sys.argv[1:]:
        for r in json.load(open(path))["results"]:
            phases = r["phase_seconds"]
            made = [v for t, v in r["min_scaled_jacobian_per_type"].items()
                    if t != "tet" and r["output_counts"].get(t, 0) > 0]
            check = r["check"]
            print(f"| {r['mesh'].removesuffix('.msh')} | {r['tets']:,} | {r['wall_seconds']:.2f} "
                  f"| {phases.get('candidates', 0):.2f} | {phases.get('pruning', 0):.2f} "
                  f"| {phases.get('selection', 0):.2f} "
                  f"| {r['peak_bytes'] / 2**20:.0f} ({r['bytes_per_tet']:.0f}) "
                  f"| {100 * r['volume_fraction']['hex']:.1f} "
                  f"| {100 * r['volume_fraction']['prism']:.1f} "
                  f"| {r['report']['element_reduction_percent']:.1f} "
                  f"| {check['nonconforming_quads']} | {check['cracks']} "
                  f"| {min(made) if made else float('nan'):.2f} "
                  f"| {check['relative_volume_difference']:.1e} |")


if __name__ == "__main__":
    main()
