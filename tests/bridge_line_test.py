#!/usr/bin/env python3
"""End-to-end tests of `dpc31 bridge`'s line side (docs/bridge.md, "Over TCP" and "The line as a
capture"), run by CTest.

tcp_two_clients_and_garbage: the bridge on a raw TCP port of the loopback (`--tcp 0`: the kernel
picks the port, the log's first line names it); tools/dp_master.py's Master on socket://HOST:PORT
reaches Data_Exchange with DO4; a second connection while the first is there is closed at once;
garbage is carried to the chip as on the pty (a broken telegram in the log, the next request
answered); the first client's disconnect, then a second client that exchanges data at once.
tools/dp_master.py as a second client while the first is connected: refused, exit 4, one line.

pcap_tshark_fields: the same start-up with --pcap; tshark with the shipped dissector
(lib/capture/profibus_dl.lua) decodes the capture, and every request and answer is checked field
by field against the telegrams' definitions (EN 50170 via tools/dp_master.py's encoders, and the
exact answers of tests/bridge_test.py), with the line timing of docs/timing.md: each telegram
11 bit times a character, an answer MinTSDR = 11 bit times after its request, every request at
least TSYN = 33 bit times after the telegram before; timestamps the start cycle in ns.

tcp_flood_and_sigterm: a client that writes random bytes without pause; chip time goes on (the
drop lines), and SIGTERM ends the bridge promptly while the flood goes on.

tcp_bad_arguments: bad options, --pty beside --tcp, a port in use: one line, exit 2, nothing made.

tcp_half_close: a client that half-closes after its FDL_Status (shutdown(SHUT_WR), `nc -N`) reads
the answer, then the bridge closes the connection.

tcp_split_writes_nagle: a client with Nagle on writes each request in two writes 1 ms apart:
every one is answered (the bridge ACKs at once).

Usage: bridge_line_test.py DPC31_CLI DISSECTOR CASE. Python 3 standard library and tshark.
Every wait is on an event (a log line, an answer), none on a wall time, except the bound
tcp_flood_and_sigterm checks.
"""

import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bridge_test as bt  # noqa: E402
from bridge_test import GUARD, SCALE, PacedMaster, dx_answer, exchange_do4, startup_do4  # noqa: E402
from dp_master import Fail, check  # noqa: E402

DISSECTOR = None
BAUD = 19200
T = 48_000_000 // BAUD  # cycles per bit time (docs/timing.md: 48 MHz)


class TcpBridge(bt.Bridge):
    """The bridge as a child process on --tcp 0; the port read from the log's first line."""

    def __init__(self, tmp, *args):  # pylint: disable=super-init-not-called
        self.path = None  # no symlink
        self.start(tmp, ["--tcp", "0"], args, self.port_named,
                   "the bridge named no TCP port")

    def port_named(self):
        lines = self.log_lines()
        found = re.search(r", tcp 127\.0\.0\.1:(\d+)$", lines[0]) if lines else None
        if found:
            self.url = f"socket://127.0.0.1:{found.group(1)}"
            self.port = int(found.group(1))
        return found is not None


def check_stations(lines):
    """docs/bridge.md, "The log": CYCLE TAG STATION TEXT; the master's requests, the bridge's
    notes, the slave's answers and events (slave5: --address 5)."""
    want = {"RxD": "master", "NOTE": "bridge", "LOG": "bridge", "TxD": "slave5", "STATE": "slave5",
            "CHIP": "slave5", "PORT": "slave5"}
    for line in lines[1:]:
        parts = line.split()
        check(len(parts) >= 3 and parts[1] in want and parts[2] == want[parts[1]],
              f"log line without its station: {line}")


