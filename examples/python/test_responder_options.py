"""Master.run_responder's wd_baud_control= and user_wd_value=: the built-in user side's
WD_Baud_Control_Val and R_User_WD_Value, as a scenario's `user wd_baud_control= user_wd_value=`
line sets them (docs/python.md; docs/scenario-format.md), with its ranges and words.

Expected values: docs/timing.md, "Baud_Control": WD_Baud_Control_Val x 10 ms (x 2 on the VPC3+)
from the last error-free telegram to us, acted on at its last stop sample, end - T + T/2 (T = 4
clocks at 12 Mbaud and 48 MHz); "user watchdog": Res_User_WD (the Start carries it) reloads
R_User_WD_Value at the next Data_Exchange, each later one counts down, the one that reaches 0 is
not answered (docs/segment.md: the station leaves at Data_Exchange N + 1).
"""

import pytest

import dpc31

T = 4
MS = 48_000


@pytest.mark.parametrize("profile,factor", [("spc3", 1), ("vpc3plus", 2), ("dpc31", 1)])
def test_wd_baud_control_sets_the_baud_control_time(profile, factor):
    chip = dpc31.Chip(profile)
    master = dpc31.Master(chip, baud=12_000_000, slave=dpc31.SlaveConfig(wd_on=False))
    master.run_responder(wd_baud_control=3)  # 30 ms (60 ms on the VPC3+)
    assert master.startup()
    ex = master.data_exchange(b"\x00" * 4)
    acted = ex.request_end - T + T // 2
    master.idle(acted + 30 * MS * factor - 1 - chip.cycle)
    assert chip.wd_state == dpc31.WdState.Baud_Control
    chip.step(1)
    assert chip.wd_state == dpc31.WdState.Baud_Search
    assert chip.dp_state == dpc31.DpState.Data_Exchange  # WD_On = 0: the DP state stays


@pytest.mark.parametrize("profile", ["spc3", "vpc3plus"])
def test_user_wd_value_leaves_at_data_exchange_n_plus_1(profile):
    chip = dpc31.Chip(profile)
    master = dpc31.Master(chip, baud=12_000_000)
    master.run_responder(user_wd_value=2)  # the user side never serves it (user_watchdog off)
    assert master.startup()
    for _ in range(2):  # the 1st loads 2, the 2nd counts to 1
        assert master.data_exchange(b"\x00" * 4).answer is not None
    assert master.data_exchange(b"\x00" * 4).answer is None  # the 3rd reaches 0
    assert chip.dp_state == dpc31.DpState.Wait_Prm


@pytest.mark.parametrize("kwargs,words", [
    (dict(wd_baud_control=256), "wd_baud_control 256 out of range (0..255)"),
    (dict(wd_baud_control=-1), "wd_baud_control -1 out of range (0..255)"),
    (dict(user_wd_value=65536), "user_wd_value 65536 out of range (0..65535)"),
])
def test_a_value_out_of_range_is_refused_in_the_scenarios_words(kwargs, words):
    master = dpc31.Master(dpc31.Chip("spc3"))
    with pytest.raises(ValueError) as e:
        master.run_responder(**kwargs)
    assert str(e.value) == words
    assert master.responder is None  # nothing half set up


def test_user_wd_value_on_the_dpc31_needs_user_watchdog():
    master = dpc31.Master(dpc31.Chip("dpc31"))
    with pytest.raises(ValueError) as e:
        master.run_responder(user_wd_value=3)
    assert str(e.value) == ("user_wd_value needs user_wd=1 on profile dpc31: the "
                            "DPS_User_Watchdog loads R_User_WD_Value only through its requests")
    assert master.run_responder(user_wd_value=3, user_watchdog=True) is not None
