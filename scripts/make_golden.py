#!/usr/bin/python3
"""Writes handemo's PyTorch golden fixtures (tests/fixtures/*.safetensors) and checks safetensors files
written by handemo's C++ writer.

Usage:
  python3 scripts/make_golden.py [out_dir]            regenerate the fixtures (needs python3-torch;
                                                      ./setup.sh --golden installs it)
  python3 scripts/make_golden.py --check-roundtrip F  read F (written by tests/nn/safetensors_test.cpp)
                                                      with the Python reader below and verify its contents;
                                                      needs only python3 (no torch)

Debian has no python3-safetensors, so the format (8-byte little-endian header length, JSON header with
dtype/shape/data_offsets and optional __metadata__, raw little-endian data) is written and read here
with struct + json, as the reference implementation lays it out (header padded with spaces to 8 bytes).

Fixtures (seeded with torch.manual_seed; float32 except the StarGAN one, computed and stored in float64):
  ops.safetensors      per op: inputs, output, a random upstream gradient `gy`, input gradients
  stargan_tiny.safetensors  a tiny StarGAN G and D with the layout of scripts/reference_stargan.py
                       (official StarGAN parameter names), inputs, outputs, losses, parameter gradients of
                       L_D (with WGAN-GP), of the gradient penalty alone (create_graph=True double backward)
                       and of L_G
  adam.safetensors     torch.optim.Adam steps on a small tensor with given gradients (F32 and F64)
  f16.safetensors      binary16 rounding (Tensor.half()) of special values, ties and random values of every scale
"""
import array
import json
import math
import os
import struct
import sys

# ---------------------------------------------------------------- safetensors in plain Python
FMT = {"F32": ("f", 4), "F64": ("d", 8), "I64": ("q", 8), "I32": ("i", 4), "U8": ("B", 1),
       "I8": ("b", 1), "U64": ("Q", 8), "U32": ("I", 4), "I16": ("h", 2), "U16": ("H", 2), "BOOL": ("B", 1),
       "F16": ("e", 2)}


def st_write(path, tensors, metadata=None):
    """tensors: list of (name, dtype, shape, flat list of numbers)."""
    header, blobs, off = {}, [], 0
    if metadata:
        header["__metadata__"] = {str(k): str(v) for k, v in metadata.items()}
    for name, dt, shape, values in tensors:
        code, size = FMT[dt]
        n = 1
        for d in shape:
            n *= d
        assert len(values) == n, (name, shape, len(values))
        blob = array.array(code, values).tobytes() if n else b""
        if sys.byteorder != "little":
            a = array.array(code, values); a.byteswap(); blob = a.tobytes()
        header[name] = {"dtype": dt, "shape": list(shape), "data_offsets": [off, off + len(blob)]}
        blobs.append(blob)
        off += len(blob)
    h = json.dumps(header, separators=(",", ":")).encode()
    h += b" " * ((8 - len(h) % 8) % 8)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(struct.pack("<Q", len(h)))
        f.write(h)
        for b in blobs:
            f.write(b)
    os.replace(tmp, path)


def st_read(path):
    """Returns (metadata, {name: (dtype, shape, flat list)}), validating the layout."""
    with open(path, "rb") as f:
        raw = f.read()
    if len(raw) < 8:
        raise ValueError(f"{path}: truncated")
    (n,) = struct.unpack("<Q", raw[:8])
    if n > len(raw) - 8:
        raise ValueError(f"{path}: header length {n} beyond file")
    header = json.loads(raw[8:8 + n].decode("utf-8"))
    data = raw[8 + n:]
    meta = header.pop("__metadata__", {})
    out, spans = {}, []
    for name, e in header.items():
        code, size = FMT[e["dtype"]]
        b, en = e["data_offsets"]
        cnt = 1
        for d in e["shape"]:
            cnt *= d
        if en - b != cnt * size or en > len(data):
            raise ValueError(f"{path}: {name}: bad offsets")
        if code == "e":  # array has no binary16 type code; struct reads little-endian halves exactly
            values = list(struct.unpack(f"<{cnt}e", data[b:en]))
        else:
            a = array.array(code)
            a.frombytes(data[b:en])
            if sys.byteorder != "little":
                a.byteswap()
            values = list(a)
        out[name] = (e["dtype"], list(e["shape"]), values)
        spans.append((b, en))
    pos = 0
    for b, en in sorted(spans):
        if b != pos:
            raise ValueError(f"{path}: hole or overlap at {b}")
        pos = en
    if pos != len(data):
        raise ValueError(f"{path}: trailing bytes")
    return meta, out


