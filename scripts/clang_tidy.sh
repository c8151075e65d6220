#!/usr/bin/env bash
# clang-tidy over the library (runtime/, nodes/, graph/) with the checks .clang-tidy names;
# every warning is an error. Needs a build directory configured with
# -DCMAKE_EXPORT_COMPILE_COMMANDS=ON (default: build/).
#   scripts/clang_tidy.sh [BUILD_DIR]
# In a unity build (CMAKE_UNITY_BUILD=ON, as .ci/run's sanitizer build) it checks the library's
# unity units, each of which includes about eight of its .cpp files, so the heavy headers (Eigen,
# oneTBB, CGAL) are parsed once per unit instead of once per file: 95 s instead of 380 s on 2
# cores, with the same findings (the included .cpp files match HeaderFilterRegex). Otherwise it
# checks every .cpp file.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
if [ ! -f "$build/compile_commands.json" ]; then
  echo "clang_tidy: $build/compile_commands.json is missing (configure with" \
       "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON)" >&2
  exit 2
fi
# clang's own -Wbitwise-instead-of-logical is off: the branch-free code combines bools with & and
# | on purpose (a mispredicted && costs more there).
args=(-quiet -j "$(nproc)" -extra-arg=-Wno-bitwise-instead-of-logical)
# clang-tidy reads .clang-tidy from the checked file's directory upwards: a build directory
# outside the repository gets the configuration explicitly.
case "$build/" in "$PWD"/*) ;; *) args+=(-config="$(cat .clang-tidy)") ;; esac
if compgen -G "$build/CMakeFiles/meshflow_nodes.dir/Unity/*.cxx" > /dev/null; then
  files="$build/CMakeFiles/meshflow_(runtime|nodes|nodes_cgal|graph)\.dir/Unity/.*\.cxx"
  # Unity units include .cpp files by design; the sources must not (checked here instead).
  args+=(-checks=-bugprone-suspicious-include)
  if grep -rnE '^#include "[^"]*\.cpp"' runtime nodes graph tools; then
    echo "clang_tidy: a source includes a .cpp file" >&2
    exit 1
  fi
else
  files="$PWD/(runtime|nodes|graph)/.*\.cpp"
fi
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
run-clang-tidy -p "$build" "${args[@]}" "$files" > "$log" 2>&1 || status=$?
# Findings only (not the commands run-clang-tidy echoes, with the configuration they carry).
grep -E -A3 '(error|warning): ' "$log" || true
echo "clang_tidy: exit $status"
exit "$status"
