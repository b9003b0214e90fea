#!/usr/bin/env bash
# Instructions per G inference (batch 1) on aarch64, counted under qemu-aarch64: Debian's QEMU has no
# instruction-count plugin and qemu-user no -icount, so the program runs with one instruction per translation
# block (-singlestep) and every executed block logged (-d nochain,exec); the lines between the two marker
# system calls that bench/cross/icount_infer.cpp makes around one inference (-d strace) are its instructions.
# Deterministic: the same binary gives the same count on any host. Builds tests/cross/aarch64 with
# -DHANDEMO_CROSS_ICOUNT=ON (Release, -O3, NEON through xsimd) in BUILD (default <repo>/build-aarch64-icount).
# Usage: bench/aarch64_icount.sh [BUILD] [CONFIG[:STORAGE] ...]
#   CONFIG: micro-plain (hand-micro through handemo::micro) | micro | embedded | paper (SIMD kernels, frozen G)
#   STORAGE: native (default) | f16. Default list: micro-plain micro embedded embedded:f16.
#   The paper G takes about 4.5 minutes here (90 M instructions emulated one by one), hence not in the default.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
build=${1:-$root/build-aarch64-icount}
shift || true
configs=("$@")
[ ${#configs[@]} -gt 0 ] || configs=(micro-plain micro embedded embedded:f16)
for tool in aarch64-linux-gnu-g++ qemu-aarch64; do
  command -v "$tool" >/dev/null 2>&1 || { echo "aarch64_icount: $tool not found (./setup.sh --cross installs it)"; exit 1; }
done
echo "== building icount_infer for aarch64 in $build"
cmake -S "$root/tests/cross/aarch64" -B "$build" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_CROSS_ICOUNT=ON \
      -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchains/aarch64-linux-gnu.cmake" >"$build.configure.log" 2>&1 \
  || { cat "$build.configure.log"; exit 1; }
rm -f "$build.configure.log"
cmake --build "$build" --target icount_infer -j2 >/dev/null
echo "compiler: $(aarch64-linux-gnu-g++ --version | head -1); $(qemu-aarch64 --version | head -1)"
echo
echo "| config | weights | instructions per inference | emulated in |"
echo "|---|---|---|---|"
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for c in "${configs[@]}"; do
  cfg=${c%%:*}
  st=native
  [ "$cfg" = "$c" ] || st=${c#*:}
  start=$(date +%s)
  # the log goes to fd 3 (a pipe into awk); the program's own output to $out
  n=$( { qemu-aarch64 -L /usr/aarch64-linux-gnu -singlestep -d nochain,exec,strace -D /dev/fd/3 \
           "$build/icount_infer" "$cfg" "$st" >"$out"; } 3>&1 |
       awk '/ getppid\(\)/ { m++; next } /^Trace/ { if (m == 1) n++ } END { if (m != 2) exit 1; print n }' ) \
    || { echo "aarch64_icount: $c: the run failed or its two markers were not both seen"; cat "$out"; exit 1; }
  bytes=$(sed -n 's/^icount_infer: \([0-9]*\) weight bytes.*/\1/p' "$out")
  echo "| $cfg | $st, $bytes bytes | $n | $(( $(date +%s) - start )) s |"
done
