# Writes OUT, a header defining HANDEMO_BUILD_COMMIT: the git commit of the source tree SRC at build time, with
# "-dirty" when tracked files differ from it, or "unknown" when SRC is not the top of a git checkout (a source
# archive, also one unpacked inside another repository). Run at every
# build (the custom target handemo_build_commit, examples/CMakeLists.txt), not at configure time: a value taken
# when CMake configured would go stale at the next commit, since nothing re-runs the configure then. The file is
# rewritten only when its text changes, so an unchanged commit recompiles nothing.
# Variables: SRC, OUT.
set(commit unknown)
find_package(Git QUIET)
if(GIT_FOUND)
  # SRC must be the top of its own checkout: a source archive unpacked inside another repository (a vendored
  # copy) is not that repository's commit
  execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SRC} rev-parse --show-toplevel
                  OUTPUT_VARIABLE top RESULT_VARIABLE rc0 OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  get_filename_component(top_real "${top}" REALPATH)
  get_filename_component(src_real "${SRC}" REALPATH)
  set(head "")
  set(rc 1)
  if(rc0 EQUAL 0 AND top_real STREQUAL src_real)
    execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SRC} rev-parse --verify HEAD
                    OUTPUT_VARIABLE head RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  endif()
  if(rc EQUAL 0 AND head MATCHES "^[0-9a-f]+$")
    set(commit ${head})
    # --no-optional-locks: a build never takes the index lock a git command running beside it may need
    execute_process(COMMAND ${GIT_EXECUTABLE} --no-optional-locks -C ${SRC} status --porcelain --untracked-files=no
                    OUTPUT_VARIABLE changes RESULT_VARIABLE rc2 ERROR_QUIET)
    if(rc2 EQUAL 0 AND NOT changes STREQUAL "")
      string(APPEND commit "-dirty")
    endif()
  endif()
endif()
set(text "// Generated at build time by cmake/build_commit.cmake: the source tree's git commit.\n#pragma once\n#define HANDEMO_BUILD_COMMIT \"${commit}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUT} "${text}")
endif()
