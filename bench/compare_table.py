#!/usr/bin/python3
"""Prints the handemo vs PyTorch vs ONNX Runtime vs FMA-peak tables of compare.sh from the outputs it collected.
bench_stargan results are matched by name: a benchmark whose name contains `paper` or `(64,` (resp.
`embedded` or `(32,`) and `stargan_infer/` is the generator inference (`/b1` batch 1, `/b32` batch 32), one
containing `train` the training step (D+G, batch 16), `stargan_transfer/` the transfer of 32 clips. Anything missing prints n/a. The FLOPs of a call are the
benchmark's FLOP counter (stargan/flops.hpp: counted from the layer shapes), its share of the peak FLOP / time /
peak. onnxruntime_bench.js lines (`onnxruntime <config>(...) b<batch>: <us> us per call, ...`) give ONNX
Runtime's times; each round's ONNX Runtime / handemo ratio is taken within the round (the two ran one after the
other) and the table gives the median of those ratios.
--torch1, --torch2, --conv, --stargan and --ort take a comma-separated list of files, one per round (compare.sh's
HANDEMO_COMPARE_ROUNDS): every time is the median over the rounds, printed with its range; the FMA peaks are
the median of the rounds' best repetitions; the 2-thread / 1-thread ratio of the training step is the median
of the rounds' ratios (each round measures the pair back to back)."""
import argparse, json, os, re, statistics

def load_json(path):
    try:
        with open(path) as f:
            return json.load(f).get("benchmarks", [])
    except (OSError, ValueError):
        return []

def files(arg):
    return [f for f in arg.split(",") if f]

def aggregate(rounds):
    """One entry per benchmark name (iterations only, in the first round's order): the median over the
    rounds of real_time, cpu_time and the rate counters, with each round's wall seconds in `_times`."""
    by_name, order = {}, []
    for r, benches in enumerate(rounds):
        for b in benches:
            if b.get("run_type", "iteration") != "iteration":
                continue
            if b["name"] not in by_name:
                by_name[b["name"]] = {}
                order.append(b["name"])
            by_name[b["name"]].setdefault(r, b)  # the first repetition of a round
    out = []
    for name in order:
        per = by_name[name]
        m = dict(next(iter(per.values())))
        for key in ("real_time", "cpu_time", "GFLOP/s", "GFLOPS"):
            if key in m:
                m[key] = statistics.median(b[key] for b in per.values())
        m["_times"] = {r: seconds(b) for r, b in per.items()}
        out.append(m)
    return out

def seconds(b):
    unit = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b.get("time_unit", "ns")]
    return b["real_time"] * unit  # wall time: what a user waits for

def torch_results(paths):
    """{config: (inference s, train step s, [each round's inference s], [each round's step s])}: medians first."""
    per = {}
    for path in files(paths):
        try:
            for line in open(path):
                m = re.match(r"(\w+)\(.*?\): .*inference b1 ([0-9.]+) us, train step .* ([0-9.]+) ms", line)
                if m:
                    per.setdefault(m.group(1), []).append((float(m.group(2)) * 1e-6, float(m.group(3)) * 1e-3))
        except OSError:
            pass
    return {k: (statistics.median(v[0] for v in vs), statistics.median(v[1] for v in vs), [v[0] for v in vs],
                [v[1] for v in vs]) for k, vs in per.items()}

def gflops(b):
    """A benchmark's GFLOPS (bench_conv) or GFLOP/s (bench_stargan) counter in GFLOP/s (JSON may hold FLOP/s)."""
    g = b.get("GFLOPS", b.get("GFLOP/s", 0)) if b else 0
    return g / 1e9 if g > 1e6 else g

def fmt_t(s):
    return "n/a" if s is None else (f"{s*1e6:.0f} us" if s < 1e-2 else f"{s*1e3:.1f} ms")

def fmt_range(times):
    """ (lo-hi) of a list of seconds when there are several rounds, else "". """
    times = [t for t in times if t is not None]
    if len(times) < 2:
        return ""
    lo, hi = fmt_t(min(times)), fmt_t(max(times))
    if lo.split()[1] == hi.split()[1]:  # same unit: (1866-2182 us)
        return f" ({lo.split()[0]}-{hi})"
    return f" ({lo}-{hi})"

