# Shared by scripts/example.sh, scripts/test.sh, scripts/fuzz.sh and freecad/install.sh: the one
# list of Debian packages, and the build.
# Sourced, not run. Idempotent: packages already installed are not touched; the build is
# incremental.

HEXMERGE_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
HEXMERGE_BUILD="${HEXMERGE_BUILD:-$HEXMERGE_ROOT/build}"
# FreeCAD's interpreter: the module is built for it (the first python3 on PATH may be another).
HEXMERGE_PYTHON=/usr/bin/python3.11

# The packages every use needs: compiler, CMake, pybind11, numpy, meshio (mesh files), Gmsh and
# TetGen (test meshes; TetGen is also the CAD mesher's tetrahedraliser), GoogleTest, OpenCASCADE
# (src/occ: the mesher from CAD and regions by solid; STEP and IGES need
# libocct-data-exchange-dev; Debian 12 ships one header OCCT needs in libocct-visualization-dev,
# and OCCT's CMake targets link libtbb-dev's files), GLPK (the optimality bound), CGAL (the
# facets TetGen gets triangulated, src/tetgen).
HEXMERGE_BASE_PACKAGES=(g++ cmake make pybind11-dev python3-dev python3-numpy python3-meshio
                        gmsh tetgen libgtest-dev
                        libocct-foundation-dev libocct-modeling-data-dev
                        libocct-modeling-algorithms-dev libocct-data-exchange-dev
                        libocct-visualization-dev libtbb-dev libglpk-dev libcgal-dev)

# scripts/fuzz.sh: clang with its sanitizer runtimes (AddressSanitizer, UBSan).
HEXMERGE_FUZZ_PACKAGES=(clang)

# freecad/install.sh: FreeCAD and CalculiX for the add-on (with the base packages, which build
# the engine module it imports).
HEXMERGE_FREECAD_PACKAGES=(freecad calculix-ccx)

# scripts/test.sh: pytest, the lint step (pyflakes, clang-format), and what tests/freecad/run.sh
# needs (Xvfb and ImageMagick for the GUI test, Netgen for a test mesh).
HEXMERGE_TEST_PACKAGES=(python3-pytest python3-pytest-xdist pyflakes3 clang-format xvfb xauth imagemagick python3-netgen)

# Installs the Debian packages given that are not installed yet (apt-get update first, once).
ensure_packages() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  local sudo=""
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  echo "== installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# Configures and builds everything (library, Python module, tests, CLI) into $HEXMERGE_BUILD,
# then puts `hexmerge` on the PATH and the package on the interpreter's path.
build_hexmerge() {
  echo "== building into $HEXMERGE_BUILD"
  cmake -S "$HEXMERGE_ROOT" -B "$HEXMERGE_BUILD" -DCMAKE_BUILD_TYPE=Release \
        -DPython_EXECUTABLE="$HEXMERGE_PYTHON" >/dev/null
  cmake --build "$HEXMERGE_BUILD" -j"$(nproc)"
  sh "$HEXMERGE_ROOT/src/python/install.sh"
}
