#!/usr/bin/env python3
"""tools/dp_master.py's Master against scripted slow lines (issue 35), no bridge: a TCP peer on
the loopback (the Master's socket:// door) that answers the requests in order, as a bridge
slower than its bus does: one by one, each `WORK` seconds after the one before (the ASan build
beside two CPU hogs: `Bridge.dpv1_plugin_read_write` lost station 5 three times, 178 FDL_Status
requests of the search still queued at the end), or held and let go in bursts (the same test, the
ASan build beside two helpers' builds: the answer to the request lost the second time came in
one read with the second search's FDL_Status answers, "186 bytes too many").

Then its options and its errors (the audit of 2026-12-05): hex bytes, the outputs the Cfg gives,
the range checks, and the program's exits on bad arguments, on a device that is not a serial
device, a TCP port nobody listens on (the URL named, after --wait), when the device goes away
during the run (a pty whose other side closes, a TCP connection reset), and a failure with
several slaves (the station named), each one line on stderr.

Usage: dp_master_tool_test.py CASE. Exit 0 when the case holds, 1 with its failure."""

import argparse
import os
import queue
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "dp_master.py")
sys.path.insert(0, os.path.dirname(TOOL))
from dp_master import (IDENT, SAP_MASTER, SAP_SLAVE_DIAG, SC, SD1, SD2, STATION,  # noqa: E402
                       Fail, Master, Parser, byte_list, cfg_outputs, check, exchange, frame_length,
                       hexs, sd1, sd2, slave_spec, slaves_of)

MASTER, SLAVE = 2, 5
TIMEOUT = 1.0  # the master's answer timeout (--timeout)
STALL = 1.5    # the first Data_Exchange's answer comes this late: the request is taken as lost
WORK = 0.1     # then every request takes this long: 5 times the search's period at 19200 baud


class SlowLine:
    """Answers FDL_Status with FDL_Status OK (SD1, FC 00h) and a Data_Exchange (SRD, SD2) with
    the inputs [n], n counting the Data_Exchanges; strictly in the order written."""

    def __init__(self):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self.server.getsockname()[1]}"
        self.requests = queue.Queue()
        self.srd_fcs = []  # the FC of each Data_Exchange request, in order
        self.status_requests = 0
        self.conn = None
        threading.Thread(target=self.read, daemon=True).start()
        threading.Thread(target=self.work, daemon=True).start()

    def read(self):
        self.conn, _ = self.server.accept()
        buf = b""
        while chunk := self.conn.recv(512):
            buf += chunk
            while (n := frame_length(buf)) is not None and len(buf) >= n:
                self.requests.put(buf[:n])
                buf = buf[n:]
        self.requests.put(None)

    def work(self):
        while (req := self.requests.get()) is not None:
            if req[0] == SD1 and req[3] == 0x49:
                time.sleep(WORK)
                self.status_requests += 1
                self.conn.sendall(sd1(MASTER, SLAVE, 0x00))
            elif req[0] == SD2:
                self.srd_fcs.append(req[6])
                time.sleep(STALL if len(self.srd_fcs) == 1 else WORK)
                self.conn.sendall(sd2(MASTER, SLAVE, 0x08, [len(self.srd_fcs)]))


def data_exchange_answered(url, n, srd_fcs):
    """The Master's Data_Exchange on the line at `url` gets the n-th Data_Exchange's answer
    (inputs [n]) after n - 1 lost requests; `srd_fcs()` gives the FCs of the Data_Exchange
    requests the line read. EN 50170 FCB/FCV: the first SRD of a new master has FCV 0 (FC 4Dh);
    the first after FDL_Status restarts the sequence with FCB 1, FCV 1 (FC 7Dh)."""
    m = Master(url, 19200, TIMEOUT, MASTER, SLAVE, search=20.0)
    try:
        a = m.srd([0x05])
        want = sd2(MASTER, SLAVE, 0x08, [n])
        check(a == want, f"answer {hexs(a) if a else None}, expected Data_Exchange {n}'s "
              f"{hexs(want)}")
        check(m.lost == n - 1, f"{m.lost} lost requests, expected {n - 1}")
        fcs = srd_fcs()
        check(fcs == [0x4D] + [0x7D] * (n - 1), f"Data_Exchange FCs {hexs(fcs)}")
    finally:
        m.close()