def fmt_b(b):
    """A benchmark's median wall time with its range over the rounds."""
    return "n/a" if b is None else fmt_t(seconds(b)) + fmt_range(b.get("_times", {}).values())

def round_ratios(num, den, scale=1.0):
    """Each round's num x scale / den, sorted: num and den are benchmarks' `_times` ({round: s})."""
    return sorted(num[k] * scale / den[k] for k in num if k in den and den[k])

def best(a, b):
    xs = [v for v in (a, b) if v is not None]
    return min(xs) if xs else None

def ratio(a, b):
    return "n/a" if a is None or b is None or b == 0 else f"{a/b:.2f}x"

ap = argparse.ArgumentParser()
for a in ("--isa", "--peak", "--torch1", "--torch2", "--conv", "--layers", "--stargan", "--ort", "--quick"):
    ap.add_argument(a, default="")
o = ap.parse_args()
if o.quick == "1":
    print("QUICK RUN-THROUGH (compare.sh --quick): every benchmark ran for a moment; no number below is a measurement")
peak = float(o.peak or 0)
t1, t2 = torch_results(o.torch1), torch_results(o.torch2)
conv_rounds = [load_json(f) for f in files(o.conv)]
rounds = max(1, len(conv_rounds))
conv_all = aggregate(conv_rounds)
conv = {b["name"]: b for b in conv_all}
try:
    ctx = json.load(open(files(o.conv)[0])).get("context", {})
except (OSError, ValueError, IndexError):
    ctx = {}
isa = ctx.get("simd_arch") or o.isa or "unknown"
print(f"Kernels compiled for: {isa} ({ctx.get('simd_float_lanes', '?')} float lanes); peak below is {isa}'s")
if rounds > 1:
    print(f"Every number is the median of {rounds} rounds, with its range in parentheses")

def round_peak(prefix):
    """Median over the rounds of each round's best repetition of a peak benchmark (0 when absent)."""
    best_r = [max([gflops(b) for b in bs if b["name"].startswith(prefix) and b.get("run_type") == "iteration"], default=0)
              for bs in conv_rounds]
    best_r = [v for v in best_r if v]
    return (statistics.median(best_r), best_r) if best_r else (0, [])

# the FMA peak of the kernels' ISA measured inside bench_conv (same load as the kernels) wins over the
# standalone one
inproc, inproc_r = round_peak("peak_fma/")
if inproc:
    spread = f" (rounds: {', '.join(f'{v:.1f}' for v in inproc_r)})" if rounds > 1 else ""
    print(f"FMA peak ({isa}): standalone {peak:.1f} GFLOP/s, inside bench_conv {inproc:.1f} GFLOP/s{spread} (used below)")
    peak = inproc
star = aggregate([load_json(f) for f in files(o.stargan) if os.path.exists(f)])

def star_bench(cfg_keys, kind, extra="", exclude=None):
    for b in star:
        n = b["name"].lower()
        if exclude and exclude in n:
            continue
        if any(k in n for k in cfg_keys) and kind in n and extra in n and b.get("run_type", "iteration") == "iteration":
            return b
    return None

print(f"FP32 FMA peak (1 core, {isa}): {peak:.1f} GFLOP/s" if peak else "FP32 FMA peak: n/a")
# the peak two threads get together (peak_fma_threads): on SMT siblings about the 1-thread peak, so a compute-bound
# 2-thread step cannot be below (1-thread peak / 2-thread peak) x the 1-thread step
peak2, _ = round_peak("peak_fma_threads/")
bound = peak / peak2 if peak and peak2 else None
if peak2:
    print(f"FMA peak of 2 threads together: {peak2:.1f} GFLOP/s = {peak2 / peak:.2f}x the 1-thread peak"
          f" (a compute-bound 2-thread step is at best {bound:.2f}x the 1-thread step on this machine)")
