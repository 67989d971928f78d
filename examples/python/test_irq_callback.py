"""An interrupt callback counting events: the SPC3's User_Timer_Clock, acknowledged and ended by
a Python "ISR" after each X/INT edge.

Expected cycles (docs/timing.md): a bus access takes 4 clocks and acts at its end; the user timer's
first event is at Start + P, then every P, P = ceil(1 ms x 48 MHz) = 48000 (User_Time_Base = 0);
X/INT goes active in the cycle the event is latched and inactive when the acknowledge completes.
"""

import pytest

import dpc31

P = 48_000


def test_callback_counts_every_user_timer_clock():
    chip = dpc31.Chip("spc3")
    utc = dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask
    imr, ack = chip.addr_of("Int_Mask_Reg"), chip.addr_of("Int_Ack_Reg")
    mode1_s = chip.addr_of("Mode_Reg1_S")
    start_bit = dpc31.register("spc3", "Mode_Reg1_S").field("Start_SPC3").mask
    eoi_bit = dpc31.register("spc3", "Mode_Reg1_S").field("EOI").mask

    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    mask = ~utc & 0xFFFF
    chip.write(imr, mask & 0xFF)  # intel: bits 7..0 at the address, 15..8 above
    chip.write(imr + 1, mask >> 8)
    chip.write(mode1_s, start_bit)  # completes at 3 x 4 = 12
    start = 12
    assert chip.cycle == start and chip.started

    for k in range(1, 6):
        assert chip.step_until_irq(2 * P)
        assert chip.cycle == start + k * P
        assert chip.peek_field("Int_Reg", "User_Timer_Clock") == 1
        chip.write(ack, utc)  # acknowledge: the line goes inactive when it completes
        chip.write(mode1_s, eoi_bit)

    active = [c for c, a in edges if a]
    inactive = [c for c, a in edges if not a]
    assert active == [start + k * P for k in range(1, 6)]
    assert inactive == [start + k * P + 4 for k in range(1, 6)]


def test_an_exception_in_a_callback_stops_the_run_and_is_raised():
    chip = dpc31.Chip("spc3")
    utc = dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask
    chip.write(chip.addr_of("Int_Mask_Reg"), ~utc & 0xFF)
    chip.write(chip.addr_of("Int_Mask_Reg") + 1, 0xFF)

    calls = []

    def boom(cycle, active):
        calls.append(cycle)
        raise ValueError(f"edge at {cycle}")

    chip.on_irq_change(boom)
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)
    try:
        chip.step(10 * P)
        raised = None
    except ValueError as e:
        raised = str(e)
    assert raised == f"edge at {12 + P}"
    # step(n) advances exactly n cycles (docs/timing.md); Python is not called again in it
    assert chip.cycle == 12 + 10 * P and calls == [12 + P]
    chip.on_irq_change(None)
    chip.step(P)  # and the chip goes on
    assert chip.cycle == 12 + 11 * P


def started_with_an_active_interrupt():
    """An SPC3 with User_Timer_Clock alone unmasked, started at 12: the interrupt active at
    12 + P; its on_irq_change edges in a list."""
    chip = dpc31.Chip("spc3")
    utc = dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask
    chip.write(chip.addr_of("Int_Mask_Reg"), ~utc & 0xFF)
    chip.write(chip.addr_of("Int_Mask_Reg") + 1, 0xFF)
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)  # Start_SPC3, completes at 12
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    assert chip.step_until_irq(2 * P) and chip.cycle == 12 + P
    return chip, edges


def test_a_reset_and_a_snapshots_load_show_the_interrupts_edge():
    """A hardware reset clears Int_Req_Reg: the interrupt ends at cycle 0 of the new time line,
    and on_irq_change is told, as for PB3 (docs/timing.md, "Interrupt line"); a snapshot's load
    shows the loaded interrupt at the loaded cycle where it differs (docs/snapshots.md)."""
    chip, edges = started_with_an_active_interrupt()
    active = chip.save_state()
    chip.reset()
    assert not chip.irq_active and chip.x_int
    chip.load_state(active)
    assert chip.irq_active and not chip.x_int
    chip.load_state(active)  # the same level: no edge
    assert edges == [(12 + P, True), (0, False), (12 + P, True)]


def test_an_observers_exception_in_a_reset_is_raised_by_the_reset():
    chip, _ = started_with_an_active_interrupt()

    def boom(cycle, active):
        raise ValueError(f"edge at {cycle}: {active}")

    chip.on_irq_change(boom)
    with pytest.raises(ValueError, match="edge at 0: False"):
        chip.reset()
    assert chip.cycle == 0 and not chip.irq_active
    chip.step(10)  # nothing left over for the next call
    assert chip.cycle == 10


def test_observers_may_look_but_not_touch():
    chip = dpc31.Chip("spc3")
    seen = []

    def look(cycle, write, addr, data):
        seen.append((cycle, write, addr, data, chip.cycle))
        chip.read(0)  # an access from inside an access: refused

    chip.on_bus_access(look)
    try:
        chip.write(0x16, 0x33)
    except dpc31.Error as e:
        assert "observer" in str(e)
    else:
        raise AssertionError("an access from an observer was not refused")
    assert seen == [(4, True, 0x16, 0x33, 4)]