def slow_line_search_drained():
    """A Data_Exchange unanswered within --timeout is lost: FDL_Status until answered, then the
    request once more (tools/dp_master.py, Master.srd). The search writes FDL_Status every 300 bit
    times + 3 ms (18.6 ms at 19200 baud) while the line works one off every 0.1 s, so the request
    sent again waits behind about (STALL - TIMEOUT) / 18.6 ms = 27 of them, 2.7 s, longer than
    --timeout. Each late FDL_Status answer shows the line working off what was written before:
    the wait starts anew, and the answer that comes is the second Data_Exchange's, with one lost
    request. Before the fix it was lost three times and srd gave None."""
    line = SlowLine()
    # The late answer to the first request ended the search; the second one's is ours.
    data_exchange_answered(line.url, 2, lambda: line.srd_fcs)
    check(line.status_requests >= 10, f"{line.status_requests} FDL_Status requests: the "
          "line was not slower than the search")


class HeldLine:
    """Answers every request in order, as SlowLine does, but holds the answers back and lets them
    go in bursts: `release(requests)` says after each request how many of the held answers go
    out now, in one write (None: all). A bridge that stalls on a loaded host and then catches
    up."""

    def __init__(self, release):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self.server.getsockname()[1]}"
        self.release = release
        self.requests = []  # (SD, FC) of each request, in order
        self.held = []
        self.srds = 0
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self):
        conn, _ = self.server.accept()
        buf = b""
        while chunk := conn.recv(512):
            buf += chunk
            while (n := frame_length(buf)) is not None and len(buf) >= n:
                req, buf = buf[:n], buf[n:]
                self.requests.append(req)
                if req[0] == SD2:
                    self.srds += 1
                    self.held.append(sd2(MASTER, SLAVE, 0x08, [self.srds]))
                else:
                    self.held.append(sd1(MASTER, SLAVE, 0x00))
                k = self.release(self.requests)
                k = len(self.held) if k is None else k
                if k:
                    conn.sendall(b"".join(self.held[:k]))
                    del self.held[:k]


def late_answer_before_the_search():
    """The answer to a request taken as lost comes after a second search began, in one burst with
    the second search's FDL_Status answers and the answer to the request sent last: it is not
    ours, since ours was written last, so its answer comes last (tools/dp_master.py, transact).
    The script, in order (the answers in the order of the requests, as a bridge gives them):
    Data_Exchange 1 held; the first search's second FDL_Status lets Data_Exchange 1's answer go
    (the search takes it: the slave answers); Data_Exchange 2 lets one FDL_Status answer go, then
    nothing for longer than --timeout (lost again); the second search's second FDL_Status lets one
    more FDL_Status answer go (found again); Data_Exchange 3 lets all go: the first search's last
    FDL_Status answers, Data_Exchange 2's answer, the second search's, Data_Exchange 3's. Ours is
    Data_Exchange 3's (inputs [3]); two lost; FCs 4D, then 7D after each FDL_Status (EN 50170).
    Before the fix the burst failed as an answer with bytes too many."""
    def release(reqs):
        srds = [i for i, r in enumerate(reqs) if r[0] == SD2]
        last = reqs[-1]
        if last[0] == SD2:
            return {1: 0, 2: 1, 3: None}[len(srds)]
        status_since = len(reqs) - 1 - srds[-1]  # FDL_Status requests since the last SRD
        return 1 if status_since == 2 else 0
    line = HeldLine(release)
    data_exchange_answered(line.url, 3, lambda: [r[6] for r in line.requests if r[0] == SD2])


