# What the browser tests share (sourced by browser_view_test.sh and browser_run_test.sh):
# finding Chromium, a PLY header's counts, waiting for a server's URL, and loading the page in
# headless Chromium (browser_check.py) to check its state, counts and screenshot.
# Fails (never skips) when Chromium or Python 3 is missing: scripts/install_deps.sh installs them.

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
chromium=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$chromium" ]; then
  echo "FAIL: no chromium on PATH: the browser test needs Debian's chromium" \
       "(scripts/install_deps.sh installs it)" >&2
  exit 1
fi
if ! command -v python3 >/dev/null; then
  echo "FAIL: no python3 on PATH (the screenshot check needs it)" >&2
  exit 1
fi

# ply_counts FILE: prints "VERTICES TRIANGLES" from the PLY header (read here, not by meshflow).
ply_counts() {
  local header
  header=$(head -c 2048 "$1" | tr -d '\r' | sed -n '1,/^end_header/p' | tr -d '\000')
  echo "$(sed -n 's/^element vertex \([0-9]*\)$/\1/p' <<<"$header")" \
       "$(sed -n 's/^element face \([0-9]*\)$/\1/p' <<<"$header")"
}

# wait_url LOG PID: prints the "url http://..." a server wrote to LOG (empty if PID ended or
# 20 s passed first).
wait_url() {
  local url=""
  for _ in $(seq 1 200); do
    url=$(sed -n 's/^url \(http:[^ ]*\)$/\1/p' "$1")
    [ -n "$url" ] && break
    kill -0 "$2" 2>/dev/null || break
    sleep 0.1
  done
  echo "$url"
}

# load_page URL WORK: loads URL in headless Chromium until the page says it is complete (or
# failed), writing WORK/page.json (its data attributes) and WORK/page.png. Returns 1 when the page
# did not load or finish in time.
load_page() {
  local url=$1 work=$2
  case "$url" in
    http://127.0.0.1:*) ;;
    *) echo "FAIL: --serve PORT did not bind 127.0.0.1: $url" >&2; return 1 ;;
  esac
  # Chromium through the DevTools protocol (browser_check.py): it waits for the page's own
  # data-state instead of a fixed time, then takes the screenshot.
  if ! timeout 120 python3 "$here/browser_check.py" "$chromium" "$url" "$work/page.json" \
      "$work/page.png" 90; then
    echo "FAIL: the page did not load (Chromium's log: $work/page.json.chromium.log)" >&2
    return 1
  fi
}

# check_page WORK VERTICES TRIANGLES MIN_LEVELS: checks the page load_page saw: complete,
# showing VERTICES and TRIANGLES, at least MIN_LEVELS levels drawn, and a screenshot with the
# mesh in its middle. Returns 1 on any failure (each one printed).
check_page() {
  local work=$1 vertices=$2 triangles=$3 min_levels=$4 status=0
  local state page_triangles page_vertices levels
  read -r state page_triangles page_vertices levels < <(python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
print(d.get("state", "-"), d.get("triangles", "-"), d.get("vertices", "-"), d.get("levels", 0))' \
    "$work/page.json")
  if [ "$levels" -lt "$min_levels" ]; then
    echo "FAIL: the page drew $levels level(s), fewer than $min_levels" >&2
    status=1
  fi
  if [ "$state" != complete ]; then
    echo "FAIL: the page's state is '$state', not complete" >&2
    status=1
  fi
  if [ "$page_triangles" != "$triangles" ] || [ "$page_vertices" != "$vertices" ]; then
    echo "FAIL: the page shows $page_triangles triangles, $page_vertices vertices;" \
         "the file has $triangles and $vertices" >&2
    status=1
  fi
  python3 "$here/screenshot_check.py" "$work/page.png" || status=1
  [ $status -eq 0 ] || echo "Chromium's log: $work/page.json.chromium.log" >&2
  return $status
}
