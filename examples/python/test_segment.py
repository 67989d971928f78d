"""A bus segment from Python (docs/python.md, "A segment"; docs/segment.md): three slaves of the
three profiles, each its own firmware, polled by the built-in master; one slave left unpolled
until its DP watchdog expires; a collision and a lost token counted by the bus check; the
master's start-up spread over its token visits under TTR.

Expected values come from docs/timing.md at 48 MHz, as traces/segment/three_slaves.scn derives
them in its comments (the same line as a scenario): T = 48 MHz / 1.5 Mbaud = 32 clocks per bit.
"""

import pathlib
import re

import dpc31
import pytest

T = 32
# "DP watchdog": TWD = ceil(10 ms x WD_Fact_1 x WD_Fact_2 x f) = 10 ms x 1 x 1 x 48 MHz.
TWD = 480_000
MASTER = "master 2"


def three_slaves():
    seg = dpc31.Segment(1_500_000)
    stations = (seg.add_station(5, "spc3", firmware="DO4", name="spc3", wd=(1, 1)),
                seg.add_station(6, "vpc3plus", firmware="CNT2", name="vpc3plus", wd=(1, 1)),
                seg.add_station(7, "dpc31", firmware="DO4", name="dpc31", wd=(1, 1)))
    master = seg.add_master(2, [5, 6, 7])
    check = seg.check_bus()
    line = []
    seg.on_telegram(line.append)
    return seg, stations, master, check, line


def requests_to(seg, line, address):
    """The master's requests to `address` on the line (SD1/SD3: DA is byte 1; SD2: byte 4)."""
    out = []
    for t in line:
        if seg.name(t.sender) != MASTER or t.bytes[0] == 0xDC:
            continue
        da = t.bytes[4] if t.bytes[0] == 0x68 else t.bytes[1]
        if da & 0x7F == address:
            out.append(t)
    return out


def acted_on(t):
    """A request is acted on at its last stop sample: end - T + floor(T/2) (docs/timing.md)."""
    return t.end - T + T // 2


def test_three_slaves_reach_data_exchange_each_at_its_cycle():
    seg, stations, master, check, line = three_slaves()
    assert master.startup_all()
    exchanges = master.dp_cycle() + master.dp_cycle() + master.dp_cycle()
    seg.flush()
    for st in stations:
        assert (st.dp_state, st.wd_state) == (dpc31.DpState.Data_Exchange,
                                              dpc31.WdState.DP_Control)
    # every answer MinTSDR = 11 T after its request's end (MinTSDR_Val 11, set by both firmwares)
    answered = [ex for ex in master.history if ex.answer is not None]
    assert answered and all(ex.answer_start - ex.request_end == 11 * T for ex in answered)
    assert [ex.answer.sa for ex in exchanges] == [5, 6, 7] * 3
    # Data_Exchange entered after the Chk_Cfg's end: the SPC3 at DO4's first New_Din_Buffer_Cmd
    # (access 14 of the ISR entered at the acted-on cycle, end - 16: end + 40), the VPC3+ and the
    # DPC31 at the User_Cfg_Data_Okay read (access 10: end + 24); three_slaves.scn derives them.
    for st, after in zip(stations, (40, 24, 24)):
        entered = next(c for c, dp, _ in st.changes if dp == dpc31.DpState.Data_Exchange)
        last = [t for t in requests_to(seg, line, st.address) if acted_on(t) <= entered][-1]
        assert last.bytes[8] == 0x3E  # Chk_Cfg: DSAP 62
        assert entered - last.end == after, st.name
    assert check.total == 0 and seg.collisions == []


def test_an_unpolled_slave_expires_at_its_cycle_the_others_stay():
    seg, stations, master, check, line = three_slaves()
    spc3, vpc3plus, dpc31_st = stations
    assert master.startup_all()
    master.dp_cycle()
    foreign = [st.fdl_counters["foreign_address"] for st in stations]
    # 40 DP cycles over 5 and 6 only (about 0.45 ms each: more than TWD)
    for _ in range(40):
        master.dp_cycle(skip=[7])
    seg.flush()
    # The watchdog restarts at the acted-on cycle of the last request from Master_Add to 7 and
    # expires TWD later: Baud_Control and Leave_Master (Wait_Prm) in that cycle.
    restart = acted_on(requests_to(seg, line, 7)[-1])
    expired = next(c for c, _, wd in dpc31_st.changes
                   if wd != dpc31.WdState.DP_Control and c > restart)
    assert expired == restart + TWD
    assert (dpc31_st.dp_state, dpc31_st.wd_state) == (dpc31.DpState.Wait_Prm,
                                                      dpc31.WdState.Baud_Control)
    for st in (spc3, vpc3plus):
        assert (st.dp_state, st.wd_state) == (dpc31.DpState.Data_Exchange,
                                              dpc31.WdState.DP_Control)
    # What each ignored: a request to another station is counted in foreign_address (the
    # answers are not): per cycle, 7 heard the requests to 5 and 6, 5 the one to 6.
    now = [st.fdl_counters["foreign_address"] for st in stations]
    assert [b - a for a, b in zip(foreign, now)] == [40, 40, 80]
    # each firmware set its own chip's station address (R_TS_Adr) at init
    assert [st.peek_reg("R_TS_Adr") for st in stations] == [5, 6, 7]
    assert check.total == 0


