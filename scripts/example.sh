#!/usr/bin/env bash
# Installs what HexMerge needs (Debian 12), builds it, and recombines the bundled example: a
# Gmsh tetrahedral mesh of an L-bracket with a hole. Writes build/example/bracket-hexdom.vtu and
# a JSON report, then checks the result with the independent checker. Safe to run again.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ensure_packages "${HEXMERGE_BASE_PACKAGES[@]}"
build_hexmerge
out="$HEXMERGE_BUILD/example"
mkdir -p "$out"
echo "== hexmerge recombine resources/examples/bracket.msh"
hexmerge recombine "$HEXMERGE_ROOT/resources/examples/bracket.msh" -o "$out/bracket-hexdom.vtu" \
  --stats "$out/bracket-report.json"
echo "== hexmerge check"
hexmerge check "$out/bracket-hexdom.vtu" --source "$HEXMERGE_ROOT/resources/examples/bracket.msh"
echo "== done: $out/bracket-hexdom.vtu (open it in ParaView), report in $out/bracket-report.json"
