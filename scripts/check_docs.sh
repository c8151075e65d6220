#!/usr/bin/env bash
# Generates the API reference (Doxygen over runtime/, nodes/ and graph/ headers) into
# BUILD_DIR/docs and fails on an undocumented public function or a malformed documentation
# comment. Undocumented structs, fields and constants are counted, not failed: many are named
# by their type's comment. Needs doxygen. Run by `cmake --build build --target docs`.
#   scripts/check_docs.sh DOXYFILE OUTPUT_DIR
set -euo pipefail
doxyfile=$1
out=$2
mkdir -p "$out"
doxygen "$doxyfile"
log="$out/warnings.txt"
functions=$(grep -c '(function) of .* is not documented' "$log" || true)
errors=$(grep 'warning:' "$log" | grep -vc 'is not documented' || true)
others=$(grep -c 'is not documented' "$log" || true)
echo "check_docs: $out/html/index.html; undocumented: $functions functions (must be 0)," \
     "$((others - functions)) types, fields and constants; $errors other warnings (must be 0)"
if [ "$functions" -gt 0 ] || [ "$errors" -gt 0 ]; then
  grep -E '\(function\) of .* is not documented' "$log" || true
  grep 'warning:' "$log" | grep -v 'is not documented' || true
  exit 1
fi
