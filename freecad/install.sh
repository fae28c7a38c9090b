#!/usr/bin/env bash
# Installs what the HexMerge FreeCAD add-on needs (Debian 12) and links this checkout into
# FreeCAD's user Mod folder, so a rebuild of the engine module is picked up. Idempotent.
#   freecad/install.sh            apt packages + link
#   freecad/install.sh --no-apt   link only
#   HEXMERGE_TEST_DEPS=1 ...      also what tests/freecad/run.sh needs (Xvfb, ImageMagick, Netgen)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if [[ "${1:-}" != "--no-apt" ]]; then
  # The OpenCASCADE -dev packages build the engine's regions by solid (hexmerge.regions_by_solid);
  # Debian 12 puts one header they need in libocct-visualization-dev, and their CMake targets
  # link libtbb-dev's libraries. TetGen: the mesher of the shape mode (hexmerge.mesh_shape).
  pkgs=(freecad calculix-ccx gmsh tetgen python3-numpy
        libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
        libocct-visualization-dev libtbb-dev)
  if [[ "${HEXMERGE_TEST_DEPS:-0}" == 1 ]]; then
    pkgs+=(xvfb xauth imagemagick python3-netgen)
  fi
  missing=()
  for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    sudo=""; [[ $(id -u) -ne 0 ]] && sudo="sudo"
    $sudo apt-get update
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
  fi
fi

mod="${HOME}/.local/share/FreeCAD/Mod"
mkdir -p "$mod"
link="$mod/HexMerge"
if [[ -L "$link" || ! -e "$link" ]]; then
  ln -sfn "$root" "$link"
else
  echo "install.sh: $link exists and is not a link; leaving it alone" >&2
  exit 1
fi
echo "HexMerge add-on: $link -> $root"
if ! /usr/bin/python3.11 -c "import sys; sys.path.insert(0, '$root/src/python'); import hexmerge" 2>/dev/null; then
  echo "install.sh: the engine module is not built yet: build it for /usr/bin/python3.11 (README)" >&2
fi