def test_a_collision_and_a_lost_token_are_counted():
    # 12 Mbaud (T = 4): the chips search 12 Mbaud first, so a request at 20 000, long after their
    # Start plus TSYN, is heard at once (docs/timing.md, "Baud_Search").
    t = 4
    seg = dpc31.Segment(12_000_000)
    seg.add_station(5, "spc3", name="spc3")
    seg.add_station(5, "dpc31", name="twin")  # a second station at address 5
    master = seg.add_sender(MASTER)
    check = seg.check_bus(ttr=1000, masters=[2])
    # FDL_Status 5 <- 2: SD1 DA SA FC FCS ED, FCS = 05 + 02 + 49 = 50h
    end = seg.send(master, bytes([0x10, 5, 2, 0x49, 0x50, 0x16]), start=20_000)
    seg.run_until(end + 400 * t)
    # both answer at end + 11 T: the second driver collides there, the first keeps the line
    [c] = seg.collisions
    assert (c.cycle, seg.name(c.first), seg.name(c.second)) == (end + 11 * t, "spc3", "twin")
    assert c.answer  # a chip's: a slave sends nothing but answers
    assert check.count("collision") == 1
    assert any("twin drove the line while spc3 had it" in l for l in seg.bus_log)
    # The token to master 3, which is not there: the line stays idle; TTO = TSL x (6 + 2 x 2),
    # 2 the lowest master's address, = 1000 T.
    token_end = seg.send(master, bytes([0xDC, 3, 2]))
    seg.run_until(token_end + 1000 * t - 1)
    assert check.count("token_lost") == 0
    seg.run_until(token_end + 1000 * t)
    assert check.count("token_lost") == 1
    assert check.total == 2


def test_a_startup_under_ttr_is_spread_over_the_visits():
    # TTR 500 bit times, a master alone: tests/segment_test.cpp
    # (Segment.AMasterUnderTtrSpreadsItsStartupOverItsVisits) derives every visit by hand.
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3", wd=(100, 100))
    seg.add_station(6, "vpc3plus", wd=(100, 100))
    master = seg.add_master(2, [5, 6], ttr=500)
    check = seg.check_bus(ttr=500)
    master.begin_startup()
    visits = []
    while master.starting_up:
        visits.append(master.use_token(2))
    assert master.started_up and len(visits) == 256
    assert [len(v.startup) for v in visits[:6]] == [3, 1, 2, 1, 2, 1]
    assert visits[246].rotation == 265 * T and len(visits[246].startup) == 2  # the first answer
    assert [v.startup for v in visits[-5:]] == [[1]] * 5
    assert check.count("token_hold") == 0 and check.total == 0
    # startup_all under the same check: every request after TTR since the first is token_hold
    seg2 = dpc31.Segment(1_500_000)
    seg2.add_station(5, "spc3", wd=(100, 100))
    m2 = seg2.add_master(2, [5], ttr=500)
    check2 = seg2.check_bus(ttr=500)
    assert m2.startup_all()
    assert check2.count("token_hold") > 0


def test_a_slave_locked_by_another_master_is_named_in_locks():
    # Master 3 parameterises station 5 (Lock_Req); master 2's start-up finds master 3 in its
    # Slave_Diag's Master_Add and leaves it alone (docs/segment.md, the scenario's `startup`),
    # takes station 6, and names the lock where startup_all's False cannot (docs/python.md).
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3", wd=(100, 100))
    seg.add_station(6, "vpc3plus", wd=(100, 100))
    m3 = seg.add_master(3, [5])
    m2 = seg.add_master(2, [5, 6])
    assert m3.startup_all() and m3.locks == {}
    assert not m2.startup_all()
    assert m2.locks == {5: 3}
    sent_to_5 = [ex.request.service for ex in m2.history if ex.request.da == 5]
    assert "Set_Prm" not in sent_to_5 and sent_to_5[-1] == "Slave_Diag"


def test_the_built_in_user_side_serves_its_user_watchdog_when_asked():
    """docs/timing.md: the user watchdog counts Data_Exchanges; the user side's Start loads
    R_User_WD_Value at the first, each later one counts down, and the one that reaches 0 is not
    answered. R_User_WD_Value = 3 unserved: Data_Exchanges 1..3 answered, the 4th not; served
    (user_wd=True: Res_User_WD on every DX_Out): every one answered."""
    import pytest
    seg = dpc31.Segment(12_000_000)
    unserved = seg.add_station(5, "spc3", user_wd_value=3)
    served = seg.add_station(6, "vpc3plus", user_wd=True, user_wd_value=3)
    master = seg.add_master(2, [5, 6])
    assert master.startup_all()
    with_data = [[ex.answer is not None and len(ex.answer.du) == 4 for ex in master.dp_cycle()]
                 for _ in range(6)]
    assert [c[0] for c in with_data] == [True, True, True, False, False, False]
    assert all(c[1] for c in with_data)
    assert unserved.dp_state == dpc31.DpState.Wait_Prm
    assert served.dp_state == dpc31.DpState.Data_Exchange
    # the checks of a scenario's `station`
    # user_wd given at all beside a firmware, True or False, as user_wd=0 on a `station` line
    for given in (True, False):
        with pytest.raises(ValueError, match="'user_wd' configures the built-in user side"):
            seg.add_station(7, "spc3", firmware="DO4", user_wd=given)
    with pytest.raises(ValueError, match="user_wd_value needs user_wd=1 on profile dpc31"):
        seg.add_station(8, "dpc31", user_wd_value=5)
    # its range, in the `station` line's words, as Master.run_responder's (was pybind's TypeError)
    for value in (70000, -1):
        with pytest.raises(ValueError, match=rf"^user_wd_value {value} out of range \(0..65535\)$"):
            seg.add_station(9, "spc3", user_wd_value=value)


