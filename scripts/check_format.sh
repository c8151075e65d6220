#!/usr/bin/env bash
# Fails when a tracked C++ file differs from clang-format's output under the root .clang-format;
# clang-format's messages name each file and line. Needs clang-format (Debian 12: version 14).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v clang-format > /dev/null; then
  echo "check_format: clang-format is not installed (apt-get install clang-format)" >&2
  exit 2
fi
if ! git ls-files -z '*.h' '*.cpp' | xargs -0 clang-format --dry-run -Werror; then
  echo "check_format: the files above are not clang-formatted (clang-format -i FILE)" >&2
  exit 1
fi
echo "check_format: $(git ls-files '*.h' '*.cpp' | wc -l) files formatted"