def tcp_two_clients_and_garbage():
    with tempfile.TemporaryDirectory() as tmp:
        b = TcpBridge(tmp, "--firmware", "DO4", "--baud", str(BAUD), "--pacing", "free",
                      "--log-level", "telegrams")
        try:
            m = PacedMaster(b, BAUD, device=b.url)
            b.wait_for_log("client connected from 127.0.0.1:", GUARD)
            startup_do4(m)
            exchange_do4(m)
            # One client at a time: the second connection is accepted and closed at once.
            second = socket.create_connection(("127.0.0.1", b.port), timeout=GUARD)
            check(second.recv(16) == b"", "a second client was not closed")
            second.close()
            b.wait_for_log("refused a second client from 127.0.0.1:", GUARD)
            # tools/dp_master.py as the second client says it was refused, exit 4 (it said "the
            # device went away", exit 3: the bridge's stop), and the first client goes on.
            r = subprocess.run([sys.executable, os.path.join(bt.SOURCE, "tools", "dp_master.py"),
                                b.url, "--ident", "0x0D04", "--cfg", "21,10"],
                               capture_output=True, text=True, timeout=GUARD, check=False)
            check(r.returncode == 4 and r.stderr == f"dp_master: {b.url}: the bridge refused the "
                  "connection: another client is connected (one at a time)\n",
                  f"a second dp_master.py: exit {r.returncode}, {r.stderr!r}")
            # Garbage as on the pty: the bytes go on RxD as they came (a broken telegram, no
            # answer); the next request is answered.
            os.write(m.fd, bytes([0x00, 0x01, 0x02, 0xFF]))
            b.wait_for_log("| broken telegram", GUARD)
            m.expect("Data_Exchange after garbage", m.srd([0x05, 0x01]), dx_answer(0x08, [0x51]))
            # The first client goes; a second one exchanges data at once (DO4 is still in
            # Data_Exchange: its watchdog is 10 s).
            m.close()
            b.wait_for_log("closed the connection: queues flushed", GUARD)
            m2 = PacedMaster(b, BAUD, device=b.url)
            try:  # FCV 0: a new master's first request is taken whatever the FCB
                m2.expect("Data_Exchange, second client", m2.srd([0x05, 0x01]),
                          dx_answer(0x08, [0x51]))
            finally:
                m2.close()
            b.wait_for_log("closed the connection: queues flushed", GUARD, 2)
            b.stop()
            lines = b.log_lines()
            check(lines[0].endswith(f", tcp 127.0.0.1:{b.port}"), f"log line 1: {lines[0]}")
            check_stations(lines)
            bt.check_order(lines)
            text = "\n".join(lines)
            for want in ("RxD   master   10 05 02 49 50 16  | FDL_Status 2->5",
                         "TxD   slave5   E5  | SC",
                         "RxD   master   00 01 02 FF  | broken telegram",
                         "STATE slave5   dp_state Wait_Cfg -> Data_Exchange"):
                check(want in text, f"log lacks '{want}'")
            check(text.count("NOTE  bridge   client connected from 127.0.0.1:") == 2,
                  "two clients connected")
        finally:
            b.kill()


def tcp_flood_and_sigterm():
    """A client that writes random bytes without pause, as fast as the loopback takes them, to a
    bridge in realtime pacing: chip time goes on (the flood dropped in one line a second of chip
    time, at rising cycles), and SIGTERM ends the bridge within 5 s while the flood goes on. Before, the bridge read the socket until it was empty, which it never was: no chip time,
    no signal, until the client stopped (an outside report: 6.1 s after SIGTERM)."""
    stop_limit = 5 * SCALE  # a turn of the bridge's loop is milliseconds, also on a loaded host
    dropped = "bytes dropped in the last"
    with tempfile.TemporaryDirectory() as tmp:
        b = TcpBridge(tmp, "--firmware", "DO4")
        done = threading.Event()

        def flood():
            block = os.urandom(65536)
            try:
                with socket.create_connection(("127.0.0.1", b.port), timeout=GUARD) as s:
                    while not done.is_set():
                        s.sendall(block)
            except OSError:  # the bridge went, or held the flood back for GUARD
                pass

        writer = threading.Thread(target=flood, daemon=True)
        writer.start()
        try:
            b.wait_for_log(dropped, GUARD, 2)
            drops = [int(line.split()[0]) for line in b.log_lines() if dropped in line]
            check(drops[1] - drops[0] >= 48_000_000,
                  f"two drop lines within a second of chip time: cycles {drops[:2]}")
            check(writer.is_alive(), "the flood ended before SIGTERM")
            sent = time.monotonic()
            b.proc.send_signal(signal.SIGTERM)
            try:
                b.proc.wait(timeout=stop_limit)
            except subprocess.TimeoutExpired:
                raise Fail(f"the bridge still ran {stop_limit:g} s after SIGTERM under the "
                           "flood") from None
            took = time.monotonic() - sent
            err = b.proc.stderr.read()
            check(b.proc.returncode == 0 and err == b"",
                  f"exit {b.proc.returncode} after SIGTERM, stderr {err!r}")
            lines = b.log_lines()
            stops = [i for i, line in enumerate(lines) if "NOTE  bridge   stopping on SIGTERM" in line]
            # The stop may share the cycle of the last drop line: on a loaded host the signal can
            # arrive in the same turn of the loop, before chip time moves on (a CI run did).
            check(len(stops) == 1 and stops[0] > max(i for i, line in enumerate(lines)
                                                       if dropped in line)
                  and int(lines[stops[0]].split()[0]) >= drops[-1],
                  f"no stop line after the drop lines: {[lines[i] for i in stops]}")
            print(f"stopped {took:.2f} s after SIGTERM, {len(drops)} drop lines")
        finally:
            done.set()
            b.kill()
            writer.join(GUARD)


