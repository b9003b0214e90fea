#!/usr/bin/env python3
"""handemo's generator equals ONNX Runtime's on the same weights and inputs, to 1e-5.

Usage: onnx_test.py HELPER SOURCE_DIR [--plant weight]

For hand-embedded and hand-paper: scripts/reference_stargan.py's G with PyTorch's default initialisation after
torch.manual_seed(0) (the G bench/compare.sh exports) is written as a safetensors file of G parameters and
exported to ONNX (opset 13); a batch of 5 zero-padded motion images with random angles in [-1, 1], one per
target, goes through ONNX Runtime (bench/onnxruntime_bench.js run, the npm package onnxruntime-node) and through
HELPER (golden_generator_output --batch: frozen_generator::infer_batch on the whole batch, and infer() one image
at a time). Every output value of both handemo paths must be within 1e-5 of ONNX Runtime's. Then the same with
binary16 weights: ONNX Runtime runs the model exported with every convolution weight rounded to binary16
(reference_stargan.py's round_conv_weights_to_half(), Tensor.half()), handemo loads the same float weights and
rounds them itself (HELPER ... f16: weight_storage::f16), and both paths must again be within 1e-5. Then the float
model again with handemo's residual convolutions by Winograd's F(3x2, 3x3) (HELPER ... winograd:
conv_algorithm::winograd), both paths within 1e-5.

--plant weight runs the check with one weight of the exported ONNX model off by 1e-3 (main.0.weight[0, 0, 3, 3],
the first convolution's centre tap; handemo loads the weights as they were) and inverts the exit code (0: the
fault was caught).
Exits 77 (skipped), naming what is missing, when python3 cannot import torch (or HANDEMO_TEST_NO_TORCH is set),
when node is not on PATH, or when onnxruntime-node is not installed (bench/onnxruntime_bench.js check; it looks
in $HANDEMO_ORT_DIR/node_modules, default <repository>/build-ort). Runs itself again under /usr/bin/python3
(Debian's python3-torch) when the interpreter it was started with has no torch.
"""
import array
import copy
import json
import os
import shutil
import subprocess
import sys
import tempfile

from golden_common import import_torch, verdict

SKIP = 77
TOL = 1e-5
BATCH = 5


def write_f32(path, values):
    a = array.array("f", values)
    if sys.byteorder != "little":
        a.byteswap()
    with open(path, "wb") as f:
        a.tofile(f)


def read_f32(path):
    a = array.array("f")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    if sys.byteorder != "little":
        a.byteswap()
    return a


def check_config(ref, torch, config, helper, runner, node, work, plant):
    """Errors of one configuration (empty: agreement), and a summary line."""
    from make_golden import st_write

    g, _ = ref.generator_of(config)
    _, _, (h, w, domains) = ref.build(config)
    joints, keyframes = ref.CONFIGS[config][0], ref.CONFIGS[config][1]
    weights = os.path.join(work, f"{config}.safetensors")
    st_write(weights, [(n, "F32", list(p.shape), p.flatten().tolist()) for n, p in g.state_dict().items()])
    if plant == "weight":
        with torch.no_grad():
            g.state_dict()["main.0.weight"][0, 0, 3, 3] += 1e-3
    model = os.path.join(work, f"{config}.onnx")
    ref.write_onnx(g, config, model)
    g_half = copy.deepcopy(g)
    ref.round_conv_weights_to_half(g_half)
    model_half = os.path.join(work, f"{config}_f16.onnx")
    ref.write_onnx(g_half, config, model_half)

    torch.manual_seed(1)
    x = torch.zeros(BATCH, 3, h, w)
    x[:, :, :keyframes, :joints] = torch.rand(BATCH, 3, keyframes, joints) * 2 - 1
    c = torch.zeros(BATCH, domains)
    for n in range(BATCH):
        c[n, n % domains] = 1
    xs, cs = x.flatten().tolist(), c.flatten().tolist()
    errors, lines = [], []
    for kind, onnx_model, extra in (("float weights", model, []), ("binary16 weights", model_half, ["f16"]),
                                    ("float weights, handemo's residual convolutions by Winograd", model, ["winograd"])):
        e, line = compare_paths(config, kind, onnx_model, extra, weights, xs, cs, h, w, helper, runner, node, work)
        errors += e
        lines.append(line)
    return errors, "\n".join(l for l in lines if l)


