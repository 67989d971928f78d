#!/usr/bin/env python3
"""PulseView 0.4.2 under Xvfb decodes the demo's capture with the session the demo writes
(docs/waveforms.md, "PulseView").

Usage: pulseview_check.py path/to/dpc31 SOURCE_DIR
       pulseview_check.py --self-check   (the comparison on doctored lists; no PulseView)

`dpc31 demo` writes dpc31-demo-la.vcd and, beside it, dpc31-demo-la.pvs. PulseView opens the
VCD as the page says (`pulseview -I vcd -i dpc31-demo-la.vcd`, SIGROKDECODE_DIR naming
lib/sigrok) and, by itself, the session setup of the same name: the UART decoder (8E1, 1.5
Mbaud, RX rxd, TX txd) with PROFIBUS DP stacked on it. The decoder's annotations never reach
PulseView's log (libsigrokdecode logs a put only for a decoder that has another stacked on it),
so the embedded Python reports them: a sitecustomize module (PYTHONPATH) wraps
sigrokdecode.Decoder.put and writes each of the profibus_dp decoder's telegram annotations to a
file. They must be exactly sigrok-cli's for the same stack on the same file (whose decoding the
Sigrok.profibus_dp_demo test checks against the demo's pcapng): every telegram, its sample
numbers and its text, in order, and no more. Once as many are there, PulseView gets a further
second to put any extra ones, is closed (SIGTERM, then SIGKILL after 5 s) and so is the Xvfb the
test started; the whole list it put is then compared (`got == want`): fewer, more or other
telegrams fail, and a run that has not shown them all in 60 s fails with what PulseView
printed. Nothing is installed here (setup.sh installs pulseview and
xvfb). Exit 0 if so, 1 with the reason.
"""

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DEADLINE_S = 60  # PulseView decodes the demo's 1.16 s (116 M samples) in about 5 s here

# Runs inside PulseView's Python (libsigrokdecode's) before any decoder is loaded.
HOOK = '''
import os
import sigrokdecode

_put = sigrokdecode.Decoder.put


def put(self, ss, es, output, data):
    if getattr(self, "id", "") == "profibus_dp" and isinstance(data, list):
        cls, texts = data
        if self.annotations[cls][0] == "telegram":
            with open(os.environ["DPC31_PV_PUTS"], "a", encoding="utf-8") as f:
                f.write("%d-%d %s\\n" % (ss, es, texts[0]))
    return _put(self, ss, es, output, data)


sigrokdecode.Decoder.put = put
'''


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, check=False, **kw)
    if r.returncode != 0:
        fail(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()[:400]}")
    return r.stdout


