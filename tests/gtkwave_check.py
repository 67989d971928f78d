#!/usr/bin/env python3
"""GTKWave 3.3 under Xvfb shows what our save files say (issue 33 items 3 and 4;
docs/waveforms.md "GTKWave", docs/wavediff.md "One file for a comparison").

Usage: gtkwave_check.py path/to/dpc31 SOURCE_DIR CASE [--screenshot PNG]
CASE demo: `dpc31 demo`; its full VCD has every signal once at #0; GTKWave opens
  dpc31-demo.gtkw and shows the groups pins, bus, state, blocks with their signals; one named
  marker at each DP and watchdog state change of the demo's state walk, at its time (cycle x
  10^12 / 48 MHz ps, rounded); at each marker the state trace named by the marker shows that
  state's name, and the buffer and diag traces show their filter's text.
CASE window, window_10ns: a window late in a run (--from 2885996 --to 2888108, Baud_Control at
  60 ms inside it) in units of 1 ps, or of 10 ns; GTKWave opens its save file on the window
  (docs/waveforms.md): the view begins at the window's first time, holds its last within 2 x its
  length, and every named marker is in it. GTKWave counts a 10 ns file in ns (its time x 10):
  its last time is --to's x 10, and so are the view and the markers.
CASE flat: a whole run in the logic-analyser form (--flat, 10 ns units by default); GTKWave's
  last time is the VCD's x 10, and the view opens on 0 and holds it within 2 x.
CASE merge_two_runs: two runs of startup_dpc31_1m5 whose slave inputs differ in one bit
  (B4h / B5h), `dpc31 wavediff --merge ab.fst`; fst2vcd reads it back: every diff.X is 1 exactly
  where the two runs' own VCDs give X different values (walked here, independently); GTKWave
  opens ab.gtkw on the whole merged file (from its first time, holding its last within 2 x) with
  one group per signal with a.X, b.X, diff.X; the first difference of TxD is in view, and there
  it shows diff 1, just before it 0.
  (demo, too: at the markers of Wait_Cfg the telegram service shows Set_Prm.)
GTKWave's Tcl interface (gtkwave -S) reports what it shows: the traces with their flags
(getTraceNameFromIndex, getTraceFlagsFromIndex: group begin 0x800000, end 0x1000000), named
markers (getNamedMarker) and a trace's value as displayed, after its translate filter
(getTraceValueAtNamedMarkerFromName, getTraceValueAtMarkerFromName).
Exit 0 if so, 1 with the differences.
"""

import os
import re
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

CLOCK_HZ = 48_000_000
GRP_BEGIN, GRP_END = 0x800000, 0x1000000
SRC = "."


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def run(cmd, ok=(0,), **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, check=False, **kw)
    if r.returncode not in ok:
        fail(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()[:400]}")
    return r.stdout


def gtkwave(save, tcl, d, screenshot=None):
    """Runs GTKWave on `save` under Xvfb with the Tcl script; its stdout."""
    script = Path(d) / "check.tcl"
    extra = []
    if screenshot:
        # The picture once GTKWave has drawn it: a timer script (-R, first run after -P ms, from
        # GTK's main loop) copies Xvfb's framebuffer (XWD, -fbdir) and quits.
        rep = Path(d) / "shot.tcl"
        rep.write_text(f"exec cp {d}/Xvfb_screen0 {d}/shot.xwd\ngtkwave::/File/Quit\n",
                       encoding="utf-8")
        extra = ["-R", str(rep), "-P", "3000"]
    script.write_text(tcl + ("" if screenshot else "gtkwave::/File/Quit\n"), encoding="utf-8")
    server = "-screen 0 1400x900x24" + (f" -fbdir {d}" if screenshot else "")
    out = run(["timeout", "120", "xvfb-run", "-a", "-s", server, "gtkwave", "-S", str(script),
               *extra, save])
    if screenshot:
        xwd_to_png(f"{d}/shot.xwd", screenshot)
    return out


