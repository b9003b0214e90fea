#!/usr/bin/env bash
# Instructions per G inference (batch 1, handemo::micro) on the Cortex-M7 and the Cortex-M55, counted under
# qemu-system-arm -icount shift=0 by the firmware of tests/cross/cortex_m (SysTick on the CPU clock, calibrated
# on a loop of known length; deterministic). Builds, for the header HEADER (`handemo export --header`, or the
# seeded-weights header of docs/embedded.md), the firmware for:
#   cortex-m7          mps2-an500, FPv5
#   cortex-m55         mps3-an547, Helium: the MVE convolutions (micro::detail::mve)
#   cortex-m55-plain   the same core and flags with -DHANDEMO_MICRO_NO_MVE: the plain loops as GCC vectorises them
#   cortex-m55+nomve   the same core with the scalar FPU only
# and prints a table: instructions per inference and, for the Cortex-M55 builds, how many of them are MVE
# instructions. That share comes from a second run with one instruction per translation block and every executed
# block logged (-singlestep -d nochain,exec), each logged address matched with arm-none-eabi-objdump's disassembly:
# the MVE instructions (those naming a q register) executed outside main (the calibration loop) over the
# instructions per inference. The firmware is built without its MVE kernel check
# (-DHANDEMO_FIRMWARE_MVE_CHECK=OFF) so that only the inference runs G's functions. About half a minute in all.
# Usage: bench/cortex_m_icount.sh HEADER [BUILD] [OPT]   (BUILD default <repo>/build-cortex-m-icount, OPT -O2)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
header=${1:?usage: bench/cortex_m_icount.sh HEADER [BUILD] [OPT]}
build=${2:-$root/build-cortex-m-icount}
opt=${3:--O2}
for tool in arm-none-eabi-g++ qemu-system-arm python3; do
  command -v "$tool" >/dev/null 2>&1 || { echo "cortex_m_icount: $tool not found (./setup.sh --cross installs it)"; exit 1; }
done
[ -f "$header" ] || { echo "cortex_m_icount: $header not found"; exit 1; }
header=$(cd "$(dirname "$header")" && pwd)/$(basename "$header")
echo "compiler: $(arm-none-eabi-g++ --version | head -1); $(qemu-system-arm --version | head -1); firmware $opt"
echo
echo "| firmware | instructions per inference | MVE instructions executed |"
echo "|---|---|---|"
for variant in cortex-m7 cortex-m55 cortex-m55-plain cortex-m55+nomve; do
  cpu=${variant%-plain} flags=$opt machine=(-M mps3-an547)
  [ "$variant" = cortex-m55-plain ] && flags="$opt -DHANDEMO_MICRO_NO_MVE"
  [ "$cpu" = cortex-m7 ] && machine=(-M mps2-an500 -cpu cortex-m7)
  bin=$build/$variant
  mkdir -p "$bin"
  cmake -S "$root/tests/cross/cortex_m" -B "$bin" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_MODEL_HEADER="$header" \
        -DHANDEMO_CORTEX_M_CPU="$cpu" -DHANDEMO_FIRMWARE_OPT="$flags" -DHANDEMO_FIRMWARE_MVE_CHECK=OFF \
        -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchains/arm-none-eabi.cmake" >"$bin/configure.log" 2>&1 \
    || { cat "$bin/configure.log"; exit 1; }
  cmake --build "$bin" -j1 >"$bin/build.log" 2>&1 || { cat "$bin/build.log"; exit 1; }
  qemu=(qemu-system-arm "${machine[@]}" -nographic -monitor none -serial none
        -semihosting-config enable=on,target=native -icount shift=0,align=off,sleep=off -kernel "$bin/firmware.elf")
  out=$("${qemu[@]}" 2>&1) || { echo "$out"; echo "cortex_m_icount: $variant: the firmware failed"; exit 1; }
  n=$(sed -n 's/^instructions per inference: \([0-9]*\).*/\1/p' <<<"$out")
  [ -n "$n" ] || { echo "$out"; echo "cortex_m_icount: $variant: no instruction count"; exit 1; }
  share=""
  if [ "$cpu" = cortex-m55 ]; then
    # executions per address (the second field of a Trace line's [cs_base/pc/flags/cflags])
    "${qemu[@]}" -singlestep -d nochain,exec -D /dev/fd/3 3>&1 >/dev/null 2>&1 |
      awk -F'[][/]' '/^Trace/ { n[$3]++ } END { for (a in n) print a, n[a] }' >"$bin/executed.txt"
    arm-none-eabi-objdump -d --no-show-raw-insn -marmv8.1-m.main "$bin/firmware.elf" >"$bin/firmware.dis"
    mve=$(python3 - "$bin/executed.txt" "$bin/firmware.dis" <<'EOF'
import re, sys
runs = {int(a, 16): int(n) for a, n in (line.split() for line in open(sys.argv[1]))}
fn, mve = "", 0
for line in open(sys.argv[2]):
    m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
    if m:
        fn = m.group(1)
        continue
    m = re.match(r"^ *([0-9a-f]+):\t(\S+)\t?(.*)", line)
    if m and fn != "main" and m.group(2).startswith("v") and re.search(r"\bq[0-7]\b", m.group(3)):
        mve += runs.get(int(m.group(1), 16), 0)
print(mve)
EOF
)
    share="$mve ($(( (100 * mve + n / 2) / n ))%)"
  fi
  echo "| $variant | $n | $share |"
done
