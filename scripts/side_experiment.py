#!/usr/bin/python3
"""The PyTorch side experiment of docs/results.md: StarGAN as the reference trains it, then with a residual
generator and an identity loss, then with per-channel normalisation, on the synthetic hand images with one
motion type held out. It answers "is it the method or handemo's code?" outside handemo: the same data, the
reference layout (scripts/reference_stargan.py: G = conv7, 2 down, residual blocks, 2 up, conv7,
tanh, instance norm; D = PatchGAN with a source and a classification head), PyTorch's own autograd and Adam.

Input: a folder written by `handemo encode DATA --out ENC` (Eq. 3 BMPs, one per clip, and range.json with the
paper's one global range); the angles are read back by Eq. 6, so every number here carries Eq. 3's
quantisation (at most (p_max - p_min) / 510 deg, 0.33 deg on the synthetic set).

Variants (each trained from the same seed):
  reference   G(x, c) = tanh(...), Eq. 3's global range, the StarGAN losses (adversarial WGAN-GP, domain
              classification, cycle reconstruction), n_critic 5
  residual    + G(x, c) = x + tanh(last conv), the last conv zero-initialised, + identity loss 10
  channel     + per-channel normalisation: (angle - channel mean) / (3 x channel std) over the training set

Printed per variant: mean keyframe RMSE (deg) of the held-out content's neutral takes transferred to every
other emotion against the real take of that emotion (same take index), the number of (take, emotion) pairs
where it beats the mean-offset baseline, and the same RMSE on the training contents (seen contents); identity
and mean-offset on the first lines. Needs Debian's python3-torch (./setup.sh --golden installs it).

Usage: /usr/bin/python3 scripts/side_experiment.py ENC [--held-out pushing] [--steps 2000] [--threads 1]
       [--variants reference,residual,channel] [--lambda-cls 5] [--seed 1]
"""
import argparse
import json
import math
import os
import struct
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

EMOTIONS = ["angry", "happy", "neutral", "sad", "fearful"]  # handemo's hand_domains() order
K, J, H, W = 9, 23, 12, 24


def read_bmp(path):
    """24-bit uncompressed BMP -> uint8 array [rows, cols, 3] in RGB, top row first."""
    b = open(path, "rb").read()
    if b[:2] != b"BM":
        raise ValueError(f"{path}: not a BMP")
    off, = struct.unpack_from("<I", b, 10)
    w, h, _, bpp, comp = struct.unpack_from("<iiHHI", b, 18)
    if bpp != 24 or comp != 0:
        raise ValueError(f"{path}: expected a 24-bit uncompressed BMP, got {bpp} bpp, compression {comp}")
    stride = (w * 3 + 3) & ~3
    rows = abs(h)
    img = np.zeros((rows, w, 3), np.uint8)
    for r in range(rows):
        line = np.frombuffer(b, np.uint8, w * 3, off + r * stride).reshape(w, 3)[:, ::-1]  # BGR -> RGB
        img[r if h < 0 else rows - 1 - r] = line
    return img


def load(enc):
    rng = json.load(open(os.path.join(enc, "range.json")))
    pmin, pmax = rng["p_min"], rng["p_max"]
    clips = []
    for f in sorted(os.listdir(enc)):
        if not f.endswith(".bmp"):
            continue
        _, content, emotion, take = f[:-4].split("_")
        v = read_bmp(os.path.join(enc, f)).astype(np.float64)
        if v.shape != (K, J, 3):
            raise ValueError(f"{f}: image is {v.shape}, expected {K}x{J}x3")
        clips.append(dict(content=content, emotion=emotion, take=take, angles=v / 255.0 * (pmax - pmin) + pmin))
    if not clips:
        raise ValueError(f"{enc}: no .bmp files (run handemo encode first)")
    return clips, pmin, pmax


class Res(nn.Module):
    def __init__(s, d):
        super().__init__()
        s.main = nn.Sequential(nn.Conv2d(d, d, 3, 1, 1, bias=False), nn.InstanceNorm2d(d, affine=True), nn.ReLU(True),
                               nn.Conv2d(d, d, 3, 1, 1, bias=False), nn.InstanceNorm2d(d, affine=True))

    def forward(s, x):
        return x + s.main(x)