def xwd_to_png(xwd, png):
    """Xvfb's framebuffer (XWD, 32 bits a pixel, TrueColor) as a PNG of its non-black part."""
    data = Path(xwd).read_bytes()
    h = struct.unpack(">25I", data[:100])
    header_size, width, height = h[0], h[4], h[5]
    byte_order, bpp, bpl, ncolors = h[7], h[11], h[12], h[19]
    if bpp != 32:
        fail(f"{xwd}: {bpp} bits a pixel, not 32")
    pix = data[header_size + 12 * ncolors:]
    order = "<I" if byte_order == 0 else ">I"
    rows = []
    for y in range(height):
        line = pix[y * bpl:y * bpl + 4 * width]
        row = bytearray()
        for x in range(width):
            v = struct.unpack_from(order, line, 4 * x)[0]
            row += bytes(((v >> 16) & 255, (v >> 8) & 255, v & 255))
        rows.append(bytes(row))
    # GTKWave's window sits at the top left of the black screen: keep its bounding box.
    used = [y for y, r in enumerate(rows) if r.strip(b"\0")]
    cols = [len(r.rstrip(b"\0")) // 3 for r in rows if r.strip(b"\0")]
    top, bottom, right = used[0], used[-1] + 1, max(cols)
    raw = b"".join(b"\0" + r[:3 * right] for r in rows[top:bottom])

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
    Path(png).write_bytes(b"\x89PNG\r\n\x1a\n" +
                          chunk(b"IHDR", struct.pack(">IIBBBBB", right, bottom - top, 8, 2, 0,
                                                     0, 0)) +
                          chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


TRACES_TCL = """set n [gtkwave::getTotalNumTraces]
for {set i 0} {$i < $n} {incr i} {
  puts "trace [gtkwave::getTraceFlagsFromIndex $i] [gtkwave::getTraceNameFromIndex $i]"
}
"""


def traces(out):
    """[(flags, name)] as GTKWave lists them."""
    return [(int(m.group(1)), m.group(2))
            for m in re.finditer(r"^trace (\d+) (.*)$", out, re.M)]


def groups(tr):
    """{group: [member names]} from the group-begin / group-end traces."""
    out, cur = {}, None
    for flags, name in tr:
        if flags & GRP_BEGIN:
            cur = name
            out[cur] = []
        elif flags & GRP_END:
            cur = None
        elif cur is not None:
            out[cur].append(name)
    return out


def units(cycle, per_second):
    # A cycle's time at 48 MHz: round(cycle x per_second / 48e6), halves up (docs/waveforms.md).
    return (cycle * per_second * 2 + CLOCK_HZ) // (2 * CLOCK_HZ)


def ps(cycle):
    return units(cycle, 10**12)


VIEW_TCL = ('puts "window [gtkwave::getWindowStartTime] [gtkwave::getWindowEndTime] '
            '[gtkwave::getMaxTime]"\n')


def last_time(vcd):
    """The last time step of a VCD."""
    return int(Path(vcd).read_text(encoding="ascii").rsplit("\n#", 1)[1].split()[0])


def view(out):
    """(start, end, last time) of the view GTKWave opened on, or None."""
    m = re.search(r"^window (\d+) (\d+) (\d+)$", out, re.M)
    return tuple(int(x) for x in m.groups()) if m else None


def vcd_changes(path):
    """{name: [(time, value)]} of a VCD (scopes joined by '.', no range)."""
    ids, scope, ch, t = {}, [], {}, 0
    with open(path, encoding="ascii") as f:
        body = False
        for line in f:
            w = line.split()
            if not w:
                continue
            if not body:
                if w[0] == "$scope":
                    scope.append(w[2])
                elif w[0] == "$upscope":
                    scope.pop()
                elif w[0] == "$var":
                    name = ".".join(scope + [w[4]])
                    ids.setdefault(w[3], []).append(name)
                    ch[name] = []
                elif w[0] == "$enddefinitions":
                    body = True
                continue
            if w[0].startswith("#"):
                t = int(w[0][1:])
            elif w[0][0] in "01xz" and len(w) == 1:
                for n in ids.get(w[0][1:], []):
                    ch[n].append((t, w[0][0]))
            elif w[0][0] == "b":
                for n in ids.get(w[1], []):
                    ch[n].append((t, w[0][1:].lstrip("0") or "0"))
    return ch


def value_at(changes, t):
    v = None
    for when, val in changes:
        if when > t:
            break
        v = val
    return v


def differs(a, b, end):
    """The stretches [from, to) where the two change lists hold different values."""
    times = sorted({t for t, _ in a} | {t for t, _ in b})
    out, start = [], None
    for t in times:
        d = value_at(a, t) != value_at(b, t)
        if d and start is None:
            start = t
        if not d and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, end))
    return out


