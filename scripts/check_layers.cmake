# The include rules of docs/ARCHITECTURE.md, checked on every source file of the library layers
# by the build itself (the meshflow_layers target, which every library waits for) and by
# scripts/check_layers.sh:
#   runtime/  includes only runtime/;
#   nodes/X/  includes runtime/, its own folder X (and X's sub-folders) and the shared node
#             folders io/ (files), search/ (spatial queries), cube/ (cube tables), depth/
#             (depth-image pre-processing) and decimate/ (QEM); never another stage's folder nor
#             a layer above (graph/ options/ serve/ tools/ python/ web/);
#   graph/    includes runtime/, nodes/ and graph/;
#   options/  (the option model) includes runtime/, nodes/, graph/ and options/;
#   serve/    includes runtime/, nodes/, graph/, options/ and serve/, never a front end.
# Usage: cmake -DSOURCE_DIR=<repository> -P scripts/check_layers.cmake
# Prints each offending include (file: includes target) and fails if there is one. O(lines of
# the layers' files).
cmake_minimum_required(VERSION 3.16)
if(NOT SOURCE_DIR)
  get_filename_component(SOURCE_DIR "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
endif()
set(shared_stages io search cube depth decimate)
set(allowed_runtime runtime)
set(allowed_graph runtime nodes graph)
set(allowed_options runtime nodes graph options)
set(allowed_serve runtime nodes graph options serve)

set(problems "")
foreach(layer runtime nodes graph options serve)
  file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE "${SOURCE_DIR}"
       "${SOURCE_DIR}/${layer}/*.h" "${SOURCE_DIR}/${layer}/*.cpp")
  foreach(file ${files})
    if(layer STREQUAL "nodes")
      string(REGEX REPLACE "^nodes/([^/]+)/.*" "\\1" stage "${file}")
    endif()
    file(STRINGS "${SOURCE_DIR}/${file}" lines REGEX "^#include \"")
    foreach(line ${lines})
      string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" target "${line}")
      string(REGEX REPLACE "/.*" "" to_layer "${target}")
      if(NOT target MATCHES "/")
        continue()  # a file beside it (none today) or a system header written with quotes
      endif()
      set(ok FALSE)
      if(layer STREQUAL "nodes")
        if(to_layer STREQUAL "runtime")
          set(ok TRUE)
        elseif(to_layer STREQUAL "nodes")
          string(REGEX REPLACE "^nodes/([^/]+)/.*" "\\1" to_stage "${target}")
          if(to_stage STREQUAL stage OR to_stage IN_LIST shared_stages)
            set(ok TRUE)
          endif()
        endif()
      elseif(to_layer IN_LIST allowed_${layer})
        set(ok TRUE)
      endif()
      if(NOT ok)
        string(APPEND problems "${file}: includes ${target}\n")
      endif()
    endforeach()
  endforeach()
endforeach()
if(problems)
  message(FATAL_ERROR "includes across layers (docs/ARCHITECTURE.md):\n${problems}")
endif()
