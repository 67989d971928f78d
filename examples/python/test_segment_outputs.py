"""A segment's waveforms and the pcapng of its line from Python (docs/python.md, "A segment";
docs/segment.md, "Outputs"): a segment scenario writes through SegmentScenario.run the same bytes
as `dpc31 run` of it; a Segment built call by call writes its line as pcapng that tshark decodes
with the shipped dissector (lib/capture/profibus_dl.lua), each telegram at its first start bit
(docs/capture.md, "A segment's line": ns = round(cycle x 10^9 / 48 MHz)) with its sender and who
answered it; bad paths are one clear dpc31.Error and leave nothing behind.
"""

import os
import pathlib
import signal
import subprocess
import sys

import pytest

import dpc31

CLOCK_HZ = 48_000_000
T = 32  # clocks a bit at 1.5 Mbaud (docs/timing.md)


def tshark_fields(traces, pcap, tmp_path):
    lua = pathlib.Path(traces).parent / "lib" / "capture" / "profibus_dl.lua"
    env = dict(os.environ, HOME=str(tmp_path), XDG_CONFIG_HOME=str(tmp_path))
    out = subprocess.run(
        ["tshark", "-n", "-X", f"lua_script:{lua}", "-r", str(pcap), "-T", "fields",
         "-E", "separator=|", "-e", "frame.time_epoch", "-e", "frame.comment",
         "-e", "profibus.sd"],
        env=env, capture_output=True, text=True, check=True).stdout
    return [line.split("|") for line in out.splitlines()]


@pytest.mark.parametrize("name", ["two_masters", "three_slaves"])
def test_a_scenarios_outputs_are_those_of_dpc31_run(cli, traces, tmp_path, name):
    scn = str(traces / "segment" / f"{name}.scn")
    subprocess.run([cli, "run", scn, "--quiet", "--vcd", str(tmp_path / "cli.vcd"),
                    "--fst", str(tmp_path / "cli.fst"), "--pcap", str(tmp_path / "cli.pcapng")],
                   check=True)
    result = dpc31.SegmentScenario.load(scn).run(vcd=str(tmp_path / "py.vcd"),
                                                 fst=str(tmp_path / "py.fst"),
                                                 pcapng=str(tmp_path / "py.pcapng"))
    assert result.ok, result.failures
    for ext in ("vcd", "pcapng"):
        assert (tmp_path / f"py.{ext}").read_bytes() == (tmp_path / f"cli.{ext}").read_bytes(), ext
    # An FST's header holds the time it was written: its changes are compared.
    report = dpc31.wavediff(str(tmp_path / "cli.fst"), str(tmp_path / "py.fst"))
    assert report.same and not report.only_a and not report.only_b, report.text()