print()
print("| config | measure | handemo | PyTorch 1 thr | PyTorch 2 thr | best PyTorch / handemo | fraction of peak (FLOPs performed) |")
print("|---|---|---|---|---|---|---|")
def peak_range(b):
    """ (lo-hi) of a benchmark's fraction of the peak over the rounds (each round's time against the median peak)."""
    ts = list(b.get("_times", {}).values()) if b else []
    if not peak or len(ts) < 2 or not gflops(b):
        return ""
    flop = performed_gflops(b) * seconds(b)  # GFLOP per iteration (the median's rate x the median's time)
    return f" ({flop / max(ts) / peak:.0%}-{flop / min(ts) / peak:.0%})"

def performed_rate(b):
    """GFLOP/s of bench_stargan's performed_FLOP (the FLOPs a call performs: the packed kernels skip the kernel rows
    over the zero padding, Winograd's GEMMs multiply less) over the benchmark's time; None without that counter."""
    perf = b.get("performed_FLOP") if b else None
    return perf / seconds(b) / 1e9 if perf else None

def performed_gflops(b):
    """GFLOP/s of the FLOPs a benchmark performs: performed_rate() where it has one, else its GFLOP(S) counter
    (bench_conv's packed rows count what they perform already)."""
    return performed_rate(b) or gflops(b)

def frac_of_peak(b):
    gfl = performed_gflops(b)
    return f"{gfl/peak:.0%} ({gfl:.1f} GFLOP/s)" if peak and gfl else "n/a"

for cfg, keys, suffix in (("paper", ("paper", "(64,"), "paper(64,6)/b1"), ("embedded", ("embedded", "(32,"), "embedded(32,3)/b1")):
    tp1 = t1.get(cfg, (None, None, [], [])); tp2 = t2.get(cfg, (None, None, [], []))
    for label, gname in (("G conv stack, weights packed once (bench_conv)", "packed_generator_convs/" + suffix),
                         ("G conv stack, unpacked kernels (bench_conv)", "generator_convs/" + suffix)):
        g = conv.get(gname)
        if g:
            print(f"| {cfg} | {label} | {fmt_b(g)} | | | | {frac_of_peak(g)} |")
    # the G inference of the target: frozen_generator (weights packed once), what transfer and the CLI run
    inf_b = star_bench(keys, "stargan_infer/", "/b1")  # not stargan_infer_f16/ nor stargan_infer_unpacked/
    inf = seconds(inf_b) if inf_b else None
    print(f"| {cfg} | **G inference, batch 1, 1 thread** (frozen_generator) | {fmt_b(inf_b)} | {fmt_t(tp1[0])}{fmt_range(tp1[2])} | {fmt_t(tp2[0])}{fmt_range(tp2[2])} | {ratio(best(tp1[0], tp2[0]), inf)} | **{frac_of_peak(inf_b)}**{peak_range(inf_b)} |")
    h_b = star_bench(keys, "infer_f16", "/b1")
    if h_b:
        h = seconds(h_b)
        mb = h_b.get("weight_MB")
        print(f"| {cfg} | G inference, batch 1, 1 thread, binary16 weights (`weight_storage::f16`{f', {mb:.1f} MB' if mb else ''}) | {fmt_b(h_b)} | | | {ratio(best(tp1[0], tp2[0]), h)} | {frac_of_peak(h_b)}{peak_range(h_b)} |")
    un_b = star_bench(keys, "infer_unpacked")
    if un_b:
        un = seconds(un_b)
        print(f"| {cfg} | G inference, batch 1, generator::infer (unpacked) | {fmt_b(un_b)} | | | {ratio(best(tp1[0], tp2[0]), un)} | {frac_of_peak(un_b)} |")
    tr_b = star_bench(keys, "stargan_train/", "threads:2") or star_bench(keys, "stargan_train/")
    tr1_b = star_bench(keys, "stargan_train/", "threads:1")
    tr = seconds(tr_b) if tr_b else None
    tr1 = seconds(tr1_b) if tr1_b else None
    print(f"| {cfg} | train step D+G, batch 16, 2 threads | {fmt_b(tr_b)} | {fmt_t(tp1[1])}{fmt_range(tp1[3])} | {fmt_t(tp2[1])}{fmt_range(tp2[3])} | {ratio(best(tp1[1], tp2[1]), tr)} | |")
    if tr1:
        eff = ""
        if tr:
            # each round's 2-thread and 1-thread steps ran back to back: the median of the rounds' ratios
            t1r = tr1_b.get("_times", {})
            rr = round_ratios(tr_b.get("_times", {}), t1r) or [tr / tr1]
            med = statistics.median(rr)
            each = f" (rounds {', '.join(f'{x:.2f}' for x in rr)})" if len(rr) > 1 else ""
            eff = f"2-thread step = {med:.2f}x the 1-thread step{each}, parallel efficiency {1 / (2 * med):.0%}"
            if bound:
                eff += f"; FMA bound {max(0.5, bound):.2f}x"
            # two independent half-batch trainers stepping at once on two threads: Google Benchmark divides the
            # wall time by the iterations of both threads, so one concurrent step is the reported time x threads
            pair_b = star_bench(keys, "stargan_train_pair/")
            if pair_b:
                nt = pair_b.get("threads", 2)
                prr = round_ratios(pair_b.get("_times", {}), t1r, nt)
                if prr:
                    eff += (f"; two independent half-batch steps at once (the bound with the memory system): "
                            f"{fmt_t(seconds(pair_b) * nt)} = {statistics.median(prr):.2f}x")
        share = frac_of_peak(tr1_b)
        print(f"| {cfg} | train step D+G, batch 16, 1 thread | {fmt_b(tr1_b)} | {fmt_t(tp1[1])} | | {ratio(tp1[1], tr1)} | "
              f"{share if share != 'n/a' else ''}{peak_range(tr1_b)}{'; ' if eff and share != 'n/a' else ''}{eff} |")
