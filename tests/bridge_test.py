#!/usr/bin/env python3
"""End-to-end tests of `dpc31 bridge` (docs/bridge.md), run by CTest.

Starts the real binary as a child process, then plays a small DP master (class 1) of our own on
the pty the way an off-the-shelf master program does: it opens the symlink, sets raw 8E1 at the
bridge's baud rate with one tcsetattr, and writes and reads FDL telegram bytes. Every answer is
checked byte for byte. The master itself is tools/dp_master.py.

Usage: bridge_test.py DPC31_CLI CASE     (CASE: see CASES at the bottom)
Python 3 standard library only.
"""

import fcntl
import os
import select
import shlex
import signal
import struct
import subprocess
import sys
import tempfile
import termios
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
from dp_master import (SAP_SLAVE_DIAG, SAP_SET_PRM, SAP_CHK_CFG, SAP_MASTER, SC, SD1,  # noqa: E402
                       SD2, Fail, Master, check, frame_length, hexs, sd1, sd2)

CLI = None
# Wall-clock limits are multiplied by this; only the sanitizer build (CMakePresets.json, asan)
# sets it above 1 (docs/sanitizers.md).
SCALE = float(os.environ.get("DPC31_TIMEOUT_SCALE", "1"))
# The guard of every wait for what will come (an answer, a log line, the slave found in its baud
# search: --timeout, --search, --c1-timeout): a hang ends it, a loaded host does not (issue 35).
GUARD = 20 * SCALE
# A master that cannot see the log (tools/dp_master.py, a client at the events level) takes a
# request as lost after this answer timeout and looks for the slave again: a measurement, not a
# guard, and not scaled. In free pacing the bridge answers once it has run the exchange (tens of
# ms of chip time, less on the host); no answer means the slave went back to its baud search
# (chip time ran past Baud_Control, 160 ms, while a loaded host held the master back). This and
# the search must end well within the watchdogs of the slaves (DO4: 10 s; the DPC31's user
# watchdog about 5 s), which run on chip time, the wall clock between exchanges: with GUARD here
# BridgeSegment.pty_two_do4 failed 1 in 20 beside two CPU hogs (the other DO4 left
# Data_Exchange while the master waited 20 s).
LOST = 2.0
# A master with one slave (dpv1_over_bridge, profibus_rates_default_log) has no other slave's
# watchdog to keep within, and a slow build runs each exchange SCALE times as long on the host:
# its answer timeout is LOST x SCALE (Bridge.dpv1_plugin_read_write lost station 5 at 2 s in the
# ASan build at load 8). At most 4 s, within the tightest watchdog of such a slave: DO4 on the
# DPC31 (profibus_rates_default_log; dpc31 is the bridge's default profile) enables its
# DPS_User_Watchdog in Data_Exchange at 01FFh (firmware/dps/dps.c) and resets it at each DX_Out;
# "decremented every 10 msec" (DPC31 p.31), it makes the slave leave the master 511 x 10 ms =
# 5.11 s of chip time after the last exchange. So a request really lost is still found lost, and
# the master's search and the request sent again find the slave still in Data_Exchange
# (dpc31_request_lost_in_data_exchange).
LOST_ALONE = min(LOST * SCALE, 4.0)
MASTER = 2
SLAVE = 5


# --- what the slave answers (exact telegrams) ---

def status_ok():  # FDL_Status: OK, station type 0 (slave)
    return sd1(MASTER, SLAVE, 0x00)


def diag(du):  # Slave_Diag answer: DL from SAP 60 to SAP 62
    return sd2(MASTER, SLAVE, 0x08, du, dsap=SAP_MASTER, ssap=SAP_SLAVE_DIAG)


def dx_answer(code, inputs):  # Data_Exchange answer: DL (0x08) or DH (0x0A), no SAPs
    return sd2(MASTER, SLAVE, code, inputs)


def fate_tags(lines):
    """The fate of each request in a bridge log at the telegrams level (lines "CYCLE TAG STATION
    TEXT"), in order: "TxD" (its answer's line) or "NOTE" ("no answer within the slot time"); a
    late answer is none."""
    tags = []
    for line in lines[1:]:
        parts = line.split(maxsplit=3)
        if len(parts) < 4:
            continue
        if parts[1] == "TxD" and not parts[3].endswith("(late)"):
            tags.append("TxD")
        elif parts[1] == "NOTE" and parts[3] == "no answer within the slot time":
            tags.append("NOTE")
    return tags