def foreign_saps_are_not_ours():
    """A late answer whose SAPs are not the request's mirrored is not its answer (EN 50170: the
    answer's DSAP is the request's SSAP, its SSAP the request's DSAP), even when it comes alone:
    a Slave_Diag request (DSAP 60, SSAP 62) gets first a late Data_Exchange answer (no SAPs),
    then a late Get_Cfg answer (DSAP 62, SSAP 59), each in a write of its own, then its own
    answer (DSAP 62, SSAP 60)."""
    diag = sd2(MASTER, SLAVE, 0x08, [0x02, 0x05, 0x00, 0xFF, 0x0E, 0x01], dsap=62, ssap=60)
    late = [sd2(MASTER, SLAVE, 0x08, [7]), sd2(MASTER, SLAVE, 0x08, [0x21], dsap=62, ssap=59)]
    server = socket.create_server(("127.0.0.1", 0))

    def serve():
        conn, _ = server.accept()
        conn.recv(512)
        for t in late + [diag]:
            conn.sendall(t)
            time.sleep(0.1)
        conn.recv(512)  # until the master closes
    threading.Thread(target=serve, daemon=True).start()
    m = Master(f"socket://127.0.0.1:{server.getsockname()[1]}", 19200, TIMEOUT, MASTER, SLAVE,
               search=20.0)
    try:
        a = m.slave_diag()
        check(a == bytes([0x02, 0x05, 0x00, 0xFF, 0x0E, 0x01]), f"diagnosis {hexs(a)}")
        check(m.lost == 0, f"{m.lost} lost requests, expected 0")
    finally:
        m.close()


def answering_line(answer, requests=None):
    """A line on the loopback that answers each request `req`, in order, with `answer(req)` (and
    appends it to `requests`) until the master closes. Returns its server socket and thread."""
    server = socket.create_server(("127.0.0.1", 0))

    def serve():
        conn, _ = server.accept()
        buf = b""
        while chunk := conn.recv(512):
            buf += chunk
            while (n := frame_length(buf)) is not None and len(buf) >= n:
                req, buf = buf[:n], buf[n:]
                if requests is not None:
                    requests.append(req)
                conn.sendall(answer(req))
        conn.close()
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return server, thread


def msac_c1_refusals_named():
    """An SD1 answer to an MSAC_C1 request is named by its FC (EN 50170, include/dpc31/fdl.hpp:
    1 UE, 2 RR, 3 RS, 9 NR) with a reason that holds: RR is no resource (a Write longer than the
    SAP's Max_Length, docs/firmware.md's DO4 table; the buffer busy), RS the SAP not served. A
    line answers FDL_Status OK and the request with SD1 FC `code`. Before the fix RR was named
    "UE (the slave serves no SAP 51)" and UE was raw hex."""
    want = {0x01: "UE (user error", 0x02: "RR (no resource: the request is longer than the SAP's "
            "buffer, or its buffer is busy)", 0x03: "RS (the slave serves no SAP 51 now",
            0x09: "NR (no response data)"}
    for code, name in want.items():
        server, _ = answering_line(
            lambda req, code=code: sd1(MASTER, SLAVE, code if req[0] == SD2 else 0x00))
        m = Master(f"socket://127.0.0.1:{server.getsockname()[1]}", 19200, TIMEOUT, MASTER,
                   SLAVE, search=20.0)
        try:
            m.msac_c1([0x5E, 0x00, 0x01, 0x02], 1.0)
            raise Fail(f"FC {code:X}h: no failure")
        except Fail as e:
            check(str(e).startswith(f"MSAC_C1 5E 00 01 02: {name}"), f"FC {code:X}h: '{e}'")
        finally:
            m.close()
            server.close()


def refused(convert, text, want):
    """`convert(text)` is an argparse type error whose message holds `want`."""
    try:
        got = convert(text)
    except argparse.ArgumentTypeError as e:
        check(want in str(e), f"{text!r}: {e}")
        return
    raise Fail(f"{text!r} taken as {got!r}")


