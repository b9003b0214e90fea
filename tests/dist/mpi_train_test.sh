#!/usr/bin/env bash
# Data-parallel training across MPI processes (`handemo train --mpi`, dist/mpi.hpp): 2 processes of one thread each
# train bit for bit what `handemo train --shards 2 --threads 1` trains in one process, with the handemo preset (the change
# gate's inner trainings, EMA, one G step per D step), the paper preset (a G step every 5th D step) and a resumed
# run: checkpoint, generator, loss log, range and gate files byte for byte equal, and rank 1 prints nothing.
# 3 processes are refused before anything is written (a batch is cut into at most 2 parts).
# Usage: mpi_train_test.sh HANDEMO_CLI MPIEXEC WORK_DIR; exits 77 (skipped) without mpirun.
set -euo pipefail
name=mpi_train cli=$1 mpiexec=$2 work=$3
source "$(dirname "$0")/mpi_common.sh"
common=(--data "$work/data" --config hand-tiny --threads 1 --log-every 1 --exclude-content pointing --seed 5)

same() {  # same <what> <one-process folder> <two-process folder>
  local f
  for f in checkpoint.safetensors generator.safetensors log.csv range.json; do
    cmp "$2/$f" "$3/$f" || { echo "FAIL: $1: $f differs between 1 process x 2 shards and 2 processes"; exit 1; }
  done
  if [[ -d "$2/gate" ]]; then
    cmp "$2/gate/gate.csv" "$3/gate/gate.csv" || { echo "FAIL: $1: gate/gate.csv differs"; exit 1; }
  fi
  echo "$1: 2 processes equal 1 process x 2 shards byte for byte"
}
two() {  # two <log> <train arguments...>: `handemo train --mpi` on 2 processes; rank 0 alone prints the summary
  local log=$1
  shift
  "${launch[@]}" -np 2 "$cli" train --mpi "$@" >"$log" 2>&1 || { cat "$log"; echo "FAIL: mpirun -np 2 exited non-zero"; exit 1; }
  local done_lines
  done_lines=$(grep -c "iterations done" "$log" || true)
  [[ "$done_lines" == 1 ]] || { cat "$log"; echo "FAIL: $done_lines summaries printed (rank 0 alone prints)"; exit 1; }
}

# the handemo preset: the change gate (2 inner trainings, each shared across the processes), EMA, n_critic 1
"$cli" train "${common[@]}" --iters 4 --shards 2 --checkpoint-every 2 --out "$work/ref_handemo" >/dev/null 2>&1
two "$work/two_handemo.log" "${common[@]}" --iters 4 --checkpoint-every 2 --out "$work/two_handemo"
same "handemo preset" "$work/ref_handemo" "$work/two_handemo"

# the paper preset: G steps only every 5th D step; then resumed to 8 iterations (every process reads rank 0's checkpoint)
"$cli" train "${common[@]}" --preset paper --iters 6 --shards 2 --out "$work/ref_paper" >/dev/null 2>&1
two "$work/two_paper.log" "${common[@]}" --preset paper --iters 6 --out "$work/two_paper"
same "paper preset" "$work/ref_paper" "$work/two_paper"
"$cli" train "${common[@]}" --preset paper --iters 8 --shards 2 --resume --out "$work/ref_paper" >/dev/null 2>&1
two "$work/two_resume.log" "${common[@]}" --preset paper --iters 8 --resume --out "$work/two_paper"
same "paper preset, resumed" "$work/ref_paper" "$work/two_paper"

# 3 processes: refused by every process before anything is read or written, rank 0 says why
rc=0
"${launch[@]}" -np 3 "$cli" train --mpi "${common[@]}" --iters 2 --out "$work/three" >"$work/three.log" 2>&1 || rc=$?
if [[ $rc -eq 0 ]]; then cat "$work/three.log"; echo "FAIL: 3 processes were accepted"; exit 1; fi
grep -q "3 processes, but a batch of 16 is cut into at most 2 parts" "$work/three.log" ||
  { cat "$work/three.log"; echo "FAIL: no error naming the 3 processes"; exit 1; }
[[ ! -e "$work/three" ]] || { echo "FAIL: 3 processes wrote $work/three"; exit 1; }
echo "3 processes: refused (exit $rc) before writing anything"