class Bridge:
    """The bridge as a child process; its symlink in a temporary directory."""

    def __init__(self, tmp, *args, link="dp0", ignored=()):
        self.path = os.path.join(tmp, link)
        self.start(tmp, ["--pty", self.path], args,
                   lambda: os.path.islink(self.path) and os.path.exists(self.path),
                   "the bridge made no symlink", ignored)

    def start(self, tmp, line, args, ready, missing, ignored=()):
        """Runs the bridge on `line` (its --pty or --tcp option) with its log in `tmp`, and waits
        until `ready()` (or fails with `missing` after GUARD, or when the bridge exits).
        `ignored`: signals the bridge inherits ignored (as under nohup)."""
        self.log = os.path.join(tmp, "bridge.log")
        self.proc = subprocess.Popen([CLI, "bridge"] + line + ["--log", self.log] + list(args),
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     preexec_fn=lambda: [signal.signal(s, signal.SIG_IGN)
                                                         for s in ignored])
        deadline = time.monotonic() + GUARD
        while not ready():
            if self.proc.poll() is not None:
                raise Fail(f"bridge exited with {self.proc.returncode}: "
                           f"{self.proc.stderr.read()!r}")
            check(time.monotonic() < deadline, f"{missing} within {GUARD:g} s")
            time.sleep(0.01)

    def stop(self, sig=signal.SIGTERM):
        self.proc.send_signal(sig)
        try:
            _, err = self.proc.communicate(timeout=GUARD)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise Fail(f"the bridge did not stop on signal {sig}") from None
        check(self.proc.returncode == 0,
              f"bridge exit code {self.proc.returncode} on signal {sig}, stderr {err!r}")
        check(err == b"", f"bridge wrote to stderr: {err!r}")
        check(self.path is None or not os.path.lexists(self.path),
              "the symlink is still there after the bridge stopped")

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        if sys.exc_info()[0] is not None and os.path.exists(self.log):
            # A failing case shows the end of the bridge's log.
            print("--- bridge log (last 80 lines) ---", file=sys.stderr)
            for line in self.log_lines()[-80:]:
                print(line, file=sys.stderr)

    def cpu_ticks(self):
        """User + system CPU time of the bridge so far, in clock ticks."""
        with open(f"/proc/{self.proc.pid}/stat", encoding="utf-8") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])

    def log_lines(self):
        """The log so far; none before the bridge has made it (it may not have, beside a CPU hog,
        when the first client comes and goes)."""
        if not os.path.exists(self.log):
            return []
        with open(self.log, encoding="utf-8") as f:
            return f.read().splitlines()

    def fates(self, all_lines=False):
        """How many requests have met their fate so far (fate_tags); with `all_lines`, also the
        list of their tags."""
        tags = fate_tags(self.log_lines())
        return (len(tags), tags) if all_lines else len(tags)

    def wait_for_log(self, text, limit_s, count=1):
        """Until `count` lines of the log hold `text` (an event of the chip or the pty), at most
        `limit_s`: a test waits on the event, not on a wall time (issue 35)."""
        deadline = time.monotonic() + limit_s
        while sum(text in line for line in self.log_lines()) < count:
            check(time.monotonic() < deadline, f"the log has no '{text}' after {limit_s} s")
            time.sleep(0.01)

    def close_and_wait(self, m):
        """Closes the client `m` and waits until the bridge has reset the slave side, so that the
        next client's tcsetattr finds it reset (a fixed 50 ms was too short beside a CPU hog)."""
        before = sum("slave side reset" in line for line in self.log_lines())
        m.close()
        self.wait_for_log("slave side reset", GUARD, before + 1)


class PacedMaster(Master):
    """A master for a bridge at the telegrams log level that waits on each request's fate in the
    bridge's log (its answer, or "no answer within the slot time") instead of a wall-clock
    timeout, in either pacing. In free pacing a host slower than the chip's time (the 80C32 with
    --trace-cpu beside a CPU hog ran at 1/17 of real time) otherwise fills the bridge's queue with
    the FDL_Status requests of find_slave's retries faster than the chip works them off, and the
    first Slave_Diag was answered, but behind 230 stale FDL_Status exchanges, long after the
    master's 0.5 s (issue 35); an answer timeout that expires on a loaded host is a lost request
    by chance. `limit_s` (the answer's and find_slave's) only guards against a hang; `device`: a
    TcpBridge's URL."""

    def __init__(self, bridge, baud, limit_s=GUARD, slave=SLAVE, device=None):
        super().__init__(device or bridge.path, baud, limit_s, MASTER, slave, search=limit_s)
        self.bridge = bridge
        self.fates = bridge.fates()

    def transact(self, req, timeout=None, searching=False):
        self.flush_input()
        os.write(self.fd, req)
        self.fates += 1
        deadline = time.monotonic() + self.timeout
        while (fates := self.bridge.fates(all_lines=True))[0] < self.fates:
            check(time.monotonic() < deadline, f"no fate of {hexs(req)} in the log")
            time.sleep(0.005)
        if fates[1][self.fates - 1] != "TxD":
            return None
        buf = b""
        while True:
            # A late answer's tail (a request before) is not ours: bytes before a delimiter.
            buf = buf.lstrip(bytes(b for b in range(256) if b not in (SD1, SD2, SC)))
            n = frame_length(buf)
            if n is not None and len(buf) >= n:
                return buf[:n]
            left = deadline - time.monotonic()
            check(left > 0, f"the answer to {hexs(req)} is in the log but not on the pty")
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                buf += self.read()


def startup_do4(m, wd=(0x64, 0x0A)):
    """FDL_Status until answered, Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag until ready."""
    m.expect("FDL_Status", m.find_slave(), status_ok())
    # Not parameterised: Station_Not_Ready, Prm_Req, no master yet, ident 0D04.
    m.expect("first Slave_Diag", m.srd([], SAP_SLAVE_DIAG), diag([0x02, 0x05, 0x00, 0xFF, 0x0D,
                                                                  0x04]))
    parameterise_do4(m, wd, [])


def parameterise_do4(m, wd, ext):
    """Set_Prm, Chk_Cfg, Slave_Diag until ready. `ext`: the device-related diag block the
    firmware has set by now (none at power-on)."""
    # Lock_Req + WD_On, watchdog factors, MinTSDR 0, ident 0D04, group 0; user prm: Spec_User_Prm
    # 00, OSPMode 0 (retain), replacement 0, refresh monitor off.
    prm = [0x88, wd[0], wd[1], 0x00, 0x0D, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00]
    m.expect("Set_Prm", m.srd(prm, SAP_SET_PRM), bytes([SC]))
    m.expect("Chk_Cfg", m.srd([0x21, 0x10], SAP_CHK_CFG), bytes([SC]))
    ready = diag([0x00, 0x0C, 0x00, MASTER, 0x0D, 0x04] + ext)
    for _ in range(20):
        # Station_Not_Ready while the firmware is still checking Prm/Cfg, then ready (WD_On).
        a = m.expect("Slave_Diag after Chk_Cfg", m.srd([], SAP_SLAVE_DIAG), ready,
                     diag([0x02, 0x0C, 0x00, MASTER, 0x0D, 0x04] + ext))
        if a == ready:
            return
    raise Fail("the slave never became ready")


