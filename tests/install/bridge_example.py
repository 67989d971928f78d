#!/usr/bin/env python3
"""A firmware plug-in behind the installed `dpc31 bridge` (tests/install/check_install.cmake).

Usage: bridge_example.py DPC31 DP_MASTER PLUGIN CASE
  dx     the bridge with the plug-in (VPC3+, free pacing) and DP_MASTER (tools/dp_master.py) on
         its pty: the master reaches Data_Exchange and reads back its output byte 05 inverted
         (FA), the bridge logs the plug-in's port write and stops cleanly on SIGTERM;
  fatal  the same plug-in on a DPC31 (not the VPC3+C its driver checks for): the driver stops in
         its while(1) fatal-error loop, and the bridge's hang guard ends the run with one line
         on stderr, exit 2, and no symlink left behind.
Exit 0 when every check holds; the first failing check is printed. Python 3 standard library.
"""

import os
import signal
import subprocess
import sys
import tempfile
import time

SCALE = float(os.environ.get("DPC31_TIMEOUT_SCALE", "1"))


def fail(what):
    print(f"bridge_example: {what}", file=sys.stderr)
    sys.exit(1)


def start_bridge(dpc31, plugin, tmp, profile):
    link = os.path.join(tmp, "dp0")
    log = os.path.join(tmp, "bridge.log")
    proc = subprocess.Popen([dpc31, "bridge", "--pty", link, "--firmware", plugin, "--profile",
                             profile, "--pacing", "free", "--log", log],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return proc, link, log


def dx(dpc31, master, plugin):
    with tempfile.TemporaryDirectory() as tmp:
        proc, link, log = start_bridge(dpc31, plugin, tmp, "vpc3plus")
        try:
            m = subprocess.run([sys.executable, master, link, "--ident", "0x0E01", "--cfg", "20,10",
                                "--user-prm", "00", "--outputs", "05", "--cycles", "5",
                                # A loaded machine must not turn a slow search into a failure
                                # (issue 35); 2 s without an answer: the slave is lost (LOST in
                                # tests/bridge_test.py).
                                "--timeout", "2", "--search", str(20 * SCALE)],
                               capture_output=True, text=True, timeout=60 * SCALE, check=False)
            print(m.stdout, end="")
            if m.returncode != 0:
                fail(f"dp_master exit {m.returncode}: {m.stderr.strip()}")
            if "Data_Exchange 05: inputs FA" not in m.stdout:
                fail("no Data_Exchange answer with the inverted outputs FA")
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=10 * SCALE)
            if proc.returncode != 0 or err:
                fail(f"bridge exit {proc.returncode}, stderr {err!r}")
            with open(log, encoding="utf-8") as f:
                text = f.read()
            if "outputs = 0x05" not in text:
                fail("the bridge log lacks the plug-in's port write outputs = 0x05")
            if "dp_state Wait_Cfg -> Data_Exchange" not in text:
                fail("the bridge log lacks the step to Data_Exchange")
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def fatal(dpc31, plugin):
    with tempfile.TemporaryDirectory() as tmp:
        proc, link, _ = start_bridge(dpc31, plugin, tmp, "dpc31")
        try:
            t0 = time.monotonic()
            _, err = proc.communicate(timeout=30 * SCALE)
            took = time.monotonic() - t0
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            fail("the bridge did not stop on the firmware's fatal-error loop within 30 s")
        text = err.decode()
        print(text, end="")
        if proc.returncode != 2:
            fail(f"exit code {proc.returncode}, expected 2")
        if text.count("\n") != 1 or " hangs: it ran 2000 ms of host time" not in text:
            fail(f"stderr is not the hang guard's one line: {text!r}")
        if os.path.lexists(link):
            fail("the symlink was left behind")
        print(f"stopped after {took:.1f} s")


def main():
    if len(sys.argv) != 5 or sys.argv[4] not in ("dx", "fatal"):
        print(__doc__, file=sys.stderr)
        return 2
    dpc31, master, plugin, case = sys.argv[1:]
    if case == "dx":
        dx(dpc31, master, plugin)
    else:
        fatal(dpc31, plugin)
    print(f"ok {case} {os.path.basename(plugin)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
