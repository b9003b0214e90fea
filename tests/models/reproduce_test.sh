#!/usr/bin/env bash
# The shipped model's recipe reproduces itself: scripts/make_hand_model.sh run twice on a short training gives
# byte-identical checkpoints, and the shipped checkpoint loads as a hand-embedded model with its skeleton.
# Usage: reproduce_test.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
src=$1 build=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
for run in a b; do
  "$src/scripts/make_hand_model.sh" --build "$build" --out "$work/$run" --iters 4 > "$work/$run.log" 2>&1 ||
    { cat "$work/$run.log"; exit 1; }
done
cmp "$work/a/checkpoint.safetensors" "$work/b/checkpoint.safetensors"
echo "two short runs of the recipe: byte-identical checkpoints ($(stat -c %s "$work/a/checkpoint.safetensors") bytes)"
grep -q 'config.":."hand-embedded' "$src/data/models/hand-embedded/checkpoint.safetensors"
grep -q 'ROOT forearm' "$src/data/models/hand-embedded/checkpoint.safetensors"
echo "the shipped checkpoint is a hand-embedded model with its skeleton"