print()


def ort_results(paths):
    """{(config, batch): {round: seconds}} of onnxruntime_bench.js's `time` lines, one file per round."""
    per = {}
    for r, path in enumerate(files(paths)):
        try:
            for line in open(path):
                m = re.match(r"onnxruntime (\w+)\(.*?\) b(\d+): ([0-9.]+) us per call", line)
                if m:
                    per.setdefault((m.group(1), int(m.group(2))), {})[r] = float(m.group(3)) * 1e-6
        except OSError:
            pass
    return per


ort = ort_results(o.ort)
print("ONNX Runtime side by side (the same G exported by reference_stargan.py --onnx; one intra-op thread; "
      "handemo: frozen_generator, batch 32 through infer_batch):")
print()
print("| config | batch | handemo | ONNX Runtime | handemo throughput / ONNX Runtime's | handemo clips/s | ONNX Runtime clips/s |")
print("|---|---|---|---|---|---|---|")
# the binary16 rows: both engines run the weights rounded to binary16 (reference_stargan.py --onnx --half-weights), handemo
# storing them as binary16 (stargan_infer_f16/), ONNX Runtime as the float values they are; the Winograd rows: handemo's
# residual convolutions by Winograd's F(3x2, 3x3) (stargan_infer_winograd/, conv_algorithm::winograd) against the same
# ONNX Runtime rows as the first two configs (the same float weights)
for cfg, keys, kind, ort_cfg in (("paper", ("paper", "(64,"), "stargan_infer/", "paper"),
                                 ("embedded", ("embedded", "(32,"), "stargan_infer/", "embedded"),
                                 ("paper, binary16 weights", ("paper", "(64,"), "stargan_infer_f16/", "paper_f16"),
                                 ("embedded, binary16 weights", ("embedded", "(32,"), "stargan_infer_f16/", "embedded_f16"),
                                 ("paper, handemo's residual convolutions by Winograd", ("paper", "(64,"), "stargan_infer_winograd/", "paper"),
                                 ("embedded, handemo's residual convolutions by Winograd", ("embedded", "(32,"), "stargan_infer_winograd/", "embedded")):
    for batch in (1, 32):
        b = star_bench(keys, kind, f"/b{batch}")
        ot = ort.get((ort_cfg, batch), {})
        if (ort_cfg.endswith("_f16") or "winograd" in kind) and not b:
            continue
        o_med = statistics.median(ot.values()) if ot else None
        o_rng = fmt_range(list(ot.values()))
        rr = round_ratios(ot, b.get("_times", {})) if b else []
        ratio_s = (f"{statistics.median(rr):.2f}x" + (f" (rounds {', '.join(f'{x:.2f}' for x in rr)})" if len(rr) > 1 else "")
                   if rr else "n/a")
        h_cps = f"{batch / seconds(b):.0f}" if b else "n/a"
        o_cps = f"{batch / o_med:.0f}" if o_med else "n/a"
        print(f"| {cfg} | {batch} | {fmt_b(b)} | {fmt_t(o_med)}{o_rng} | {ratio_s} | {h_cps} | {o_cps} |")
