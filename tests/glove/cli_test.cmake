# `handemo glove` through the built CLI, without hardware: list (no devices here: one clear line), simulate
# a glove into a raw stream with lost and malformed reports, record from the replay (counts in the summary,
# a valid BVH), record --raw and replay the copy, calibrate a flex glove (flat + fist) and record with it,
# live transfer with a 2-iteration hand-tiny model, and the one-line errors.
# Usage: cmake -DHANDEMO_CLI=<exe> -DPROFILES=<examples/glove> -DWORK_DIR=<dir> -P cli_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(W "${WORK_DIR}")
set(IMU "${PROFILES}/imu7_example.json")
set(FLEX "${PROFILES}/flex15_example.json")

function(expect_output re)
  if(NOT last_output MATCHES "${re}")
    message(FATAL_ERROR "output does not match '${re}':\n${last_output}")
  endif()
endfunction()

run_ok(list glove list)
if(NOT last_output MATCHES "no HID devices found|usage [0-9a-f]+:[0-9a-f]+")
  message(FATAL_ERROR "glove list printed neither devices nor the 'no HID devices found' line:\n${last_output}")
endif()

run_ok(simulate glove simulate --profile ${IMU} --out ${W}/imu.raw --seconds 3 --drop-every 50 --garbage-every 70)
expect_output("393 reports at 100 Hz .* 7 dropped, 5 garbage")
run_ok(record glove record --profile ${IMU} --replay ${W}/imu.raw --out ${W}/take.bvh --raw ${W}/copy.raw)
expect_output("393 samples \\(3.99 s, 98.2 Hz\\) -> .*take.bvh: 240 frames at 60 fps; dropped reports 7, malformed 5 \\(short 2, unknown id 2, non-unit quaternion 1\\)")
run_ok(info info ${W}/take.bvh)
expect_output("joints: 23 .*frames: 240, fps: 60")
# the --raw copy replays to the same take
run_ok(record_copy glove record --profile ${IMU} --replay ${W}/copy.raw --out ${W}/take2.bvh)
expect_output("393 samples .* 240 frames at 60 fps; dropped reports 7, malformed 5")
file(READ ${W}/take.bvh a)
file(READ ${W}/take2.bvh b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "the replayed --raw copy gives another BVH")
endif()
run_ok(record_seconds glove record --profile ${IMU} --replay ${W}/imu.raw --out ${W}/short.bvh --seconds 1 --fps 30)
expect_output("-> .*short.bvh: 31 frames at 30 fps")

run_ok(simulate_flex glove simulate --profile ${FLEX} --out ${W}/flex.raw --motion crawling --seconds 2)
run_ok(calibrate glove calibrate --profile ${FLEX} --replay ${W}/flex.raw --out ${W}/calib.json)
expect_output("90 flat and 90 fist samples")
run_ok(record_flex glove record --profile ${FLEX} --replay ${W}/flex.raw --calib ${W}/calib.json --out ${W}/flex.bvh)
expect_output("360 samples \\(3.99 s, 90.0 Hz\\)")

run_ok(synth synth --out ${W}/data --takes 1)
run_ok(train train --data ${W}/data --config hand-tiny --iters 2 --out ${W}/model --threads 1)
run_ok(live glove live --model ${W}/model --emotion angry --profile ${IMU} --replay ${W}/imu.raw --out ${W}/rolling.bvh --window 1 --every 0.5)
expect_output("glove live: 7 windows of 1.0 s transferred to angry -> .*rolling.bvh; latency from report to output mean")
run_ok(info_rolling info ${W}/rolling.bvh)
expect_output("joints: 23")
run_ok(live_print glove live --model ${W}/model --emotion sad --profile ${IMU} --replay ${W}/imu.raw --print --seconds 2)
expect_output("t=1.01 latency=[0-9.]+ms forearm=")

run_fail(bad_profile glove record --profile ${W}/take.bvh --replay ${W}/imu.raw --out ${W}/x.bvh)
expect_error_matches("glove profile: .*take.bvh: .*parse error")
run_fail(not_raw glove record --profile ${IMU} --replay ${W}/take.bvh --out ${W}/x.bvh)
expect_error_matches("not a raw glove stream")
run_fail(no_device glove record --profile ${IMU} --out ${W}/x.bvh)
expect_error_matches("has no vendor/product id: give --device")
run_fail(missing_device glove record --profile ${IMU} --device 1234:abcd --out ${W}/x.bvh)
expect_error_matches("no HID device 1234:abcd")
# a replay of another glove: warnings on the way, then the error as the last line, and no file
execute_process(COMMAND ${HANDEMO_CLI} glove record --profile ${FLEX} --replay ${W}/imu.raw --out ${W}/x.bvh
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "glove: warning: report 1 skipped: report id 1 is not in the profile"
   OR NOT err MATCHES "\nhandemo: error: glove record: .*no complete samples in 398 reports \\(398 malformed \\(unknown id 398\\)\\); nothing written\n$"
   OR EXISTS ${W}/x.bvh)
  message(FATAL_ERROR "wrong_glove: exit ${rc}\n${err}")
endif()
run_fail(calib_other glove record --profile ${IMU} --calib ${W}/calib.json --replay ${W}/imu.raw --out ${W}/x.bvh)
expect_error_matches("made for profile 'flex15-example'")
run_fail(live_emotion glove live --model ${W}/model --emotion furious --profile ${IMU} --replay ${W}/imu.raw --print)
expect_error_matches("unknown emotion 'furious'")
run_fail(live_no_output glove live --model ${W}/model --emotion sad --profile ${IMU} --replay ${W}/imu.raw)
expect_error_matches("give --out rolling.bvh or --print")
file(REMOVE_RECURSE "${WORK_DIR}")
