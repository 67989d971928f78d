#!/usr/bin/env python3
"""The sigrok decoder profibus_dp on a waveform window that opens at a telegram's first start bit
(the outside audit of the thirty-first session; docs/waveforms.md, "Gaps ... never below 0").

Usage: sigrok_profibus_dp_window.py path/to/dpc31 SOURCE_DIR

The run: traces/startup_dpc31_1m5.scn (1.5 Mbaud, T = 32 clocks at 48 MHz, a character 11 T =
352 clocks). Its first FDL_Status request 10 05 02 49 50 16 (the pcapng's `cycles S-E`,
docs/capture.md; E = S + 6 x 352) is the window: `--la-vcd --from S --to E`. The line is low at
the window's first time (the SD's start bit), so sigrok's uart decoder misses that start bit and
reads the first characters wrong, but it takes the third character's start bit at S + 2 x 352
and every character after it, each a telegram of its own (none of 02, 49, 50, 16 is a start
delimiter). Each of 49, 50 and 16 starts where the one before ends (11 T after its start bit): no
idle. A 10 ns sample is 100 / 48 cycles, so a character's end, 733 1/3 samples after its start
bit, falls between samples; the decoder must read `Idle 0.0 bit times` before each (it read
`-0.0` where the next start bit's sample came 1/3 sample before that end), at the character's
start sample round(cycle x 100 / 48) - round(S x 100 / 48) (sigrok counts from the file's first
time), and no annotation anywhere ends before it starts or gives a gap below 0.
Exit 0 if so, 1 with the differences.
"""

import re
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sigrok_profibus_dp import decode, run  # noqa: E402
from waveform_sigrok_demo import fail_if, pcapng_blocks  # noqa: E402

CHAR = 11 * 32  # clocks per character at 1.5 Mbaud
FDL_STATUS = bytes([0x10, 0x05, 0x02, 0x49, 0x50, 0x16])


def sample(cycle):
    """The 10 ns time of `cycle` at 48 MHz, rounded halves up (docs/waveforms.md)."""
    return (cycle * 100 + 24) // 48


def main():
    dpc31, srcdir = sys.argv[1:3]
    scn = f"{srcdir}/traces/startup_dpc31_1m5.scn"
    with tempfile.TemporaryDirectory() as d:
        run([dpc31, "run", "--quiet", scn, "--pcap", f"{d}/all.pcapng"])
        start = next(int(m.group(1)) for _, _, payload, comment in pcapng_blocks(f"{d}/all.pcapng")
                     if payload == FDL_STATUS
                     and (m := re.fullmatch(r"cycles (\d+)-(\d+)", comment)))
        end = start + len(FDL_STATUS) * CHAR
        run([dpc31, "run", "--quiet", scn, "--la-vcd", f"{d}/w.vcd", "--from", str(start),
             "--to", str(end)])
        anns = decode(f"{d}/w.vcd", 1_500_000, srcdir, 1)
        problems = []
        for k in (3, 4, 5):  # 49, 50, 16: each right after the one before
            at = sample(start + k * CHAR) - sample(start)
            # From the character's computed end (within one sample before it) to its start bit.
            if not [a for a in anns
                    if a[2] == "Idle 0.0 bit times" and a[1] == at and at - 1 <= a[0] <= at]:
                problems.append(f"no Idle 0.0 bit times ending at {at}; the idle annotations: "
                                f"{[a for a in anns if a[2].startswith('Idle')]}")
        for ss, es, text in anns:
            if es < ss or re.match(r"(Idle|TSDR) (>= )?-", text):
                problems.append(f"{ss}-{es}: {text}")
        fail_if(problems)
    print("ok: the characters after the first start bit are back to back, Idle 0.0 each")


if __name__ == "__main__":
    main()
