#!/usr/bin/env bash
# Whole-process timings of the meshflow CLI with hyperfine (Debian package `hyperfine`): start-up
# (--help, against an empty C++ program and an empty one linked with the same shared libraries
# as meshflow, the floor the dynamic loader sets) and file-to-mesh runs on a built-in object
# and, when the shared data are there, kurt3d scan000 at 5 cm.
# Usage: scripts/startup_time.sh [path/to/meshflow]   (default build/meshflow)
set -euo pipefail
cd "$(dirname "$0")/.."
MESHFLOW=${1:-build/meshflow}
DATA=${MESHFLOW_DATA:-../shared/data}
if ! command -v hyperfine > /dev/null; then
  echo "startup_time: hyperfine is not installed (apt-get install hyperfine)" >&2
  exit 2
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
echo 'int main() { return 0; }' > "$WORK/empty.cpp"
c++ -O2 "$WORK/empty.cpp" -o "$WORK/empty"
# The shared libraries meshflow loads (ldd), linked into the empty program.
mapfile -t libs < <(ldd "$MESHFLOW" | awk '$3 ~ /^\// {print $3}')
c++ -O2 "$WORK/empty.cpp" -o "$WORK/same_libraries" -Wl,--no-as-needed "${libs[@]}"
"$MESHFLOW" sample torus -q -o "$WORK/torus.ply"
runs=(-N -w 3 -r 30 "$WORK/empty" "$WORK/same_libraries" "$MESHFLOW --help")
hyperfine "${runs[@]}" --export-markdown "$WORK/startup.md" > /dev/null
cat "$WORK/startup.md"
echo
meshing=(-w 2 -r 10 "$MESHFLOW reconstruct $WORK/torus.ply -o $WORK/torus_mesh.ply -q")
if [ -f "$DATA/kurt3d/scan000.3d" ]; then
  meshing+=("$MESHFLOW reconstruct $DATA/kurt3d/scan000.3d -o $WORK/kurt3d.ply --voxel 0.05 -q")
fi
hyperfine "${meshing[@]}" --export-markdown "$WORK/meshing.md" > /dev/null
cat "$WORK/meshing.md"
