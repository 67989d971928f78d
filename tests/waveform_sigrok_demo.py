#!/usr/bin/env python3
"""sigrok-cli decodes the demo's waveform for logic-analyser tools, as it is, into exactly the
telegrams of the demo's own log (issue 18 item 3; docs/waveforms.md).

Usage: waveform_sigrok_demo.py path/to/dpc31

Runs `dpc31 demo` with no options but --out-dir, then sigrok-cli's UART decoder (8E1 at the baud
rate the demo's log states) on RxD and on TxD of dpc31-demo-la.vcd. The telegram log is the
demo's pcapng (every telegram the chip received and sent, with its start time and direction) and,
for the master's FDL_Status requests the chip did not take while it searched the baud rate, the
demo's "no answer (xN, last at cycle C)" line. Each decoded telegram must equal one of the log's,
byte for byte, and start when the log says (within a quarter bit); every telegram of the log
must be decoded; no parity error or framing warning. Exit 0 if so, 1 with the differences.
"""

import re
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

CLOCK_HZ = 48_000_000


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def fail_if(problems):
    """Fails with the first 20 of `problems`, if there are any."""
    if problems:
        fail("\n".join(problems[:20]))


def pcapng_blocks(path):
    """(start ns, direction 'rx'/'tx', bytes, opt_comment) of every Enhanced Packet Block."""
    data = Path(path).read_bytes()
    out, pos = [], 0
    while pos + 12 <= len(data):
        btype, blen = struct.unpack_from("<II", data, pos)
        if btype == 6:  # EPB: interface, timestamp high/low (ns), captured and original length
            _, hi, lo, caplen, _ = struct.unpack_from("<IIIII", data, pos + 8)
            payload = data[pos + 28:pos + 28 + caplen]
            opt = pos + 28 + (caplen + 3) // 4 * 4
            flags, comment = 0, None
            while opt + 4 <= pos + blen - 4:
                code, olen = struct.unpack_from("<HH", data, opt)
                if code == 0:
                    break
                if code == 1:  # opt_comment: "cycles START-END"
                    comment = data[opt + 4:opt + 4 + olen].decode("utf-8")
                if code == 2:  # epb_flags: bits 1:0 direction, 1 inbound (RxD), 2 outbound
                    flags = struct.unpack_from("<I", data, opt + 4)[0]
                opt += 4 + (olen + 3) // 4 * 4
            direction = {1: "rx", 2: "tx"}.get(flags & 3)
            if direction is None:
                fail(f"{path}: a packet without a direction")
            out.append(((hi << 32) | lo, direction, bytes(payload), comment))
        pos += blen
    return out


def pcapng_telegrams(path):
    """(start ns, direction 'rx'/'tx', bytes) of every Enhanced Packet Block."""
    return [(t, d, p) for t, d, p, _ in pcapng_blocks(path)]


