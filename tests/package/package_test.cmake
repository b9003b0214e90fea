# CTest driver for the package tests. MODE=install: configure a fresh build of handemo with tests,
# examples and benchmarks off, install it into a temporary prefix, then configure, build and run the
# consumer with find_package(handemo CONFIG REQUIRED COMPONENTS image), and configure a core-only consumer
# with pkg-config hidden (stb not findable). MODE=subdirectory: the same consumer with
# add_subdirectory(<handemo source>).
# Usage: cmake -DMODE=install|subdirectory -DHANDEMO_SOURCE=<dir> -DCONSUMER=<dir> -DWORK_DIR=<dir>
#              -DCXX=<compiler> -P package_test.cmake
foreach(v MODE HANDEMO_SOURCE CONSUMER WORK_DIR CXX)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "package_test: -D${v}=... is required")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "package_test (${MODE}): ${step} failed (exit ${rc}):\n${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${step}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

set(consumer_args -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=)  # -O0: fastest to compile
if(MODE STREQUAL "install")
  set(prefix "${WORK_DIR}/prefix")
  run("configure handemo" ${CMAKE_COMMAND} -S "${HANDEMO_SOURCE}" -B "${WORK_DIR}/handemo-build"
      -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_INSTALL_PREFIX=${prefix}
      -DHANDEMO_BUILD_TESTS=OFF -DHANDEMO_BUILD_EXAMPLES=OFF -DHANDEMO_BUILD_BENCH=OFF)
  run("install handemo" ${CMAKE_COMMAND} --install "${WORK_DIR}/handemo-build")
  foreach(f include/handemo.hpp include/handemo/image.hpp include/handemo/motion/bvh.hpp
            share/cmake/handemo/handemoConfig.cmake share/cmake/handemo/handemoConfigVersion.cmake)
    if(NOT EXISTS "${prefix}/${f}")
      message(FATAL_ERROR "package_test (install): ${prefix}/${f} was not installed")
    endif()
  endforeach()
  run("configure consumer (find_package)" ${CMAKE_COMMAND} -S "${CONSUMER}" -B "${WORK_DIR}/consumer-build"
      ${consumer_args} -DCMAKE_PREFIX_PATH=${prefix})
  # Without stb (pkg-config hidden from the consumer) the core target is found and usable, and the image
  # component is refused naming stb (checked inside the consumer's CMakeLists; configure only).
  run("configure core-only consumer without stb" ${CMAKE_COMMAND} -S "${CONSUMER}" -B "${WORK_DIR}/core-build"
      ${consumer_args} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_DISABLE_FIND_PACKAGE_PkgConfig=TRUE
      -DHANDEMO_CONSUMER_CORE_ONLY=ON)
elseif(MODE STREQUAL "subdirectory")
  run("configure consumer (add_subdirectory)" ${CMAKE_COMMAND} -S "${CONSUMER}" -B "${WORK_DIR}/consumer-build"
      ${consumer_args} -DHANDEMO_SOURCE=${HANDEMO_SOURCE})
  # handemo's own tests/examples/bench must default to OFF when it is not the top-level project.
  file(STRINGS "${WORK_DIR}/consumer-build/CMakeCache.txt" opts REGEX "^HANDEMO_BUILD_(TESTS|EXAMPLES|BENCH):BOOL=")
  list(LENGTH opts n_opts)
  if(NOT n_opts EQUAL 3)
    message(FATAL_ERROR "package_test (subdirectory): HANDEMO_BUILD_TESTS/EXAMPLES/BENCH not in the cache: ${opts}")
  endif()
  foreach(o IN LISTS opts)
    if(NOT o MATCHES "=OFF$")
      message(FATAL_ERROR "package_test (subdirectory): ${o}, expected OFF for a subproject")
    endif()
  endforeach()
else()
  message(FATAL_ERROR "package_test: MODE=${MODE}, expected install or subdirectory")
endif()
run("build consumer" ${CMAKE_COMMAND} --build "${WORK_DIR}/consumer-build")
run("run consumer" "${WORK_DIR}/consumer-build/app" "${WORK_DIR}")
if(NOT last_output MATCHES "consumer: ok")
  message(FATAL_ERROR "package_test (${MODE}): consumer printed:\n${last_output}")
endif()
file(REMOVE_RECURSE "${WORK_DIR}")
