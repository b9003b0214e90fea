#!/usr/bin/env bash
# Side-by-side: handemo's benchmarks vs the PyTorch CPU reference StarGAN vs ONNX Runtime vs this machine's FMA
# peak. Everything it measures against is in the repository: the reference is scripts/reference_stargan.py, which
# also exports the G that ONNX Runtime runs (--onnx, opset 13), ONNX Runtime's runner bench/onnxruntime_bench.js
# (the npm package onnxruntime-node, one thread), and the peak program bench/peak_fma.cpp (CMake target peak_fma).
# Builds bench_conv, peak_fma (and bench_stargan when bench/stargan_bench.cpp exists) in Release with
# -march=native, then in one run: the instruction set the kernels were compiled for (xsimd's default_arch:
# avx512bw, avx2, ...), the FP32 FMA peak of that instruction set (peak_fma's AVX512 or AVX2 line; and the
# same loop inside bench_conv, which the table uses), reference_stargan.py with 1 and 2 threads, the handemo
# benchmarks, ONNX Runtime at batch 1 and 32, and tables of ratios and of FLOPs against the peak.
# The machine this runs on may be a shared VM whose speed moves by 15-30% within minutes, so the PyTorch
# reference, the in-process peaks, the handemo inference and training benchmarks and ONNX Runtime run in ROUNDS rounds,
# one after the other within each round; the table gives each number's median over the rounds with its
# range, and the 2-thread / 1-thread ratio as the median of the rounds' ratios (each round's pair is
# measured back to back).
# Usage: bench/compare.sh [--out[=FILE]] [--dry-run] [--quick] [build-dir]   (default build-dir: <repo>/build-bench)
#   --out       also writes the table to bench/results/<YYYY-MM-DD>-<cpu-model>.md (FILE: there instead)
#               under a header giving the commit, the CPU model, the compiler, the load average at the start
#               and the number of rounds; an existing file of that name is kept (-2, -3, ... is added), one
#               written by another run while this one measured too
#   --dry-run   checks that the reference and the peak program are there and whether Python has torch,
#               prints what a run would build, run and write (with --out, the file's name and header), and
#               builds and measures nothing
#   --quick     runs every step for a moment (benchmarks 0.01 s, a few reference calls): checks that the whole
#               comparison runs end to end; its numbers are not measurements (the table says so; no --out)
#   HANDEMO_COMPARE_ROUNDS=N (default 3; 1 gives the single-pass numbers of earlier versions)
#   HANDEMO_COMPARE_ICOUNT=0 leaves out the embedded instruction counts (aarch64 and Cortex-M under emulation, after
#               the rounds, several minutes; they need ./setup.sh --cross, and for the Cortex-M a model header:
#               HANDEMO_COMPARE_MICRO_HEADER=FILE, else the seeded-weights header the built tests in build/ write)
#   HANDEMO_ORT_DIR=DIR (default <repo>/build-ort): where onnxruntime-node is installed, by
#               npm install --prefix DIR onnxruntime-node --ignore-scripts (without it, or without node or
#               torch, the ONNX Runtime columns are n/a)
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
usage() { sed -n '/^# Usage: /,/^[^#]/{/^#/s/^# \{0,1\}//p}' "$0"; }
write_out=0 results="" dry=0 build="" quick=0
for arg in "$@"; do
  case "$arg" in
    --out) write_out=1 ;;
    --out=*) write_out=1; results=${arg#--out=} ;;
    --dry-run) dry=1 ;;
    --quick) quick=1 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "compare.sh: unknown option $arg" >&2; usage >&2; exit 2 ;;
    *) [ -z "$build" ] || { echo "compare.sh: more than one build directory ($build, $arg)" >&2; exit 2; }
       build=$arg ;;
  esac
done
build=${build:-$root/build-bench}
if [ "$quick" = 1 ] && [ "$write_out" = 1 ]; then
  echo "compare.sh: --quick numbers are not measurements: no --out with --quick" >&2; exit 2
fi
rounds=${HANDEMO_COMPARE_ROUNDS:-3}
case "$rounds" in ''|*[!0-9]*|0) echo "compare.sh: HANDEMO_COMPARE_ROUNDS '$rounds' is not a positive integer"; exit 1 ;; esac
py=/usr/bin/python3
ref="$root/scripts/reference_stargan.py"
peak_src="$here/peak_fma.cpp"
load_start=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)
commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown) dirty=""
git -C "$root" diff --quiet HEAD -- 2>/dev/null || dirty=" (with uncommitted changes)"

