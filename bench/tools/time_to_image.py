#!/usr/bin/env python3
"""Time to image against the steady frame, for one or more specula binaries.

    python3 bench/tools/time_to_image.py N BIN [BIN ...]

For each of N pairs and each binary (in an order rotated from pair to pair):
one cold run, the wall time of `BIN render SCENE -o g.png` from process
start to exit (the PNG is on disk), then one steady run, the median frame
of `--stats --repeat 10 --threads 2`. The ratio is taken per pair, so
that both of its sides land in the same phase of the host. Each binary
renders once first, to fill the mesh cache: the cold runs read the OBJ's
mesh from it.

Before each pair the script waits until the host has been idle (>= 90 %
of CPU time) for half a second; set QUIET=0 not to wait. SCENE is
fixtures/scenes/sphere-grid.toml unless the SCENE variable names another.
Outputs go to a temporary folder.
"""

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time


def idle_share(dt=0.5):
    def read():
        v = list(map(int, open("/proc/stat").readline().split()[1:]))
        return v[3] + v[4], sum(v)

    i0, t0 = read()
    time.sleep(dt)
    i1, t1 = read()
    return (i1 - i0) / max(1, t1 - t0)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    n = int(sys.argv[1])
    bins = sys.argv[2:]
    scene = os.environ.get("SCENE", "fixtures/scenes/sphere-grid.toml")
    quiet = os.environ.get("QUIET", "1") != "0"
    out = os.path.join(tempfile.mkdtemp(), "g.png")

    def cold(b):
        t0 = time.perf_counter()
        subprocess.run([b, "render", scene, "-o", out], check=True, capture_output=True)
        return (time.perf_counter() - t0) * 1e3

    def steady(b):
        args = ["--stats", "--repeat", "10", "--threads", "2"]
        text = subprocess.run(
            [b, "render", scene, "-o", out, *args], check=True, capture_output=True, text=True
        ).stdout
        return float(re.search(r"^\s+frame\s+([0-9.]+)", text, re.M).group(1))

    for b in bins:
        cold(b)
    t = {b: [] for b in bins}
    s = {b: [] for b in bins}
    r = {b: [] for b in bins}
    loads = []
    waits = 0
    for i in range(n):
        while quiet and idle_share() < 0.9:
            waits += 1
            time.sleep(1)
        loads.append(os.getloadavg()[0])
        for b in bins[i % len(bins) :] + bins[: i % len(bins)]:
            tb, sb = cold(b), steady(b)
            t[b].append(tb)
            s[b].append(sb)
            r[b].append(tb / sb)
    med = statistics.median
    print(f"load average {min(loads):.2f}-{max(loads):.2f}; waits for an idle host: {waits}")
    for b in bins:
        print(
            f"{b}: time to image {med(t[b]):.1f} ms ({min(t[b]):.1f}-{max(t[b]):.1f}), "
            f"steady frame {med(s[b]):.1f} ms ({min(s[b]):.1f}-{max(s[b]):.1f}), "
            f"ratio per pair {med(r[b]):.2f} ({min(r[b]):.2f}-{max(r[b]):.2f})"
        )


if __name__ == "__main__":
    main()