print()

tr_rows = [(label, star_bench(("embedded",), "stargan_transfer/", suffix, exclude))
           for label, suffix, exclude in (("clip by clip (transfer() with a workspace)", "one_at_a_time", None),
                                          ("in batches of 32 (transfer_batch)", "batch32", "winograd"),
                                          ("in batches of 32, residual convolutions by Winograd (--conv winograd)", "batch32_winograd", None),
                                          ("the shipped gates (statistics for sad: G not run), in batches of 32", "shipped_gates", None))]
if any(b for _, b in tr_rows):
    print("Transfer of 32 clips to sad with the shipped hand-embedded model, 1 thread: keyframes, G, spline, its gate set to "
          "keep G's change; in the last row its own gates, which weigh G's change 0 for sad:")
    print()
    print("| path | 32 clips | per clip | clips/s |")
    print("|---|---|---|---|")
    for label, b in tr_rows:
        print(f"| {label} | {fmt_b(b)} | {fmt_t(seconds(b) / 32) if b else 'n/a'} | {f'{32 / seconds(b):.0f}' if b else 'n/a'} |")
    print()

print("Roofline: FLOPs per call counted from the layer shapes (stargan/flops.hpp; the training step's forward, "
      "backward and the gradient penalty's double backward), against the 1-thread FP32 FMA peak"
      + (f" of {peak:.1f} GFLOP/s" if peak else "") + "; the last column counts the FLOPs the kernels perform "
      "(without the products with the zero padding above and below the image that the weight-stationary kernels skip, "
      "in inference and in training; the `handemo` preset's step, what an evaluation trains, has only that count):")
print()
print("| config | measure | FLOP per call | handemo | GFLOP/s | share of the peak | FLOP performed per call: GFLOP/s (share of the peak) |")
print("|---|---|---|---|---|---|---|")


def fmt_flop(f):
    return "n/a" if not f else (f"{f / 1e9:.2f} G" if f >= 1e9 else f"{f / 1e6:.1f} M")


for cfg, keys in (("paper", ("paper", "(64,")), ("embedded", ("embedded", "(32,"))):
    rows = [("G inference, batch 1", star_bench(keys, "stargan_infer/", "/b1")),
            ("G inference, batch 32 (infer_batch)", star_bench(keys, "stargan_infer/", "/b32")),
            ("train step D+G, batch 16, 1 thread", star_bench(keys, "stargan_train/", "threads:1"))]
    preset = star_bench(keys, "stargan_train_preset/", "threads:1")  # only where bench_stargan has the preset's row
    if preset:
        rows.append(("train step, `handemo` preset, batch 16, 1 thread", preset))
    for label, b in rows:
        # FLOP over the median wall time (what the user waits for), each round's range against the median peak
        flop = b.get("FLOP") if b else None
        gfl = flop / seconds(b) / 1e9 if flop else None
        ts = list(b.get("_times", {}).values()) if b else []
        rng = f" ({flop / max(ts) / 1e9 / peak:.0%}-{flop / min(ts) / 1e9 / peak:.0%})" if gfl and peak and len(ts) > 1 else ""
        # the weight-stationary kernels skip the kernel rows over the zero padding, so they perform fewer FLOPs
        perf, gp = (b.get("performed_FLOP"), performed_rate(b)) if b else (None, None)
        perf_s = (f"{fmt_flop(perf)}: {gp:.1f} ({gp / peak:.0%})" if gp and peak else
                  (f"{fmt_flop(perf)}: {gp:.1f}" if gp else "as counted"))
        print(f"| {cfg} | {label} | {fmt_flop(flop)} | {fmt_b(b)} | {f'{gfl:.1f}' if gfl else 'n/a'} | "
              f"{f'{gfl / peak:.0%}' if gfl and peak else 'n/a'}{rng} | {perf_s} |")