def tshark_fields(path, fields):
    """tshark with the shipped dissector, isolated from the user's configuration: one list of
    field values per packet."""
    home = os.path.join(os.path.dirname(path), "home")
    os.makedirs(home, exist_ok=True)
    cmd = ["tshark", "-n", "-X", f"lua_script:{DISSECTOR}", "-r", path, "-T", "fields",
           "-E", "separator=|"]
    for f in fields:
        cmd += ["-e", f]
    r = subprocess.run(cmd, capture_output=True, text=True, check=False,
                       env=dict(os.environ, HOME=home, XDG_CONFIG_HOME=home))
    check(r.returncode == 0 and "Lua" not in r.stderr, f"tshark: {r.returncode} {r.stderr}")
    # tshark 4.0 prints booleans as 1/0, later versions as True/False.
    out = r.stdout.replace("True", "1").replace("False", "0")
    return [line.split("|") for line in out.splitlines()]


def pcap_tshark_fields():
    with tempfile.TemporaryDirectory() as tmp:
        pcap = os.path.join(tmp, "line.pcapng")
        b = TcpBridge(tmp, "--firmware", "DO4", "--baud", str(BAUD), "--pacing", "free",
                      "--pcap", pcap, "--log-level", "telegrams")
        try:
            m = PacedMaster(b, BAUD, device=b.url)
            startup_do4(m)
            exchange_do4(m)
            m.close()
            b.wait_for_log("closed the connection", GUARD)
            check(not os.path.exists(pcap), "the capture exists before the bridge stopped")
            b.stop()
        finally:
            b.kill()
        fields = ["frame.comment", "frame.time_epoch", "frame.packet_flags_direction",
                  "profibus.le", "profibus.sd", "profibus.da", "profibus.sa", "profibus.fc", "profibus.dsap",
                  "profibus.ssap", "profibus.du", "profibus.fcs_ok", "profibus.service"]
        rows = [dict(zip(fields, r)) for r in tshark_fields(pcap, fields)]
        check(len(rows) >= 10, f"only {len(rows)} packets")
        # Who sent it, when (cycles in the comment, the timestamp in ns from them), and how long.
        packets = []
        for r in rows:
            found = re.fullmatch(r"cycles (\d+)-(\d+), (master|slave5)", r["frame.comment"])
            check(found, f"comment {r['frame.comment']!r}")
            start, end, who = int(found.group(1)), int(found.group(2)), found.group(3)
            ns = (start * 10**9 * 2 + 48_000_000) // (2 * 48_000_000)  # rounded, halves up
            check(r["frame.time_epoch"] == f"{ns // 10**9}.{ns % 10**9:09d}",
                  f"timestamp {r['frame.time_epoch']} of cycle {start}")
            check(r["frame.packet_flags_direction"] ==
                  ("0x00000001" if who == "master" else "0x00000002"), f"direction of {r}")
            packets.append((start, end, who, r))
        # The line timing: every telegram 11 bit times a character; each answer MinTSDR = 11 bit
        # times after its request; a request at least TSYN after the telegram before it.
        for i, (start, end, who, r) in enumerate(packets):
            # Characters: SD1 6, SC 1, SD2 LE + 6 (SD, LE, LEr, SD, FCS, ED).
            n = {"0x10": 6, "0xe5": 1}.get(r["profibus.sd"]) or int(r["profibus.le"] or -99) + 6
            check(end - start == n * 11 * T, f"{n} characters from {start} to {end}: {r}")
            check(r["profibus.fcs_ok"] in ("1", ""), f"bad FCS in {r}")
            if i == 0:
                continue
            p_start, p_end, p_who, _ = packets[i - 1]
            if who == "slave5":
                check(p_who == "master" and start == p_end + 11 * T,
                      f"answer at {start}, request ended at {p_end}")
            else:
                check(start >= p_end + 33 * T, f"request at {start} within TSYN of {p_end}")
        # Field by field: the first answered FDL_Status, Set_Prm and its SC, the last exchange.
        pick = ["profibus.sd", "profibus.da", "profibus.sa", "profibus.fc", "profibus.dsap",
                "profibus.ssap", "profibus.du", "profibus.service"]

        def row(p):
            return [p[3][k] for k in pick] + [p[2]]

        answered = next(i for i, p in enumerate(packets) if p[2] == "slave5")
        check(row(packets[answered - 1]) ==
              ["0x10", "5", "2", "0x49", "", "", "", "FDL_Status request", "master"],
              f"FDL_Status: {row(packets[answered - 1])}")
        check(row(packets[answered]) ==
              ["0x10", "2", "5", "0x00", "", "", "", "FDL_Status response", "slave5"],
              f"FDL_Status answer: {row(packets[answered])}")
        set_prm = [i for i, p in enumerate(packets) if p[3]["profibus.dsap"] == "61"]
        check(len(set_prm) == 1, f"{len(set_prm)} Set_Prm")
        i = set_prm[0]
        # Slave_Diag went first with FCB 1 (7D), so Set_Prm has FCB 0: 5D (EN 50170 FCB/FCV).
        check(row(packets[i]) == ["0x68", "5", "2", "0x5d", "61", "62", "88640a000d040000000000",
                                  "Set_Prm request", "master"], f"Set_Prm: {row(packets[i])}")
        check(row(packets[i + 1]) == ["0xe5", "", "", "", "", "", "", "Set_Prm response",
                                      "slave5"], f"Set_Prm answer: {row(packets[i + 1])}")
        last_req, last_ans = row(packets[-2]), row(packets[-1])
        check(last_req[:3] == ["0x68", "5", "2"] and last_req[3] in ("0x5d", "0x7d") and
              last_req[6:] == ["0501", "Data_Exchange request", "master"],
              f"last request {last_req}")
        check(last_ans == ["0x68", "2", "5", "0x08", "", "", "51", "Data_Exchange response",
                           "slave5"], f"last answer {last_ans}")


