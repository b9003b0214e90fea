#!/usr/bin/env bash
# Fetches the Bandai-Namco Research Motion Dataset 1 (real captured bodies, one actor, the same contents in
# different styles) for training and evaluating body models: the BVH clips and their labels of the 8 styles the
# body-embedded configuration knows (normal, happy, sad, angry, proud, not-confident, tired, active) and 7
# contents (walk, run, dash, walk-back, bow, bye, walk-left), into DIR/bandai.
# The dataset is licensed CC BY-NC 4.0 (non-commercial): the script shows the licence and asks before anything
# is downloaded (--accept-licence skips the question). Cite: Kobayashi et al., "Motion Capture Dataset for
# Practical Use of AI-based Motion Editing and Stylization", arXiv:2306.08861, 2023.
# Usage: scripts/fetch_bandai.sh DIR [--accept-licence]
# Then:  build/examples/handemo train --data DIR/bandai --config body-embedded --out body-model
set -euo pipefail
repo=${HANDEMO_BANDAI_REPO:-https://github.com/BandaiNamcoResearchInc/Bandai-Namco-Research-Motiondataset.git}
sub=dataset/Bandai-Namco-Research-Motiondataset-1
styles=(normal happy sad angry proud not-confident tired active)
contents=(walk run dash walk-back bow bye walk-left)
dir=${1:-}
accept=0
[[ ${2:-} == --accept-licence ]] && accept=1
if [[ -z $dir || $dir == -* ]]; then
  echo "usage: $0 DIR [--accept-licence]" >&2
  exit 2
fi
cat <<'TXT'
Bandai-Namco Research Motion Dataset 1, (c) Bandai Namco Research Inc.
Licence: Creative Commons Attribution-NonCommercial 4.0 International (CC BY-NC 4.0),
https://creativecommons.org/licenses/by-nc/4.0/ : you may share and adapt it for non-commercial purposes,
with attribution. The full licence text is copied next to the data as LICENSE.
TXT
if ((!accept)); then
  read -r -p "Download it under these terms? [y/N] " ans
  [[ $ans == y || $ans == Y ]] || { echo "fetch_bandai.sh: nothing downloaded" >&2; exit 1; }
fi
command -v git >/dev/null || { echo "fetch_bandai.sh: needs git (apt-get install git)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
git clone --quiet --depth 1 --filter=blob:none --sparse "$repo" "$tmp/repo"
git -C "$tmp/repo" sparse-checkout set --no-cone "/$sub/data/" "/$sub/cfg/" "/$sub/LICENSE" "/$sub/README.md"
mkdir -p "$dir/bandai.tmp"
n=0
for c in "${contents[@]}"; do
  for s in "${styles[@]}"; do
    for f in "$tmp/repo/$sub/data/dataset-1_${c}_${s}_"*.bvh; do
      [[ -e $f ]] || continue
      cp "$f" "$dir/bandai.tmp/"
      [[ -e ${f%.bvh}.json ]] && cp "${f%.bvh}.json" "$dir/bandai.tmp/"
      n=$((n + 1))
    done
  done
done
cp "$tmp/repo/$sub/LICENSE" "$tmp/repo/$sub/README.md" "$dir/bandai.tmp/"
cp "$tmp/repo/$sub/cfg/"*.txt "$dir/bandai.tmp/"
rm -rf "$dir/bandai"
mv "$dir/bandai.tmp" "$dir/bandai"
echo "fetch_bandai.sh: $n clips in $dir/bandai (licence: $dir/bandai/LICENSE)"
