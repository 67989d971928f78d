#!/usr/bin/env python3
"""End-to-end tests of `dpc31 bridge --cpu c31` (docs/bridge.md, docs/dpc31.md "The C31"), run by
CTest.

c31_ack_trace: the DPC31's C31 runs tests/mcs51/board/c31_ack.asm (as the build assembles it)
behind the pty, from the chip's RAM at --code 1000h; --trace-cpu has every step with its machine
cycle, PC and opcode exactly as the program's listing gives them (the machine cycles in brackets
in c31_ack.asm, the instruction set's cycle counts): the C31's interrupt, raised by its own MOVX
to Int_Req_Reg in [12,14), is called in [15,17), the vector's LJMP runs in [17,19) and the
routine starts at 004Eh in 19; the C31 at 24 MHz puts machine cycle m at chip cycle 24 m
(docs/cpu.md).

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

# (machine cycle, PC, opcode) of every step: the listing of c31_ack.asm (.org 30h on). The
# interrupt call is a step of its own, the hardware LCALL in [15,17), traced with the PC it
# interrupts (0040h, the return address); the vector's LJMP at 0003h follows in [17,19).
STEPS = [(0, 0x0000, 0x02), (2, 0x0030, 0x90), (4, 0x0033, 0x74), (5, 0x0035, 0xF0),
         (7, 0x0036, 0x75), (9, 0x0039, 0x90), (11, 0x003C, 0x74), (12, 0x003E, 0xF0),
         (14, 0x003F, 0x00), (15, 0x0040, 0x90), (17, 0x0003, 0x02), (19, 0x004E, 0x90),
         (21, 0x0051, 0x74), (22, 0x0053, 0xF0), (24, 0x0054, 0x32), (26, 0x0040, 0x90),
         (28, 0x0043, 0x74), (29, 0x0045, 0xF0), (31, 0x0046, 0x74), (32, 0x0048, 0x90),
         (34, 0x004B, 0xF0), (36, 0x004C, 0x80), (38, 0x004C, 0x80)]


def c31_ack():
    return os.path.join(os.path.dirname(os.path.abspath(bt.CLI)), "..", "tests", "mcs51", "board",
                        "c31_ack.ihx")


def c31_ack_trace():
    # The program needs 40 machine cycles, 960 chip cycles (20 us of chip time); free pacing runs
    # the chip with the wall clock while no client is connected. SIGTERM comes after the event
    # that shows chip time past them (not after a sleep, which beside a CPU hog could end before
    # the bridge ran that far): a client's open of the pty, logged with the cycle at which the
    # bridge saw it. A client that only opens and closes the pty changes nothing for the C31.
    need = 24 * (STEPS[-1][0] + 2)
    with tempfile.TemporaryDirectory() as tmp:
        trace = os.path.join(tmp, "c31.trace")
        b = bt.Bridge(tmp, "--cpu", "c31", "--firmware", c31_ack(), "--code", "0x1000",
                      "--profile", "dpc31", "--pacing", "free", "--trace-cpu", trace)
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
            check("c31_ack.ihx on the C31 at 24000000 Hz" in lines[0], f"log line 1: {lines[0]}")
            check("profile dpc31, irq-controller c31," in lines[0], f"log line 1: {lines[0]}")
            with open(trace, encoding="utf-8") as f:
                steps = f.read().splitlines()
            got = [line.split()[:4] for line in steps[:len(STEPS)]]
            want = [[str(24 * m), str(m), f"{pc:04X}", f"{op:02X}"] for m, pc, op in STEPS]
            check(got == want, f"the trace's first steps: {got}, expected {want}")
        finally:
            b.kill()


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
    "c31_bad_arguments": c31_bad_arguments,
}


if __name__ == "__main__":
    sys.exit(blt.main(CASES))