def hex_bytes_and_ranges():
    """byte_list: with commas every item is one byte of 1 or 2 hex digits, without commas pairs
    (the audit: '5,1' was one byte 51h, '1,2,3,4' two bytes 12h 34h); the station address and
    Ident_Number ranges; the output bytes a Cfg gives (EN 50170: general and special format)."""
    for text, want in (("5,1", [0x05, 0x01]), ("1,2,3,4", [1, 2, 3, 4]), ("21,10", [0x21, 0x10]),
                       ("2110", [0x21, 0x10]), ("a,Bc", [0x0A, 0xBC]), ("", [])):
        check(byte_list(text) == want, f"byte_list({text!r}) = {byte_list(text)}")
    for text, want in (("5,123", "'123' is not a byte"), ("5,,1", "'' is not a byte"),
                       ("21,", "'' is not a byte"), ("5,x", "'x' is not a byte"),
                       ("211", "an odd number of hex digits"), ("21 10", "not hex bytes")):
        refused(byte_list, text, want)
    check(STATION("0") == 0 and STATION("125") == 125 and IDENT("0xFFFF") == 0xFFFF, "ranges")
    for convert, text in ((STATION, "126"), (STATION, "300"), (STATION, "-1"), (STATION, "x"),
                          (IDENT, "0x1FFFF"), (IDENT, "-1"), (IDENT, "0xZZ")):
        refused(convert, text, f"'{text}': not a")
    # 21 10: 2 output bytes, 1 input; 63h: 4 output words; 00h an empty slot; 80h 01h: special,
    # an output length byte (2 bytes); C0h 41h 03h: special, output then input length byte (2
    # words out); 42h 05h AA BB: special, an input length byte, 2 bytes of manufacturer data.
    for cfg, outputs in (([0x21, 0x10], 2), ([0x63], 8), ([0x00], 0), ([0x10], 0),
                         ([0x80, 0x01], 2), ([0xC0, 0x41, 0x03], 4),
                         ([0x42, 0x05, 0xAA, 0xBB, 0x20], 1)):
        check(cfg_outputs(cfg) == outputs, f"Cfg {hexs(cfg)}: {cfg_outputs(cfg)} outputs")
    for cfg in ([0x80], [0xC0, 0x01], [0x41, 0x00], [0x0F]):
        try:
            cfg_outputs(cfg)
            raise Fail(f"Cfg {hexs(cfg)} sized")
        except ValueError:
            pass
    # No outputs: the Data_Exchange is an SD1 request (an SD2 has LE 4 at least: DA, SA, FC and
    # one byte; the chip counts LE 3 as bad_le).
    m = Master.__new__(Master)
    m.slave, m.address, m.fcb, m.fcv = SLAVE, MASTER, True, False
    for du, want in (([], sd1(SLAVE, MASTER, 0x4D)), ([0, 0], sd2(SLAVE, MASTER, 0x6D, [0, 0]))):
        got = m.srd_frame(du, None)
        check(got == want, f"Data_Exchange {hexs(du)}: {hexs(got)}, expected {hexs(want)}")


def outputs_from_the_cfg():
    """Each station's settings (slaves_of): without --outputs the Data_Exchange carries as many
    zeros as the Cfg gives output bytes (the audit: an empty one, an SD2 with LE 3, was never
    answered); --outputs of another length, a Cfg that cannot be sized without --outputs and a
    data unit over 244 bytes are refused with one line naming the station."""
    def stations(*argv):
        p = Parser()
        for name, kind in (("--slave", slave_spec), ("--ident", IDENT), ("--cfg", byte_list),
                           ("--user-prm", byte_list), ("--outputs", byte_list)):
            p.add_argument(name, type=kind, **({"action": "append"} if name == "--slave" else {}))
        args = p.parse_args(argv)
        args.user_prm = args.user_prm or []
        args.watchdog = [0x64, 0x0A]

        def error(message):
            raise Fail(message)
        return slaves_of(args, error)
    for argv, outputs in ((["--ident", "1", "--cfg", "21,10"], [[0, 0]]),
                          (["--ident", "1", "--cfg", "10"], [[]]),
                          (["--ident", "1", "--cfg", "80", "--outputs", "1,2,3"], [[1, 2, 3]]),
                          (["--ident", "1", "--cfg", "21,10", "--slave", "5",
                            "--slave", "6:2:13,23::1,2,3,4"], [[0, 0], [1, 2, 3, 4]])):
        got = [s.outputs for s in stations(*argv)]
        check(got == outputs, f"{argv}: outputs {got}")
    many = ",".join(["01"] * 300)
    for argv, want in (
            (["--ident", "1", "--cfg", "21,10", "--outputs", "5,1,2"],
             "station 5: 3 output bytes, its Chk_Cfg gives 2 (the slave would answer RS)"),
            (["--ident", "1", "--cfg", "80"], "station 5: Chk_Cfg: the special identifier 80 "
             "(byte 1) runs past the end; give its outputs (--outputs)"),
            (["--ident", "1", "--cfg", "7F" * 8],
             "station 5: a Data_Exchange of 256 bytes (at most 244)"),
            (["--ident", "1", "--cfg", many, "--outputs", "01"],
             "station 5: a Chk_Cfg of 300 bytes (at most 244)"),
            (["--ident", "1", "--cfg", "10", "--user-prm", many],
             "station 5: a Set_Prm of 307 bytes (at most 244)")):
        try:
            stations(*argv)
            raise Fail(f"{argv} taken")
        except Fail as e:
            check(str(e) == want, f"{argv}: {e}")


