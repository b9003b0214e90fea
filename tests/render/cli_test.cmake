# Runs the built `handemo` CLI: render / image / plot on small inputs must write their outputs and exit 0;
# bad input must exit 1 with exactly one line on stderr starting with "handemo: error:" (naming the file
# when one is involved).
# Variables: HANDEMO_CLI, DATA_DIR, WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)

function(expect_file path magic_hex)
  if(NOT EXISTS ${path})
    message(FATAL_ERROR "missing output ${path}")
  endif()
  file(READ ${path} head LIMIT 4 HEX)
  if(NOT head MATCHES "^${magic_hex}")
    message(FATAL_ERROR "${path} starts with ${head}, expected ${magic_hex}")
  endif()
endfunction()

run_ok(render render ${DATA_DIR}/arm.bvh ${DATA_DIR}/arm.bvh --titles "neutral,angry" --rows 3 --cell 64
       --out ${WORK_DIR}/strip.png)
expect_file(${WORK_DIR}/strip.png "89504e47")
run_ok(render_bmp render ${DATA_DIR}/arm.bvh --out ${WORK_DIR}/strip.bmp --cell 48 --rows 2)
expect_file(${WORK_DIR}/strip.bmp "424d")
run_ok(image image ${WORK_DIR}/strip.bmp --out ${WORK_DIR}/view.png --scale 2 --joints none)
expect_file(${WORK_DIR}/view.png "89504e47")
run_ok(plot plot ${DATA_DIR}/losses.csv --out ${WORK_DIR}/losses.svg)
file(READ ${WORK_DIR}/losses.svg svg)
string(REGEX MATCHALL "<polyline" lines "${svg}")
list(LENGTH lines n)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "losses.svg has ${n} polylines, expected 2")
endif()
run_ok(plot_bars plot ${DATA_DIR}/summary.csv --out ${WORK_DIR}/bars.svg)
file(READ ${WORK_DIR}/bars.svg svg)
if(NOT svg MATCHES "identity")
  message(FATAL_ERROR "bars.svg does not name the methods")
endif()

run_fail(render_titles render ${DATA_DIR}/arm.bvh --titles a,b --out ${WORK_DIR}/x.png)
run_fail_file(render_ext ${WORK_DIR}/x.jpg render ${DATA_DIR}/arm.bvh --out ${WORK_DIR}/x.jpg)
run_fail_file(render_not_bvh ${DATA_DIR}/losses.csv render ${DATA_DIR}/losses.csv --out ${WORK_DIR}/x.png)
run_fail_file(image_hand ${WORK_DIR}/strip.bmp image ${WORK_DIR}/strip.bmp --joints hand --out ${WORK_DIR}/x.png)
run_fail_file(image_not_image ${DATA_DIR}/arm.bvh image ${DATA_DIR}/arm.bvh --out ${WORK_DIR}/x.png)
run_fail_file(plot_bad ${DATA_DIR}/bad.csv plot ${DATA_DIR}/bad.csv --out ${WORK_DIR}/x.svg)
if(EXISTS ${WORK_DIR}/x.png OR EXISTS ${WORK_DIR}/x.svg)
  message(FATAL_ERROR "a failed command left an output file behind")
endif()
