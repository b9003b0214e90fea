#!/usr/bin/env bash
# Side-by-side: handemo's benchmarks vs the PyTorch CPU reference StarGAN vs this machine's FMA peak.
# Builds bench_conv, peak_fma_avx2 (and bench_stargan when bench/stargan_bench.cpp exists) in Release with
# -march=native, then in one run: the instruction set the kernels were compiled for (xsimd's default_arch:
# avx512bw, avx2, ...), the FP32 FMA peak of that instruction set (../shared/bench/peak_fma.cpp's AVX512 or
# AVX2 line; bench/peak_fma_avx2 on a CPU without AVX-512; and the same loop inside bench_conv, which the
# table uses), reference_stargan.py with 1 and 2 threads, the handemo benchmarks, and a table of ratios.
# The machine this runs on may be a shared VM whose speed moves by 15-30% within minutes, so the PyTorch
# reference, the in-process peaks and the handemo inference and training benchmarks run in ROUNDS rounds,
# one after the other within each round; the table gives each number's median over the rounds with its
# range, and the 2-thread / 1-thread ratio as the median of the rounds' ratios (each round's pair is
# measured back to back).
# Usage: bench/compare.sh [build-dir]   (default: <repo>/build-bench)
#        HANDEMO_COMPARE_ROUNDS=N (default 3; 1 gives the single-pass numbers of earlier versions)
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
build=${1:-$root/build-bench}
shared_bench="$(dirname "$0")/../../shared/bench"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

echo "== building (Release, -march=native) in $build"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_ARCH=native \
      -DHANDEMO_BUILD_TESTS=OFF -DHANDEMO_BUILD_EXAMPLES=OFF -DHANDEMO_BUILD_BENCH=ON >"$out/cmake.log" 2>&1 \
  || { cat "$out/cmake.log"; echo "compare.sh: cmake configure failed"; exit 1; }
targets="bench_conv peak_fma_avx2"
if [ -f "$here/stargan_bench.cpp" ]; then targets="$targets bench_stargan"; fi
for t in $targets; do
  nice cmake --build "$build" --target "$t" -j1 >"$out/build_$t.log" 2>&1 \
    || { tail -20 "$out/build_$t.log"; echo "compare.sh: building $t failed"; [ "$t" = bench_stargan ] || exit 1; }
done

# The instruction set xsimd picked for the kernels in this build (-march=native): the peak that counts is
# that ISA's, not the widest the CPU has (an AVX-512 CPU running AVX2 kernels is measured against AVX2).
read -r isa lanes < <("$build/bench/bench_conv" --simd_arch)
echo "== kernels compiled for: ${isa:-unknown} (${lanes:-?} float lanes; xsimd default_arch of this build)"
case "$isa" in
  avx512*) peak_line="AVX512 FMA" ;;
  avx2|fma3*|avx2*) peak_line="AVX2 FMA" ;;
  *) peak_line="" ;;
esac

echo "== FMA peak (standalone, for $isa)"
peak=""
if [ -z "$peak_line" ]; then
  echo "(no standalone peak program for $isa: the in-process peak of bench_conv is used)"
elif [ "$peak_line" = "AVX512 FMA" ] || grep -q avx512f /proc/cpuinfo; then
  # ../shared/bench/peak_fma.cpp measures both AVX-512 and AVX2 (needs a CPU with AVX-512)
  if g++ -O2 -march=native "$shared_bench/peak_fma.cpp" -o "$out/peak_fma" 2>"$out/peak_build.log" \
     && "$out/peak_fma" >"$out/peak.txt" 2>&1; then
    cat "$out/peak.txt"
    peak=$(sed -n "s/^$peak_line: \([0-9.]*\).*/\1/p" "$out/peak.txt")
  else
    echo "(shared peak_fma.cpp failed to build or run)"
  fi
fi
if [ -z "$peak" ] && [ "$peak_line" = "AVX2 FMA" ]; then
  "$build/bench/peak_fma_avx2" | tee "$out/peak.txt"
  peak=$(sed -n 's/^AVX2 FMA: \([0-9.]*\).*/\1/p' "$out/peak.txt")
fi
[ -n "$peak" ] && echo "standalone $isa peak: $peak GFLOP/s"

rounds=${HANDEMO_COMPARE_ROUNDS:-3}
case "$rounds" in ''|*[!0-9]*|0) echo "compare.sh: HANDEMO_COMPARE_ROUNDS '$rounds' is not a positive integer"; exit 1 ;; esac
py=/usr/bin/python3
ref="$shared_bench/reference_stargan.py"
have_torch=0
if [ -x "$py" ] && [ -f "$ref" ]; then have_torch=1; else echo "(no $py or $ref: PyTorch columns n/a)"; fi
start=$(date +%s)
for r in $(seq 1 "$rounds"); do
  if [ "$r" -gt 1 ]; then
    el=$(( $(date +%s) - start ))
    echo "== round $r of $rounds (elapsed ${el} s, about $(( el * (rounds - r + 1) / (r - 1) )) s to go)"
  else
    echo "== round 1 of $rounds"
  fi
  echo "-- PyTorch reference (CPU)"
  if [ "$have_torch" = 1 ]; then
    echo "-- 1 thread";  "$py" "$ref" 1 | tee "$out/torch1_$r.txt"
    echo "-- 2 threads"; "$py" "$ref" 2 | tee "$out/torch2_$r.txt"
  else
    : >"$out/torch1_$r.txt"; : >"$out/torch2_$r.txt"
  fi
  echo "-- handemo"
  "$build/bench/bench_conv" --benchmark_filter='peak_fma|generator_convs' --benchmark_min_time=0.5 \
    --benchmark_format=console --benchmark_out="$out/conv_$r.json" --benchmark_out_format=json
  if [ -x "$build/bench/bench_stargan" ]; then
    "$build/bench/bench_stargan" --benchmark_out="$out/stargan_$r.json" --benchmark_out_format=json
  else
    echo "(bench_stargan not built yet: n/a)"
  fi
done
"$build/bench/bench_conv" --benchmark_filter='^(cd|packed/)' --benchmark_min_time=0.1 \
  --benchmark_out="$out/conv_layers.json" --benchmark_out_format=json >/dev/null
echo "== $rounds rounds in $(( $(date +%s) - start )) s"

echo "== comparison"
list() { local f=$1 acc="" r; for r in $(seq 1 "$rounds"); do acc="$acc${acc:+,}$out/${f}_$r.$2"; done; echo "$acc"; }
"$py" "$here/compare_table.py" --isa "${isa:-unknown}" --peak "${peak:-0}" --torch1 "$(list torch1 txt)" \
  --torch2 "$(list torch2 txt)" --conv "$(list conv json)" --layers "$out/conv_layers.json" --stargan "$(list stargan json)"