def test_a_long_run_takes_its_user_sides_interrupts_so_they_stay_short():
    """interrupts grows for as long as a user side runs; take_interrupts() returns the records
    and forgets them. Two identical segments, the first's taken after every DP cycle: nothing is
    left after a take, and the takes in order are the twin's interrupts, none lost or repeated."""
    def segment():
        seg = dpc31.Segment(12_000_000)
        stations = (seg.add_station(5, "spc3", user_wd=True),
                    seg.add_station(6, "dpc31", firmware="DO4"))
        master = seg.add_master(2, [5, 6])
        assert master.startup_all()
        return (stations[0].responder, stations[1].firmware), master
    user_sides, master = segment()
    twins, twin_master = segment()
    taken = ([], [])
    for _ in range(300):
        master.dp_cycle()
        twin_master.dp_cycle()
        for side, into in zip(user_sides, taken):
            into.extend(side.take_interrupts())
            assert side.interrupts == []
        master.clear_history()
        twin_master.clear_history()
    for side, into, twin in zip(user_sides, taken, twins):
        assert len(twin.interrupts) > 300  # one ISR entry per Data_Exchange at least
        assert into + side.interrupts == twin.interrupts


def test_a_long_run_takes_its_firmwares_port_writes_so_they_stay_short():
    """port_writes grows by one write per port write of the firmware (DO4: each change of its
    terminals, here on every Data_Exchange: terminals 1, 2, 1, ... with OSPValid set in the
    second output byte, firmware/do4/do4.c); take_port_writes() returns them and forgets them,
    none lost or repeated. dp_cycle takes each slave's outputs as bytes, a bytearray or a list of
    ints."""
    def segment():
        seg = dpc31.Segment(12_000_000)
        station = seg.add_station(6, "dpc31", firmware="DO4")
        master = seg.add_master(2, [6])
        assert master.startup_all()
        return station.firmware, master
    firmware, master = segment()
    twin, twin_master = segment()
    taken = []
    for k in range(300):
        master.dp_cycle([bytes([1 + k % 2, 0x01])])
        twin_master.dp_cycle([[1 + k % 2, 0x01]] if k % 3 else [bytearray([1 + k % 2, 0x01])])
        taken.extend(firmware.take_port_writes())
        assert firmware.port_writes == []
        master.clear_history()
        twin_master.clear_history()
    # do4.c's drive(): the first Data_Exchange sets the terminals (0 -> 1), then modul_ok (OSP
    # left: 0 -> 1); every one after changes the terminals only.
    assert len(twin.port_writes) == 301
    assert [(port, value) for _, port, value in taken[:4]] == [
        ("outputs", 1), ("modul_ok", 1), ("outputs", 2), ("outputs", 1)]
    assert taken == twin.port_writes
    import pytest
    with pytest.raises(TypeError, match=r"outputs\[1\]: bytes expected, got str"):
        master.dp_cycle([b"\x01\x01", "no"])


def test_a_running_user_side_is_refused_to_another_thread_and_changes_to_an_observer():
    """While the segment runs, its user sides run: another thread gets a clear error instead of a
    data race, and an observer (the running thread, between two of the ISR's accesses) may look
    at a user side but not take or change what its ISR uses. After the run every call works."""
    import threading

    import pytest

    seg = dpc31.Segment(1_500_000)
    st = seg.add_station(5, "spc3")
    fw_st = seg.add_station(6, "dpc31", firmware="DO4")
    master = seg.add_master(2, [5, 6])
    assert master.startup_all()
    r, fw = st.responder, fw_st.firmware
    started, proceed = threading.Event(), threading.Event()
    in_observer = {}

    def observer(_):
        if started.is_set():
            return
        in_observer["looked"] = (len(r.interrupts), len(r.outputs), fw.port("outputs"))
        for name, call in (("take_interrupts", r.take_interrupts),
                           ("keep_last_output", r.keep_last_output),
                           ("take_port_writes", fw.take_port_writes),
                           ("inputs", lambda: setattr(r, "inputs", b"\x01"))):
            try:
                call()
            except dpc31.Error as e:
                in_observer[name] = str(e)
        started.set()
        proceed.wait()  # the GIL released: the main thread calls now

    seg.on_telegram(observer)
    runner = threading.Thread(target=master.dp_cycle)
    runner.start()
    assert started.wait(60)
    try:
        for call in (r.take_interrupts, lambda: r.outputs, lambda: r.cfg_accepted,
                     fw.take_port_writes, lambda: fw.port("outputs"),
                     lambda: fw.hw_input("inputs", 1)):
            with pytest.raises(dpc31.Error, match="running in another thread"):
                call()
    finally:
        proceed.set()
        runner.join()
    assert len(in_observer["looked"]) == 3
    for name in ("take_interrupts", "keep_last_output", "take_port_writes", "inputs"):
        assert "an observer may look" in in_observer[name], name
    assert len(r.take_interrupts()) > 0 and r.interrupts == []
    r.keep_last_output()
    fw.take_port_writes()


def test_outputs_are_copies_that_stay_valid():
    """Responder.outputs gives copies: a list taken earlier keeps its values after the ISR has
    fetched more outputs and keep_last_output() forgot them (it pointed into freed memory)."""
    seg = dpc31.Segment(1_500_000)
    slave = dpc31.SlaveConfig(address=5, cfg=b"\x21", out_len=2)  # 2 bytes out (Cfg 0x21)
    r = seg.add_station(5, "spc3", slave=slave).responder
    master = seg.add_master(2, [slave])
    assert master.startup_all()
    master.dp_cycle([b"\xa5\x5a"])
    before = r.outputs
    kept = [(o.cycle, o.data, o.cleared) for o in before]
    for i in range(100):
        master.dp_cycle([bytes([i, 255 - i])])
    r.keep_last_output()
    assert [(o.cycle, o.data, o.cleared) for o in before] == kept
    assert kept[-1][1] == b"\xa5\x5a" and r.outputs[-1].data == bytes([99, 156])


