#!/usr/bin/env python3
"""The sigrok decoder profibus_dp on hand-built telegrams: what no run of ours sends (DPV1 PDUs,
late answers, short idle, broken frames, SD3, the token), each with the annotation the standard
makes of it (issue 33 item 1; docs/waveforms.md).

Usage: sigrok_profibus_dp_units.py SOURCE_DIR

Writes a VCD of a logic analyser at 100 MHz (10 ns) on a 500 kbaud bus (200 samples a bit): the
master's telegrams on `rxd`, the slave's on `txd`, characters 11 bits (start, 8 data LSB first,
even parity, stop; EN 50170), back to back inside a telegram, each telegram after the idle time
(in bit times) written next to it. Then `sigrok-cli -P uart:...,profibus_dp` and every expected
annotation must be among the decoder's, at its time. The expected texts come from the
standard's numbers: DPV1 function numbers Read 5Eh, Write 5Fh, Alarm_Ack 5Ch, Initiate 57h,
Abort 58h, Data_Transport 51h, Idle 48h, a negative response the function with bit 7 set and
Error_Decode, Error_Code_1, Error_Code_2 (docs/waveforms.md, "DPV1"); FC and SAP numbers
(EN 50170 / IEC 61158-3-3); the default slot time at 500 kbaud, 200 bit times.
"""

import os
import subprocess
import sys
import tempfile

BIT = 200            # samples per bit: 100 MHz / 500 kbaud
CHAR = 11 * BIT


def fcs(body):
    return sum(body) & 0xFF


def sd1(da, sa, fc):
    body = [da, sa, fc]
    return [0x10, *body, fcs(body), 0x16]


def sd2(da, sa, fc, du):
    body = [da, sa, fc, *du]
    return [0x68, len(body), len(body), 0x68, *body, fcs(body), 0x16]


# Master 2 (SAP ext 0x82), slave 5 (0x85). (line, idle bit times before it, bytes).
MS = 0x82
SL = 0x85
BUS = [
    # MSAC_C1 Read request on DSAP 51 / SSAP 51, SRD_high FCB=1 FCV=1 (7Dh), then the SC.
    ("rxd", 40, sd2(SL, MS, 0x7D, [51, 51, 0x5E, 0x01, 0x02, 0xF0])),
    ("txd", 11, [0xE5]),
    # The poll, and the Read response (DL, 08h): slot 1, index 2, 3 bytes.
    ("rxd", 33, sd2(SL, MS, 0x5D, [51, 51])),
    ("txd", 11, sd2(MS, SL, 0x08, [51, 51, 0x5E, 0x01, 0x02, 0x03, 0xAA, 0xBB, 0xCC])),
    # A Write request and its negative response: DFh, Error_Decode 80h (DPV1), Error_Code_1
    # B6h (access: access denied), Error_Code_2 00h.
    ("rxd", 33, sd2(SL, MS, 0x7D, [51, 51, 0x5F, 0x03, 0x04, 0x01, 0x42])),
    ("txd", 20, sd2(MS, SL, 0x08, [51, 51, 0xDF, 0x80, 0xB6, 0x00])),
    # MSAC_C2 Initiate on DSAP 49: 3 reserved, Send_Timeout 0064h, Features 0100h,
    # Profile_Features 0000h, Profile_Ident 9700h, S_Type/S_Len/D_Type/D_Len.
    ("rxd", 33, sd2(SL, MS, 0x6D, [49, 50, 0x57, 0, 0, 0, 0x00, 0x64, 0x01, 0x00, 0x00, 0x00,
                                   0x97, 0x00, 0, 0, 0, 0])),
    ("txd", 11, [0xE5]),
    # Initiate response: Max_Len_Data_Unit 240, Features 0100h, Profile_Features 0000h,
    # Profile_Ident 9700h.
    ("rxd", 33, sd2(SL, MS, 0x5D, [49, 50])),
    ("txd", 11, sd2(MS, SL, 0x08, [50, 49, 0x57, 0xF0, 0x01, 0x00, 0x00, 0x00, 0x97, 0x00,
                                   0, 0, 0, 0])),
    # On the connection's SAP 40: Data_Transport, Idle, Abort (subnet 0, instance 1 =
    # MSAC_C2, reason code 3).
    ("rxd", 33, sd2(SL, MS, 0x7D, [40, 50, 0x51, 0x00, 0x00, 0x02, 0x11, 0x22])),
    ("txd", 11, [0xE5]),
    ("rxd", 33, sd2(SL, MS, 0x5D, [40, 50, 0x48])),
    ("txd", 11, [0xE5]),
    ("rxd", 33, sd2(SL, MS, 0x74, [40, 50, 0x58, 0x00, 0x13])),
    # Alarm_Ack on DSAP 50: slot 2, Alarm_Type 1 (Diagnostic), Specifier 08h = Seq_Nr 1.
    ("rxd", 33, sd2(SL, MS, 0x7D, [50, 51, 0x5C, 0x02, 0x01, 0x08])),
    ("txd", 11, [0xE5]),
    # FDL_Status answered 250 bit times late: slot time 200 at 500 kbaud.
    ("rxd", 33, sd1(5, 2, 0x49)),
    ("txd", 250, sd1(2, 5, 0x00)),
    # A request after only 20 idle bit times (TSYN is 33), never answered.
    ("rxd", 20, sd1(5, 2, 0x49)),
    # The token (SD4) and an SD3 request with its 8 data bytes.
    ("rxd", 100, [0xDC, 3, 2]),
    ("rxd", 33, [0xA2, 5, 2, 0x53, 1, 2, 3, 4, 5, 6, 7, 8, fcs([5, 2, 0x53, *range(1, 9)]),
                 0x16]),
    # Broken: LE 5 but LEr 6; a wrong FCS; ED 17h; a telegram cut after 3 bytes; noise 00h.
    ("rxd", 100, [0x68, 5, 6, 0x68, 5, 2, 0x6D, 1, 2, 0x77, 0x16]),
    ("rxd", 100, [0x10, 5, 2, 0x49, 0x51, 0x16]),
    ("rxd", 100, [0x10, 5, 2, 0x49, 0x50, 0x17]),
    ("rxd", 100, [0x10, 5, 2]),
    ("rxd", 100, [0x00]),
    ("rxd", 100, sd1(5, 2, 0x49)),
    # The poll on SAP 49 after an Initiate, and the resource manager's answer 56h: connection
    # SAP 40, Send_Timeout 0064h = 100 (the layout lib/capture/profibus_dl.lua decodes).
    ("rxd", 33, sd2(SL, MS, 0x5D, [49, 50])),
    ("txd", 11, sd2(MS, SL, 0x08, [50, 49, 0x56, 40, 0x00, 0x64])),
    # An FDL_Status, a token instead of its answer, then an SC: the answer of no request.
    ("rxd", 33, sd1(5, 2, 0x49)),
    ("rxd", 100, [0xDC, 5, 2]),
    ("rxd", 33, [0xE5]),
]