def zero_inputs_sc_and_sd1_dh():
    """A slave without inputs answers Data_Exchange with SC, or SD1 DH while a new diagnosis waits
    (docs/decisions.md: "with R_Len_Din_Buf = 0 the answer is SC (or SD1 DH)"): exchange() takes
    both as answers with no inputs, and DH is followed by a Slave_Diag. The line answers a
    scripted sequence in order. Before, it failed "Data_Exchange with station 5: got E5"."""
    diag = [0x08, 0x0C, 0x00, MASTER, 0x0C, 0x31]
    server = socket.create_server(("127.0.0.1", 0))
    requests = []

    def serve():
        answers = [bytes([SC]), sd1(MASTER, SLAVE, 0x0A),
                   sd2(MASTER, SLAVE, 0x08, diag, dsap=SAP_MASTER, ssap=SAP_SLAVE_DIAG),
                   bytes([SC])]
        conn, _ = server.accept()
        buf = b""
        while answers and (chunk := conn.recv(512)):
            buf += chunk
            while (n := frame_length(buf)) is not None and len(buf) >= n:
                requests.append(buf[:n])
                buf = buf[n:]
                conn.sendall(answers.pop(0))
        conn.close()
    line = threading.Thread(target=serve, daemon=True)
    line.start()
    m = Master(f"socket://127.0.0.1:{server.getsockname()[1]}", 19200, TIMEOUT, MASTER, SLAVE)
    said = []
    try:
        exchange(m, [argparse.Namespace(address=SLAVE, outputs=[0x05])], 3,
                 lambda s: said.append)
    finally:
        m.close()
        line.join(5)
    check(said == ["Data_Exchange 05: inputs -", "Slave_Diag (after DH): 08 0C 00 02 0C 31"],
          f"said {said}")
    # Data_Exchange (SD2, no SAPs), again, Slave_Diag (DSAP 60), Data_Exchange.
    saps = [r[7] if r[0] == SD2 and r[4] & 0x80 else None for r in requests]
    check(saps == [None, None, SAP_SLAVE_DIAG, None], f"requests {[hexs(r) for r in requests]}")


def run_tool(*args):
    """tools/dp_master.py with `args`: (exit code, stdout, stderr's lines)."""
    r = subprocess.run([sys.executable, TOOL] + list(args), capture_output=True, text=True,
                       timeout=60, check=False)
    return r.returncode, r.stdout, r.stderr.splitlines()


def exits(want_code, want, *args):
    """tools/dp_master.py with `args` exits `want_code` with one line on stderr holding `want`."""
    code, _, err = run_tool(*args)
    check(code == want_code and len(err) == 1 and want in err[0],
          f"dp_master.py {' '.join(args)}: exit {code}, stderr {err}")


DO4 = ["--ident", "0x0D04", "--cfg", "21,10"]


