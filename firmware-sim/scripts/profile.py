#!/usr/bin/env python3
"""Instructions per evaluated point, by function, from a simulator profile.

Usage:
    NEUROSURF_SIM_PROFILE=prof.txt neurosurf sim M.nsb --points Q --scalar q16.16 --mode single --json
    firmware-sim/scripts/profile.py target/firmware/thumbv7em-none-eabihf/release/neurosurf-firmware \
        prof.txt POINTS

The profile's lines are `neurosurf-profile <block address> <instructions in the block>
<instructions executed> <estimated cycles>` (the QEMU plugin's heaviest translation blocks over
the whole run; the cycles are not used here).
Every instruction of a block is attributed to the function it was compiled from (the innermost
inlined one, so kernels inlined into the evaluation count as themselves); the totals are divided
by POINTS. A development aid: it needs `llvm-objdump` and `llvm-addr2line` (Debian: `llvm`).
"""

import bisect
import collections
import re
import subprocess
import sys


def instruction_addresses(elf):
    """Sorted addresses of every instruction in the ELF's code."""
    listing = subprocess.run(
        ["llvm-objdump", "-d", "--no-show-raw-insn", elf],
        capture_output=True, text=True, check=True,
    ).stdout
    found = (re.match(r"\s+([0-9a-f]+):\s+\S", line) for line in listing.splitlines())
    return sorted(int(m.group(1), 16) for m in found if m)


def function_names(elf, addresses):
    """The innermost function each address was compiled from, demangled."""
    out = subprocess.run(
        ["llvm-addr2line", "-f", "-C", "-e", elf],
        input="\n".join(hex(a) for a in addresses),
        capture_output=True, text=True, check=True,
    ).stdout.splitlines()
    # Two lines per address: the function, then file:line.
    return {a: out[2 * k] for k, a in enumerate(addresses)}


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    elf, profile, points = sys.argv[1], sys.argv[2], int(sys.argv[3])
    blocks = []
    with open(profile) as lines:
        for line in lines:
            fields = line.split()
            if len(fields) == 5 and fields[0] == "neurosurf-profile":
                blocks.append((int(fields[1], 16), int(fields[2]), int(fields[3])))
    code = instruction_addresses(elf)
    spans = {}
    for start, size, _ in blocks:
        first = bisect.bisect_left(code, start)
        spans[start] = code[first:first + size]
    names = function_names(elf, sorted({a for span in spans.values() for a in span}))
    totals = collections.Counter()
    for start, size, executed in blocks:
        runs = executed / size
        for address in spans[start]:
            totals[names[address]] += runs
    print(f"{sum(e for _, _, e in blocks) / points:10.1f}  all (instructions per point)")
    for name, count in totals.most_common(30):
        print(f"{count / points:10.1f}  {name[:100]}")


if __name__ == "__main__":
    main()
