#!/usr/bin/env python3
"""The sigrok decoder profibus_dp (lib/sigrok/profibus_dp) on a real run's DPV1 (docs/waveforms.md,
docs/dpv1.md): traces/dpv1_c1_vpc3plus.scn on a VPC3+ at 12 Mbaud, written as the waveform for
logic-analyser tools (`dpc31 run --la-vcd`), decoded by sigrok-cli's uart decoder and the shipped
profibus_dp, exactly as a user runs them.

Usage: sigrok_profibus_dp_dpv1.py path/to/dpc31 SOURCE_DIR

The expected telegrams follow from the manual and the standard, not from the run:
- MSAC_C1 Read / Write go to SAP 51 (manual-quotes.md, "DPV1": "MSAC_C1 Read / Write on SAP 51";
  function numbers Read 5Eh, Write 5Fh; the request: function, slot, index, length (and the
  data); the positive response the same head, with the data read); the built-in master sends
  from its SAP 51 (docs/dpv1.md, "The master's side": DSAP / SSAP 51 / 51).
- The telegram (EN 50170, docs/dpv1.md "A request, a poll, a response"): SD2 68h LE LEr 68h, DA
  and SA with bit 7 set (SAPs follow), FC, DSAP, SSAP, the data unit, FCS (the sum of DA to the
  data unit's last byte, modulo 256), ED 16h; LE counts DA to the data unit's last byte.
- The request's FC: SRD high (Dh) as a request (40h) with FCV (10h) and the FCB (20h), which
  alternates from one request to the same slave to the next (EN 50170); the response's FC 08h
  (the Profichip driver's DL, which the built-in user side writes; the chip clears bits 7..6).
- The answer's DSAP is the request's SSAP and its SSAP the request's DSAP (VPC3+C p.56, as
  docs/dpv1.md step 4 gives it).
- The record: slot 0, index 1, 11 22 33 44 (the scenario's `record` line); the Write's data A1
  A2 A3 A4; the Read of index 7 gets the negative response DE 80 B0 00 (Read | 80h, Error_Decode
  DPV1 = 80h, Error_Code_1 B0h access / invalid index, manual-quotes.md).
- Between request and response the master polls with the same SAPs and no data, answered SC
  (E5h) until the response is in (docs/dpv1.md): the scenario derives two SC polls.
Exit 0 if every expected telegram is decoded in order, byte for byte, with its DPV1 annotation;
1 with the difference.
"""

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from waveform_sigrok_demo import fail  # noqa: E402

SD2, ED, SC = 0x68, 0x16, 0xE5
MASTER, SLAVE = 2, 5   # the scenario's `master address=2`, `slave address=5`
C1 = 51                # MSAC_C1's SAP
SRD_HIGH, REQUEST, FCV, FCB = 0x0D, 0x40, 0x10, 0x20
RESPONSE_FC = 0x08


def sd2(da, sa, fc, dsap, ssap, du):
    body = bytes([da | 0x80, sa | 0x80, fc, dsap, ssap]) + bytes(du)
    return bytes([SD2, len(body), len(body), SD2]) + body + bytes([sum(body) & 0xFF, ED])


def run(cmd, env=None):
    r = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    if r.returncode != 0:
        fail(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()[:400]}")
    return r.stdout


def decoded(dpc31, srcdir, d):
    """[(bytes row, [DPV1 annotations inside the telegram])] of the run, in bus order."""
    run([dpc31, "run", f"{srcdir}/traces/dpv1_c1_vpc3plus.scn", "--la-vcd", f"{d}/la.vcd"])
    env = dict(os.environ, SIGROKDECODE_DIR=f"{srcdir}/lib/sigrok")
    out = run(["sigrok-cli", "-I", "vcd", "-i", f"{d}/la.vcd", "-P",
               "uart:rx=rxd:tx=txd:baudrate=12000000:parity=even,profibus_dp",
               "-A", "profibus_dp=bytes:dpv1:error", "--protocol-decoder-samplenum"], env=env)
    telegrams, dpv1 = [], []
    for line in out.splitlines():
        m = re.fullmatch(r"(\d+)-(\d+) profibus_dp-1: (.*)", line.strip())
        if not m:
            fail(f"not an annotation: {line!r}")
        ss, es, text = int(m.group(1)), int(m.group(2)), m.group(3)
        if re.fullmatch(r"([0-9A-F]{2} ?)+", text):
            telegrams.append((ss, es, bytes.fromhex(text)))
        elif re.match(r"(Read|Write|Alarm_Ack|Initiate|Abort|Idle|Data_Transport)", text):
            dpv1.append((ss, es, text))
        else:
            fail(f"an error on a clean run: {text!r}")
    return [(b, [t for s, e, t in dpv1 if ss <= s and e <= es]) for ss, es, b in telegrams]


