# `handemo rcm stylise` on a tiny synthetic hand set (fit a model, stylise a sad take toward happy), then
# bad input: each failure must exit 1 with one `handemo: error:` line naming the fault.
# Variables: HANDEMO_CLI, WORK_DIR.
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(D ${WORK_DIR}/data)
set(M ${WORK_DIR}/model.json)
set(IN ${D}/hand_pointing_sad_0.bvh)

run_ok(synth synth --out ${D} --takes 1 --seed 5 --fps 30)
run_ok(fit rcm fit --data ${D} --out ${M} --min-features 10 --no-clusters)
run_ok(stylise rcm stylise --model ${M} ${IN} --valence 0.8 --arousal 0.5 --out ${WORK_DIR}/happy.bvh)
if(NOT last_output MATCHES "selected features targeted" OR NOT last_output MATCHES "Eq. 6 loss"
   OR NOT last_output MATCHES "output valence -?[01]\\.[0-9]+ arousal -?[01]\\.[0-9]+ quadrant [1-4]")
  message(FATAL_ERROR "rcm stylise printed:\n${last_output}")
endif()
message(STATUS "${last_output}")
if(NOT EXISTS ${WORK_DIR}/happy.bvh)
  message(FATAL_ERROR "rcm stylise did not write happy.bvh")
endif()
run_ok(info_out info ${WORK_DIR}/happy.bvh)
run_ok(stylise_rate rcm stylise --model ${M} ${IN} --valence -0.7 --arousal -0.6 --out ${WORK_DIR}/sad.bvh --frame-rate)

# bad input
run_fail(bad_valence rcm stylise --model ${M} ${IN} --valence 2 --arousal 0 --out ${WORK_DIR}/x.bvh)
expect_error_matches("--valence")
run_fail_file(missing_model ${WORK_DIR}/nomodel.json rcm stylise --model ${WORK_DIR}/nomodel.json ${IN} --valence 0 --arousal 0 --out ${WORK_DIR}/x.bvh)
run_fail(missing_input rcm stylise --model ${M} ${WORK_DIR}/none.bvh --valence 0 --arousal 0 --out ${WORK_DIR}/x.bvh)
expect_error_matches("none.bvh")
run_fail(no_out rcm stylise --model ${M} ${IN} --valence 0 --arousal 0)
expect_error_matches("--out")