def test_the_shipped_segment_scenarios_pass(traces):
    for name in ("three_slaves.scn", "startup_ttr.scn"):
        result = dpc31.SegmentScenario.load(str(traces / "segment" / name)).run()
        assert result.ok, result.failures


def test_the_example_of_docs_python_md_runs(traces):
    doc = (pathlib.Path(traces).parent / "docs" / "python.md").read_text()
    section = doc.split("## A segment", 1)[1]
    example = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    exec(compile(example, "docs/python.md", "exec"), {})


def test_the_bus_check_takes_the_masters_slot_time():
    # docs/python.md, "The bus check": slot_bits defaults to the largest TSL of the masters added.
    # Set_Prm's MinTSDR 200 places every answer 200 T after its request's end (docs/timing.md,
    # "answer": max(11, MinTSDR) T; the Set_Prm's own SC too). Master 2's TSL is 300 bit times, so
    # it takes each answer (review B, finding 2): neither late (past TSL) nor unsolicited (past
    # TSL + TSYN = 133 with the old default of 100).
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3", slave=dpc31.SlaveConfig(address=5, min_tsdr=200))
    master = seg.add_master(2, [5], slot_bits=300)
    check = seg.check_bus()
    assert master.startup_all()
    seg.flush()
    late = [ex for ex in master.history
            if ex.answer is not None and ex.answer_start - ex.request_end == 200 * T]
    assert late, "no answer at MinTSDR 200"
    assert (check.count("late_answer"), check.count("unsolicited")) == (0, 0), seg.bus_log


def test_bad_input_is_a_clear_error_and_an_observers_exception_arrives():
    import pytest
    with pytest.raises(ValueError, match="baud 0 is not a PROFIBUS rate"):
        dpc31.Segment(0)
    with pytest.raises(ValueError, match="clock_hz 1"):
        dpc31.Segment(1_500_000, clock_hz=1)
    seg = dpc31.Segment(1_500_000)
    with pytest.raises(ValueError, match="profile"):
        seg.add_station(5, "spc4")
    seg.add_station(5, "spc3")
    with pytest.raises(ValueError, match="no station at address 9"):
        seg.add_master(2, [9])
    stations = seg.size
    with pytest.raises(ValueError, match=r"^DpMaster: slave 5 is listed twice \(a slave has one FCB\)$"):
        seg.add_master(2, [5, 5])
    assert seg.size == stations  # the refused master's station did not join
    master = seg.add_master(2, [5])
    sender = seg.add_sender("rogue")
    with pytest.raises(ValueError, match="fault"):
        seg.send(sender, b"\x10", fault="smoke")
    check = seg.check_bus()
    with pytest.raises(ValueError, match="no violation 'late'"):
        check.count("late")

    def boom(t):
        raise KeyError("observer")

    seg.on_telegram(boom)
    with pytest.raises(KeyError, match="observer"):
        master.fdl_status()
    # docs/python.md, "A segment": a master's call ends after the wait the exception came in. The
    # start-up's first request is the only one sent (it ran all its tries on before).
    requests = master.counters.requests
    with pytest.raises(KeyError, match="observer"):
        master.startup_all()
    assert master.counters.requests == requests + 1
    seg.on_telegram(None)
    with pytest.raises(ValueError, match="before the line's time"):
        seg.send(sender, b"\x10", start=0)


def test_a_master_and_a_chip_station_never_share_an_address():
    # docs/python.md, "A segment": refused as a segment scenario's `master` and `station` lines
    # refuse it, in their words, the station not joined (s34 audit aSeg, finding 5: master 5
    # polled its own address and the chip there answered it). A SlaveConfig at the master's own
    # address is refused by DpMaster itself, the C++ door's words.
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    with pytest.raises(ValueError, match=r"^master 5 at the address of station 5$"):
        seg.add_master(5, [5])
    assert seg.size == 1
    seg.add_master(2, [5])
    with pytest.raises(ValueError, match=r"^station 2 at the address of master 2$"):
        seg.add_station(2, "dpc31")
    assert seg.size == 2
    with pytest.raises(ValueError, match=r"^DpMaster: master 3 at the address of station 3$"):
        seg.add_master(3, [dpc31.SlaveConfig(address=3)])
    assert seg.size == 2


def test_a_second_station_in_one_waveform_scope_is_refused(tmp_path):
    # docs/python.md, "A segment": the name is the station's scope in the waveforms; `a/b` and
    # `a_b` at one address are both station5_a_b (s35 audit aMix finding 5), refused at the
    # second's add_station in a segment scenario's words, outputs asked or not, the station not
    # joined.
    for vcd in (None, str(tmp_path / "s.vcd")):
        seg = dpc31.Segment(1_500_000, vcd=vcd)
        seg.add_station(5, "spc3", name="a/b")
        with pytest.raises(ValueError, match=r"^a second station named 'a_b' in the waveform "
                           r"scope of 'a/b' \(station5_a_b\)$"):
            seg.add_station(5, "vpc3plus", name="a_b")
        assert seg.size == 1
        seg.add_station(6, "spc3", name="a_b")  # station6_a_b: a scope of its own
        assert seg.size == 2


