#!/usr/bin/env python3
"""A small DP master (class 1) on a serial device: start-up of its slaves, Data_Exchange, DPV1.

Made for `dpc31 bridge` (docs/bridge.md, docs/bring-up.md section 6) but written as a master on
any 8E1 serial device is: open the device, one call that sets raw, 8 data bits, even parity and
the bus rate (tcsetattr, or the TCSETS2 ioctl for the five rates termios has no constant for),
then FDL telegrams (EN 50170: SD1/SD2, FCS, FCB/FCV) with a timeout per answer. Linux only.

    python3 tools/dp_master.py /tmp/dp0 --baud 19200 --ident 0x0D04 --cfg 21,10 \
        --user-prm 00,00,00,64 --outputs 05,01

Several slaves (`dpc31 bridge --slave ...`, docs/bridge.md "Several slaves"): `--slave` once per
station, ADDR or ADDR:IDENT:CFG[:USER_PRM[:OUTPUTS]] (hex bytes as for --cfg; what is left out
comes from --ident, --cfg, --user-prm, --outputs, or the zeros its CFG gives). Each is started up
in turn, then every DP cycle exchanges data with each in the order given; the lines of a station
begin with "slave ADDR: ".

    python3 tools/dp_master.py socket://127.0.0.1:5000 --slave 5:0x0D04:21,10:00,00,00,64:05,01 \
        --slave 6:0x0C31:13,23:00:01,02,03,04

The device may also be pyserial's URL of a raw TCP port, socket://HOST:PORT (`dpc31 bridge
--tcp PORT`): the same byte stream, no termios; the rate is the bridge's own (--baud then only
sets the master's timing).
With `--dpv1-read SLOT,INDEX,LENGTH` / `--dpv1-write SLOT,INDEX,DATA...` (hex bytes) it then
reads / writes a record with MSAC_C1 (SAP 51 to SAP 51; set DPV1_Enable in --user-prm): the
request, then polls while the slave answers SC, until the response or --c1-timeout
(docs/dpv1.md, "The master's side").

Without --outputs a Data_Exchange carries zeros, as many as the Cfg bytes give output bytes
(an SD1 request without a data unit when they give none); --outputs of another length is refused
(the slave would answer RS).

Prints one line per step and the inputs of the last Data_Exchange.
Python 3 standard library only; tests/bridge_test.py uses the same Master class.
"""

import argparse
import fcntl
import math
import os
import select
import socket
import struct
import sys
import termios
import time

SD1, SD2, SC, ED = 0x10, 0x68, 0xE5, 0x16
SAP_SLAVE_DIAG, SAP_SET_PRM, SAP_CHK_CFG, SAP_MASTER = 60, 61, 62, 62
# DPV1 (include/dpc31/pdu.hpp): MSAC_C1's SAP, Read and Write, the negative response's bit.
SAP_MSAC_C1, DPV1_READ, DPV1_WRITE, DPV1_ERROR = 51, 0x5E, 0x5F, 0x80
# An SD1 answer to a request with data: its FC's low nibble (EN 50170; include/dpc31/fdl.hpp).
FDL_REFUSALS = {
    0x01: "UE (user error: the slave's user refused the request)",
    0x02: "RR (no resource: the request is longer than the SAP's buffer, or its buffer is busy)",
    0x03: f"RS (the slave serves no SAP {SAP_MSAC_C1} now, or not for this master)",
    0x09: "NR (no response data)",
}
# The longest data unit of a DP telegram (Set_Prm, Chk_Cfg, Data_Exchange, a DPV1 PDU).
MAX_DU = 244
# --help's epilog (docs/bridge.md, "With a master program", says the same).
EPILOG = """\
hex bytes (--cfg, --user-prm, --outputs, --watchdog, --dpv1-read, --dpv1-write and the fields of
--slave): with commas every item is one byte of 1 or 2 hex digits (5,1 is 05 01), without commas
pairs of hex digits (0501); at most 244 bytes in one data unit.

exit codes: 0 Data_Exchange reached with every slave (and every DPV1 service answered
positively); 1 a slave did not come up, or a DPV1 service failed (the line says where, and with
several --slave which station: a negative response with its error bytes, RS, the time-out); 2 bad
arguments or device (not there, not a serial device, no TCP connection within --wait); 3 the
device or the connection went away during the run (the bridge stopped); 4 socket:// only: the
bridge refused the connection, another client is connected (it takes one at a time). Every error
is one line on stderr."""
# The ten PROFIBUS DP rates (EN 50170). Five have a termios constant; the others (45.45, 93.75,
# 187.5 kbaud, 6 and 12 Mbaud) are set as Linux's "other" rate: struct termios2 with BOTHER and
# the rate itself, through the TCSETS2 ioctl (as pyserial does for such rates).
RATES = (9600, 19200, 45450, 93750, 187500, 500000, 1500000, 3000000, 6000000, 12000000)
SPEEDS = {9600: termios.B9600, 19200: termios.B19200, 500000: termios.B500000,
          1500000: termios.B1500000, 3000000: termios.B3000000}
