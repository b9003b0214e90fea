#!/usr/bin/env bash
# Crash safety of what `handemo train` keeps: kills a training run with SIGKILL at several points while it
# trains and writes a checkpoint every iteration, then requires that
#   - the checkpoint left behind (if any) is whole: `handemo transfer` loads it,
#   - `train --resume` from it ends bitwise equal (checkpoint and generator) to an uninterrupted run.
# Usage: kill_test.sh HANDEMO_CLI WORK_DIR
set -euo pipefail
cli=$1
work=$2
iters=8
rm -rf "$work"
mkdir -p "$work"
train=(train --data "$work/data" --config hand-tiny --iters $iters --threads 1 --checkpoint-every 1 --log-every 1
       --exclude-content pointing --seed 5)
"$cli" synth --out "$work/data" --takes 1 --seed 3 >/dev/null

start=$(date +%s%N)
"$cli" "${train[@]}" --out "$work/ref" >/dev/null
total_ms=$(( ($(date +%s%N) - start) / 1000000 ))
echo "uninterrupted run: ${total_ms} ms"

checked=0
killed_mid=0
# after a kill of the run into $1 (described by $2): the checkpoint left behind loads, and --resume (or a
# restart when none was written yet) ends bitwise equal to the uninterrupted run
check_after_kill() {
  local out=$1 what=$2 how=restarted
  if [[ -f "$out/checkpoint.safetensors" ]]; then
    how=resumed
    # the checkpoint left behind by the killed run loads
    if ! "$cli" transfer --model "$out" --in "$work/data/hand_pointing_neutral_0.bvh" --emotion sad \
         --out "$out/probe.bvh" >/dev/null 2>"$out/probe.err"; then
      echo "kill ${what}: the checkpoint left behind does not load: $(cat "$out/probe.err")"
      exit 1
    fi
    "$cli" "${train[@]}" --out "$out" --resume >/dev/null
    checked=$((checked + 1))
  else
    "$cli" "${train[@]}" --out "$out" >/dev/null  # killed before the first checkpoint: start again
  fi
  for f in checkpoint.safetensors generator.safetensors; do
    if ! cmp -s "$work/ref/$f" "$out/$f"; then
      echo "kill ${what}: $f after --resume differs from the uninterrupted run"
      exit 1
    fi
  done
  echo "kill ${what}: ${how}, bitwise equal"
}
for pct in 15 45 75 95; do
  out="$work/kill_$pct"
  delay_ms=$(( total_ms * pct / 100 ))
  "$cli" "${train[@]}" --out "$out" >/dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  if kill -KILL "$pid" 2>/dev/null; then killed_mid=$((killed_mid + 1)); fi
  wait "$pid" 2>/dev/null || true
  check_after_kill "$out" "at ${delay_ms} ms (${pct}%)"
done
# The change gate's inner trainings and scoring come first and the final training writes its checkpoints only
# in the last part of the run, a window that timed kills can miss on a loaded machine: one more kill lands in
# it for sure, as soon as the first checkpoint of the final training is on disk.
out="$work/kill_ck"
"$cli" "${train[@]}" --out "$out" >/dev/null 2>&1 &
pid=$!
while kill -0 "$pid" 2>/dev/null && [[ ! -f "$out/checkpoint.safetensors" ]]; do sleep 0.002; done
if kill -KILL "$pid" 2>/dev/null; then killed_mid=$((killed_mid + 1)); fi
wait "$pid" 2>/dev/null || true
check_after_kill "$out" "at the first checkpoint"
if ((killed_mid == 0 || checked == 0)); then
  echo "no run was killed while training with a checkpoint on disk (machine too fast or too slow?)"
  exit 1
fi
echo "kill_test: ${killed_mid} runs killed, ${checked} resumed from the checkpoint left behind, all bitwise equal"
