#!/usr/bin/env python3
"""Summarises fuzz logs written by tests/fuzz/run.sh: tests/fuzz/stats.py WORK_DIR/*/fuzz.log

One markdown row per log: executions, exec/s, cov and ft of libFuzzer's last status line, the
corpus (entries / bytes), the duration, and how the run ended."""
import re
import sys

print("| target | executions | exec/s | cov | ft | corpus | duration | end |")
print("|---|---|---|---|---|---|---|---|")
for path in sys.argv[1:]:
    text = open(path, errors="replace").read()
    name = path.rstrip("/").split("/")[-2]
    status = re.findall(r"cov: (\d+) ft: (\d+) corp: (\d+)/(\d+\w*)", text)
    cov, ft, corp, size = status[-1] if status else ("?",) * 4
    execs = re.search(r"stat::number_of_executed_units: (\d+)", text)
    rate = re.search(r"stat::average_exec_per_sec:\s+(\d+)", text)
    done = re.search(r"Done (\d+) runs in (\d+) second", text)
    secs = done.group(2) if done else "?"
    if not execs:  # fork mode: "#N: cov: ... exec/s: R ... time: Ss"
        fork = re.findall(r"#(\d+): cov: (\d+) ft: (\d+) corp: (\d+) exec/s:? \d+ "
                          r"oom/timeout/crash: (\d+)/(\d+)/(\d+) time: (\d+)s", text)
        if fork:
            n, cov, ft, corp, oom, to, crash, secs = fork[-1]
            size = "-"
            execs_s, rate_s = n, str(int(n) // max(1, int(secs)))
            end = f"fork mode: {crash} crashes, {to} time-outs, {oom} OOMs (ignored, see findings)"
        else:
            execs_s = rate_s = "?"
            end = "?"
    else:
        execs_s, rate_s = execs.group(1), rate.group(1)
        m = re.search(r"SUMMARY: (.*)", text)
        end = m.group(1) if m else ("no crash, hang or leak" if done else "?")
    print(f"| {name} | {execs_s} | {rate_s} | {cov} | {ft} | {corp} / {size} | {secs} s | {end} |")