def bad_arguments_exit_2():
    """Usage errors, of each kind (an option's type, the stations' settings, a check after
    parsing): exit 2, one line on stderr (no usage lines, no traceback), before the device is
    opened. Each station's settings are checked in-process by outputs_from_the_cfg."""
    many = ",".join(["01"] * 300)
    for want, args in (
            ("--address: '300': not a station address 0..125", ["--address", "300"] + DO4),
            ("--ident: '0x1FFFF': not an Ident_Number 0..0xFFFF",
             ["--ident", "0x1FFFF", "--cfg", "21,10"]),
            ("--outputs: '5,123': '123' is not a byte", ["--outputs", "5,123"] + DO4),
            ("station 5: 300 output bytes, its Chk_Cfg gives 2", ["--outputs", many] + DO4),
            ("--dpv1-write: a DPV1 PDU of 245 bytes", ["--dpv1-write", many[:3 * 243 - 1]] + DO4),
            # Sent before (the audit of 2026-12-05, run 21): a WD_Fact of 0 in Set_Prm, an empty
            # Chk_Cfg, the master at a slave's address; a search without end, a wait below 0.
            ("--watchdog takes two bytes, each 01..FF", ["--watchdog", "0,0"] + DO4),
            # The ident given, the empty Chk_Cfg named (the audit s28 aud2, finding 11); each
            # missing one named alone.
            ("station 5: an empty Chk_Cfg configures no module", ["--ident", "0x0D04", "--cfg", ""]),
            ("station 5: no Ident_Number (--ident and --cfg", ["--cfg", "21,10"]),
            ("station 5: no Chk_Cfg (--ident and --cfg", ["--ident", "0x0D04"]),
            ("station 5: no Ident_Number or Chk_Cfg (--ident", []),
            ("station 5: the master's own --address", ["--address", "5", "--slave",
                                                       "5:0x0D04:21,10"]),
            ("--search takes a positive number of seconds", ["--search", "inf"] + DO4),
            ("--wait takes a number of seconds, 0 or more", ["--wait", "-3"] + DO4),
            # DPV1 values the scenario refuses were sent (the audit a11 of 2026-12-06, finding 9):
            # a Read of 0 or 241 bytes, slot 255, an option given twice (the last one won).
            ("--dpv1-read: length 0 out of range (1..240)", ["--dpv1-read", "0,1,0"] + DO4),
            ("--dpv1-read: length 241 out of range (1..240)", ["--dpv1-read", "0,1,F1"] + DO4),
            ("--dpv1-read: slot 255 out of range (0..254)", ["--dpv1-read", "FF,1,1"] + DO4),
            ("--dpv1-write: slot 255 out of range (0..254)", ["--dpv1-write", "FF,1,1"] + DO4),
            ("--dpv1-read given twice", ["--dpv1-read", "0,1,1", "--dpv1-read", "0,1,2"] + DO4),
            ("--c1-timeout given twice", ["--c1-timeout", "1", "--c1-timeout", "2"] + DO4)):
        exits(2, want, "/nonexistent", *args)
    # A port beyond 65535 was taken modulo 2^16 (99999: 34463).
    exits(2, "dp_master: socket://127.0.0.1:99999: not socket://HOST:PORT (PORT 1..65535)",
          "socket://127.0.0.1:99999", *DO4)


def tcp_refused_names_the_url():
    """Nobody on the port: the URL in the line, exit 2, after --wait (it was a fixed 10 s and
    `[Errno 111] Connection refused` alone)."""
    free = socket.create_server(("127.0.0.1", 0))
    url = f"socket://127.0.0.1:{free.getsockname()[1]}"
    free.close()
    start = time.monotonic()
    exits(2, f"dp_master: {url}: connection refused (waited 0.3 s)", url, "--wait", "0.3", *DO4)
    check(time.monotonic() - start < 5, f"--wait 0.3 took {time.monotonic() - start:.1f} s")


def failure_names_the_station():
    """With several --slave, the failure's line names its station, as its stdout lines do: a
    line that answers nothing."""
    server = socket.create_server(("127.0.0.1", 0))
    conns = []
    threading.Thread(target=lambda: conns.append(server.accept()), daemon=True).start()
    exits(1, "dp_master: slave 5: FDL_Status never answered",
          f"socket://127.0.0.1:{server.getsockname()[1]}", "--slave", "5:0x0D04:21,10",
          "--slave", "9:0x0C31:13,23", "--search", "0.5")
    server.close()


def a_locked_slave_is_left_alone():
    """A slave whose Slave_Diag names another master in Master_Add (byte 3) is locked by it: the
    tool leaves it alone, as a DP master does (EN 50170's Master_Lock; the built-in master's
    `startup: slave locked by master N ...`, docs/decisions.md): exit 1 naming the lock, and no
    Set_Prm (DSAP 61) on the line. Before, it sent Set_Prm and Chk_Cfg and failed with "the slave
    never became ready" after 20 more Slave_Diags."""
    # Station_Status_1 00h, _2 0Ch (bit 2 always 1, WD_On), _3 00h, Master_Add 3, Ident 0D04h.
    diag = sd2(MASTER, SLAVE, 0x08, [0x00, 0x0C, 0x00, 0x03, 0x0D, 0x04], dsap=SAP_MASTER,
               ssap=SAP_SLAVE_DIAG)
    requests = []
    server, line = answering_line(
        lambda req: sd1(MASTER, SLAVE, 0x00) if req[0] == SD1 else diag, requests)
    exits(1, "dp_master: locked by master 3 (its Slave_Diag's Master_Add): not parameterised",
          f"socket://127.0.0.1:{server.getsockname()[1]}", *DO4)
    server.close()
    line.join(5)
    dsaps = [r[7] for r in requests if r[0] == SD2 and r[4] & 0x80]
    check(dsaps == [SAP_SLAVE_DIAG], f"requests {[hexs(r) for r in requests]}")