def ones(changes, end):
    """The stretches where a 1-bit change list is 1."""
    out, start = [], None
    for t, v in changes:
        if v == "1" and start is None:
            start = t
        elif v != "1" and start is not None:
            if t != start:
                out.append((start, t))
            start = None
    if start is not None:
        out.append((start, end))
    return out


def case_demo(dpc31, d, screenshot):
    # A save file needs a waveform to open: one line, exit 2, nothing written.
    r = subprocess.run([dpc31, "run", f"{SRC}/traces/startup_dpc31_1m5.scn", "--quiet",
                        "--gtkw", f"{d}/alone.gtkw"], capture_output=True, text=True,
                       check=False)
    if r.returncode != 2 or len(r.stderr.splitlines()) != 1 or Path(f"{d}/alone.gtkw").exists():
        fail(f"--gtkw without --vcd: exit {r.returncode}, {r.stderr!r}")
    log = run([dpc31, "demo", "--out-dir", d])
    save = f"{d}/dpc31-demo.gtkw"
    if f"GTKWave save file (gtkwave {save}): {save}" not in log:
        fail("the demo does not name its GTKWave save file")
    # No pin twice at #0: every identifier once in the #0 block.
    text = Path(f"{d}/dpc31-demo.vcd").read_text(encoding="ascii")
    first = text.split("#0\n", 1)[1].split("\n#", 1)[0]
    ids = [ln[-1] if not ln.startswith("b") else ln.split()[1]
           for ln in first.splitlines() if ln and not ln.startswith("$")]
    if len(ids) != len(set(ids)):
        fail(f"a signal has two values at #0: {ids}")
    markers = [ln.split(" ", 1)[1] for ln in Path(save).read_text().splitlines()
               if ln.startswith("[markername] ")]
    tcl = TRACES_TCL + VIEW_TCL
    for m in markers:
        letter = m[0]
        tcl += (f'puts "marker {letter} [gtkwave::getNamedMarker {letter}]|'
                + "|".join(f"[gtkwave::getTraceValueAtNamedMarkerFromName {letter} "
                           f"{{dpc31.{s}}}]" for s in
                           ("state.dp_state[1:0]", "state.wd_state[1:0]",
                            "blocks.dout_sm[7:0]", "blocks.diag_sm[3:0]",
                            "state.baud_code[3:0]", "state.service[7:0]")) + '"\n')
    out = gtkwave(save, tcl, d, screenshot)
    problems = []
    want_groups = {"pins": ["rxd", "txd", "x_int", "pb3"],
                   "bus": ["rd", "wr", "addr[12:0]", "data[7:0]"],
                   "state": ["dp_state[1:0]", "wd_state[1:0]", "baud_code[3:0]",
                             "service[7:0]"],
                   "blocks": ["irr[15:0]", "dout_sm[7:0]", "din_sm[7:0]", "diag_sm[3:0]"]}
    got_groups = groups(traces(out))
    if got_groups != want_groups:
        problems.append(f"groups shown {got_groups}, want {want_groups}")
    # It opens on the whole run (docs/waveforms.md): from 0 to at least the VCD's last time.
    end = last_time(f"{d}/dpc31-demo.vcd")
    shown = view(out)
    if not shown or shown[0] != 0 or shown[1] < end:
        problems.append(f"GTKWave opens on {shown}, the run is 0..{end}")
    # A marker at each change of the state signals in the VCD, named by the state the walk
    # names for that change (the walk polls the states, so its cycles may come a little later:
    # never earlier).
    walk = [(int(m.group(1)), m.group(2), m.group(3)) for m in re.finditer(
        r"^\[cycle +(\d+)\] +(dp_state|wd_state) \S+ -> (\S+)", log, re.M)]
    vcd = vcd_changes(f"{d}/dpc31-demo.vcd")
    want = []
    for machine in ("dp_state", "wd_state"):
        changes = [t for t, _ in vcd[f"dpc31.state.{machine}"] if t > 0]
        names = [(c, n) for c, mm, n in walk if mm == machine]
        if len(changes) != len(names):
            problems.append(f"{machine}: {len(changes)} changes in the VCD, {len(names)} in the "
                            f"walk")
        for t, (c, n) in zip(changes, names):
            if ps(c) < t:
                problems.append(f"{machine} -> {n}: the walk at {ps(c)} ps, the VCD at {t}")
            want.append((t, f"{machine}={n}"))
    want.sort()
    shown = {}
    for m in re.finditer(r"^marker (\w) (-?\d+)\|(.*)$", out, re.M):
        shown[m.group(1)] = (int(m.group(2)), m.group(3).split("|"))
    got = sorted((shown[m[0]][0], m[1:]) for m in markers if m[0] in shown)
    if not want or got != want:
        problems.append(f"markers {got}, the state changes {want}")
    for m in markers:
        t, (dp, wd, dout, diag, baud, service) = shown.get(m[0], (None, [""] * 6))
        machine, state = m[1:].split("=")
        if (dp if machine == "dp_state" else wd) != state:
            problems.append(f"marker {m}: GTKWave shows dp_state {dp!r}, wd_state {wd!r}")
        if not re.fullmatch(r"F[-123] U[-123] N[-123] D[-123]", dout) or \
                not re.fullmatch(r"buf1 \w+, buf2 \w+", diag) or baud != "1.5Mbaud":
            problems.append(f"marker {m}: dout_sm {dout!r}, diag_sm {diag!r}, baud {baud!r}")
        # Set_Prm takes the slave from Wait_Prm to Wait_Cfg in the cycle it is acted on, which
        # is when state.service takes it.
        if m[1:] == "dp_state=Wait_Cfg" and service != "Set_Prm":
            problems.append(f"marker {m}: service {service!r}, want Set_Prm")
    print(f"demo: {len(got_groups)} groups, {len(got)} markers, states by name at each")
    return problems