def test_a_stations_snapshot_is_its_chips_at_the_lines_time():
    # docs/python.md, "A segment": Station.save_state is the station's chip's snapshot at the
    # line's time (s35 audit aMix finding 10: no snapshot door for a station outside C++). Loaded
    # into a Chip of its profile it is that chip: its cycle, states, counters and registers, and
    # it saves back to the same bytes.
    seg, stations, master, check, line = three_slaves()
    assert master.startup_all()
    master.dp_cycle()
    for st in stations:
        snap = st.save_state()
        chip = dpc31.Chip(st.profile)
        chip.load_state(snap)
        assert chip.cycle == st.cycle == seg.cycle
        assert (chip.dp_state, chip.wd_state) == (dpc31.DpState.Data_Exchange,
                                                  dpc31.WdState.DP_Control)
        assert chip.fdl_counters == st.fdl_counters
        assert chip.peek_reg("Status_Reg") == st.peek_reg("Status_Reg")
        assert chip.save_state() == snap


def test_a_slave_read_back_is_a_read_only_copy():
    # docs/python.md: Station.slave and SegmentMaster.slave are copies of the slave the master
    # sends (given at add_station); a field set on one raises instead of changing nothing.
    seg = dpc31.Segment(1_500_000)
    st = seg.add_station(5, "spc3", name="spc3", wd=(3, 4))
    master = seg.add_master(2, [5])
    for obj, owner in ((st, "Station.slave"), (master, "SegmentMaster.slave")):
        slave = obj.slave
        assert isinstance(slave, dpc31.MasterSlave) and isinstance(slave, dpc31.SlaveConfig)
        assert (slave.address, slave.wd_fact1, slave.wd_fact2) == (5, 3, 4)
        try:
            slave.user_prm = b"\x01"
        except AttributeError as e:
            assert str(e) == (f"{owner} is a read-only copy: setting its user_prm would change "
                              "nothing the master sends; give the slave as "
                              "Segment.add_station(..., slave=SlaveConfig(...))")
        else:
            raise AssertionError(f"{owner}: a field set on the copy was taken in silence")


def test_a_bus_check_kept_from_before_a_second_check_bus_keeps_its_counts():
    """docs/python.md, "The bus check": a second check_bus() starts a new check; the BusCheck
    kept from the first keeps the counts it had (it read freed memory: s31 benches finding 1).
    One telegram of two characters 55h 01h from a sender is no frame (docs/segment.md,
    bad_frame)."""
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    sender = seg.add_sender("noise")
    first = seg.check_bus()
    seg.send(sender, b"\x55\x01")
    seg.run_until(seg.cycle + 10_000)
    assert first.total == 1 and first.count("bad_frame") == 1
    second = seg.check_bus()
    junk = [bytearray(b"\xff" * 2440) for _ in range(200)]  # what reused the freed check
    assert first.total == 1 and first.counts["bad_frame"] == 1 and len(junk) == 200
    seg.send(sender, b"\x55\x01")
    seg.run_until(seg.cycle + 10_000)
    assert (first.total, second.total, seg.bus_check.total) == (1, 1, 1)
    seg.send(sender, b"\x55\x01")
    seg.run_until(seg.cycle + 10_000)
    assert (first.total, second.total, seg.bus_check.total) == (1, 2, 2)


def test_a_running_segments_state_is_refused_to_another_thread(refused_while):
    """docs/python.md, "A segment": one thread at a time. The line's cycle and collisions, a
    station's changes, a master's selected slave, start-up and token state, the bus check's
    counts were read (and bus_log flushed the running check) by another thread while the segment
    ran (s31 benches finding 3): each is refused now, as a master's history is. Looked at while
    an on_telegram observer holds a dp_cycle."""
    seg = dpc31.Segment(1_500_000)
    st = seg.add_station(5, "spc3")
    master = seg.add_master(2, [5])
    check = seg.check_bus()
    assert master.startup_all()
    looks = {
        "Segment.cycle": lambda: seg.cycle, "Segment.collisions": lambda: seg.collisions,
        "Segment.bus_log": lambda: seg.bus_log, "Station.changes": lambda: st.changes,
        "SegmentMaster.selected": lambda: master.selected,
        "SegmentMaster.slave": lambda: master.slave,
        "SegmentMaster.starting_up": lambda: master.starting_up,
        "SegmentMaster.started_up": lambda: master.started_up,
        "SegmentMaster.token_rotation": lambda: master.token_rotation,
        "SegmentMaster.history": lambda: master.history,
        "SegmentMaster.clear_history": master.clear_history,
        "BusCheck.total": lambda: check.total, "BusCheck.counts": lambda: check.counts,
        "BusCheck.count": lambda: check.count("bad_frame"),
        "constants": lambda: (seg.size, seg.bit_cycles, seg.clock_hz, st.name, st.address,
                              master.address, master.slave_count),
    }
    refused = refused_while(master.dp_cycle, looks, seg.on_telegram)
    assert set(refused) == set(looks) - {"constants"}
    for name, e in refused.items():
        # bus_log and clear_history change the running state: refused to an observer too
        assert e in ("the segment is running in another thread (one thread at a time)",
                     "the segment is running (another thread, or an observer)"), name
    assert len(master.history) > 0 and check.total == 0


def test_an_observer_may_look_at_the_segments_state_but_not_flush_its_check():
    """The running thread's observer may read what it looks at (a master's history is so), not
    bus_log, which flushes the running check."""
    seg = dpc31.Segment(1_500_000)
    st = seg.add_station(5, "spc3")
    master = seg.add_master(2, [5])
    check = seg.check_bus()
    seen = []

    def observer(_):
        if seen:
            return
        seen.append((seg.cycle > 0, len(st.changes), check.total, master.started_up))
        try:
            seg.bus_log
        except dpc31.Error as e:
            seen.append(str(e))

    seg.on_telegram(observer)
    assert master.startup_all()
    assert seen[0][0] and seen[1:] == ["the segment is running (another thread, or an observer)"]


