#!/usr/bin/env bash
# meshflow-mpi on 1, 2, 3 and 4 ranks of this machine gives the same meshes, byte for byte, as
# meshflow in one process: `reconstruct --chunk` on a cloud with normals and on one without
# (normals estimated and oriented per chunk, then made to agree across seams), and `run` per
# frame on the synthetic sequence; `reconstruct --json` reports every rank's phases.
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
  for n in 1 2 3 4; do
    mpirun --bind-to none -n $n "$meshflow_mpi" reconstruct "$work/$cloud.ply" -o "$work/ranks_$n.ply" \
      "${args[@]}" > "$work/log_$n.txt"
    cmp "$work/one_process.ply" "$work/ranks_$n.ply" || {
      echo "FAIL: $cloud: $n ranks give another mesh than one process"; cat "$work/log_$n.txt"; exit 1; }
    echo "$cloud, $n ranks: $(grep '^mesh' "$work/log_$n.txt")"
  done
done
# --json (the mesh as without it): every rank's phases in order, the chunks they meshed adding
# up to all, and the serial fraction those phases imply; --tiles (each rank its own chunks'
# tiles and their levels, rank 0 the index): the tiles of one process, on 1 and 2 ranks.
mpirun --bind-to none -n 2 "$meshflow_mpi" reconstruct "$work/normals.ply" -o "$work/json_2.ply" \
  "${args[@]}" --json --tiles "$work/tiles_2" > "$work/json_2.txt"
mpirun --bind-to none -n 1 "$meshflow_mpi" reconstruct "$work/normals.ply" -o "$work/tiled_1.ply" \
  "${args[@]}" --tiles "$work/tiles_rank_1" > "$work/log_tiles_1.txt"
"$meshflow" reconstruct "$work/normals.ply" -o "$work/one_process.ply" "${args[@]}" -q \
  --tiles "$work/tiles_1"
cmp "$work/one_process.ply" "$work/json_2.ply" || { echo "FAIL: --json changed the mesh"; exit 1; }
cmp "$work/one_process.ply" "$work/tiled_1.ply" || { echo "FAIL: --tiles changed the mesh"; exit 1; }
for n in rank_1 2; do
  diff -r "$work/tiles_1" "$work/tiles_$n" || { echo "FAIL: tiles_$n: other tiles"; exit 1; }
done
compgen -G "$work/tiles_1/*_lod0.glb" > /dev/null || { echo "FAIL: no coarser levels"; exit 1; }
echo "--tiles, 1 and 2 ranks: $(ls "$work/tiles_2" | wc -l) files ($(ls "$work/tiles_2" | grep -c _lod) levels), as one process's"
# Not streamed (--finish-after-stitch: rank 0 gathers the parts and finishes the whole mesh):
# rank 0 cuts the tiles and sends each rank those of the chunks it meshed, every rank writes its
# own, rank 0 the index; the tiles of one process on 1, 2 and 4 ranks, and on 2 ranks rank 1
# wrote tiles ("tiles", its work > 0) while rank 0 scattered them and wrote the index.
"$meshflow" reconstruct "$work/normals.ply" -o "$work/stitched_one.ply" "${args[@]}" -q \
  --finish-after-stitch --tiles "$work/stitched_tiles_one"
for n in 1 2 4; do
  mpirun --bind-to none -n $n "$meshflow_mpi" reconstruct "$work/normals.ply" \
    -o "$work/stitched_$n.ply" "${args[@]}" --finish-after-stitch --json \
    --tiles "$work/stitched_tiles_$n" > "$work/stitched_$n.txt"
  cmp "$work/stitched_one.ply" "$work/stitched_$n.ply" || {
    echo "FAIL: not streamed, $n ranks: another mesh"; cat "$work/stitched_$n.txt"; exit 1; }
  diff -r "$work/stitched_tiles_one" "$work/stitched_tiles_$n" || {
    echo "FAIL: not streamed, $n ranks: other tiles"; exit 1; }
