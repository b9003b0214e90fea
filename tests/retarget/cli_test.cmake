# `handemo transfer` and `handemo retarget` on a capture that is not handemo's skeleton (SMPL-X names, two hands),
# with the shipped hand model. Needs HANDEMO_CLI, MAKE_CAPTURE, CHECK (test_retarget_capture), WORK_DIR.
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(cap ${WORK_DIR}/gesture_smplx.bvh)
execute_process(COMMAND ${MAKE_CAPTURE} ${cap} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "make_capture failed")
endif()

# the right hand transferred with the shipped model (no --model), written back on the capture's skeleton
run_ok(transfer_right transfer --in ${cap} --hand right --emotion sad --out ${WORK_DIR}/sad.bvh)
if(NOT last_output MATCHES "using the shipped hand model" OR NOT last_output MATCHES "convention smpl -> model hand-embedded .handemo-hand.: right hand, relative to 'right_elbow'")
  message(FATAL_ERROR "transfer_right: output does not say which model and mapping it used:\n${last_output}")
endif()
execute_process(COMMAND ${CHECK} ${cap} ${WORK_DIR}/sad.bvh right RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the sad right hand changed channels outside the hand or the skeleton")
endif()
# the left hand, mirrored into the right-hand model and back
run_ok(transfer_left transfer --in ${cap} --hand left --emotion angry --out ${WORK_DIR}/angry_left.bvh)
if(NOT last_output MATCHES "left hand .mirrored.")
  message(FATAL_ERROR "transfer_left: not mirrored:\n${last_output}")
endif()
execute_process(COMMAND ${CHECK} ${cap} ${WORK_DIR}/angry_left.bvh left RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the angry left hand changed channels outside the hand or the skeleton")
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
