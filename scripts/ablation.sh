#!/usr/bin/env bash
# The ablation of the handemo preset on the synthetic hand set (README, "Ablation"): the full leave-one-
# content-out evaluation once per variant, then one Markdown table of keyframe RMSE to the real clip (mean +- std
# over the 7 folds) and the share of (fold, target) pairs where the variant beats mean-offset.
# Usage: scripts/ablation.sh [OUT_DIR] [VARIANT ...]   (default OUT_DIR /tmp/handemo_ablation, all variants)
# Needs build/examples/handemo (the README's first command builds it). Each variant takes ~25 min (no-gate) to
# ~75 min (the change gate's three trainings per fold) on one core;
# two run at a time (one thread each).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/handemo_ablation}; shift || true
bin=build/examples/handemo
declare -A args=(
  [handemo]=""
  [paper]="--preset paper --iters 4000"
  [no-pair]="--lambda-pair 0"
  [no-residual]="--residual false --gate-folds 0"
  [no-gate]="--gate-folds 0"
  [no-augment]="--augment 0"
  [global-range]="--range global"
  [no-ema]="--ema 0"
  [no-id]="--lambda-id 0"
  [gate-no-rule]="--gate-margin -1"
  [gate-no-prior]="--gate-prior false"
  [gate-first]="--gate-prior false --gate-margin -1"
  [gate-fixed-margin]="--gate-auto-margin false"
  [gate-hits]="--gate-posterior false"
  [gate-previous]="--gate-auto-margin false --gate-posterior false"
)
# variants that only change the gate: the handemo variant's trained models with another gate (seconds each)
declare -A regate=([gate-no-rule]=1 [gate-no-prior]=1 [gate-first]=1 [gate-fixed-margin]=1 [gate-hits]=1 [gate-previous]=1)
variants=("$@")
if ((${#variants[@]} == 0)); then
  variants=(handemo paper no-gate no-pair no-residual no-augment global-range no-ema no-id gate-no-rule gate-no-prior gate-first gate-fixed-margin gate-hits gate-previous)
fi
mkdir -p "$out"
[[ -d "$out/data" ]] || "$bin" synth --out "$out/data" --takes 3 --seed 1 >/dev/null
run() {  # variant
  local v=$1
  [[ -f "$out/$v/summary.csv" ]] && return 0
  # shellcheck disable=SC2086
  "$bin" eval --data "$out/data" --config hand-embedded --report "$out/$v" --threads 1 --synth-seed 1 ${args[$v]} \
    >"$out/$v.log" 2>&1
}
running=0
for v in "${variants[@]}"; do
  [[ -n "${args[$v]+x}" ]] || { echo "ablation: unknown variant '$v' (known: ${!args[*]})" >&2; exit 1; }
  [[ -n "${regate[$v]+x}" ]] && continue
  run "$v" & running=$((running + 1))
  if ((running == 2)); then wait -n; running=$((running - 1)); fi
done
wait
for v in "${variants[@]}"; do
  [[ -n "${regate[$v]+x}" && ! -f "$out/$v/summary.csv" ]] || continue
  [[ -f "$out/handemo/summary.csv" ]] || run handemo
  rm -rf "$out/$v" && cp -r "$out/handemo" "$out/$v"
  # shellcheck disable=SC2086
  "$bin" eval --data "$out/data" --config hand-embedded --report "$out/$v" --threads 1 --synth-seed 1 --reuse-models ${args[$v]} \
    >"$out/$v.log" 2>&1
done
echo "| variant | options | RMSE to real (deg) | G alone (deg) | identity | mean-offset | pairs beating mean-offset |"
echo "|---|---|---|---|---|---|---|"
for v in "${variants[@]}"; do
  s="$out/$v/summary.csv"; r="$out/$v/report.md"
  [[ -f "$s" ]] || continue
  get() { awk -F, -v m="$1" '$1=="all" && $2==m && $3=="rmse_real" {printf "%.2f +- %.2f", $4, $5}' "$s"; }
  pairs=$(grep -A2 '^\*\*vs mean-offset\*\*' "$r" | grep -o 'lower in [0-9]* of [0-9]* ([0-9]*%)' | head -1)
  g=$(get stargan-g); [[ -n "$g" ]] || g="(no amplitude stage)"
  echo "| $v | \`${args[$v]:-(defaults)}\` | $(get stargan) | $g | $(get identity) | $(get mean-offset) | ${pairs#lower in } |"
done