# Linux, asm-generic/termbits.h and ioctls.h: struct termios2 (4 flags, c_line, c_cc[19], the
# input and output rates) and _IOR/_IOW('T', 0x2A/0x2B, struct termios2).
TERMIOS2 = "IIIIB19sII"
TCGETS2 = 0x80000000 | (struct.calcsize(TERMIOS2) << 16) | (ord("T") << 8) | 0x2A
TCSETS2 = 0x40000000 | (struct.calcsize(TERMIOS2) << 16) | (ord("T") << 8) | 0x2B
BOTHER = 0o010000
CBAUD = 0o010017


def set_8e1(fd, baud):
    """One call with everything, as serial libraries do: raw, 8 data bits, even parity, one stop
    bit, receiver on, no modem control, the bus rate; no blocking reads."""
    cflag = termios.CS8 | termios.PARENB | termios.CREAD | termios.CLOCAL
    if baud in SPEEDS:
        a = termios.tcgetattr(fd)
        a[0] = a[1] = a[3] = 0
        a[2] = cflag
        a[4] = a[5] = SPEEDS[baud]
        a[6][termios.VMIN] = 0
        a[6][termios.VTIME] = 0
        termios.tcsetattr(fd, termios.TCSANOW, a)
        return
    _, _, _, _, line, cc, _, _ = struct.unpack(
        TERMIOS2, fcntl.ioctl(fd, TCGETS2, bytes(struct.calcsize(TERMIOS2))))
    cc = bytearray(cc)
    cc[termios.VMIN] = 0
    cc[termios.VTIME] = 0
    fcntl.ioctl(fd, TCSETS2, struct.pack(TERMIOS2, 0, 0, (cflag & ~CBAUD) | BOTHER, 0, line,
                                         bytes(cc), baud, baud))


class Fail(Exception):
    pass


class Lost(Fail):
    """The device or the connection went away during the run (exit 3)."""


class Refused(Fail):
    """socket://: the bridge closed the connection while it still takes others: it had another
    client (exit 4)."""


def check(cond, what):
    if not cond:
        raise Fail(what)


def hexs(b):
    return " ".join(f"{x:02X}" for x in b) if b is not None else "nothing"


def fcs(body):
    return sum(body) & 0xFF


def sd1(da, sa, fc):
    body = [da, sa, fc]
    return bytes([SD1] + body + [fcs(body), ED])


def sd2(da, sa, fc, du, dsap=None, ssap=None):
    body = [da | (0x80 if dsap is not None else 0), sa | (0x80 if ssap is not None else 0), fc]
    if dsap is not None:
        body.append(dsap)
    if ssap is not None:
        body.append(ssap)
    body += list(du)
    le = len(body)
    return bytes([SD2, le, le, SD2] + body + [fcs(body), ED])


def frame_length(buf):
    """Length of the telegram at the start of buf as its SD (and LE) tell, None if unknown yet."""
    if not buf:
        return None
    sd = buf[0]
    if sd == SC:
        return 1
    if sd == SD1:
        return 6
    if sd == SD2:
        return buf[1] + 6 if len(buf) >= 2 else None
    raise Fail(f"answer starts with {sd:02X}, no start delimiter")


def not_ours(req, a):
    """Whether the whole answer `a` cannot be the answer to `req`: an FDL_Status answer to a
    request that is none, or an SD2 answer whose SAPs are not the request's mirrored (EN 50170:
    the answer's DSAP is the request's SSAP and its SSAP the request's DSAP; a request without
    SAPs gets an answer without)."""
    if a[0] == SD1:
        return a[3] == 0x00 and not (req[0] == SD1 and req[3] == 0x49)
    if a[0] != SD2:
        return False
    req_saps = (req[7], req[8]) if req[0] == SD2 and req[4] & 0x80 else None
    saps = (a[8], a[7]) if a[4] & 0x80 else None
    return saps != req_saps


def answer_du(a, sap):
    """The data unit of an SD2 answer (after DA, SA, FC and, with `sap`, DSAP/SSAP)."""
    check(a is not None and a[0] == SD2, f"expected an SD2 answer, got {hexs(a)}")
    return a[(9 if sap else 7):-2]


