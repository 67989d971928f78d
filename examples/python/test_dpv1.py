"""DPV1 from Python: the built-in master reads and writes DO4's OSP record (slot 0, index 1) on a
VPC3+ over MSAC_C1, is refused a missing index, and opens, uses and aborts an MSAC_C2 connection.

The bytes are DO4's record as docs/firmware.md ("DO4 with DPV1") and docs/dpv1.md ("Negative
responses") give it; the cycles are derived by hand in traces/do4_dpv1_vpc3plus.scn (the same
slave, master and firmware: one call is one call, so the Read starts where the scenario's does).
"""

import pytest

import dpc31

T = 32  # clocks per bit at 1.5 Mbaud (docs/timing.md, "Serial line")
CHAR = 11 * T
# DO4's GSD values, with DPV1_Status_1..3 C0 20 00 before its OSPMode 1, replacement value 9,
# refresh monitor off (the scenario's `slave` line).
SLAVE = dict(address=5, ident=0x0D04, cfg=b"\x21\x10", in_len=1, out_len=2, wd_on=True,
             wd_fact1=2, wd_fact2=5, user_prm=b"\xC0\x20\x00\x01\x09\x00")


def do4_in_data_exchange():
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=1_500_000, slave=dpc31.SlaveConfig(**SLAVE))
    fw = master.run_firmware("DO4", gsd_defaults=False)
    assert master.startup()
    master.data_exchange(b"\x05\x01")  # OSPValid: normal operation, outputs 5
    assert fw.port("modul_ok") == 1
    return chip, master, fw


def test_read_and_write_the_osp_record():
    chip, master, fw = do4_in_data_exchange()
    a = master.dpv1_read(0, 1, 2)
    assert a.outcome == dpc31.Dpv1Outcome.positive
    assert a.du == bytes([0x5E, 0x00, 0x01, 0x02, 0x01, 0x09])  # Read, slot, index, 2, OSPMode, 9
    assert a.error is None
    # traces/do4_dpv1_vpc3plus.scn: the Read from t0 = 2 939 600, its response (17 characters)
    # after poll 6, ending at t0 + 45 408; polls 1-5 answered SC.
    assert a.start == 2_939_600
    assert a.end == 2_939_600 + 45_408 == 2_985_008
    assert a.polls == 5
    # The response telegram: DA 82h, SA 85h, FC 08h, DSAP = SSAP = 33h, FCS E0h.
    assert a.last.encode() == bytes([0x68, 0x0B, 0x0B, 0x68, 0x82, 0x85, 0x08, 0x33, 0x33, 0x5E,
                                     0x00, 0x01, 0x02, 0x01, 0x09, 0xE0, 0x16])

    w = master.dpv1_write(0, 1, b"\x01\x06")
    assert w.outcome == dpc31.Dpv1Outcome.positive
    assert w.du == bytes([0x5F, 0x00, 0x01, 0x02])
    assert master.dpv1_read(0, 1, 2).du == bytes([0x5E, 0x00, 0x01, 0x02, 0x01, 0x06])
    # The new replacement value drives the terminals once the master requests OSP.
    master.data_exchange(b"\x05\x00")
    assert fw.port("outputs") == 6 and fw.port("modul_ok") == 0


def test_negative_responses():
    _, master, _ = do4_in_data_exchange()
    a = master.dpv1_read(0, 7, 2)  # no index 7: Read | 80h, DPV1, access / invalid index
    assert a.outcome == dpc31.Dpv1Outcome.negative
    assert a.du == bytes([0xDE, 0x80, 0xB0, 0x00])
    assert a.error == (0x80, 0xB0, 0x00)
    assert master.dpv1_write(0, 1, b"\x01").error == (0x80, 0xB1, 0x00)  # write length error
    assert master.dpv1_write(0, 1, b"\x02\x06").error == (0x80, 0xB7, 0x00)  # OSPMode 2: range