print()
# Winograd's residual convolutions: the same G's FLOPs (direct convolution) per second, beside the FLOPs the call
# performs (its GEMMs' multiply-adds in place of the direct ones)
wrows = [(cfg, batch, star_bench(keys, "stargan_infer_winograd/", f"/b{batch}"))
         for cfg, keys in (("paper", ("paper", "(64,")), ("embedded", ("embedded", "(32,"))) for batch in (1, 32)]
if any(b for _, _, b in wrows):
    print("G inference with the residual convolutions by Winograd's F(3x2, 3x3) (`conv_algorithm::winograd`): the G's FLOPs "
          "per second as above (a share above 100% is more than the direct convolution can do), and the FLOPs it performs:")
    print()
    print("| config | batch | handemo | against the direct row | G's FLOPs per second (share of the peak) | FLOPs performed per call | performed per second (share of the peak) |")
    print("|---|---|---|---|---|---|---|")
    for cfg, batch, b in wrows:
        if not b:
            continue
        keys = ("paper", "(64,") if cfg == "paper" else ("embedded", "(32,")
        d = star_bench(keys, "stargan_infer/", f"/b{batch}")
        vs = f"{seconds(d) / seconds(b):.2f}x faster" if d else "n/a"
        flop, perf = b.get("FLOP"), b.get("performed_FLOP")
        g1 = flop / seconds(b) / 1e9 if flop else None
        g2 = performed_rate(b)
        share = lambda g: f"{g:.1f} ({g / peak:.0%})" if g and peak else (f"{g:.1f}" if g else "n/a")
        print(f"| {cfg} | {batch} | {fmt_b(b)} | {vs} | {share(g1)} | {fmt_flop(perf)} | {share(g2)} |")
    print()
# the iteration the product trains (handemo preset: a fourth pass of G for the identity term, EMA, augmentation)
pre_rows = [(name, star_bench((key,), "stargan_train_preset/", "threads:1"))
            for name, key in (("hand-embedded", "preset/embedded("), ("body-embedded", "preset/body-embedded("))]
if any(b for _, b in pre_rows):
    paper_step = star_bench(("embedded", "(32,"), "stargan_train/", "threads:1")
    print("Training iteration of the handemo preset (what `handemo train` and `handemo eval` run), batch 16, 1 thread:")
    print()
    print("| config | handemo preset | against the paper's options' step (hand-embedded, the roofline's row) |")
    print("|---|---|---|")
    for name, b in pre_rows:
        ratio = f"{seconds(b) / seconds(paper_step):.2f}x" if b and paper_step else "n/a"
        print(f"| {name} | {fmt_b(b)} | {ratio} |")
    print()
layers = load_json(o.layers)
if layers:
    print("Per-layer conv kernels (CPU time GFLOP/s" + (f", fraction of {peak:.0f} GFLOP/s peak" if peak else "") + "):")
    print("| layer / pass / batch | time | GFLOP/s | of peak |")
    print("|---|---|---|---|")
    for b in layers:
        gfl = gflops(b)
        print(f"| {b['name']} | {fmt_t(b['cpu_time'] * {'ns':1e-9,'us':1e-6,'ms':1e-3,'s':1.0}[b.get('time_unit','ns')])} | {gfl:.1f} | {gfl/peak:.0%} |" if peak else
              f"| {b['name']} | | {gfl:.1f} | n/a |")
