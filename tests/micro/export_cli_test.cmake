# `handemo export --header` end to end: synth -> train hand-micro (a few steps) -> export -> compile the header
# into tests/micro/self_test_main.cpp with -fno-exceptions -fno-rtti -> run it (G on the header's self-test
# input equals the host's output). Then the one-line errors of export. Leaves ${WORK_DIR}/model.hpp for the
# Cortex-M test. Variables: HANDEMO_CLI, CXX, SOURCE_DIR, WORK_DIR.
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(D ${WORK_DIR}/data)
set(M ${WORK_DIR}/model)

run_ok(synth synth --out ${D} --takes 1 --seed 3)
run_ok(train train --data ${D} --out ${M} --config hand-micro --iters 4 --threads 1)
run_ok(export export --header ${M} --out ${WORK_DIR}/model.hpp --self-test-emotion sad)
file(READ ${WORK_DIR}/model.hpp h)
foreach(want "static constexpr const char\\* config = \"hand-micro\";" "conv_dim = 8, res_blocks = 3;"
             "float weights\\[80632\\]" "self_test_target = 3;" "residual = true;")
  if(NOT h MATCHES "${want}")
    message(FATAL_ERROR "export: model.hpp lacks '${want}'")
  endif()
endforeach()

execute_process(COMMAND ${CXX} -std=c++20 -O2 -fno-exceptions -fno-rtti -I${SOURCE_DIR}/include
                        "-DHANDEMO_MODEL_HEADER=\"${WORK_DIR}/model.hpp\"" ${SOURCE_DIR}/tests/micro/self_test_main.cpp
                        -o ${WORK_DIR}/self_test
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "compiling the exported header failed (${rc}):\n${out}${err}")
endif()
execute_process(COMMAND ${WORK_DIR}/self_test RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "self-test hand-micro target sad: .*: ok")
  message(FATAL_ERROR "the exported header's self-test failed (${rc}): ${out}${err}")
endif()

# bad input
run_fail(missing_model export --header ${WORK_DIR}/nomodel --out ${WORK_DIR}/x.hpp)
expect_error_matches("nomodel")
run_fail(bad_emotion export --header ${M} --out ${WORK_DIR}/x.hpp --self-test-emotion bored)
expect_error_matches("unknown emotion 'bored'")
run_fail(bad_out export --header ${M} --out ${WORK_DIR}/no/such/dir/x.hpp)
expect_error_matches("cannot write")