def test_class2_connection():
    _, master, _ = do4_in_data_exchange()
    master.dpv1_rules = dpc31.Dpv1Rules(c2_ssap=48)
    init = master.c2_initiate(send_timeout=100)
    # 57h, Max_Len_Data_Unit 10h, Features_Supported_1 01h (Read/Write) and _2 00h, no profile,
    # S and D Type 0 Len 2, API 0 SCL 0 (traces/do4_dpv1_c2_vpc3plus.scn)
    assert init.du == bytes([0x57, 0x10, 0x01, 0x00] + [0x00] * 4 + [0x00, 0x02, 0x00, 0x02]
                            + [0x00] * 4)
    assert master.c2_sap == 40
    assert master.c2_send_timeout == 100
    assert master.c2_read(0, 1, 2).du == bytes([0x5E, 0x00, 0x01, 0x02, 0x01, 0x09])
    assert master.c2_idle().du == bytes([0x48, 0x00])
    abort = master.c2_abort(reason=3)
    assert abort.outcome == dpc31.Dpv1Outcome.positive and abort.du == b""
    assert abort.last.encode() == b"\xE5"  # SC
    assert master.c2_sap is None
    # Without a connection: no_connection at the cycle asked, nothing sent (docs/dpv1.md). The
    # master acted on the Abort's SC at its stop bit's sample, T/2 = 16 clocks before the SC's
    # end, the Abort's outcome cycle: the Read, asked after that outcome, is stamped there.
    sent, now = master.counters.requests, master.chip.cycle
    assert now == abort.end - 16
    none = master.c2_read(0, 1, 2)
    assert none.outcome == dpc31.Dpv1Outcome.no_connection
    assert (none.start, none.end, none.polls, none.last) == (abort.end, abort.end, 0, None)
    assert (master.counters.requests, master.chip.cycle) == (sent, now)


def test_the_rules_and_the_slave_as_attributes():
    """`master.dpv1_rules.FIELD = v` reaches the master's next service (audit a20, finding 1:
    the getter returned a copy and the write was lost). At 12 Mbaud (T = 4) with a user side that
    works 1 s, C1_Response_Timeout 1 = 10 ms = 480 000 clocks (docs/dpv1.md): the Read's SC ends
    at start + 748 (15 characters of 44 clocks, then SC 11 T later), poll n's SC 704 n later
    (TSYN 132, 11 characters, 11 T, SC); the master gives up at the first at or past 480 000:
    n = 681, as Dpv1Master.ResponseTimeOut."""
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.run_responder(records=[(0, 1, b"\x11\x22\x33\x44")], work_cycles=48_000_000)
    assert master.startup()
    master.dpv1_rules.c1_response_timeout = 1
    assert master.dpv1_rules.c1_response_timeout == 1
    a = master.dpv1_read(0, 1, 4)
    assert (a.outcome, a.polls) == (dpc31.Dpv1Outcome.timeout, 681)
    assert a.end - a.start == 748 + 704 * 681
    # The class-2 master's SAP: every MSAC_C2 request from it, the slave's answers to it (a
    # user side that answers at once: the one above still works on the Read).
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.run_responder(records=[(0, 1, b"\x11\x22\x33\x44")])
    assert master.startup()
    master.dpv1_rules.c2_ssap = 20
    first = len(master.history)
    init = master.c2_initiate(send_timeout=100)
    assert init.last.dsap == 20
    assert {e.request.ssap for e in master.history[first:]} == {20}
    # The slave is a copy (the master is made anew when a user side starts): a field set on it
    # would change nothing, so it raises; reading it works.
    assert master.slave.user_prm == b"\xC0\x00\x00"
    assert isinstance(master.slave, dpc31.SlaveConfig)
    with pytest.raises(AttributeError) as e:
        master.slave.user_prm = b"\x00\x00\x00"
    assert str(e.value) == ("Master.slave is a read-only copy: setting its user_prm would change "
                            "nothing the master sends; give the slave as "
                            "Master(slave=SlaveConfig(...))")