def expected():
    """The scenario's first four services: Read, Write, Read again, the Read of a missing index;
    each: the request and two polls answered SC, a third poll answered with the response. A request is
    a function of its FC."""
    out = []

    def req(du):
        return lambda fc: sd2(SLAVE, MASTER, fc, C1, C1, du)

    res = lambda du: sd2(MASTER, SLAVE, RESPONSE_FC, C1, C1, du)
    services = [
        ([0x5E, 0x00, 0x01, 0x04], [0x5E, 0x00, 0x01, 0x04, 0x11, 0x22, 0x33, 0x44],
         "Read request: Slot 0, Index 1, Length 4",
         "Read response: Slot 0, Index 1, Length 4, Data 11 22 33 44"),
        ([0x5F, 0x00, 0x01, 0x04, 0xA1, 0xA2, 0xA3, 0xA4], [0x5F, 0x00, 0x01, 0x04],
         "Write request: Slot 0, Index 1, Length 4, Data A1 A2 A3 A4",
         "Write response: Slot 0, Index 1, Length 4"),
        ([0x5E, 0x00, 0x01, 0x04], [0x5E, 0x00, 0x01, 0x04, 0xA1, 0xA2, 0xA3, 0xA4],
         "Read request: Slot 0, Index 1, Length 4",
         "Read response: Slot 0, Index 1, Length 4, Data A1 A2 A3 A4"),
        ([0x5E, 0x00, 0x07, 0x04], [0xDE, 0x80, 0xB0, 0x00],
         "Read request: Slot 0, Index 7, Length 4",
         "Read negative response: Error_Decode 80h (DPV1), Error_Code_1 B0h (access: invalid "
         "index), Error_Code_2 00h"),
    ]
    for request, response, req_text, res_text in services:
        out.append((req(request), [req_text]))
        for _ in range(3):  # the request's SC, then poll 1 and 2's; poll 3 gets the response
            out.append((bytes([SC]), []))
            out.append((req([]), []))
        out.append((res(response), [res_text]))
    return out


def main():
    dpc31, srcdir = sys.argv[1:3]
    with tempfile.TemporaryDirectory() as d:
        got = decoded(dpc31, srcdir, d)
    want = expected()
    first = next((i for i, (b, _) in enumerate(got) if len(b) > 9 and b[9] in (0x5E, 0x5F)
                  and b[4] == SLAVE | 0x80), None)
    if first is None:
        fail("no DPV1 request decoded")
    # The first request's FCB follows the start-up's requests: taken as decoded, then alternating.
    fcb = got[first][0][6] & FCB
    for k, (make, notes) in enumerate(want):
        i = first + k
        if i >= len(got):
            fail(f"telegram {k} of the DPV1 part: not decoded")
        b, texts = got[i]
        if callable(make):
            w = make(REQUEST | fcb | FCV | SRD_HIGH)
            fcb ^= FCB  # the next request to the slave carries the other FCB
        else:
            w = make
        if b != w:
            fail(f"telegram {k}: decoded {b.hex(' ')}, expected {w.hex(' ')}")
        if texts != notes:
            fail(f"telegram {k} ({b.hex(' ')}): DPV1 {texts}, expected {notes}")
    print(f"OK: {len(want)} DPV1 telegrams decoded as expected")


if __name__ == "__main__":
    main()