class Master:
    """A DP master on the device: 8E1 raw, FCB/FCV per EN 50170, a timeout per answer."""

    def __init__(self, path, baud, timeout, address=2, slave=5, search=20.0, wait=10.0):
        self.sock = None
        self.path = path
        if path.startswith("socket://"):
            self.sock = connect(path, wait)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.sock.setblocking(False)
            self.fd = self.sock.fileno()
        else:
            self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
            try:
                set_8e1(self.fd, baud)
            except (OSError, termios.error) as e:  # termios.error is no OSError
                os.close(self.fd)
                raise OSError(f"{path}: not a serial device ({e.args[-1]})") from None
        self.baud = baud
        self.timeout = timeout
        self.search = search
        self.address = address
        self.slave = slave
        self.fcb = True
        self.fcv = False
        self.others = {}  # the FCB state of the slaves not selected: address -> (fcb, fcv)
        self.lost = 0
        self.answered = False  # a byte came from the device (socket://: the bridge took us)

    def select(self, slave):
        """Makes `slave` the station every request goes to, with its own FCB state (EN 50170: FCB
        and FCV belong to one master-slave pair)."""
        if slave == self.slave:
            return
        self.others[self.slave] = (self.fcb, self.fcv)
        self.fcb, self.fcv = self.others.pop(slave, (True, False))
        self.slave = slave

    def close(self):
        if self.sock is not None:
            self.sock.close()
        else:
            os.close(self.fd)

    def flush_input(self):
        """Drops what arrived before the request: tcflush on a tty; on a socket, what is there."""
        if self.sock is None:
            try:
                termios.tcflush(self.fd, termios.TCIFLUSH)
            except termios.error as e:  # EIO: the pty's other side is gone
                raise Lost(f"the device went away ({e.args[-1]})") from None
            return
        while select.select([self.fd], [], [], 0)[0]:
            self.read()

    def read(self):
        try:
            b = os.read(self.fd, 512)
        except BlockingIOError:
            return b""
        except OSError as e:  # EIO on a pty, ECONNRESET on a socket
            self.gone(f"the device went away ({e.strerror})")
        if not b and self.sock is not None:
            self.gone("the bridge closed the connection")
        self.answered = self.answered or bool(b)
        return b

    def gone(self, why):
        """Raises Lost, or Refused when on socket:// nothing ever came and the bridge still takes
        connections: it closes a client itself only when it stops, or at once, unread and
        unanswered, when another client is connected (docs/bridge.md, "Over TCP"). The probe is
        closed at once."""
        if self.sock is not None and not self.answered:
            try:
                socket.create_connection(socket_address(self.path), timeout=self.timeout).close()
            except OSError:
                pass  # not listening any more: it stopped
            else:
                raise Refused(f"{self.path}: the bridge refused the connection: another client "
                              "is connected (one at a time)") from None
        raise Lost(why) from None

    def write(self, req):
        try:
            os.write(self.fd, req)
        except OSError as e:
            self.gone(f"the device went away ({e.strerror})")

    def transact(self, req, timeout=None, searching=False):
        """Writes one request, returns the answer telegram (bytes) or None after the timeout.
        `searching` (find_slave): bytes before a start delimiter are dropped, an answer begun by
        the timeout is awaited for the answer timeout, and bytes after the first whole telegram
        (late answers to earlier requests) are left to find_slave's drain. Otherwise an answer
        that cannot be ours is dropped and the wait for ours starts anew (up to --search longer in
        all): a late FDL_Status answer (to a request of find_slave's still queued ahead of ours),
        an answer with bytes after it (ours is the last request written, so its answer is the
        last to come), and an SD2 answer whose SAPs do not mirror ours."""
        self.flush_input()
        self.write(req)
        buf = b""
        wait = timeout or self.timeout
        deadline = time.monotonic() + wait
        # Late answers may extend the wait (below), up to the search's budget: a guard only.
        limit = deadline + self.search
        extended = False
        while True:
            if searching:  # the tail of a late answer that the flush cut is not ours either
                buf = buf.lstrip(bytes(b for b in range(256) if b not in (SD1, SD2, SC)))
            n = frame_length(buf)
            if n is not None and len(buf) >= n:
                if searching:
                    return buf[:n]
                if not_ours(req, buf[:n]) or len(buf) > n:
                    # A late answer to a request written before ours, on a loaded host later
                    # than find_slave's drain: it shows the line still working off what came
                    # before (a bridge slower than the bus queues the requests), so ours waits
                    # anew from here: its fate is known only after theirs (issue 35).
                    buf = buf[n:]
                    deadline = min(limit, max(deadline, time.monotonic() + wait))
                    continue
                return buf
            left = deadline - time.monotonic()
            if left <= 0 and searching and buf and not extended:
                deadline, left, extended = time.monotonic() + self.timeout, self.timeout, True
            if left <= 0:
                check(searching or not buf, f"incomplete answer {hexs(buf)} to {hexs(req)}")
                return None
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                buf += self.read()

    def fdl_status(self, timeout=None, searching=False):
        a = self.transact(sd1(self.slave, self.address, 0x49), timeout, searching)
        if a is not None:
            self.fcb = False  # the first SRD after FDL_Status: FCB = 1, FCV = 1
            self.fcv = True
        return a

    def find_slave(self, budget=None):
        """FDL_Status until answered, for `budget` seconds at most (default: the master's
        `search`, --search). While the chip searches the
        rate it listens max(4096 bit times, 20 ms) at each of the ten (12 Mbaud first; the round
        is 0.896 s of chip time, docs/timing.md "Baud_Search"): a request goes out every exchange
        time at this rate (request, TSYN, slot time, answer: under 300 bit times) plus 3 ms for
        the host, so at every rate one lands whole in the first window at our rate (a period of
        at most 19.8 ms does). A longer fixed period can be nearly a divisor of the round and then
        miss the window round after round. Once answered, the answers to
        requests still on their way are read and dropped (until the line has been quiet for two
        periods: not longer, or Baud_Control, a few hundred ms of a silent bus, sends the chip
        back to its search), so the next request gets its own answer."""
        period = 300.0 / self.baud + 0.003
        deadline = time.monotonic() + (self.search if budget is None else budget)
        while time.monotonic() < deadline:
            a = self.fdl_status(timeout=period, searching=True)
            if a is not None:
                self.drain(2 * period)
                return a
        raise Fail("FDL_Status never answered")

    def drain(self, quiet):
        """Reads and drops what arrives until the line has been quiet for `quiet` seconds."""
        while True:
            r, _, _ = select.select([self.fd], [], [], quiet)
            if not r:
                return
            self.read()

    def srd(self, du, dsap=None, ssap=SAP_MASTER):
        """SRD_high with FCB/FCV. No answer: the station is lost (on a loaded host chip time can
        run past Baud_Control between two requests, and the slave searches the rate again), so
        FDL_Status until it answers, then the request once more, as a master re-finds a lost
        station; up to three times (once was not enough for a bridge in realtime pacing beside a
        CPU hog; issue 35). Counted in `self.lost` and said on stderr."""
        a = self.transact(self.srd_frame(du, dsap, ssap))
        for _ in range(3):
            if a is not None:
                break
            self.lost += 1
            print(f"dp_master: no answer from station {self.slave}, searching it again",
                  file=sys.stderr)
            self.find_slave()
            a = self.transact(self.srd_frame(du, dsap, ssap))
        return a

    def srd_frame(self, du, dsap, ssap=SAP_MASTER):
        self.fcb = not self.fcb
        fc = 0x40 | (0x20 if self.fcb else 0) | (0x10 if self.fcv else 0) | 0x0D
        if not du and dsap is None:  # no data unit: SD1 (an SD2 has LE 4 at least)
            return sd1(self.slave, self.address, fc)
        return sd2(self.slave, self.address, fc, du, dsap=dsap,
                   ssap=ssap if dsap is not None else None)

    def msac_c1(self, pdu, time_out):
        """MSAC_C1: `pdu` from SAP 51 to SAP 51, then polls (SRD without data, the same SAPs, the
        next FCB each) while the slave answers SC, until its response or `time_out` seconds (the
        GSD's C1_Response_Timeout). Returns (the response's data unit, the polls answered SC).
        Anything else fails: no answer, an FDL refusal (FDL_REFUSALS), the time-out."""
        a = self.srd(pdu, SAP_MSAC_C1, SAP_MSAC_C1)
        deadline = time.monotonic() + time_out
        polls = -1  # the request's own SC is not a poll's
        while a == bytes([SC]):
            polls += 1
            check(time.monotonic() < deadline,
                  f"MSAC_C1 {hexs(pdu)}: no response within {time_out:g} s ({polls} polls)")
            a = self.srd([], SAP_MSAC_C1, SAP_MSAC_C1)
        if a is not None and a[0] == SD1:
            raise Fail(f"MSAC_C1 {hexs(pdu)}: "
                       + FDL_REFUSALS.get(a[3] & 0x0F, f"answered {hexs(a)}"))
        return answer_du(a, True), max(polls, 0)

    def slave_diag(self):
        return answer_du(self.srd([], SAP_SLAVE_DIAG), True)

    def expect(self, what, got, *allowed):
        check(got in allowed,
              f"{what}: got {hexs(got)}, expected " + " or ".join(hexs(a) for a in allowed))
        return got


