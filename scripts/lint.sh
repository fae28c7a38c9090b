#!/usr/bin/env bash
# The lint step of scripts/test.sh: pyflakes over the Python sources and clang-format
# (the repository's .clang-format) over the C++ sources, both without changing any file.
# Exit status 1 when either finds something. To reformat the C++ sources:
#   git ls-files '*.cpp' '*.h' | xargs clang-format -i
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root" || exit 1
status=0
echo "-- pyflakes3 src/python freecad bench tests scripts"
mapfile -t python_files < <(git ls-files 'src/python/*.py' 'freecad/*.py' 'bench/*.py' 'tests/*.py' 'scripts/*.py')
pyflakes3 "${python_files[@]}" || status=1
echo "-- clang-format --dry-run -Werror (C++ sources)"
mapfile -t cpp_files < <(git ls-files '*.cpp' '*.h')
clang-format --dry-run -Werror "${cpp_files[@]}" || status=1
exit $status