# (index of the telegram in BUS, expected annotation text) — the telegram's start sample is
# computed from BUS.
EXPECT = [
    (0, "68 09 09 68 85 82 7D 33 33 5E 01 02 F0 3B 16"),
    (0, "Request SRD_high 2 -> 5: MSAC_C1"),
    (0, "FC 7Dh request SRD_high FCB=1 FCV=1"),
    (0, "DA 5 +SAP"),
    (0, "DSAP 51"),
    (0, "SSAP 51"),
    (0, "Read request: Slot 1, Index 2, Length 240"),
    (0, "Idle >= 40.0 bit times"),
    (1, "SC short acknowledge (MSAC_C1)"),
    (1, "TSDR 11.0 bit times"),
    (3, "Response DL 5 -> 2: MSAC_C1"),
    (3, "FC 08h response DL (slave)"),
    (3, "Read response: Slot 1, Index 2, Length 3, Data AA BB CC"),
    (4, "Write request: Slot 3, Index 4, Length 1, Data 42"),
    (5, "Write negative response: Error_Decode 80h (DPV1), Error_Code_1 B6h (access: access "
        "denied), Error_Code_2 00h"),
    (5, "TSDR 20.0 bit times"),
    (6, "Request SRD_high 2 -> 5: MSAC_C2_Initiate"),
    (6, "Initiate request: Send_Timeout 100 x 10 ms, Features 0100, Profile_Ident 9700"),
    (9, "Initiate response: Max_Len_Data_Unit 240, Features 0100, Profile_Ident 9700"),
    (10, "Request SRD_high 2 -> 5: MSAC_C2 (SAP 40)"),
    (10, "Data_Transport request: Slot 0, Index 0, Length 2, Data 11 22"),
    (12, "Idle request"),
    (14, "Abort request: Subnet 0, Instance 1, Reason_Code 3"),
    (14, "Request SDN_low 2 -> 5: MSAC_C2 (SAP 40)"),
    (15, "Alarm_Ack request: Slot 2, Alarm_Type 1 (Diagnostic), Seq_Nr 1"),
    (15, "Request SRD_high 2 -> 5: MSAC_C1_Alarm"),
    (17, "Request FDL_Status 2 -> 5"),
    (18, "Response OK 5 -> 2: FDL_Status"),
    (18, "TSDR 250.0 bit times"),
    (18, "Late answer: TSDR 250.0 > slot time 200 bit times"),
    (19, "Idle 20.0 bit times"),
    (19, "Idle 20.0 < TSYN (33 bit times): a receiver ignores it"),
    (20, "No answer: the next telegram came after 100.0 bit times"),
    (20, "Token 2 -> 3"),
    (21, "Request SDA_low 2 -> 5"),
    (21, "Data 01 02 03 04 05 06 07 08"),
    (21, "FCS 7Eh ok"),
    (22, "Broken telegram: LE 5 but LEr 6: Request SRD_high 2 -> 5: Data_Exchange"),
    (23, "Broken telegram: FCS 51h, expected 50h: Request FDL_Status 2 -> 5"),
    (23, "FCS 51h, expected 50h"),
    (24, "Broken telegram: ED 17h, expected 16h: Request FDL_Status 2 -> 5"),
    (25, "Broken telegram: truncated after 3 bytes: SD1 telegram"),
    (26, "Broken telegram: not a start delimiter: 00h: Noise 00h"),
    (27, "Request FDL_Status 2 -> 5"),
    (29, "Response DL 5 -> 2: MSAC_C2_Initiate"),
    (29, "Resource_Manager response: Connection SAP 40, Send_Timeout 100 x 10 ms"),
    (31, "No answer: the next telegram came after 100.0 bit times"),
    (32, "SC short acknowledge"),
    (32, "Idle 33.0 bit times"),
]


