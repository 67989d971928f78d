"""A waveform comparison: the same start-up recorded by `dpc31 run --vcd` with the event engine
and with the per-cycle reference engine is the same waveform (docs/engine.md: both give the same
observable results); a slave whose inputs differ in one bit differs first on TxD in that bit.

Expected place (docs/timing.md, "Serial line"): a character is start bit, 8 data bits LSB first,
parity, stop; character i of an answer starts at answer_start + 11 T i. The VCD's time is
round(cycle x 10^12 / 48 MHz) ps (docs/waveforms.md).
"""

import subprocess

import pytest

import dpc31

T = 32
SCENARIO = """profile spc3
bus motorola
baud 1500000
master address=1
slave address=12 ident=0x8031 cfg=11,21 in=2 out=2 wd=20,10 wd_on=1 wd_base=10ms
user inputs=C0,{last:02X}
startup
exchange 1 outputs=5A,A5
"""


def ps(cycle):
    return (cycle * 10**12 + 24_000_000) // 48_000_000


def record(cli, tmp_path, name, last, engine="event"):
    scn = tmp_path / f"{name}.scn"
    scn.write_text(SCENARIO.format(last=last))
    vcd = tmp_path / f"{name}.vcd"
    subprocess.run([cli, "run", str(scn), "--quiet", "--engine", engine, "--vcd", str(vcd)],
                   check=True)
    return str(vcd)


def test_both_engines_give_the_same_waveform(cli, tmp_path):
    report = dpc31.wavediff(record(cli, tmp_path, "event", 0xDE),
                            record(cli, tmp_path, "cycle", 0xDE, engine="per-cycle"))
    assert report.same, report.text()
    assert report.compared == 15 and not report.diffs  # the 15 signals of a run (docs/waveforms.md)


def test_one_input_bit_differs_on_txd_in_its_data_bit(cli, tmp_path):
    # the answer's start, through the module: the same start-up and Data_Exchange
    chip = dpc31.Chip("spc3", bus="motorola")
    master = dpc31.Master(chip, address=1, slave=dpc31.SlaveConfig(
        address=12, ident=0x8031, cfg=b"\x11\x21", in_len=2, out_len=2, wd_fact1=20,
        wd_fact2=10))
    master.run_responder(inputs=b"\xC0\xDE")
    assert master.startup()
    ex = master.data_exchange(b"\x5A\xA5")
    assert ex.answer.encode() == bytes.fromhex("680505 68 010C08 C0DE B3 16".replace(" ", ""))

    report = dpc31.wavediff(record(cli, tmp_path, "de", 0xDE), record(cli, tmp_path, "df", 0xDF))
    assert not report.same
    txd = next(d for d in report.diffs if d.name.endswith("txd"))
    # DE and DF differ in bit 0, the first data bit of character 8 (68 05 05 68 01 0C 08 C0 DE)
    first_bit = ex.answer_start + 8 * 11 * T + T
    assert (txd.first.at.time, txd.first.a, txd.first.b) == (ps(first_bit), "0", "1")
    # the user writes the inputs into its Din buffer before: the data bus differs earlier
    data = next(d for d in report.diffs if d.name.endswith("data"))
    assert data.first.at.time < txd.first.at.time
    assert report.diffs[0].name == data.name


def test_no_signal_in_common_is_an_error_not_same(cli, tmp_path):
    # a run against a dump whose names match none of it: with ignore_missing nothing is compared,
    # which is no verdict (docs/wavediff.md, "Matching signals" 6): InputError, as the CLI's exit 2
    run = record(cli, tmp_path, "run", 0xDE)
    other = tmp_path / "other.vcd"
    other.write_text("$timescale 1ns $end\n$scope module rtl $end\n$var wire 1 ! clk $end\n"
                     "$upscope $end\n$enddefinitions $end\n#0\n0!\n#10\n1!\n")
    with pytest.raises(dpc31.InputError) as e:
        dpc31.wavediff(run, str(other), ignore_missing=True)
    # the message bare: the CLI adds "dpc31 wavediff: ", Python does not (docs/wavediff.md)
    assert str(e.value) == (f"no signals to compare: no signal of {run} matched "
                            f"one of {other} (check --strip, --map and --include/--exclude)")
    # an option of clock mode without the clock, in the same words (docs/bad-input.md)
    with pytest.raises(dpc31.InputError) as e:
        dpc31.wavediff(run, run, clock_b="clk")
    assert str(e.value) == "--clock-b requires --clock"
    assert not dpc31.wavediff(run, str(other)).same  # one-sided names: different


def late_pair(tmp_path):
    """Two dumps of one 10 ns clock (rising at 5, 15, 25, 35 ns: edges 0..3) whose `sig` rises at
    12 ns in A and one clock later, at 22 ns, in B: sampled at the rising edges, A and B differ at
    edge 1 only (A 1, B 0); in event mode for the 10 ns from 12 to 22 ns."""
    def dump(name, rise):
        changes = [(t, f"{(t // 5) % 2}!") for t in range(5, 45, 5)] + [(rise, '1"')]
        path = tmp_path / name
        path.write_text("$timescale 1ns $end\n$scope module top $end\n$var wire 1 ! clk $end\n"
                        "$var wire 1 \" sig $end\n$upscope $end\n$enddefinitions $end\n"
                        "#0\n0!\n0\"\n" + "".join(f"#{t}\n{v}\n" for t, v in sorted(changes)))
        return str(path)
    return dump("a.vcd", 12), dump("b.vcd", 22)


def test_window_tolerance_and_edge_as_the_cli_takes_them(tmp_path):
    # docs/wavediff.md: --tolerance-cycles, --tolerance, --start, --end (inclusive), --edge
    a, b = late_pair(tmp_path)
    late = dpc31.wavediff(a, b, clock="top.clk")
    assert not late.same
    assert (late.diffs[0].first.at.cycle, late.diffs[0].first.a, late.diffs[0].first.b) == (1, "1",
                                                                                             "0")
    assert dpc31.wavediff(a, b, clock="top.clk", tolerance_cycles=1).same  # one cycle long
    assert dpc31.wavediff(a, b, clock="top.clk", start="c2").same  # edges 2 and 3 agree
    assert dpc31.wavediff(a, b, clock="top.clk", end="c0").same
    assert not dpc31.wavediff(a, b, clock="top.clk", end="c1").same
    # the falling edges are at 10, 20, 30, 40 ns: at 20 ns A is 1 and B 0
    falling = dpc31.wavediff(a, b, clock="top.clk", edge="falling")
    assert (falling.diffs[0].first.at.cycle, falling.diffs[0].first.at.time) == (1, 20)
    # event mode: 10 ns of difference
    assert dpc31.wavediff(a, b, tolerance="10ns").same
    assert not dpc31.wavediff(a, b, tolerance="9ns").same
    assert dpc31.wavediff(a, b, start="25ns").same
    # bad options: the CLI's words (docs/bad-input.md)
    for kw, message in [({"edge": "falling"}, "--edge requires --clock"),
                        ({"tolerance_cycles": 1}, "--tolerance-cycles requires --clock"),
                        ({"start": "30ns", "end": "20ns"}, "--start is after --end")]:
        with pytest.raises(dpc31.InputError) as e:
            dpc31.wavediff(a, b, **kw)
        assert str(e.value) == message
    with pytest.raises(dpc31.InputError) as e:
        dpc31.wavediff(a, b, tolerance="10")
    assert str(e.value).startswith("--tolerance: ")