# What a reader of a results file needs to compare two runs.
cpu_model() {
  { sed -n 's/^model name[[:space:]]*: *//p' /proc/cpuinfo 2>/dev/null; lscpu 2>/dev/null | sed -n 's/^Model name: *//p'; } \
    | grep . | head -1 | grep . || echo unknown-cpu
}
compiler_version() {
  local cxx
  cxx=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt" 2>/dev/null)
  "${cxx:-${CXX:-c++}}" --version 2>/dev/null | head -1 | grep . || echo unknown
}
results_header() {  # $1: the load average when the rounds started
  echo "# bench/compare.sh: $(cpu_model), $(date +%F)"
  echo
  echo "- commit: \`$commit\`$dirty"
  echo "- CPU: $(cpu_model) ($(nproc) logical CPUs); kernels compiled for ${isa:-the native instruction set}"
  echo "- compiler: $(compiler_version)"
  echo "- PyTorch: $torch_version"
  echo "- ONNX Runtime: $ort_version"
  echo "- load average (1, 5, 15 min): $load_start at the start, $1 when the rounds started"
  echo "- rounds: $rounds (HANDEMO_COMPARE_ROUNDS): every time is the median over the rounds, its range in parentheses"
  echo
}
auto_name=0
if [ "$write_out" = 1 ] && [ -z "$results" ]; then
  auto_name=1
  slug=$(cpu_model | tr '[:upper:]' '[:lower:]' | sed 's/([^)]*)//g; s/[^a-z0-9]\{1,\}/-/g; s/^-//; s/-$//')
  results="$root/bench/results/$(date +%F)-${slug:-unknown-cpu}.md"
  base=${results%.md} n=2
  while [ -e "$results" ]; do results="$base-$n.md"; n=$((n + 1)); done
fi

have_torch=0 torch_version="n/a: $py cannot import torch (./setup.sh --golden installs python3-torch)"
if [ ! -f "$ref" ]; then
  torch_version="n/a: $ref is missing"
elif [ -x "$py" ] && v=$("$py" -c 'import torch; print(torch.__version__)' 2>/dev/null); then
  have_torch=1 torch_version="$v ($py)"
fi

# ONNX Runtime: node, the runner, onnxruntime-node where HANDEMO_ORT_DIR says, and torch to export G
ort_runner="$here/onnxruntime_bench.js" have_ort=0
export HANDEMO_ORT_DIR=${HANDEMO_ORT_DIR:-$root/build-ort}
if ! command -v node >/dev/null 2>&1; then
  ort_version="n/a: node is not on PATH"
elif ! v=$(node "$ort_runner" check 2>&1); then
  ort_version="n/a: ${v#SKIP: }"
elif [ "$have_torch" != 1 ]; then
  ort_version="n/a: exporting G to ONNX needs torch ($torch_version)"
else
  have_ort=1 ort_version="${v%% (*} (HANDEMO_ORT_DIR)"  # no machine path in a results file
fi

if [ "$dry" = 1 ]; then
  echo "== dry run: nothing is built or measured"
  echo "build directory: $build (Release, -march=native; targets bench_conv peak_fma$([ -f "$here/stargan_bench.cpp" ] && echo ' bench_stargan'))"
  echo "peak program:    $peak_src$([ -f "$peak_src" ] || echo ': MISSING')"
  echo "reference:       $ref$([ -f "$ref" ] || echo ': MISSING')"
  echo "PyTorch:         $torch_version"
  echo "ONNX Runtime:    $ort_version"
  echo "rounds:          $rounds$([ "$quick" = 1 ] && echo ' (--quick: a run-through, not a measurement)')"
  if [ "$write_out" = 1 ]; then
    echo "results file:    $results, starting:"
    results_header "..." | sed 's/^/    /'
  fi
  [ -f "$peak_src" ] && [ -f "$ref" ]
  exit
fi

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

