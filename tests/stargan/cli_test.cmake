# Runs the built `handemo` through synth -> train -> transfer on a tiny configuration, then every kind of
# bad input of train and transfer: each must exit non-zero with one `handemo: error:` line naming the fault.
# Variables: HANDEMO_CLI, SHARED_DIR, WORK_DIR.
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(D ${WORK_DIR}/data)
set(M ${WORK_DIR}/model)

run_ok(synth synth --out ${D} --takes 1 --seed 3)
run_ok(train train --data ${D} --out ${M} --config hand-tiny --iters 10 --threads 2 --exclude-content pointing
       --checkpoint-every 5)
foreach(f checkpoint.safetensors generator.safetensors log.csv losses.svg range.json)
  if(NOT EXISTS ${M}/${f})
    message(FATAL_ERROR "train did not write ${M}/${f}")
  endif()
endforeach()
run_ok(resume train --data ${D} --out ${M} --config hand-tiny --iters 20 --threads 2 --exclude-content pointing --resume)
run_ok(transfer transfer --model ${M} --in ${D}/hand_pointing_neutral_0.bvh --emotion sad --out ${WORK_DIR}/sad.bvh)
if(NOT last_output MATCHES "tempo x")
  message(FATAL_ERROR "transfer did not report the tempo: ${last_output}")
endif()
run_ok(transfer_bmp transfer --model ${M} --in ${D}/hand_pointing_neutral_0.bvh --emotion angry --out ${WORK_DIR}/angry.bmp)
run_ok(transfer_img transfer --model ${M} --in ${WORK_DIR}/angry.bmp --emotion happy --out ${WORK_DIR}/happy.bvh
       --like ${D}/hand_pointing_neutral_0.bvh)
run_ok(info_out info ${WORK_DIR}/sad.bvh)

# the README's 10-line example (examples/transfer.cpp) on the same model
execute_process(COMMAND ${EXAMPLE} ${M} ${D}/hand_pointing_neutral_0.bvh sad ${WORK_DIR}/example
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK_DIR}/example.bvh OR NOT EXISTS ${WORK_DIR}/example.png)
  message(FATAL_ERROR "the README example failed (${rc}): ${out}${err}")
endif()

# bad input
run_fail(unknown_emotion transfer --model ${M} --in ${D}/hand_pointing_neutral_0.bvh --emotion bored --out ${WORK_DIR}/x.bvh)
expect_error_matches("unknown emotion 'bored'")
run_fail(wrong_skeleton transfer --model ${M} --in ${SHARED_DIR}/data/xia/neutral_16_000.bvh --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("neutral_16_000.bvh has 31 joints, the model .*checkpoint.safetensors \\(hand-tiny\\).*wrong skeleton")
run_fail(missing_model transfer --model ${WORK_DIR}/nomodel --in ${D}/hand_pointing_neutral_0.bvh --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("nomodel")
file(READ ${M}/checkpoint.safetensors ck HEX)
string(LENGTH "${ck}" n)
math(EXPR half "${n} / 2")
string(SUBSTRING "${ck}" 0 ${half} ck_half)
file(MAKE_DIRECTORY ${WORK_DIR}/truncated)
# write the first half of the checkpoint back as bytes
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "\\\\x\\1" esc "${ck_half}")
file(WRITE ${WORK_DIR}/truncated/checkpoint.safetensors "")
execute_process(COMMAND printf "${esc}" OUTPUT_FILE ${WORK_DIR}/truncated/checkpoint.safetensors)
run_fail(truncated_model transfer --model ${WORK_DIR}/truncated --in ${D}/hand_pointing_neutral_0.bvh --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("checkpoint.safetensors")
run_fail(bad_image transfer --model ${M} --in ${WORK_DIR}/angry.bmp --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("--like")
run_fail(wrong_ext transfer --model ${M} --in ${D}/hand_pointing_neutral_0.csv --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("expected a .bvh")
run_fail(missing_data train --data ${WORK_DIR}/nodata --out ${WORK_DIR}/m2 --config hand-tiny --iters 2)
expect_error_matches("nodata")
run_fail(unknown_config train --data ${D} --out ${WORK_DIR}/m2 --config hand-huge --iters 2)
expect_error_matches("unknown configuration 'hand-huge'")
run_fail(zero_iters train --data ${D} --out ${WORK_DIR}/m2 --config hand-tiny --iters 0)
expect_error_matches("iters 0")
run_fail(no_checkpoint train --data ${D} --out ${WORK_DIR}/m3 --config hand-tiny --iters 2 --resume)
expect_error_matches("no checkpoint")
run_fail(body_on_hand train --data ${SHARED_DIR}/data/xia --out ${WORK_DIR}/m2 --config hand-tiny --iters 2)
run_fail(all_excluded train --data ${D} --out ${WORK_DIR}/m2 --config hand-tiny --iters 2 --exclude-content crawling
         --exclude-content gripping --exclude-content patting --exclude-content impatient --exclude-content hand-on-mouse
         --exclude-content pointing --exclude-content pushing)
expect_error_matches("no motion clips")
run_fail(usage train --out ${WORK_DIR}/m2)
expect_error_matches("--data is required")
message(STATUS "stargan CLI: all checks passed")
