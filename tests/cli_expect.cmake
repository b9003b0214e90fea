# Shared helpers of the CLI tests (cmake -P scripts that run the built `handemo`):
#   run_ok(<name> <cli args>...)     the command must exit 0
#   run_fail(<name> <cli args>...)   the command must exit 1 (the README: every failure, usage errors
#                                    included, exits 1) with exactly one stderr line starting
#                                    "handemo: error: "; that line is left in ${last_error}
#   run_fail_file(<name> <file> <cli args>...)  as run_fail, and the error line must name <file> (its
#                                    file name; the message may show the path as given or resolved)
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
  if(NOT rc STREQUAL "1")
    message(FATAL_ERROR "${name}: expected exit code 1, got '${rc}'\n${out}\n${err}")
  endif()
  string(STRIP "${err}" e)
  string(FIND "${e}" "\n" nl)
  if(NOT nl EQUAL -1 OR NOT e MATCHES "^handemo: error: ")
    message(FATAL_ERROR "${name}: expected one line 'handemo: error: ...', got:\n${err}")
  endif()
  set(last_error "${e}" PARENT_SCOPE)
  set(last_name "${name}" PARENT_SCOPE)
endfunction()

function(run_fail_file name file)
  run_fail(${name} ${ARGN})
  get_filename_component(base "${file}" NAME)
  string(FIND "${last_error}" "${base}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${name}: error '${last_error}' does not name the file '${base}'")
  endif()
  set(last_error "${last_error}" PARENT_SCOPE)
  set(last_name "${name}" PARENT_SCOPE)
endfunction()

function(expect_error_matches re)
  if(NOT last_error MATCHES "${re}")
    message(FATAL_ERROR "${last_name}: error '${last_error}' does not match '${re}'")
  endif()
endfunction()
