#!/usr/bin/env bash
# The bug hunt kept in the suite (issue 14), run by scripts/test.sh after the other tests:
#  1. builds the core library, the C++ tests and the engine fuzzer with clang, AddressSanitizer +
#     UndefinedBehaviorSanitizer and -D_GLIBCXX_ASSERTIONS (the checked standard library that
#     Fedora, RHEL and Arch build packages with) into its own folder, build-asan, and runs the C++
#     tests there;
#  2. fuzzes the engine (tests/fuzz/fuzz_recombine.cpp, sanitized) for HEXMERGE_FUZZ_SECONDS
#     (default 60) on the seed corpus tests/fuzz/corpus;
#  3. fuzzes the readers and the CLI (tests/fuzz/fuzz_readers.py, the regular build's module) for
#     HEXMERGE_FUZZ_READER_SECONDS (default 30).
# The seed is the day's date unless HEXMERGE_FUZZ_SEED is set, so each day explores new cases
# and every failure prints the command that repeats it.
#   scripts/fuzz.sh                 after build_hexmerge (scripts/common.sh) has built the module
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ASAN_BUILD="${HEXMERGE_ASAN_BUILD:-$HEXMERGE_ROOT/build-asan}"
SEED="${HEXMERGE_FUZZ_SEED:-$(date -u +%Y%m%d)}"
SANITIZE="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
ensure_packages "${HEXMERGE_FUZZ_PACKAGES[@]}"

echo "== sanitized build (ASan + UBSan + _GLIBCXX_ASSERTIONS) into $ASAN_BUILD"
# Only what the fuzzing needs: no Python module, no OpenCASCADE layer, no benchmarks.
cmake -S "$HEXMERGE_ROOT" -B "$ASAN_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g $SANITIZE -D_GLIBCXX_ASSERTIONS" \
      -DCMAKE_EXE_LINKER_FLAGS="$SANITIZE" \
      -DHEXMERGE_WITH_PYTHON=OFF -DHEXMERGE_WITH_OCC=OFF >/dev/null
cmake --build "$ASAN_BUILD" -j"$(nproc)" --target hexmerge_tests hexmerge_fuzz

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
status=0
echo "== C++ tests, sanitized"
"$ASAN_BUILD/tests/hexmerge_tests" --gtest_brief=1 || status=1
echo "== engine fuzzing, sanitized (seed $SEED)"
"$ASAN_BUILD/tests/hexmerge_fuzz" "$HEXMERGE_ROOT/tests/fuzz/corpus" \
  --seconds "${HEXMERGE_FUZZ_SECONDS:-60}" --seed "$SEED" || status=1
echo "== reader and CLI fuzzing (seed $SEED)"
"$HEXMERGE_PYTHON" "$HEXMERGE_ROOT/tests/fuzz/fuzz_readers.py" \
  --seconds "${HEXMERGE_FUZZ_READER_SECONDS:-30}" --seed "$SEED" || status=1
exit $status