def char_bits(v):
    parity = bin(v).count("1") & 1
    return [0] + [(v >> i) & 1 for i in range(8)] + [parity, 1]


def build_vcd(path):
    """Writes BUS; returns each telegram's start sample."""
    changes = {"rxd": [], "txd": []}
    t, starts = 0, []
    for line, idle, frame in BUS:
        t += idle * BIT
        starts.append(t)
        for v in frame:
            for i, b in enumerate(char_bits(v)):
                changes[line].append((t + i * BIT, b))
            t += CHAR
    t += 200 * BIT
    events = {}
    for sym, line in (("!", "rxd"), ('"', "txd")):
        level = 1
        for when, b in changes[line]:
            if b != level:
                events.setdefault(when, []).append(f"{b}{sym}")
                level = b
    with open(path, "w", encoding="ascii") as f:
        f.write("$timescale 10 ns $end\n$scope module dpc31 $end\n"
                "$var wire 1 ! rxd $end\n$var wire 1 \" txd $end\n$upscope $end\n"
                "$enddefinitions $end\n#0\n1!\n1\"\n")
        for when in sorted(events):
            if when:
                f.write(f"#{when}\n")
            f.write("\n".join(events[when]) + "\n")
        f.write(f"#{t}\n")
    return starts


def main():
    srcdir = sys.argv[1]
    with tempfile.TemporaryDirectory() as d:
        vcd = f"{d}/bus.vcd"
        starts = build_vcd(vcd)
        env = dict(os.environ, SIGROKDECODE_DIR=f"{srcdir}/lib/sigrok")
        cmd = ["sigrok-cli", "-I", "vcd", "-i", vcd, "-P",
               "uart:rx=rxd:tx=txd:baudrate=500000:parity=even,profibus_dp", "-A",
               "profibus_dp", "--protocol-decoder-samplenum"]
        r = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
        if r.returncode != 0 or "Error" in r.stderr:
            print(f"FAIL: {' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
            return 1
        anns = []
        for line in r.stdout.splitlines():
            ss_es, _, text = line.partition(" profibus_dp-1: ")
            ss, _, es = ss_es.partition("-")
            anns.append((int(ss), int(es), text))
        missing = []
        for i, text in EXPECT:
            start = starts[i]
            end = start + CHAR * len(BUS[i][2])
            # At the telegram, or (timing) in the gap before it; one sample of slack each side.
            hit = [a for a in anns if a[2] == text and a[1] >= start - BUS[i][1] * BIT - 1
                   and a[0] <= end + 1]
            if not hit:
                near = [a[2] for a in anns if start - 1 <= a[0] <= end]
                missing.append(f"telegram {i}: no {text!r}; there: {near}")
        if missing:
            print("FAIL:\n" + "\n".join(missing))
            return 1
    print(f"ok: {len(EXPECT)} annotations on {len(BUS)} telegrams")
    return 0


if __name__ == "__main__":
    sys.exit(main())