def test_the_built_in_user_side_serves_the_records_a_scenario_gives_it():
    """run_responder takes a scenario's `record` and `dpv1 work=` lines: the first steps of
    traces/dpv1_c1_vpc3plus.scn, one call for one line, with its cycles derived by hand there."""
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.run_responder(records=[(0, 1, b"\x11\x22\x33\x44")], work_cycles=1440)
    assert master.startup()
    a = master.dpv1_read(0, 1, 4)
    assert a.du == bytes([0x5E, 0x00, 0x01, 0x04, 0x11, 0x22, 0x33, 0x44])
    assert (a.end - a.start, a.polls) == (3652, 2)
    w = master.dpv1_write(0, 1, b"\xA1\xA2\xA3\xA4")
    assert (w.du, w.end - w.start, w.polls) == (bytes([0x5F, 0x00, 0x01, 0x04]), 3652, 2)
    assert master.dpv1_read(0, 1, 4).du == bytes([0x5E, 0x00, 0x01, 0x04, 0xA1, 0xA2, 0xA3, 0xA4])
    assert master.dpv1_read(0, 7, 4).error == (0x80, 0xB0, 0x00)  # no index 7: Invalid_Index


def test_alarm_ack_to_sap_51_is_answered_on_sap_51():
    """Alarm_Ack goes to the slave's "SAP 50 or 51" (manual-quotes.md, "DPV1"): sap=51 as a
    scenario's `alarm_ack sap=51` (Dpv1Scenario.AlarmAckOnSap51, the same slave and master). The
    built-in user side echoes the 4 bytes (docs/dpv1.md, "The master's side") from the SAP the
    request came to, to the master's SSAP 51: the response telegram 68 09 09 68, DA 82h, SA 85h
    (address extension: SAPs follow), FC 08h (DL), DSAP 33h, SSAP 33h or 32h, the data unit, FCS
    (the sum of DA..DU modulo 256), 16h."""
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.run_responder(records=[(0, 1, b"\x11\x22\x33\x44")])
    assert master.startup()
    # Specifier: Seq_Nr 3 << 3 = 18h (Add_Ack 0, bits 1..0 0).
    a = master.alarm_ack(0, 1, 3 << 3, sap=51)
    assert a.outcome == dpc31.Dpv1Outcome.positive
    assert a.du == bytes([0x5C, 0x00, 0x01, 0x18])
    assert (a.last.dsap, a.last.ssap) == (51, 51)
    # FCS: 82h + 85h + 08h + 33h + 33h + 5Ch + 00h + 01h + 18h = 1EAh -> EAh.
    assert a.last.encode() == bytes([0x68, 0x09, 0x09, 0x68, 0x82, 0x85, 0x08, 0x33, 0x33, 0x5C,
                                     0x00, 0x01, 0x18, 0xEA, 0x16])
    # Without sap= it goes to SAP 50, as before: FCS 82h + ... + 32h + ... + 20h = 1F1h -> F1h.
    b = master.alarm_ack(0, 1, 4 << 3)
    assert (b.du, b.last.dsap, b.last.ssap) == (bytes([0x5C, 0x00, 0x01, 0x20]), 51, 50)
    assert b.last.encode() == bytes([0x68, 0x09, 0x09, 0x68, 0x82, 0x85, 0x08, 0x33, 0x32, 0x5C,
                                     0x00, 0x01, 0x20, 0xF1, 0x16])


def test_no_answer_is_reported_where_the_masters_wait_ends():
    """`Exchange.wait_end` is where the master's wait ended, and a DPV1 no_answer's cycle
    (docs/timing.md, "The master's wait"; docs/dpv1.md, "The outcome's cycle"). A chip nobody
    started answers nothing: each try's wait ends TSL = 100 bit times (T = 4 at 12 Mbaud) after
    its request's last stop bit."""
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.dpv1_rules.retries = 1
    a = master.dpv1_read(0, 1, 4)
    assert a.outcome == dpc31.Dpv1Outcome.no_answer
    tries = master.history[-2:]
    assert [e.answer_end for e in tries] == [0, 0]
    assert [e.wait_end - e.request_end for e in tries] == [400, 400]
    assert a.end == tries[-1].wait_end