def byte_list(text):
    """Hex bytes: with commas each item one byte of 1 or 2 hex digits ('5,1' -> [0x05, 0x01]),
    without commas pairs of digits ('2110' -> [0x21, 0x10]); '' -> []."""
    hexdigits = "0123456789abcdefABCDEF"
    if "," in text:
        for item in text.split(","):
            if not 1 <= len(item.strip()) <= 2 or not all(c in hexdigits for c in item.strip()):
                raise argparse.ArgumentTypeError(
                    f"'{text}': '{item}' is not a byte (1 or 2 hex digits between commas)")
        return [int(item, 16) for item in text.split(",")]
    if not all(c in hexdigits for c in text):
        raise argparse.ArgumentTypeError(f"'{text}': not hex bytes")
    if len(text) % 2:
        raise argparse.ArgumentTypeError(f"'{text}': an odd number of hex digits (without "
                                         "commas every byte is two)")
    return list(bytes.fromhex(text))


def cfg_outputs(cfg):
    """The output bytes that the Chk_Cfg identifier bytes `cfg` give (EN 50170; the chip docs'
    chip-facts.md). General format (bits 5..4 not 00): 01 input, 10 output, 11 both, bits 3..0
    the length - 1, bit 6 words. Special format (bits 5..4 00): bits 7..6 01 an input length
    byte follows, 10 an output one, 11 an output then an input one (each bits 5..0 the length -
    1, bit 6 words), then bits 3..0 bytes of manufacturer data; 00h is an empty slot. ValueError
    for what cannot be sized: length bytes or data missing, or the data length 15."""
    outputs, i = 0, 0
    while i < len(cfg):
        ident = cfg[i]
        if ident & 0x30:
            if ident & 0x20:
                outputs += ((ident & 0x0F) + 1) * (2 if ident & 0x40 else 1)
            i += 1
            continue
        if ident & 0x0F == 0x0F:
            raise ValueError(f"the special identifier {ident:02X} (byte {i + 1}) gives no "
                             "manufacturer data length")
        lengths = cfg[i + 1:i + 1 + bin(ident & 0xC0).count("1")]
        end = i + 1 + len(lengths) + (ident & 0x0F)
        if len(lengths) < bin(ident & 0xC0).count("1") or end > len(cfg):
            raise ValueError(f"the special identifier {ident:02X} (byte {i + 1}) runs past the "
                             "end")
        if ident & 0x80:  # the output length byte comes first
            outputs += ((lengths[0] & 0x3F) + 1) * (2 if lengths[0] & 0x40 else 1)
        i = end
    return outputs


