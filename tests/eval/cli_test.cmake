# Runs the built `handemo eval` on a tiny synthetic set: hand-tiny, two folds, a few iterations; the report
# files must exist with one CSV row per (fold, target, take, method); bad input must fail with one line.
# `--no-rcm` (accepted whether or not the circumplex method is built) keeps the rows to StarGAN's and the
# baselines'; rcm_cli_test.cmake tests the circumplex rows.
# Variables: HANDEMO_CLI, WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)

run_ok(synth synth --out ${WORK_DIR}/data --takes 1 --seed 2)
run_ok(eval eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/report --iters 8 --threads 1
       --folds patting,gripping --seed 3 --synth-seed 2 --no-rcm)
foreach(f report.md results.csv summary.csv summary.svg folds/patting/checkpoint.safetensors folds/gripping/losses.svg)
  if(NOT EXISTS ${WORK_DIR}/report/${f})
    message(FATAL_ERROR "eval did not write ${f}")
  endif()
endforeach()
file(STRINGS ${WORK_DIR}/report/results.csv rows)
list(LENGTH rows n)
file(STRINGS ${WORK_DIR}/report/results.csv ungated REGEX ",stargan-ungated,")
list(LENGTH ungated nu)
# header + 2 folds x 4 targets x 1 take x 10 methods (stargan, stargan+detail, stargan-g, identity, mean-offset,
# amplitude-only, statistics, nearest-neighbour, real, and the oracle: --synth-seed), plus stargan-ungated (4 rows)
# in each fold whose change gate is not all 1
math(EXPR expect "81 + ${nu}")
if(NOT n EQUAL expect OR NOT (nu EQUAL 0 OR nu EQUAL 4 OR nu EQUAL 8))
  message(FATAL_ERROR "results.csv has ${n} lines with ${nu} stargan-ungated rows, expected 81 + those (0, 4 or 8)")
endif()
foreach(f patting gripping)
  if(NOT EXISTS ${WORK_DIR}/report/folds/${f}/gate/gate.csv)
    message(FATAL_ERROR "eval did not fit the change gate in fold ${f}")
  endif()
endforeach()
file(READ ${WORK_DIR}/report/report.md md)
foreach(s "### held out: patting" "### held out: gripping" "Where StarGAN beats each baseline" "--folds" "Partial report"
          "| all | statistics |" "**vs statistics**" "duration ratio error")
  string(FIND "${md}" "${s}" at)
  if(s STREQUAL "Partial report")
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "a finished run's report.md says it is partial")
    endif()
  elseif(at EQUAL -1)
    message(FATAL_ERROR "report.md lacks '${s}'")
  endif()
endforeach()

run_fail(eval_config eval --data ${WORK_DIR}/data --config hand-huge --report ${WORK_DIR}/bad)
expect_error_matches("unknown configuration 'hand-huge'")
run_fail(eval_synth_seed eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --synth-seed 5)
expect_error_matches("--synth-seed 5 at 60.000000 fps does not reproduce")
run_fail(eval_fold eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --folds swimming)
expect_error_matches("content 'swimming' is not in the data set")
run_fail(eval_data eval --data ${WORK_DIR}/missing --config hand-tiny --report ${WORK_DIR}/bad)
expect_error_matches("is not a folder")
run_fail(eval_body_on_hand eval --data ${WORK_DIR}/data --config body-embedded --report ${WORK_DIR}/bad --iters 1)