def expect_refused(args, want, *files):
    """`dpc31 bridge ARGS` refused: exit 2, one line on stderr holding `want`, none of `files`
    made (docs/bad-input.md)."""
    r = subprocess.run([bt.CLI, "bridge"] + args, capture_output=True, text=True,
                       timeout=GUARD, check=False)
    lines = r.stderr.splitlines()
    check(r.returncode == 2 and len(lines) == 1 and want in lines[0],
          f"{args}: exit {r.returncode}, stderr {r.stderr!r}")
    check(not any(os.path.exists(f) for f in files), f"{args}: a file made")


def tcp_bad_arguments():
    """One line on stderr, exit 2, nothing listening, no log or capture made (docs/bad-input.md)."""
    with tempfile.TemporaryDirectory() as tmp:
        busy = socket.socket()
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        log, pcap = os.path.join(tmp, "log"), os.path.join(tmp, "x.pcapng")
        cases = [
            (["--tcp", "0", "--pty", os.path.join(tmp, "dp0")], "--pty excludes --tcp"),
            ([], "one of --pty PATH"),
            (["--tcp", "0.0.0.0:0"], "not a loopback address"),
            (["--tcp", "127.0.0.1:70000"], "has no port 0..65535"),
            (["--tcp", "localhost:5000"], "is no numeric IPv4 or IPv6 address"),
            (["--tcp", "0", "--allow-remote", "--pty", "x"], "--pty excludes --tcp"),
            (["--pty", os.path.join(tmp, "dp0"), "--allow-remote"], "--allow-remote needs --tcp"),
            (["--tcp", str(busy.getsockname()[1])], "Address already in use"),
            (["--tcp", "0", "--pcap", log], "--pcap"),
            # '' was taken as not given: the bridge ran and wrote no capture, silently.
            (["--tcp", "0", "--pcap", ""],
             "dpc31 bridge: --pcap: an empty file name: nothing can be written there"),
            (["--tcp", "0", "--trace-cpu", ""], "--trace-cpu: an empty file name"),
        ]
        for args, want in cases:
            expect_refused(["--firmware", "DO4", "--log", log] + args, want, log, pcap)
        busy.close()


def tcp_bridge_with_the_rate(tmp):
    """DO4 on --tcp 0 in free pacing at the telegrams level, its baud search over: a searching
    master found it and closed its connection."""
    b = TcpBridge(tmp, "--firmware", "DO4", "--baud", str(BAUD), "--pacing", "free",
                  "--log-level", "telegrams")
    try:
        m = PacedMaster(b, BAUD, device=b.url)
        m.expect("FDL_Status", m.find_slave(), bt.status_ok())
        m.close()
        b.wait_for_log("closed the connection: queues flushed", GUARD)
    except BaseException:
        b.kill()
        raise
    return b