echo "== building (Release, -march=native) in $build"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DHANDEMO_ARCH=native \
      -DHANDEMO_BUILD_TESTS=OFF -DHANDEMO_BUILD_EXAMPLES=OFF -DHANDEMO_BUILD_BENCH=ON >"$out/cmake.log" 2>&1 \
  || { cat "$out/cmake.log"; echo "compare.sh: cmake configure failed"; exit 1; }
targets="bench_conv peak_fma"
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

# bench/peak_fma prints one line per instruction set (n/a for one the CPU lacks); the kernels' line counts.
echo "== FMA peak (standalone, for ${isa:-unknown})"
peak=""
"$build/bench/peak_fma" >"$out/peak.txt" 2>&1
cat "$out/peak.txt"
if [ -z "$peak_line" ]; then
  echo "(no standalone peak for ${isa:-unknown}: the in-process peak of bench_conv is used)"
else
  peak=$(sed -n "s/^$peak_line: \([0-9.]*\).*/\1/p" "$out/peak.txt")
  [ -n "$peak" ] && echo "standalone $isa peak: $peak GFLOP/s" \
    || echo "(no $peak_line line from peak_fma: the in-process peak of bench_conv is used)"
fi

[ "$have_torch" = 1 ] || echo "(PyTorch $torch_version: PyTorch columns n/a)"
# --quick: every benchmark for a moment
ref_quick="" conv_min=0.5 layer_min=0.1 ort_min=1
if [ "$quick" = 1 ]; then
  export HANDEMO_BENCH_QUICK=1
  ref_quick=--quick conv_min=0.01 layer_min=0.01 ort_min=0
fi
# the G ONNX Runtime runs: the reference's paper and embedded G, exported once for every round, and the same G with its
# convolution weights rounded to binary16 (--half-weights: the model handemo's binary16 rows run, in float for ONNX Runtime)
if [ "$have_ort" = 1 ]; then
  echo "== ONNX Runtime: $ort_version; exporting G (reference_stargan.py --onnx, opset 13)"
  for cfg in paper embedded; do
    "$py" "$ref" --onnx "hand-$cfg" "$out/$cfg.onnx" || { echo "(export of hand-$cfg failed: ONNX Runtime columns n/a)"; have_ort=0; }
    "$py" "$ref" --onnx "hand-$cfg" "$out/${cfg}_f16.onnx" --half-weights || echo "(export of hand-$cfg with binary16 weights failed)"
  done
else
  echo "(ONNX Runtime $ort_version: ONNX Runtime columns n/a)"
fi
load_rounds=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)
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
    echo "-- 1 thread";  "$py" "$ref" 1 $ref_quick | tee "$out/torch1_$r.txt"
    echo "-- 2 threads"; "$py" "$ref" 2 $ref_quick | tee "$out/torch2_$r.txt"
  else
    : >"$out/torch1_$r.txt"; : >"$out/torch2_$r.txt"
  fi
  echo "-- handemo"
  "$build/bench/bench_conv" --benchmark_filter='peak_fma|generator_convs' --benchmark_min_time=$conv_min \
    --benchmark_format=console --benchmark_out="$out/conv_$r.json" --benchmark_out_format=json
  if [ -x "$build/bench/bench_stargan" ]; then
    "$build/bench/bench_stargan" --benchmark_out="$out/stargan_$r.json" --benchmark_out_format=json
  else
    echo "(bench_stargan not built yet: n/a)"
  fi
  : >"$out/ort_$r.txt"
  if [ "$have_ort" = 1 ]; then
    echo "-- ONNX Runtime (onnxruntime-node, 1 thread)"
    node "$ort_runner" time "$out/paper.onnx" "paper(64,6)" 1,32 "$ort_min" | tee -a "$out/ort_$r.txt"
    node "$ort_runner" time "$out/embedded.onnx" "embedded(32,3)" 1,32 "$ort_min" | tee -a "$out/ort_$r.txt"
    for cfg in paper embedded; do
      [ -f "$out/${cfg}_f16.onnx" ] || continue
      node "$ort_runner" time "$out/${cfg}_f16.onnx" "${cfg}_f16($([ $cfg = paper ] && echo 64,6 || echo 32,3))" 1,32 "$ort_min" | tee -a "$out/ort_$r.txt"
    done
  fi
