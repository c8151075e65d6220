#!/usr/bin/env bash
# Regenerates docs/view_sphere.png, the screenshot in README.md and docs/VIEW.md: runs the
# browser test of `meshflow view` (browser_view_test.sh: headless Chromium, the page's counts and
# screenshot checked) and copies the screenshot it took. Fails when the test fails or the PNG is
# 150 kB or more (the README's picture stays small).
#
# usage: tests/serve/docs_screenshot.sh BUILD_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
work="$build/tests/serve/docs_screenshot"
"$here/browser_view_test.sh" "$build/meshflow" "$work"
bytes=$(stat -c %s "$work/page.png")
if [ "$bytes" -ge 153600 ]; then
  echo "FAIL: the screenshot has $bytes bytes (at most 150 kB for the docs)" >&2
  exit 1
fi
cp "$work/page.png" "$here/../../docs/view_sphere.png"
echo "docs/view_sphere.png: $bytes bytes"