def not_a_serial_device_exit_2():
    """A device that is no tty (/dev/null, a regular file): exit 2, one line (it was a
    termios.error traceback)."""
    with tempfile.TemporaryDirectory() as tmp:
        plain = os.path.join(tmp, "file")
        with open(plain, "w", encoding="utf-8"):
            pass
        for device in ("/dev/null", plain):
            exits(2, f"{device}: not a serial device (Inappropriate ioctl for device)", device,
                  *DO4)


def device_lost_pty():
    """The pty's other side closes during the run (the bridge stopped): exit 3, one line, no
    traceback (it was termios.error from tcflush)."""
    master, slave = os.openpty()  # the slave side held until the program has it open
    path = os.ttyname(slave)
    p = subprocess.Popen([sys.executable, TOOL, path, "--ident", "0x0D04", "--cfg", "21,10"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        os.read(master, 6)  # its first FDL_Status: it has the device open
        os.close(slave)
        os.close(master)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    lines = err.splitlines()
    check(p.returncode == 3 and len(lines) == 1 and "dp_master: the device went away" in lines[0],
          f"exit {p.returncode}, stderr {lines}")


def device_lost_tcp():
    """The TCP connection is reset during the run (the bridge killed), and in another run closed:
    exit 3, one line each (a reset was a ConnectionResetError traceback). The port closes with
    it, as the bridge's does: a port that still listens would be a bridge refusing the client
    (tests/bridge_line_test.py)."""
    for reset, want in ((True, "the device went away (Connection reset by peer)"),
                        (False, "the bridge closed the connection")):
        server = socket.create_server(("127.0.0.1", 0))

        held = []

        def serve(server=server, reset=reset, held=held):
            conn, _ = server.accept()
            conn.recv(6)  # its first FDL_Status
            server.close()
            if reset:
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                conn.close()
            else:  # the end of its bytes; a close would answer its next request with a reset
                conn.shutdown(socket.SHUT_WR)
                held.append(conn)
        threading.Thread(target=serve, daemon=True).start()
        exits(3, want, f"socket://127.0.0.1:{server.getsockname()[1]}", "--ident", "0x0D04",
              "--cfg", "21,10")
        for conn in held:
            conn.close()
        server.close()


CASES = {"slow_line_search_drained": slow_line_search_drained,
         "late_answer_before_the_search": late_answer_before_the_search,
         "foreign_saps_are_not_ours": foreign_saps_are_not_ours,
         "msac_c1_refusals_named": msac_c1_refusals_named,
         "hex_bytes_and_ranges": hex_bytes_and_ranges,
         "outputs_from_the_cfg": outputs_from_the_cfg,
         "zero_inputs_sc_and_sd1_dh": zero_inputs_sc_and_sd1_dh,
         "bad_arguments_exit_2": bad_arguments_exit_2,
         "not_a_serial_device_exit_2": not_a_serial_device_exit_2,
         "device_lost_pty": device_lost_pty,
         "device_lost_tcp": device_lost_tcp,
         "tcp_refused_names_the_url": tcp_refused_names_the_url,
         "failure_names_the_station": failure_names_the_station,
         "a_locked_slave_is_left_alone": a_locked_slave_is_left_alone}


def main():
    if len(sys.argv) != 2 or sys.argv[1] not in CASES:
        print(f"usage: {sys.argv[0]} CASE ({', '.join(CASES)})", file=sys.stderr)
        return 2
    try:
        CASES[sys.argv[1]]()
    except Fail as e:
        print(f"FAIL {sys.argv[1]}: {e}", file=sys.stderr)
        return 1
    print(f"ok {sys.argv[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
