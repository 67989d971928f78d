#!/usr/bin/env python3
"""The sigrok decoder profibus_dp (lib/sigrok/profibus_dp) against the truth of a run (issue 33
item 2; docs/waveforms.md).

Usage: sigrok_profibus_dp.py path/to/dpc31 SOURCE_DIR CASE
CASE: demo, or a scenario of traces/ (startup_dpc31_9k6, startup_dpc31_1m5, startup_dpc31_12m,
faults, ...).

Runs the case with the waveform for logic-analyser tools and the pcapng, then
`sigrok-cli -P uart:rx=rxd:tx=txd:...,profibus_dp` with the decoder from SOURCE_DIR/lib/sigrok.
The truth is the pcapng (every telegram the chip received without error and every answer it
sent, bytes SD..ED, its first start bit and the end of its last stop bit in cycles: the
`cycles START-END` comment, docs/capture.md) and the run's state walk for what the chip did not
take: the master's requests during the baud search ("=> no answer (xN, last at cycle C)": an
FDL_Status SD1, 6 characters back to back) and the requests a fault scenario broke ("[parity
error in char 3] => no answer": the request's bytes as logged, its start cycle).

Checked, with T the bit time:
- every telegram the decoder shows without error is one of the truth's, byte for byte, and starts
  when the truth says (within one T); every truth telegram is decoded;
- every gap the decoder gives (the idle time before a telegram, TSDR before an answer) equals the
  truth's (start minus the previous telegram's end) within one T, wherever both ends are known
  to the cycle;
- every broken request of the state walk comes out as a broken telegram at its time, with the
  error the walk names (parity error, stop bit error, FCS); nothing else is broken, no warning
  but the "No answer" of requests the chip did not answer.
Exit 0 if so, 1 with the differences.
"""

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from waveform_sigrok_demo import fail, fail_if, pcapng_blocks, timescale_ns  # noqa: E402

CLOCK_HZ = 48_000_000
# The walk's fault tag -> the decoder's error text (emu/mac.cpp counts a shifted character
# without its start bit as the parity error it samples; sigrok's uart decoder does the same).
FAULTS = {"parity error": "parity error", "stop bit 0": "stop bit error",
          "bad FCS": "FCS", "no start bit": "parity error"}


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, check=False, **kw)
    if r.returncode not in (0,):
        fail(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()[:400]}")
    return r.stdout


def sd1(da, sa, fc):
    body = bytes([da, sa, fc])
    return bytes([0x10]) + body + bytes([sum(body) & 0xFF, 0x16])


def walk_requests(log, baud):
    """(start cycle or None, bytes or None, fault or None, (first, last, length in cycles) or None,
    unanswered) of the requests the chip did not take: the baud search's FDL_Status (first and
    last of a run of N exact, the others within) and the broken ones."""
    out = []
    cyc_bit = CLOCK_HZ / baud
    for m in re.finditer(r"\[cycle +(\d+)\] (\d+) -> (\d+) FDL_Status => no answer"
                         r"(?: \(x(\d+), last at cycle (\d+)\))?", log):
        first, sa, da = int(m.group(1)), int(m.group(2)), int(m.group(3))
        n, last = int(m.group(4) or 1), int(m.group(5) or first)
        frame = sd1(da, sa, 0x49)
        for i in range(n):
            exact = first if i == 0 else last if i == n - 1 else None
            out.append((exact, frame, None, (first, last, len(frame) * 11 * cyc_bit)))
    out = [(s, f, None, r, True) for s, f, _, r in out]
    for m in re.finditer(r"\[cycle +(\d+)\] \d+ -> \d+ .*\[([a-zA-Z0-9 ]+?)(?: in char "
                         r"(\d+))?\]( => no answer)?", log):
        fault = m.group(2)
        if fault not in FAULTS:
            fail(f"the walk names a fault this test does not know: {fault!r}")
        # The walk counts characters from 0, the decoder's bytes from 1.
        where = f" in byte {int(m.group(3)) + 1}" if m.group(3) and fault != "no start bit" else ""
        out.append((int(m.group(1)), None, FAULTS[fault] + where, None, bool(m.group(4))))
    return out