def test_dp_cycle_skip_refuses_what_a_scenarios_cycle_skip_refuses(cli, tmp_path):
    """docs/python.md, "Errors": a value a scenario line takes too is refused in its words. A
    skip= address that is no station (a typo) was accepted and every slave polled (s31 benches
    finding 5); `cycle 1 skip=` refuses it in a segment scenario."""
    import subprocess

    import pytest

    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    seg.add_station(6, "spc3")
    master = seg.add_master(2, [5, 6])
    assert master.startup_all()
    words = {}
    for skip in (99, 200):
        scn = tmp_path / f"skip{skip}.scn"
        scn.write_text("segment baud=1500000\nstation 5 profile=spc3\nstation 6 profile=spc3\n"
                       f"master 2 slaves=5,6\nstartup\ncycle 1 skip={skip}\n")
        r = subprocess.run([cli, "run", str(scn)], capture_output=True, text=True)
        assert r.returncode == 2
        words[skip] = r.stderr.strip().removeprefix(f"{scn}:6: ")
    assert words == {99: "no station 99", 200: "station 200 out of range (0..126)"}
    before = len(master.history)
    for skip in (99, 200):
        with pytest.raises(ValueError) as e:
            master.dp_cycle(skip=[5, skip])
        assert str(e.value) == words[skip]
    with pytest.raises(ValueError, match=r"^station 1099511627776 out of range \(0\.\.126\)$"):
        master.dp_cycle(skip=[2**40])
    assert len(master.history) == before  # nothing polled
    assert [e.request.da for e in master.dp_cycle(skip=[5])] == [6]


@pytest.mark.parametrize("outputs", [False, True])
def test_a_station_refused_at_its_init_leaves_the_segment_as_it_was(built, tmp_path, outputs):
    """docs/python.md, "A segment": an add_station whose firmware's init fails (the bad plug-in's
    NULL buffer to CopyToVpc3) takes its chip off the line again: the segment's size, stations and
    cycle are as before, its name, address and index are free, and the line runs as on a segment
    that never saw it; with outputs, the waveform and the pcapng are those of that segment byte
    for byte (no scope of the refused station)."""
    bad = str(built("DPC31_BAD_PLUGIN_HAL_INIT"))

    def run(refused):
        d = tmp_path / ("refused" if refused else "plain")
        d.mkdir()
        files = {"vcd": str(d / "seg.vcd"), "pcapng": str(d / "seg.pcapng")} if outputs else {}
        seg = dpc31.Segment(1_500_000, **files)
        seg.add_station(5, "spc3", firmware="DO4", name="spc3", wd=(1, 1))
        if refused:
            cycle = seg.cycle
            # Refused before the chip is made: a taken name, a bad address, firmware or profile,
            # buffers past the built-in user side's RAM.
            for bad_args in (dict(address=6, name="spc3"), dict(address=200),
                             dict(address=6, firmware="NOPE"), dict(address=6, profile="spc4"),
                             dict(address=6, profile="spc3",
                                  slave=dpc31.SlaveConfig(address=6, in_len=244, out_len=244))):
                with pytest.raises((ValueError, dpc31.FirmwareError)):
                    seg.add_station(**bad_args)
                assert seg.size == 1, bad_args
            # Refused by the firmware's init, on the station's chip: it leaves again.
            with pytest.raises(dpc31.FirmwareError,
                               match=r"^firmware BAD: CopyToVpc3: local buffer is NULL"):
                seg.add_station(6, "dpc31", firmware=bad, name="dpc31")
            assert (seg.size, len(seg.stations), seg.cycle) == (1, 1, cycle)
        station = seg.add_station(6, "dpc31", firmware="DO4", name="dpc31", wd=(1, 1))
        assert (station.index, seg.size) == (1, 2)
        master = seg.add_master(2, [5, 6])
        line = []
        seg.on_telegram(line.append)
        assert master.startup_all()
        master.dp_cycle()
        assert seg.collisions == []
        seen = ([(t.sender, t.start, t.end, t.bytes) for t in line], seg.cycle,
                [st.dp_state for st in seg.stations])
        seg.close()
        if outputs:
            seen += ((d / "seg.vcd").read_bytes(), (d / "seg.pcapng").read_bytes())
        return seen

    assert run(True) == run(False)


def test_after_a_late_answer_the_next_request_waits_tsyn_from_its_end():
    # docs/timing.md, "The master's wait": the idle time counts from the end of the last telegram
    # on the line or the master's own exchange's end, whichever is later. 12 Mbaud, T = 4. A
    # Set_Prm to station 5 from its master with Lock/Unlock 00 and byte 3 = 105 takes only MinTSDR
    # (docs/decisions.md, the Set_Prm lock rules): its own SC starts 105 T after the request's end
    # E ("answer": max(11, MinTSDR) T), past TSL = 100, and ends at E + 116 T. The FDL_Status to
    # station 6 then starts TSYN after it, at E + 149 T (not at the slot time's end + TSYN,
    # E + 133 T, where station 6 heard 17 bit times of idle: no_sync, no answer), and is answered.
    seg = dpc31.Segment(12_000_000)
    t = seg.bit_cycles
    seg.add_station(5, "spc3")
    six = seg.add_station(6, "vpc3plus")
    master = seg.add_master(2, [5, 6], slot_bits=100)
    assert master.startup_all()
    check = seg.check_bus(slot_bits=100)
    no_sync = six.fdl_counters["no_sync"]  # the start-up's, from the baud search
    master.select(0)
    prm = master.transact(dpc31.Frame(da=5, sa=2, fc=0x4D, dsap=61, ssap=62,
                                      du=bytes([0x08, 10, 10, 105, 0x0C, 0x31, 0, 0])))
    e = prm.request_end
    assert prm.answer is None and prm.wait_end == e + 100 * t
    master.select(1)
    status = master.fdl_status()
    assert status.request_start == e + 149 * t
    assert status.answer is not None
    assert master.counters.late == 1
    assert six.fdl_counters["no_sync"] == no_sync
    seg.flush()
    # The bus check: the SC late (after TSL, before TSL + TSYN), nothing of the master's.
    assert (check.count("late_answer"), check.total) == (1, 1), seg.bus_log


