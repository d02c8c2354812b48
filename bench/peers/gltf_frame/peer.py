#!/usr/bin/env python3
"""Mesa llvmpipe peer of bench/scenes/gltf-frame.toml: the same frame in
OpenGL 3.3 on the CPU (Mesa's LLVM-JIT rasterizer, through a headless
EGL context), as a forward GPU engine draws it. See README.md.

usage: peer.py [--threads N] [--frames 10] [--warmup 2] [--scene FILE]
               [--out FILE.json] [--save FILE.png]

LP_NUM_THREADS = N: N rasterizer threads, beside the calling thread that
runs vertex processing and triangle setup. A timed frame is the wall time
of the sun's depth pass, the point light's six, the main pass (meshes,
then the map behind them) and glFinish. Prints (and with --out writes)
JSON with every frame time and their median.
"""
import argparse
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--scene", default=os.path.join(ROOT, "bench", "scenes", "gltf-frame.toml"))
ap.add_argument("--out", help="write the results as JSON here")
ap.add_argument("--save", help="write the last frame as a PNG here")
args = ap.parse_args()

# The driver reads these when it loads, so before moderngl is imported.
os.environ["LP_NUM_THREADS"] = str(args.threads)
os.environ["LIBGL_ALWAYS_SOFTWARE"] = "1"
os.environ["GALLIUM_DRIVER"] = "llvmpipe"

import moderngl  # noqa: E402

sys.path.insert(0, HERE)
import render  # noqa: E402
import scene  # noqa: E402

t0 = time.perf_counter()
sc = scene.load(args.scene)
ctx = moderngl.create_standalone_context(backend="egl", require=330)
info = {k: ctx.info[k] for k in ("GL_RENDERER", "GL_VERSION")}
if "llvmpipe" not in info["GL_RENDERER"]:
    sys.exit(f"not llvmpipe: {info}")
renderer = render.Renderer(ctx, sc)
load_s = time.perf_counter() - t0

for _ in range(args.warmup):
    renderer.frame()
frame_ms = []
for _ in range(args.frames):
    t = time.perf_counter()
    renderer.frame()
    frame_ms.append((time.perf_counter() - t) * 1e3)

results = dict(peer="mesa-llvmpipe", scene=os.path.relpath(args.scene, ROOT), lp_num_threads=args.threads,
               info=info, width=sc["width"], height=sc["height"],
               triangles=int(sum(len(m.indices) for m in sc["meshes"])), load_s=round(load_s, 2),
               warmup=args.warmup, frame_ms=[round(x, 3) for x in frame_ms],
               median_ms=round(statistics.median(frame_ms), 3))
if args.save:
    from PIL import Image
    Image.fromarray(renderer.image()).save(args.save)
    results["saved"] = args.save
    results["fragments_shaded"] = renderer.fragments_shaded()
text = json.dumps(results, indent=1)
if args.out:
    with open(args.out, "w") as fh:
        fh.write(text + "\n")
print(text)