def test_a_segments_line_decodes_in_tshark(traces, tmp_path):
    seg = dpc31.Segment(1_500_000, vcd=str(tmp_path / "seg.vcd"),
                        pcapng=str(tmp_path / "seg.pcapng"))
    seg.add_station(5, "spc3", firmware="DO4", name="spc3", wd=(1, 1))
    seg.add_station(6, "dpc31", firmware="DO4", wd=(1, 1))
    master = seg.add_master(2, [5, 6])
    line = []
    seg.on_telegram(line.append)
    assert master.startup_all()
    exchanges = master.dp_cycle()
    assert not (tmp_path / "seg.pcapng").exists()  # nothing before close()
    seg.close()
    assert [ex.answer_start - ex.request_end for ex in exchanges] == [11 * T] * 2  # TSDR

    rows = tshark_fields(traces, tmp_path / "seg.pcapng", tmp_path)
    assert len(rows) == len(line) > 10
    names = {5: "spc3", 6: "station 6"}
    for i, (t, (epoch, comment, sd)) in enumerate(zip(line, rows)):
        ns = (t.start * 10**9 + CLOCK_HZ // 2) // CLOCK_HZ
        assert epoch == f"{ns // 10**9}.{ns % 10**9:09d}", i
        want = f"cycles {t.start}-{t.end}, {seg.name(t.sender)}"
        # A slave's telegram right after the master's is its answer (SD4 tokens: none here).
        if seg.name(t.sender) != "master 2":
            want += ", answer to master 2"
        elif i + 1 < len(line) and seg.name(line[i + 1].sender) != "master 2":
            want += f", answered by {seg.name(line[i + 1].sender)}"
        assert comment == want, i
        assert int(sd, 16) == t.bytes[0], i
    assert set(seg.name(t.sender) for t in line) == {"master 2", *names.values()}

    vcd = (tmp_path / "seg.vcd").read_text()
    header = vcd.split("$enddefinitions", 1)[0]
    for scope in ("segment", "line", "station5_spc3", "station6"):
        assert f"$scope module {scope} $end" in header, scope
    assert header.count("$var wire 1 ") > 2 and " level $end" in header and " driver $end" in header


def test_a_parity_error_is_marked_in_the_pcap_and_the_bus_check(traces, tmp_path):
    """The audit's py_parity_pcap.py: an FDL_Status to station 5 with the parity bit of its FCS
    (character 4) inverted reads as good bytes, but the chip discards it (docs/timing.md
    "Telegrams": one parity error, no answer), so the line's view says so too: the LineTelegram's
    fault, the bus check's bad_frame (docs/segment.md "Bus checks") and, in the pcapng, the comment
    and the symbol error flag that the dissector shows as profibus.char_error (docs/capture.md)."""
    seg = dpc31.Segment(1_500_000, pcapng=str(tmp_path / "parity.pcapng"))
    s5 = seg.add_station(5, "spc3")
    master = seg.add_master(2, [5])
    rogue = seg.add_sender("rogue")
    check = seg.check_bus()
    assert master.startup_all()
    before = dict(s5.fdl_counters)
    line = []
    seg.on_telegram(line.append)
    request = bytes([0x10, 5, 2, 0x49, 0x50, 0x16])
    start = seg.cycle + 40 * T
    end = seg.send(rogue, request, start=start, fault="parity", fault_char=4)
    assert end == start + 6 * 11 * T
    seg.run_until(end + 300 * T)
    assert {k: s5.fdl_counters[k] - before[k] for k in before
            if s5.fdl_counters[k] != before[k]} == {"parity": 1}
    # The start-up's last answer (closed once the line stayed idle past it), then the request.
    assert [(t.sender, t.start, t.end, t.bytes, t.fault, t.fault_char) for t in line[-1:]] == [
        (rogue, start, end, request, "parity", 4)]
    assert all(t.fault is None and t.fault_char is None for t in line[:-1]) and len(line) == 2
    assert {k: v for k, v in check.counts.items() if v} == {"bad_frame": 1}
    assert seg.bus_log[-1] == (f"[cycle {start}] bus: bad_frame: 6 bytes from cycle {start} do "
                               "not decode (character 4: parity error)")
    seg.close()
    lua = pathlib.Path(traces).parent / "lib" / "capture" / "profibus_dl.lua"
    env = dict(os.environ, HOME=str(tmp_path), XDG_CONFIG_HOME=str(tmp_path))
    out = subprocess.run(
        ["tshark", "-n", "-X", f"lua_script:{lua}", "-r", str(tmp_path / "parity.pcapng"),
         "-T", "fields", "-E", "separator=|", "-e", "frame.comment",
         "-e", "frame.packet_flags_symbol_error", "-e", "profibus.fcs_ok", "-e", "_ws.expert"],
        env=env, capture_output=True, text=True, check=True).stdout
    rows = [r.split("|") for r in out.splitlines()]
    # The master's start-up (every telegram good, none flagged), then the rogue's request.
    assert all(r[1] in ("0", "False") and "Malformed" not in r[3] for r in rows[:-1])
    comment, symbol_error, fcs_ok, expert = rows[-1]
    assert comment == f"cycles {start}-{end}, rogue, character 4: parity error"
    assert symbol_error in ("1", "True") and fcs_ok in ("1", "True")
    assert ("(Error/Malformed): A character with a parity, start or stop bit error (pcapng "
            "symbol error)") in expert


def test_bad_paths_and_late_stations_are_clear_errors(traces, tmp_path):
    missing = tmp_path / "no" / "such"
    with pytest.raises(dpc31.Error, match="no/such/seg.vcd"):
        dpc31.Segment(1_500_000, vcd=str(missing / "seg.vcd"))
    with pytest.raises(dpc31.Error, match="no/such/seg.pcapng"):
        dpc31.Segment(1_500_000, pcapng=str(missing / "seg.pcapng"))
    scn = dpc31.SegmentScenario.load(str(traces / "segment" / "two_masters.scn"))
    with pytest.raises(dpc31.Error, match="no/such/two.fst"):
        scn.run(vcd=str(tmp_path / "two.vcd"), fst=str(missing / "two.fst"))
    with pytest.raises(dpc31.Error, match="no signal matches 'nothing.*'"):
        scn.run(vcd=str(tmp_path / "two.vcd"), signals=["nothing.*"])
    # nothing written, no temporary left (.dpc31-PID.tmp, docs/bad-input.md)
    assert not list(tmp_path.glob("two*")) and not list(tmp_path.glob(".dpc31-*"))
    seg = dpc31.Segment(1_500_000, vcd=str(tmp_path / "glob.vcd"),
                        pcapng=str(tmp_path / "glob.pcapng"), signals=["nothing.*"])
    seg.add_station(5, "spc3")
    with pytest.raises(dpc31.Error, match="no signal matches 'nothing.*'"):
        seg.run_until(1000)
    # Its temporaries go at the error, not when the segment is collected (audit s29 a-py
    # finding 9), and every later call and close() say the same.
    assert not list(tmp_path.glob("glob*")) and not list(tmp_path.glob(".dpc31-*"))
    for call in (lambda: seg.run_until(2000), seg.close):
        with pytest.raises(dpc31.Error, match="no signal matches 'nothing.*'"):
            call()
    assert not list(tmp_path.glob("glob*")) and not list(tmp_path.glob(".dpc31-*"))

    seg = dpc31.Segment(1_500_000, pcapng=str(tmp_path / "late.pcapng"))
    seg.add_station(5, "spc3")
    seg.run_until(1000)
    with pytest.raises(dpc31.Error, match="joins before the line first runs"):
        seg.add_station(6, "spc3")
    with pytest.raises(dpc31.Error, match="joins before the line first runs"):
        seg.add_sender("rogue")
    seg.close()
    assert (tmp_path / "late.pcapng").exists()


def test_scenario_load_names_the_segment_loader(traces):
    path = str(traces / "segment" / "three_slaves.scn")
    with pytest.raises(dpc31.ScenarioError) as e:
        dpc31.Scenario.load(path)
    assert e.value.file == path and e.value.line == 33  # the `segment` line
    assert "segment scenario" in e.value.reason
    assert "SegmentScenario" in e.value.reason and "dpc31 run" in e.value.reason


@pytest.mark.parametrize("kind", ["vcd", "fst", "pcapng"])
def test_the_segment_runs_on_after_close(tmp_path, kind):
    # close() writes the files and drops the writers; the observers they put on the line and the
    # chips stay and do nothing, so the segment runs on (it crashed in them) and the file stays.
    path = tmp_path / f"after.{kind}"
    seg = dpc31.Segment(1_500_000, **{kind: str(path)})
    seg.add_station(5, "spc3")
    master = seg.add_master(2, [5])
    seg.run_until(10_000)
    seg.close()
    written = path.read_bytes()
    assert master.startup()
    seg.run_until(seg.cycle + 2_000_000)
    seg.close()
    assert path.read_bytes() == written


def test_an_output_that_is_an_input_or_another_output_is_refused(traces, tmp_path):
    # `dpc31 run`'s check (outfile::distinct) and its line, before anything is opened or run.
    same = str(tmp_path / "same.vcd")
    with pytest.raises(ValueError, match=f"^vcd {same} and fst {same} are the same file: each "
                                         "output needs its own$"):
        dpc31.Segment(1_500_000, vcd=same, fst=same)
    scn_path = tmp_path / "two.scn"
    scn_path.write_bytes((traces / "segment" / "two_masters.scn").read_bytes())
    before = scn_path.read_bytes()
    scn = dpc31.SegmentScenario.load(str(scn_path))
    with pytest.raises(ValueError, match=f"^vcd {scn_path}: is the scenario {scn_path}: an output "
                                         "must not replace an input$"):
        scn.run(vcd=str(scn_path))
    with pytest.raises(ValueError, match="are the same file"):
        scn.run(pcapng=same, fst=same)
    assert scn_path.read_bytes() == before
    assert not (tmp_path / "same.vcd").exists()


@pytest.mark.parametrize("what", ["vcd", "fst", "pcapng"])
def test_an_empty_output_name_is_refused(traces, what):
    # '' was taken as not given: the line ran and nothing was written, silently.
    empty = f"^{what}: an empty file name: nothing can be written there$"
    with pytest.raises(ValueError, match=empty):
        dpc31.Segment(1_500_000, **{what: ""})
    with pytest.raises(ValueError, match=empty):
        dpc31.SegmentScenario.load(str(traces / "segment" / "two_masters.scn")).run(**{what: ""})


PACKAGE_DIR = str(pathlib.Path(dpc31.__file__).resolve().parents[1])  # PYTHONPATH from anywhere
OPEN_SEGMENT = """
import dpc31, sys
mode = sys.argv[1]
seg = dpc31.Segment(1_500_000, vcd="out.vcd", pcapng="out.pcapng")
seg.add_station(5, "spc3")
master = seg.add_master(2, [5])
closing = False
def observer(telegram):
    if mode == "raise" or closing:
        raise ValueError("a bug in the observer")
seg.on_telegram(observer)
if mode == "close_raises":
    master.startup_all()
    closing = True  # the last answer is still open: close() hands it to the observer
    seg.close()
    print("closed", flush=True)
master.startup_all()
print("ready", flush=True)
sys.stdin.readline()
"""


@pytest.mark.parametrize("end", ["raise", "close_raises", "SIGTERM", "SIGHUP"])
def test_an_unfinished_output_leaves_no_temporary(tmp_path, end):
    """A script that ends with its Segment's outputs unfinished (an observer's uncaught
    exception, a close() that raises, a SIGTERM or SIGHUP without a handler of the script's)
    leaves neither the outputs nor their NAME.PID.tmp: Python need not destroy the Segment, so
    the module removes them at exit and on those signals."""
    proc = subprocess.Popen([sys.executable, "-c", OPEN_SEGMENT,
                             "wait" if end.startswith("SIG") else end],
                            cwd=tmp_path, env=dict(os.environ, PYTHONPATH=PACKAGE_DIR),
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    if end.startswith("SIG"):
        assert proc.stdout.readline() == "ready\n"
        assert sorted(p.suffix for p in tmp_path.iterdir()) == [".tmp", ".tmp"]
        proc.send_signal(getattr(signal, end))
        assert proc.wait(timeout=30) == -getattr(signal, end)
    else:
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 1 and "a bug in the observer" in err
        assert "closed" not in out  # close_raises: it was close() that raised
    assert list(tmp_path.iterdir()) == []
