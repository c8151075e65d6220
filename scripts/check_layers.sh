#!/usr/bin/env bash
# Checks the include rules of docs/ARCHITECTURE.md on every tracked source file:
#   runtime/  includes only runtime/;
#   nodes/X/  includes runtime/, its own folder X (and X's sub-folders), and the shared node
#             folders io/ (files), search/ (spatial queries), cube/ (cube tables), depth/
#             (depth-image pre-processing) and decimate/ (QEM), never another stage's folder;
#   graph/    includes runtime/, nodes/ and graph/, never options/, serve/ or a front end;
#   options/  (the option model) includes runtime/, nodes/, graph/ and options/, never a front
#             end (tools/, python/, web/);
#   serve/    includes runtime/, nodes/, graph/ and serve/, never a front end (tools/ web/ python/).
# Prints each offending include as file:line and exits 1 if there is one.
set -euo pipefail
cd "$(dirname "$0")/.."
shared='io|search|cube|depth|decimate'
status=0
while IFS= read -r file; do
  layer=${file%%/*}
  while IFS=: read -r line target; do
    ok=1
    case "$layer" in
      runtime) [[ $target == runtime/* ]] || ok=0 ;;
      nodes)
        stage=$(cut -d/ -f2 <<<"$file")
        if [[ $target == nodes/* ]]; then
          to=$(cut -d/ -f2 <<<"$target")
          [[ $to == "$stage" || $to =~ ^($shared)$ ]] || ok=0
        elif [[ $target == graph/* || $target == tools/* ]]; then
          ok=0
        fi ;;
      graph) [[ $target != tools/* && $target != options/* && $target != serve/* &&
                $target != python/* && $target != web/* ]] || ok=0 ;;
      options) [[ $target != tools/* && $target != python/* && $target != web/* ]] || ok=0 ;;
      serve) [[ $target != tools/* && $target != web/* && $target != python/* ]] || ok=0 ;;
    esac
    if [ $ok = 0 ]; then
      echo "$file:$line: includes $target"
      status=1
    fi
  done < <(grep -n '^#include "' "$file" | sed -E 's/^([0-9]+):#include "([^"]+)".*/\1:\2/')
done < <(git ls-files 'runtime/*.h' 'runtime/*.cpp' 'nodes/*.h' 'nodes/*.cpp' 'graph/*.h' 'graph/*.cpp' \
           'options/*.h' 'options/*.cpp' 'serve/*.h' 'serve/*.cpp')
exit $status