def case_window(dpc31, d, unit):
    start_c, end_c = 2_885_996, 2_888_108
    # The unit, its units a second, and GTKWave's factor (it counts a 10 ns file in ns).
    per_second, scale = {"1ps": (10**12, 1), "10ns": (10**8, 10)}[unit]
    save = f"{d}/win.gtkw"
    run([dpc31, "run", "--quiet", f"{SRC}/traces/startup_dpc31_1m5.scn", "--vcd", f"{d}/win.vcd",
         "--timescale", unit, "--from", str(start_c), "--to", str(end_c), "--gtkw", save])
    markers = [ln.split(" ", 1)[1][0] for ln in Path(save).read_text().splitlines()
               if ln.startswith("[markername] ")]
    tcl = VIEW_TCL + "".join(f'puts "marker {m} [gtkwave::getNamedMarker {m}]"\n'
                             for m in markers)
    out = gtkwave(save, tcl, d)
    problems = []
    # --to is one past the last cycle written: the file's last time is end_c's.
    start, end = units(start_c, per_second) * scale, units(end_c, per_second) * scale
    shown = view(out)
    if not shown or shown[2] != end:
        problems.append(f"GTKWave's last time is {shown and shown[2]}, want {end}")
    if not shown or shown[0] != start or not end <= shown[1] <= start + 2 * (end - start):
        problems.append(f"GTKWave opens on {shown}, the window is {start}..{end}")
    at = {m.group(1): int(m.group(2)) for m in re.finditer(r"^marker (\w) (-?\d+)$", out, re.M)}
    if not markers or len(at) != len(markers):
        problems.append(f"markers {markers}, GTKWave shows {at}")
    for m, t in sorted(at.items()):
        if shown and not shown[0] <= t <= shown[1]:
            problems.append(f"marker {m} at {t} is out of the view {shown}")
    print(f"window at {unit}: GTKWave shows {shown}, the window {start}..{end}, {len(at)} markers "
          f"in it")
    return problems


