#!/usr/bin/env python3
"""The textured glTF frame (bench/scenes/gltf-frame.toml) in Mesa
llvmpipe (peer.py) and in specula, alternated in one run on this
machine: two rounds, each the peer's median of 10 frames (after 2
warm-ups) then specula's median frame of `--repeat 10`, both at the same
thread count, each after waiting (up to 5 minutes) for other processes
to leave the CPUs nearly idle. Prints both medians (the median of the rounds) and
llvmpipe/specula, then how close the two images of the last round are.

usage (from the project root):
  python3 bench/peers/gltf_frame/ratio.py [SPECULA_BINARY] [THREADS]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
SCENE = os.path.join(ROOT, "bench", "scenes", "gltf-frame.toml")
ROUNDS = 2
QUIET_SHARE = 0.10   # the host counts as quiet when others use at most this share of its CPUs
QUIET_WAIT_S = 300   # the longest wait for a quiet host before each measurement

sys.path.insert(0, HERE)
import compare  # noqa: E402


def busy_share(seconds=1.0):
    """The share of the host's CPU time spent busy over `seconds` while
    this script sleeps: what other processes use."""
    def sample():
        with open("/proc/stat") as fh:
            f = [int(x) for x in fh.readline().split()[1:9]]
        return sum(f) - f[3] - f[4], sum(f)  # busy (all but idle, iowait), total
    b0, t0 = sample()
    time.sleep(seconds)
    b1, t1 = sample()
    return (b1 - b0) / max(t1 - t0, 1)


def wait_for_quiet():
    """Waits (up to QUIET_WAIT_S) until other processes leave the CPUs
    nearly idle, since both renderers use every core; returns the busy
    share last seen."""
    start = time.monotonic()
    share = busy_share()
    while share > QUIET_SHARE and time.monotonic() - start < QUIET_WAIT_S:
        share = busy_share()
    return share


def peer_median(threads, out, png=None):
    cmd = [sys.executable, os.path.join(HERE, "peer.py"), "--threads", threads, "--frames", "10",
           "--warmup", "2", "--out", out]
    if png:
        cmd += ["--save", png]
    subprocess.run(cmd, check=True, capture_output=True)
    with open(out) as fh:
        return json.load(fh)["median_ms"]


def specula_median(binary, threads, out, png):
    subprocess.run([binary, "render", SCENE, "-o", png, "--threads", threads, "--repeat", "10",
                    "--stats-json", out], check=True, capture_output=True)
    with open(out) as fh:
        return statistics.median(json.load(fh)["frame_ms"])


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "specula")
    threads = sys.argv[2] if len(sys.argv) > 2 else "2"
    if not os.access(binary, os.X_OK):
        sys.exit(f"no specula binary at {binary} (cargo build --release first)")
    tmp = tempfile.mkdtemp(prefix="gltf-peer-")
    peer_png, spec_png = os.path.join(tmp, "peer.png"), os.path.join(tmp, "specula.png")
    llvm, spec, busy = [], [], []
    load = os.getloadavg()
    for rnd in range(ROUNDS):
        last = rnd == ROUNDS - 1
        busy.append(wait_for_quiet())
        llvm.append(peer_median(threads, os.path.join(tmp, f"peer{rnd}.json"), peer_png if last else None))
        busy.append(wait_for_quiet())
        spec.append(specula_median(binary, threads, os.path.join(tmp, f"spec{rnd}.json"), spec_png))
    l, s = statistics.median(llvm), statistics.median(spec)
    print(f"rounds (ms): llvmpipe {', '.join(f'{x:.1f}' for x in llvm)}; "
          f"specula {', '.join(f'{x:.1f}' for x in spec)}")
    print(f"llvmpipe {l:.1f} ms, specula {s:.1f} ms ({threads} threads): llvmpipe/specula = {l / s:.2f}")
    print(f"load average before: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; after: "
          + " ".join(f"{x:.2f}" for x in os.getloadavg())
          + "; other processes' CPU share before each measurement: "
          + ", ".join(f"{100 * b:.0f} %" for b in busy))
    result, _ = compare.compare(peer_png, spec_png)
    print(compare.describe(result))
    print(f"images: {peer_png} {spec_png}")


if __name__ == "__main__":
    main()