class Generator(nn.Module):
    def __init__(s, cd=32, rep=3, residual=False):
        super().__init__()
        L = [nn.Conv2d(3 + len(EMOTIONS), cd, 7, 1, 3, bias=False), nn.InstanceNorm2d(cd, affine=True), nn.ReLU(True)]
        d = cd
        for _ in range(2):
            L += [nn.Conv2d(d, 2 * d, 4, 2, 1, bias=False), nn.InstanceNorm2d(2 * d, affine=True), nn.ReLU(True)]
            d *= 2
        L += [Res(d) for _ in range(rep)]
        for _ in range(2):
            L += [nn.ConvTranspose2d(d, d // 2, 4, 2, 1, bias=False), nn.InstanceNorm2d(d // 2, affine=True), nn.ReLU(True)]
            d //= 2
        L += [nn.Conv2d(d, 3, 7, 1, 3, bias=False)]
        s.main = nn.Sequential(*L)
        s.residual = residual
        if residual:
            nn.init.zeros_(L[-1].weight)  # G is exactly the identity before training

    def forward(s, x, c):
        c = c.view(c.size(0), c.size(1), 1, 1).repeat(1, 1, x.size(2), x.size(3))
        y = torch.tanh(s.main(torch.cat([x, c], 1)))
        return x + y if s.residual else y


class Discriminator(nn.Module):
    def __init__(s, cd=32, rep=3):
        super().__init__()
        L = [nn.Conv2d(3, cd, 4, 2, 1), nn.LeakyReLU(0.01)]
        d = cd
        for _ in range(rep - 1):
            L += [nn.Conv2d(d, 2 * d, 4, 2, 1), nn.LeakyReLU(0.01)]
            d *= 2
        s.main = nn.Sequential(*L)
        s.conv1 = nn.Conv2d(d, 1, 3, 1, 1, bias=False)
        s.conv2 = nn.Conv2d(d, len(EMOTIONS), (H // 2 ** rep, W // 2 ** rep), bias=False)

    def forward(s, x):
        h = s.main(x)
        return s.conv1(h), s.conv2(h).view(x.size(0), -1)


def run_variant(name, clips, held, pmin, pmax, args):
    residual = name in ("residual", "channel")
    train = [c for c in clips if c["content"] != held]
    if name == "channel":
        a = np.stack([c["angles"] for c in train])  # [M, K, J, 3]
        mu, sd = a.mean(axis=(0, 1)), np.maximum(a.std(axis=(0, 1)), 1e-3)
        to_net = lambda p: (p - mu) / (3 * sd)
        from_net = lambda x: x * (3 * sd) + mu
    else:
        to_net = lambda p: (p - pmin) / (pmax - pmin) * 2 - 1
        from_net = lambda x: (x + 1) / 2 * (pmax - pmin) + pmin

    def image(p):  # [K, J, 3] degrees -> [3, H, W] network units, zero padded
        x = np.zeros((3, H, W), np.float32)
        x[:, :K, :J] = np.transpose(to_net(p), (2, 0, 1))
        return x

    def angles(x):  # [3, H, W] -> [K, J, 3] degrees
        return from_net(np.transpose(x[:, :K, :J], (1, 2, 0)).astype(np.float64))

    torch.manual_seed(args.seed)
    rs = np.random.RandomState(args.seed)
    X = torch.tensor(np.stack([image(c["angles"]) for c in train]))
    Y = torch.tensor([EMOTIONS.index(c["emotion"]) for c in train])
    G, D = Generator(residual=residual), Discriminator()
    og = torch.optim.Adam(G.parameters(), 1e-4, betas=(0.5, 0.999))
    od = torch.optim.Adam(D.parameters(), 1e-4, betas=(0.5, 0.999))
    onehot = lambda y: F.one_hot(y, len(EMOTIONS)).float()
    t0 = time.time()
    for step in range(1, args.steps + 1):
        lr = 1e-4 * min(1.0, (args.steps - step) / (args.steps / 2)) if step > args.steps / 2 else 1e-4
        for o in (og, od):
            for g in o.param_groups:
                g["lr"] = lr
        idx = torch.tensor(rs.randint(0, len(X), 16))
        x, yo = X[idx], Y[idx]
        yt = yo[torch.tensor(rs.permutation(16))]
        co, ct = onehot(yo), onehot(yt)
        # D: WGAN-GP + domain classification
        src, cls = D(x)
        fake = G(x, ct).detach()
        fsrc, _ = D(fake)
        alpha = torch.rand(16, 1, 1, 1)
        xh = (alpha * x + (1 - alpha) * fake).requires_grad_(True)
        hs, _ = D(xh)
        gr = torch.autograd.grad(hs, xh, torch.ones_like(hs), create_graph=True)[0].view(16, -1)
        d_loss = -src.mean() + fsrc.mean() + args.lambda_cls * F.cross_entropy(cls, yo) + 10 * ((gr.norm(2, dim=1) - 1) ** 2).mean()
        od.zero_grad()
        d_loss.backward()
        od.step()
        if step % 5 == 0:  # G every n_critic = 5 D steps
            fake = G(x, ct)
            fsrc, fcls = D(fake)
            g_loss = -fsrc.mean() + args.lambda_cls * F.cross_entropy(fcls, yt) + 10 * (x - G(fake, co)).abs().mean()
            if residual:
                g_loss = g_loss + 10 * (G(x, co) - x).abs().mean()  # identity loss
            og.zero_grad()
            g_loss.backward()
            og.step()
        if step % max(1, args.steps // 10) == 0:
            el = time.time() - t0
            print(f"  {name}: step {step}/{args.steps}, {el:.0f} s, ETA {el / step * (args.steps - step):.0f} s", file=sys.stderr)

    G.eval()
    key = {(c["content"], c["emotion"], c["take"]): c["angles"] for c in clips}
    neutral_diff = {}
    for e in EMOTIONS:  # mean-offset: mean (emotion - neutral) keyframe difference over training contents and takes
        d = [key[(c["content"], e, c["take"])] - c["angles"] for c in train if c["emotion"] == "neutral" and (c["content"], e, c["take"]) in key]
        neutral_diff[e] = np.mean(d, axis=0)

    def score(contents):
        r = dict(model=[], identity=[], offset=[])
        wins = 0
        with torch.no_grad():
            for c in clips:
                if c["content"] not in contents or c["emotion"] != "neutral":
                    continue
                for e in EMOTIONS:
                    if e == "neutral" or (c["content"], e, c["take"]) not in key:
                        continue
                    real = key[(c["content"], e, c["take"])]
                    out = angles(G(torch.tensor(image(c["angles"]))[None], onehot(torch.tensor([EMOTIONS.index(e)])))[0].numpy())
                    rm = math.sqrt(((out - real) ** 2).mean())
                    ro = math.sqrt(((c["angles"] + neutral_diff[e] - real) ** 2).mean())
                    r["model"].append(rm)
                    r["identity"].append(math.sqrt(((c["angles"] - real) ** 2).mean()))
                    r["offset"].append(ro)
                    wins += rm < ro
        return {k: float(np.mean(v)) for k, v in r.items()}, wins, len(r["model"])

    held_s, wins, n = score({held})
    seen_s, _, _ = score({c["content"] for c in train})
    return held_s, wins, n, seen_s, time.time() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("enc")
    ap.add_argument("--held-out", default="pushing")
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--variants", default="reference,residual,channel")
    ap.add_argument("--lambda-cls", type=float, default=5.0)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    clips, pmin, pmax = load(args.enc)
    if not any(c["content"] == args.held_out for c in clips):
        sys.exit(f"side_experiment: no clip of content '{args.held_out}' in {args.enc}")
    rows = []
    for v in args.variants.split(","):
        if v not in ("reference", "residual", "channel"):
            sys.exit(f"side_experiment: unknown variant '{v}' (reference, residual, channel)")
        print(f"side_experiment: training {v} ({args.steps} steps, {args.held_out} held out)", file=sys.stderr)
        rows.append((v,) + run_variant(v, clips, args.held_out, pmin, pmax, args))
    h0 = rows[0][1]
    print(f"held out: {args.held_out}; identity {h0['identity']:.2f} deg, mean-offset {h0['offset']:.2f} deg "
          f"(seen contents: identity {rows[0][4]['identity']:.2f})")
    print("| PyTorch variant | held-out RMSE | wins vs mean-offset | seen contents | train time |")
    print("|---|---|---|---|---|")
    for v, hs, wins, n, ss, secs in rows:
        print(f"| {v} | {hs['model']:.2f} | {wins}/{n} | {ss['model']:.2f} | {secs:.0f} s |")


if __name__ == "__main__":
    main()
