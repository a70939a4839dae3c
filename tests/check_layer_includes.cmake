# Each layer includes only what is below it: engine and simulator/backends
# (homing/) <- register table (registers/) <- Sparkplug B payloads (sparkplug/,
# which also reads persistence's event records) <- runtime, transports, tools. Run by ctest (tests/CMakeLists.txt) as
#   cmake -D SOURCE_DIR=<source tree> -P check_layer_includes.cmake
# Every #include "..." or <...> of the .hpp/.cpp files under each checked
# layer is resolved (a path starting with '.', or one that exists beside the
# including file, relative to that file; any other from the source root) and
# the check fails, naming the file and the include, when it lands in a part of
# the project the layer may not use. Includes outside the project (the
# standard library, fmt, toml++) are not judged.
cmake_minimum_required(VERSION 3.25)

if(NOT SOURCE_DIR)
  message(FATAL_ERROR "usage: cmake -D SOURCE_DIR=<source tree> -P ${CMAKE_CURRENT_LIST_FILE}")
endif()

# The project's parts (top-level directories whose headers code may include).
set(parts homing registers persistence server tools bench fuzz tests tls sparkplug)
# What each checked layer may include, itself first.
set(may_include_homing homing)
set(may_include_registers registers homing)
# Sparkplug B payloads are built from the register table and the event records
# of persistence/ (a leaf: it includes nothing of the project), never from the runtime.
set(may_include_sparkplug sparkplug registers homing persistence)

set(problems "")
set(checked 0)
foreach(layer IN ITEMS homing registers sparkplug)
  file(GLOB_RECURSE sources LIST_DIRECTORIES false RELATIVE "${SOURCE_DIR}"
       "${SOURCE_DIR}/${layer}/*.hpp" "${SOURCE_DIR}/${layer}/*.cpp" "${SOURCE_DIR}/${layer}/*.h"
       "${SOURCE_DIR}/${layer}/*.c")
  if(NOT sources)
    message(FATAL_ERROR "${SOURCE_DIR}/${layer}: no sources found; is SOURCE_DIR the source tree?")
  endif()
  list(SORT sources)
  set(forbidden ${parts})
  list(REMOVE_ITEM forbidden ${may_include_${layer}})
  foreach(source IN LISTS sources)
    file(STRINGS "${SOURCE_DIR}/${source}" includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    get_filename_component(here "${source}" DIRECTORY)
    foreach(line IN LISTS includes)
      if(NOT line MATCHES "#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
        continue()
      endif()
      set(included "${CMAKE_MATCH_1}")
      math(EXPR checked "${checked} + 1")
      if(included MATCHES "^\\." OR EXISTS "${SOURCE_DIR}/${here}/${included}")
        cmake_path(APPEND here "${included}" OUTPUT_VARIABLE resolved)
        cmake_path(NORMAL_PATH resolved)
      else()
        set(resolved "${included}")
      endif()
      string(REGEX REPLACE "/.*" "" top "${resolved}")
      if(top IN_LIST forbidden)
        list(JOIN may_include_${layer} "/, " allowed)
        string(APPEND problems "  - ${source} includes \"${included}\": ${top}/ is not below ${layer}/, "
                               "which may include only ${allowed}/\n")
      endif()
    endforeach()
  endforeach()
endforeach()

if(problems)
  message(FATAL_ERROR "includes across the layers, the wrong way:\n${problems}")
endif()
message(STATUS "${checked} includes of homing/, registers/ and sparkplug/ checked: none reaches a layer above")
