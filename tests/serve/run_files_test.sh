#!/usr/bin/env bash
# --serve changes nothing a run writes: each command that can serve (run per frame, with
# --triangulate, --merged, --fuse; reconstruct) runs on meshflow's own synthetic inputs with and
# without --serve, and every file written must be the same byte for byte. `live` writes no
# files: it must serve and exit cleanly. No browser here (browser_run_test.sh has a viewer).
#
# usage: run_files_test.sh MESHFLOW_BINARY WORK_DIR
set -euo pipefail
meshflow=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
status=0
serve=(--serve 0 --exit-after 0.05)

# same NAME ARGS...: runs `meshflow ARGS -o DIR` without and with --serve, compares DIR's files.
same() {
  local name=$1
  shift
  "$meshflow" "$@" -o "$work/$name.plain" > "$work/$name.plain.log" 2>&1
  "$meshflow" "$@" -o "$work/$name.served" "${serve[@]}" > "$work/$name.served.log" 2>&1
  grep -q '^url http://127.0.0.1:' "$work/$name.served.log" ||
    { echo "FAIL: $name: no url printed" >&2; status=1; }
  local files
  files=$(cd "$work/$name.plain" && ls)
  [ -n "$files" ] || { echo "FAIL: $name wrote nothing" >&2; status=1; return; }
  if [ "$files" != "$(cd "$work/$name.served" && ls)" ]; then
    echo "FAIL: $name: other files with --serve" >&2
    status=1
    return
  fi
  for f in $files; do
    cmp "$work/$name.plain/$f" "$work/$name.served/$f" ||
      { echo "FAIL: $name: $f differs with --serve" >&2; status=1; }
  done
  echo "$name: $(wc -w <<<"$files") file(s) the same with --serve"
}

depth=(--synthetic-depth --synthetic-size 160x120 --synthetic-frames 4)
same per-frame run "${depth[@]}" --voxel 0.05
same triangulate run "${depth[@]}" --triangulate rqt
same merged run --synthetic --synthetic-frames 2 --merged
same fuse run "${depth[@]}" --fuse --voxel 0.05 --compress progressive

"$meshflow" sample sphere --points 5000 -o "$work/sphere.ply" > /dev/null
mkdir -p "$work/reconstruct.plain" "$work/reconstruct.served"
"$meshflow" reconstruct "$work/sphere.ply" -o "$work/reconstruct.plain/mesh.ply" > /dev/null
"$meshflow" reconstruct "$work/sphere.ply" -o "$work/reconstruct.served/mesh.ply" "${serve[@]}" \
  > "$work/reconstruct.log" 2>&1
cmp "$work/reconstruct.plain/mesh.ply" "$work/reconstruct.served/mesh.ply" ||
  { echo "FAIL: reconstruct: mesh.ply differs with --serve" >&2; status=1; }

"$meshflow" live "${depth[@]}" --triangulate rqt "${serve[@]}" > "$work/live.log" 2>&1 ||
  { echo "FAIL: live --serve failed" >&2; cat "$work/live.log" >&2; status=1; }
grep -q '^served ' "$work/live.log" || { echo "FAIL: live --serve served nothing" >&2; status=1; }

# Usage errors: --serve-rate without --serve, a bad address.
if "$meshflow" run "${depth[@]}" -o "$work/bad" --serve-rate 1 > /dev/null 2>&1; then
  echo "FAIL: --serve-rate without --serve was accepted" >&2
  status=1
fi
if "$meshflow" run "${depth[@]}" -o "$work/bad" --serve 70000 > /dev/null 2>&1; then
  echo "FAIL: --serve 70000 was accepted" >&2
  status=1
fi
[ $status -eq 0 ] && echo "PASS: the same files with and without --serve"
exit $status