def compare_paths(config, kind, model, extra, weights, xs, cs, h, w, helper, runner, node, work):
    """Errors of handemo's two paths against ONNX Runtime on `model` (empty: agreement), and a summary line."""
    tag = "".join(ch if ch.isalnum() else "_" for ch in kind)
    paths = {k: os.path.join(work, f"{config}_{tag}_{k}") for k in ("x.f32", "c.f32", "batch.f32", "one.f32", "in.json", "out.json")}
    write_f32(paths["x.f32"], xs)
    write_f32(paths["c.f32"], cs)
    run = subprocess.run([helper, "--batch", config, weights, paths["x.f32"], paths["c.f32"], str(BATCH), paths["batch.f32"],
                          paths["one.f32"]] + extra, capture_output=True, text=True)
    if run.returncode != 0:
        return [f"{config} ({kind}): {helper} exited {run.returncode}: {run.stderr.strip()}"], ""
    with open(paths["in.json"], "w") as f:
        json.dump({"batch": BATCH, "x": xs, "c": cs}, f)
    run = subprocess.run([node, runner, "run", model, paths["in.json"], paths["out.json"]], capture_output=True, text=True)
    if run.returncode != 0:
        return [f"{config} ({kind}): onnxruntime_bench.js run exited {run.returncode}: {(run.stdout + run.stderr).strip()}"], ""
    with open(paths["out.json"]) as f:
        ort = json.load(f)["y"]
    errors, worst = [], {}
    for path in ("batch", "one"):
        mine = read_f32(paths[f"{path}.f32"])
        if len(mine) != len(ort):
            errors.append(f"{config} ({kind}) {path}: {len(mine)} values, ONNX Runtime {len(ort)}")
            continue
        diffs = [abs(a - b) for a, b in zip(mine, ort)]
        i = max(range(len(diffs)), key=diffs.__getitem__)
        worst[path] = diffs[i]
        if not diffs[i] <= TOL:
            errors.append(f"{config} ({kind}) through {'infer_batch' if path == 'batch' else 'infer'}: max |handemo - ONNX Runtime| "
                          f"{diffs[i]:.3g} > {TOL:g} (image {i // (3 * h * w)}, element {i % (3 * h * w)}: {mine[i]:.7g} against {ort[i]:.7g})")
    line = (f"{config}, {kind}, batch {BATCH}: max |handemo - ONNX Runtime| {worst.get('batch', float('nan')):.3g} (infer_batch), "
            f"{worst.get('one', float('nan')):.3g} (infer, one image at a time); tolerance {TOL:g}")
    return errors, line


def main(argv):
    plant = None
    if len(argv) == 4 and argv[2] == "--plant" and argv[3] == "weight":
        plant, argv = argv[3], argv[:2]
    if len(argv) != 2:
        print(__doc__)
        return 2
    helper, root = argv
    # node and onnxruntime-node first: they are what is most often missing, and finding them out costs no
    # torch import (seconds)
    node = shutil.which("node")
    if not node:
        print("SKIP: node is not on PATH (Debian's nodejs; ONNX Runtime runs in it as the npm package onnxruntime-node)")
        return SKIP
    runner = os.path.join(root, "bench", "onnxruntime_bench.js")
    check = subprocess.run([node, runner, "check"], capture_output=True, text=True)
    if check.returncode != 0:
        print((check.stdout + check.stderr).strip() or f"SKIP: onnxruntime_bench.js check exited {check.returncode}")
        return SKIP if check.returncode == SKIP else 1
    missing = import_torch()
    if missing:
        print(f"SKIP: {missing}")
        return SKIP
    import torch

    torch.set_num_threads(1)
    sys.path.insert(0, os.path.join(root, "scripts"))
    import reference_stargan as ref

    print(check.stdout.strip())
    errors = []
    with tempfile.TemporaryDirectory() as work:
        for config in ("hand-embedded", "hand-paper"):
            e, line = check_config(ref, torch, config, helper, runner, node, work, plant)
            errors += e
            if line:
                print(line)
    return verdict(errors, plant)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
