#!/usr/bin/env python3
"""Docs.firmware_sizes: the code sizes of the shipped 80C32 firmware that the documents give are
the build's (audit a19: they stood 353 bytes behind dps.c for a while). The sizes are SDCC's, read from
what it wrote: `A CSEG size` / `A CONST size` of dps.rel, the CSEG and CONST lines of
do4_80c32.map and cnt2_80c32.map. The documents name SDCC 4.2.0; another SDCC gives other sizes,
and the test is skipped (exit 77) there.

Usage: firmware_sizes_test.py SOURCE_DIR FIRMWARE_BUILD_DIR SDCC.
"""

import os
import re
import subprocess
import sys


def rel_size(path, area):
    with open(path, encoding="latin-1") as f:
        for line in f:
            m = re.match(rf"A {area} size ([0-9A-F]+) ", line)
            if m:
                return int(m.group(1), 16)
    raise SystemExit(f"{path}: no area {area}")


def map_size(path, area):
    with open(path, encoding="latin-1") as f:
        for line in f:
            m = re.match(rf"{area}\s+[0-9A-F]+\s+[0-9A-F]+ =\s+(\d+)\. bytes", line)
            if m:
                return int(m.group(1))
    raise SystemExit(f"{path}: no area {area}")


def spaced(n):
    """14549 as the documents write it: 14 549."""
    return f"{n:,}".replace(",", " ")


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    src, fw, sdcc = sys.argv[1:]
    version = subprocess.run([sdcc, "--version"], capture_output=True, text=True,
                             check=False).stdout
    if " 4.2.0 " not in version:
        print(f"skipped: the documents' sizes are SDCC 4.2.0's, this is {version.strip()}")
        return 77
    dps = os.path.join(fw, "dps.rel")
    do4 = os.path.join(fw, "do4_80c32.map")
    cnt2 = os.path.join(fw, "cnt2_80c32.map")
    dps_code, dps_const = spaced(rel_size(dps, "CSEG")), rel_size(dps, "CONST")
    want = {
        "docs/dpc31.md": [f"The shared driver layer is {dps_code} bytes of code (and "
                          f"{dps_const} of constants)"],
        "docs/decisions.md": [f"dps.c is {dps_code} bytes of code for the 80C32"],
        "docs/firmware.md": [f"they are {spaced(map_size(do4, 'CSEG'))} and "
                             f"{spaced(map_size(cnt2, 'CSEG'))} bytes of code now"],
        "docs/cpu.md": [f"`build/firmware/mcs51/cnt2_80c32.ihx` ({spaced(map_size(cnt2, 'CSEG'))} "
                        f"bytes of code and {map_size(cnt2, 'CONST')} of constants with SDCC "
                        "4.2.0"],
    }
    failed = 0
    for doc, sentences in want.items():
        with open(os.path.join(src, doc), encoding="utf-8") as f:
            text = " ".join(f.read().split())  # a sentence may break across lines
        for s in sentences:
            if s not in text:
                print(f"{doc}: no '{s}' (the build's sizes)")
                failed += 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
