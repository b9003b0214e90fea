# CTest driver for `handemo info`: runs the built CLI on good files (BVH, CSV with --skeleton, PNG, JSON)
# and on bad ones (malformed BVH, unknown extension, CSV without skeleton, missing file), checking the
# exit code, the output and that an error is exactly one line `handemo: error: ...`.
# Usage: cmake -DHANDEMO_CLI=<exe> -DDATA_DIR=<tests/formats/data> -DSHARED_DIR=<../shared> -DWORK_DIR=<dir> -P info_cli_test.cmake
foreach(v HANDEMO_CLI DATA_DIR SHARED_DIR WORK_DIR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "info_cli_test: -D${v}=... is required")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

function(expect_ok name)  # expect_ok(<name> <regex>... ARGS <cli args>...)
  cmake_parse_arguments(E "" "" "MATCH;ARGS" ${ARGN})
  execute_process(COMMAND "${HANDEMO_CLI}" info ${E_ARGS} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: exit ${rc}, expected 0\nstdout: ${out}\nstderr: ${err}")
  endif()
  foreach(re IN LISTS E_MATCH)
    if(NOT out MATCHES "${re}")
      message(FATAL_ERROR "${name}: output does not match '${re}':\n${out}")
    endif()
  endforeach()
  message(STATUS "${name}: ok")
endfunction()

function(expect_error name re)  # expect_error(<name> <stderr regex> <cli args>...)
  execute_process(COMMAND "${HANDEMO_CLI}" info ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc STREQUAL "1")
    message(FATAL_ERROR "${name}: exit '${rc}', expected 1 (the README: every failure exits 1)\nstdout: ${out}")
  endif()
  string(REGEX REPLACE "\n$" "" line "${err}")
  if(line MATCHES "\n" OR NOT line MATCHES "^handemo: error: ")
    message(FATAL_ERROR "${name}: stderr is not one 'handemo: error:' line:\n${err}")
  endif()
  if(NOT line MATCHES "${re}")
    message(FATAL_ERROR "${name}: stderr does not match '${re}':\n${err}")
  endif()
  if(NOT out STREQUAL "")
    message(FATAL_ERROR "${name}: printed a partial description on failure:\n${out}")
  endif()
  message(STATUS "${name}: ok (${line})")
endfunction()

expect_ok(xia_bvh ARGS "${SHARED_DIR}/data/xia/neutral_16_000.bvh"
  MATCH "format: BVH" "joints: 31 \\(Hips, " "1 joint x 6 \\(Xposition Yposition Zposition Zrotation Yrotation Xrotation\\)"
        "30 joints x 3 \\(Zrotation Yrotation Xrotation\\)" "frames: 150, fps: 120, duration: 1.250 s" "angle range \\(deg\\): x \\[")
expect_ok(tiny_bvh ARGS "${DATA_DIR}/tiny.bvh"
  MATCH "joints: 2 \\(Hips, Left_Arm\\)" "end sites: 1" "frames: 2, fps: 30"
        "x \\[-8.000, 8.000\\] y \\[-9.250, 9.000\\] z \\[-7.000, 7.000\\]")
expect_ok(tiny_csv ARGS "${DATA_DIR}/tiny.csv" --skeleton "${DATA_DIR}/tiny.bvh"
  MATCH "format: CSV" "frames: 2, fps: 30" "y \\[-9.250, 9.000\\]")
expect_ok(png ARGS "${DATA_DIR}/motion_23x9.png"
  MATCH "format: PNG" "size: 23x9 \\(width x height\\)" "channels: 3" "pixel range: R \\[10, 209\\]")
file(WRITE "${WORK_DIR}/range.json" "{\"p_min\": -180, \"p_max\": 180, \"per_joint\": [[1, 2], [3, -4]]}")
expect_ok(json ARGS "${WORK_DIR}/range.json"
  MATCH "p_min: -180" "p_max: 180" "per_joint: array\\[2\\] of 4 numbers in \\[-4.0000, 3.0000\\]")

file(WRITE "${WORK_DIR}/bad.bvh" "HIERARCHY\nROOT a\n{\n  OFFSET 0 0 0\n  CHANNELS 7 Xrotation\n")
expect_error(bad_bvh "bad.bvh:5: CHANNELS 7 is not 3 or 6" "${WORK_DIR}/bad.bvh")
file(WRITE "${WORK_DIR}/notes.xyz" "hello")
expect_error(unknown_ext "unknown file type '.xyz'" "${WORK_DIR}/notes.xyz")
expect_error(csv_without_skeleton "needs --skeleton" "${DATA_DIR}/tiny.csv")
expect_error(missing_file "cannot open .*missing.bvh" "${WORK_DIR}/missing.bvh")
file(WRITE "${WORK_DIR}/bad.json" "{\"p_min\": ")
expect_error(bad_json "json: .*bad.json: .*parse error" "${WORK_DIR}/bad.json")
file(REMOVE_RECURSE "${WORK_DIR}")