def exchange_do4(m, before=0x00):
    """Data_Exchange 05 01 (DO1+DO3, OSPValid) until the input byte reads 51h (terminals 0101,
    ModulOK); `before` is the input byte until the firmware has taken the outputs. A DH answer
    (the device diag changed: ModulOK) is followed by a Slave_Diag."""
    # The device-related diag block DO4 keeps: header 02, OSP bit 0.
    ext_ok = diag([0x00, 0x0C, 0x00, MASTER, 0x0D, 0x04, 0x02, 0x00])
    for _ in range(20):
        a = m.expect("Data_Exchange 05 01", m.srd([0x05, 0x01]), dx_answer(0x08, [before]),
                     dx_answer(0x0A, [before]), dx_answer(0x0A, [0x51]), dx_answer(0x08, [0x51]))
        if a[6] == 0x0A:  # DH
            m.expect("Slave_Diag after DH", m.srd([], SAP_SLAVE_DIAG), ext_ok)
            continue
        if a == dx_answer(0x08, [0x51]):
            return
    raise Fail("the input byte never became 51h")


class LosingMaster(Master):
    """A master whose next request after `lose_next` is set goes out with its FCS broken: the
    slave drops it, the request is lost."""

    lose_next = False

    def srd_frame(self, du, dsap, ssap=SAP_MASTER):
        f = super().srd_frame(du, dsap, ssap)
        if self.lose_next:
            self.lose_next = False
            f = f[:-2] + bytes([f[-2] ^ 0xFF]) + f[-1:]
        return f


def dpc31_request_lost_in_data_exchange():
    """DO4 on the DPC31 in Data_Exchange (free pacing: chip time runs with the wall clock while
    the master waits): a Data_Exchange lost on the way is found lost after LOST_ALONE, the slave
    is searched and the request sent again, which finds the slave still in Data_Exchange, its
    DPS_User_Watchdog (5.11 s, LOST_ALONE's comment) not run out: the same answer, DL 51h."""
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", "DO4", "--baud", "19200", "--pacing", "free")
        try:
            m = LosingMaster(b.path, 19200, LOST_ALONE, search=GUARD)
            startup_do4(m)
            exchange_do4(m)
            m.lose_next = True
            m.expect("Data_Exchange sent again after a loss", m.srd([0x05, 0x01]),
                     dx_answer(0x08, [0x51]))
            check(m.lost == 1, f"{m.lost} requests lost, one was broken")
            b.close_and_wait(m)
            b.stop(signal.SIGTERM)
        finally:
            b.kill()


def check_order(lines):
    """Every line after the header starts with its cycle; the cycles never go back."""
    last = 0
    for line in lines[1:]:
        parts = line.split()
        check(parts[0].isdigit(), f"log line without a cycle: {line}")
        check(int(parts[0]) >= last, f"log line out of cycle order: {line}")
        last = int(parts[0])


def check_log(b, pacing, baud, firmware="DO4"):
    """`firmware`: as given; line 1 names a plug-in's path beside its name (audit s30, finding 10:
    a plug-in that keeps a built-in's name was not told from it)."""
    lines = b.log_lines()
    first = lines[0]
    named = "DO4" if firmware == "DO4" else f"DO4 ({firmware})"
    for want in (f"pacing {pacing}", f"baud {baud}",
                 f"profile dpc31, irq-controller external, firmware {named}, address 5",
                 "address 5, slot 100 bit times, log level telegrams",
                 f"pty {b.path} -> /dev/pts/"):
        check(want in first, f"log line 1 lacks '{want}': {first}")
    check("variant" not in first, f"log line 1 names a variant for the dpc31: {first}")
    text = "\n".join(lines)
    for want in ("RxD   master   10 05 02 49 50 16  | FDL_Status 2->5",
                 "TxD   slave5   10 02 05 00 07 16  | OK 5->2",
                 "| Set_Prm 2->5 SRD_high FCB 0 SAP 62->61 DU 88 64 0A 00 0D 04 00 00 00 00 00",
                 "TxD   slave5   E5  | SC", "| Chk_Cfg 2->5", "| Data_Exchange 2->5 SRD_high",
                 "DL 5->2 DU 51", "PORT  slave5   DO4 outputs = 0x05", "PORT  slave5   DO4 modul_ok = 0x01",
                 "CHIP  slave5   request MAC_Start",  # the DPC31 starts by request (docs/dpc31.md)
                 "client opened the pty", "client closed the pty", "STATE slave5   dp_state Wait_Cfg -> "
                 "Data_Exchange"):
        check(want in text, f"log lacks '{want}'")
    check_order(lines)


def plugin(name):
    """The built-in firmware NAME as a run-time plug-in: build/lib/libdpc31_fw_NAME.so."""
    return os.path.join(os.path.dirname(os.path.abspath(CLI)), "..", "lib",
                        f"libdpc31_fw_{name}.so")


def ihx_80c32(fw="do4"):
    """DO4 (or CNT2) for the 80C32 as the build makes it (firmware/CMakeLists.txt)."""
    return os.path.join(os.path.dirname(os.path.abspath(CLI)), "..", "firmware", "mcs51",
                        f"{fw}_80c32.ihx")