def start_up(m, args, say):
    """Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag until the slave is ready (Station_Not_Ready and
    Prm_Req clear)."""
    say(f"FDL_Status: {hexs(m.find_slave())}")
    du = m.slave_diag()
    say(f"Slave_Diag: {hexs(du)}")
    # Master_Add (Slave_Diag byte 3) naming another master: the slave is locked by it, and a DP
    # master leaves it alone (EN 50170's Master_Lock; docs/decisions.md, the twenty-eighth
    # session), as the built-in master does (`startup: slave locked by master N ...`).
    if len(du) >= 4 and du[3] not in (0xFF, m.address):
        raise Fail(f"locked by master {du[3]} (its Slave_Diag's Master_Add): not parameterised")
    # Lock_Req + WD_On, watchdog factors, MinTSDR 0, ident, group 0, then the user parameters.
    prm = [0x88, args.watchdog[0], args.watchdog[1], 0x00, args.ident >> 8, args.ident & 0xFF,
           0x00] + args.user_prm
    a = m.srd(prm, SAP_SET_PRM)
    say(f"Set_Prm {hexs(prm)}: {hexs(a)}")
    check(a == bytes([SC]), "Set_Prm not acknowledged")
    a = m.srd(args.cfg, SAP_CHK_CFG)
    say(f"Chk_Cfg {hexs(args.cfg)}: {hexs(a)}")
    check(a == bytes([SC]), "Chk_Cfg not acknowledged")
    for _ in range(20):
        du = m.slave_diag()
        # Station_Not_Ready, Cfg_Fault, Prm_Fault (Station_Status_1) and Prm_Req (_2) clear
        if du[0] & 0x46 == 0 and du[1] & 0x01 == 0:
            say(f"Slave_Diag: {hexs(du)} (ready)")
            return
    raise Fail(f"the slave never became ready; last Slave_Diag {hexs(du)}")