done
compgen -G "$work/stitched_tiles_one/*_lod0.glb" > /dev/null || { echo "FAIL: not streamed: no coarser levels"; exit 1; }
/usr/bin/python3 - "$work/stitched_2.txt" <<'PY'
import json, sys
ranks = json.load(open(sys.argv[1]))["timing"]["ranks"]
names = [[p["phase"] for p in r["phases"]] for r in ranks]
assert names[0][-4:] == ["write", "scatter", "tiles", "index"], names[0]
assert names[1][-2:] == ["finish", "tiles"], names[1]
tiles = [p for p in ranks[1]["phases"] if p["phase"] == "tiles"]
assert len(tiles) == 1 and tiles[0]["work_s"] > 0 and not tiles[0]["serial"], ranks[1]
PY
echo "--tiles, not streamed, 1, 2 and 4 ranks: $(ls "$work/stitched_tiles_2" | wc -l) files, as one process's, each rank its own chunks'"
/usr/bin/python3 - "$work/json_2.txt" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
ranks = d["timing"]["ranks"]
assert [r["rank"] for r in ranks] == [0, 1], ranks
assert sum(r["chunks"] for r in ranks) == d["chunks"], (ranks, d["chunks"])
names = [[p["phase"] for p in r["phases"]] for r in ranks]
# Every rank welds and writes its own parts into the file ("write", parallel: each chunk read
# back from its spill, welded and written, a few at once); rank 0 gathers only the seams'
# neighbourhoods and finishes them; then every rank writes its own chunks' tiles from the
# file's finished rows ("tiles", parallel) and rank 0 joins their records ("index").
assert names[0] == ["decide", "setup", "partition", "join", "chunks", "exchange", "seams",
                    "create", "write", "gather", "finish", "tiles", "index"], names[0]
assert names[1] == ["decide", "setup", "partition", "plan", "chunks", "exchange", "seams",
                    "create", "write", "finish", "tiles"], names[1]
assert all(p["work_s"] == 0 for p in ranks[1]["phases"]
           if p["phase"] in ("setup", "plan", "exchange", "seams", "create", "finish"))
for phase in ("write", "tiles"):
  assert [p["work_s"] > 0 for p in ranks[1]["phases"] if p["phase"] == phase] == [True], ranks[1]
assert not [p for p in ranks[0]["phases"] if p["phase"] == "tiles" and p["serial"]], ranks[0]
assert not any(p["serial"] for p in ranks[1]["phases"]), "only rank 0's phases are serial"
s = d["timing"]["serial"]
assert 0 < s["fraction"] < 1 and s["max_speedup"] > 1, s
print(f"--json, 2 ranks: serial {s['serial_s']:.2f} s of {s['serial_s'] + s['parallel_work_s']:.2f} s, "
      f"f = {s['fraction']:.3f}")
PY
# The defaults (automatic voxel and method, decided once from the whole input; every rank reads
# its own byte range of the binary PLY): `--chunk` in one process and over 1 and 2 ranks give
# the same file, with the whole cloud's triangle count when the stitched mesh is finished once
# (--finish-after-stitch; input normals: without them chunks orient their own estimates; the
# holes step may pick another diagonal, not another count); `--chunk auto` is taken by both.
# (Finished per chunk, the default, the mesh differs from the whole cloud's only near seams:
# tests/graph/test_chunked_reconstruction.cpp; the runs above compare it across ranks.)
"$meshflow" sample city --site 60 --points 60000 --normals -o "$work/defaults.ply" -q
triangles() { /usr/bin/python3 -c 'import json,sys; print(json.load(sys.stdin)["mesh"]["triangles"])'; }
whole=$("$meshflow" reconstruct "$work/defaults.ply" -o "$work/whole.ply" --threads 1 --json | triangles)
"$meshflow" reconstruct "$work/defaults.ply" -o "$work/chunked.ply" --chunk 12 --threads 1 \
  --chunk-dir "$work" --finish-after-stitch -q
for n in 1 2; do
  mpirun --bind-to none -n $n "$meshflow_mpi" reconstruct "$work/defaults.ply" \
    -o "$work/defaults_$n.ply" --chunk 12 --threads 1 --chunk-dir "$work" --finish-after-stitch \
    > "$work/dlog_$n.txt"
  cmp "$work/chunked.ply" "$work/defaults_$n.ply" || {
    echo "FAIL: defaults: $n ranks give another mesh than --chunk in one process"; cat "$work/dlog_$n.txt"; exit 1; }
  got=$(sed -n 's/^mesh *[0-9]* vertices, \([0-9]*\) triangles.*/\1/p' "$work/dlog_$n.txt")
  [ "$got" = "$whole" ] || { echo "FAIL: defaults: $n ranks: $got triangles, the whole cloud $whole"; exit 1; }
  echo "defaults, $n ranks: $got triangles, as the whole cloud in one process"
done
"$meshflow" reconstruct "$work/defaults.ply" -o "$work/auto.ply" --chunk auto --threads 1 \
  --chunk-dir "$work" -q
mpirun --bind-to none -n 2 "$meshflow_mpi" reconstruct "$work/defaults.ply" -o "$work/auto_2.ply" \
  --chunk auto --threads 1 --chunk-dir "$work" > "$work/alog.txt"
cmp "$work/auto.ply" "$work/auto_2.ply" || { echo "FAIL: --chunk auto over 2 ranks"; cat "$work/alog.txt"; exit 1; }
echo "--chunk auto, 2 ranks: $(grep '^mesh' "$work/alog.txt")"
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
echo "1-4 ranks: the same meshes as one process (chunked, with and without normals; per frame)"
