"""A fail-safe Clear on the DPC31: Global_Control Clear_Data makes the chip hand the user its clear
buffer C (the substitute values), and Data_Exchange without outputs (fail-safe) is still answered
with the inputs.

Expected values: the DPC31 sets N_Cl instead of clearing D, so the user's next fetch is C with
U_Buffer_Cleared (docs/dpc31.md; the hand check of traces/gc_clear_failsafe_dpc31.trace); cycles
from docs/timing.md, "Telegrams": a request is acted on at its last stop sample, end - T + T/2, and
answered 11 bit times after its end (T = 32 clocks at 1.5 Mbaud and 48 MHz).
"""

import dpc31

T = 32
CLEAR_DATA = 0x02  # Global_Control Control_Command bit 1 (EN 50170: Clear_Data)


def test_fail_safe_clear_through_the_master():
    chip = dpc31.Chip("dpc31")
    master = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5, group_ident=0x01))
    user = master.run_responder(inputs=b"\x01\x02\x03\x04", spec_clear_mode=True,
                                substitute=b"\x5A" * 4)
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    assert master.startup()
    master.data_exchange(b"\x11\x22\x33\x44")
    master.data_exchange(b"\x11\x22\x33\x44")
    assert (user.outputs[-1].data, user.outputs[-1].cleared) == (b"\x11\x22\x33\x44", False)
    user.keep_last_output()  # what a long loop calls, so memory stays flat
    assert [(o.data, o.cleared) for o in user.outputs] == [(b"\x11\x22\x33\x44", False)]

    gc = master.global_control(CLEAR_DATA, groups=0x01)
    assert gc.answer is None  # a broadcast SDN has no answer
    acted = gc.request_end - T + T // 2
    assert (acted, True) in edges  # DX_Out and New_GC_Command at the stop sample
    master.idle(2000)  # the bus is silent while the user's ISR fetches (it runs as time passes)
    assert user.outputs[-1].cycle > acted
    assert (user.outputs[-1].data, user.outputs[-1].cleared) == (b"\x5A" * 4, True)
    assert chip.dp_state == dpc31.DpState.Data_Exchange

    # fail-safe: Data_Exchange without outputs while in Clear: answered with the inputs
    ex = master.data_exchange(b"")
    assert ex.answer is not None and ex.answer.du == b"\x01\x02\x03\x04"
    assert ex.answer_start == ex.request_end + 11 * T
    assert chip.dp_state == dpc31.DpState.Data_Exchange


def test_the_same_through_its_scenario_file(traces):
    scenario = dpc31.Scenario.load(str(traces / "gc_clear_failsafe_dpc31.scn"))
    expects = scenario.expects
    assert expects[0].text == "expect outputs 11,22,33,44"
    result = scenario.run()
    assert result.ok, result.failures
    assert [(e.line, e.ok) for e in result.expects] == [(e.line, True) for e in expects]
    # The trace's hand check: the Clear_Data telegram starts at 186336 + 28 + 2763712 (its
    # rechecks: the DPC31's MAC_Start, then the 20 ms baud-search windows), 13 characters, and
    # is acted on at its last stop sample; the user fetches the substitute values after that.
    gc = next(s for s in result.steps if s.text.startswith("gc clear"))
    assert gc.cycle == 186336 + 28 + 2763712
    acted = gc.cycle + 13 * 11 * T - T + T // 2
    fetch = next(line for line in result.walk if "user: outputs 5A 5A 5A 5A (cleared)" in line)
    assert acted < int(fetch.split("]")[0].split()[-1]) < acted + 100
