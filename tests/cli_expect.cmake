# Shared helpers of the CLI tests (cmake -P scripts that run the built `handemo`):
#   run_ok(<name> <cli args>...)     the command must exit 0
#   run_fail(<name> <cli args>...)   the command must exit non-zero with exactly one stderr line
#                                    "handemo: error: ..."; that line is left in ${last_error}
#   expect_error_matches(<regex>)    ${last_error} must match
# Needs HANDEMO_CLI.
function(run_ok name)
  execute_process(COMMAND ${HANDEMO_CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: exit ${rc}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

function(run_fail name)
  execute_process(COMMAND ${HANDEMO_CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0)
    message(FATAL_ERROR "${name}: expected a non-zero exit, got 0\n${out}")
  endif()
  string(STRIP "${err}" e)
  string(FIND "${e}" "\n" nl)
  if(NOT nl EQUAL -1 OR NOT e MATCHES "^handemo: error: ")
    message(FATAL_ERROR "${name}: expected one line 'handemo: error: ...', got:\n${err}")
  endif()
  set(last_error "${e}" PARENT_SCOPE)
  set(last_name "${name}" PARENT_SCOPE)
endfunction()

function(expect_error_matches re)
  if(NOT last_error MATCHES "${re}")
    message(FATAL_ERROR "${last_name}: error '${last_error}' does not match '${re}'")
  endif()
endfunction()