def case_flat(dpc31, d):
    save = f"{d}/flat.gtkw"
    run([dpc31, "run", "--quiet", f"{SRC}/traces/startup_dpc31_1m5.scn", "--vcd", f"{d}/flat.vcd",
         "--flat", "--gtkw", save])
    problems = []
    if "$timescale 10ns $end" not in Path(f"{d}/flat.vcd").read_text(encoding="ascii"):
        problems.append("the logic-analyser form is not in 10 ns units")
    end = last_time(f"{d}/flat.vcd") * 10
    shown = view(gtkwave(save, VIEW_TCL, d))
    if not shown or shown[2] != end or shown[0] != 0 or not end <= shown[1] <= 2 * end:
        problems.append(f"GTKWave opens on {shown} (start, end, last time), the run is 0..{end}")
    print(f"flat: GTKWave shows {shown}, the run 0..{end}")
    return problems


def case_merge(dpc31, src, d):
    scn = Path(f"{src}/traces/startup_dpc31_1m5.scn").read_text(encoding="utf-8")
    if "inputs B1,B2,B3,B4" not in scn:
        fail("startup_dpc31_1m5.scn no longer sets inputs B1,B2,B3,B4")
    Path(f"{d}/a.scn").write_text(scn, encoding="utf-8")
    Path(f"{d}/b.scn").write_text(scn.replace("inputs B1,B2,B3,B4", "inputs B1,B2,B3,B5"),
                                  encoding="utf-8")
    for side in "ab":
        run([dpc31, "run", f"{d}/{side}.scn", "--quiet", "--vcd", f"{d}/{side}.vcd",
             "--signals", "pins.*,bus.*"], ok=(0, 1))
    run([dpc31, "wavediff", f"{d}/a.vcd", f"{d}/b.vcd", "--merge", f"{d}/ab.fst"], ok=(1,))
    run(["fst2vcd", "-o", f"{d}/ab.vcd", f"{d}/ab.fst"])
    a, b, m = vcd_changes(f"{d}/a.vcd"), vcd_changes(f"{d}/b.vcd"), vcd_changes(f"{d}/ab.vcd")
    end = max(t for ch in a.values() for t, _ in ch)
    problems = []
    first_txd = None
    for name in a:
        want = differs(a[name], b[name], end)
        got = ones(m.get(f"diff.{name}", []), end)
        if got != want:
            problems.append(f"diff.{name} is 1 over {got[:4]}, the runs differ over {want[:4]}")
        if name.endswith("pins.txd") and want:
            first_txd = want[0][0]
    if first_txd is None:
        problems.append("the two runs' TxD do not differ")
        return problems
    save = f"{d}/ab.gtkw"
    tcl = VIEW_TCL + TRACES_TCL + "".join(
        f'gtkwave::setMarker {t}\nputs "at {t} '
        f'[gtkwave::getTraceValueAtMarkerFromName diff.dpc31.pins.txd]"\n'
        for t in (first_txd - 1, first_txd))
    out = gtkwave(save, tcl, d)
    shown = view(out)
    merged_end = last_time(f"{d}/ab.vcd")
    if not shown or shown[2] != merged_end or shown[0] != 0 or \
            not merged_end <= shown[1] <= 2 * merged_end or not shown[0] <= first_txd <= shown[1]:
        problems.append(f"GTKWave opens on {shown} (start, end, last time), the merged file is "
                        f"0..{merged_end}, TxD differs first at {first_txd}")
    g = groups(traces(out))
    for name in a:
        leaf = name.split(".", 1)[1]
        if not any(k == name for k in g):
            problems.append(f"no group {name} in GTKWave")
            continue
        members = [re.sub(r"\[\d+:0\]$", "", x) for x in g[name]]
        if members != [f"a.{name}", f"b.{name}", f"diff.{name}"] and \
                [x.rsplit(".", 1)[-1] for x in members] != [leaf.rsplit(".", 1)[-1]] * 3:
            problems.append(f"group {name} shows {g[name]}")
    vals = dict(re.findall(r"^at (\d+) (\S*)$", out, re.M))
    if vals.get(str(first_txd - 1)) != "0" or vals.get(str(first_txd)) != "1":
        problems.append(f"GTKWave shows diff.dpc31.pins.txd {vals} around {first_txd}")
    print(f"merge_two_runs: {len(a)} signals, diff exactly where they differ; TxD first at "
          f"{first_txd} ps; {len(g)} groups in GTKWave")
    return problems


