#!/usr/bin/env bash
# Compile cost of including handemo, measured as CPU time (user + system) and peak memory of g++, median of
# ROUNDS runs each, one after the other:
#   light        examples/transfer.cpp, the README's 10-line example on <handemo/transfer.hpp>, at -O2
#   light impl   examples/handemo_impl.cpp, the one file that compiles <handemo/transfer_impl.hpp>, at -O2
#   umbrella     the same 10 lines on <handemo.hpp> (stargan::load_model + transfer_capture), at -O2
#   umbrella -fsyntax-only   parsing <handemo.hpp> alone
# then g++ -ftime-report's three largest phases for the light example and the umbrella program.
# CPU time, not wall time, because the machine may be shared; the header names the CPU, the compiler and the load.
# Usage: bench/compile_time.sh [--out]   (--out: also writes bench/results/<YYYY-MM-DD>-compile-<cpu>.txt)
#   HANDEMO_COMPILE_ROUNDS=N (default 3), CXX (default g++), HANDEMO_COMPILE_FLAGS (default -march=native)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
rounds=${HANDEMO_COMPILE_ROUNDS:-3}
cxx=${CXX:-g++}
flags=${HANDEMO_COMPILE_FLAGS:--march=native}
out=""
case "${1:-}" in
  --out) out=yes ;;
  "") ;;
  *) sed -n '2,13s/^# \{0,1\}//p' "$0"; exit 2 ;;
esac
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# the viewer page, which CMake embeds at build time (cmake/embed_viewer_page.cmake)
cmake -DHANDEMO_SOURCE="$root" -DHANDEMO_GENERATED="$work/generated" -P "$root/cmake/embed_viewer_page.cmake"
cat > "$work/umbrella.cpp" <<'CPP'
#include <handemo.hpp>
int main(int argc, char** argv) {
    if (argc != 5) return 1;
    handemo::clip capture = handemo::read_bvh(argv[2]);
    auto model = handemo::stargan::load_model(argv[1]);
    auto sad = handemo::stargan::transfer_capture(*model, capture, argv[3], {}, {});
    handemo::write_bvh(argv[4], sad.motion, -1);
}
CPP
echo '#include <handemo.hpp>' > "$work/parse.cpp"

# measure NAME SOURCE EXTRA-FLAGS...: prints "NAME  cpu s (min-max)  peak MB", median over the rounds
measure() {
  local name=$1 src=$2; shift 2
  local cpus=() mems=()
  for ((r = 0; r < rounds; r++)); do
    /usr/bin/time -f "%U %S %M" -o "$work/t" "$cxx" -std=c++20 $flags -I"$root/include" -I"$work/generated" "$@" -c "$src" -o "$work/o.o"
    read -r u s m < "$work/t"
    cpus+=("$(echo "$u + $s" | bc)")
    mems+=("$m")
  done
  local sorted_c sorted_m
  sorted_c=$(printf '%s\n' "${cpus[@]}" | sort -n)
  sorted_m=$(printf '%s\n' "${mems[@]}" | sort -n)
  local mid=$(( (rounds + 1) / 2 ))
  printf '%-28s %6.2f s CPU (%s-%s)  %5d MB peak\n' "$name" "$(sed -n "${mid}p" <<< "$sorted_c")" \
    "$(head -1 <<< "$sorted_c")" "$(tail -1 <<< "$sorted_c")" $(( $(sed -n "${mid}p" <<< "$sorted_m") / 1024 ))
}

phases() {
  local name=$1 src=$2
  "$cxx" -std=c++20 $flags -O2 -I"$root/include" -I"$work/generated" -ftime-report -c "$src" -o "$work/o.o" 2> "$work/r" || true
  echo "$name, largest -ftime-report entries (user s, share):"
  grep -E '^ [a-zA-Z].*: +[0-9]' "$work/r" | grep -v TOTAL | sed 's/^ //' |
    awk -F' : ' '{split($2, a, " "); print a[1] "\t" $1 "\t" a[2] a[3]}' | sort -rn | head -3 |
    awk -F'\t' '{gsub(/ +$/, "", $2); printf "  %-32s %6.2f s user %s\n", $2, $1, $3}'
}

{
  echo "handemo compile time, $(date -u +%Y-%m-%d), commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores; load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "compiler: $("$cxx" --version | head -1); flags: -std=c++20 $flags; median of $rounds runs"
  echo
  measure "light (transfer.hpp) -O2" "$root/examples/transfer.cpp" -O2
  measure "light impl -O2" "$root/examples/handemo_impl.cpp" -O2
  measure "umbrella (handemo.hpp) -O2" "$work/umbrella.cpp" -O2
  measure "umbrella -fsyntax-only" "$work/parse.cpp" -fsyntax-only
  echo
  phases "light" "$root/examples/transfer.cpp"
  phases "umbrella" "$work/umbrella.cpp"
} | tee "$work/report"
if [[ -n "$out" ]]; then
  cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //; s/[^A-Za-z0-9]\+/-/g; s/-$//')
  dest="$root/bench/results/$(date -u +%Y-%m-%d)-compile-$cpu.txt"
  cp "$work/report" "$dest"
  echo "written: bench/results/$(basename "$dest")"
fi
