#!/usr/bin/python3
"""handemo's StarGAN in PyTorch (CPU): the side-by-side anchor of bench/compare.sh and the reference of the
golden generator test (tests/golden/).

The networks are the official StarGAN's (Choi et al. 2018) as include/handemo/stargan/model.hpp lays them out,
with the same parameter names, so a generator.safetensors written by `handemo train` (G) or a checkpoint's
`G_ema.*` / `G.*` tensors load with load_state_dict(strict=True):
  G: main.0 conv7 (3 + C -> cd) / main.1 IN / ReLU, two [conv4 s2 / IN / ReLU] down to 4 cd, R residual
     blocks main.<9+r>.main.{0,1,3,4} (conv3 / IN / ReLU / conv3 / IN, plus the block's input), two
     [convT4 s2 / IN / ReLU] up to cd, main.<15+R> conv7 (cd -> 3), tanh; no biases, InstanceNorm affine
     with eps 1e-5. The target label is tiled as C extra input channels. A residual G (the training option
     `residual`) returns x + tanh(...).
  D: d_repeat x [conv4 s2 with bias / LeakyReLU(0.01)] named main.<2i>, src head conv1 (3x3, 1 channel), cls
     head conv2 whose kernel is the whole remaining map; neither head has a bias.
Motion images are K x J x 3 zero-padded to H x W = round_up(K, 4) x round_up(J, 4).

Usage:
  /usr/bin/python3 scripts/reference_stargan.py [threads] [--quick]
      For hand-paper (conv_dim 64, 6 blocks) and hand-embedded (32, 3), prints one line each:
      `<name>(<conv_dim>,<blocks>): G params P, inference b1 T us, train step (D+G, b16, GP) S ms`:
      batch-1 generator inference latency (no autograd) and one training step (D step with WGAN-GP, then G
      step with adversarial, reconstruction and classification losses; Adam on both; batch 16).
      --quick: 3 inference calls and 1 training step instead of 200 and 10 (a run-through, not a measurement).
  /usr/bin/python3 scripts/reference_stargan.py --params CONFIG
      Prints G's and D's parameter names and shapes of a configuration (hand-embedded, hand-paper,
      body-embedded, hand-micro, hand-tiny), one `G <name> <shape>` / `D <name> <shape>` line each.
  /usr/bin/python3 scripts/reference_stargan.py --onnx SOURCE OUT.onnx
      Exports G to ONNX (torch.onnx.export, opset 13; needs no `onnx` package) for ONNX Runtime: inputs
      x [batch, 3, H, W] and c [batch, C] (one-hot), output y [batch, 3, H, W], the batch a dynamic axis.
      SOURCE is a configuration name (its G with PyTorch's default initialisation after torch.manual_seed(0),
      the G the benchmark times) or a checkpoint / generator.safetensors written by handemo (load_generator).
      Prints `onnx <OUT.onnx>: <config>, H x W, C domains, P parameters`.
  /usr/bin/python3 scripts/reference_stargan.py --onnx SOURCE OUT.onnx --half-weights
      The same with every convolution weight rounded to IEEE binary16 first (Tensor.half(), stored back as float):
      the model handemo runs with binary16 weights (weight_storage::f16), for ONNX Runtime in float.

Needs Debian's python3-torch (./setup.sh --golden). Checkpoints are read with the plain-Python safetensors
reader of scripts/make_golden.py (st_read); the module functions load_generator() and build() are what the
golden test imports.
"""
import json
import os
import sys
import time

import torch
import torch.nn as nn
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_golden import st_read  # noqa: E402  (plain-Python safetensors reader, no torch needed)

# (joints, keyframes, domains, conv_dim, res_blocks, d_repeat) of include/handemo/stargan/configs.hpp
CONFIGS = {
    "hand-embedded": (23, 9, 5, 32, 3, 3),
    "hand-paper": (23, 9, 5, 64, 6, 3),
    "body-embedded": (22, 9, 8, 32, 3, 3),
    "hand-micro": (23, 9, 5, 8, 3, 3),
    "hand-tiny": (23, 9, 5, 8, 1, 3),
}


def padded(n):
    """n rounded up to a multiple of 4: the generator's two stride-2 stages return the input size."""
    return (n + 3) // 4 * 4


def conv_in(ch_in, ch_out, kernel, stride, pad, relu=True, transposed=False):
    """[conv or convT without bias, InstanceNorm(affine), ReLU?]: three Sequential slots, as StarGAN numbers them."""
    conv = (nn.ConvTranspose2d if transposed else nn.Conv2d)(ch_in, ch_out, kernel, stride, pad, bias=False)
    layers = [conv, nn.InstanceNorm2d(ch_out, affine=True, eps=1e-5)]
    return layers + ([nn.ReLU(inplace=True)] if relu else [])


class ResidualBlock(nn.Module):
    """x + IN(conv3(ReLU(IN(conv3(x))))): parameters main.0, main.1, main.3, main.4."""

    def __init__(self, ch):
        super().__init__()
        self.main = nn.Sequential(*conv_in(ch, ch, 3, 1, 1), *conv_in(ch, ch, 3, 1, 1, relu=False))

    def forward(self, x):
        return x + self.main(x)


