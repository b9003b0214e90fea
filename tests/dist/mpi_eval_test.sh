#!/usr/bin/env bash
# The evaluation's trainings dealt over MPI processes (`handemo eval --mpi`: eval/schedule.hpp run_training_waves(),
# dist/mpi.hpp mpi_group). With 2 processes and with 3 (--jobs 2 each), the report folder holds byte for byte what
# one process writes: every model (the change gate's shared inner models, each fold's final G), each fold's gate and
# loss log, results.csv and summary.csv, and again with --reuse-models over the finished folder; rank 0 alone prints
# and writes the report. An error in one process ends all of them (the folder one fold's model goes to is a file: the
# process that trains that fold fails, and no process waits for it). `mpirun -np 2 handemo eval` without --mpi is
# refused before anything is written.
# Usage: mpi_eval_test.sh HANDEMO_CLI MPIEXEC WORK_DIR; exits 77 (skipped) without mpirun.
set -euo pipefail
name=mpi_eval cli=$1 mpiexec=$2 work=$3
source "$(dirname "$0")/mpi_common.sh"
# 4 folds of 7 contents: 6 inner models of the shared plan and 4 final Gs, in two waves
common=(--data "$work/data" --config hand-tiny --threads 1 --iters 4 --seed 5 --no-rcm --no-retargeted
        --folds crawling,gripping,patting,pointing)

"$cli" eval "${common[@]}" --report "$work/one" >"$work/one.log" 2>&1 || { cat "$work/one.log"; echo "FAIL: one process"; exit 1; }

same() {  # same <what> <report folder>: every file of one process's report but report.md (timings, command) is equal
  local f n=0
  while IFS= read -r f; do
    [[ "$f" == report.md ]] && continue
    [[ -f "$2/$f" ]] || { echo "FAIL: $1: $f is missing"; exit 1; }
    cmp "$work/one/$f" "$2/$f" || { echo "FAIL: $1: $f differs from one process's"; exit 1; }
    n=$((n + 1))
  done < <(cd "$work/one" && find . -type f -printf '%P\n' | sort)
  local extra
  extra=$(comm -13 <(cd "$work/one" && find . -type f -printf '%P\n' | sort) <(cd "$2" && find . -type f -printf '%P\n' | sort))
  [[ -z "$extra" ]] || { echo "FAIL: $1: files one process does not write: $extra"; exit 1; }
  echo "$1: $n files equal to one process's byte for byte ($(cd "$2" && find . -name '*.safetensors' | wc -l) models)"
}
run() {  # run <np> <log> <eval arguments...>: `handemo eval --mpi` on np processes; rank 0 alone prints
  local np=$1 log=$2
  shift 2
  "${launch[@]}" -np "$np" "$cli" eval --mpi "$@" >"$log" 2>&1 || { cat "$log"; echo "FAIL: mpirun -np $np exited non-zero"; exit 1; }
  local lines
  lines=$(grep -c "^eval: 4 folds, " "$log" || true)
  [[ "$lines" == 1 ]] || { cat "$log"; echo "FAIL: $lines summaries printed (rank 0 alone prints)"; exit 1; }
  lines=$(grep -c "^eval: fold 1/4: holding out" "$log" || true)
  [[ "$lines" == 1 ]] || { cat "$log"; echo "FAIL: $lines progress lines for fold 1 (rank 0 alone prints)"; exit 1; }
}
waves() {  # waves <log>: the inner models and the final Gs were trained in two waves
  grep -q "^eval: wave 2 of 2 done on every process" "$1" || { cat "$1"; echo "FAIL: no second wave"; exit 1; }
}

run 2 "$work/two.log" "${common[@]}" --report "$work/two"
waves "$work/two.log"
same "2 processes" "$work/two"
# again over the finished folder with --reuse-models: every process plans no training, the same files
run 2 "$work/reuse.log" "${common[@]}" --reuse-models --report "$work/two"
grep -q "^eval: training 0 models" "$work/reuse.log" || { cat "$work/reuse.log"; echo "FAIL: --reuse-models trained again"; exit 1; }
same "2 processes, --reuse-models" "$work/two"
run 3 "$work/three.log" "${common[@]}" --jobs 2 --report "$work/three"
waves "$work/three.log"
same "3 processes, --jobs 2" "$work/three"
grep -q "^processes 3 " "$work/three/report.md" || { echo "FAIL: the report does not name the 3 processes"; exit 1; }

# an error in one process: the folder of the second fold's model (process 1's) is a file; every process ends
mkdir -p "$work/broken/folds"
touch "$work/broken/folds/gripping"
rc=0
timeout 120 "${launch[@]}" -np 2 "$cli" eval --mpi "${common[@]}" --report "$work/broken" >"$work/broken.log" 2>&1 || rc=$?
if [[ $rc -eq 0 || $rc -eq 124 ]]; then cat "$work/broken.log"; echo "FAIL: a failing process gave exit $rc (124: the others hung)"; exit 1; fi
grep -q "folds/gripping" "$work/broken.log" || { cat "$work/broken.log"; echo "FAIL: the error does not name the fold's folder"; exit 1; }
[[ ! -e "$work/broken/results.csv" ]] || { echo "FAIL: a report was written after the error"; exit 1; }
echo "an error in process 1: every process ended (exit $rc), no report"

# 2 processes without --mpi would each run the whole evaluation into one folder: refused before anything is written
rc=0
"${launch[@]}" -np 2 "$cli" eval "${common[@]}" --report "$work/nompi" >"$work/nompi.log" 2>&1 || rc=$?
if [[ $rc -eq 0 ]]; then cat "$work/nompi.log"; echo "FAIL: 2 processes without --mpi were accepted"; exit 1; fi
grep -q "without --mpi" "$work/nompi.log" || { cat "$work/nompi.log"; echo "FAIL: no error naming --mpi"; exit 1; }
[[ ! -e "$work/nompi" ]] || { echo "FAIL: 2 processes without --mpi wrote $work/nompi"; exit 1; }
echo "2 processes without --mpi: refused (exit $rc) before writing anything"
