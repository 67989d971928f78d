#!/usr/bin/env python3
"""tools/dp_master.py's Master against scripted slow lines (issue 35), no bridge: a TCP peer on
the loopback (the Master's socket:// door) that answers the requests in order, as a bridge
slower than its bus does: one by one, each `WORK` seconds after the one before (the ASan build
beside two CPU hogs: `Bridge.dpv1_plugin_read_write` lost station 5 three times, 178 FDL_Status
requests of the search still queued at the end), or held and let go in bursts (the same test, the
ASan build beside two helpers' builds: the answer to the request lost the second time came in
one read with the second search's FDL_Status answers, "186 bytes too many").

Usage: dp_master_tool_test.py CASE. Exit 0 when the case holds, 1 with its failure."""

import os
import queue
import socket
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
from dp_master import SD1, SD2, Fail, Master, check, frame_length, hexs, sd1, sd2  # noqa: E402

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


CASES = {"slow_line_search_drained": slow_line_search_drained,
         "late_answer_before_the_search": late_answer_before_the_search,
         "foreign_saps_are_not_ours": foreign_saps_are_not_ours}


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
