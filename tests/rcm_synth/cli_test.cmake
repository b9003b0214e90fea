# `handemo rcm stylise` and `rcm path` on a tiny synthetic hand set (fit a model, stylise a sad take toward happy,
# then along sad -> neutral -> happy as a filmstrip), then
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

# `rcm path`: the same take along sad -> neutral -> happy, two columns per segment, as a filmstrip
run_ok(path rcm path --model ${M} ${IN} --path sad,neutral,happy --steps 2 --rows 2 --cell 48 --iters 20
       --out ${WORK_DIR}/strip.png --bvh-dir ${WORK_DIR}/path)
message(STATUS "${last_output}")
string(REGEX MATCHALL "step [0-9]+: target [^\n]*" steps "${last_output}")
list(LENGTH steps n)
if(NOT n EQUAL 5)
  message(FATAL_ERROR "rcm path printed ${n} steps, expected 5 (sad, between, neutral, between, happy):\n${last_output}")
endif()
foreach(s "step 0: target sad valence -0.72[0-9] arousal -0.37[0-9] quadrant 3 -> valence"
          "step 1: target \\(-0.30,-0.38\\) valence -0.30[0-9] arousal -0.38[0-9] quadrant 3"
          "step 2: target neutral valence 0.12[0-9]" "step 4: target happy valence 0.86[0-9] arousal 0.26[0-9] quadrant 1 -> valence"
          "wrote [^ ]*strip.png \\(([0-9]+)x([0-9]+), 6 clips x 2 frames\\)")
  if(NOT last_output MATCHES "${s}")
    message(FATAL_ERROR "rcm path output lacks '${s}':\n${last_output}")
  endif()
endforeach()
set(w ${CMAKE_MATCH_1})
set(h ${CMAKE_MATCH_2})
# the PNG's own header says the same size (IHDR width and height, big-endian, at byte 16)
file(READ ${WORK_DIR}/strip.png ihdr OFFSET 16 LIMIT 8 HEX)
string(SUBSTRING "${ihdr}" 0 8 wx)
string(SUBSTRING "${ihdr}" 8 8 hx)
math(EXPR pw "0x${wx}")
math(EXPR ph "0x${hx}")
if(NOT pw EQUAL w OR NOT ph EQUAL h OR pw LESS 288)
  message(FATAL_ERROR "strip.png is ${pw}x${ph}, the command said ${w}x${h} (6 columns of 48 px at least)")
endif()
foreach(k 00 01 02 03 04)
  if(NOT EXISTS ${WORK_DIR}/path/step${k}.bvh)
    message(FATAL_ERROR "rcm path --bvh-dir did not write step${k}.bvh")
  endif()
endforeach()
# explicit points, one column per waypoint, no input column
run_ok(path_points rcm path --model ${M} ${IN} "--path=-0.5:0.2,(0.6,0.3)" --steps 1 --rows 1 --cell 48 --iters 5 --no-input
       --out ${WORK_DIR}/points.bmp)
if(NOT last_output MATCHES "step 0: target \\(-0.50,0.20\\)" OR NOT last_output MATCHES "step 1: target \\(0.60,0.30\\)"
   OR NOT last_output MATCHES "2 clips x 1 frames")
  message(FATAL_ERROR "rcm path with points printed:\n${last_output}")
endif()

run_fail(path_label rcm path --model ${M} ${IN} --path sad,ecstatic --out ${WORK_DIR}/x.png)
expect_error_matches("waypoint 'ecstatic' is not a label .*known: .*happy")
run_fail(path_range rcm path --model ${M} ${IN} --path=0.5:1.5 --out ${WORK_DIR}/x.png)
expect_error_matches("outside \\[-1, 1\\]")
run_fail(path_steps rcm path --model ${M} ${IN} --path sad,happy --steps 0 --out ${WORK_DIR}/x.png)
expect_error_matches("--steps")
run_fail(path_ext rcm path --model ${M} ${IN} --path sad,happy --out ${WORK_DIR}/x.jpg)
expect_error_matches("x.jpg.*not .png or .bmp")
run_fail_file(path_model ${WORK_DIR}/nomodel.json rcm path --model ${WORK_DIR}/nomodel.json ${IN} --path sad --out ${WORK_DIR}/x.png)
