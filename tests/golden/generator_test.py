#!/usr/bin/env python3
"""The shipped hand-embedded model's generator in handemo equals the PyTorch reference on the same weights.

Usage: generator_test.py HELPER SOURCE_DIR [--plant name|sign]

HELPER is the built golden_generator_output (tests/golden/generator_output.cpp). It prints the input image x,
G(x, c) for every one-hot target c through generator::infer and frozen_generator, and the parameter names and
shapes of handemo's G and D. This script loads SOURCE_DIR/data/models/hand-embedded/checkpoint.safetensors
(its G_ema.* tensors) into scripts/reference_stargan.py's Generator with load_state_dict(strict=True), runs it
in float64 on the same x, and requires every output value within 1e-4 of both handemo paths. The reference's
G and D state_dict names and shapes must equal handemo's, in order.

--plant runs the check on a planted fault and inverts the exit code (0: the fault was caught):
  name  one generator parameter renamed (main.1.weight -> main.1.gamma) before the strict load
  sign  the sign of the last convolution's weights flipped after loading
Runs itself again under /usr/bin/python3 (where Debian's python3-torch lives) when the interpreter it was started
with has no torch. Exits 77 (skipped) when neither can import torch, or when HANDEMO_TEST_NO_TORCH is set (the
test of the skip itself).
"""
import json
import os
import subprocess
import sys

from golden_common import import_torch, verdict

SKIP = 77
TOL = 1e-4


def main(argv):
    plant = None
    if len(argv) == 4 and argv[2] == "--plant" and argv[3] in ("name", "sign"):
        plant, argv = argv[3], argv[:2]
    if len(argv) != 2:
        print(__doc__)
        return 2
    helper, root = argv
    missing = import_torch()
    if missing:
        print(f"SKIP: {missing}")
        return SKIP
    import torch
    sys.path.insert(0, os.path.join(root, "scripts"))
    import reference_stargan as ref

    checkpoint = os.path.join(root, "data", "models", "hand-embedded", "checkpoint.safetensors")
    run = subprocess.run([helper, checkpoint], capture_output=True, text=True)
    if run.returncode != 0:
        print(f"{helper} exited {run.returncode}: {run.stderr.strip()}")
        return 1
    out = json.loads(run.stdout)
    errors = []

    g, info = ref.load_generator(checkpoint)
    if plant == "name":
        state = g.state_dict()
        state["main.1.gamma"] = state.pop("main.1.weight")
        try:
            g.load_state_dict(state, strict=True)
        except RuntimeError as e:
            errors.append(f"strict load of the reference generator: {str(e).splitlines()[0]}")
    _, d, (h, w, domains) = ref.build(info["config"])
    if (h, w, domains) != (out["H"], out["W"], out["C"]) or info["config"] != out["config"]:
        errors.append(f"reference {info['config']} {h}x{w}, {domains} domains; handemo {out['config']} "
                      f"{out['H']}x{out['W']}, {out['C']} domains")
    if g.residual != out["residual"]:
        errors.append(f"reference residual {g.residual}, handemo {out['residual']}")
    for tag, net, theirs in (("G", g, out["g_params"]), ("D", d, out["d_params"])):
        ours = [[n, list(p.shape)] for n, p in net.state_dict().items()]
        if ours != theirs:
            diff = [f"{a} != {b}" for a, b in zip(ours, theirs) if a != b][:3]
            errors.append(f"{tag} parameters: reference {len(ours)}, handemo {len(theirs)}; first differences {diff}")

    torch.set_num_threads(1)
    g = g.double()
    if plant == "sign":
        last = f"main.{len(g.main) - 2}.weight"
        with torch.no_grad():
            g.state_dict()[last].neg_()
    x = torch.tensor(out["x"], dtype=torch.float64).reshape(1, 3, h, w)
    worst = {"infer": 0.0, "frozen": 0.0}
    with torch.no_grad():
        for t in range(domains):
            c = torch.zeros(1, domains, dtype=torch.float64)
            c[0, t] = 1
            y = g(x, c).flatten()
            for path in worst:
                mine = torch.tensor(out[path][t]["y"], dtype=torch.float64)
                err = (mine - y).abs().max().item()
                worst[path] = max(worst[path], err)
                if not err <= TOL:
                    i = int((mine - y).abs().argmax())
                    errors.append(f"G(x, target {t}) through {path}: max |handemo - reference| {err:.3g} > {TOL:g} "
                                  f"(element {i}: {mine[i].item():.7g} against {y[i].item():.7g})")
    print(f"hand-embedded G_ema, {domains} targets, float64 reference: max |handemo - reference| "
          f"{worst['infer']:.3g} (generator::infer), {worst['frozen']:.3g} (frozen_generator); tolerance {TOL:g}")
    return verdict(errors, plant)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
