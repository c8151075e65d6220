#!/usr/bin/env bash
# Fresh Debian machine to a first mesh: installs the dependencies, builds Release into build/
# and runs `meshflow demo` (a synthetic scan that meshflow generates itself).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
./build/meshflow demo -o build/meshflow_demo.ply
