#!/usr/bin/env python3
"""End-to-end tests of `dpc31 bridge --slave` (docs/bridge.md, "Several slaves"), run by CTest.

Two stations on the bridge's one line: DO4 on a DPC31 at address 5 and the built-in user side
(`responder`: ident 0C31h, Cfg 13 23, its inputs the outputs it last fetched) at address 6.
tools/dp_master.py, the real program, is the master with two `--slave`s: it starts both up and
exchanges data with each in every DP cycle.

pty_two_slaves: over the pty; both reach Data_Exchange (the program's lines and the bridge's
STATE lines), each with its own data (DO4's input byte 51h for outputs 05 01; the responder's
inputs are its outputs 11 22 33 44); every TxD line names the station that answered.

tcp_two_slaves_pcap: over the raw TCP port with --pcap; tshark with the shipped dissector shows
both stations' answers, each from the station the comment names (SA of SD1/SD2 answers), at the
line timing of docs/timing.md: an answer MinTSDR = 11 bit times after its request, a request at
least TSYN = 33 bit times after the telegram before it, 11 bit times a character.

pty_two_do4: DO4 on a DPC31 at 5 and DO4 on an SPC3 at 7, each its own instance (docs/firmware.md,
"Instances"): each answers with the inputs of its own outputs (51h for 05 01, A1h for 0A 01).

bad_slave_arguments: a bad --slave, a duplicate address, mixing --slave with
the single slave's options: one line on stderr, exit 2, no log made.

one_slave_log_line: log line 1 with one --slave says `1 slave:`.

Usage: bridge_segment_test.py DPC31_CLI DISSECTOR CASE. Every wait is on an event (the master
program's exit, a log line), none on a wall time.
"""

import os
import re
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bridge_line_test as blt  # noqa: E402
import bridge_test as bt  # noqa: E402
from bridge_test import GUARD, LOST  # noqa: E402
from dp_master import Fail, check  # noqa: E402

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "dp_master.py")
BAUD = 19200
T = 48_000_000 // BAUD
STATIONS = ["--slave", "5:DO4", "--slave", "6:responder:spc3"]
# DO4's GSD defaults with the refresh monitor off, outputs 05 01; the responder's ident and Cfg,
# one User_Prm byte, outputs 11 22 33 44.
MASTER_SLAVES = ["--slave", "5:0x0D04:21,10:00,00,00,00:05,01",
                 "--slave", "6:0x0C31:13,23:00:11,22,33,44"]


def run_master(device, slaves=None):
    """tools/dp_master.py with both slaves, 20 DP cycles; its exit is the event waited for."""
    r = subprocess.run([sys.executable, TOOL, device, "--baud", str(BAUD), "--cycles", "20",
                        "--timeout", str(LOST), "--search", str(GUARD)]
                       + (slaves or MASTER_SLAVES),
                       capture_output=True, text=True, timeout=5 * GUARD, check=False)
    check(r.returncode == 0, f"dp_master exit {r.returncode}: {r.stdout} {r.stderr}")
    lines = r.stdout.splitlines()
    if slaves:
        return lines
    for a in (5, 6):
        check(any(line.startswith(f"slave {a}: Slave_Diag: ") and line.endswith("(ready)")
                  for line in lines), f"slave {a} never ready: {r.stdout}")
    # The inputs each station gave last: DO4's terminals 0101 with ModulOK; the loop-back.
    last = {a: [line for line in lines if line.startswith(f"slave {a}: Data_Exchange ")][-1]
            for a in (5, 6)}
    check(last[5] == "slave 5: Data_Exchange 05 01: inputs 51", f"slave 5: {last[5]}")
    check(last[6] == "slave 6: Data_Exchange 11 22 33 44: inputs 11 22 33 44",
          f"slave 6: {last[6]}")


def check_two_stations_log(lines, header_end):
    check(lines[0].startswith("dpc31 bridge: pacing free, baud 19200, 2 slaves: slave5 (profile "
                              "dpc31, irq-controller external, firmware DO4), slave6 (profile "
                              "spc3, firmware responder), slot 100 bit times, log level ")
          and lines[0].endswith(header_end), f"log line 1: {lines[0]}")
    bt.check_order(lines)
    text = "\n".join(lines)
    for a in (5, 6):
        check(f"STATE slave{a}   dp_state Wait_Cfg -> Data_Exchange" in text,
              f"slave{a} never reached Data_Exchange in the log")
    # Every answer's line names the station whose address its summary gives as the source
    # ("DL 5->2"; SC has none).
    for line in lines[1:]:
        parts = line.split(maxsplit=3)
        if parts[1] == "TxD" and "->" in parts[3]:
            source = re.search(r" (\d+)->2\b", parts[3])
            check(source and f"slave{source.group(1)}" == parts[2],
                  f"answer from another station: {line}")


def log_has(lines, *wants):
    text = "\n".join(lines)
    for want in wants:
        check(want in text, f"log lacks '{want}'")


