# cmake -DCMD=<program;args...> [-DENV=<VAR=value;...>] -DEXPECT_RC=<code> [-DEXPECT_OUT=<regex>] -P expect_exit.cmake
# Succeeds when the command exits with EXPECT_RC and (if given) its stdout+stderr matches EXPECT_OUT.
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${ENV} ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "${CMD}: exit code '${rc}', expected ${EXPECT_RC}\n${out}${err}")
endif()
if(DEFINED EXPECT_OUT AND NOT "${out}${err}" MATCHES "${EXPECT_OUT}")
  message(FATAL_ERROR "${CMD}: output does not match '${EXPECT_OUT}':\n${out}${err}")
endif()
message(STATUS "exit ${rc} as expected")
