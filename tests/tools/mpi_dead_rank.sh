#!/usr/bin/env bash
# A rank that dies during `meshflow-mpi reconstruct` (killed with SIGKILL while the ranks work)
# makes mpirun exit non-zero with a message naming the rank, and leaves no mesh under the
# output's name (the writer only renames a finished file into place).
# Usage: mpi_dead_rank.sh MESHFLOW MESHFLOW_MPI
set -euo pipefail
meshflow=$1
meshflow_mpi=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
"$meshflow" sample city --site 150 --points 1000000 --normals -o "$work/city.ply" -q
mpirun --bind-to none -n 2 "$meshflow_mpi" reconstruct "$work/city.ply" -o "$work/mesh.ply" \
  --chunk 8 --voxel 0.25 --threads 1 --chunk-dir "$work" > "$work/log.txt" 2>&1 &
runner=$!
# Rank 1 is the meshflow-mpi process whose environment says so; it dies half a second after
# it is found (well before the run ends: several seconds of meshing).
victim=""
for _ in $(seq 1 400); do
  for pid in $(pgrep -f "$meshflow_mpi reconstruct $work/city.ply" || true); do
    if tr '\0' '\n' < "/proc/$pid/environ" 2> /dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1'; then
      victim=$pid
    fi
  done
  [ -n "$victim" ] && break
  sleep 0.05
done
[ -n "$victim" ] || { echo "FAIL: rank 1 never started"; cat "$work/log.txt"; exit 1; }
sleep 0.5
kill -KILL "$victim"
status=0
wait "$runner" || status=$?
if [ "$status" -eq 0 ]; then
  echo "FAIL: mpirun exited 0 after rank 1 died"; cat "$work/log.txt"; exit 1
fi
grep -qi "rank 1\|signal 9\|killed" "$work/log.txt" || {
  echo "FAIL: no message about the dead rank"; cat "$work/log.txt"; exit 1; }
if [ -e "$work/mesh.ply" ]; then echo "FAIL: a mesh was left under the output's name"; exit 1; fi
echo "rank 1 killed: mpirun exited $status, no $work/mesh.ply; its message:"
grep -i "rank 1\|signal 9\|killed" "$work/log.txt" | head -3
