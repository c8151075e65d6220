#!/usr/bin/env bash
# meshflow-mpi on 1, 2 and 4 ranks of this machine gives the same meshes, byte for byte, as
# meshflow in one process: `reconstruct --chunk` on a cloud with normals and on one without
# (normals estimated and oriented per chunk, then made to agree across seams), and `run` per
# frame on the synthetic sequence.
# Usage: mpi_ranks.sh MESHFLOW MESHFLOW_MPI
set -euo pipefail
meshflow=$1
meshflow_mpi=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Root in containers and CI: Open MPI refuses to run as root unless told; 4 ranks on 2 cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
args=(--chunk 12 --voxel 0.5 --threads 1 --chunk-dir "$work")
for cloud in normals plain; do
  flags=()
  [ "$cloud" = normals ] && flags=(--normals)
  "$meshflow" sample city --site 120 --points 400000 "${flags[@]}" -o "$work/$cloud.ply" -q
  "$meshflow" reconstruct "$work/$cloud.ply" -o "$work/one_process.ply" "${args[@]}" -q
  for n in 1 2 4; do
    mpirun --bind-to none -n $n "$meshflow_mpi" reconstruct "$work/$cloud.ply" -o "$work/ranks_$n.ply" \
      "${args[@]}" > "$work/log_$n.txt"
    cmp "$work/one_process.ply" "$work/ranks_$n.ply" || {
      echo "FAIL: $cloud: $n ranks give another mesh than one process"; cat "$work/log_$n.txt"; exit 1; }
    echo "$cloud, $n ranks: $(grep '^mesh' "$work/log_$n.txt")"
  done
done
# Per-frame meshing of a sequence with its frames dealt to the ranks: the files `meshflow run`
# writes, byte for byte.
"$meshflow" run --synthetic --synthetic-frames 5 -o "$work/run_one" -q
for n in 1 2 4; do
  mpirun --bind-to none -n $n "$meshflow_mpi" run --synthetic --synthetic-frames 5 \
    -o "$work/run_$n" --threads 1 > "$work/run_log_$n.txt"
  for f in "$work"/run_one/*.ply; do
    cmp "$f" "$work/run_$n/$(basename "$f")" || {
      echo "FAIL: run on $n ranks: $(basename "$f") differs"; cat "$work/run_log_$n.txt"; exit 1; }
  done
  echo "run, $n ranks: $(grep '^frames' "$work/run_log_$n.txt")"
done
if ls "$work"/meshflow-chunks-* > /dev/null 2>&1; then echo "FAIL: chunk files left behind"; exit 1; fi
echo "1, 2 and 4 ranks: the same meshes as one process (chunked, with and without normals; per frame)"
