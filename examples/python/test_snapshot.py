"""A snapshot taken and restored: a chip in Data_Exchange saved to bytes, loaded into a second
chip, and both run into the DP watchdog's expiry at the same cycle.

Expected cycle (docs/timing.md, "Timers"): TWD = ceil(10 ms x WD_Fact_1 x WD_Fact_2 x 48 MHz),
restarted when a request from Master_Add is acted on (its last stop sample, end - T + T/2);
expiry at the last restart + TWD: WD_DP_Control_Timeout, Baud_Control, Leave_Master (Wait_Prm).
"""

import pytest

import dpc31

T = 32


def test_snapshot_round_trip_and_watchdog_expiry(tmp_path):
    a = dpc31.Chip("dpc31")
    master = dpc31.Master(a, slave=dpc31.SlaveConfig(wd_fact1=10, wd_fact2=10, wd_base_1ms=False))
    master.run_responder(inputs=b"\xA1\xA2\xA3\xA4")
    assert master.startup()
    ex = master.data_exchange(b"\x01\x02\x03\x04")
    twd = 10 * 10 * 480_000  # 10 ms x 10 x 10 at 48 MHz
    due = ex.request_end - T + T // 2 + twd
    assert a.watchdog_due == due

    snap = a.save_state()
    b = dpc31.Chip("dpc31")
    b.load_state(snap)
    assert (b.cycle, b.dp_state, b.watchdog_due) == (a.cycle, dpc31.DpState.Data_Exchange, due)
    assert b.peek_block(0, 0x800) == a.peek_block(0, 0x800)

    for chip in (a, b):  # the cable is pulled: both expire at the same cycle
        chip.step(due - chip.cycle - 1)
        assert chip.dp_state == dpc31.DpState.Data_Exchange
        chip.step(1)
        assert chip.wd_state == dpc31.WdState.Baud_Control
        assert chip.dp_state == dpc31.DpState.Wait_Prm
        assert chip.peek_field("Int_Req_Reg", "WD_DP_Control_Timeout") == 1

    path = tmp_path / "dx.snap"
    c = dpc31.Chip("dpc31")
    a.load_state(snap)
    a.save_state_file(str(path))
    c.load_state_file(str(path))
    assert c.save_state() == snap


def test_a_snapshot_of_another_profile_is_refused():
    snap = dpc31.Chip("spc3").save_state()
    chip = dpc31.Chip("dpc31")
    chip.step(100)
    with pytest.raises(dpc31.SnapshotError):
        chip.load_state(snap)
    assert chip.cycle == 100  # unchanged
    with pytest.raises(dpc31.SnapshotError):
        chip.load_state(b"not a snapshot")


def test_at_the_end_of_time_every_access_stops_there_and_the_snapshot_loads_back():
    """The chip's time ends at Chip::kLastCycle, 2**62 - 1 (docs/python.md): the "no limit"
    step(2**64 - 1) of a chip without events reaches it at once, and a block transfer, a Start and
    step_until_irq stop there as a single access does; its snapshot loads back (docs/timing.md,
    "Clock and time")."""
    last = 2**62 - 1
    chip = dpc31.Chip("spc3")
    chip.step(2**64 - 1)
    assert chip.cycle == last
    chip.write_block(0x100, b"\x01\x02\x03\x04")
    assert chip.read_block(0x100, 8)[:4] == b"\x01\x02\x03\x04" and chip.cycle == last
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)  # Start_SPC3
    assert chip.started and chip.cycle == last
    assert not chip.step_until_irq(10) and chip.cycle == last
    again = dpc31.Chip("spc3")
    again.load_state(chip.save_state())
    assert again.cycle == last and again.started


def test_load_state_takes_any_bytes_like_object_and_files_take_paths(tmp_path):
    """load_state takes what the buffer protocol gives (bytes, bytearray, memoryview, array), as
    write_block takes a bytearray; anything else is a one-line TypeError naming its type, never
    the snapshot's bytes (pybind11 printed all of them as the call's arguments). The file
    functions take a pathlib.Path as open() does (docs/python.md)."""
    import array
    import pathlib

    a = dpc31.Chip("spc3")
    a.step(1000)
    snap = a.save_state()
    assert len(snap) == 2867  # docs/snapshots.md: after reset on the spc3 (version 7)
    for data in (bytearray(snap), memoryview(snap), memoryview(bytearray(snap)),
                 array.array("B", snap)):
        b = dpc31.Chip("spc3")
        b.load_state(data)
        assert (b.cycle, b.save_state()) == (1000, snap), type(data).__name__
    b = dpc31.Chip("spc3")
    with pytest.raises(TypeError) as e:
        b.load_state(list(snap))
    assert str(e.value) == "data: a bytes-like object expected, got list"
    with pytest.raises(TypeError) as e:
        b.load_state(snap.hex())
    assert str(e.value) == "data: a bytes-like object expected, got str"
    assert b.cycle == 0

    path = tmp_path / "a.snap"
    assert isinstance(path, pathlib.Path)
    a.save_state_file(path)
    assert path.read_bytes() == snap
    b.load_state_file(path)
    assert b.save_state() == snap
    with pytest.raises(dpc31.SnapshotError) as e:
        b.load_state_file(tmp_path / "missing.snap")
    assert str(e.value) == f"{tmp_path / 'missing.snap'}: no such file"
    with pytest.raises(TypeError):
        b.load_state_file(5)
