#!/usr/bin/env bash
# Side-by-side: handemo's benchmarks vs the PyTorch CPU reference StarGAN vs this machine's FMA peak.
# Builds bench_conv, peak_fma_avx2 (and bench_stargan when bench/stargan_bench.cpp exists) in Release with
# -march=native, then in one run: the FP32 FMA peak (the shared AVX-512 program first, the AVX2 one when
# that fails to build or run), reference_stargan.py with 1 thread (inference) and 2 threads (training),
# the handemo benchmarks, and a table of ratios.
# Usage: bench/compare.sh [build-dir]   (default: <repo>/build-bench)
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

echo "== FMA peak"
peak=""
if g++ -O2 -march=native -mavx512f "$shared_bench/peak_fma.cpp" -o "$out/peak_fma" 2>/dev/null \
   && { "$out/peak_fma" >"$out/peak.txt"; } 2>/dev/null; then
  cat "$out/peak.txt"
  peak=$(sed -n 's/^AVX2 FMA: \([0-9.]*\).*/\1/p' "$out/peak.txt")
  avx512=$(sed -n 's/^AVX512 FMA: \([0-9.]*\).*/\1/p' "$out/peak.txt")
  if [ -n "$avx512" ] && grep -q avx512f /proc/cpuinfo; then peak=$avx512; fi
else
  echo "(shared peak_fma.cpp needs AVX-512: not available here, using peak_fma_avx2)"
  "$build/bench/peak_fma_avx2" | tee "$out/peak.txt"
  peak=$(sed -n 's/^AVX2 FMA: \([0-9.]*\).*/\1/p' "$out/peak.txt")
fi

echo "== PyTorch reference (CPU)"
py=/usr/bin/python3
ref="$shared_bench/reference_stargan.py"
if [ -x "$py" ] && [ -f "$ref" ]; then
  echo "-- 1 thread";  "$py" "$ref" 1 | tee "$out/torch1.txt"
  echo "-- 2 threads"; "$py" "$ref" 2 | tee "$out/torch2.txt"
else
  echo "(no $py or $ref)"; : >"$out/torch1.txt"; : >"$out/torch2.txt"
fi

echo "== handemo"
"$build/bench/bench_conv" --benchmark_filter='peak_fma|generator_convs' --benchmark_min_time=0.5 \
  --benchmark_format=console --benchmark_out="$out/conv.json" --benchmark_out_format=json
"$build/bench/bench_conv" --benchmark_filter='^cd' --benchmark_min_time=0.1 \
  --benchmark_out="$out/conv_layers.json" --benchmark_out_format=json >/dev/null
if [ -x "$build/bench/bench_stargan" ]; then
  "$build/bench/bench_stargan" --benchmark_out="$out/stargan.json" --benchmark_out_format=json
else
  echo "(bench_stargan not built yet: n/a)"
fi

echo "== comparison"
"$py" "$here/compare_table.py" --peak "${peak:-0}" --torch1 "$out/torch1.txt" --torch2 "$out/torch2.txt" \
  --conv "$out/conv.json" --layers "$out/conv_layers.json" --stargan "$out/stargan.json"
