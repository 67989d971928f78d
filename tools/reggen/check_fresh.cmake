# ctest helper: fails when a checked-in generated file differs from the freshly generated one.
#   cmake -DGENERATED=<build output> -DCHECKED_IN=<file in the source tree> -P check_fresh.cmake
set(_fix "run `cmake --build build --target update-generated` and commit the result")
if(NOT EXISTS "${GENERATED}")
  message(FATAL_ERROR "${GENERATED} does not exist: build first (cmake --build build)")
endif()
if(NOT EXISTS "${CHECKED_IN}")
  message(FATAL_ERROR "${CHECKED_IN} does not exist: ${_fix}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${GENERATED}" "${CHECKED_IN}"
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${CHECKED_IN} is stale (differs from ${GENERATED}, which reggen made from "
                      "regs/dpc31_regs.json): ${_fix}")
endif()
