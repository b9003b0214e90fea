#!/usr/bin/env bash
# Makes the hand model handemo ships in data/models/hand-embedded, the one `handemo transfer` uses without
# --model: the synthetic hand set (3 takes of every motion and emotion, seed 1, 60 fps) and `handemo train` with
# its defaults (configuration hand-embedded, preset handemo, 4000 iterations, seed 1) on 2 data-parallel shards,
# which give the same weights on 1, 2 or 3 threads. A rerun with the same build reproduces the checkpoint bit for
# bit (the test model_reproduce checks that on a short run); another instruction set (AVX2 against AVX-512) may
# differ in the last bits of the weights.
# Usage: scripts/make_hand_model.sh [--build DIR] [--out DIR] [--iters N]   (about 20 minutes on 2 cores)
set -euo pipefail
build=build
out=data/models/hand-embedded
iters=4000
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --iters) iters=$2; shift 2 ;;
    *) echo "usage: $0 [--build DIR] [--out DIR] [--iters N]" >&2; exit 2 ;;
  esac
done
cli=$build/examples/handemo
[[ -x $cli ]] || { echo "make_hand_model.sh: no $cli: build the project first" >&2; exit 1; }
cli=$(realpath "$cli")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# run inside the work folder, so that the data folder's name in the loss plot's title is "data", not a temporary path
(cd "$work" && "$cli" synth --out data --takes 3 --seed 1 >/dev/null &&
  "$cli" train --data data --out model --config hand-embedded --iters "$iters" --seed 1 --shards 2 --checkpoint-every "$iters")
mkdir -p "$out"
# the inference part only (metadata and the EMA generator's weights, stored as binary16): what transfer reads
"$cli" export --inference "$work/model" --half --out "$out/checkpoint.safetensors"
cp "$work/model/losses.svg" "$out/losses.svg.tmp"
mv "$out/losses.svg.tmp" "$out/losses.svg"
echo "make_hand_model.sh: wrote $out/checkpoint.safetensors and $out/losses.svg"