def stop(proc, name):
    """SIGTERM, then SIGKILL after 5 s: the process is gone when this returns."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            print(f"{name} did not end on SIGTERM within 5 s: SIGKILL")
            proc.kill()
            proc.wait()


def start_xvfb(d):
    """An Xvfb of our own on a free display (-displayfd: it writes the number when ready)."""
    r, w = os.pipe()
    with open(d / "xvfb.log", "w", encoding="utf-8") as log:
        xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-nolisten", "tcp", "-screen", "0",
                                 "1280x800x24"], pass_fds=(w,), stdout=subprocess.DEVNULL,
                                stderr=log)
    os.close(w)
    with os.fdopen(r) as f:
        display = f.readline().strip()
    if not display.isdigit():
        stop(xvfb, "Xvfb")
        fail(f"Xvfb gave no display: {(d / 'xvfb.log').read_text(encoding='utf-8')[-400:]}")
    return xvfb, f":{display}"


def telegrams(lines):
    """'SS-ES text' lines as (ss, es, text)."""
    out = []
    for line in lines:
        span, _, text = line.partition(" ")
        ss, _, es = span.partition("-")
        out.append((int(ss), int(es), text))
    return out


def mismatch(got, want):
    """Why PulseView's telegrams are not sigrok-cli's, or None: the whole lists, in order."""
    if got == want:
        return None
    for i, (g, w) in enumerate(zip(got, want)):
        if g != w:
            return (f"telegram {i + 1}: PulseView {g[0]}-{g[1]} '{g[2]}', sigrok-cli "
                    f"{w[0]}-{w[1]} '{w[2]}'")
    if len(got) > len(want):
        g = got[len(want)]
        return (f"PulseView put {len(got)} telegrams, sigrok-cli decodes {len(want)}: the first "
                f"extra one is {g[0]}-{g[1]} '{g[2]}' (a decoder stacked twice?)")
    return f"PulseView put {len(got)} of the {len(want)} telegrams sigrok-cli decodes"


def self_check():
    """mismatch() on doctored lists: each difference is found, equal lists pass."""
    want = [(10, 20, "Request SRD_high 2 -> 5: Set_Prm"), (30, 40, "Short acknowledge SC")]
    cases = [
        (list(want), None),
        (want + [want[1]], "PulseView put 3 telegrams, sigrok-cli decodes 2: the first extra one "
                           "is 30-40 'Short acknowledge SC' (a decoder stacked twice?)"),
        (want[:1], "PulseView put 1 of the 2 telegrams sigrok-cli decodes"),
        ([want[0], (30, 41, want[1][2])],
         "telegram 2: PulseView 30-41 'Short acknowledge SC', sigrok-cli 30-40 "
         "'Short acknowledge SC'"),
    ]
    for got, why in cases:
        if mismatch(got, want) != why:
            fail(f"mismatch({got}) gave {mismatch(got, want)!r}, expected {why!r}")
    print(f"OK: the comparison caught all {len(cases) - 1} doctored lists")


def main():
    if sys.argv[1:] == ["--self-check"]:
        self_check()
        return
    if len(sys.argv) != 3:
        fail(__doc__.split("\n\n")[1])
    dpc31, src = sys.argv[1], Path(sys.argv[2])
    for tool in ("pulseview", "Xvfb", "sigrok-cli"):
        if shutil.which(tool) is None:
            fail(f"{tool} is not installed: ./setup.sh installs it (Debian's pulseview, xvfb, "
                 "sigrok-cli)")
    decoders = src / "lib" / "sigrok"
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        run([dpc31, "demo", "--out-dir", str(d / "demo")])
        vcd = d / "demo" / "dpc31-demo-la.vcd"
        if not (d / "demo" / "dpc31-demo-la.pvs").is_file():
            fail("dpc31 demo wrote no dpc31-demo-la.pvs beside dpc31-demo-la.vcd")
        # The truth: sigrok-cli's decode of the same stack.
        cli = run(["sigrok-cli", "-I", "vcd", "-i", str(vcd), "-P",
                   "uart:rx=rxd:tx=txd:baudrate=1500000:parity=even,profibus_dp", "-A",
                   "profibus_dp=telegram", "--protocol-decoder-samplenum"],
                  env=dict(os.environ, SIGROKDECODE_DIR=str(decoders)))
        want = telegrams(line.replace(" profibus_dp-1: ", " ", 1) for line in cli.splitlines())
        if not any(t[2] == "Request SRD_high 2 -> 5: Set_Prm" for t in want):
            fail(f"sigrok-cli decoded no Set_Prm of the demo: {cli[:400]}")

        (d / "hook").mkdir()
        (d / "hook" / "sitecustomize.py").write_text(HOOK, encoding="utf-8")
        (d / "cfg").mkdir()
        (d / "rt").mkdir(mode=0o700)
        puts = d / "puts.txt"
        env = dict(os.environ, SIGROKDECODE_DIR=str(decoders), PYTHONPATH=str(d / "hook"),
                   DPC31_PV_PUTS=str(puts), XDG_CONFIG_HOME=str(d / "cfg"),
                   XDG_RUNTIME_DIR=str(d / "rt"))
        xvfb, display = start_xvfb(d)
        env["DISPLAY"] = display
        env.pop("QT_QPA_PLATFORM", None)
        log = d / "pulseview.log"
        t0 = time.monotonic()
        pv = None
        got = []
        try:
            # -c: no sessions restored, -D: no device scan; the rest is the page's command line.
            with open(log, "w", encoding="utf-8") as out:
                pv = subprocess.Popen(["pulseview", "-c", "-D", "-I", "vcd", "-i", str(vcd)],
                                      env=env, stdout=out, stderr=subprocess.STDOUT)
            while time.monotonic() - t0 < DEADLINE_S and pv.poll() is None:
                time.sleep(0.2)
                if puts.exists():
                    got = telegrams(puts.read_text(encoding="utf-8").splitlines())
                if len(got) >= len(want):
                    time.sleep(1)  # room for any telegram beyond sigrok-cli's
                    break
        finally:
            exited = pv.poll() if pv else None
            if pv:
                stop(pv, "PulseView")
            stop(xvfb, "Xvfb")
        took = time.monotonic() - t0
        said = log.read_text(encoding="utf-8", errors="replace").strip()[-600:]
        # The whole list PulseView put, read after it stopped.
        if puts.exists():
            got = telegrams(puts.read_text(encoding="utf-8").splitlines())
        if len(got) < len(want):
            why = (f"PulseView exited ({exited})" if exited is not None
                   else f"in {DEADLINE_S} s")
            fail(f"{why}, PulseView's PROFIBUS DP decoder put {len(got)} of the {len(want)} "
                 f"telegrams sigrok-cli decodes (no decoder stack from dpc31-demo-la.pvs?); "
                 f"PulseView printed: {said}")
        why = mismatch(got, want)
        if why is not None:
            fail(why)
        print(f"OK: PulseView decoded the demo's {len(want)} telegrams as sigrok-cli does "
              f"({took:.1f} s)")


if __name__ == "__main__":
    main()
