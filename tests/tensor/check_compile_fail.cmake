# cmake -DCXX=<compiler> -DSRC=<file> -DINC=<include dir> -DDEF=<define> -DEXPECT=<regex> -P check_compile_fail.cmake
# Succeeds when compiling SRC fails AND the diagnostic matches EXPECT.
execute_process(COMMAND ${CXX} -std=c++20 -fsyntax-only -I${INC} -D${DEF} ${SRC}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "${SRC} (${DEF}) compiled, but a shape mismatch must not compile")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "diagnostic does not contain '${EXPECT}':\n${err}")
endif()
message(STATUS "shape mismatch rejected with: ${EXPECT}")
