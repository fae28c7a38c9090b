#!/usr/bin/env bash
# Runs the FreeCAD add-on's tests: headless suites with freecadcmd, then the GUI test under Xvfb.
# Prints "N passed, N failed" and exits non-zero on any failure.
#   tests/freecad/run.sh [--no-gui]
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
log="${HEXMERGE_TEST_LOG:-$(mktemp -d)/freecad-tests}"
mkdir -p "$(dirname "$log")"
passed=0; failed=0
# The add-on under test uses this checkout's engine (as tests/python's conftest does), not another
# `hexmerge` the interpreter may find first.
export PYTHONPATH="$root/src/python${PYTHONPATH:+:$PYTHONPATH}"

run_suite() {  # module, per-suite timeout (s)
  local out="$log.$1.txt"
  (cd "$here" && QT_QPA_PLATFORM=offscreen timeout "$2" freecadcmd -t "$1" -M "$root" -M "$here" >"$out" 2>&1)
  local rc=$?
  local ran fails
  ran=$(grep -Eo '^Ran [0-9]+ test' "$out" | grep -Eo '[0-9]+' | tail -1)
  fails=$(grep -Eo '^FAILED \((failures|errors)=[0-9]+(, (failures|errors)=[0-9]+)?' "$out" | grep -Eo '[0-9]+' | awk '{s += $1} END {print s + 0}')
  ran=${ran:-0}; fails=${fails:-0}
  if [[ $rc -ne 0 && $fails -eq 0 ]]; then fails=1; [[ $ran -eq 0 ]] && ran=1; fi  # crash or timeout
  passed=$((passed + ran - fails)); failed=$((failed + fails))
  echo "$1: $((ran - fails)) passed, $fails failed (exit $rc; log $out)"
  grep -E '^(FAIL|ERROR):' "$out" || true
}

run_suite test_femmesh_arrays 120
run_suite test_addon 480
run_suite test_mesh_regions 240
run_suite test_modules 240
run_suite test_fem_accuracy 600
if [[ "${1:-}" != "--no-gui" ]]; then
  out="$log.gui.txt"
  # PYTHONFAULTHANDLER: a crash of FreeCAD prints the Python stack of every thread in the log.
  (cd "$here" && PYTHONFAULTHANDLER=1 QTWEBENGINE_DISABLE_SANDBOX=1 timeout 300 \
     xvfb-run -a -s "-screen 0 1600x1000x24" freecad "$here/gui_test.py" -M "$root" >"$out" 2>&1)
  if grep -q "^GUI TEST PASSED" "$out"; then passed=$((passed + 1)); echo "gui: passed";
  else failed=$((failed + 1)); echo "gui: FAILED (log $out)"; grep -E "GUI TEST|Error" "$out" | head -20
    grep -A12 "^Fatal Python error" "$out" | head -14 || true; fi
fi
echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