def test_on_bus_access_gives_the_byte_of_a_write_and_none_for_a_read():
    """The C++ observer has the byte of a write only (BusAccess::data, "writes only"): a read is
    reported with None, not a 0 that looks like a value read. Each access takes 4 clocks
    (docs/timing.md, "Bus accesses")."""
    chip = dpc31.Chip("spc3")
    seen = []
    chip.on_bus_access(lambda *a: seen.append(a))
    chip.write(0x100, 0x12)
    assert chip.read(0x100) == 0x12
    assert seen == [(4, True, 0x100, 0x12), (8, False, 0x100, None)]


def test_the_gil_is_released_while_the_chip_runs():
    """Another Python thread runs while one chip steps (per-cycle engine: every clock evaluated,
    a long native run), and finds that chip busy instead of racing it."""
    import threading

    chip = dpc31.Chip("spc3", engine="per-cycle")
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)
    runner = threading.Thread(target=chip.step, args=(40 * P,))
    refused = 0
    runner.start()
    while runner.is_alive():
        try:
            chip.poke(0x100, 0x12)
        except dpc31.Error as e:
            assert "another thread" in str(e)
            refused += 1
    runner.join()
    assert refused > 0  # the main thread ran Python while the other thread was inside step()
    assert chip.cycle == 4 + 40 * P  # one access of 4 clocks, then the step


def test_a_masters_user_side_is_refused_to_another_thread_while_the_master_runs_its_chip():
    """A user side given to a master's chip runs while the master runs that chip: another thread
    is refused it (docs/python.md, "A user side runs with its chip or segment")."""
    import threading

    chip = dpc31.Chip("spc3", engine="per-cycle")
    master = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=3))
    r = master.run_responder()
    runner = threading.Thread(target=master.idle, args=(40 * P,))
    refused = 0
    runner.start()
    while runner.is_alive():
        try:
            r.take_interrupts()
        except dpc31.Error as e:
            assert "running in another thread" in str(e)
            refused += 1
    runner.join()
    assert refused > 0  # the main thread ran Python while the other thread was inside idle()
    r.take_interrupts()  # between runs every call works


def _raising(calls):
    def fails(cycle, active):
        calls.append((cycle, active))
        raise RuntimeError("observer fails")
    return fails


def test_an_observers_exception_ends_the_masters_call_at_once():
    """docs/python.md, "The GIL": the master's waits end at once. The master cleared the chip's
    stop after every wait and went on: startup() ran 2.9 M cycles and 458 requests to
    Data_Exchange before it raised (audit s29 a-py finding 4)."""
    chip = dpc31.Chip("spc3")
    m = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5))
    m.run_responder(inputs=b"\1\2\3\4")
    calls = []
    chip.on_irq_change(_raising(calls))
    with pytest.raises(RuntimeError, match="^observer fails$"):
        m.startup()
    # The first request starts after TSYN, 33 bit times of 32 clocks at 1.5 Mbaud: 1056. The
    # responder's first interrupt edge comes before it, and the call ends at its cycle.
    assert len(calls) == 1 and calls[0][0] < 33 * 32
    assert chip.cycle == calls[0][0] and m.counters.requests == 0


def test_an_observers_exception_ends_a_data_exchange_before_its_answer():
    chip = dpc31.Chip("spc3")
    m = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5))
    m.run_responder(inputs=b"\1\2\3\4")
    assert m.startup()
    answered = m.counters.answered
    calls = []
    chip.on_irq_change(_raising(calls))
    with pytest.raises(RuntimeError, match="^observer fails$"):
        m.data_exchange(b"\0\0\0\0")
    # DX_Out's edge, at the request's end: the call ends there, the answer not waited for.
    assert len(calls) == 1 and calls[0][1] is True
    assert chip.cycle == calls[0][0] and m.counters.answered == answered


def test_an_observers_exception_in_the_answers_wait_leaves_idle_its_cycles():
    # The exception at the ISR's EOI (the second edge), while the master waits for the answer:
    # the wait it ended leaves no wake on TxD behind, so idle(n) takes its n cycles, the answer's
    # edges on TxD notwithstanding (the review of the twenty-ninth session: 300, 352, 352).
    chip = dpc31.Chip("spc3")
    m = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5))
    m.run_responder(inputs=b"\1\2\3\4")
    assert m.startup()
    calls = []

    def fails_second(cycle, active):
        calls.append((cycle, active))
        if len(calls) == 2:
            raise RuntimeError("observer fails")
    chip.on_irq_change(fails_second)
    with pytest.raises(RuntimeError, match="^observer fails$"):
        m.data_exchange(b"\0\0\0\0")
    chip.on_irq_change(None)
    for _ in range(3):
        start = chip.cycle
        m.idle(3000)
        assert chip.cycle == start + 3000


