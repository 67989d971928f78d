"""A start-up with exact cycles: the built-in DP master finds an SPC3 at 1.5 Mbaud, parameterises
and configures it, and the chip enters Data_Exchange.

Expected cycles: docs/timing.md at 48 MHz, T = 48 MHz / 1.5 Mbaud = 32 clocks per bit, as the
golden trace traces/startup_spc3_1m5.trace derives them by hand in its header (the same slave).
"""

import json
import subprocess

import dpc31

T = 32  # clocks per bit at 1.5 Mbaud (docs/timing.md, "Serial line": round(48e6 / 1.5e6))
SLAVE = dict(address=12, ident=0x8031, cfg=b"\x11\x21", in_len=2, out_len=2, wd_fact1=20,
             wd_fact2=10, wd_on=True, wd_base_1ms=False)
SCENARIO_HEAD = """profile spc3
bus motorola
baud 1500000
master address=1
slave address=12 ident=0x8031 cfg=11,21 in=2 out=2 wd=20,10 wd_on=1 wd_base=10ms
user inputs=C0,DE
"""


def start_up():
    chip = dpc31.Chip("spc3", bus="motorola")
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    master = dpc31.Master(chip, address=1, baud=1_500_000, slave=dpc31.SlaveConfig(**SLAVE))
    master.run_responder(inputs=b"\xC0\xDE")  # the built-in user side: init, then Start_SPC3
    assert master.startup()
    return chip, master, edges


def test_startup_cycles_from_the_timing_contract():
    chip, master, edges = start_up()
    assert chip.dp_state == dpc31.DpState.Data_Exchange
    assert chip.wd_state == dpc31.WdState.DP_Control
    # The user side's init, 48 bus accesses of 4 clocks, ends with the Start_SPC3 write
    # completing at 48 x 4 = 192; Start latches DX_Out (docs/timing.md, "Mode and state
    # changes"), which it unmasked: X/INT active at 192.
    start = next(c for c, active in edges if active)
    assert start == 192
    # The baud search listens max(4096 bit times, 20 ms) at each rate from 12 Mbaud down
    # (docs/timing.md, "Baud_Search"): 12, 6 and 3 Mbaud have 20 ms = 960 000 cycles each, so the
    # 1.5 Mbaud window opens at:
    window = start + 3 * 960000
    assert window == 2880192
    # The master's unanswered FDL_Status requests start at start + 33 T and repeat every
    # 66 + 100 (slot) + 33 = 199 bit times; the first with >= 33 idle bit times after the window
    # opened is answered: start + 33 T + k x 199 T >= window + 33 T for k = 453.
    answered = [ex for ex in master.history if ex.answer is not None]
    fdl_status = answered[0]
    assert fdl_status.request.service == "FDL_Status"
    assert fdl_status.request_start == start + 33 * T + 453 * 199 * T == 2885952
    # acted on at the stop sample of its last character: end - T + T/2 -> Baudrate_Detect
    acted = fdl_status.request_end - T + T // 2
    assert acted == 2885952 + 66 * T - T + T // 2 == 2888048
    assert (acted, True) in edges
    # the answer: 11 bit times after the request's end, 6 characters of 11 bits
    assert fdl_status.answer_start == fdl_status.request_end + 11 * T == 2888416
    assert fdl_status.answer_end == fdl_status.answer_start + 6 * 11 * T == 2890528
    # every answer of the start-up keeps the same distance (MinTSDR 11 bit times)
    for ex in answered:
        assert ex.answer_start == ex.request_end + 11 * T
    # the next request after TSYN = 33 idle bit times
    position = [ex.request_start for ex in master.history].index(fdl_status.request_start)
    assert master.history[position + 1].request_start == 2890528 + 33 * T
    assert [ex.request.service for ex in answered] == [
        "FDL_Status", "Slave_Diag", "Set_Prm", "Chk_Cfg", "Slave_Diag"]
    assert chip.fdl_counters["requests"] == 5


def test_startup_from_python_has_the_cycles_of_dpc31_run(cli, tmp_path):
    chip, master, _ = start_up()
    # A scenario's step ends when the bus is free again: TSYN (33 bit times) after the last answer
    # (session/scenario_run.cpp, settle; docs/scenario-format.md).
    master.idle(master.history[-1].answer_end + 33 * T - chip.cycle)
    scn = tmp_path / "startup.scn"
    scn.write_text(SCENARIO_HEAD + "startup\nexpect dp_state Data_Exchange\n")
    out = tmp_path / "run.json"
    subprocess.run([cli, "run", str(scn), "--quiet", "--json", str(out)], check=True)
    assert json.loads(out.read_text())["final_cycle"] == chip.cycle
    # and the same scenario through the module
    result = dpc31.run_scenario(str(scn))
    assert result.ok and result.final_cycle == chip.cycle
    assert [(e.line, e.ok) for e in result.expects] == [(8, True)]