@pytest.mark.parametrize("dsap, name", [
    (48, "SAP 48"), (49, "MSAC_C2_Initiate"), (50, "MSAC_C1_Alarm"), (51, "MSAC_C1"),
    (52, "SAP 52"), (53, "Set_Ext_Prm"), (54, "SAP 54"), (55, "Set_Slave_Add"), (62, "Chk_Cfg"),
])
def test_a_request_names_its_sap_as_the_decoders_do(dsap, name):
    """`Frame.service` (and the run's log, one naming) calls a SAP what the Wireshark, sigrok and
    GTKWave decoders call it (tests/decoder_sap_names.py): 49 MSAC_C2 Initiate, 50 and 51
    MSAC_C1 (manual-quotes.md, "DPV1"), 53 Set_Ext_Prm (VPC3+C p.53), 55..62 the DP services
    (chip-facts.md, "DP SAPs"); a SAP without a service by its number."""
    frame = dpc31.Frame(5, 2, 0x6D, b"\x5E\x00\x01\x04", dsap=dsap, ssap=51)  # SRD_high
    assert frame.service == name


def test_an_initiate_the_slave_refuses_is_aborted_and_its_addresses_are_the_callers():
    """The Initiate from Python (audit s32-dpv1m, findings 1 and 3): the addresses are the
    caller's (s_type=, s_addr=, d_type=, d_addr=); the request is 16 bytes and the two
    addresses (docs/dpv1.md "The Initiate"). A Type 0 S_Addr of 1 byte is one the Profichip
    driver refuses: the built-in user side answers its Abort 58 00 12 00 (Instance MSAC_C2,
    Reason_Code FE), the outcome is `aborted` with that Abort, and no connection is known.
    The default Initiate is then taken; its response swaps S and D."""
    chip = dpc31.Chip("vpc3plus")
    master = dpc31.Master(chip, address=2, baud=12_000_000,
                          slave=dpc31.SlaveConfig(address=5, user_prm=b"\xC0\x00\x00"))
    master.run_responder(records=[(0, 1, b"\x11\x22\x33\x44")])
    assert master.startup()
    first = len(master.history)
    refused = master.c2_initiate(s_addr=b"\x00")
    assert refused.outcome == dpc31.Dpv1Outcome.aborted
    assert refused.du == b"\x58\x00\x12\x00"
    assert refused.abort == (0, 1, 2, 0)
    assert master.c2_sap is None and master.c2_send_timeout is None
    assert master.history[first].request.du == bytes(
        [0x57, 0, 0, 0, 0x00, 0x64, 0x01, 0x00, 0, 0, 0, 0, 0x00, 0x01, 0x00, 0x02, 0x00, 0x00,
         0x00])
    init = master.c2_initiate(s_addr=b"\x00\x11", d_addr=b"\x00\x22")
    assert init.outcome == dpc31.Dpv1Outcome.positive and init.abort is None
    assert init.du == bytes([0x57, 0xF0, 0x01, 0x00, 0, 0, 0, 0, 0x00, 0x02, 0x00, 0x02,
                             0x00, 0x22, 0x00, 0x11])
    with pytest.raises(ValueError, match="s_addr: more than 16 bytes"):
        master.c2_initiate(s_addr=bytes(17))
    # s32-rev2 (review finding 2): both addresses together fit the resource manager's 32-byte
    # buffer beside the request's 16 fixed bytes, or the call is refused, nothing sent.
    sent = master.counters.requests
    with pytest.raises(ValueError, match=r"s_addr and d_addr: 18 bytes together, more than 16: "
                       r"the Initiate \(34 bytes\) would not fit the resource manager's 32-byte"):
        master.c2_initiate(s_type=1, s_addr=bytes(16))
    assert master.counters.requests == sent
    # The largest taken (the connection closed first): a Type 1 S_Addr of 14 bytes beside the
    # Type 0 D_Addr, 32 bytes; the response swaps them.
    master.c2_abort()
    assert master.c2_sap is None
    big = master.c2_initiate(s_type=1, s_addr=bytes(14))
    assert big.outcome == dpc31.Dpv1Outcome.positive
    assert big.du == bytes([0x57, 0xF0, 0x01, 0x00, 0, 0, 0, 0, 0x00, 0x02, 0x01, 0x0E, 0x00,
                            0x00]) + bytes(14)
    with pytest.raises(ValueError, match=r"d_type 256 out of range \(0..255\)"):
        master.c2_initiate(d_type=256)
