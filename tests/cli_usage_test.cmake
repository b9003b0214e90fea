# The CLI's exit codes and error lines, on commands that fail fast: usage errors (a missing required
# option, an unknown flag, no subcommand, a bad option value) and a file error exit 1 with one line
# "handemo: error: ..." (naming the file when there is one); --help and --version exit 0.
# Usage: cmake -DHANDEMO_CLI=<exe> -DDATA_DIR=<tests/formats/data> -DWORK_DIR=<dir> -P cli_usage_test.cmake
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/cli_expect.cmake)

run_ok(help --help)
run_ok(version --version)
run_ok(sub_help synth --help)

run_fail(missing_option synth --takes 1)                                  # --out is required (CLI11: 106)
expect_error_matches("--out")
run_fail(unknown_flag info ${DATA_DIR}/tiny.bvh --no-such-flag)           # CLI11: 109
expect_error_matches("--no-such-flag")
run_fail(unknown_subcommand frobnicate)
run_fail(no_subcommand)
run_fail(bad_value synth --out ${WORK_DIR}/s --takes many)                # CLI11: ConversionError
expect_error_matches("many")
run_fail_file(missing_file ${WORK_DIR}/missing.bvh info ${WORK_DIR}/missing.bvh)
file(WRITE ${WORK_DIR}/bad.bvh "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 7 Xposition\n}\n")
run_fail_file(bad_file ${WORK_DIR}/bad.bvh info ${WORK_DIR}/bad.bvh)
expect_error_matches(":5:")
message(STATUS "cli_usage: ok")