def test_a_master_gone_before_its_chip_leaves_it_nothing_to_run():
    # run_responder makes the master anew, and a Master collected while its Chip lives goes
    # too: their observers on the chip's TxD go with them (~DpMaster), so the master made next,
    # often in the freed memory, hears every character once (docs/python.md, "Masters").
    chip = dpc31.Chip("spc3")
    for _ in range(3):
        master = dpc31.Master(chip, address=2, baud=1_500_000,
                              slave=dpc31.SlaveConfig(address=5))
        master.run_responder(inputs=b"\x11\x22\x33\x44")
        assert master.startup()
        history = master.history
        ex = master.data_exchange(b"\x00" * 4)
        assert ex.answer is not None and ex.answer.du == b"\x11\x22\x33\x44"
        assert len(master.history) == len(history) + 1
        del master, history


def test_a_slave_locked_by_another_master_is_named_in_locks():
    # Slave_Diag byte 3, Master_Add, naming another master (neither FFh nor ours) means the slave
    # is locked by it (chip-facts.md "Slave_Diag"); the master leaves it alone, as a scenario's
    # `startup` does ("slave locked by master 3", docs/scenario-format.md), and startup()'s bare
    # False gets its reason in Master.locks (docs/python.md).
    chip = dpc31.Chip("spc3")
    slave = dict(address=5, wd_fact1=5, wd_fact2=10, wd_on=True, wd_base_1ms=False)
    first = dpc31.Master(chip, address=3, baud=1_500_000, slave=dpc31.SlaveConfig(**slave))
    first.run_responder(inputs=b"\x11\x22\x33\x44")
    assert first.startup() and first.locks == {}
    second = dpc31.Master(chip, address=2, baud=1_500_000, slave=dpc31.SlaveConfig(**slave))
    assert not second.startup()
    assert second.locks == {5: 3}
    # FDL_Status, then the Slave_Diag that names master 3: no Set_Prm, no Chk_Cfg
    assert [ex.request.service for ex in second.history] == ["FDL_Status", "Slave_Diag"]
    assert second.history[-1].answer.du[3] == 3
    # TWD = 10 ms x 5 x 10 = 500 ms without master 3 (docs/timing.md, "DP watchdog"): the slave
    # is back in Wait_Prm, its Master_Add FFh, and the next start-up takes it off locks.
    second.idle(48_000_000 * 6 // 10)
    assert chip.dp_state == dpc31.DpState.Wait_Prm
    before = len(second.history)
    second.startup(tries=3)  # no user side of its own: the slave stays in Wait_Prm
    diags = [ex for ex in second.history[before:] if ex.request.service == "Slave_Diag"]
    assert diags[0].answer.du[3] == 0xFF
    assert second.locks == {}


def test_an_spc3_firmware_that_never_reads_new_din_buffer_cmd_is_told_once(capfd):
    # docs/bring-up.md, section 7: an SPC3 with a Din buffer enters Data_Exchange at the firmware's
    # first New_Din_Buffer_Cmd read after its Cfg verdict (SPC3 p.31, modelled). Here the built-in
    # user side does not see New_Cfg_Data (masked: its own mask C0F0h with bit 10 set) and the
    # verdict is read for it, without that read: the chip stays in Wait_Cfg, and its warning
    # reaches Python on standard error (the default log sink), once, as `[cycle N] warn: ...`.
    chip = dpc31.Chip("spc3")
    master = dpc31.Master(chip, address=2, baud=12_000_000, slave=dpc31.SlaveConfig(address=5))
    master.run_responder(inputs=b"\x11\x22\x33\x44")
    mask = chip.addr_of("Int_Mask_Reg")
    chip.write(mask, 0xF0)  # Intel: the low byte first
    chip.write(mask + 1, 0xC4)
    assert not master.startup(tries=20)  # Set_Prm, Chk_Cfg, then polls: the verdict pending
    assert chip.read(chip.addr_of("User_Cfg_Data_Okay")) == 0x00
    capfd.readouterr()
    assert not master.startup(tries=400)  # Slave_Diag every 1 408 cycles: 11.7 ms of polls
    assert chip.dp_state == dpc31.DpState.Wait_Cfg
    warnings = [line for line in capfd.readouterr().err.splitlines()
                if "has not read New_Din_Buffer_Cmd" in line]
    assert len(warnings) == 1, warnings
    assert "] warn: master 2 is refused (Slave_Diag with Station_Not_Ready): the SPC3 is still " \
           "in Wait_Cfg at least 10 ms after User_Cfg_Data_Okay" in warnings[0]