def test_a_running_chips_state_properties_are_refused_to_another_thread(refused_while):
    """docs/python.md, "The GIL": a call from another thread while the chip runs raises
    dpc31.Error; its state properties (cycle, dp_state, fdl_counters, ...) were read while the
    running thread wrote them (audit s29 a-py finding 10). Its constants still read. The looks
    happen while an on_irq_change observer holds the step (User_Timer_Clock's first event at
    12 + P): none depends on the scheduler (s31 benches finding 14)."""
    chip = dpc31.Chip("spc3", engine="per-cycle")
    mask = ~dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask & 0xFFFF
    chip.write(chip.addr_of("Int_Mask_Reg"), mask & 0xFF)
    chip.write(chip.addr_of("Int_Mask_Reg") + 1, mask >> 8)
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)  # Start, at 3 x 4 = 12
    names = ("cycle", "x_int", "irq_active", "pb3", "txd", "started", "dp_state", "wd_state",
             "station_address", "bit_cycles", "fdl_counters", "next_deadline", "watchdog_due")
    looks = {name: (lambda name=name: getattr(chip, name)) for name in names}
    looks["constants"] = lambda: (chip.profile, chip.clock_hz)
    refused = refused_while(lambda: chip.step(40 * P), looks, chip.on_irq_change)
    assert set(refused) == set(names)
    assert all("running in another thread" in e for e in refused.values())
    assert chip.cycle == 12 + 40 * P


def test_a_running_masters_history_counters_and_locks_are_refused_to_another_thread(
        refused_while):
    """The master's running state, as the chip's (the review of the twenty-ninth session: all 48
    reads of history, counters and locks went through while the chip's cycle was refused). Read
    while the chip's on_telegram holds a Data_Exchange: it failed now and then when 3 000
    exchanges ended before the other thread looked (s31 benches finding 14)."""
    chip = dpc31.Chip("spc3")
    m = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5))
    m.run_responder(inputs=b"\1\2\3\4")
    assert m.startup()
    names = ("history", "counters", "locks", "c2_sap", "c2_send_timeout")
    looks = {name: (lambda name=name: getattr(m, name)) for name in names}
    # clear_history() cleared the list the running master appends to: a segfault or a double
    # free (audit s35 aTb finding 1).
    looks["clear_history"] = m.clear_history
    refused = refused_while(lambda: m.data_exchange(b"\x0a\x0b\x0c\x0d"), looks, chip.on_telegram)
    assert set(refused) == set(names) | {"clear_history"}
    assert all("running in another thread" in e for e in refused.values())
    assert m.history[-1].request.du == b"\x0a\x0b\x0c\x0d" and m.locks == {}  # it ran


def test_an_observer_may_not_clear_the_history_the_running_master_appends_to():
    """As SegmentMaster.clear_history() (docs/python.md, "The GIL"): an observer may look at the
    history but not clear it; the Error is raised when the exchange returns, which ran to its end
    (its request the last entry), and between runs the call works."""
    chip = dpc31.Chip("spc3")
    m = dpc31.Master(chip, slave=dpc31.SlaveConfig(address=5))
    m.run_responder(inputs=b"\1\2\3\4")
    assert m.startup()
    chip.on_telegram(lambda *_: m.clear_history())
    with pytest.raises(dpc31.Error, match="an observer may look at it .* but not clear the "
                                          "master's history"):
        m.data_exchange(b"\0\0\0\0")
    chip.on_telegram(None)
    assert len(m.history) > 1
    m.clear_history()
    assert m.history == []


def test_an_observer_may_not_change_the_observers_it_is_among():
    """docs/python.md, "The GIL": an observer may look at its chip but not change what the run
    uses; its own list of observers is that (the chip calls each in turn), so on_irq_change(None)
    from an observer is a dpc31.Error that says so (it spoke of accessing or stepping the chip:
    s31 benches finding 10), raised when the step returns; after it the observer is removed. A
    callback that is not callable is a TypeError naming the argument."""
    chip = dpc31.Chip("spc3")
    mask = ~dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask & 0xFFFF
    chip.write(chip.addr_of("Int_Mask_Reg"), mask & 0xFF)
    chip.write(chip.addr_of("Int_Mask_Reg") + 1, mask >> 8)
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)  # Start at 12: the first event at 12 + P
    calls = []

    def once(cycle, active):
        calls.append(cycle)
        chip.on_irq_change(None)

    chip.on_irq_change(once)
    with pytest.raises(dpc31.Error) as e:
        chip.step(2 * P)
    assert str(e.value) == ("the chip is running: an observer may look at it (peek, cycle, "
                            "probe, ...) but not add or remove observers (on_irq_change): change "
                            "them after the call returns")
    assert calls == [12 + P] and chip.cycle == 12 + 2 * P
    chip.on_irq_change(None)
    with pytest.raises(TypeError, match="^on_pb3_change: callback: a callable or None expected, "
                                        "got int$"):
        chip.on_pb3_change(5)
