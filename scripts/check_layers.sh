#!/usr/bin/env bash
# Checks the include rules of docs/ARCHITECTURE.md on every source file of the library layers
# (runtime/ nodes/ graph/ options/ serve/): the rules and their check are in
# scripts/check_layers.cmake, which the build also runs (target meshflow_layers) before any
# library compiles. Prints each offending include and exits 1 if there is one.
set -euo pipefail
cd "$(dirname "$0")/.."
exec cmake -DSOURCE_DIR="$PWD" -P scripts/check_layers.cmake