def do4_80c32_free():
    """DO4 built by SDCC on an 80C32 at 24 MHz beside an SPC3 (docs/cpu.md): the same start-up and
    Data_Exchange as the host-built DO4, and --trace-cpu writes every instruction with its cycle:
    the reset vector first, cycles rising, the INT0 routine entered by its map name."""
    ihx = ihx_80c32()
    with tempfile.TemporaryDirectory() as tmp:
        trace = os.path.join(tmp, "cpu.trace")
        b = Bridge(tmp, "--cpu", "80c32:24000000", "--firmware", ihx, "--profile", "spc3",
                   "--baud", "19200", "--pacing", "free", "--trace-cpu", trace,
                   "--log-level", "telegrams")
        try:
            m = PacedMaster(b, 19200, 3 * GUARD)
            startup_do4(m)
            exchange_do4(m)
            m.close()
            b.stop(signal.SIGTERM)
            check("on an 80C32 at 24000000 Hz" in b.log_lines()[0],
                  f"log line 1 lacks the 80C32: {b.log_lines()[0]}")
            # The names of --trace-cpu come from the map beside the image (docs/cpu.md).
            check(f"Hz, symbols from {ihx[:-4]}.map, " in b.log_lines()[0],
                  f"log line 1 lacks the map: {b.log_lines()[0]}")
            # The 80C32 has not run when line 1 is written: the address is the switch's offer.
            check(", address switch 5 (port 1), " in b.log_lines()[0],
                  f"log line 1 lacks the address switch: {b.log_lines()[0]}")
            with open(trace, encoding="utf-8") as f:
                lines = f.read().splitlines()
            check(lines and lines[0].split()[:3] == ["0", "0", "0000"],
                  f"the trace does not start at the reset vector in cycle 0: {lines[:1]}")
            last = -1
            for line in lines:
                chip, machine = (int(x) for x in line.split()[:2])
                check(machine > last, f"machine cycles do not rise: {line}")
                last = machine
            check(any(line.endswith(" int0_isr") for line in lines),
                  "the trace never enters int0_isr by its map name")
        finally:
            b.kill()


def ignored_signal_stays_ignored():
    """A signal ignored when the bridge starts stays ignored (`nohup dpc31 bridge ... &`, and a
    background job's SIGINT): the bridge replaced it with its stop handler and ended on the
    terminal's hangup (s31, after the serve audit's finding 2). After the ignored signal the
    bridge still answers a master, and only SIGTERM stops it, exit 0, said in its log."""
    for sig, name in ((signal.SIGHUP, "SIGHUP"), (signal.SIGINT, "SIGINT")):
        with tempfile.TemporaryDirectory() as tmp:
            b = Bridge(tmp, "--firmware", "DO4", "--baud", "19200", "--log-level", "telegrams",
                       ignored=(sig,))
            try:
                b.proc.send_signal(sig)
                m = PacedMaster(b, 19200)
                m.expect("FDL_Status", m.find_slave(), status_ok())
                m.close()
                check(b.proc.poll() is None, f"the bridge ended on the ignored {name}")
                b.stop(signal.SIGTERM)
                stops = [line for line in b.log_lines() if "stopping on" in line]
                check(len(stops) == 1 and stops[0].endswith("stopping on SIGTERM"),
                      f"after an ignored {name}: {stops}")
            finally:
                b.kill()


def do4_two_clients(pacing, baud=19200, firmware="DO4"):
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", firmware, "--baud", str(baud), "--pacing", pacing,
                   "--log-level", "telegrams")
        try:
            m = PacedMaster(b, baud)
            startup_do4(m)
            exchange_do4(m)
            # A second master program on the same pty, same speed: its 8E1 tcsetattr only works
            # because the bridge reset the slave side when the first one closed. The slave is
            # still parameterised by master 2 (watchdog 100 x 10 x 10 ms = 10 s), so FDL_Status
            # and one Slave_Diag find it ready and the outputs are still 05 01.
            b.close_and_wait(m)
            m = PacedMaster(b, baud)
            a = None
            for _ in range(20):
                a = m.fdl_status()
                if a is not None:
                    break
            m.expect("FDL_Status (second client)", a, status_ok())
            m.expect("Slave_Diag (second client)", m.srd([], SAP_SLAVE_DIAG),
                     diag([0x00, 0x0C, 0x00, MASTER, 0x0D, 0x04, 0x02, 0x00]))
            m.expect("Data_Exchange (second client)", m.srd([0x05, 0x01]),
                     dx_answer(0x08, [0x51]))
            # New outputs: DO2+DO4 -> input byte A1h.
            m.expect("Data_Exchange 0A 01", m.srd([0x0A, 0x01]), dx_answer(0x08, [0x51]))
            m.expect("Data_Exchange 0A 01 again", m.srd([0x0A, 0x01]), dx_answer(0x08, [0xA1]))
            m.close()
            b.stop(signal.SIGTERM)
            check_log(b, pacing, baud, firmware)
        finally:
            b.kill()


def do4_reparameterise_after_watchdog():
    """Free pacing, watchdog 10 x 10 x 10 ms: the second client comes after it expired and must
    parameterise the slave again (Prm_Req in the first Slave_Diag), then reaches Data_Exchange.
    Chip time follows the wall clock between exchanges, so the watchdogs are long enough for a
    loaded test machine (1 s while parameterised for the first time, 10 s after)."""
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", "DO4", "--pacing", "free", "--log-level", "telegrams")
        try:
            m = PacedMaster(b, 19200)
            startup_do4(m, wd=(0x0A, 0x0A))
            exchange_do4(m)
            m.close()
            # The DP watchdog (1 s of chip time) expires while no client is there: waited for in
            # the log, not for a wall time (chip time falls behind the wall clock on a loaded
            # machine; issue 35).
            b.wait_for_log("DP watchdog expired", GUARD)
            m = PacedMaster(b, 19200)
            # Baud_Control expired too (the chip searches the rate again): FDL_Status until
            # answered.
            m.expect("FDL_Status", m.find_slave(), status_ok())
            # Wait_Prm again (Prm_Req), outputs kept by the OSP model (retain), diag block OSP.
            m.expect("Slave_Diag after the watchdog", m.srd([], SAP_SLAVE_DIAG),
                     diag([0x02, 0x05, 0x00, 0xFF, 0x0D, 0x04, 0x02, 0x01]))
            # Parameterise again; until the outputs are valid again the module is in OSP with
            # the retained outputs 0101 (input byte 50h).
            parameterise_do4(m, (0x64, 0x0A), [0x02, 0x01])
            exchange_do4(m, before=0x50)
            m.close()
            b.stop(signal.SIGINT)
            text = "\n".join(b.log_lines())
            check("DP watchdog expired" in text, "log lacks the watchdog expiry")
        finally:
            b.kill()


