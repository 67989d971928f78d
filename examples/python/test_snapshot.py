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