def dx_response(a):
    """The response code of a Data_Exchange answer: DL 08h or DH 0Ah (new diagnosis), from an SD2
    with inputs, or for a slave without inputs an SD1 or the short acknowledge (SC: DL, docs/
    decisions.md "with R_Len_Din_Buf = 0 the answer is SC (or SD1 DH)"); None for anything else."""
    if a == bytes([SC]):
        return 0x08
    fc = {SD1: 3, SD2: 6}.get(a[0]) if a else None
    return a[fc] if fc is not None and a[fc] in (0x08, 0x0A) else None


def exchange(m, slaves, cycles, say_for):
    """`cycles` DP cycles, each a Data_Exchange with every slave in turn (its own outputs); a DH
    answer (new diagnosis) is followed by a Slave_Diag. Prints a slave's inputs whenever they
    change."""
    last = {}
    for _ in range(cycles):
        for s in slaves:
            m.select(s.address)
            say = say_for(s)
            a = m.srd(s.outputs)
            fc = dx_response(a)
            check(fc is not None, f"Data_Exchange with station {s.address}: got {hexs(a)}")
            inputs = answer_du(a, False) if a[0] == SD2 else b""
            if inputs != last.get(s.address):
                say(f"Data_Exchange {hexs(s.outputs) or '-'}: inputs {hexs(inputs) or '-'}")
                last[s.address] = inputs
            if fc == 0x0A:
                say(f"Slave_Diag (after DH): {hexs(m.slave_diag())}")


def in_range(parse, low, high, what):
    """An argparse type: `parse(text)` within low..high, else an error naming `what`."""
    def convert(text):
        try:
            n = parse(text)
        except ValueError:
            n = None
        if n is None or not low <= n <= high:
            raise argparse.ArgumentTypeError(f"'{text}': not {what}")
        return n
    return convert


STATION = in_range(int, 0, 125, "a station address 0..125")
IDENT = in_range(lambda text: int(text, 0), 0, 0xFFFF, "an Ident_Number 0..0xFFFF")


def slave_spec(text):
    """--slave ADDR[:IDENT:CFG[:USER_PRM[:OUTPUTS]]] -> its fields (None: from the options)."""
    f = text.split(":")
    if len(f) == 2 or len(f) > 5:
        raise argparse.ArgumentTypeError(f"'{text}': not ADDR[:IDENT:CFG[:USER_PRM[:OUTPUTS]]]")
    return argparse.Namespace(address=STATION(f[0]), ident=IDENT(f[1]) if len(f) > 1 else None,
                              cfg=byte_list(f[2]) if len(f) > 2 else None,
                              user_prm=byte_list(f[3]) if len(f) > 3 else None,
                              outputs=byte_list(f[4]) if len(f) > 4 else None)


def slaves_of(args, error):
    """The stations to poll, each with its start-up's settings and its outputs (from the Cfg
    when not given); `error` for one that lacks one or has one that does not fit."""
    out = []
    for s in args.slave or [slave_spec("5")]:
        for name in ("ident", "cfg", "user_prm", "outputs"):
            if getattr(s, name) is None:
                setattr(s, name, getattr(args, name))
        missing = [n for n, v in (("Ident_Number", s.ident), ("Chk_Cfg", s.cfg)) if v is None]
        if missing:
            error(f"station {s.address}: no {' or '.join(missing)} (--ident and --cfg, or "
                  "--slave ADDR:IDENT:CFG)")
        if not s.cfg:
            error(f"station {s.address}: an empty Chk_Cfg configures no module (give at least "
                  "one Cfg byte)")
        if s.address in [o.address for o in out]:
            error(f"--slave {s.address} twice")
        try:
            n = cfg_outputs(s.cfg)
        except ValueError as e:  # --outputs is then taken as it is
            if s.outputs is None:
                error(f"station {s.address}: Chk_Cfg: {e}; give its outputs (--outputs)")
            n = len(s.outputs)
        for what, du in (("Set_Prm", 7 + len(s.user_prm)), ("Chk_Cfg", len(s.cfg)),
                         ("Data_Exchange", n)):
            if du > MAX_DU:
                error(f"station {s.address}: a {what} of {du} bytes (at most {MAX_DU})")
        if s.outputs is None:
            s.outputs = [0] * n
        if len(s.outputs) != n:
            error(f"station {s.address}: {len(s.outputs)} output bytes, its Chk_Cfg gives {n} "
                  "(the slave would answer RS)")
        s.watchdog = args.watchdog
        out.append(s)
    return out


def socket_address(url):
    """socket://HOST:PORT (pyserial's URL; HOST may be [V6]; PORT 1..65535) -> (host, port)."""
    hostport = url[len("socket://"):].split("/", 1)[0]
    host, sep, port = hostport.rpartition(":")
    if not sep or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise OSError(f"{url}: not socket://HOST:PORT (PORT 1..65535)")
    return host.strip("[]") or "127.0.0.1", int(port)