done
"$build/bench/bench_conv" --benchmark_filter='^(cd|packed/)' --benchmark_min_time=$layer_min \
  --benchmark_out="$out/conv_layers.json" --benchmark_out_format=json >/dev/null
echo "== $rounds rounds in $(( $(date +%s) - start )) s"

# Embedded targets: instructions per G inference counted under emulation. The counts are deterministic (the same
# binary gives the same count on any host), so they run once, after the timed rounds, and take several minutes.
# HANDEMO_COMPARE_ICOUNT=0 leaves them out; without the cross tools (./setup.sh --cross) each line says why.
icount_section() {
  echo "Embedded targets: instructions per G inference (batch 1), counted under emulation (deterministic; not times):"
  echo
  if [ "${HANDEMO_COMPARE_ICOUNT:-1}" = 0 ] || [ "$quick" = 1 ]; then
    echo "(not counted: HANDEMO_COMPARE_ICOUNT=0 or --quick)"
    return
  fi
  local a c header=${HANDEMO_COMPARE_MICRO_HEADER:-}
  echo "aarch64, NEON (bench/aarch64_icount.sh):"
  echo
  if a=$(bash "$here/aarch64_icount.sh" "$out/aarch64-icount" micro-plain micro embedded 2>&1); then
    printf '%s\n' "$a" | grep -v '^== building'
  else
    echo "(not counted: $(printf '%s\n' "$a" | tail -1))"
  fi
  echo
  echo "Cortex-M (bench/cortex_m_icount.sh, hand-micro with the test fixture's seeded weights):"
  echo
  if [ -z "$header" ] && [ -x "$root/build/tests/handemo_tests_quick" ]; then
    header="$out/micro_model.hpp"
    HANDEMO_WRITE_MICRO_HEADER="$header" "$root/build/tests/handemo_tests_quick" -tc='*fixture*exported header*' >/dev/null 2>&1 \
      || header=""
  fi
  if [ -z "$header" ]; then
    echo "(not counted: no model header; build the tests (cmake --build build) or set HANDEMO_COMPARE_MICRO_HEADER)"
  elif c=$(bash "$here/cortex_m_icount.sh" "$header" "$out/cortex-m-icount" 2>&1); then
    printf '%s\n' "$c"
  else
    echo "(not counted: $(printf '%s\n' "$c" | tail -1))"
  fi
}
echo "== embedded instruction counts"
icount_section | tee "$out/icount.txt"

echo "== comparison"
list() { local f=$1 acc="" r; for r in $(seq 1 "$rounds"); do acc="$acc${acc:+,}$out/${f}_$r.$2"; done; echo "$acc"; }
"$py" "$here/compare_table.py" --isa "${isa:-unknown}" --peak "${peak:-0}" --torch1 "$(list torch1 txt)" \
  --torch2 "$(list torch2 txt)" --conv "$(list conv json)" --layers "$out/conv_layers.json" --stargan "$(list stargan json)" \
  --ort "$(list ort txt)" --quick "$quick" \
  | tee "$out/table.txt"
status=${PIPESTATUS[0]}

if [ "$write_out" = 1 ]; then
  # a file of the chosen name written while the rounds ran (another run of the same day) is kept too
  if [ "$auto_name" = 1 ] && [ -e "$results" ]; then
    taken=$results
    while [ -e "$results" ]; do results="$base-$n.md"; n=$((n + 1)); done
    echo "== $taken appeared during the run; writing $results instead"
  fi
  # the lines before the first table (peaks and bounds) in a code block, as docs/performance.md shows them; a
  # blank line between a table and the text line above it, so that Markdown renders it as a table
  if mkdir -p "$(dirname "$results")" && {
       results_header "$load_rounds"
       echo "Standalone FMA peaks (bench/peak_fma.cpp):"
       echo
       echo '```'; cat "$out/peak.txt"; echo '```'
       echo
       awk 'BEGIN { print "```" }
            !done && /^$/ { print "```"; done = 1 }
            done && /^\|/ && prev != "" && prev !~ /^\|/ { print "" }
            { print; prev = $0 }
            END { if (!done) print "```" }' "$out/table.txt"
       echo
       cat "$out/icount.txt"
     } >"$results"; then
    echo "== wrote $results"
  else
    echo "compare.sh: cannot write $results"; exit 1
  fi
fi
exit "$status"
