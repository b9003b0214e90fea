#!/usr/bin/env python3
"""Writes the checkpoint fuzz seed (a hand-tiny checkpoint holding G only, weights in F16 to stay small)
and the regression file of the label overflow (the same with a sixth domain name). The fuzz harness
recomputes the checksum, so the one written here only has to exist. Run from tests/fuzz/."""
import json, random, struct

cd, C, R = 8, 5, 1  # hand-tiny: conv_dim, domains, residual blocks


def g_params():
    p = []
    conv = lambda n, o, i, k: p.append((n + ".weight", [o, i, k, k]))
    norm = lambda n, c: p.extend([(n + ".weight", [c]), (n + ".bias", [c])])
    conv("main.0", cd, 3 + C, 7); norm("main.1", cd)
    conv("main.3", 2 * cd, cd, 4); norm("main.4", 2 * cd)
    conv("main.6", 4 * cd, 2 * cd, 4); norm("main.7", 4 * cd)
    for r in range(R):
        b = "main.%d.main." % (9 + r)
        conv(b + "0", 4 * cd, 4 * cd, 3); norm(b + "1", 4 * cd); conv(b + "3", 4 * cd, 4 * cd, 3); norm(b + "4", 4 * cd)
    p.append(("main.%d.weight" % (9 + R), [4 * cd, 2 * cd, 4, 4])); norm("main.%d" % (10 + R), 2 * cd)
    p.append(("main.%d.weight" % (12 + R), [2 * cd, cd, 4, 4])); norm("main.%d" % (13 + R), cd)
    conv("main.%d" % (15 + R), 3, cd, 7)
    return p


def checkpoint(domains):
    rnd = random.Random(1)
    joints = ["forearm", "wrist", "palm"] + [f + "_" + s for f in ["thumb", "index", "middle", "ring", "pinky"]
                                             for s in ["metacarpal", "proximal", "intermediate", "distal"]]
    meta = {"config": "hand-tiny", "domains": domains, "neutral": "neutral", "p_min": -90.0, "p_max": 90.0,
            "keyframes": 9, "joints": 23, "tempo": [1.0] * len(domains), "amplitude": [1.0] * len(domains),
            "joint_names": joints, "step": 1, "options": {"residual": True, "amplitude": False}}
    header = {"__metadata__": {"format": "handemo-checkpoint/1", "handemo": json.dumps(meta), "checksum": "0"}}
    data = b""
    for name, shape in g_params():
        n = 1
        for d in shape:
            n *= d
        b = b"".join(struct.pack("<e", rnd.uniform(-0.05, 0.05)) for _ in range(n))
        header["G." + name] = {"dtype": "F16", "shape": shape, "data_offsets": [len(data), len(data) + len(b)]}
        data += b
    h = json.dumps(header).encode()
    h += b" " * ((8 - len(h) % 8) % 8)
    return struct.pack("<Q", len(h)) + h + data


hand = ["angry", "happy", "neutral", "sad", "fearful"]
open("corpus/checkpoint/hand_tiny_g.safetensors", "wb").write(checkpoint(hand))
# a sixth domain name must be refused: it would make label[target] = 1.f write past the 5-float label buffer
open("regressions/checkpoint/extra_domain.safetensors", "wb").write(checkpoint(hand + ["bored"]))