def test_a_master_starts_no_request_into_another_stations_telegram():
    # docs/segment.md, "Masters on it" (the audit s35 aMix, finding 2): a master drives no busy
    # line. 1.5 Mbaud, T = 32. A scripted FDL_Status to station 5 (SA 9, 6 characters) with its
    # default start, then dp_cycle: the master decides while it is on the line, station 5 answers
    # it 11 T after its end (6 characters), and the Data_Exchange starts TSYN (33 T) after that
    # answer's end, is answered, collides with nothing and is no late answer of the master's.
    seg = dpc31.Segment(1_500_000)
    t = seg.bit_cycles
    seg.add_station(5, "spc3")
    master = seg.add_master(2, [5])
    tool = seg.add_sender("tool")
    assert master.startup_all()
    master.dp_cycle()
    end = seg.send(tool, bytes([0x10, 0x05, 0x09, 0x49, 0x57, 0x16]))
    (dx,) = master.dp_cycle()
    assert dx.request_start == end + (11 + 66 + 33) * t
    assert dx.answer is not None
    assert seg.collisions == [] and master.counters.late == 0


def test_a_bus_check_armed_inside_an_answer_judges_what_begins_after_it():
    # startup_all (as every exchange) returns at its last answer's last stop sample, inside that
    # answer (docs/timing.md, "Serial line": ready at the stop sample, 2 cycles before the end at
    # T = 4): a check armed there does not call that answer, whose request it never saw,
    # unsolicited; the FDL_Status after it is a clean exchange.
    seg = dpc31.Segment(12_000_000)
    seg.add_station(5, "spc3")
    seg.add_station(6, "vpc3plus")
    master = seg.add_master(2, [5, 6], slot_bits=100)
    assert master.startup_all()
    assert seg.cycle == master.history[-1].answer_end - 2
    check = seg.check_bus(slot_bits=100)
    master.select(0)
    assert master.fdl_status().answer is not None
    seg.flush()
    assert check.total == 0, seg.bus_log


def test_a_token_passed_again_after_a_silent_slot_time_is_no_duplicate_token():
    """EN 50170 token passing (docs/segment.md, "The token"; s34 audit aSeg finding 1): master 2
    passes the token to 9 (nobody there), hears nothing for the slot time (100 bit times), passes
    it again, then to master 3, which takes it and passes it back. Master 2 holds the token until
    3 shows activity: no violation (the retry and the pass to 3 were each a duplicate_token)."""
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    m2 = seg.add_master(2, [5])
    m3 = seg.add_master(3, [5])
    check = seg.check_bus()
    for to in (9, 9, 3):
        m2.pass_token(to)
        m2.idle(100 * T)
    assert m3.wait_token(10**6)
    m3.pass_token(2)
    seg.flush()
    assert check.total == 0, seg.bus_log


def test_use_token_takes_the_token_passed_to_it():
    """docs/segment.md "A master that obeys TTR", Arrival (s34 audit aSeg finding 6): a master's
    use_token takes a token to it already on the line, as wait_token would, so a ring of
    use_token alone measures TRR from one arrival (the end of the SD4 to it) to the next; it used
    to claim the token at every visit (TRR 0, TTH the whole TTR)."""
    seg = dpc31.Segment(1_500_000)
    for a, p in ((5, "spc3"), (6, "vpc3plus"), (7, "dpc31")):
        seg.add_station(a, p)
    m2 = seg.add_master(2, [5, 6], ttr=600)
    m3 = seg.add_master(3, [7], ttr=600)
    assert m2.startup_all() and m3.startup_all()
    tokens = {}
    seg.on_telegram(lambda t: tokens.setdefault(t.bytes[1], []).append(t.end)
                    if t.bytes[0] == 0xDC else None)
    check = seg.check_bus()  # the masters' TTR, 600 bit times
    visits = {2: [], 3: []}
    for _ in range(4):
        visits[2].append(m2.use_token(3))
        visits[3].append(m3.use_token(2))
    seg.flush()
    assert [v.arrived for v in visits[3]] == tokens[3]
    assert [v.arrived for v in visits[2][1:]] == tokens[2][:3]
    for vs in visits.values():
        for before, v in zip(vs, vs[1:]):
            assert v.rotation == v.arrived - before.arrived
            assert v.hold == max(0, 600 * T - v.rotation)
    assert check.total == 0, seg.bus_log


