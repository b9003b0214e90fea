# `handemo transfer` and `handemo retarget` on a capture that is not handemo's skeleton (SMPL-X names, two hands),
# with the shipped hand model. Needs HANDEMO_CLI, MAKE_CAPTURE, CHECK (test_retarget_capture), EXAMPLE
# (handemo_example_transfer), SOURCE_DIR, WORK_DIR.
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(cap ${WORK_DIR}/gesture_smplx.bvh)
execute_process(COMMAND ${MAKE_CAPTURE} ${cap} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "make_capture failed")
endif()

# `transfer` of one hand: the output must say which model and mapping it used, and only that hand may change
function(transfer_hand name side emotion expect)
  run_ok(${name} transfer --in ${cap} --hand ${side} --emotion ${emotion} --out ${WORK_DIR}/${name}.bvh)
  if(NOT last_output MATCHES "using the shipped hand model" OR NOT last_output MATCHES "${expect}")
    message(FATAL_ERROR "${name}: output does not say which model and mapping it used (expected '${expect}'):\n${last_output}")
  endif()
  execute_process(COMMAND ${CHECK} ${cap} ${WORK_DIR}/${name}.bvh ${side} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: channels outside the ${side} hand or the skeleton changed")
  endif()
endfunction()
# the right hand with the shipped model (no --model), written back on the capture's skeleton
transfer_hand(sad right sad "convention smpl -> model hand-embedded .handemo-hand.: right hand, relative to 'right_elbow'")
# the left hand, mirrored into the right-hand model and back
transfer_hand(angry_left left angry "left hand .mirrored.")

# the README's 10-line example (examples/transfer.cpp) on the same capture with the shipped model
execute_process(COMMAND ${EXAMPLE} ${SOURCE_DIR}/data/models/hand-embedded ${cap} happy ${WORK_DIR}/example.bvh right
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "retargeted" OR NOT EXISTS ${WORK_DIR}/example.bvh)
  message(FATAL_ERROR "the README example on the capture failed (${rc}): ${out}${err}")
endif()
execute_process(COMMAND ${CHECK} ${cap} ${WORK_DIR}/example.bvh right RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the README example changed channels outside the right hand or the skeleton")
endif()

# two hands and no --hand
run_fail_file(two_hands ${cap} transfer --in ${cap} --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("has two hands, left \\('left_wrist'.*and right \\('right_wrist'.*pick one with --hand left or --hand right")
# a body without fingers
run_ok(to_body retarget --in ${cap} --to body --out ${WORK_DIR}/body.bvh)
run_fail(no_hand transfer --in ${WORK_DIR}/body.bvh --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("no hand recognised \\(tried conventions handemo-hand, bandai, cmu/mixamo, smpl, openxr, unreal; best match bandai")

# retarget alone, and its map file round trip
run_ok(to_hand retarget --in ${cap} --hand right --to hand --out ${WORK_DIR}/hand.bvh)
run_ok(back retarget --in ${WORK_DIR}/body.bvh --to ${cap} --out ${WORK_DIR}/back.bvh)
run_ok(print_map retarget --in ${cap} --print-map)
file(WRITE ${WORK_DIR}/map.json "${last_output}")
run_ok(with_map transfer --in ${cap} --map ${WORK_DIR}/map.json --hand right --emotion happy --out ${WORK_DIR}/happy.bvh)
# bad map files name the entry
file(WRITE ${WORK_DIR}/bad_joint.json "{\"joints\": {\"r.hand\": \"right_wrist\", \"r.index1\": \"no_such_joint\"}}")
run_fail_file(map_missing_joint ${WORK_DIR}/bad_joint.json transfer --in ${cap} --map ${WORK_DIR}/bad_joint.json --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("entry 'r.index1': skeleton '.*' has no joint 'no_such_joint'")
file(WRITE ${WORK_DIR}/bad_dup.json "{\"joints\": {\"r.hand\": \"right_wrist\", \"r.palm\": \"right_wrist\"}}")
run_fail_file(map_duplicate ${WORK_DIR}/bad_dup.json transfer --in ${cap} --map ${WORK_DIR}/bad_dup.json --emotion sad --out ${WORK_DIR}/x.bvh)
expect_error_matches("entry 'r.palm': joint 'right_wrist' is already the joint of entry 'r.hand'")

# the input and the output side by side in the viewer
run_ok(view view ${cap} ${WORK_DIR}/sad.bvh --out ${WORK_DIR}/view.html)
