#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, AddressSanitizer and UndefinedBehaviorSanitizer
# and runs each for SECONDS (default 60), seeded from the test fixtures and, when present, the
# small files of $MESHFLOW_DATA. A finding stops the run with libFuzzer's report and its input
# saved as BUILD/findings/<target>/crash-* (or oom-*, leak-*, timeout-*: one input over 10 s); a
# fixed finding goes to fuzz/regressions/<target>/ (a seed of later runs) with a test.
#   scripts/fuzz.sh [--build-dir DIR] [SECONDS] [TARGET ...]   e.g. scripts/fuzz.sh 20 ply pcd
# Without --build-dir it configures build-fuzz/ (readers only); with it, DIR is a clang build
# configured with -DMESHFLOW_BUILD_FUZZERS=ON and sanitizers (.ci/run's ASan + UBSan build) and
# only the fuzz targets are built there. Needs clang and libclang-rt-14-dev (libFuzzer).
set -euo pipefail
cd "$(dirname "$0")/.."
build=""
if [ "${1:-}" = "--build-dir" ]; then
  build=$2
  shift 2
fi
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ply pcd xyz 3dtk las mesh rgbd tum image tsdf_map mfc client_message)
data=${MESHFLOW_DATA:-../shared/data}

if [ -z "$build" ]; then
  build=build-fuzz
  CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DMESHFLOW_BUILD_FUZZERS=ON \
    -DMESHFLOW_SANITIZE=address,undefined -DMESHFLOW_SANITIZE_SKIP=vptr \
    -DMESHFLOW_BUILD_TESTS=OFF -DMESHFLOW_BUILD_BENCHMARKS=OFF -DMESHFLOW_BUILD_TOOLS=OFF \
    -DMESHFLOW_SCALABLE_MALLOC=OFF > /dev/null
elif ! grep -qs "^MESHFLOW_BUILD_FUZZERS:BOOL=ON" "$build/CMakeCache.txt"; then
  echo "fuzz: $build is not configured with -DMESHFLOW_BUILD_FUZZERS=ON" >&2
  exit 2
fi
cmake --build "$build" --target $(printf 'fuzz_%s ' "${targets[@]}")

# Seeds: files whose extension the target reads, at most 256 kB each.
seed_patterns() {
  case $1 in
    ply) echo '*.ply' ;; pcd) echo '*.pcd' ;; xyz) echo '*.xyz *.pts *.txt *.csv' ;;
    3dtk) echo '*.3d *.pose' ;; las) echo '*.las' ;; mesh) echo '*.obj *.off *.stl' ;;
    rgbd) echo '*.log *.json' ;; tum) echo '*.txt' ;; image) echo '*.png *.tiff *.tif *.pclzf *.jpg' ;;
    tsdf_map) echo '*.tsdf' ;; mfc) echo '*.mfc' ;;
  esac
}
# Seeds made by meshflow itself where the fixtures and the shared data have none (no such files
# are committed): a small TSDF map (8 blocks of 0.6 m voxels, 49 kB) from the synthetic depth
# camera, a coarse sphere mesh as OBJ, OFF and STL, and that mesh compressed (Edgebreaker and
# progressive).
meshflow_tool() {
  local tool
  for tool in "$build/meshflow" build/meshflow; do
    if [ -x "$tool" ]; then echo "$tool"; return; fi
  done
}
made_seeds() {  # TARGET CORPUS
  local tool
  tool=$(meshflow_tool)
  if [ -z "$tool" ]; then
    echo "fuzz: no meshflow executable to make seeds for fuzz_$1" >&2
    return
  fi
  case $1 in
    tsdf_map)
      "$tool" run --synthetic-depth --synthetic-frames 1 --synthetic-size 32x24 --fuse \
        --voxel 0.6 --save-map "$2/seed_synthetic.tsdf" -o "$build/map_seed" -q ;;
    mesh)
      "$tool" sample sphere --points 3000 -o "$build/seed_sphere.ply" -q
      for ext in obj off stl; do
        "$tool" reconstruct "$build/seed_sphere.ply" --voxel 0.25 -o "$2/seed_sphere.$ext" -q
      done ;;
    mfc)
      "$tool" sample torus --points 3000 -o "$build/seed_torus.ply" -q
      "$tool" reconstruct "$build/seed_torus.ply" --voxel 0.2 -o "$2/seed_torus.mfc" -q
      "$tool" reconstruct "$build/seed_torus.ply" --voxel 0.2 --compress progressive \
        -o "$2/seed_torus_progressive.mfc" -q ;;
  esac
}
status=0
for t in "${targets[@]}"; do
  corpus="$build/corpus/$t"
  findings="$build/findings/$t"
  mkdir -p "$corpus" "$findings"
  # Earlier findings first (fuzz/regressions/<target>/, each fixed and covered by a test).
  if [ -d "fuzz/regressions/$t" ]; then cp fuzz/regressions/"$t"/* "$corpus"/; fi
  for pattern in $(seed_patterns "$t"); do
    find tests/data "$data" -name "$pattern" -size -256k -type f 2>/dev/null |
      head -n 50 | while read -r f; do cp "$f" "$corpus/seed_$(basename "$f")"; done
  done
  made_seeds "$t" "$corpus"
  if [ "$t" = client_message ]; then  # the two messages a browser may send
    printf '{"type":"hello"}' > "$corpus/seed_hello.json"
    printf '{"type":"ping","t":12.5}' > "$corpus/seed_ping.json"
  fi
  if [ "$t" = tum ]; then  # depth.txt lines, a zero byte, groundtruth.txt lines
    printf '# depth\n1305031102.160407 depth/1305031102.160407.png\n1305031102.194330 depth/1305031102.194330.png\n\0# timestamp tx ty tz qx qy qz qw\n1305031102.1758 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n' \
      > "$corpus/seed_association.txt"
  fi
  echo "== fuzz_$t: $seconds s, $(ls "$corpus" | wc -l) corpus files"
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      "$build/fuzz/fuzz_$t" "$corpus" -max_total_time="$seconds" -max_len=65536 \
      -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10 -artifact_prefix="$findings/" \
      -print_final_stats=1 2>"$build/fuzz_$t.log"; then
    tail -n 40 "$build/fuzz_$t.log"
    echo "fuzz: fuzz_$t found a problem; inputs in $findings" >&2
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/fuzz_$t.log" | tr '\n' ' '
    echo
  fi
done
exit $status