def case_segment(dpc31, d):
    """A segment's save file: the line and a group per station, each state by name at its
    station's markers (docs/waveforms.md, "Segments")."""
    save = f"{d}/two.gtkw"
    run([dpc31, "run", "--quiet", f"{SRC}/traces/segment/two_masters.scn", "--vcd", f"{d}/two.vcd",
         "--gtkw", save])
    markers = [ln.split(" ", 1)[1] for ln in Path(save).read_text().splitlines()
               if ln.startswith("[markername] ")]
    tcl = TRACES_TCL
    for m in markers:
        letter, station = m[0], m[1:].split(" ")[0]
        tcl += (f'puts "marker {letter} [gtkwave::getNamedMarker {letter}]|'
                + "|".join(f"[gtkwave::getTraceValueAtNamedMarkerFromName {letter} "
                           f"{{segment.{station}.{s}}}]" for s in
                           ("state.dp_state[1:0]", "state.wd_state[1:0]")) + '"\n')
    out = gtkwave(save, tcl, d)
    problems = []
    chip = ["rxd", "txd", "x_int", "rd", "wr", "addr[12:0]", "data[7:0]", "dp_state[1:0]",
            "wd_state[1:0]", "baud_code[3:0]", "service[7:0]", "irr[15:0]", "dout_sm[7:0]",
            "din_sm[7:0]", "diag_sm[3:0]"]
    want_groups = {"line": ["level", "driver[7:0]"], "station5_spc3": chip,
                   "station6_dpc31": chip[:3] + ["pb3"] + chip[3:]}
    got_groups = groups(traces(out))
    if got_groups != want_groups:
        problems.append(f"groups shown {got_groups}, want {want_groups}")
    vcd = vcd_changes(f"{d}/two.vcd")
    shown = {m.group(1): (int(m.group(2)), m.group(3).split("|"))
             for m in re.finditer(r"^marker (\w) (-?\d+)\|(.*)$", out, re.M)}
    if len(markers) != 8 or len(shown) != len(markers):
        problems.append(f"markers {markers}, shown {shown}")
    for m in markers:
        station, change = m[1:].split(" ")
        machine, state = change.split("=")
        t, (dp, wd) = shown.get(m[0], (None, ["", ""]))
        if (dp if machine == "dp_state" else wd) != state:
            problems.append(f"marker {m}: GTKWave shows dp_state {dp!r}, wd_state {wd!r}")
        if t not in [c for c, _ in vcd[f"segment.{station}.state.{machine}"]]:
            problems.append(f"marker {m} at {t}: no change of {station}'s {machine} there")
    print(f"segment: {len(got_groups)} groups, {len(shown)} markers, states by name at each")
    return problems


def main():
    global SRC
    dpc31, src, case = sys.argv[1:4]
    SRC = src
    shot = sys.argv[5] if len(sys.argv) > 5 and sys.argv[4] == "--screenshot" else None
    with tempfile.TemporaryDirectory() as d:
        problems = (case_demo(dpc31, d, shot) if case == "demo" else
                    case_segment(dpc31, d) if case == "segment" else
                    case_window(dpc31, d, "1ps") if case == "window" else
                    case_window(dpc31, d, "10ns") if case == "window_10ns" else
                    case_flat(dpc31, d) if case == "flat" else case_merge(dpc31, src, d))
    if problems:
        fail("\n".join(problems[:20]))
    print("ok")


if __name__ == "__main__":
    os.environ.pop("DISPLAY", None)
    main()
