#!/usr/bin/env bash
# The Cortex-M7 test (CTest label cross): builds tests/cross/cortex_m with cmake/toolchains/arm-none-eabi.cmake
# around the header that `handemo export --header` wrote (test micro_export_cli), checks that nothing in the
# firmware can allocate (no malloc/_sbrk linked), runs it under qemu-system-arm -M mps2-an500 with
# semihosting and -icount shift=0 (deterministic: one virtual step per instruction), and prints the memory
# map and the instructions of one inference. The firmware compares its output with the host's (x86) itself.
# Exits 77 (CTest: skipped) when arm-none-eabi-g++ or qemu-system-arm is missing (`./setup.sh --cross`).
# Usage: run_cortex_m.sh SOURCE_DIR BUILD_DIR MODEL_HEADER
set -euo pipefail
src=$1
bin=$2
header=$3
for tool in arm-none-eabi-g++ qemu-system-arm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "cross_cortex_m: $tool not found: skipped (./setup.sh --cross installs gcc-arm-none-eabi, libstdc++-arm-none-eabi-newlib and qemu-system-arm)"
    exit 77
  fi
done
if [[ ! -f "$header" ]]; then
  echo "cross_cortex_m: $header not found (the micro_export_cli test writes it)"
  exit 1
fi
mkdir -p "$bin"
if ! cmake -S "$src/tests/cross/cortex_m" -B "$bin" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_MODEL_HEADER="$header" \
     -DCMAKE_TOOLCHAIN_FILE="$src/cmake/toolchains/arm-none-eabi.cmake" >"$bin/configure.log" 2>&1; then
  cat "$bin/configure.log"
  exit 1
fi
cmake --build "$bin" -j1
elf=$bin/firmware.elf
if arm-none-eabi-nm "$elf" | grep -Eq ' (malloc|_malloc_r|_sbrk|_sbrk_r|__cxa_allocate_exception)$'; then
  echo "cross_cortex_m: the firmware links an allocator or exceptions:"
  arm-none-eabi-nm "$elf" | grep -E ' (malloc|_malloc_r|_sbrk|_sbrk_r|__cxa_allocate_exception)$'
  exit 1
fi
echo "cross_cortex_m: memory map (linker map: $bin/firmware.map)"
arm-none-eabi-size -A "$elf" | grep -E '^(section|\.isr_vector|\.text|\.rodata|\.ARM\.exidx|\.init_array|\.data|\.bss|\.stack) '
arm-none-eabi-size -B "$elf"
out=$(timeout 300 qemu-system-arm -M mps2-an500 -cpu cortex-m7 -nographic -monitor none -serial none \
        -semihosting-config enable=on,target=native -icount shift=0,align=off,sleep=off -kernel "$elf" 2>&1) || {
  echo "$out"
  echo "cross_cortex_m: the firmware failed"
  exit 1
}
echo "$out"
grep -q ': ok$' <<<"$out" || { echo "cross_cortex_m: no ok line"; exit 1; }