def tcp_half_close():
    """docs/bridge.md, "Over TCP": a client that closes its sending side after its request
    (shutdown(SHUT_WR), `nc -N`) still reads: the request goes on the bus, the answer comes back,
    then the bridge closes the connection (s29-sec, finding 3: the request was dropped)."""
    with tempfile.TemporaryDirectory() as tmp:
        b = tcp_bridge_with_the_rate(tmp)
        try:
            for k in range(1, 4):
                c = socket.create_connection(("127.0.0.1", b.port), timeout=GUARD)
                c.sendall(bt.sd1(bt.SLAVE, bt.MASTER, 0x49))  # FDL_Status: 10 05 02 49 50 16
                c.shutdown(socket.SHUT_WR)
                got = b""
                while chunk := c.recv(64):
                    got += chunk
                c.close()
                check(got == bt.status_ok(), f"half-close {k}: the answer was {got.hex(' ')}")
                b.wait_for_log("closed the connection: queues flushed", GUARD, 1 + k)
            # The searching master's close is an end of input too: 1 + 3.
            check(sum("closed its sending side: answering what it sent" in line
                      for line in b.log_lines()) == 4, "the half-closes are not in the log")
            check(not any("queued telegrams" in line for line in b.log_lines()),
                  "a request was dropped")
            b.stop()
        finally:
            b.kill()


def tcp_split_writes_nagle():
    """docs/bridge.md, "Over TCP": "a telegram may come in several segments"; only a pause of
    20 ms sends an incomplete one. A client with Nagle on (pyserial's socket:// sets no
    TCP_NODELAY) writing each FDL_Status as 1 byte, 1 ms, 5 bytes: every one is answered (audit
    s30 a-master, finding 3: the bridge's delayed ACK held the rest back for up to 40 ms, and the
    request went out as a truncated and a bad_sd telegram; 0-3 of 10 were answered)."""
    with tempfile.TemporaryDirectory() as tmp:
        b = tcp_bridge_with_the_rate(tmp)
        try:
            request = bt.sd1(bt.SLAVE, bt.MASTER, 0x49)  # 10 05 02 49 50 16
            c = socket.create_connection(("127.0.0.1", b.port), timeout=GUARD)
            try:
                for k in range(10):
                    c.sendall(request[:1])
                    time.sleep(0.001)
                    c.sendall(request[1:])
                    got = b""
                    try:
                        while len(got) < len(bt.status_ok()):
                            got += c.recv(64)
                    except TimeoutError:
                        raise Fail(f"request {k}: no answer within {GUARD:g} s") from None
                    check(got == bt.status_ok(), f"request {k}: the answer was {got.hex(' ')}")
            finally:
                c.close()
            check(not any("broken telegram" in line for line in b.log_lines()),
                  "a request was split on the bus")
            b.stop()
        finally:
            b.kill()


def doc_commands_tcp():
    """docs/bridge.md, "Over TCP": the bridge on a TCP port and tools/dp_master.py as written
    there (the port the kernel picks for 5000)."""
    args, master = bt.doc_commands("build/bin/dpc31 bridge --tcp 5000 ")
    with tempfile.TemporaryDirectory() as tmp:
        b = TcpBridge(tmp, *args)
        try:
            bt.run_doc_master(master, b.url, "socket://127.0.0.1:5000")
            b.stop()
        finally:
            b.kill()


CASES = {
    "doc_commands_tcp": doc_commands_tcp,
    "tcp_bad_arguments": tcp_bad_arguments,
    "tcp_two_clients_and_garbage": tcp_two_clients_and_garbage,
    "pcap_tshark_fields": pcap_tshark_fields,
    "tcp_flood_and_sigterm": tcp_flood_and_sigterm,
    "tcp_half_close": tcp_half_close,
    "tcp_split_writes_nagle": tcp_split_writes_nagle,
}


def main(cases=None):
    """DPC31_CLI DISSECTOR CASE: runs one of `cases` (this file's by default); the exit code."""
    global DISSECTOR
    cases = cases or CASES
    if len(sys.argv) != 4 or sys.argv[3] not in cases:
        print(f"usage: {sys.argv[0]} DPC31_CLI DISSECTOR CASE ({', '.join(cases)})",
              file=sys.stderr)
        return 2
    bt.CLI, DISSECTOR = sys.argv[1], sys.argv[2]
    return bt.run_case(cases, sys.argv[3])


if __name__ == "__main__":
    sys.exit(main())
