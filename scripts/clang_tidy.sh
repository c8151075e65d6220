#!/usr/bin/env bash
# clang-tidy over the library (runtime/, nodes/, graph/) with the checks .clang-tidy names;
# every warning is an error. Needs a build directory configured with
# -DCMAKE_EXPORT_COMPILE_COMMANDS=ON (default: build/). Takes ~5 min on 2 cores.
#   scripts/clang_tidy.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
if [ ! -f "$build/compile_commands.json" ]; then
  echo "clang_tidy: $build/compile_commands.json is missing (configure with" \
       "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON)" >&2
  exit 2
fi
# clang's own -Wbitwise-instead-of-logical is off: the branch-free code combines bools with & and
# | on purpose (a mispredicted && costs more there; GCC, which builds the project, has no such
# warning).
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
run-clang-tidy -p "$build" -quiet -j "$(nproc)" -extra-arg=-Wno-bitwise-instead-of-logical \
  "$PWD/(runtime|nodes|graph)/.*\.cpp" > "$log" 2>&1 || status=$?
grep -v -e ' warnings\? generated\.$' -e '^clang-tidy-14 ' "$log" || true  # findings only
echo "clang_tidy: exit $status"
exit "$status"
