#!/usr/bin/env bash
# The aarch64 cross tests (CTest label cross): configures tests/cross/aarch64 with
# cmake/toolchains/aarch64-linux-gnu.cmake, builds it and runs its ctest, every program under qemu-aarch64
# (the kernel tests and the inference test against the x86 fixture). Exits 77, which CTest reports as
# skipped, when aarch64-linux-gnu-g++ or qemu-aarch64 is missing (`./setup.sh --cross` installs them).
# Usage: run_aarch64.sh SOURCE_DIR BUILD_DIR     HANDEMO_CROSS_JOBS: build jobs (default 2)
set -euo pipefail
src=$1
bin=$2
for tool in aarch64-linux-gnu-g++ qemu-aarch64; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "cross_aarch64: $tool not found: skipped (./setup.sh --cross installs g++-aarch64-linux-gnu and qemu-user)"
    exit 77
  fi
done
mkdir -p "$bin"
start=$(date +%s)
if ! cmake -S "$src/tests/cross/aarch64" -B "$bin" -DCMAKE_BUILD_TYPE=Release \
     -DCMAKE_TOOLCHAIN_FILE="$src/cmake/toolchains/aarch64-linux-gnu.cmake" >"$bin/configure.log" 2>&1; then
  cat "$bin/configure.log"
  exit 1
fi
cmake --build "$bin" -j"${HANDEMO_CROSS_JOBS:-2}"
built=$(date +%s)
echo "cross_aarch64: configured and built in $((built - start)) s"
ctest --test-dir "$bin" -V
echo "cross_aarch64: tests ran in $(($(date +%s) - built)) s under qemu-aarch64"
