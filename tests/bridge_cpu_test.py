#!/usr/bin/env python3
"""End-to-end tests of `dpc31 bridge --cpu c31` (docs/bridge.md, docs/dpc31.md "The C31"), run by
CTest.

c31_ack_trace: the DPC31's C31 runs tests/mcs51/board/c31_ack.asm (as the build assembles it)
behind the pty, from the chip's RAM at --code 1000h; --trace-cpu has every step with its machine
cycle, PC and opcode exactly as the program's listing gives them (the machine cycles in brackets
in c31_ack.asm, the instruction set's cycle counts): the C31's interrupt, raised by its own MOVX
to Int_Req_Reg in [12,14), is called in [15,17) (its own line, naming ie0 and the vector 0003h),
the vector's LJMP runs in [17,19) and the routine starts at 004Eh in 19; the C31 at 24 MHz puts
machine cycle m at chip cycle 24 m (docs/cpu.md).

idle_timer_window: --trace-cpu-from / --trace-cpu-to keep only the lines in the window.

trace_write_fails: a trace on a full device names the file, exit 2; an empty window is refused.

idle_timer_trace: the 80C32 at 24 MHz runs tests/mcs51/board/idle_timer.asm: each idle stretch
is one line with its cycles, each timer 0 call one line naming tf0 and 000Bh (docs/cpu.md, "The
CPU trace"); the cycles from the listing's brackets.

c31_bad_arguments: --cpu c31 on another profile, against --irq-controller external, a --code
outside the RAM's user area, --ports or --board-address (the 80C32 board's), --code on the
80C32, --trace-cpu naming the SDCC map beside the image: one line on stderr, exit 2, no log
made.

Usage: bridge_cpu_test.py DPC31_CLI DISSECTOR CASE.
"""

import os
import shutil
import signal
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bridge_line_test as blt  # noqa: E402
import bridge_test as bt  # noqa: E402
from bridge_test import GUARD  # noqa: E402
from dp_master import check  # noqa: E402

# Every line of the trace: the listing of c31_ack.asm (.org 30h on). The interrupt call, the
# hardware LCALL in [15,17), is a line of its own with the PC it interrupts (0040h, the return
# address); the vector's LJMP at 0003h follows in [17,19). Without a map a place is its address.
def step(m, pc, op):
    return f"{24 * m} {m} {pc:04X} {op:02X} {pc:04X}h"


C31_STEPS = [step(0, 0x0000, 0x02), step(2, 0x0030, 0x90), step(4, 0x0033, 0x74),
             step(5, 0x0035, 0xF0), step(7, 0x0036, 0x75), step(9, 0x0039, 0x90),
             step(11, 0x003C, 0x74), step(12, 0x003E, 0xF0), step(14, 0x003F, 0x00),
             "360 15 interrupt ie0 0003 from 0040 0040h", step(17, 0x0003, 0x02),
             step(19, 0x004E, 0x90), step(21, 0x0051, 0x74), step(22, 0x0053, 0xF0),
             step(24, 0x0054, 0x32), step(26, 0x0040, 0x90), step(28, 0x0043, 0x74),
             step(29, 0x0045, 0xF0), step(31, 0x0046, 0x74), step(32, 0x0048, 0x90),
             step(34, 0x004B, 0xF0), step(36, 0x004C, 0x80), step(38, 0x004C, 0x80)]

# idle_timer.asm: TL0 counts F7h..FFh in 11..19 and overflows in 20; idle begins after the ORL
# (13). An idle cycle polls the flags sampled in the one before: TF0, raised in 20, is polled in
# 21, which ends idle; the call is [22,24), the RETI [24,26) (its hold-off lets the SJMP run),
# the SJMP [26,28), the ORL [28,30); the reload counted F7h in 21, so TF0 rises again in 30 and
# the second idle stretch is [30,32).
IDLE_STEPS = [step(0, 0x0000, 0x02), step(2, 0x0030, 0x75), step(4, 0x0033, 0x75),
              step(6, 0x0036, 0x75), step(8, 0x0039, 0x75), step(10, 0x003C, 0xD2),
              step(11, 0x003E, 0x43), "312 13 idle 9 machine cycles to 528 22",
              "528 22 interrupt tf0 000B from 0041 0041h", step(24, 0x000B, 0x32),
              step(26, 0x0041, 0x80), step(28, 0x003E, 0x43),
              "720 30 idle 2 machine cycles to 768 32",
              "768 32 interrupt tf0 000B from 0041 0041h", step(34, 0x000B, 0x32)]