def connect(url, seconds):
    """A connection to socket://HOST:PORT, retried while refused for `seconds` (--wait: the
    bridge is starting); one attempt waits for the host as long, at least 1 s."""
    address = socket_address(url)
    deadline = time.monotonic() + seconds
    while True:
        try:
            return socket.create_connection(address, timeout=max(seconds, 1.0))
        except ConnectionRefusedError:
            if time.monotonic() > deadline:
                raise OSError(f"{url}: connection refused (waited {seconds:g} s)") from None
        except OSError as e:  # no route, a time-out, a host name that does not resolve
            raise OSError(f"{url}: {e.strerror or e}") from None
        time.sleep(0.02)
def dpv1_record(m, function, slot, index, data, length, time_out):
    """MSAC_C1 Read (`length` bytes wanted) or Write (`data`) of slot / index: the positive
    response's data unit and the polls; a negative response fails with its three error bytes."""
    pdu = bytes([function, slot, index, length if function == DPV1_READ else len(data)]) + data
    du, polls = m.msac_c1(pdu, time_out)
    if du[:1] == bytes([function | DPV1_ERROR]) and len(du) == 4:
        raise Fail(f"MSAC_C1 {hexs(pdu)}: negative response, Error_Decode {du[1]:02X}, "
                   f"Error_Code_1 {du[2]:02X}, Error_Code_2 {du[3]:02X}")
    check(len(du) >= 4 and du[:3] == pdu[:3] and len(du) == 4 + (du[3] if function == DPV1_READ
                                                                 else 0),
          f"MSAC_C1 {hexs(pdu)}: response {hexs(du)}")
    return du, polls


def dpv1(m, args, say):
    """The --dpv1-read / --dpv1-write services, in that order."""
    if args.dpv1_read:
        slot, index, length = args.dpv1_read
        du, polls = dpv1_record(m, DPV1_READ, slot, index, b"", length, args.c1_timeout)
        say(f"MSAC_C1 Read slot {slot} index {index}: {hexs(du[4:])} ({polls} polls)")
    if args.dpv1_write:
        slot, index, data = args.dpv1_write[0], args.dpv1_write[1], bytes(args.dpv1_write[2:])
        _, polls = dpv1_record(m, DPV1_WRITE, slot, index, data, len(data), args.c1_timeout)
        say(f"MSAC_C1 Write slot {slot} index {index}: {hexs(data)} ({polls} polls)")


def wait_for(path, seconds):
    deadline = time.monotonic() + seconds
    if path.startswith("socket://"):  # Master connects (a probe connection would be a client)
        return
    while not os.path.exists(path):
        if time.monotonic() > deadline:
            raise FileNotFoundError(f"{path}: no such device (waited {seconds:g} s)")
        time.sleep(0.02)