def cnt2_logmsg(firmware="CNT2", board=("--profile", "vpc3plus"), module="CNT2",
                first="profile vpc3plus, variant c, firmware CNT2, address 9"):
    """CNT2 at 500 kbaud, free pacing: CNT1_LOGMSG and PWM1_LOGMSG (outputs 81 00 81 00 00 00)
    set LOGMSG_ACK (bit 7 of counter 1's status byte 2 and PWM 1's byte 6) and the firmware's
    hold1 and pwm_hold1 ports. `board`: the options that put the firmware on its board, `module`
    the log's name of who wrote the ports, `first` part of log line 1."""
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", firmware, "--baud", "500000", "--pacing", "free",
                   *board, "--address", "9", "--log-level", "telegrams")
        global SLAVE
        SLAVE = 9
        try:
            m = PacedMaster(b, 500000, slave=SLAVE)
            m.expect("FDL_Status", m.find_slave(), status_ok())
            m.expect("Slave_Diag", m.srd([], SAP_SLAVE_DIAG),
                     diag([0x02, 0x05, 0x00, 0xFF, 0x0C, 0x02]))
            prm = [0x88, 0x64, 0x0A, 0x00, 0x0C, 0x02, 0x00, 0x00]
            m.expect("Set_Prm", m.srd(prm, SAP_SET_PRM), bytes([SC]))
            m.expect("Chk_Cfg", m.srd([0x25, 0x17], SAP_CHK_CFG), bytes([SC]))
            ready = diag([0x00, 0x0C, 0x00, MASTER, 0x0C, 0x02])
            for _ in range(20):
                a = m.expect("Slave_Diag", m.srd([], SAP_SLAVE_DIAG), ready,
                             diag([0x02, 0x0C, 0x00, MASTER, 0x0C, 0x02]))
                if a == ready:
                    break
            check(a == ready, "CNT2 never became ready")
            zero = dx_answer(0x08, [0] * 8)
            held = dx_answer(0x08, [0x00, 0x00, 0x80, 0x00, 0x00, 0x00, 0x80, 0x00])
            for _ in range(5):
                a = m.expect("Data_Exchange 81 00 81 00 00 00",
                             m.srd([0x81, 0x00, 0x81, 0x00, 0x00, 0x00]), zero, held)
                if a == held:
                    break
            check(a == held, "LOGMSG_ACK never came")
            m.close()
            b.stop(signal.SIGHUP)
            text = "\n".join(b.log_lines())
            check(f"PORT  slave9   {module} hold1 = 0x01" in text, "log lacks the hold1 port write")
            check(f"PORT  slave9   {module} pwm_hold1 = 0x01" in text,
                  "log lacks the pwm_hold1 port write")
            check(first in b.log_lines()[0],
                  f"log line 1 lacks the profile, variant or firmware: {b.log_lines()[0]}")
        finally:
            SLAVE = 5
            b.kill()


def cnt2_80c32_free():
    """CNT2 built by SDCC on an 80C32 at 24 MHz beside an SPC3 (docs/cpu.md, "CNT2 on the
    80C32"), its latch bytes named by --ports as the scenario's ports= names them: the same
    LOGMSG hold as the host-built CNT2, the port writes logged by the 80C32 under CNT2's names."""
    cnt2_logmsg(ihx_80c32("cnt2"),
                ("--cpu", "80c32", "--profile", "spc3",
                 "--ports", "hold1,hold2,pwm_hold1,pwm_hold2,pwm1,pwm2"),
                "80C32", "profile spc3, ")


def bad_arguments():
    with tempfile.TemporaryDirectory() as tmp:
        regular = os.path.join(tmp, "file")
        with open(regular, "w", encoding="utf-8") as f:
            f.write("keep me\n")
        link = os.path.join(tmp, "dp0")
        cases = [
            ["bridge", "--firmware", "DO4"],                               # no --pty
            ["bridge", "--pty", link],                                     # no --firmware
            ["bridge", "--pty", link, "--firmware", "DO5"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--baud", "12345"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--baud", "fast"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--profile", "spc4"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--address", "126"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--pacing", "slow"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--slot", "0"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--colour"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--log-level", "loud"],
            ["bridge", "--pty", link, "--firmware", "DO4", "extra"],
            ["bridge", "--pty", regular, "--firmware", "DO4"],             # a regular file
            ["bridge", "--pty", os.path.join(tmp, "no", "dir"), "--firmware", "DO4"],
            ["bridge", "--pty", link, "--firmware", "DO4", "--log", os.path.join(tmp, "no", "x")],
            # The 80C32: a bad --cpu, a broken or missing image, --trace-cpu without --cpu or
            # into a directory that does not exist.
            ["bridge", "--pty", link, "--cpu", "8051", "--firmware", regular],
            ["bridge", "--pty", link, "--cpu", "80c32:99000000", "--firmware", regular],
            ["bridge", "--pty", link, "--cpu", "80c32", "--firmware", regular],  # not Intel HEX
            ["bridge", "--pty", link, "--cpu", "80c32", "--firmware", os.path.join(tmp, "none")],
            ["bridge", "--pty", link, "--firmware", "DO4", "--trace-cpu", os.path.join(tmp, "t")],
            ["bridge", "--pty", link, "--firmware", "DO4", "--ports", "outputs"],
            ["bridge", "--pty", link, "--cpu", "80c32", "--firmware", ihx_80c32(),
             "--ports", "outputs,,modul_ok"],
            ["bridge", "--pty", link, "--cpu", "80c32", "--firmware", ihx_80c32(),
             "--trace-cpu", os.path.join(tmp, "no", "t")],
        ]
        for args in cases:
            p = subprocess.run([CLI] + args, capture_output=True, timeout=GUARD, check=False)
            check(p.returncode == 2, f"{args}: exit code {p.returncode}, expected 2")
            err = p.stderr.decode()
            check(err.count("\n") == 1 and err.endswith("\n"),
                  f"{args}: stderr is not one line: {err!r}")
            check(not os.path.lexists(link), f"{args}: left a symlink behind")
        with open(regular, encoding="utf-8") as f:
            check(f.read() == "keep me\n", "the regular file was changed")


