# cmake -DCXX=<compiler> -DSRC=<file> -DINC=<include dirs, ;-separated> -DDEF=<define> -DEXPECT=<regex> -P check_compile_fail.cmake
# Succeeds when compiling SRC fails AND the diagnostic matches EXPECT.
# With -DEXPECT_SUCCESS=1 instead: succeeds when SRC compiles (the control of the same file).
set(_inc)
foreach(_d IN LISTS INC)
  list(APPEND _inc -I${_d})
endforeach()
execute_process(COMMAND ${CXX} -std=c++20 -fsyntax-only ${_inc} -D${DEF} ${EXTRA_DEF} ${SRC}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(EXPECT_SUCCESS)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${SRC} (${DEF} ${EXTRA_DEF}) must compile (the shapes agree):\n${err}")
  endif()
  message(STATUS "matching shapes compile")
  return()
endif()
if(rc EQUAL 0)
  message(FATAL_ERROR "${SRC} (${DEF}) compiled, but a shape mismatch must not compile")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "diagnostic does not contain '${EXPECT}':\n${err}")
endif()
message(STATUS "shape mismatch rejected with: ${EXPECT}")