class Once(argparse.Action):
    """An option that may be given once: a second one would silently replace the first."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = vars(namespace).setdefault("given_once", set())
        if self.dest in given:
            parser.error(f"{option_string} given twice")
        given.add(self.dest)
        setattr(namespace, self.dest, values)


class Parser(argparse.ArgumentParser):
    """argparse with a usage error in one line on stderr (no usage lines), exit 2."""

    def error(self, message):
        self.exit(2, f"dp_master: {message}\n")


def main():
    p = Parser(description=__doc__.split("\n")[0], epilog=EPILOG,
               formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("device", help="serial device, e.g. the path given to dpc31 bridge --pty, or "
                   "socket://HOST:PORT (dpc31 bridge --tcp PORT)")
    p.add_argument("--baud", type=int, default=19200, choices=RATES,
                   help="the bus rate, one of the ten PROFIBUS rates (default 19200)")
    p.add_argument("--address", type=STATION, default=2,
                   help="the master's station address, 0..125 (default 2)")
    p.add_argument("--slave", type=slave_spec, action="append",
                   metavar="ADDR[:IDENT:CFG[:USER_PRM[:OUTPUTS]]]",
                   help="a slave's station address (default 5), and what it is started with; "
                   "once per slave, polled in this order")
    p.add_argument("--ident", type=IDENT, help="Ident_Number, 0..0xFFFF")
    p.add_argument("--cfg", type=byte_list, help="Chk_Cfg bytes, e.g. 21,10 (hex bytes)")
    p.add_argument("--user-prm", type=byte_list, default=[],
                   help="user parameter bytes (hex bytes)")
    p.add_argument("--watchdog", type=byte_list, default=[0x64, 0x0A],
                   help="WD_Fact_1,WD_Fact_2 (default 64,0A: 10 s)")
    p.add_argument("--outputs", type=byte_list,
                   help="output bytes (hex bytes), as many as --cfg gives (default: zeros)")
    p.add_argument("--cycles", type=in_range(int, 1, 1 << 31, "a number of cycles, 1 or more"),
                   default=10, help="Data_Exchange cycles")
    p.add_argument("--timeout", type=float, default=0.5, help="seconds to wait for an answer")
    p.add_argument("--search", type=float, default=20.0, metavar="SECONDS",
                   help="seconds to look for a slave with FDL_Status (while it searches the "
                   "rate) before giving up (default 20; longer on a loaded host)")
    p.add_argument("--dpv1-read", type=byte_list, action=Once, metavar="SLOT,INDEX,LENGTH",
                   help="then MSAC_C1 Read of this record (hex bytes)")
    p.add_argument("--dpv1-write", type=byte_list, action=Once, metavar="SLOT,INDEX,DATA",
                   help="then MSAC_C1 Write of these data bytes to this record (hex bytes)")
    p.add_argument("--c1-timeout", type=float, default=1.0, action=Once,
                   help="seconds a DPV1 service may take (C1_Response_Timeout, default 1)")
    p.add_argument("--wait", type=float, default=10.0,
                   help="seconds to wait for the device to appear, or on socket:// for the "
                   "bridge to take the connection (default 10)")
    args = p.parse_args()
    for name in ("timeout", "search", "c1_timeout"):  # NaN and inf are no number of seconds
        if not 0 < getattr(args, name) < math.inf:
            p.error(f"--{name.replace('_', '-')} takes a positive number of seconds")
    if not 0 <= args.wait < math.inf:
        p.error("--wait takes a number of seconds, 0 or more")
    # DP's WD_Fact_1 and WD_Fact_2 are 1..255 (EN 50170); 0 the slave takes as a parameter fault.
    if len(args.watchdog) != 2 or 0 in args.watchdog:
        p.error("--watchdog takes two bytes, each 01..FF (WD_Fact_1,WD_Fact_2)")
    if args.dpv1_read is not None and len(args.dpv1_read) != 3:
        p.error("--dpv1-read takes three bytes: SLOT,INDEX,LENGTH")
    if args.dpv1_write is not None and len(args.dpv1_write) < 3:
        p.error("--dpv1-write takes SLOT,INDEX and at least one data byte")
    if args.dpv1_write is not None and 2 + len(args.dpv1_write) > MAX_DU:
        p.error(f"--dpv1-write: a DPV1 PDU of {2 + len(args.dpv1_write)} bytes (at most {MAX_DU})")
    # The ranges of the scenario's dpv1_read / dpv1_write (docs/scenario-format.md, "DPV1"):
    # slot 255 is no slot, a Read of 0 bytes or of more than a PDU carries is no Read.
    for name, values in (("read", args.dpv1_read), ("write", args.dpv1_write)):
        if values is not None and values[0] > 254:
            p.error(f"--dpv1-{name}: slot {values[0]} out of range (0..254)")
    if args.dpv1_read is not None and not 1 <= args.dpv1_read[2] <= MAX_DU - 4:
        p.error(f"--dpv1-read: length {args.dpv1_read[2]} out of range (1..{MAX_DU - 4})")
    slaves = slaves_of(args, p.error)
    if args.address in [s.address for s in slaves]:
        p.error(f"station {args.address}: the master's own --address (each station needs its "
                "own)")
    if len(slaves) > 1 and (args.dpv1_read or args.dpv1_write):
        p.error("--dpv1-read and --dpv1-write are for one --slave")

    def say(line):
        print(line, flush=True)

    def say_for(s):
        return say if len(slaves) == 1 else lambda line: say(f"slave {s.address}: {line}")

    try:
        wait_for(args.device, args.wait)
        m = Master(args.device, args.baud, args.timeout, args.address, slaves[0].address,
                   args.search, args.wait)
    except OSError as e:
        print(f"dp_master: {e}", file=sys.stderr)
        return 2
    try:
        for s in slaves:
            m.select(s.address)
            start_up(m, s, say_for(s))
        exchange(m, slaves, args.cycles, say_for)
        dpv1(m, args, say)
    except Refused as e:
        print(f"dp_master: {e}", file=sys.stderr)
        return 4
    except Lost as e:
        print(f"dp_master: {e}", file=sys.stderr)
        return 3
    except Fail as e:  # named as its station's lines are
        station = f"slave {m.slave}: " if len(slaves) > 1 else ""
        print(f"dp_master: {station}{e}", file=sys.stderr)
        return 1
    finally:
        m.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