def pty_run(stations, master):
    """The bridge on its pty with `stations`; master(path) runs the master program until it exits.
    Returns what master returned, the pty's path and the bridge's log lines."""
    with tempfile.TemporaryDirectory() as tmp:
        b = bt.Bridge(tmp, *stations, "--baud", str(BAUD), "--pacing", "free",
                      "--log-level", "telegrams")
        try:
            out = master(b.path)
            b.wait_for_log("client closed the pty", GUARD)
            b.stop(signal.SIGTERM)
            return out, b.path, b.log_lines()
        finally:
            b.kill()


def pty_two_slaves():
    _, path, lines = pty_run(STATIONS, run_master)
    check_two_stations_log(lines, f"pty {path} -> " + lines[0].rsplit(" -> ", 1)[-1])
    # LE 7: DA, SA, FC and 4 bytes; FCS 02 + 06 + 08 + 11 + 22 + 33 + 44 = BAh.
    log_has(lines, "TxD   slave6   10 02 06 00 08 16  | OK 6->2",
            "TxD   slave6   68 07 07 68 02 06 08 11 22 33 44 BA 16  | DL 6->2",
            "PORT  slave5   DO4 outputs = 0x05")


def tcp_two_slaves_pcap():
    with tempfile.TemporaryDirectory() as tmp:
        pcap = os.path.join(tmp, "line.pcapng")
        b = blt.TcpBridge(tmp, *STATIONS, "--baud", str(BAUD), "--pacing", "free",
                          "--pcap", pcap)
        try:
            run_master(b.url)
            b.wait_for_log("closed the connection", GUARD)
            b.stop()
            check_two_stations_log(b.log_lines(), f"tcp 127.0.0.1:{b.port}")
        finally:
            b.kill()
        fields = ["frame.comment", "profibus.sd", "profibus.le", "profibus.da", "profibus.sa",
                  "profibus.du", "profibus.service"]
        rows = [dict(zip(fields, r)) for r in blt.tshark_fields(pcap, fields)]
        packets = []
        for r in rows:
            found = re.fullmatch(r"cycles (\d+)-(\d+), (master|slave5|slave6)", r["frame.comment"])
            check(found, f"comment {r['frame.comment']!r}")
            packets.append((int(found.group(1)), int(found.group(2)), found.group(3), r))
        for i, (start, end, who, r) in enumerate(packets):
            n = {"0x10": 6, "0xe5": 1}.get(r["profibus.sd"]) or int(r["profibus.le"] or -99) + 6
            check(end - start == n * 11 * T, f"{n} characters from {start} to {end}: {r}")
            if who != "master":
                # An answer: its own address as SA (SC has none), MinTSDR after the request.
                check(r["profibus.sd"] == "0xe5" or r["profibus.sa"] == who[-1], f"{who}: {r}")
                p_start, p_end, p_who, p = packets[i - 1]
                check(p_who == "master" and start == p_end + 11 * T and
                      (r["profibus.sd"] == "0xe5" or p["profibus.da"] == who[-1]),
                      f"answer at {start} to {p}, request ended at {p_end}")
            elif i > 0:
                check(start >= packets[i - 1][1] + 33 * T, f"request at {start} within TSYN")
        answers = {(p[2], p[3]["profibus.service"], p[3]["profibus.du"]) for p in packets}
        for want in (("slave5", "FDL_Status response", ""), ("slave6", "FDL_Status response", ""),
                     ("slave5", "Data_Exchange response", "51"),
                     ("slave6", "Data_Exchange response", "11223344")):
            check(want in answers, f"the capture lacks {want}")


def pty_two_do4():
    # DO4's input byte: the terminals read back in the high nibble, ModulOK in bit 0.
    lines, _, log = pty_run(["--slave", "5:DO4", "--slave", "7:DO4:spc3"], lambda path: run_master(
        path, ["--slave", "5:0x0D04:21,10:00,00,00,00:05,01",
               "--slave", "7:0x0D04:21,10:00,00,00,00:0A,01"]))
    for a, want in ((5, "05 01: inputs 51"), (7, "0A 01: inputs A1")):
        last = [x for x in lines if x.startswith(f"slave {a}: Data_Exchange ")][-1]
        check(last == f"slave {a}: Data_Exchange {want}", f"slave {a}: {last}")
    log_has(log, "PORT  slave5   DO4 outputs = 0x05", "PORT  slave7   DO4 outputs = 0x0A")


