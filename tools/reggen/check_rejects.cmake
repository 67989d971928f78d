# ctest helper for reggen_rejects_bad_input: reggen must accept DATA_DIR/minimal_ok.json and
# reject every file listed in DATA_DIR/cases.txt ("<file>: <expected text>") with exit code 2,
# exactly one line on stderr containing the expected text, and no output file written.
#   cmake -DREGGEN=<reggen> -DDATA_DIR=<dir> -DWORK_DIR=<scratch dir> -P check_rejects.cmake
file(REMOVE_RECURSE "${WORK_DIR}")

execute_process(COMMAND "${REGGEN}" --quiet --in "${DATA_DIR}/minimal_ok.json" --out-dir "${WORK_DIR}/ok"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "minimal_ok.json: expected exit 0, got ${rc}: ${err}")
endif()

file(STRINGS "${DATA_DIR}/cases.txt" _cases REGEX "^[^#]")
set(_failures 0)
set(_count 0)
foreach(line IN LISTS _cases)
  string(REGEX MATCH "^([^:]+): (.*)$" _m "${line}")
  set(name "${CMAKE_MATCH_1}")
  set(expected "${CMAKE_MATCH_2}")
  math(EXPR _count "${_count} + 1")
  set(out "${WORK_DIR}/${name}")
  execute_process(COMMAND "${REGGEN}" --quiet --in "${DATA_DIR}/${name}" --out-dir "${out}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE err)
  string(REGEX MATCHALL "\n" _newlines "${err}")
  list(LENGTH _newlines _lines)
  string(FIND "${err}" "${expected}" _at)
  file(GLOB_RECURSE _written "${out}/*")
  set(problem "")
  if(NOT rc EQUAL 2)
    set(problem "exit code ${rc} instead of 2")
  elseif(NOT _lines EQUAL 1)
    set(problem "${_lines} lines on stderr instead of 1")
  elseif(_at EQUAL -1)
    set(problem "message does not contain '${expected}'")
  elseif(_written)
    set(problem "files written: ${_written}")
  endif()
  if(problem)
    message(SEND_ERROR "${name}: ${problem}; stderr: ${err}")
    math(EXPR _failures "${_failures} + 1")
  else()
    string(STRIP "${err}" err)
    message(STATUS "${name}: rejected as expected: ${err}")
  endif()
endforeach()
if(_count EQUAL 0)
  message(FATAL_ERROR "no cases in ${DATA_DIR}/cases.txt")
endif()

# The command line's own bad input, the same way (CLI11's exit() gave 106 and 109 and a second
# line; a file as --out-dir was exit 1 after generating everything).
macro(expect_refused label expected)
  math(EXPR _count "${_count} + 1")
  execute_process(COMMAND "${REGGEN}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE stdout
                  ERROR_VARIABLE err)
  string(REGEX MATCHALL "\n" _newlines "${err}")
  list(LENGTH _newlines _lines)
  string(FIND "${err}" "${expected}" _at)
  if(NOT rc EQUAL 2 OR NOT _lines EQUAL 1 OR _at EQUAL -1)
    message(SEND_ERROR "${label}: exit ${rc}, ${_lines} lines, expected exit 2 and one line "
                       "containing '${expected}'; stderr: ${err}")
    math(EXPR _failures "${_failures} + 1")
  endif()
endmacro()
file(WRITE "${WORK_DIR}/a_file" "")
expect_refused("no arguments" "reggen: --in is required")
expect_refused("unknown option" "reggen: The following argument was not expected: --bogus"
               --in "${DATA_DIR}/minimal_ok.json" --out-dir "${WORK_DIR}/x" --bogus)
expect_refused("--out-dir a file" "reggen: --out-dir ${WORK_DIR}/a_file: not a directory"
               --in "${DATA_DIR}/minimal_ok.json" --out-dir "${WORK_DIR}/a_file")
if(_failures GREATER 0)
  message(FATAL_ERROR "${_failures} of ${_count} bad inputs not rejected as expected")
endif()
