# Runs EXE with ARGS (a ;-list) and checks both its exit code (RC) and its output (REGEX on
# stdout, ERR_REGEX on stderr): CTest's PASS_REGULAR_EXPRESSION alone would ignore the exit code.
# OUT_FILE: stdout goes there instead (/dev/full: a failed write).
if(DEFINED OUT_FILE)
  execute_process(COMMAND ${EXE} ${ARGS} RESULT_VARIABLE rc OUTPUT_FILE ${OUT_FILE}
    ERROR_VARIABLE err)
else()
  execute_process(COMMAND ${EXE} ${ARGS} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
endif()
if(NOT rc STREQUAL "${RC}")
  message(FATAL_ERROR "exit ${rc}, expected ${RC}\nstdout:\n${out}\nstderr:\n${err}")
endif()
if(DEFINED REGEX AND NOT out MATCHES "${REGEX}")
  message(FATAL_ERROR "stdout does not match '${REGEX}':\n${out}")
endif()
if(DEFINED ERR_REGEX AND NOT err MATCHES "${ERR_REGEX}")
  message(FATAL_ERROR "stderr does not match '${ERR_REGEX}':\n${err}")
endif()