def stale_symlink_replaced():
    """A stale symlink is replaced; a client that only configures the pty, one at another speed;
    no busy loop while no client is connected."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "dp0")
        os.symlink("/dev/pts/nonexistent-stale", path)
        b = Bridge(tmp, "--firmware", "DO4", "--pacing", "free", "--log-level", "telegrams")
        try:
            check(os.readlink(path).startswith("/dev/pts/") and os.path.exists(path),
                  "the stale symlink was not replaced")
            # A client that only opens, configures and closes: the next one still gets a
            # working tcsetattr at the same speed.
            b.close_and_wait(Master(b.path, 19200, GUARD))
            m = PacedMaster(b, 19200)
            m.expect("FDL_Status", m.find_slave(), status_ok())
            # A client at another speed: the pty carries no timing, the bytes go on the bus at
            # the bridge's rate, and the log says so.
            b.close_and_wait(m)
            m = PacedMaster(b, 9600)
            # Until answered: on a loaded host chip time can run past Baud_Control while no
            # client is there, and the slave searches the rate again (issue 35).
            m.expect("FDL_Status at 9600 on the pty", m.find_slave(), status_ok())
            m.close()
            # No client: the master fd reports hang-up all the time; the bridge must not spin.
            before = b.cpu_ticks()
            time.sleep(1.0)
            used = b.cpu_ticks() - before
            check(used < 0.3 * os.sysconf("SC_CLK_TCK"),
                  f"the bridge used {used} clock ticks of CPU in 1 s without a client")
            b.stop(signal.SIGINT)
            text = "\n".join(b.log_lines())
            check("the client set 9600 baud on the pty; the bridge carries its bytes at 19200 "
                  "baud" in text, "log lacks the speed note")
            check("stopping on SIGINT" in text, "log lacks the stop note")
        finally:
            b.kill()


def profibus_rates_default_log():
    """tools/dp_master.py at PROFIBUS rates termios has no constant for (45.45 and 187.5 kbaud:
    set with TCSETS2 and BOTHER) brings DO4 to Data_Exchange; the bridge reads the client's rate
    (no speed note when it matches; 12 Mbaud, named, when it does not: the bytes travel at the
    bridge's rate all the same). The default log level says state changes and faults only: no
    telegram lines, lines in cycle order. (Data_Exchange at 12 Mbaud through the pty works too:
    the master's FDL_Status every 3 ms lands in the chip's 20 ms window at 12 Mbaud; the search
    at all ten rates is BridgeBaudSearch.*, on the engine.)"""
    for baud in (45450, 187500):
        with tempfile.TemporaryDirectory() as tmp:
            b = Bridge(tmp, "--firmware", "DO4", "--baud", str(baud), "--pacing", "free")
            try:
                # The events level has no line per request to wait on (LOST_ALONE).
                m = Master(b.path, baud, LOST_ALONE, search=GUARD)
                startup_do4(m)
                exchange_do4(m)
                for _ in range(50):
                    m.expect("Data_Exchange", m.srd([0x05, 0x01]), dx_answer(0x08, [0x51]))
                b.close_and_wait(m)
                # Another client at another rate: the bridge says which.
                other = 12000000
                m = Master(b.path, other, LOST_ALONE, search=GUARD)
                m.expect(f"FDL_Status at {other} on the pty", m.find_slave(), status_ok())
                m.close()
                b.stop(signal.SIGTERM)
                lines = b.log_lines()
                check(f"baud {baud}," in lines[0] and "log level events" in lines[0],
                      f"log line 1: {lines[0]}")
                tags = [line.split()[1] for line in lines[1:]]
                check("RxD" not in tags and "TxD" not in tags,
                      "telegram lines at the events level")
                text = "\n".join(lines)
                # DO4 on the DPC31 started by MAC_Start (Table 5.1-3), its outputs fetched
                # with User_New_Dout: Data_Exchange with an outside master.
                for want in ("CHIP  slave5   request MAC_Start", "STATE slave5   dp_state Wait_Cfg -> Data_Exchange",
                             "PORT  slave5   DO4 outputs = 0x05", "client opened the pty",
                             f"the client set {other} baud on the pty; the bridge carries its "
                             f"bytes at {baud} baud"):
                    check(want in text, f"log lacks '{want}'")
                check(text.count("the client set") == 1, "a speed note for the matching client")
                check(text.count("PORT  slave5   DO4 outputs = 0x05") == 1,
                      "PORT logged without a change")
                check(len(lines) < 40, f"{len(lines)} log lines at the events level")
                check_order(lines)
            finally:
                b.kill()
    # The master program offers exactly the ten rates.
    p = subprocess.run([sys.executable, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                     "..", "tools", "dp_master.py"),
                        "/nonexistent", "--baud", "38400", "--ident", "0x0D04", "--cfg", "21,10"],
                       capture_output=True, text=True, check=False)
    check(p.returncode == 2 and "invalid choice: 38400 (choose from 9600, 19200, 45450, 93750, "
          "187500, 500000, 1500000, 3000000, 6000000, 12000000)" in p.stderr,
          f"dp_master.py --baud 38400: exit {p.returncode}, {p.stderr!r}")


def answer_dropped_without_client():
    """A client that leaves after its request went on the line, before the answer: the answer is
    dropped, and the log says so with the cycle at which it was dropped (between the client's
    leaving and the next one's coming), not when the next client comes. Realtime, 9600 baud,
    telegrams level. Each attempt waits on events, not on wall time (issue 35): the Slave_Diag's
    RxD line in the log (the request is on the line: 9 characters, 10.3 ms, then at least TSDR
    before the answer), then the bridge is stopped (SIGSTOP) and the test looks: no answer byte
    on the pty and no TxD line yet, so the client closes while the bridge cannot run, and the
    bridge, continued, finds it gone. An attempt is lost only when the test reacted to the RxD
    line later than the answer came (beside a CPU hog it may): the next client tries again."""
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", "DO4", "--baud", "9600", "--log-level", "telegrams")
        try:
            for attempt in range(20):
                m = PacedMaster(b, 9600)
                m.expect("FDL_Status", m.find_slave(), status_ok())
                req = m.srd_frame([], SAP_SLAVE_DIAG)
                on_line = f"RxD   master   {hexs(req)}  |"
                before = sum(on_line in line for line in b.log_lines())
                os.write(m.fd, req)
                b.wait_for_log(on_line, GUARD, before + 1)
                b.proc.send_signal(signal.SIGSTOP)
                lines = b.log_lines()
                at = max(i for i, line in enumerate(lines) if on_line in line)
                answered = any(" TxD " in line for line in lines[at:])
                waiting = fcntl.ioctl(m.fd, termios.FIONREAD, struct.pack("i", 0))
                resets = sum("slave side reset" in line for line in lines)
                drops = sum("no client:" in line for line in lines)
                m.close()
                b.proc.send_signal(signal.SIGCONT)
                # The next client's tcsetattr needs the slave side reset (close_and_wait), and
                # comes after the Slave_Diag's fate (its answer, or none), so that no tail of it
                # reaches the next client.
                b.wait_for_log("slave side reset", GUARD, resets + 1)
                deadline = time.monotonic() + GUARD
                k = len(fate_tags(lines[:at]))
                while (fates := b.fates(all_lines=True))[0] <= k:
                    check(time.monotonic() < deadline, f"the Slave_Diag met no fate in {GUARD:g} s")
                    time.sleep(0.01)
                # No answer at all: Baud_Control expired after find_slave (a loaded host).
                if fates[1][k] == "TxD" and not answered and struct.unpack("i", waiting)[0] == 0:
                    # At least the answer's tail is dropped (it takes 19.5 ms of chip time, the
                    # bridge's first turn after SIGCONT 5 ms at most); all 17 bytes unless that
                    # turn wrote its first characters to the closed pty.
                    b.wait_for_log("no client:", GUARD, drops + 1)
                    if any("no client: 17 answer bytes dropped" in line for line in b.log_lines()):
                        break
                print(f"answer_dropped_without_client: attempt {attempt} lost", file=sys.stderr)
            m = PacedMaster(b, 9600)
            m.expect("FDL_Status (next client)", m.find_slave(), status_ok())
            m.close()
            b.stop(signal.SIGTERM)
            lines = b.log_lines()
            check_order(lines)
            at = [i for i, line in enumerate(lines) if "no client: 17 answer bytes dropped" in line]
            check(len(at) == 1, "no line 'no client: 17 answer bytes dropped' (or several)")
            before = [line for line in lines[:at[0]] if "NOTE  bridge   client" in line]
            after = [line for line in lines[at[0]:] if "NOTE  bridge   client" in line]
            check(before and "client closed the pty" in before[-1],
                  f"the drop is not after the client left: {before[-1:]}")
            check(after and "client opened the pty" in after[0],
                  f"the drop is not before the next client came: {after[:1]}")
        finally:
            b.kill()


SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def doc_commands(bridge_line):
    """docs/bridge.md's bridge command that begins with `bridge_line` and the tools/dp_master.py
    command after it, each as its words: the bridge's arguments after its line option (`--pty
    PATH`, `--tcp PORT`; the `&` left out), the master's whole command line."""
    with open(os.path.join(SOURCE, "docs", "bridge.md"), encoding="utf-8") as f:
        lines = f.read().splitlines()
    at = lines.index(next(line for line in lines
                          if line.startswith(bridge_line) and line.endswith(" &")))
    bridge = shlex.split(lines[at])
    master = next(line for line in lines[at:] if line.startswith("python3 tools/dp_master.py"))
    return bridge[4:-1], shlex.split(master)


def run_doc_master(master, device, doc_device):
    """The documented master command, run from the source tree with `device` for the doc's
    `doc_device` (the only word changed): it reaches Data_Exchange with DO4 and sends zeros,
    the outputs its Cfg 21 10 gives (it sent an SD2 with LE 3 that the chip counts as bad_le,
    exit 1; the audit of 2026-12-05)."""
    check(doc_device in master, f"the documented command has no {doc_device}: {master}")
    argv = [sys.executable if w == "python3" else device if w == doc_device else w for w in master]
    r = subprocess.run(argv, cwd=SOURCE, capture_output=True, text=True, timeout=3 * GUARD,
                       check=False)
    check(r.returncode == 0, f"{' '.join(master)}: exit {r.returncode}: {r.stdout} {r.stderr}")
    check("Data_Exchange 00 00: inputs 00" in r.stdout, r.stdout)


def doc_commands_pty():
    """docs/bridge.md, "With a master program": the bridge on a pty and tools/dp_master.py as
    written there (a temporary path for /tmp/dp0)."""
    args, master = doc_commands("build/bin/dpc31 bridge --pty /tmp/dp0 ")
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, *args)
        try:
            run_doc_master(master, b.path, "/tmp/dp0")
            b.stop()
        finally:
            b.kill()


def dpv1_over_bridge(firmware, master_args, body):
    """A VPC3+ with `firmware` behind the bridge (free pacing, 19200 baud); `body(run)` calls
    run(*dpv1_options) for each client: tools/dp_master.py with `master_args` and those options,
    to Data_Exchange and then its MSAC_C1 services; returns its CompletedProcess once the bridge
    has reset the slave side."""
    tool = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "dp_master.py")
    with tempfile.TemporaryDirectory() as tmp:
        b = Bridge(tmp, "--firmware", firmware, "--profile", "vpc3plus", "--baud", "19200",
                   "--pacing", "free")
        try:
            def run(*dpv1):
                before = sum("slave side reset" in line for line in b.log_lines())
                r = subprocess.run([sys.executable, tool, b.path] + master_args +
                                   ["--cycles", "2", "--timeout", str(LOST_ALONE), "--search",
                                    str(GUARD), "--c1-timeout", str(GUARD)] + list(dpv1),
                                   capture_output=True, text=True, timeout=3 * GUARD)
                b.wait_for_log("slave side reset", GUARD, before + 1)
                return r
            body(run)
            b.stop(signal.SIGTERM)
        finally:
            b.kill()


def expect_missing_index(r):
    """Index 7 does not exist: the negative response DE 80 B0 00, exit 1 with its error bytes."""
    check(r.returncode == 1, f"dp_master exit {r.returncode}: {r.stdout} {r.stderr}")
    check("negative response, Error_Decode 80, Error_Code_1 B0, Error_Code_2 00" in r.stderr,
          r.stderr)


def dpv1_plugin_read_write():
    """tools/dp_master.py's MSAC_C1 Read and Write (docs/dpv1.md, "The master's side") end to end:
    the program itself on the pty, against the test plug-in tests/dpv1_plugin.c behind the bridge
    (a VPC3+ whose firmware answers SAP 51 through the SAP list; its record at slot 0, index 1
    reads 11 22 33 44). One client reads and writes the record, the next reads the new value, a
    third reads index 7: the negative response, exit 1 with its error bytes."""
    def body(run):
        r = run("--dpv1-read", "00,01,04", "--dpv1-write", "00,01,A1,A2,A3,A4")
        check(r.returncode == 0, f"dp_master exit {r.returncode}: {r.stderr}")
        check("MSAC_C1 Read slot 0 index 1: 11 22 33 44 (" in r.stdout, r.stdout)
        check("MSAC_C1 Write slot 0 index 1: A1 A2 A3 A4 (" in r.stdout, r.stdout)
        r = run("--dpv1-read", "00,01,04")
        check(r.returncode == 0, f"dp_master exit {r.returncode}: {r.stderr}")
        check("MSAC_C1 Read slot 0 index 1: A1 A2 A3 A4 (" in r.stdout, r.stdout)
        expect_missing_index(run("--dpv1-read", "00,07,04"))
    dpv1_over_bridge(os.environ["DPC31_DPV1_PLUGIN"],
                     ["--ident", "0x0E01", "--cfg", "20,10", "--user-prm", "80,00,00",
                      "--outputs", "05"], body)


def do4_dpv1_read_write():
    """Issue 28's done-when: `dpc31 bridge --profile vpc3plus --firmware DO4` with
    tools/dp_master.py reads and writes DO4's OSP record over the pty (docs/firmware.md, "DO4
    with DPV1"; the bytes as traces/do4_dpv1_vpc3plus.scn derives them): user_prm C0,20,00
    (DPV1_Enable, Fail_Safe; Enable_Diagnostic_Alarm) then OSPMode 1, replacement value 9, refresh
    monitor off. Slot 0 index 1 reads 01 09 (the Set_Prm's values); a Write of 01 07 is answered
    with its header; index 7 is the negative response DE 80 B0 00. (The read-back of a written
    value within one session is checked by traces/do4_dpv1_vpc3plus.scn.)"""
    def body(run):
        r = run("--dpv1-read", "00,01,02", "--dpv1-write", "00,01,01,07")
        check(r.returncode == 0, f"dp_master exit {r.returncode}: {r.stdout} {r.stderr}")
        check("MSAC_C1 Read slot 0 index 1: 01 09 (" in r.stdout, r.stdout)
        check("MSAC_C1 Write slot 0 index 1: 01 07 (" in r.stdout, r.stdout)
        expect_missing_index(run("--dpv1-read", "00,07,02"))
    dpv1_over_bridge("DO4", ["--ident", "0x0D04", "--cfg", "21,10", "--user-prm",
                             "C0,20,00,01,09,00", "--outputs", "05,01"], body)

CASES = {
    "doc_commands_pty": doc_commands_pty,
    "dpv1_plugin_read_write": dpv1_plugin_read_write,
    "do4_dpv1_read_write": do4_dpv1_read_write,
    "do4_realtime_two_clients": lambda: do4_two_clients("realtime"),
    "do4_free_two_clients": lambda: do4_two_clients("free"),
    "do4_free_watchdog_then_reparameterise": do4_reparameterise_after_watchdog,
    "cnt2_free_logmsg": cnt2_logmsg,
    # The same through the plug-in path: the built-in firmwares as shared libraries.
    "do4_plugin_free_two_clients": lambda: do4_two_clients("free", firmware=plugin("do4")),
    "cnt2_plugin_free_logmsg": lambda: cnt2_logmsg(
        plugin("cnt2"), first=f"profile vpc3plus, variant c, firmware CNT2 ({plugin('cnt2')}), "
        "address 9"),
    "bad_arguments_exit_2": bad_arguments,
    "do4_80c32_free": do4_80c32_free,
    "cnt2_80c32_free": cnt2_80c32_free,
    "stale_symlink_and_silent_client": stale_symlink_replaced,
    "profibus_rates_default_log": profibus_rates_default_log,
    "dpc31_request_lost_in_data_exchange": dpc31_request_lost_in_data_exchange,
    "answer_dropped_without_client": answer_dropped_without_client,
    "ignored_signal_stays_ignored": ignored_signal_stays_ignored,
}


def run_case(cases, name):
    """Runs the case `name` of `cases`: exit code 0 when it holds, 1 with its failure."""
    try:
        cases[name]()
    except Fail as e:
        print(f"FAIL {name}: {e}", file=sys.stderr)
        return 1
    print(f"ok {name}")
    return 0


def main():
    global CLI
    if len(sys.argv) != 3 or sys.argv[2] not in CASES:
        print(f"usage: {sys.argv[0]} DPC31_CLI CASE ({', '.join(CASES)})", file=sys.stderr)
        return 2
    CLI = sys.argv[1]
    return run_case(CASES, sys.argv[2])


if __name__ == "__main__":
    sys.exit(main())
