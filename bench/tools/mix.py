#!/usr/bin/env python3
"""Executed-instruction mix of a callgrind profile.

Joins callgrind's per-instruction counts (`--dump-instr=yes`) with the
binary's disassembly and sums them by kind: vector FP arithmetic, FMAs,
compares/selects, vector loads/stores/moves, gathers, scalar, branches.

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=/tmp/cg.mix \
        --toggle-collect='*shade_tile*' target/release/specula render \
        fixtures/scenes/sphere-grid.toml --threads 1 -o /tmp/g.png
    objdump -d --no-show-raw-insn target/release/specula > /tmp/dis.txt
    python3 bench/tools/mix.py /tmp/cg.mix /tmp/dis.txt [PIXELS]

PIXELS (default 1920 × 1080) divides the counts into per-pixel figures.
Only the instructions' own (self) counts are summed: the inclusive cost
lines that follow a `calls=` line are skipped.
"""

import collections
import re
import sys

COUNT_LINE = re.compile(r"^(0x[0-9a-f]+|[+-]\d+|\*)\s+(\S+)\s+(\d+)$")
DIS_LINE = re.compile(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$")


def self_counts(path):
    """Instruction address -> executed count, from a callgrind file whose
    positions are `instr line` (addresses may be relative to the last)."""
    costs = collections.Counter()
    addr, after_call = 0, False
    for line in open(path):
        if line.startswith("calls="):
            after_call = True
            continue
        m = COUNT_LINE.match(line.rstrip("\n"))
        if not m:
            continue
        a, _, c = m.groups()
        if a.startswith("0x"):
            addr = int(a, 16)
        elif a != "*":
            addr += int(a)
        if after_call:
            after_call = False
            continue
        costs[addr] += int(c)
    return costs


def mnemonics(path):
    ops = {}
    for line in open(path):
        m = DIS_LINE.match(line)
        if m:
            ops[int(m.group(1), 16)] = (m.group(2), m.group(3))
    return ops


def kind(op, args):
    if "gather" in op:
        return "gather"
    if op.startswith("v") and ("ymm" in args or "xmm" in args):
        if re.match(r"vfn?m(add|sub)\d+[ps]s", op):
            return "fp fma"
        if re.match(r"v(add|sub|mul|div|sqrt|rcp|rsqrt|max|min)[ps]s", op):
            return "fp arith"
        if re.match(r"v(cmp|blendv|and|andn|or|xor)p[sd]", op):
            return "fp compare/select/logic"
        if re.match(r"vmov|vbroadcast|vinsert|vextract|vperm|vunpck|vshuf|vpbroadcast", op):
            return "vector load/store/move"
        if op.startswith("vp"):
            return "vector integer"
        if re.match(r"vcvt|vround", op):
            return "conversion"
        return "vector other"
    if op.startswith("j") or op in ("call", "ret"):
        return "branch"
    return "scalar"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    costs = self_counts(sys.argv[1])
    ops = mnemonics(sys.argv[2])
    pixels = int(sys.argv[3]) if len(sys.argv) > 3 else 1920 * 1080
    by_kind = collections.Counter()
    for addr, n in costs.items():
        by_kind[kind(*ops.get(addr, ("?", "")))] += n
    total = sum(by_kind.values())
    print(f"{'total':28s} {total:>14,}")
    for k, n in by_kind.most_common():
        print(f"{k:28s} {n:>14,} {100 * n / total:5.1f} %  {n / pixels:6.1f} per pixel")


if __name__ == "__main__":
    main()
