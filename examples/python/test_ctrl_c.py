"""Ctrl-C in a long run (docs/python.md, "Ctrl-C"): the documented "no limit", step(2**64 - 1) or
Master.idle(2**64 - 1), on a started chip has a User_Timer event every 48 000 cycles
(docs/timing.md, "User_Timer": 10^14 events before Chip::kLastCycle, about a day); SIGINT raises
KeyboardInterrupt at a cycle boundary within a fraction of a second, and the chip goes on from
there. It waited for the whole call."""
import os
import signal
import threading
import time

import dpc31
import pytest

LAST = 2**62 - 1  # Chip::kLastCycle (docs/python.md)


def interrupted(run):
    """`run()` with SIGINT sent to this process 0.3 s after it started: how long it took, and the
    KeyboardInterrupt."""
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    started = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as info:
            run()
    finally:
        timer.cancel()
    return time.monotonic() - started, info.value


def started_spc3():
    chip = dpc31.Chip("spc3")
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)  # Start: the User_Timer runs
    return chip


def test_ctrl_c_ends_a_no_limit_step():
    chip = started_spc3()
    assert interrupted(lambda: chip.step(2**64 - 1))[0] < 5
    stopped = chip.cycle
    assert 4 < stopped < LAST
    chip.step(4)  # a cycle boundary: the chip goes on
    assert chip.cycle == stopped + 4
    chip.write(0x100, 0x5A)
    assert chip.read(0x100) == 0x5A
    assert chip.cycle == stopped + 12  # two bus accesses of 4 clocks (docs/timing.md, "Bus accesses")


def test_ctrl_c_ends_a_no_limit_idle():
    chip = started_spc3()
    m = dpc31.Master(chip, address=2, slave=dpc31.SlaveConfig(address=5))
    assert interrupted(lambda: m.idle(2**64 - 1))[0] < 5
    stopped = chip.cycle
    assert 4 < stopped < LAST
    m.idle(100)
    assert chip.cycle == stopped + 100


def test_an_observers_exception_ends_a_segment_s_idle_at_its_slice_s_end():
    """docs/python.md, "Ctrl-C in step and idle": on a segment an observer's exception ends a
    `SegmentMaster.idle` at the end of the slice it came in (the first slice: 65 536 cycles);
    the segment runs on from there and the error is not raised again. (Before, the idle ran on
    to its end: a Ctrl-C was the only way out of `idle(2**64 - 1)`.)"""
    seg = dpc31.Segment(1_500_000)
    station = seg.add_station(5, "spc3", wd=(1, 1))  # the built-in responder starts it: User_Timer
    master = seg.add_master(2, [5])
    babbler = seg.add_sender("babbler")
    start = seg.cycle
    # An FDL_Status to station 9, which is not there (SD1: DA, SA, FC 0x49, FCS, ED): on the line
    # at cycle start + 1000, inside the first slice.
    seg.send(babbler, bytes([0x10, 9, 3, 0x49, (9 + 3 + 0x49) & 0xFF, 0x16]), start=start + 1000)
    assert seg.cycle == start + 1000  # send() ran the line to the telegram's start
    seen = []

    def boom(t):
        seen.append(t.start)
        raise RuntimeError("observer")

    seg.on_telegram(boom)
    with pytest.raises(RuntimeError, match="^observer$"):
        master.idle(2**64 - 1)
    assert seen == [start + 1000]  # called once: not again after its exception
    stopped = seg.cycle
    assert stopped == start + 1000 + 65_536
    assert station.cycle == stopped  # the chip is at the line's time
    master.idle(100)  # the error is not raised again
    assert seg.cycle == stopped + 100
    assert station.cycle == stopped + 100
    assert seen == [start + 1000]


def test_a_no_limit_step_on_a_chip_without_events_still_ends_at_the_last_cycle():
    chip = dpc31.Chip("spc3")  # not started: no event before kLastCycle
    chip.step(2**64 - 1)
    assert chip.cycle == LAST


def test_an_observer_error_in_a_slice_s_last_cycle_ends_the_call_there():
    """An observer's exception ends the call at its cycle (docs/python.md, "Observers"), also when
    that cycle is the last of a slice: the first slice is 65 536 cycles (docs/python.md, "Ctrl-C").
    The call went on to its end there."""
    # An FDL_Status request to station 5 (SD1: DA, SA, FC 0x49, FCS, ED), on the line at 100 000.
    request = bytes([0x10, 0x05, 0x02, 0x49, (0x05 + 0x02 + 0x49) & 0xFF, 0x16])

    def ready(at):
        chip = started_spc3()
        m = dpc31.Master(chip, address=2, slave=dpc31.SlaveConfig(address=5))
        if at > chip.cycle:
            chip.step(at - chip.cycle)
        chip.drive_rxd_chars(request, 100_000, 4)
        return chip, m

    chip, m = ready(0)
    seen = []
    chip.on_telegram(lambda t: seen.append(chip.cycle))
    m.idle(300_000)
    told = seen[0]  # the cycle the chip tells the request

    for start in (told - 65_536 + 1, told - 65_536):  # within the first slice; its last cycle
        chip, m = ready(start)

        def boom(t):
            raise RuntimeError("observer")

        chip.on_telegram(boom)
        with pytest.raises(RuntimeError, match="observer"):
            m.idle(10**8)
        assert chip.cycle == told
        m.idle(100)  # the next call starts clean
        assert chip.cycle == told + 100