def board_program(name):
    return os.path.join(os.path.dirname(os.path.abspath(bt.CLI)), "..", "tests", "mcs51", "board",
                        name + ".ihx")


def c31_ack():
    return board_program("c31_ack")


def traced(want, *args, whole=False):
    """Runs the bridge with `args` and --trace-cpu past the last machine cycle of `want` (its
    lines), then checks that the trace begins with them (is them, `whole`)."""
    # Free pacing runs the chip with the wall clock while no client is connected. SIGTERM comes
    # after the event that shows chip time past them (not after a sleep, which beside a CPU hog
    # could end before the bridge ran that far): a client's open of the pty, logged with the
    # cycle at which the bridge saw it. A client that only opens and closes the pty changes
    # nothing for the CPU.
    need = int(want[-1].split()[0]) + 24 * 4
    with tempfile.TemporaryDirectory() as tmp:
        trace = os.path.join(tmp, "cpu.trace")
        b = bt.Bridge(tmp, *args, "--pacing", "free", "--trace-cpu", trace)
        try:
            deadline = time.monotonic() + GUARD
            while True:
                opened = [line for line in b.log_lines() if "client opened the pty" in line]
                fd = os.open(b.path, os.O_RDWR | os.O_NOCTTY)
                b.wait_for_log("client opened the pty", GUARD, len(opened) + 1)
                b.close_and_wait(Pty(fd))
                seen = [line for line in b.log_lines() if "client opened the pty" in line][-1]
                if int(seen.split()[0]) >= need:
                    break
                check(time.monotonic() < deadline, f"chip time not at {need} after {GUARD:g} s")
            b.stop(signal.SIGTERM)
            lines = b.log_lines()
            check(lines[-1].endswith("stopping on SIGTERM"), f"last log line: {lines[-1]}")
            with open(trace, encoding="utf-8") as f:
                got = f.read().splitlines()
            got = got if whole else got[:len(want)]
            check(got == want, f"the trace's first lines: {got}, expected {want}")
            return lines
        finally:
            b.kill()


def c31_ack_trace():
    lines = traced(C31_STEPS, "--cpu", "c31", "--firmware", c31_ack(), "--code", "0x1000",
                   "--profile", "dpc31")
    check("c31_ack.ihx on the C31 at 24000000 Hz" in lines[0], f"log line 1: {lines[0]}")
    check("profile dpc31, irq-controller c31," in lines[0], f"log line 1: {lines[0]}")


def idle_timer_trace():
    traced(IDLE_STEPS, "--cpu", "80c32", "--firmware", board_program("idle_timer"),
           "--profile", "spc3")


def idle_timer_window():
    """--trace-cpu-from 528 --trace-cpu-to 720: the lines whose first chip cycle lies in
    [528, 720) and nothing else (the idle stretch from 312 and the one from 720 left out)."""
    traced(IDLE_STEPS[8:12], "--cpu", "80c32", "--firmware", board_program("idle_timer"),
           "--profile", "spc3", "--trace-cpu-from", "528", "--trace-cpu-to", "720", whole=True)


def serial_port():
    """docs/bridge.md, "The log": a character the 80C32's serial port sends is an `SBUF` line at
    the default events level. MOV SBUF,#41h; SJMP $ (ServeCpu.SerialCharactersReachTheClient's
    image): in mode 0 TI is set at the end of machine cycle 10, chip cycle 264 at 24 MHz
    (ScenarioCpu51.TheSerialPortsCharactersReachTheWalk derives it from the manual)."""
    with tempfile.TemporaryDirectory() as tmp:
        image = os.path.join(tmp, "sbuf.ihx")
        with open(image, "w", encoding="ascii") as f:
            f.write(":0500000075994180FE2E\n:00000001FF\n")
        b = bt.Bridge(tmp, "--cpu", "80c32", "--firmware", image, "--profile", "spc3",
                      "--pacing", "free")
        try:
            b.wait_for_log(" SBUF ", GUARD)
            b.stop(signal.SIGTERM)
            got = [line for line in b.log_lines() if " SBUF " in line]
            want = [f"{264:>12} SBUF  slave5   80C32 serial port: sent 0x41 'A'"]
            check(got == want, f"SBUF lines: {got}, expected {want}")
        finally:
            b.kill()


