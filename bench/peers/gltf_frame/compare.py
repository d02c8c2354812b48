#!/usr/bin/env python3
"""How close the peer's frame is to specula's: per-channel mean absolute
difference (8-bit codes), the share of pixels whose largest channel
difference is within 0, 1, 2, 8 and 32 codes, and the largest difference.

usage: compare.py PEER.png SPECULA.png [--heatmap OUT.png]
"""
import argparse

import numpy as np
from PIL import Image

WITHIN = (0, 1, 2, 8, 32)


def compare(a_path, b_path):
    a = np.asarray(Image.open(a_path).convert("RGB")).astype(np.int32)
    b = np.asarray(Image.open(b_path).convert("RGB")).astype(np.int32)
    if a.shape != b.shape:
        raise SystemExit(f"sizes differ: {a.shape} against {b.shape}")
    d = np.abs(a - b)
    worst = d.max(axis=2)
    return dict(mean_abs=[round(float(x), 3) for x in d.mean(axis=(0, 1))],
                within={k: round(float((worst <= k).mean()), 5) for k in WITHIN},
                max=int(worst.max())), worst


def describe(r):
    within = ", ".join(f"≤{k}: {100 * v:.2f} %" for k, v in r["within"].items())
    return (f"mean |peer − specula| per channel (R, G, B; 8-bit codes): {r['mean_abs']}\n"
            f"pixels whose largest channel difference is {within}; largest {r['max']}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("peer")
    ap.add_argument("specula")
    ap.add_argument("--heatmap", help="write |difference| × 16 (grey) here")
    args = ap.parse_args()
    result, worst = compare(args.peer, args.specula)
    print(describe(result))
    if args.heatmap:
        Image.fromarray(np.clip(worst * 16, 0, 255).astype(np.uint8)).save(args.heatmap)
