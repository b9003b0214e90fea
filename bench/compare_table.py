#!/usr/bin/python3
"""Prints the handemo vs PyTorch vs FMA-peak table of compare.sh from the outputs it collected.
bench_stargan results are matched by name: a benchmark whose name contains `paper` or `64` (resp.
`embedded` or `32`) and `infer` is the batch-1 generator inference, one containing `train` the training
step (D+G, batch 16). Anything missing prints n/a."""
import argparse, json, os, re

def load_json(path):
    try:
        with open(path) as f:
            return json.load(f).get("benchmarks", [])
    except (OSError, ValueError):
        return []

def seconds(b):
    unit = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b.get("time_unit", "ns")]
    return b["real_time"] * unit  # wall time: what a user waits for

def torch_results(path):
    r = {}
    try:
        for line in open(path):
            m = re.match(r"(\w+)\(.*?\): .*inference b1 ([0-9.]+) us, train step .* ([0-9.]+) ms", line)
            if m:
                r[m.group(1)] = (float(m.group(2)) * 1e-6, float(m.group(3)) * 1e-3)
    except OSError:
        pass
    return r

def gflops(b):
    """A benchmark's GFLOPS (bench_conv) or GFLOP/s (bench_stargan) counter in GFLOP/s (JSON may hold FLOP/s)."""
    g = b.get("GFLOPS", b.get("GFLOP/s", 0)) if b else 0
    return g / 1e9 if g > 1e6 else g

def fmt_t(s):
    return "n/a" if s is None else (f"{s*1e6:.0f} us" if s < 1e-2 else f"{s*1e3:.1f} ms")

def best(a, b):
    xs = [v for v in (a, b) if v is not None]
    return min(xs) if xs else None

def ratio(a, b):
    return "n/a" if a is None or b is None or b == 0 else f"{a/b:.2f}x"

ap = argparse.ArgumentParser()
for a in ("--isa", "--peak", "--torch1", "--torch2", "--conv", "--layers", "--stargan"):
    ap.add_argument(a, default="")
o = ap.parse_args()
peak = float(o.peak or 0)
t1, t2 = torch_results(o.torch1), torch_results(o.torch2)
conv_all = load_json(o.conv)
conv = {b["name"]: b for b in conv_all}
try:
    ctx = json.load(open(o.conv)).get("context", {})
except (OSError, ValueError):
    ctx = {}
isa = ctx.get("simd_arch") or o.isa or "unknown"
print(f"Kernels compiled for: {isa} ({ctx.get('simd_float_lanes', '?')} float lanes); peak below is {isa}'s")
# the FMA peak of the kernels' ISA measured inside bench_conv (same load as the kernels) wins over the
# standalone one
inproc = [gflops(b) for b in conv_all if b["name"].startswith("peak_fma/") and b.get("run_type") == "iteration"]
if inproc:
    print(f"FMA peak ({isa}): standalone {peak:.1f} GFLOP/s, inside bench_conv {max(inproc):.1f} GFLOP/s (used below)")
    peak = max(inproc)
star = load_json(o.stargan) if os.path.exists(o.stargan) else []

def star_bench(cfg_keys, kind, extra="", exclude=None):
    for b in star:
        n = b["name"].lower()
        if exclude and exclude in n:
            continue
        if any(k in n for k in cfg_keys) and kind in n and extra in n and b.get("run_type", "iteration") == "iteration":
            return b
    return None

def star_find(cfg_keys, kind, extra="", exclude=None):
    b = star_bench(cfg_keys, kind, extra, exclude)
    return seconds(b) if b else None

print(f"FP32 FMA peak (1 core, {isa}): {peak:.1f} GFLOP/s" if peak else "FP32 FMA peak: n/a")
# the peak two threads get together (peak_fma_threads): on SMT siblings about the 1-thread peak, so a compute-bound
# 2-thread step cannot be below (1-thread peak / 2-thread peak) x the 1-thread step
peak2 = max([gflops(b) for b in conv_all if b["name"].startswith("peak_fma_threads/") and b.get("run_type") == "iteration"],
            default=0)
bound = peak / peak2 if peak and peak2 else None
if peak2:
    print(f"FMA peak of 2 threads together: {peak2:.1f} GFLOP/s = {peak2 / peak:.2f}x the 1-thread peak"
          f" (a compute-bound 2-thread step is at best {bound:.2f}x the 1-thread step on this machine)")
print()
print("| config | measure | handemo | PyTorch 1 thr | PyTorch 2 thr | best PyTorch / handemo | fraction of peak |")
print("|---|---|---|---|---|---|---|")
def frac_of_peak(b):
    gfl = gflops(b)
    return f"{gfl/peak:.0%} ({gfl:.1f} GFLOP/s)" if peak and gfl else "n/a"

for cfg, keys, suffix in (("paper", ("paper", "64"), "paper(64,6)/b1"), ("embedded", ("embedded", "32"), "embedded(32,3)/b1")):
    tp1 = t1.get(cfg, (None, None)); tp2 = t2.get(cfg, (None, None))
    for label, gname in (("G conv stack, weights packed once (bench_conv)", "packed_generator_convs/" + suffix),
                         ("G conv stack, unpacked kernels (bench_conv)", "generator_convs/" + suffix)):
        g = conv.get(gname)
        if g:
            print(f"| {cfg} | {label} | {fmt_t(seconds(g))} | | | | {frac_of_peak(g)} |")
    # the G inference of the target: frozen_generator (weights packed once), what transfer and the CLI run
    inf_b = star_bench(keys, "stargan_infer/")  # not stargan_infer_f16/ nor stargan_infer_unpacked/
    inf = seconds(inf_b) if inf_b else None
    print(f"| {cfg} | **G inference, batch 1, 1 thread** (frozen_generator) | {fmt_t(inf)} | {fmt_t(tp1[0])} | {fmt_t(tp2[0])} | {ratio(best(tp1[0], tp2[0]), inf)} | **{frac_of_peak(inf_b)}** |")
    h_b = star_bench(keys, "infer_f16")
    if h_b:
        h = seconds(h_b)
        mb = h_b.get("weight_MB")
        print(f"| {cfg} | G inference, batch 1, 1 thread, binary16 weights (`weight_storage::f16`{f', {mb:.1f} MB' if mb else ''}) | {fmt_t(h)} | | | {ratio(best(tp1[0], tp2[0]), h)} | {frac_of_peak(h_b)} |")
    un_b = star_bench(keys, "infer_unpacked")
    if un_b:
        un = seconds(un_b)
        print(f"| {cfg} | G inference, batch 1, generator::infer (unpacked) | {fmt_t(un)} | | | {ratio(best(tp1[0], tp2[0]), un)} | {frac_of_peak(un_b)} |")
    tr = star_find(keys, "train", "threads:2") or star_find(keys, "train")
    tr1 = star_find(keys, "train", "threads:1")
    print(f"| {cfg} | train step D+G, batch 16, 2 threads | {fmt_t(tr)} | {fmt_t(tp1[1])} | {fmt_t(tp2[1])} | {ratio(best(tp1[1], tp2[1]), tr)} | |")
    if tr1:
        eff = f"2-thread step = {tr/tr1:.2f}x the 1-thread step, parallel efficiency {tr1/(2*tr):.0%}" if tr else ""
        if tr and bound:
            eff += f"; machine bound {max(0.5, bound):.2f}x"
        print(f"| {cfg} | train step D+G, batch 16, 1 thread | {fmt_t(tr1)} | {fmt_t(tp1[1])} | | {ratio(tp1[1], tr1)} | {eff} |")
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
