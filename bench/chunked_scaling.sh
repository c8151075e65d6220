#!/usr/bin/env bash
# The out-of-core path on the synthetic city (`meshflow sample city`, exact normals) as the input
# grows at constant density (2, 5, 10, 20 M points; the site's side grows with the square root),
# whole process, measured with /usr/bin/time (wall time, peak resident memory) and with the run's
# own --json timing (Amdahl's serial fraction f from its phases); then 20 M points on 1 against
# 2 threads, finished once after stitching (--finish-after-stitch) and at the default voxel; then
# meshflow-mpi on 1, 2 and 4 ranks of this machine, one thread each (every rank's phases and peak
# memory from --json), with Amdahl's model for 8, 32 and 128 nodes from the phases of the 4-rank
# run (bench/amdahl_model.py). Markdown rows.
#   bench/chunked_scaling.sh [BUILD_DIR] [WORK_DIR] [MILLIONS...]   (WORK_DIR: ~1.5 GB scratch;
#   MILLIONS: the sizes, default "2 5 10 20"; the last one is the one the later tables use)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
work=${2:-$(mktemp -d)}
shift $(($# < 2 ? $# : 2))
sizes=("${@:-2 5 10 20}")
read -r -a sizes <<< "${sizes[*]}"
big=${sizes[-1]}
tool="$build/meshflow"
mkdir -p "$work"
trap 'rm -f "$work"/city_*.ply "$work"/mesh_*.ply' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
voxel=0.3
chunk=30

# Runs "$@" under /usr/bin/time; prints "seconds MiB".
measure() {
  /usr/bin/time -f "%e %M" -o "$work/time.txt" "$@" > "$work/out.txt" 2> "$work/err.txt"
  read -r s kb < "$work/time.txt"
  echo "$s $((kb / 1024))"
}
# A field of the --json document in $work/out.txt (a Python expression over d).
field() { /usr/bin/python3 -c "import json; d=json.load(open('$work/out.txt')); print($1)"; }
# "serial s / f / at most Nx" of the run's phases.
serial() { field "'%.1f s / %.3f / %.1fx' % (d['timing']['serial']['serial_s'], d['timing']['serial']['fraction'], d['timing']['serial']['max_speedup'])"; }

echo "| points | site | voxel | chunks | triangles | wall s | peak MiB | µs per point | serial s / f / max speedup |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|---|"
for m in "${sizes[@]}"; do
  n=$((m * 1000000))
  site=$(/usr/bin/python3 -c "print(round(300 * ($m / 20) ** 0.5))")
  "$tool" sample city --points $n --site "$site" --normals -o "$work/city_$m.ply" -q
  read -r s mib < <(measure "$tool" reconstruct "$work/city_$m.ply" -o "$work/mesh_$m.ply" \
    --chunk $chunk --voxel $voxel --json)
  us=$(/usr/bin/python3 -c "print(f'{$s * 1e6 / $n:.2f}')")
  echo "| ${m} M | ${site} m | $voxel m | $(field "d['chunks']") | $(field "d['mesh']['triangles']") | $s | $mib | $us | $(serial) |"
  [ "$m" = "$big" ] || rm -f "$work/city_$m.ply"
done
echo
echo "| ${big} M points, voxel $voxel m, one process | wall s | peak MiB | decide / partition / chunks / stitch / finish / write s | serial s / f / max speedup |"
echo "|---|---:|---:|---|---|"
phases() { field "' / '.join('%.1f' % p['wall_s'] for p in d['timing']['ranks'][0]['phases'])"; }
for threads in 1 2; do
  read -r s mib < <(measure "$tool" reconstruct "$work/city_$big.ply" -o "$work/mesh_t.ply" \
    --chunk $chunk --voxel $voxel --threads $threads --json)
  echo "| $threads thread(s) | $s | $mib | $(phases) | $(serial) |"
done
read -r s mib < <(measure "$tool" reconstruct "$work/city_$big.ply" -o "$work/mesh_f.ply" \
  --chunk $chunk --voxel $voxel --json --finish-after-stitch)
echo "| 2 threads, --finish-after-stitch (serial finish) | $s | $mib | $(phases) | $(serial) |"
read -r s mib < <(measure "$tool" reconstruct "$work/city_$big.ply" -o "$work/mesh_d.ply" \
  --chunk $chunk --json)
echo "| default voxel ($(field "'%.3f' % d['voxel']") m), 2 threads: $(field "d['mesh']['triangles']") triangles | $s | $mib | $(phases) | $(serial) |"

if [ -x "$build/meshflow-mpi" ] && command -v mpirun > /dev/null; then
  echo
  echo "| meshflow-mpi, ${big} M points, voxel $voxel m | wall s | peak MiB per rank | rank 0: $(echo decide setup partition join chunks exchange seams weld gather stitch finish write | sed 's/ / \/ /g') s | chunks per rank | serial s / f / max speedup |"
  echo "|---|---:|---|---|---|---|"
  for spec in "1 1" "2 1" "4 1"; do
    read -r ranks threads <<< "$spec"
    read -r s mib < <(measure mpirun --bind-to none -n "$ranks" "$build/meshflow-mpi" reconstruct \
      "$work/city_$big.ply" -o "$work/mesh_mpi.ply" --chunk $chunk --voxel $voxel \
      --threads "$threads" --json)
    peaks=$(field "', '.join('%.0f' % r['peak_rss_mib'] for r in d['timing']['ranks'])")
    per=$(field "', '.join(str(r['chunks']) for r in d['timing']['ranks'])")
    echo "| $ranks rank(s) × $threads thread(s) | $s | $peaks | $(phases) | $per | $(serial) |"
    cp "$work/out.txt" "$work/mpi_$ranks.json"
  done
  echo
  /usr/bin/python3 bench/amdahl_model.py "$work/mpi_4.json"
fi