def trace_write_fails():
    """A trace that cannot be written (a full device) stops the bridge naming the file, as every
    output does (docs/bad-input.md, "Output files"), exit 2; an empty window and a window without
    --trace-cpu are refused before anything runs."""
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "log")
        run = ["--pty", os.path.join(tmp, "dp0"), "--pacing", "free", "--log", log, "--cpu",
               "80c32", "--firmware", board_program("idle_timer"), "--profile", "spc3"]
        blt.expect_refused(run + ["--trace-cpu", "/dev/full"],
                           "dpc31 bridge: /dev/full: cannot write: No space left on device")
        trace = os.path.join(tmp, "t")
        blt.expect_refused(run + ["--trace-cpu", trace, "--trace-cpu-from", "5",
                                  "--trace-cpu-to", "5"],
                           "--trace-cpu-from 5 must lie before --trace-cpu-to 5: an empty window",
                           trace)
        blt.expect_refused(run + ["--trace-cpu-to", "5"], "--trace-cpu-to needs --trace-cpu")


class Pty:
    """A client of the pty that only opened it (for Bridge.close_and_wait)."""

    def __init__(self, fd):
        self.fd = fd

    def close(self):
        os.close(self.fd)


def c31_bad_arguments():
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "log")
        c31 = ["--tcp", "0", "--log", log, "--cpu", "c31", "--firmware", c31_ack()]
        cases = [
            (c31 + ["--profile", "spc3"], "--cpu c31 is for --profile dpc31"),
            (c31 + ["--irq-controller", "external"], "--irq-controller external contradicts"),
            (c31 + ["--code", "0x800"], "--code '0x800' must be an address 0x08A0..0x1FFF"),
            (c31 + ["--ports", "outputs"], "--ports is the 80C32 board's output latch"),
            (c31 + ["--board-address", "0"], "--board-address is the 80C32 board's"),
            (["--tcp", "0", "--log", log, "--cpu", "80c32", "--firmware", c31_ack(),
              "--code", "0x1000"], "--code is the C31's"),
            (["--tcp", "0", "--log", log, "--firmware", "DO4", "--code", "0x1000"],
             "--code needs --cpu"),
            # An image named '' is no file (it said ": no such file", naming nothing).
            (["--tcp", "0", "--log", log, "--cpu", "80c32", "--firmware", ""],
             "--firmware: an empty file name: nothing can be read there"),
            (c31[:-1] + [""], "--firmware: an empty file name: nothing can be read there"),
        ]
        for args, want in cases:
            blt.expect_refused(args, want, log)
        # The SDCC map beside the image is an input too: --trace-cpu over it replaced it.
        image, map_file = os.path.join(tmp, "ack.ihx"), os.path.join(tmp, "ack.map")
        shutil.copy(c31_ack(), image)
        with open(map_file, "w", encoding="utf-8") as f:
            f.write("map\n")
        blt.expect_refused(c31[:-1] + [image, "--trace-cpu", map_file],
                           f"dpc31 bridge: --trace-cpu {map_file}: is the SDCC map {map_file}: "
                           "an output must not replace an input", log)
        with open(map_file, encoding="utf-8") as f:
            check(f.read() == "map\n", "the map was replaced")


CASES = {
    "c31_ack_trace": c31_ack_trace,
    "idle_timer_trace": idle_timer_trace,
    "c31_bad_arguments": c31_bad_arguments,
    "idle_timer_window": idle_timer_window,
    "trace_write_fails": trace_write_fails,
    "serial_port": serial_port,
}


if __name__ == "__main__":
    sys.exit(blt.main(CASES))
