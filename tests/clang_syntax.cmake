# The library with Debian's clang, the second compiler it must build with (GCC 12 is the first; CI runs both).
# Compiles, with clang's full front end but no code generation (-fsyntax-only, which still instantiates every
# template the sources use), every public header, the README's example, the CLI's StarGAN unit (training,
# evaluation and transfer for every configuration), with -Wall -Wextra -Werror. The fuzz harnesses are test code
# that GCC builds in every run; their libFuzzer form is compiled with clang itself by -DHANDEMO_FUZZ=ON.
# Without clang++ at configure time the test is a one-line skip instead (tests/CMakeLists.txt).
# -DCLANGXX=... -DSRC=<source dir> -DINCLUDES=<;-list of include dirs> -DWORK=<scratch dir>
file(MAKE_DIRECTORY ${WORK})
set(all "${WORK}/all_headers.cpp")
file(GLOB headers RELATIVE ${SRC}/include ${SRC}/include/handemo/*.hpp)
set(text "// every public header of handemo, in one unit\n#include <handemo.hpp>\n")
foreach(h IN LISTS headers)
  string(APPEND text "#include <${h}>\n")
endforeach()
string(APPEND text "#include <handemo/eval/rcm.hpp>\nint main() {}\n")
file(WRITE ${all} "${text}")
set(sources ${all} ${SRC}/examples/transfer.cpp ${SRC}/examples/cli/cmd_stargan.cpp)
set(flags -std=c++20 -fsyntax-only -Wall -Wextra -Werror "-DHANDEMO_SOURCE_DIR=\"${SRC}\"" "-DHANDEMO_RCM_CIRCUMPLEX=\"\"")
foreach(d IN LISTS INCLUDES)
  list(APPEND flags -I${d})
endforeach()
# The units are independent: JOBS of them (default 2, the README's -j2) run at once. execute_process runs its
# COMMANDs concurrently (as a pipeline, which -fsyntax-only leaves empty: it writes nothing to stdout), and
# RESULTS_VARIABLE gives each unit's exit code. A unit that fails is compiled again on its own so that its
# diagnostics are printed unmixed.
if(NOT JOBS)
  set(JOBS 2)
endif()
set(failed "")
set(pending ${sources})
while(pending)
  set(batch "")
  set(cmds "")
  foreach(i RANGE 1 ${JOBS})
    if(pending)
      list(POP_FRONT pending s)
      list(APPEND batch ${s})
      list(APPEND cmds COMMAND ${CLANGXX} ${flags} ${s})
    endif()
  endforeach()
  execute_process(${cmds} RESULTS_VARIABLE rcs OUTPUT_VARIABLE out ERROR_VARIABLE err)
  foreach(s rc IN ZIP_LISTS batch rcs)
    if(NOT rc EQUAL 0)
      execute_process(COMMAND ${CLANGXX} ${flags} ${s} OUTPUT_VARIABLE out ERROR_VARIABLE err)
      message("${err}")
      list(APPEND failed ${s})
    endif()
  endforeach()
endwhile()
list(LENGTH sources n)
if(failed)
  message(FATAL_ERROR "clang_syntax: ${CLANGXX} rejects: ${failed}")
endif()
message("clang_syntax: ${CLANGXX} compiles all ${n} units (-fsyntax-only -Wall -Wextra -Werror)")
