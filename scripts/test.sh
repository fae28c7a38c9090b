#!/usr/bin/env bash
# Installs everything the tests need (Debian 12: the build, pytest, FreeCAD, CalculiX, Xvfb),
# builds, and runs every test: the lint step (scripts/lint.sh), GoogleTest (ctest), pytest, the fuzzers on an ASan + UBSan build
# (scripts/fuzz.sh, about two minutes of fuzzing) and the FreeCAD add-on's tests (headless
# freecadcmd suites and a GUI test under Xvfb). Safe to run again.
#   scripts/test.sh            everything
#   scripts/test.sh --no-gui   without the FreeCAD GUI test
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ensure_packages "${HEXMERGE_BASE_PACKAGES[@]}" "${HEXMERGE_TEST_PACKAGES[@]}"
HEXMERGE_TEST_DEPS=1 bash "$HEXMERGE_ROOT/freecad/install.sh"
build_hexmerge

status=0
echo "== lint: pyflakes and clang-format (scripts/lint.sh)"
bash "$HEXMERGE_ROOT/scripts/lint.sh" || status=1
echo "== C++ tests (ctest)"
ctest --test-dir "$HEXMERGE_BUILD" --output-on-failure -j"$(nproc)" || status=1
echo "== Python tests (pytest, one worker per core; a file's tests on one worker)"
(cd "$HEXMERGE_ROOT" && "$HEXMERGE_PYTHON" -m pytest -q -W error --strict-markers \
  -n "$(nproc)" --dist loadfile tests/python) \
  || status=1
echo "== fuzzing, sanitized build (scripts/fuzz.sh)"
bash "$HEXMERGE_ROOT/scripts/fuzz.sh" || status=1
echo "== FreeCAD add-on tests"
bash "$HEXMERGE_ROOT/tests/freecad/run.sh" "$@" || status=1
exit $status