class Generator(nn.Module):
    """G(x [N, 3, H, W], c [N, C] one-hot) -> [N, 3, H, W]."""

    def __init__(self, conv_dim, res_blocks, domains, residual=False):
        super().__init__()
        self.residual = residual
        cd = conv_dim
        layers = conv_in(3 + domains, cd, 7, 1, 3)
        layers += conv_in(cd, 2 * cd, 4, 2, 1) + conv_in(2 * cd, 4 * cd, 4, 2, 1)
        layers += [ResidualBlock(4 * cd) for _ in range(res_blocks)]
        layers += conv_in(4 * cd, 2 * cd, 4, 2, 1, transposed=True) + conv_in(2 * cd, cd, 4, 2, 1, transposed=True)
        layers += [nn.Conv2d(cd, 3, 7, 1, 3, bias=False), nn.Tanh()]
        self.main = nn.Sequential(*layers)

    def forward(self, x, c):
        tiled = c[:, :, None, None].expand(-1, -1, x.shape[2], x.shape[3])
        y = self.main(torch.cat([x, tiled], dim=1))
        return x + y if self.residual else y


class Discriminator(nn.Module):
    """D(x [N, 3, H, W]) -> (src [N, 1, h, w], cls [N, C])."""

    def __init__(self, conv_dim, d_repeat, domains, height, width):
        super().__init__()
        layers, ch_in, ch_out, h, w = [], 3, conv_dim, height, width
        for _ in range(d_repeat):
            layers += [nn.Conv2d(ch_in, ch_out, 4, 2, 1), nn.LeakyReLU(0.01)]
            ch_in, ch_out = ch_out, 2 * ch_out
            h, w = (h + 2 - 4) // 2 + 1, (w + 2 - 4) // 2 + 1
        self.main = nn.Sequential(*layers)
        self.conv1 = nn.Conv2d(ch_in, 1, 3, 1, 1, bias=False)
        self.conv2 = nn.Conv2d(ch_in, domains, (h, w), bias=False)

    def forward(self, x):
        h = self.main(x)
        return self.conv1(h), self.conv2(h).flatten(1)


def build(config, residual=False):
    """(G, D, (H, W, C)) of a named configuration, PyTorch's default initialisation."""
    if config not in CONFIGS:
        raise ValueError(f"unknown configuration '{config}', expected one of {', '.join(CONFIGS)}")
    joints, keyframes, domains, cd, blocks, d_repeat = CONFIGS[config]
    h, w = padded(keyframes), padded(joints)
    return (Generator(cd, blocks, domains, residual), Discriminator(cd, d_repeat, domains, h, w), (h, w, domains))


def load_generator(path):
    """The generator of a checkpoint or generator.safetensors written by handemo, loaded with strict=True.
    The G_ema.* tensors win over G.*; a file of bare names (generator.safetensors) loads as it is. The
    configuration and the residual flag come from the `handemo` metadata (hand-embedded and not residual
    when the file has none). Returns (G in eval mode, metadata dict)."""
    meta, tensors = st_read(path)
    info = json.loads(meta["handemo"]) if "handemo" in meta else {}
    options = info.get("options", {}) if isinstance(info.get("options"), dict) else {}
    g, _, _ = build(info.get("config", "hand-embedded"), bool(options.get("residual", False)))
    names = set(tensors)
    prefix = "G_ema." if "G_ema.main.0.weight" in names else "G." if "G.main.0.weight" in names else ""
    dtypes = {"F16": torch.float32, "F32": torch.float32, "F64": torch.float64}  # binary16 values held exactly in float
    state = {}
    for name, (dt, shape, values) in tensors.items():
        if name.startswith(prefix):
            state[name[len(prefix):]] = torch.tensor(values, dtype=dtypes[dt]).reshape(shape)
    g.load_state_dict(state, strict=True)
    return g.eval(), info


def seconds_per_call(fn, calls):
    """Mean wall seconds of fn() over `calls` calls after two warm-up calls."""
    fn()
    fn()
    start = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - start) / calls