def decode(vcd, baud, srcdir, downsample):
    """The decoder's bytes, timing and error annotations: [(ss, es, class-row, text)]."""
    env = dict(os.environ, SIGROKDECODE_DIR=f"{srcdir}/lib/sigrok")
    out = run(["sigrok-cli", "-I", f"vcd:downsample={downsample}", "-i", vcd, "-P",
               f"uart:rx=rxd:tx=txd:baudrate={baud}:parity=even,profibus_dp",
               "-A", "profibus_dp=bytes:idle:tsdr:error:warning:telegram",
               "--protocol-decoder-samplenum"], env=env)
    anns = []
    for line in out.splitlines():
        m = re.fullmatch(r"(\d+)-(\d+) profibus_dp-1: (.*)", line.strip())
        if not m:
            fail(f"not an annotation: {line!r}")
        anns.append((int(m.group(1)), int(m.group(2)), m.group(3)))
    return anns


def produce(dpc31, srcdir, case, d):
    """Runs the case: (log, la vcd, pcapng, sigrok's downsampling factor)."""
    if case == "demo":
        log = run([dpc31, "demo", "--out-dir", d])
        return log, f"{d}/dpc31-demo-la.vcd", f"{d}/dpc31-demo.pcapng", 1
    scn = f"{srcdir}/traces/{case}.scn"
    text = Path(scn).read_text(encoding="utf-8")
    baud = int(re.search(r"^baud (\d+)", text, re.M).group(1))
    # 10 ns samples from 187.5 kbaud up; 1 us (104 samples a bit) at 9.6 kbaud, where 10 ns
    # would be 10^4 samples a bit for the uart decoder to walk: sigrok downsamples the 10 ns file
    # (a unit longer than a clock cycle is refused when it is written).
    log = run([dpc31, "run", scn, "--la-vcd", f"{d}/la.vcd", "--pcap", f"{d}/run.pcapng"])
    return log, f"{d}/la.vcd", f"{d}/run.pcapng", 100 if baud < 100_000 else 1


