# handemo_set_arch(<target> <arch>): sets the instruction set of one target (and so of every
# translation unit in it) to -march=<arch>. `none` leaves the compiler's default (portable baseline).
function(handemo_set_arch target arch)
  if(NOT arch OR arch STREQUAL "none")
    return()
  endif()
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -march=${arch})
  endif()
endfunction()
