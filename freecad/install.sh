#!/usr/bin/env bash
# Installs what the HexMerge FreeCAD add-on needs (Debian 12) and links this checkout into
# FreeCAD's user Mod folder, so a rebuild of the engine module is picked up. Idempotent.
#   freecad/install.sh            apt packages + link
#   freecad/install.sh --no-apt   link only
#   HEXMERGE_TEST_DEPS=1 ...      also what the tests need (scripts/common.sh's HEXMERGE_TEST_PACKAGES)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if [[ "${1:-}" != "--no-apt" ]]; then
  # One package list for every script: scripts/common.sh.
  source "$root/scripts/common.sh"
  pkgs=("${HEXMERGE_BASE_PACKAGES[@]}" "${HEXMERGE_FREECAD_PACKAGES[@]}")
  if [[ "${HEXMERGE_TEST_DEPS:-0}" == 1 ]]; then
    pkgs+=("${HEXMERGE_TEST_PACKAGES[@]}")
  fi
  ensure_packages "${pkgs[@]}"
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
