#!/usr/bin/env bash
# The Cortex-M tests (CTest label cross): build tests/cross/cortex_m with cmake/toolchains/arm-none-eabi.cmake
# for the core CPU around the header that `handemo export --header` wrote (test micro_export_cli), check that
# nothing in the firmware can allocate (no malloc/_sbrk linked), run it under qemu-system-arm with semihosting
# and -icount shift=0 (deterministic: one virtual step per instruction), and print the memory map and the
# instructions of one inference. The firmware compares its output with the host's (x86) itself.
#   cortex-m7 (default)  qemu-system-arm -M mps2-an500 -cpu cortex-m7 (test cross_cortex_m)
#   cortex-m55           qemu-system-arm -M mps3-an547 (Helium: MVE integer and float; test cross_cortex_m55);
#                        also prints how many instructions of the micro:: functions are MVE instructions (objdump)
#   cortex-m55+nomve     the same board, the firmware built for the scalar FPU only
# Exits 77 (CTest: skipped) when arm-none-eabi-g++ or qemu-system-arm is missing (`./setup.sh --cross`).
# Usage: run_cortex_m.sh SOURCE_DIR BUILD_DIR MODEL_HEADER [CPU]
set -euo pipefail
src=$1
bin=$2
header=$3
cpu=${4:-cortex-m7}
case "$cpu" in
  cortex-m7) name=cross_cortex_m machine=(-M mps2-an500 -cpu cortex-m7) ;;
  cortex-m55|cortex-m55+nomve) name=cross_cortex_m55 machine=(-M mps3-an547) ;;
  *) echo "run_cortex_m: CPU '$cpu' is not cortex-m7, cortex-m55 or cortex-m55+nomve"; exit 2 ;;
esac
for tool in arm-none-eabi-g++ qemu-system-arm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "$name: $tool not found: skipped (./setup.sh --cross installs gcc-arm-none-eabi, libstdc++-arm-none-eabi-newlib and qemu-system-arm)"
    exit 77
  fi
done
if [[ ! -f "$header" ]]; then
  echo "$name: $header not found (the micro_export_cli test writes it)"
  exit 1
fi
mkdir -p "$bin"
if ! cmake -S "$src/tests/cross/cortex_m" -B "$bin" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_MODEL_HEADER="$header" \
     -DHANDEMO_CORTEX_M_CPU="$cpu" -DCMAKE_TOOLCHAIN_FILE="$src/cmake/toolchains/arm-none-eabi.cmake" \
     >"$bin/configure.log" 2>&1; then
  cat "$bin/configure.log"
  exit 1
fi
cmake --build "$bin" -j1
elf=$bin/firmware.elf
if arm-none-eabi-nm "$elf" | grep -Eq ' (malloc|_malloc_r|_sbrk|_sbrk_r|__cxa_allocate_exception)$'; then
  echo "$name: the firmware links an allocator or exceptions:"
  arm-none-eabi-nm "$elf" | grep -E ' (malloc|_malloc_r|_sbrk|_sbrk_r|__cxa_allocate_exception)$'
  exit 1
fi
echo "$name: memory map (linker map: $bin/firmware.map)"
arm-none-eabi-size -A "$elf" | grep -E '^(section|\.isr_vector|\.text|\.rodata|\.ARM\.exidx|\.init_array|\.data|\.bss|\.stack) '
arm-none-eabi-size -B "$elf"
if [[ $cpu == cortex-m55 ]]; then
  # MVE instructions (q registers) in the functions of namespace micro:: (G's, whatever GCC inlined into them, and
  # the instantiations the firmware's kernel check adds)
  dis=$(arm-none-eabi-objdump -d --no-show-raw-insn -C -marmv8.1-m.main "$elf" |
        awk '/^[0-9a-f]+ <.*>:$/ { keep = /micro::/ } keep && /^ *[0-9a-f]+:\t/')
  total=$(grep -c . <<<"$dis" || true)
  mve=$(grep -cE '\bq[0-7]\b' <<<"$dis" || true)
  echo "$name: MVE instructions in the firmware's micro:: functions: $mve of $total"
  grep -qE '\bq[0-7]\b' <<<"$dis" || { echo "$name: no MVE instruction in the inference's code"; exit 1; }
fi
out=$(timeout 300 qemu-system-arm "${machine[@]}" -nographic -monitor none -serial none \
        -semihosting-config enable=on,target=native -icount shift=0,align=off,sleep=off -kernel "$elf" 2>&1) || {
  echo "$out"
  echo "$name: the firmware failed"
  exit 1
}
echo "$out"
grep -q ': ok$' <<<"$out" || { echo "$name: no ok line"; exit 1; }
