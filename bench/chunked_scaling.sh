#!/usr/bin/env bash
# The out-of-core path on the synthetic city (`meshflow sample city`, exact normals) as the input
# grows at constant density (2, 5, 10, 20 M points; the site's side grows with the square root),
# whole process, measured with /usr/bin/time (wall time, peak resident memory); then 20 M points
# at the default voxel; then meshflow-mpi on 1, 2 and 4 ranks of this machine. Markdown rows.
#   bench/chunked_scaling.sh [BUILD_DIR] [WORK_DIR]    (WORK_DIR: ~1.5 GB of scratch space)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
work=${2:-$(mktemp -d)}
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

echo "| points | site | voxel | chunks | triangles | wall s | peak MiB | us per point |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|"
for m in 2 5 10 20; do
  n=$((m * 1000000))
  site=$(python3 -c "print(round(300 * ($m / 20) ** 0.5))")
  "$tool" sample city --points $n --site "$site" --normals -o "$work/city_$m.ply" -q
  read -r s mib < <(measure "$tool" reconstruct "$work/city_$m.ply" -o "$work/mesh_$m.ply" \
    --chunk $chunk --voxel $voxel --json)
  chunks=$(python3 -c "import json; print(json.load(open('$work/out.txt'))['chunks'])")
  tris=$(python3 -c "import json; print(json.load(open('$work/out.txt'))['triangles'])")
  us=$(python3 -c "print(f'{$s * 1e6 / $n:.2f}')")
  echo "| ${m} M | ${site} m | $voxel m | $chunks | $tris | $s | $mib | $us |"
  [ "$m" = 20 ] || rm -f "$work/city_$m.ply"
done
read -r s mib < <(measure "$tool" reconstruct "$work/city_20.ply" -o "$work/mesh_20d.ply" \
  --chunk $chunk --json)
voxel_default=$(python3 -c "import json; d=json.load(open('$work/out.txt')); print(f\"{d['voxel_size']:.3f}\")")
tris=$(python3 -c "import json; print(json.load(open('$work/out.txt'))['triangles'])")
echo "| 20 M | 300 m | $voxel_default m (default: 3x spacing) | | $tris | $s | $mib | |"

if [ -x "$build/meshflow-mpi" ] && command -v mpirun > /dev/null; then
  echo
  echo "| meshflow-mpi, 20 M points, voxel $voxel m | wall s | peak MiB (per rank) | rank 0: partition / own chunks / gather / stitch + optimize s |"
  echo "|---|---:|---:|---|"
  for spec in "1 2" "2 1" "4 1"; do
    read -r ranks threads <<< "$spec"
    read -r s mib < <(measure mpirun --bind-to none -n "$ranks" "$build/meshflow-mpi" reconstruct "$work/city_20.ply" \
      -o "$work/mesh_mpi.ply" --chunk $chunk --voxel $voxel --threads "$threads")
    phases=$(grep '^time' "$work/out.txt" | sed 's/^time *//')
    echo "| $ranks rank(s) x $threads thread(s) | $s | $mib | $phases |"
  done
fi
