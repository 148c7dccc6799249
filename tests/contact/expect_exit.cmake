# Runs COMMAND (a ;-list) and fails unless it exits with EXIT_CODE and its
# output (stdout + stderr) matches EXPECT (a regular expression).
#   cmake -DCOMMAND="a;b" -DEXIT_CODE=2 -DEXPECT="regex" -P expect_exit.cmake
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code STREQUAL "${EXIT_CODE}")
  message(FATAL_ERROR "exit code ${code}, expected ${EXIT_CODE}\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "output does not match '${EXPECT}':\n${out}${err}")
endif()
