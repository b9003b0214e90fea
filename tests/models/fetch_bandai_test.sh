#!/usr/bin/env bash
# scripts/fetch_bandai.sh against a local stand-in of the dataset's repository (files of our own with the
# dataset's layout and names): nothing is fetched without the licence accepted; with it, only the styles and
# contents the body configuration knows land in DIR/bandai, with the licence beside them.
# Usage: fetch_bandai_test.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$1 work=$2
command -v git >/dev/null || { echo "git not installed: skipped"; exit 77; }
rm -rf "$work"
mkdir -p "$work/origin/dataset/Bandai-Namco-Research-Motiondataset-1/data" "$work/origin/dataset/Bandai-Namco-Research-Motiondataset-1/cfg"
d=$work/origin/dataset/Bandai-Namco-Research-Motiondataset-1
for f in dataset-1_bow_sad_001 dataset-1_walk_normal_002 dataset-1_bow_giant_001 dataset-1_call_normal_001; do
  echo "stand-in $f" > "$d/data/$f.bvh"
  echo '{}' > "$d/data/$f.json"
done
echo "stand-in licence" > "$d/LICENSE"; echo "stand-in readme" > "$d/README.md"; echo "a" > "$d/cfg/style_label.txt"
git -C "$work/origin" init -q && git -C "$work/origin" add -A && git -C "$work/origin" -c user.email=t@t -c user.name=t commit -qm data
export HANDEMO_BANDAI_REPO=file://$work/origin
if echo n | "$src/scripts/fetch_bandai.sh" "$work/out" > "$work/refused.log" 2>&1; then
  echo "FAIL: fetched without the licence accepted"; exit 1
fi
grep -q "CC BY-NC 4.0" "$work/refused.log" || { echo "FAIL: the licence was not shown"; exit 1; }
[[ ! -e $work/out/bandai ]] || { echo "FAIL: files written although refused"; exit 1; }
"$src/scripts/fetch_bandai.sh" "$work/out" --accept-licence
ls "$work/out/bandai" | sort > "$work/got.txt"
printf '%s\n' LICENSE README.md dataset-1_bow_sad_001.bvh dataset-1_bow_sad_001.json dataset-1_walk_normal_002.bvh \
  dataset-1_walk_normal_002.json style_label.txt | sort > "$work/want.txt"
diff "$work/want.txt" "$work/got.txt"
echo "fetch_bandai.sh: refused without the licence accepted; with it, the known styles and contents only"