def test_check_bus_takes_the_masters_ttr_and_the_masters_added_after_it():
    """docs/python.md "The bus check" (s34 audit aSeg finding 6): without ttr= the check takes
    the TTR the masters obey, as a scenario's `segment` does, with two or more of them; a check
    made before add_master follows the masters added after it (their addresses for TTO and the
    token checks); masters of different TTRs need the check's own."""
    def segment():
        seg = dpc31.Segment(1_500_000)
        seg.add_station(5, "spc3")
        return seg
    counts = []
    for ttr in (None, 600):
        seg = segment()
        m2 = seg.add_master(2, [5], ttr=600)
        seg.add_master(3, [5], ttr=600)
        check = seg.check_bus() if ttr is None else seg.check_bus(ttr=ttr)
        m2.startup_all()  # back to back, past TTR: a master without the token's rules
        seg.flush()
        counts.append(check.count("token_hold"))
    assert counts[0] > 0 and counts[0] == counts[1]
    # Made before the masters: TTO = 100 x (6 + 2 x 2) = 1000 bit times after the token's end.
    seg = segment()
    check = seg.check_bus()
    m2 = seg.add_master(2, [5])
    seg.add_master(3, [5])
    end = m2.pass_token(9).request_end
    seg.run_until(end + 1000 * T - 1)
    assert check.count("token_lost") == 0
    seg.run_until(end + 1000 * T)
    assert check.count("token_lost") == 1 and check.total == 1
    seg = segment()
    seg.add_master(2, [5], ttr=600)
    seg.add_master(3, [5], ttr=800)
    with pytest.raises(ValueError, match=r"^master 3: ttr=800 differs from master 2's ttr=600: "
                                         r"give the bus check's TTR \(check_bus\(ttr=BITS\)\)$"):
        seg.check_bus()
    seg.check_bus(ttr=1000)
    seg = segment()
    seg.add_master(2, [5], ttr=600)
    seg.check_bus()
    with pytest.raises(ValueError, match=r"^master 3: ttr=800 differs from master 2's ttr=600"):
        seg.add_master(3, [5], ttr=800)
    assert seg.size == 2  # the refused master's station did not join


def test_a_master_that_lowers_the_checks_slot_time_below_its_min_tsdr_is_refused():
    """docs/python.md "The bus check" (review s34 rev1 finding 2): a check following the masters'
    slot time refuses a min_tsdr_bits above it in the same words whether the master came first
    (check_bus refuses) or after (add_master refuses; its station does not join). The first
    master's slot_bits=37 replaces the default 100; 60 > 37."""
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    seg.add_master(2, [5], slot_bits=37)
    words = r"^min_tsdr_bits 60 above the slot time 37: no answer could be in time$"
    with pytest.raises(ValueError, match=words):
        seg.check_bus(min_tsdr_bits=60)
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    check = seg.check_bus(min_tsdr_bits=60)
    with pytest.raises(ValueError, match=words):
        seg.add_master(2, [5], slot_bits=37)
    assert seg.size == 1  # nothing joined
    seg.add_master(2, [5], slot_bits=60)  # at the slot time: answers at 60 are in time
    # The check's own slot time is not the masters': nothing to refuse.
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    check = seg.check_bus(min_tsdr_bits=60, slot_bits=100)
    seg.add_master(2, [5], slot_bits=37)
    assert check.total == 0


def test_a_request_lost_in_a_collision_is_no_unsolicited_answer():
    """docs/segment.md "Bus checks", `unsolicited` (review s34 rev1 finding 3): a sender's request
    that drives into another telegram is the collision alone (Collision.answer false); a
    sender's answer there, with no request waiting, is also unsolicited."""
    counts = []
    # FDL_Status 20 <- 3 (FCS 14h + 03h + 49h = 60h), then an answer 2 <- 20 (FC 00h, OK; FCS 16h)
    for lost in (bytes([0x10, 20, 3, 0x49, 0x60, 0x16]), bytes([0x10, 2, 20, 0x00, 0x16, 0x16])):
        seg = dpc31.Segment(1_500_000)
        master = seg.add_sender(MASTER)
        rogue = seg.add_sender("rogue")
        check = seg.check_bus(masters=[2])
        seg.send(master, bytes([0x10, 21, 2, 0x49, 0x60, 0x16]), start=1000)  # FCS 60h
        seg.send(rogue, lost, start=1000 + 11 * T)  # inside the master's telegram
        seg.flush()
        [c] = seg.collisions
        counts.append((c.answer, check.count("collision"), check.count("unsolicited")))
    assert counts == [(False, 1, 0), (True, 1, 1)]


def test_a_master_keeps_the_token_nobody_took():
    """docs/segment.md "The token" (review s34 rev1 finding 1): pass_token to an address of no
    master added leaves the passer holding the token it held, so its next use_token goes on with
    that token (its arrival and TRR), not a fresh claim (TRR 0)."""
    seg = dpc31.Segment(1_500_000)
    seg.add_station(5, "spc3")
    seg.add_station(6, "dpc31")
    m2 = seg.add_master(2, [5], ttr=1000)
    m3 = seg.add_master(3, [6], ttr=1000)
    m2.use_token(3)  # the claim
    m3.use_token(2)
    held = m2.use_token(3)  # the token from 3: TRR measured from the claim
    m3.use_token(2)
    assert m2.wait_token(0)  # 3's token to 2: it arrives TRR after the arrival before
    trr = m2.token_rotation
    m2.pass_token(9)
    seg.run_until(seg.cycle + 100 * T)  # the slot time: 9 showed no activity
    kept = m2.use_token(3)
    assert trr != 0
    assert (kept.arrived, kept.rotation, kept.hold) == (held.arrived + trr, trr,
                                                         max(0, 1000 * T - trr))


def test_a_pulse_of_no_clocks_is_refused_and_puts_nothing_on_the_line():
    """docs/segment.md: a pulse of 0 clocks is refused before the line is touched; it was taken,
    and a started station counted a start_bit error for it (or the line raised an internal
    "line order broken" RuntimeError): audit s35 aTb finding 4."""
    seg = dpc31.Segment(1_500_000)
    station = seg.add_station(5, "spc3", wd=(1, 1))
    rogue = seg.add_sender("rogue")
    start = seg.cycle
    with pytest.raises(ValueError, match="^pulse: low_cycles 0: a pulse lasts 1 clock or more$"):
        seg.pulse(rogue, start + 1000, 0)
    assert seg.cycle == start
    seg.run_until(start + 10_000)
    assert station.fdl_counters["start_bit"] == 0
