# ctest fixture "package: cpack builds the homingd .deb" (tests/package/CMakeLists.txt):
#   cmake -D CPACK=<cpack> -D CONFIG=<build>/CPackConfig.cmake -D OUT=<dir> -P build_deb.cmake
# Builds the package afresh into OUT (an old one is removed first, so a
# failed build never leaves a stale package for the tests) and checks that
# dpkg-deb reads it.
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")
execute_process(COMMAND "${CPACK}" --config "${CONFIG}" -G DEB -B "${OUT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cpack failed (${rc}):\n${out}\n${err}")
endif()
file(GLOB debs "${OUT}/*.deb")
list(LENGTH debs n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "cpack made ${n} .deb files in ${OUT}, not one: ${debs}\n${out}")
endif()
execute_process(COMMAND dpkg-deb --info "${debs}" RESULT_VARIABLE rc OUTPUT_VARIABLE info ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dpkg-deb cannot read ${debs}: ${err}")
endif()
message(STATUS "${debs}\n${info}")
