#!/usr/bin/env python3
"""The sigrok decoder profibus_dp where the chip's answer overlaps the master's next request
(docs/waveforms.md, "Errors" row: a collision).

Usage: sigrok_profibus_dp_late.py path/to/dpc31 SOURCE_DIR

The run: 12 Mbaud (T = 4 clocks at 48 MHz), the master's slot time 100 bit times, the slave's
MinTSDR 150 (docs/scenario-format.md, `master slot=`, `slave min_tsdr=`). Each answer starts 150 T
after its request's last stop bit (docs/timing.md, the "answer" row); the master gave up at 100 T
and started its next request TSYN (33 T) later, at 133 T ("The master's wait"). So every answer's
first character starts 17 T into the next request, on TxD while RxD is sending: one bus cannot
carry both, and the decoder, which takes both lines as one bus, must show a collision there, not
cut the request, invent a response of the two lines' bytes or an idle time below 0.

Checked against the run's pcapng (its `cycles START-END` comments, docs/capture.md):
- every request (inbound packet) is decoded whole, its bytes at its start (within one sample);
- each answer (outbound) that starts inside a request gives, at its start, the annotation
  `Collision: XXh on TxD while RxD is sending` (XX its first byte); the SC E5 after the Set_Prm
  among them, 133 + 17 = 150 T after the Set_Prm's end;
- no annotation ends before it starts, no idle or TSDR below 0, no broken telegram.
Exit 0 if so, 1 with the differences.
"""

import re
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sigrok_profibus_dp import CLOCK_HZ, decode, run  # noqa: E402
from waveform_sigrok_demo import fail_if, pcapng_blocks, timescale_ns  # noqa: E402

T = 4  # clocks per bit at 12 Mbaud
SCENARIO = """profile spc3
baud 12000000
master address=2 slot=100
slave address=5 min_tsdr=150
startup tries=6
"""


def main():
    dpc31, srcdir = sys.argv[1:3]
    with tempfile.TemporaryDirectory() as d:
        Path(f"{d}/late.scn").write_text(SCENARIO, encoding="utf-8")
        run([dpc31, "run", f"{d}/late.scn", "--la-vcd", f"{d}/la.vcd", "--pcap",
             f"{d}/late.pcapng"])
        unit_cyc = timescale_ns(f"{d}/la.vcd") * CLOCK_HZ / 1e9  # cycles per sample
        packets = []  # (start, end, bytes, from the chip)
        for _, line, payload, comment in pcapng_blocks(f"{d}/late.pcapng"):
            c = re.fullmatch(r"cycles (\d+)-(\d+)", comment)
            packets.append((int(c.group(1)), int(c.group(2)), payload, line == "tx"))
        anns = [(ss * unit_cyc, es * unit_cyc, text)
                for ss, es, text in decode(f"{d}/la.vcd", 12_000_000, srcdir, 1)]
        problems = []
        near = lambda text, at: [a for a in anns if a[2] == text and abs(a[0] - at) <= unit_cyc]
        requests = [p for p in packets if not p[3]]
        for s, _, b, _ in requests:
            if not near(b.hex(" ").upper(), s):
                problems.append(f"the request {b.hex(' ')} at cycle {s} is not decoded whole")
        collided = 0
        for s, _, b, _ in (p for p in packets if p[3]):
            inside = any(r[0] < s < r[1] for r in requests)
            if inside:
                collided += 1
                text = f"Collision: {b[0]:02X}h on TxD while RxD is sending"
                if not near(text, s):
                    problems.append(f"no {text!r} at cycle {s}")
        set_prm = next(p for p in requests if p[2][9:10] == b"\x88")  # Set_Prm's Station_Status
        sc = next(p for p in packets if p[3] and p[0] > set_prm[1])
        if (sc[2], sc[0]) != (b"\xe5", set_prm[1] + 150 * T) or collided < 1:
            problems.append(f"the Set_Prm's SC {sc} is not the late E5 at its end + 150 T")
        for ss, es, text in anns:
            if es < ss or re.match(r"(Idle|TSDR) (>= )?-", text) or text.startswith("Broken"):
                problems.append(f"{ss:.0f}-{es:.0f}: {text}")
        print(f"{len(requests)} requests decoded whole, {collided} answers collided")
        fail_if(problems)
    print("ok")


if __name__ == "__main__":
    main()