def benchmark(config, infer_calls=200, step_calls=10):
    """(G parameters, inference seconds at batch 1, training step seconds at batch 16) of a configuration."""
    g, d, (h, w, domains) = build(config)
    params = sum(p.numel() for p in g.parameters())
    x1 = torch.rand(1, 3, h, w) * 2 - 1
    c1 = F.one_hot(torch.tensor([2]), domains).float()
    with torch.no_grad():
        t_infer = seconds_per_call(lambda: g(x1, c1), infer_calls)

    batch, lambda_cls, lambda_rec, lambda_gp = 16, 1.0, 10.0, 10.0
    opt_g = torch.optim.Adam(g.parameters(), 1e-4, betas=(0.5, 0.999))
    opt_d = torch.optim.Adam(d.parameters(), 1e-4, betas=(0.5, 0.999))
    x = torch.rand(batch, 3, h, w) * 2 - 1
    label_org = torch.randint(0, domains, (batch,))
    label_trg = label_org[torch.randperm(batch)]
    c_org = F.one_hot(label_org, domains).float()
    c_trg = F.one_hot(label_trg, domains).float()

    def train_step():
        # D: -src(x) + src(G(x, c_trg)) + classification of x + WGAN-GP on x_hat
        src_real, cls_real = d(x)
        fake = g(x, c_trg).detach()
        src_fake, _ = d(fake)
        alpha = torch.rand(batch, 1, 1, 1)
        x_hat = (alpha * x + (1 - alpha) * fake).requires_grad_(True)
        src_hat, _ = d(x_hat)
        grad, = torch.autograd.grad(src_hat, x_hat, torch.ones_like(src_hat), create_graph=True)
        penalty = ((grad.flatten(1).norm(2, dim=1) - 1) ** 2).mean()
        loss_d = (-src_real.mean() + src_fake.mean() + lambda_cls * F.cross_entropy(cls_real, label_org)
                  + lambda_gp * penalty)
        opt_d.zero_grad()
        loss_d.backward()
        opt_d.step()
        # G: -src(G(x, c_trg)) + reconstruction G(G(x, c_trg), c_org) + classification of the fake
        fake = g(x, c_trg)
        src_fake, cls_fake = d(fake)
        rec = g(fake, c_org)
        loss_g = (-src_fake.mean() + lambda_rec * (x - rec).abs().mean()
                  + lambda_cls * F.cross_entropy(cls_fake, label_trg))
        opt_g.zero_grad()
        loss_g.backward()
        opt_g.step()

    t_step = seconds_per_call(train_step, step_calls)
    return params, t_infer, t_step


def generator_of(source):
    """(G in eval mode, config) of a configuration name (PyTorch's default initialisation after
    torch.manual_seed(0)) or of a checkpoint / generator.safetensors written by handemo."""
    if source in CONFIGS:
        torch.manual_seed(0)
        g, _, _ = build(source)
        return g.eval(), source
    g, info = load_generator(source)
    return g, info.get("config", "hand-embedded")


def round_conv_weights_to_half(g):
    """Rounds every convolution weight of G (4-d `.weight` parameters, the transposed convolutions' included) to IEEE
    binary16 and back in place (Tensor.half(): to nearest, ties to even), as handemo's weight_storage::f16 stores them;
    the instance norms' parameters stay float. Returns the number of values rounded."""
    n = 0
    with torch.no_grad():
        for name, p in g.named_parameters():
            if name.endswith(".weight") and p.dim() == 4:
                p.copy_(p.half().float())
                n += p.numel()
    return n


def write_onnx(g, config, path):
    """G of a configuration written to `path` as ONNX opset 13 with a dynamic batch axis (inputs x, c; output y).
    Returns (H, W, C)."""
    import warnings

    _, _, (h, w, domains) = build(config)
    x = torch.zeros(1, 3, h, w)
    c = torch.zeros(1, domains)
    axes = {"x": {0: "batch"}, "c": {0: "batch"}, "y": {0: "batch"}}
    with warnings.catch_warnings():
        # InstanceNorm2d without running statistics normalises by the instance's own statistics in eval mode
        # too, which is what ONNX's InstanceNormalization does; torch warns about its train flag regardless
        warnings.simplefilter("ignore", UserWarning)
        torch.onnx.export(g.eval(), (x, c), path, opset_version=13, input_names=["x", "c"], output_names=["y"],
                          dynamic_axes=axes)
    return h, w, domains


def main(argv):
    if argv[:1] == ["--onnx"] and (len(argv) == 3 or (len(argv) == 4 and argv[3] == "--half-weights")):
        g, config = generator_of(argv[1])
        half = len(argv) == 4 and round_conv_weights_to_half(g)
        h, w, domains = write_onnx(g, config, argv[2])
        params = sum(p.numel() for p in g.parameters())
        print(f"onnx {argv[2]}: {config}, {h} x {w}, {domains} domains, {params} parameters"
              + (f", {half} convolution weights rounded to binary16" if half else ""))
        return 0
    if len(argv) == 2 and argv[0] == "--params":
        g, d, _ = build(argv[1])
        for tag, net in (("G", g), ("D", d)):
            for name, p in net.state_dict().items():
                print(tag, name, list(p.shape))
        return 0
    quick = "--quick" in argv
    argv = [a for a in argv if a != "--quick"]
    if len(argv) > 1 or (argv and not argv[0].isdigit()):
        print(__doc__)
        return 2
    torch.set_num_threads(int(argv[0]) if argv else 1)
    torch.manual_seed(0)
    for label, config in (("paper", "hand-paper"), ("embedded", "hand-embedded")):
        _, _, _, cd, blocks, _ = CONFIGS[config]
        params, t_infer, t_step = benchmark(config, *((3, 1) if quick else (200, 10)))
        print(f"{label}({cd},{blocks}): G params {params}, inference b1 {t_infer * 1e6:.0f} us, "
              f"train step (D+G, b16, GP) {t_step * 1e3:.1f} ms", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