def check_roundtrip(path):
    """Verifies the file tests/nn/safetensors_test.cpp writes with handemo's writer."""
    meta, t = st_read(path)
    exp = {
        "a": ("F32", [2, 3], [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]),
        "b": ("F64", [4], [1e-300, -2.0, math.pi, 1e300]),
        "c": ("I64", [3], [-1, 0, 2 ** 40]),
        "d": ("U8", [2], [0, 255]),
        "e": ("F32", [0, 4], []),
    }
    ok = meta == {"format": "pt", "note": "handemo \u00e9"}
    ok = ok and set(t) == set(exp)
    for k, v in exp.items():
        ok = ok and k in t and t[k] == v
    if not ok:
        print("roundtrip mismatch:", meta, t)
        return 1
    print("ok")
    return 0


# ---------------------------------------------------------------- fixtures
def main(out_dir):
    import torch
    import torch.nn as nn
    import torch.nn.functional as F
    torch.set_num_threads(1)
    os.makedirs(out_dir, exist_ok=True)

    def flat(t):
        return t.detach().contiguous().view(-1).tolist()

    def T(name, t, dt="F32"):
        return (name, dt, list(t.shape), flat(t))

    # ---------------- 1. ops
    torch.manual_seed(0)
    ops = []

    def record(prefix, inputs, fn, extra=()):
        """inputs: dict name -> tensor (leaf, requires grad); fn(**inputs) -> output."""
        leaves = {k: v.clone().requires_grad_(True) for k, v in inputs.items()}
        y = fn(**leaves)
        gy = torch.randn_like(y)
        y.backward(gy)
        for k, v in leaves.items():
            ops.append(T(f"{prefix}.{k}", v))
        ops.append(T(f"{prefix}.y", y))
        ops.append(T(f"{prefix}.gy", gy))
        for k, v in leaves.items():
            ops.append(T(f"{prefix}.g{k}", v.grad))
        ops.extend(extra)

    r = torch.randn
    record("conv2d_s2", {"x": r(2, 3, 8, 8), "w": r(4, 3, 4, 4) * 0.2, "b": r(4)},
           lambda x, w, b: F.conv2d(x, w, b, stride=2, padding=1))
    record("conv2d_k7", {"x": r(2, 3, 6, 7), "w": r(4, 3, 7, 7) * 0.1, "b": r(4)},
           lambda x, w, b: F.conv2d(x, w, b, stride=1, padding=3))
    record("conv_transpose2d", {"x": r(2, 4, 3, 5), "w": r(4, 3, 4, 4) * 0.2},
           lambda x, w: F.conv_transpose2d(x, w, None, stride=2, padding=1))
    record("instance_norm", {"x": r(2, 3, 4, 5) * 2 + 1, "weight": r(3) * 0.5 + 1, "bias": r(3)},
           lambda x, weight, bias: F.instance_norm(x, weight=weight, bias=bias, eps=1e-5))
    # keep inputs away from the kinks so that finite precision cannot flip a branch
    xk = r(2, 3, 4, 5)
    xk = torch.where(xk.abs() < 0.05, xk.sign() * 0.05 + xk, xk)
    record("relu", {"x": xk}, lambda x: F.relu(x))
    record("leaky_relu", {"x": xk}, lambda x: F.leaky_relu(x, 0.01))
    record("tanh", {"x": r(2, 3, 4, 5) * 1.5}, lambda x: torch.tanh(x))
    lab = torch.tensor([2, 0, 4, 1])
    record("cross_entropy", {"logits": r(4, 5) * 2}, lambda logits: F.cross_entropy(logits, lab),
           extra=[("cross_entropy.labels", "I64", [4], lab.tolist())])
    tgt = (torch.rand(4, 5) > 0.5).float()
    record("bce_with_logits", {"logits": r(4, 5) * 2},
           lambda logits: F.binary_cross_entropy_with_logits(logits, tgt),
           extra=[T("bce_with_logits.targets", tgt)])
    record("l1_mean", {"a": r(2, 3, 4, 5), "b": r(2, 3, 4, 5)}, lambda a, b: (a - b).abs().mean())
    record("l2_norm", {"x": r(4, 3, 4, 5)}, lambda x: x.view(x.size(0), -1).norm(2, dim=1))
    st_write(os.path.join(out_dir, "ops.safetensors"), ops,
             {"generator": "scripts/make_golden.py", "torch": torch.__version__,
              "layout": "NCHW row-major; conv weight OIHW; conv_transpose weight [in, out, kh, kw]",
              "instance_norm.eps": "1e-5", "leaky_relu.slope": "0.01",
              "reductions": "cross_entropy, bce_with_logits, l1_mean: mean; l2_norm: per sample over C*H*W"})

    # ---------------- 2./3. tiny StarGAN (official StarGAN names: main.*, conv1 = src head, conv2 = cls head)
    cfg = dict(H=12, W=24, C=5, g_conv_dim=4, g_repeat=1, d_conv_dim=4, d_repeat=3, B=2,
               lambda_cls=1.0, lambda_rec=10.0, lambda_gp=10.0)
    H, W, C, B = cfg["H"], cfg["W"], cfg["C"], cfg["B"]

    class ResidualBlock(nn.Module):
        def __init__(s, d):
            super().__init__()
            s.main = nn.Sequential(nn.Conv2d(d, d, 3, 1, 1, bias=False), nn.InstanceNorm2d(d, affine=True),
                                   nn.ReLU(True), nn.Conv2d(d, d, 3, 1, 1, bias=False),
                                   nn.InstanceNorm2d(d, affine=True))

        def forward(s, x):
            return x + s.main(x)

    class Generator(nn.Module):
        def __init__(s, cd, rep):
            super().__init__()
            L = [nn.Conv2d(3 + C, cd, 7, 1, 3, bias=False), nn.InstanceNorm2d(cd, affine=True), nn.ReLU(True)]
            d = cd
            for _ in range(2):
                L += [nn.Conv2d(d, d * 2, 4, 2, 1, bias=False), nn.InstanceNorm2d(d * 2, affine=True),
                      nn.ReLU(True)]
                d *= 2
            L += [ResidualBlock(d) for _ in range(rep)]
            for _ in range(2):
                L += [nn.ConvTranspose2d(d, d // 2, 4, 2, 1, bias=False), nn.InstanceNorm2d(d // 2, affine=True),
                      nn.ReLU(True)]
                d //= 2
            L += [nn.Conv2d(d, 3, 7, 1, 3, bias=False), nn.Tanh()]
            s.main = nn.Sequential(*L)

        def forward(s, x, c):
            c = c.view(c.size(0), c.size(1), 1, 1).repeat(1, 1, x.size(2), x.size(3))
            return s.main(torch.cat([x, c], 1))

    class Discriminator(nn.Module):
        def __init__(s, cd, rep):
            super().__init__()
            L = [nn.Conv2d(3, cd, 4, 2, 1), nn.LeakyReLU(0.01)]
            d = cd
            for _ in range(rep - 1):
                L += [nn.Conv2d(d, d * 2, 4, 2, 1), nn.LeakyReLU(0.01)]
                d *= 2
            s.main = nn.Sequential(*L)
            s.conv1 = nn.Conv2d(d, 1, 3, 1, 1, bias=False)
            s.conv2 = nn.Conv2d(d, C, (H // 2 ** rep, W // 2 ** rep), bias=False)

        def forward(s, x):
            h = s.main(x)
            return s.conv1(h), s.conv2(h).view(x.size(0), -1)

    # float64: the reference is then exact to ~1e-15, so handemo's double model is checked tightly and
    # its float model against the truth rather than against another float computation
    torch.manual_seed(1)
    g = Generator(cfg["g_conv_dim"], cfg["g_repeat"]).double()
    d = Discriminator(cfg["d_conv_dim"], cfg["d_repeat"]).double()
    # make the InstanceNorm affine parameters non-trivial so that their gradients are tested
    with torch.no_grad():
        for name, p in g.named_parameters():
            if p.dim() == 1:
                p.add_(torch.randn_like(p) * 0.1)
    x = (torch.rand(B, 3, H, W) * 2 - 1).double()
    label_org = torch.tensor([1, 3])
    label_trg = torch.tensor([4, 0])
    c_org = torch.eye(C, dtype=torch.float64)[label_org]
    c_trg = torch.eye(C, dtype=torch.float64)[label_trg]
    alpha = torch.tensor([0.3, 0.8], dtype=torch.float64).view(B, 1, 1, 1)

    # D loss (reference_stargan.py step(), D half)
    out_src, out_cls = d(x)
    fake = g(x, c_trg)
    f_src, _ = d(fake.detach())
    xh = (alpha * x + (1 - alpha) * fake.detach()).requires_grad_(True)
    o, _ = d(xh)
    gr = torch.autograd.grad(o, xh, torch.ones_like(o), create_graph=True)[0]
    gp = ((gr.view(B, -1).norm(2, dim=1) - 1) ** 2).mean()
    d_real = -out_src.mean()
    d_fake = f_src.mean()
    d_cls = F.cross_entropy(out_cls, label_org)
    ld = d_real + d_fake + cfg["lambda_cls"] * d_cls + cfg["lambda_gp"] * gp
    # the cls head (and, piecewise, every bias) does not reach dsrc/dx_hat: unused -> zero gradient
    grad_gp = torch.autograd.grad(gp, list(d.parameters()), retain_graph=True, allow_unused=True)
    grad_gp = [torch.zeros_like(p) if gg is None else gg for p, gg in zip(d.parameters(), grad_gp)]
    grad_d = torch.autograd.grad(ld, list(d.parameters()))

    # G loss (G half)
    fake2 = g(x, c_trg)
    s_fake, cls_fake = d(fake2)
    rec = g(fake2, c_org)
    g_fake = -s_fake.mean()
    g_rec = (x - rec).abs().mean()
    g_cls = F.cross_entropy(cls_fake, label_trg)
    lg = g_fake + cfg["lambda_rec"] * g_rec + cfg["lambda_cls"] * g_cls
    grad_g = torch.autograd.grad(lg, list(g.parameters()))

    sg = []
    for n_, p in g.named_parameters():
        sg.append(T("G." + n_, p, "F64"))
    for n_, p in d.named_parameters():
        sg.append(T("D." + n_, p, "F64"))
    sg += [T("input.x", x, "F64"), ("input.label_org", "I64", [B], label_org.tolist()),
           ("input.label_trg", "I64", [B], label_trg.tolist()), T("input.c_org", c_org, "F64"), T("input.c_trg", c_trg, "F64"),
           T("input.alpha", alpha, "F64"),
           T("out.d_src_real", out_src, "F64"), T("out.d_cls_real", out_cls, "F64"), T("out.g_fake", fake, "F64"),
           T("out.d_src_fake", f_src, "F64"), T("out.gp_grad_x", gr, "F64"), T("out.g_rec", rec, "F64"), T("out.d_cls_fake", cls_fake, "F64")]
    for k, v in [("d_real", d_real), ("d_fake", d_fake), ("d_cls", d_cls), ("d_gp", gp), ("d_total", ld),
                 ("g_fake", g_fake), ("g_rec", g_rec), ("g_cls", g_cls), ("g_total", lg)]:
        sg.append(("loss." + k, "F64", [], [float(v)]))
    for (n_, _), gg in zip(d.named_parameters(), grad_d):
        sg.append(T("grad_d." + n_, gg, "F64"))
    for (n_, _), gg in zip(d.named_parameters(), grad_gp):
        sg.append(T("grad_gp." + n_, gg, "F64"))
    for (n_, _), gg in zip(g.named_parameters(), grad_g):
        sg.append(T("grad_g." + n_, gg, "F64"))
    meta = {k: str(v) for k, v in cfg.items()}
    meta.update({"generator": "scripts/make_golden.py", "torch": torch.__version__,
                 "L_D": "-mean(src(x)) + mean(src(G(x,c_trg))) + lambda_cls CE(cls(x), label_org) + lambda_gp GP",
                 "GP": "mean((||d src(x_hat)/d x_hat||_2 - 1)^2), x_hat = alpha x + (1-alpha) G(x,c_trg)",
                 "L_G": "-mean(src(G(x,c_trg))) + lambda_rec mean|x - G(G(x,c_trg),c_org)| + lambda_cls CE(cls(G(x,c_trg)), label_trg)"})
    st_write(os.path.join(out_dir, "stargan_tiny.safetensors"), sg, meta)

    # ---------------- 4. Adam
    ad = []
    for dt, tdt in [("F32", torch.float32), ("F64", torch.float64)]:
        torch.manual_seed(2)
        p = torch.nn.Parameter(torch.randn(37, dtype=tdt))
        ad.append((f"{dt}.p0", dt, [37], flat(p)))
        opt = torch.optim.Adam([p], lr=1e-3, betas=(0.5, 0.999), eps=1e-8)
        lrs = [1e-3, 1e-3, 5e-4, 2.5e-4, 1e-4]
        for k, lr in enumerate(lrs, 1):
            for gr_ in opt.param_groups:
                gr_["lr"] = lr
            gk = torch.randn(37, dtype=tdt) * (10.0 ** (k - 3))  # gradients of very different scales
            if k == 4:
                gk[:5] = 0.0
            p.grad = gk
            opt.step()
            ad.append((f"{dt}.g{k}", dt, [37], flat(gk)))
            ad.append((f"{dt}.p{k}", dt, [37], flat(p)))
        st = opt.state[p]
        ad.append((f"{dt}.m", dt, [37], flat(st["exp_avg"])))
        ad.append((f"{dt}.v", dt, [37], flat(st["exp_avg_sq"])))
        ad.append((f"{dt}.lr", "F64", [len(lrs)], lrs))
    st_write(os.path.join(out_dir, "adam.safetensors"), ad,
             {"generator": "scripts/make_golden.py", "torch": torch.__version__,
              "betas": "0.5,0.999", "eps": "1e-8", "steps": "5", "optimizer": "torch.optim.Adam"})

    # ---------------- 5. binary16 rounding (Tensor.half(): round to nearest, ties to even), for
    # handemo::float_to_half / half_to_float (core/half.hpp) and weight_storage::f16 of the packed kernels
    torch.manual_seed(3)
    vals = [0.0, -0.0, 1.0, -1.0, 65504.0, -65504.0, 65519.0, 65520.0, 1e6, -1e6, float("inf"), float("-inf"),
            float("nan"), 2.0 ** -14, 2.0 ** -24, 2.0 ** -25, 2.0 ** -26, 3 * 2.0 ** -26, 1.5 * 2.0 ** -24,
            2.0 ** -14 - 2.0 ** -25, 1.0 + 2.0 ** -11, 1.0 + 3 * 2.0 ** -11, 1.0 + 2.0 ** -11 + 2.0 ** -20]
    # every tie between two neighbouring halves is a value of the form (h + 1/2 ulp): sample them over the range
    hb = torch.randint(0, 0x7BFF, (2000,), dtype=torch.int32)
    lo = hb.to(torch.int16).view(torch.float16).double()
    hi = (hb + 1).to(torch.int16).view(torch.float16).double()
    ties = ((lo + hi) / 2).float()  # exact in float32: 12 significant bits
    scaled = torch.cat([torch.randn(4000) * (10.0 ** e) for e in range(-9, 6)])
    x = torch.cat([torch.tensor(vals, dtype=torch.float32), ties, -ties, scaled])
    bits = [v & 0xFFFF for v in x.half().view(torch.int16).tolist()]
    st_write(os.path.join(out_dir, "f16.safetensors"),
             [("x", "F32", [x.numel()], flat(x)), ("half_bits", "U16", [x.numel()], bits),
              ("half_as_float", "F32", [x.numel()], flat(x.half().float()))],
             {"generator": "scripts/make_golden.py", "torch": torch.__version__,
              "half_bits": "x.half().view(torch.int16) as unsigned 16-bit", "half_as_float": "x.half().float()"})
    print("wrote", out_dir)


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "--check-roundtrip":
        sys.exit(check_roundtrip(sys.argv[2]))
    here = os.path.dirname(os.path.abspath(__file__))
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "fixtures"))