def main():
    dpc31, srcdir, case = sys.argv[1:4]
    with tempfile.TemporaryDirectory() as d:
        log, vcd, pcap, downsample = produce(dpc31, srcdir, case, d)
        m = re.search(r"master \d+ -> slave \d+ at (\d+) baud", log)
        if not m:
            fail("the log states no baud rate")
        baud = int(m.group(1))
        cyc_bit = CLOCK_HZ / baud           # cycles per bit
        unit_cyc = timescale_ns(vcd) * downsample * CLOCK_HZ / 1e9  # cycles per sample
        truth = []  # (start, end or None, bytes or None, fault, (lo, hi) start range)
        for _, _, payload, comment in pcapng_blocks(pcap):
            c = re.fullmatch(r"cycles (\d+)-(\d+)", comment or "")
            if not c:
                fail(f"{pcap}: a packet without its cycles comment")
            s, e = int(c.group(1)), int(c.group(2))
            truth.append((s, e, payload, None, (s, s)))
        walk = walk_requests(log, baud)
        want_no_answer = sum(1 for w in walk if w[4])
        for start, frame, fault, rng, _ in walk:
            if frame is not None:
                end = start + rng[2] if start is not None else None
                truth.append((start, end, frame, None, (rng[0], rng[1])))
            else:
                truth.append((start, None, None, fault, (start, start)))
        truth.sort(key=lambda t: t[4][0])

        anns = decode(vcd, baud, srcdir, downsample)
        got = []  # (start cycle, end cycle, bytes, [errors], gap text or None)
        errors_at, warnings = [], []
        for ss, es, text in anns:
            if re.fullmatch(r"([0-9A-F]{2} ?)+", text):
                got.append([ss * unit_cyc, es * unit_cyc, bytes.fromhex(text), [], None])
            elif re.fullmatch(r"(Idle (>= )?|TSDR )\d+\.\d bit times", text):
                got.append(("gap", ss * unit_cyc, es * unit_cyc, text))
            elif text.startswith("Broken telegram"):
                errors_at.append((ss * unit_cyc, text))
            elif text.startswith("No answer"):
                warnings.append(("no answer", ss * unit_cyc))
            elif re.match(r"(Late|Idle .* < TSYN)", text):
                warnings.append((text, ss * unit_cyc))
        tels = [g for g in got if g[0] != "gap"]
        gaps = {round(g[2]): g for g in got if g[0] == "gap"}  # keyed by the telegram's start

        problems = []
        tol = cyc_bit
        broken_truth = [t for t in truth if t[3] is not None]
        good_truth = [t for t in truth if t[3] is None]
        # Broken telegrams: one at each broken request's start, with the walk's error.
        for t in broken_truth:
            hit = [e for e in errors_at if abs(e[0] - t[0]) <= tol]
            if not hit:
                problems.append(f"the broken request at cycle {t[0]} ({t[3]}) is not decoded "
                                f"as broken")
            elif t[3] not in hit[0][1]:
                problems.append(f"cycle {t[0]}: expected {t[3]}, decoded {hit[0][1]!r}")
        for e in errors_at:
            if not any(abs(e[0] - t[0]) <= tol for t in broken_truth):
                problems.append(f"cycle {e[0]:.0f}: decoded {e[1]!r}, the walk has no fault there")
        broken_starts = [e[0] for e in errors_at]
        good = [g for g in tels if not any(abs(g[0] - b) <= tol for b in broken_starts)]
        # Good telegrams, in order, one for one.
        for i in range(max(len(good), len(good_truth))):
            g = good[i] if i < len(good) else None
            t = good_truth[i] if i < len(good_truth) else None
            if g is None or t is None:
                problems.append(f"telegram {i}: decoded {g and g[2].hex(' ')} at "
                                f"{g and round(g[0])}, truth {t and t[2].hex(' ')} at "
                                f"{t and t[4][0]}")
                continue
            lo, hi = t[4]
            if g[2] != t[2] or not lo - tol <= g[0] <= hi + tol:
                problems.append(f"telegram {i}: decoded {g[2].hex(' ')} at cycle {g[0]:.0f}, "
                                f"truth {t[2].hex(' ')} at {lo}..{hi}")
        # Gaps where both ends are exact: this telegram's start and the previous one's end.
        checked = 0
        for prev, t in zip(truth, truth[1:]):
            if t[0] is None or prev[1] is None or t[3] is not None:
                continue
            want = (t[0] - prev[1]) / cyc_bit
            g = next((v for k, v in gaps.items() if abs(k - t[0]) <= tol), None)
            if g is None:
                problems.append(f"no gap annotation before the telegram at cycle {t[0]}")
                continue
            m = re.search(r"(\d+\.\d)", g[3])
            have = float(m.group(1))
            if abs(have - want) > 1.0:
                problems.append(f"gap before cycle {t[0]}: decoded {g[3]!r}, truth {want:.2f}")
            checked += 1
        no_answer = sum(1 for w in warnings if w[0] == "no answer")
        others = [w for w in warnings if w[0] != "no answer"]
        if no_answer != want_no_answer:
            problems.append(f"{no_answer} requests marked 'No answer', the walk has "
                            f"{want_no_answer} the chip did not answer")
        if others:
            problems.append(f"unexpected warnings: {others[:5]}")
        print(f"{case}: {len(good)} telegrams decoded, {len(good_truth)} in the truth, "
              f"{len(errors_at)} broken ({len(broken_truth)} in the walk), {checked} gaps "
              f"checked, {no_answer} requests without answer")
        fail_if(problems)
    print("ok")


if __name__ == "__main__":
    main()
