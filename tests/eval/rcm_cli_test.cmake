# `handemo eval` with the circumplex method (on by default when built) on a tiny synthetic set (hand-tiny, one
# fold, a few iterations, no change gate): its rows must be in results.csv next to the others, its section and
# per-clip CSV in the report, with the analysis chosen per fold (input and shrinkage); its options exclude --no-rcm,
# and a bad label table, analysis input or shrinkage fails with one line naming it.
# Variables: HANDEMO_CLI, WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/../cli_expect.cmake)

run_ok(synth synth --out ${WORK_DIR}/data --takes 1 --seed 2 --fps 30)
run_ok(eval eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/report --iters 4 --threads 1
       --folds patting --seed 3 --gate-folds 0 --rcm-iters 10 --rcm-min-features 8 --continuous)
if(NOT last_output MATCHES "eval: rcm: +rmse_real [0-9.]+" OR NOT last_output MATCHES "circumplex_quadrant [0-9.]+")
  message(FATAL_ERROR "eval --rcm printed:\n${last_output}")
endif()
foreach(f report.md results.csv summary.csv summary.svg rcm_regression.csv)
  if(NOT EXISTS ${WORK_DIR}/report/${f})
    message(FATAL_ERROR "eval --rcm did not write ${f}")
  endif()
endforeach()
file(STRINGS ${WORK_DIR}/report/results.csv rcm_rows REGEX ",rcm,")
list(LENGTH rcm_rows n)
if(NOT n EQUAL 4)
  message(FATAL_ERROR "results.csv has ${n} rcm rows, expected 4 (one neutral take x 4 targets)")
endif()
file(STRINGS ${WORK_DIR}/report/results.csv header LIMIT_COUNT 1)
if(NOT header MATCHES ",circumplex_quadrant_ok$")
  message(FATAL_ERROR "results.csv header lacks the circumplex columns: ${header}")
endif()
file(STRINGS ${WORK_DIR}/report/rcm_regression.csv reg)
list(LENGTH reg n)
if(NOT n EQUAL 6)
  message(FATAL_ERROR "rcm_regression.csv has ${n} lines, expected 6 (header + 5 held-out clips)")
endif()
file(READ ${WORK_DIR}/report/report.md md)
# --continuous with the circumplex method on: Spearman's rho of the grid's targets against its analysis, numbers
if(NOT md MATCHES "\\| all \\| 1 \\| 5 / 5 \\|[^\n]*\\| -?[01]\\.[0-9][0-9], -?[01]\\.[0-9][0-9] \\| -?[01]\\.[0-9][0-9], -?[01]\\.[0-9][0-9] \\|")
  message(FATAL_ERROR "report.md's continuous section has no Spearman numbers for the outputs and the real clips")
endif()
foreach(s "## Circumplex (Aristidou et al. 2017)" "| all | rcm |" "circumplex quadrant reached (%)" "**vs rcm**" "--rcm-iters 10"
          "rcm min_features 8" "rcm analysis input auto shrink auto" "| input, shrink |")
  string(FIND "${md}" "${s}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "report.md lacks '${s}'")
  endif()
endforeach()

run_fail(rcm_option_off eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --no-rcm --rcm-iters 3)
expect_error_matches("--rcm-iters.*--no-rcm|--no-rcm.*--rcm-iters")
run_fail(rcm_on_off eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --no-rcm --rcm)
expect_error_matches("--rcm")
run_fail(rcm_bad_input eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --rcm-input pca)
expect_error_matches("eval: --rcm-input pca is not paper, relative, clusters, judge or auto")
run_fail(rcm_bad_shrink eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad --rcm-shrink 2)
expect_error_matches("eval: --rcm-shrink 2 is not none, auto or a number")
file(WRITE ${WORK_DIR}/bad_labels.json "{\"format\": \"something-else\"}")
run_fail_file(rcm_bad_labels ${WORK_DIR}/bad_labels.json eval --data ${WORK_DIR}/data --config hand-tiny --report ${WORK_DIR}/bad
              --rcm --rcm-labels ${WORK_DIR}/bad_labels.json)