def one_slave_log_line():
    """Log line 1 of a segment of one: `1 slave:` (it said `1 slaves:`)."""
    with tempfile.TemporaryDirectory() as tmp:
        b = blt.TcpBridge(tmp, "--slave", "5:responder", "--pacing", "free")
        try:
            b.stop()
            line = b.log_lines()[0]
            check(line.startswith("dpc31 bridge: pacing free, baud 19200, 1 slave: slave5 (profile "
                                  "dpc31, irq-controller external, firmware responder), slot "),
                  f"log line 1: {line}")
        finally:
            b.kill()
        # A plug-in beside the built-in firmware of its name: its path tells them apart (audit
        # s30, finding 10: both were `firmware CNT2`).
        cnt2 = bt.plugin("cnt2")
        own = os.path.join(tmp, "plugin")  # a log of its own: the first one's is read as ready
        os.mkdir(own)
        b = blt.TcpBridge(own, "--slave", f"5:{cnt2}", "--slave", "6:CNT2", "--pacing", "free")
        try:
            b.stop()
            line = b.log_lines()[0]
            check("2 slaves: slave5 (profile dpc31, irq-controller external, firmware CNT2 "
                  f"({cnt2})), slave6 (profile dpc31, irq-controller external, firmware CNT2), "
                  "slot " in line,
                  f"log line 1: {line}")
        finally:
            b.kill()


def bad_slave_arguments():
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "log")
        cases = [
            (["--slave", "5"], "must be ADDR:FIRMWARE[:PROFILE[:VARIANT]]"),
            (["--slave", "x:responder"], "must be a station address 0..125"),
            (["--slave", "126:responder"], "must be a station address 0..125"),
            (["--slave", "5:DO5"], "unknown firmware 'DO5'"),
            (["--slave", "5:responder:spc4"], "unknown profile 'spc4'"),
            (["--slave", "5:responder:spc3:b"], "the SPC3 has no variant"),
            # VARIANT in the field's words, not --variant's or --irq-controller's
            (["--slave", "5:responder:vpc3plus:x"],
             "--slave '5:responder:vpc3plus:x': VARIANT 'x' of vpc3plus must be b, c or s"),
            (["--slave", "5:responder:dpc31:b"], "--slave '5:responder:dpc31:b': VARIANT 'b' of "
             "dpc31 must be external or c31 (its interrupt controller)"),
            (["--slave", "5:responder:spc3:b:x"], "must be ADDR:FIRMWARE[:PROFILE[:VARIANT]]"),
            (["--slave", "5:DO4", "--slave", "5:responder"], "a second station at address 5"),
            (["--slave", "5:DO4", "--firmware", "DO4"], "--firmware is for the one slave"),
            (["--slave", "5:DO4", "--address", "5"], "--address is for the one slave"),
            (["--slave", "5:DO4", "--profile", "spc3"], "--profile is for the one slave"),
            (["--slave", "5:DO4", "--cpu", "80c32"], "--cpu is for the one slave"),
            # --ports is the 80C32's, refused beside --slave as without --cpu (the audit s28
            # aud2, finding 5: taken silently, even names given twice).
            (["--slave", "5:DO4", "--ports", "1a,1a"], "--ports is for the one slave"),
            (["--slave", "5:DO4", "--ports", "p1"], "--ports is for the one slave"),
            # One slot range at every door (a segment scenario's 37..16383; finding 10).
            (["--slave", "5:responder", "--slot", "36"],
             "--slot '36' must be 37..16383 bit times"),
            (["--slave", "5:responder", "--slot", "16384"],
             "--slot '16384' must be 37..16383 bit times"),
            # the built-in user side's options, checked as a segment scenario's `station`
            (["--slave", "5:DO4:spc3:user_wd=1"],
             "'user_wd' configures the built-in user side; a firmware configures itself"),
            (["--slave", "5:responder:dpc31:user_wd_value=5"],
             "user_wd_value= needs user_wd=1 on profile dpc31"),
            (["--slave", "5:responder:user_wd_value=5"],
             "user_wd_value= needs user_wd=1 on profile dpc31"),
            (["--slave", "5:responder:spc3:user_wd=2"], "bad value '2' for user_wd: 0 or 1"),
            (["--slave", "5:responder:spc3:user_wd_value=65536"],
             "user_wd_value '65536' must be 0..65535"),
            (["--slave", "5:responder:spc3:user_wd=1:b"],
             "must be ADDR:FIRMWARE[:PROFILE[:VARIANT]]"),
            (["--slave", "5:responder:spc3:bogus=1"], "unknown option 'bogus'"),
            # an option given twice, whatever its values, as a segment scenario's `station` line
            (["--slave", "5:responder:spc3:user_wd=1:user_wd=0"],
             "--slave '5:responder:spc3:user_wd=1:user_wd=0': option 'user_wd' given twice"),
            (["--slave", "5:responder:spc3:user_wd_value=7:user_wd=1:user_wd_value=7"],
             "option 'user_wd_value' given twice"),
            (["--slave", "5:DO4:user_wd=0:user_wd=0"], "option 'user_wd' given twice"),
        ]
        for args, want in cases:
            blt.expect_refused(["--tcp", "0", "--log", log] + args, want, log)


CASES = {
    "pty_two_slaves": pty_two_slaves,
    "tcp_two_slaves_pcap": tcp_two_slaves_pcap,
    "pty_two_do4": pty_two_do4,
    "bad_slave_arguments": bad_slave_arguments,
    "one_slave_log_line": one_slave_log_line,
}


if __name__ == "__main__":
    sys.exit(blt.main(CASES))