def sigrok(vcd, pin, baud):
    """(start ns of the start bit, byte) of every character sigrok decodes on `pin`."""
    unit_ns = timescale_ns(vcd)
    cmd = ["sigrok-cli", "-I", "vcd", "-i", vcd, "-P",
           f"uart:rx={pin}:baudrate={baud}:parity=even:data_bits=8:stop_bits=1.0",
           "-A", "uart=rx-data:rx-warnings:rx-parity-err", "--protocol-decoder-samplenum"]
    r = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if r.returncode != 0:
        fail(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
    chars = []
    bit_ns = 1e9 / baud
    for line in r.stdout.splitlines():
        m = re.fullmatch(r"(\d+)-(\d+) uart-1: ([0-9A-F]{2})", line.strip())
        if not m:
            fail(f"sigrok on {pin}: not a data byte: {line!r}")
        # The data annotation starts at the first data bit: the start bit is one bit before.
        chars.append((int(m.group(1)) * unit_ns - bit_ns, int(m.group(3), 16)))
    if not chars:
        fail(f"sigrok decoded nothing on {pin} ({vcd})")
    return chars


def timescale_ns(vcd):
    with open(vcd, encoding="ascii") as f:
        for line in f:
            m = re.match(r"\$timescale\s*(1|10|100)\s*(s|ms|us|ns|ps|fs)\s*\$end", line)
            if m:
                exp = {"s": 9, "ms": 6, "us": 3, "ns": 0, "ps": -3, "fs": -6}[m.group(2)]
                return int(m.group(1)) * 10.0 ** exp
    fail(f"{vcd}: no $timescale")
    return None


def telegrams(chars, baud):
    """Characters grouped into telegrams: back to back (11 bits apart) belong together."""
    char_ns = 11e9 / baud
    groups = []
    for t, b in chars:
        if groups and t - groups[-1][1] < 1.5 * char_ns:
            groups[-1][1] = t
            groups[-1][2].append(b)
        else:
            groups.append([t, t, [b]])
    return [(start, bytes(bs)) for start, _, bs in groups]


def main():
    dpc31 = sys.argv[1]
    with tempfile.TemporaryDirectory() as d:
        r = subprocess.run([dpc31, "demo", "--out-dir", d], capture_output=True, text=True,
                           check=False)
        if r.returncode != 0:
            fail(f"dpc31 demo: exit {r.returncode}: {r.stderr.strip()}")
        log = r.stdout
        m = re.search(r"master \d+ -> slave \d+ at (\d+) baud", log)
        if not m:
            fail("the demo's log states no baud rate")
        baud = int(m.group(1))
        vcd = f"{d}/dpc31-demo-la.vcd"
        if f"waveform for logic-analyser tools (VCD, sigrok-cli -I vcd): {vcd}" not in log:
            fail("the demo does not name its waveform for logic-analyser tools")
        cycle_ns = 1e9 / CLOCK_HZ
        want = {"rx": [], "tx": []}
        for start, direction, payload in pcapng_telegrams(f"{d}/dpc31-demo.pcapng"):
            want[direction].append((start, payload, start))
        # Requests nobody took (the chip was searching the baud rate): first and last cycle.
        for m in re.finditer(r"\[cycle +(\d+)\] (\d+) -> (\d+) FDL_Status => no answer"
                             r"(?: \(x(\d+), last at cycle (\d+)\))?", log):
            first, sa, da = int(m.group(1)), int(m.group(2)), int(m.group(3))
            n = int(m.group(4) or 1)
            last = int(m.group(5) or first)
            body = bytes([da, sa, 0x49])
            frame = bytes([0x10]) + body + bytes([sum(body) & 0xFF, 0x16])
            for i in range(n):
                lo = first if i == 0 else first + 1
                hi = last if i == n - 1 else last - 1
                want["rx"].append((lo * cycle_ns, frame, hi * cycle_ns))
        tolerance = 1e9 / baud / 4
        errors = []
        for pin, direction in (("rxd", "rx"), ("txd", "tx")):
            got = telegrams(sigrok(vcd, pin, baud), baud)
            exp = sorted(want[direction])
            if not exp:
                errors.append(f"the log has no {direction} telegram")
            for i in range(max(len(got), len(exp))):
                g = got[i] if i < len(got) else None
                e = exp[i] if i < len(exp) else None
                if g is None or e is None:
                    errors.append(f"{pin} telegram {i}: decoded {g and g[1].hex(' ')}, "
                                  f"log {e and e[1].hex(' ')}")
                    continue
                if g[1] != e[1] or not e[0] - tolerance <= g[0] <= e[2] + tolerance:
                    errors.append(f"{pin} telegram {i}: decoded {g[1].hex(' ')} at "
                                  f"{g[0]:.0f} ns, log {e[1].hex(' ')} at {e[0]:.0f} ns")
            print(f"{pin}: {len(got)} telegrams decoded, {len(exp)} in the log, "
                  f"{sum(len(t[1]) for t in got)} bytes")
        fail_if(errors)
    print("ok")


if __name__ == "__main__":
    main()
