// DO4 speaking DPV1 on the VPC3+ (docs/firmware.md "DO4 with DPV1", docs/dpv1.md): the master
// reads and writes the OSP configuration record at run time through MSAC_C1 (SAP 51), driven
// only from the bus side (DpMaster::acyclic, the PDU builders of dpc31/pdu.hpp). Expected bytes
// come from the PDU layouts of IEC 61158-6 type 3 (function number, slot, index, length; the
// negative response: function | 80h, Error_Decode 80h, Error_Code_1 class | code, Error_Code_2)
// and the record as docs/firmware.md defines it; cycles from docs/timing.md: a request is acted
// on at the stop sample of its last character, an answer starts max(11, MinTSDR) = 11 bit times
// after the request's end (the firmware writes MinTSDR_Val 0Bh) and takes 11 bit times per
// character; Poll_End_Ind is raised at the last stop bit of the response (VPC3+C p.56).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "do4/do4.h"
#include "dp_master.hpp"
#include "dpc31/dpc31_regs.h"
#include "dpc31/dpv1.hpp"
#include "dpc31/pdu.hpp"
#include "firmware_bench.hpp"
#include "scenario.hpp"

namespace {

using namespace dpc31;
using firmware_bench::Bench;
using firmware_bench::gsd_slave;

constexpr std::uint8_t kC1 = 51;     // MSAC_C1 Read / Write: the slave's SAP, the master's SSAP
constexpr std::uint8_t kAlarm = 50;  // MSAC_C1 Alarm_Ack
constexpr std::uint32_t kBaud = 1'500'000;
constexpr std::uint64_t kT = 48'000'000 / kBaud;  // clocks per bit

// Set_Prm bytes 7..: DPV1_Status_1 = DPV1_Enable | Fail_Safe (C0h: DO4 runs with
// Spec_Clear_Mode, "Fail_Safe_required", VPC3+C p.53), DPV1_Status_2, _3 = 0; then DO4's
// OSPMode, replacement value, refresh monitor (0: off).
SlaveConfig dpv1_slave(std::uint8_t mode, std::uint8_t value, std::uint8_t status2) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.wd_fact1 = 2;
  s.wd_fact2 = 5;  // TWD = 2 x 5 x 10 ms = 100 ms
  s.user_prm = {0xC0, status2, 0x00, mode, value, 0x00};
  return s;
}

struct Dpv1Bench : Bench {
  explicit Dpv1Bench(std::uint8_t status2 = 0x00)
      : Bench(Profile::vpc3plus, do4_firmware, dpv1_slave(DO4_REPLACE, 0x09, status2), kBaud) {}

  // A request to SAP 51, then polls (SRD without data) until the answer has data. `polls` gets
  // every poll that was answered SC.
  fdl::Frame request(const pdu::Bytes& du, std::vector<Exchange>* polls = nullptr,
                     std::uint8_t sap = kC1) {
    first = master.acyclic(sap, kC1, du);
    EXPECT_TRUE(first.answer && *first.answer == fdl::sc()) << "the request is answered SC";
    for (int i = 0; i < 200; ++i) {
      last = master.acyclic(sap, kC1, {});
      if (last.answer && !last.answer->du.empty()) return *last.answer;
      EXPECT_TRUE(last.answer && *last.answer == fdl::sc());
      if (polls != nullptr) polls->push_back(last);
    }
    ADD_FAILURE() << "no response after 200 polls";
    return {};
  }
  Exchange first, last;
};

// Read slot 0 index 1 (the OSP record, 2 bytes) with Length 2: 5Eh 00h 01h 02h. The request is
// stored (FDL_Ind at its acted-on cycle) and answered SC; the 1 ms task answers, so the polls
// before it get SC and raise no interrupt; the response is 5Eh 00h 01h 02h, OSPMode 01h,
// replacement value 09h, with FC 08h (DL) from SAP 51 to SAP 51; Poll_End_Ind at its last stop
// bit: request end + 11 T + 17 characters x 11 T (68h LE LEr 68h DA SA FC DSAP SSAP, 6 data
// bytes, FCS, 16h).
TEST(Do4Dpv1, ReadOspRecordAfterPollsWithPollEndIndAtItsLastStopBit) {
  Dpv1Bench b;
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});  // normal operation
  const std::uint64_t requests_before = firmware_bench::stats_of(b.host)->dpv1_requests;
  std::vector<Exchange> polls;
  const fdl::Frame resp = b.request(pdu::read_request(0, 1, 2).build(), &polls);
  EXPECT_EQ(resp.du, (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x01, 0x09}));
  EXPECT_EQ(resp.fc, 0x08);
  EXPECT_EQ(resp.dsap, kC1);
  EXPECT_EQ(resp.ssap, kC1);
  // FDL_Ind at the request's acted-on cycle; one indication, the polls none.
  EXPECT_NE(std::find(b.activations.begin(), b.activations.end(), b.acted(b.first)),
            b.activations.end());
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_requests, requests_before + 1);
  ASSERT_FALSE(polls.empty()) << "the answer is delayed to the 1 ms task";
  for (const Exchange& p : polls) {
    EXPECT_EQ(std::find(b.activations.begin(), b.activations.end(), b.acted(p)),
              b.activations.end());
  }
  // Delayed by at most one 1 ms tick (48 000 clocks) and one poll cycle.
  EXPECT_LT(b.acted(b.last) - b.acted(b.first),
            48'000u + (b.last.request_end - polls.back().request_end));
  const std::uint64_t end = b.last.request_end + 11 * kT + 17 * 11 * kT;
  EXPECT_EQ(b.last.answer_end, end);
  b.master.idle(2000);
  EXPECT_NE(std::find(b.activations.begin(), b.activations.end(), end), b.activations.end());
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_responses_sent, 1u);
  // A Read with Length 1 gets the first byte only.
  EXPECT_EQ(b.request(pdu::read_request(0, 1, 1).build()).du,
            (pdu::Bytes{0x5E, 0x00, 0x01, 0x01, 0x01}));
}

// Write slot 0 index 1, 2 bytes: OSPMode 01h, replacement value 06h. The positive response
// echoes function, slot, index, length (5Fh 00h 01h 02h). The cable pulled: the DP watchdog
// expires and DO4 drives the new replacement value 6.
TEST(Do4Dpv1, WriteChangesTheReplacementValueOfTheNextOsp) {
  Dpv1Bench b;
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  EXPECT_EQ(b.request(pdu::write_request(0, 1, {0x01, 0x06}).build()).du,
            (pdu::Bytes{0x5F, 0x00, 0x01, 0x02}));
  EXPECT_EQ(b.request(pdu::read_request(0, 1, 2).build()).du,
            (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x01, 0x06}));
  b.master.data_exchange({0x05, 0x01});
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->terminals, 0x5);
  b.master.idle(6'000'000);  // 125 ms > TWD
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 0);
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->terminals, 0x6);
}

// The negative responses (4 bytes: function | 80h, Error_Decode 80h = DPV1, Error_Code_1 =
// class (bits 7..4) | code (bits 3..0), Error_Code_2 00h), IEC 61158-6 class 11 "access" and 10
// "application" (docs/dpv1.md, "Negative responses"):
//   a record that does not exist: index 7 -> B0h invalid index; slot 3 -> B2h invalid slot;
//   a wrong length: Write with 1 byte -> B1h write length error;
//   a value outside the record's range: OSPMode 2 -> B7h invalid range;
//   a write in the wrong state (the module in OSP mode) -> B5h state conflict;
//   a service DO4 does not offer on SAP 51 (Data_Transport) -> A9h feature not supported.
TEST(Do4Dpv1, NegativeResponses) {
  Dpv1Bench b;
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  EXPECT_EQ(b.request(pdu::read_request(0, 7, 2).build()).du, (pdu::Bytes{0xDE, 0x80, 0xB0, 0x00}));
  EXPECT_EQ(b.request(pdu::read_request(3, 1, 2).build()).du, (pdu::Bytes{0xDE, 0x80, 0xB2, 0x00}));
  EXPECT_EQ(b.request(pdu::write_request(0, 7, {0x01, 0x06}).build()).du,
            (pdu::Bytes{0xDF, 0x80, 0xB0, 0x00}));
  EXPECT_EQ(b.request(pdu::write_request(0, 1, {0x01}).build()).du,
            (pdu::Bytes{0xDF, 0x80, 0xB1, 0x00}));
  EXPECT_EQ(b.request(pdu::write_request(0, 1, {0x02, 0x06}).build()).du,
            (pdu::Bytes{0xDF, 0x80, 0xB7, 0x00}));
  EXPECT_EQ(b.request({0x51, 0x00, 0x01, 0x00}).du, (pdu::Bytes{0xD1, 0x80, 0xA9, 0x00}));
  b.master.data_exchange({0x05, 0x00});  // OSPValid 0: the master requests OSP
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 0);
  EXPECT_EQ(b.request(pdu::write_request(0, 1, {0x01, 0x06}).build()).du,
            (pdu::Bytes{0xDF, 0x80, 0xB5, 0x00}));
  // The refused writes changed nothing.
  EXPECT_EQ(b.request(pdu::read_request(0, 1, 2).build()).du,
            (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x01, 0x09}));
  // The same bytes as the PDU views build them.
  EXPECT_EQ((pdu::ErrorResponse{pdu::Function::Write, pdu::Error_Decode_DPV1,
                                pdu::error::State_Conflict, 0})
                .build(),
            (pdu::Bytes{0xDF, 0x80, 0xB5, 0x00}));
}

// MSAC_C1 is the class-1 master's, the one that locked the slave (manual-quotes.md, "DPV1"): in
// Data_Exchange SAPs 51 and 50 name master 2 as Request_SA, which firmware/dps reads where the
// chip writes Master_Add, byte 3 of the diag buffer it sent. A Read (SAP 51) or an Alarm_Ack
// (SAP 50) from station 7 is answered RS ("At differences ... 'no service activated'", VPC3+C
// p.55) and stores nothing: no FDL_Ind, the single C1 buffer stays free, so master 2's Read after
// it is taken and answered with the record (with 7Fh there the stray took the buffer, which no
// time-out frees, and master 2 got RR from then on).
TEST(Do4Dpv1, StrayMsac1RequestsFromAnotherStationGetRsAndStoreNothing) {
  Dpv1Bench b(0x20);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  const auto stray = [&b](std::uint8_t dsap, const pdu::Bytes& du) {
    const Exchange ex = b.master.transact(fdl::make_frame(
        b.master.target(), 7, fdl::make_request_fc(fdl::Function::SRD_high, false, false), du, dsap,
        kC1));
    EXPECT_TRUE(ex.answer);
    return ex.answer ? ex.answer->fc & fdl::kFcCodeMask : -1;
  };
  const std::uint64_t requests_before = firmware_bench::stats_of(b.host)->dpv1_requests;
  EXPECT_EQ(stray(kC1, pdu::read_request(0, 1, 2).build()), 0x03);
  EXPECT_EQ(stray(kAlarm, pdu::AlarmAck{0x00, 0x01, 0x01}.build()), 0x03);
  b.master.idle(100'000);  // two 1 ms ticks: nothing to answer
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_requests, requests_before);
  EXPECT_EQ(b.request(pdu::read_request(0, 1, 2).build()).du,
            (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x01, 0x09}));
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_requests, requests_before + 1);
}

// MSAC_C1 lives in the master's Data_Exchange (docs/dpv1.md, docs/firmware.md "DO4 with DPV1":
// the Profichip driver stops it when the slave leaves): when the DP watchdog (TWD 100 ms) expires
// and the chip goes to Wait_Prm, DO4 closes SAPs 51 and 50 (Request_SA = its own address) and
// frees their buffers. A response DO4 had ready before is not sent: the master's poll gets RS (no
// service activated, VPC3+C p.55), so does a new Read, which stores nothing. A new start-up opens
// them again. (s35 audit aMix finding 4: the poll got 5E 00 01 02 01 09 after the expiry.)
TEST(Do4Dpv1, LeavingDataExchangeClosesMsac1) {
  Dpv1Bench b;
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  const auto rs = [](const Exchange& ex) {
    ASSERT_TRUE(ex.answer);
    EXPECT_EQ(ex.answer->fc & fdl::kFcCodeMask, 0x03);
    EXPECT_TRUE(ex.answer->du.empty());
  };
  // Taken (SC) and answered by the 1 ms task, but not polled for.
  const Exchange read = b.master.acyclic(kC1, kC1, pdu::read_request(0, 1, 2).build());
  ASSERT_TRUE(read.answer && *read.answer == fdl::sc());
  const std::uint64_t requests = firmware_bench::stats_of(b.host)->dpv1_requests;
  b.master.idle(5'000'000);  // past TWD = 4 800 000 clocks
  ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  rs(b.master.acyclic(kC1, kC1, {}));
  rs(b.master.acyclic(kC1, kC1, pdu::read_request(0, 1, 2).build()));
  b.master.idle(100'000);  // two 1 ms ticks: nothing to answer
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_requests, requests);
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.request(pdu::read_request(0, 1, 2).build()).du,
            (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x01, 0x09}));
}

// Without DPV1_Enable in Set_Prm (the GSD defaults) the SAP list is off: a request to SAP 51 is
// refused RS as for any SAP the chip does not serve, and DO4 is the DP-only module it was.
TEST(Do4Dpv1, WithoutDpv1EnableSap51IsRefused) {
  Bench b(Profile::vpc3plus, do4_firmware, gsd_slave(do4_firmware, 5), kBaud);
  ASSERT_TRUE(b.master.startup());
  const Exchange ex = b.master.acyclic(kC1, kC1, pdu::read_request(0, 1, 2).build());
  ASSERT_TRUE(ex.answer);
  EXPECT_EQ(ex.answer->fc & fdl::kFcCodeMask, 0x03);  // RS: no service activated
  EXPECT_EQ(firmware_bench::stats_of(b.host)->dpv1_requests, 0u);
}

// The DPV1 diagnostic alarm (IEC 61158-6 type 3 Slave_Diag, the alarm block inside the
// device-related block; docs/firmware.md "DO4 with DPV1"): with Enable_Diagnostic_Alarm
// (DPV1_Status_2 bit 5) entering OSP mode puts header 05h, Alarm_Type 01h (diagnosis), Slot 0,
// Specifier Seq_Nr 0 << 3 | 01h (appears), then S = 01h (OSP) after the six standard bytes, with
// Ext_Diag (Station_Status_1 bit 3). The master acknowledges it with Alarm_Ack on SAP 50
// (5Ch, slot, Alarm_Type, Specifier): the positive response echoes the four bytes and the block
// becomes the status (Status_Type 81h, Specifier 01h appears, S 01h) without Ext_Diag. A second
// Alarm_Ack finds none outstanding: DC 80 B5 00 (state conflict). The next OSP entry carries
// Seq_Nr 1: Specifier 09h.
TEST(Do4Dpv1, DiagnosticAlarmOnEnteringOspAcknowledgedByTheMaster) {
  Dpv1Bench b(0x20);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  auto diag_blocks = [&b]() {
    const Exchange d = b.master.slave_diag();
    EXPECT_TRUE(d.answer);
    const auto sd = pdu::SlaveDiag::parse(d.answer ? d.answer->du : pdu::Bytes{});
    EXPECT_TRUE(sd);
    return sd ? *sd : pdu::SlaveDiag{};
  };
  pdu::SlaveDiag d = diag_blocks();
  ASSERT_EQ(d.blocks.size(), 1u);
  EXPECT_EQ(d.blocks[0].bytes, (pdu::Bytes{0x05, 0x81, 0x00, 0x02, 0x00}));  // status: normal
  EXPECT_EQ(d.station_status_1 & pdu::SlaveDiag::St1_Ext_Diag, 0);

  b.master.data_exchange({0x05, 0x00});  // the master requests OSP
  ASSERT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 0);
  d = diag_blocks();
  ASSERT_EQ(d.blocks.size(), 1u);
  EXPECT_EQ(d.blocks[0].bytes, (pdu::Bytes{0x05, 0x01, 0x00, 0x01, 0x01}));
  EXPECT_EQ(d.station_status_1 & pdu::SlaveDiag::St1_Ext_Diag, pdu::SlaveDiag::St1_Ext_Diag);
  const auto alarm = pdu::Dpv1DiagBlock::parse(d.blocks[0]);
  ASSERT_TRUE(alarm);
  EXPECT_FALSE(alarm->status);
  EXPECT_EQ(alarm->type, 1);
  EXPECT_EQ(alarm->seq_nr(), 0);

  const pdu::Bytes ack = pdu::AlarmAck{0x00, 0x01, 0x01}.build();
  ASSERT_EQ(ack, (pdu::Bytes{0x5C, 0x00, 0x01, 0x01}));
  EXPECT_EQ(b.request(ack, nullptr, kAlarm).du, ack);
  d = diag_blocks();
  ASSERT_EQ(d.blocks.size(), 1u);
  EXPECT_EQ(d.blocks[0].bytes, (pdu::Bytes{0x05, 0x81, 0x00, 0x01, 0x01}));
  EXPECT_EQ(d.station_status_1 & pdu::SlaveDiag::St1_Ext_Diag, 0);
  EXPECT_EQ(b.request(ack, nullptr, kAlarm).du, (pdu::Bytes{0xDC, 0x80, 0xB5, 0x00}));

  b.master.data_exchange({0x05, 0x01});
  b.master.data_exchange({0x05, 0x00});
  d = diag_blocks();
  ASSERT_EQ(d.blocks.size(), 1u);
  EXPECT_EQ(d.blocks[0].bytes, (pdu::Bytes{0x05, 0x01, 0x00, 0x09, 0x01}));
  // An Alarm_Ack with another Specifier than the outstanding alarm's: B8h invalid parameter.
  EXPECT_EQ(b.request(ack, nullptr, kAlarm).du, (pdu::Bytes{0xDC, 0x80, 0xB8, 0x00}));
}

// The same alarm through a scenario with `firmware DO4` (audit a20, finding 3). Alarm_Ack is taken
// on SAP 50 or 51 ("Alarm_Ack on SAP 50 or 51", manual-quotes.md, DPV1): the answer's DSAP is
// the master's SSAP 51 (33h), its SSAP the slave's SAP. A slot DO4 does not have is "Error_Code_1
// B2h = invalid slot" (manual-quotes.md), checked before the alarm's state, as a record's slot
// is: with no alarm outstanding too (else B5h, none outstanding; review B, finding 3). Each answer
// telegram is SD2 68h, LE = LEr = 9 (DA, SA, FC, DSAP, SSAP and 4 bytes), DA 82h (master 2 | SAP
// extension), SA 85h, FC 08h, then the FCS (the sum of DA..DU mod 256), 16h:
//   33 33 DC 80 B2 00: 82+85+08+33+33+DC+80+B2+00 = 383h -> 83h
//   33 33 5C 00 01 01: ... +5C+00+01+01 = 1D3h -> D3h
//   33 32 DC 80 B2 00: one less: 82h;  33 32 5C 00 01 09: 1D3h - 1 + 8 = 1DAh -> DAh
// The second OSP entry's alarm carries Seq_Nr 1: Specifier 09h (docs/firmware.md).
TEST(Do4Dpv1, AlarmAckOnSap50Or51AndAWrongSlotThroughAScenario) {
  const std::string text =
      "profile vpc3plus\nbaud 1500000\nfirmware DO4\n"
      "slave address=5 wd=2,5 user_prm=C0,20,00,01,09,00\nstartup\n"
      "exchange outputs=05,01\nexchange outputs=05,00\n"
      "diag\nexpect diag_byte 0 0x08\nexpect diag_byte 9 0x01\n"
      "alarm_ack slot=1 type=1 seq=0 spec=1 sap=51\n"
      "expect dpv1 error 80,B2,00\n"
      "expect answer 68,09,09,68,82,85,08,33,33,DC,80,B2,00,83,16\n"
      "alarm_ack slot=0 type=1 seq=0 spec=1 sap=51\n"
      "expect dpv1 5C,00,01,01\n"
      "expect answer 68,09,09,68,82,85,08,33,33,5C,00,01,01,D3,16\n"
      "diag\nexpect diag_byte 0 0x00\nexpect diag_byte 7 0x81\n"
      "alarm_ack slot=0 type=1 seq=0 spec=1 sap=51\n"
      "expect dpv1 error 80,B5,00\n"
      "alarm_ack slot=1 type=1 seq=0 spec=1 sap=51\n"
      "expect dpv1 error 80,B2,00\n"
      "exchange outputs=05,01\nexchange outputs=05,00\n"
      "alarm_ack slot=1 type=1 seq=1 spec=1\n"
      "expect dpv1 error 80,B2,00\n"
      "expect answer 68,09,09,68,82,85,08,33,32,DC,80,B2,00,82,16\n"
      "alarm_ack slot=0 type=1 seq=1 spec=1\n"
      "expect dpv1 5C,00,01,09\n"
      "expect answer 68,09,09,68,82,85,08,33,32,5C,00,01,09,DA,16\n";
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  const ScenarioOutcome o = run_scenario(s, {}, {});
  EXPECT_EQ(o.failures, std::vector<std::string>{});
  EXPECT_EQ(o.passed, 14u);
}

// A scenario with DO4 on `profile` at 1.5 Mbaud, slave 5, TWD 100 ms, these User_Prm_Data, then
// `body`; it runs with every expect passed.
void run_do4_scenario(const std::string& profile, const std::string& user_prm,
                      const std::string& body, std::size_t expects) {
  const std::string text = "profile " + profile + "\nbaud 1500000\nfirmware DO4\n" +
                           "slave address=5 wd=2,5 user_prm=" + user_prm + "\n" + body;
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  const ScenarioOutcome o = run_scenario(s, {}, {});
  EXPECT_EQ(o.failures, std::vector<std::string>{});
  EXPECT_EQ(o.passed, expects);
}

// Keep-alive for `ms` ms: a Data_Exchange with the last outputs every 40 ms, within the 100 ms
// watchdog.
std::string keep_alive(int ms) {
  std::string t;
  for (int k = 0; k < ms; k += 40) t += "exchange\nsilence 40ms\n";
  return t;
}

// docs/firmware.md "DO4 with DPV1": "A new Set_Prm drops an outstanding alarm", and the diag says
// so at once. The alarm of entering OSP (Seq_Nr 0: 05 01 00 01 01, Ext_Diag 08h in byte 0), then a
// master restart (its Set_Prm): the Slave_Diag shows the status block 05 81 00 (Specifier 01h OSP
// appears) 01 (S) with Ext_Diag clear, and an Alarm_Ack for the dropped alarm finds none
// outstanding: DC 80 B5 00. Before the fix the alarm block stayed and its Alarm_Ack got B5.
TEST(Do4Dpv1, ANewSetPrmDropsTheAlarmFromTheDiag) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\nexchange outputs=05,00\n"
                   "diag\nexpect diag_byte 0 0x08\nexpect diag_byte 7 0x01\n"
                   "restart\nexchange outputs=05,00\n"
                   "diag\nexpect diag_byte 0 0x00\nexpect diag_byte 6 0x05\n"
                   "expect diag_byte 7 0x81\nexpect diag_byte 9 0x01\nexpect diag_byte 10 0x01\n"
                   "alarm_ack slot=0 type=1 seq=0 spec=1\nexpect dpv1 error 80,B5,00\n",
                   8);
}

// docs/firmware.md: "Without DPV1 the block stays 02h, S". DPV1 in OSP mode (status block 05 81 00
// 01 01), then the master parameterises DO4 without DPV1_Enable (its module bytes right after the
// Spec_User_Prm_Byte 00) and checks its Cfg: the next Slave_Diag has the DP block 02 01 (OSP).
// Before the fix the DPV1 status block stayed.
TEST(Do4Dpv1, ADpSetPrmTurnsTheBlockBackToDp) {
  run_do4_scenario("vpc3plus", "C0,00,00,01,09,00",
                   "startup\nexchange outputs=05,01\nexchange outputs=05,00\n"
                   "diag\nexpect diag_byte 6 0x05\nexpect diag_byte 7 0x81\n"
                   "set_prm user_prm=00,01,09,00\nexpect answer sc\nchk_cfg\n"
                   "diag\nexpect diag_byte 6 0x02\nexpect diag_byte 7 0x01\n",
                   5);
}

// docs/dpv1.md "Negative responses": the request's function number | 80h. A Read (5E 00 01 02) on
// the resource manager's SAP 49 is answered, at the poll after the 1 ms task, DE 80 A9 00 (feature
// not supported) from SAP 49 to the master's SAP 48: 68 09 09 68, DA 82h, SA 85h, FC 08h, DSAP 30h,
// SSAP 31h, the 4 bytes, FCS = (82 + 85 + 08 + 30 + 31 + DE + 80 + A9) mod 100h = 77h, 16h. Before
// the fix it was the Initiate's D7 80 B8 00.
TEST(Do4Dpv1, AnotherFunctionOnSap49IsNotSupported) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\n"
                   "send from=2 fc=0x4D dsap=49 ssap=48 du=5E,00,01,02\nexpect answer sc\n"
                   "silence 3ms\nsend from=2 fc=0x4D dsap=49 ssap=48\n"
                   "expect answer 68,09,09,68,82,85,08,30,31,DE,80,A9,00,77,16\n",
                   2);
}

// An Initiate (Send_Timeout 0Ah: 100 ms) whose master never polls SAP 49: its resource manager's
// response is withdrawn with the connection it opened, whose time-out closes it at the
// (10 x 10 + 1)-th tick after the one that answered (docs/firmware.md "MSAC_C2"). At about 85 ms
// another master's Initiate still gets RR (the response waits: its master may still poll); after
// 125 ms an Initiate is positive. Before the fix SAP 49 stayed occupied for good: RR, `refused`.
TEST(Do4Dpv1, AnUnpolledInitiateIsWithdrawnAfterSendTimeout) {
  const std::string initiate = "du=57,00,00,00,00,0A,01,00,00,00,00,00,00,02,00,02,00,00,00,00\n";
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\n"
                   "send from=2 fc=0x4D dsap=49 ssap=48 " +
                       initiate + "expect answer sc\n" + keep_alive(80) +
                       "send from=7 fc=0x4D dsap=49 ssap=48 " + initiate + "expect answer rr\n" +
                       keep_alive(40) + "c2_initiate send_timeout=100\nexpect dpv1 positive\n",
                   3);
}

// A negative answer on SAP 49 that opened nothing (here to a Read) waits for its poll at most the
// GSD's C2_Response_Timeout, 100 x 10 ms: withdrawn at the 1001st tick after the one that answered
// it. At about 960 ms an Initiate still gets RR; after 1.04 s one is positive. Before the fix:
// RR for good.
TEST(Do4Dpv1, AnUnpolledNegativeAnswerOnSap49IsWithdrawn) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\n"
                   "send from=2 fc=0x4D dsap=49 ssap=48 du=5E,00,01,02\nexpect answer sc\n" +
                       keep_alive(960) +
                       "send from=7 fc=0x4D dsap=49 ssap=48 "
                       "du=57,00,00,00,00,0A,01,00,00,00,00,00,00,02,00,02,00,00,00,00\n"
                       "expect answer rr\n" +
                       keep_alive(80) + "c2_initiate send_timeout=100\nexpect dpv1 positive\n",
                   3);
}

// DO4 checks an Initiate as the Profichip driver's MSAC_C2_RealizeIndRecv (audit s32-dpv1m,
// finding 1; docs/firmware.md "MSAC_C2"): a Type 0 S_Addr of 1 byte gets the driver's Abort on
// SAP 40, 58 00 12 00 (Instance MSAC_C2, Reason_Code FE), the master's outcome `aborted`; Type 1
// addresses of no bytes (16 bytes, under 20) 58 00 17 00 (IA); D_Type 1 (DO4 is not the
// connection's end) Initiate | 80h, 80 A9 00. Each closes the connection once sent, so the
// correct Initiate after them opens it: DO4's own Features 01 00, S and D swapped.
TEST(Do4Dpv1, AnInitiateTheProfichipDriverRefusesGetsItsAbort) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\n"
                   "c2_initiate s_addr=00\nexpect dpv1 aborted\nexpect dpv1 58,00,12,00\n"
                   "c2_initiate s_type=1 s_addr=- d_type=1 d_addr=-\nexpect dpv1 58,00,17,00\n"
                   "c2_initiate d_type=1\nexpect dpv1 error 80,A9,00\n"
                   "c2_initiate d_addr=01,00\nexpect dpv1 58,00,17,00\n"
                   "c2_initiate s_addr=00,11 d_addr=00,22\n"
                   "expect dpv1 57,10,01,00,00,00,00,00,00,02,00,02,00,22,00,11\n",
                   6);
}

// s32-rev2 (review finding 4): an Initiate too short to hold its Send_Timeout (57 00 00 00 00)
// gets the driver's Abort IA like any shorter than 20 bytes: the resource manager answers 56h,
// SAP 40 (28h), the driver's own Send_Timeout 100 (00 64; FCS 52h), and the poll on SAP 40 gets
// 58 00 17 00 (FCS D6h); the connection closes once it is sent, so an Initiate after it is taken.
// Before: 80 B8 00 (Invalid_Parameter) on SAP 49 and nothing opened.
TEST(Do4Dpv1, AnInitiateWithoutSendTimeoutGetsTheAbort) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexchange outputs=05,01\n"
                   "send from=2 fc=0x4D dsap=49 ssap=48 du=57,00,00,00,00\nexpect answer sc\n"
                   "silence 3ms\nsend from=2 fc=0x5D dsap=49 ssap=48\n"
                   "expect answer 68,09,09,68,82,85,08,30,31,56,28,00,64,52,16\n"
                   "send from=2 fc=0x7D dsap=40 ssap=48\n"
                   "expect answer 68,09,09,68,82,85,08,30,28,58,00,17,00,D6,16\n"
                   "silence 3ms\nc2_initiate\nexpect dpv1 positive\n",
                   4);
}

// docs/dpv1.md: MSAC_C1 lives in the master's Data_Exchange. Right after the standard start-up
// (the slave in Data_Exchange, no cyclic telegram yet) the class-1 master reads the OSP record:
// 5E 00 01 02, OSPMode 01h, value 09h (the Set_Prm's module bytes). The FDL_Ind narrowed the SAPs
// to master 2 (Master_Add of the Slave_Diag it fetched), so station 7's Read gets RS. Before the
// fix the SAPs opened at the first DX_Out only: the Read got RS (the audit's scn/d10.scn).
TEST(Do4Dpv1, Msac1ServedRightAfterTheStartUp) {
  run_do4_scenario("vpc3plus", "C0,20,00,01,09,00",
                   "startup\nexpect dp_state Data_Exchange\n"
                   "dpv1_read slot=0 index=1 length=2\nexpect dpv1 5E,00,01,02,01,09\n"
                   "send from=7 fc=0x4D dsap=51 ssap=51 du=5E,00,01,02\nexpect answer rs\n",
                   3);
}

// The DPV1 GSD is for the VPC3+ only (docs/firmware.md "GSD files"): on the SPC3 DO4's Prm and Aux
// buffers hold its 11-byte DP Set_Prm, so the chip answers the 13-byte DPV1 Set_Prm RR ("Buffer too
// small", chip-facts.md 5.4) and the slave stays in Wait_Prm, Station_Not_Ready (02h) without
// Prm_Fault (40h); on the DPC31 the chip takes it (SC) and refuses DPV1_Enable: Prm_Fault, 42h.
TEST(Do4Dpv1, Spc3AnswersTheDpv1SetPrmRrDpc31RefusesIt) {
  const std::string body = "startup tries=470\nset_prm\nexpect answer ";
  const std::string after = "diag\nexpect dp_state Wait_Prm\nexpect diag_byte 0 ";
  run_do4_scenario("spc3", "C0,20,00,01,09,00", body + "rr\n" + after + "0x02\n", 3);
  run_do4_scenario("dpc31", "C0,20,00,01,09,00", body + "sc\n" + after + "0x42\n", 3);
}

// Without Enable_Diagnostic_Alarm the OSP mode is only a status block: no Ext_Diag, and an
// Alarm_Ack finds no alarm (state conflict).
TEST(Do4Dpv1, NoAlarmWithoutEnableDiagnosticAlarm) {
  Dpv1Bench b;
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x05, 0x01});
  b.master.data_exchange({0x05, 0x00});
  const Exchange d = b.master.slave_diag();
  ASSERT_TRUE(d.answer);
  ASSERT_GE(d.answer->du.size(), 11u);
  EXPECT_EQ(d.answer->du[0] & pdu::SlaveDiag::St1_Ext_Diag, 0);
  EXPECT_EQ(pdu::Bytes(d.answer->du.begin() + 6, d.answer->du.end()),
            (pdu::Bytes{0x05, 0x81, 0x00, 0x01, 0x01}));
  EXPECT_EQ(b.request(pdu::AlarmAck{0x00, 0x01, 0x01}.build(), nullptr, kAlarm).du,
            (pdu::Bytes{0xDC, 0x80, 0xB5, 0x00}));
}

// The DPV1 GSD file (firmware/do4/DO4V0D04.gsd) describes what the firmware does: the GSD
// keywords of DPV1 (DPV1_Slave, C1_Read_Write_supp, C1_Max_Data_Len = the buffer's 20 bytes less
// the 4-byte record header, the alarm keywords), the same ident, Cfg and module parameter
// defaults as DO4_0D04.gsd after the three DPV1_Status bytes; a master configured from it reaches
// Data_Exchange on the VPC3+ at every rate it claims and reads the record (OSPMode, value at
// their GSD defaults 0, 0); each parameter beyond its range is refused.
TEST(Do4Dpv1, GsdFileDescribesTheDpv1Slave) {
  const firmware_bench::Gsd g =
      firmware_bench::load_gsd(std::string(SOURCE_DIR) + "/firmware/do4/DO4V0D04.gsd");
  const firmware_bench::Gsd dp =
      firmware_bench::load_gsd(std::string(SOURCE_DIR) + "/firmware/" + do4_firmware.gsd);
  EXPECT_EQ(g.keys.at("DPV1_Slave"), "1");
  EXPECT_EQ(g.keys.at("C1_Read_Write_supp"), "1");
  EXPECT_EQ(std::stoul(g.keys.at("C1_Max_Data_Len")), DPS_DPV1_MAX_PDU - 4u);
  // MSAC_C2 (firmware/dps): one connection, the same records and buffer length.
  EXPECT_EQ(g.keys.at("C2_Read_Write_supp"), "1");
  EXPECT_EQ(std::stoul(g.keys.at("C2_Max_Data_Len")), DPS_DPV1_MAX_PDU - 4u);
  EXPECT_EQ(g.keys.at("C2_Response_Timeout"), g.keys.at("C1_Response_Timeout"));
  EXPECT_EQ(g.keys.at("C2_Max_Count_Channels"), "1");
  EXPECT_EQ(g.keys.at("Diagnostic_Alarm_supp"), "1");
  EXPECT_EQ(g.keys.at("Extra_Alarm_SAP_supp"), "1");  // Alarm_Ack on SAP 50
  EXPECT_EQ(g.keys.at("Process_Alarm_supp"), "0");
  EXPECT_EQ(g.keys.at("Ident_Number"), dp.keys.at("Ident_Number"));
  EXPECT_EQ(g.module_cfg, dp.module_cfg);
  ASSERT_EQ(g.prm_const.size(), dp.prm_const.size() + 2);
  EXPECT_EQ(g.prm_const[0], 0xC0);  // DPV1_Enable | Fail_Safe
  EXPECT_EQ(g.prm_const[1], 0x20);  // Enable_Diagnostic_Alarm
  EXPECT_EQ(g.prm_const[2], 0x00);
  EXPECT_EQ(pdu::Bytes(g.prm_const.begin() + 3, g.prm_const.end()),
            pdu::Bytes(dp.prm_const.begin() + 1, dp.prm_const.end()));
  EXPECT_EQ(std::stoul(g.keys.at("Max_User_Prm_Data_Len")), g.prm_const.size());
  for (const auto& [n, p] : g.params) EXPECT_EQ(g.prm_const.at(p.offset), p.def) << n;
  for (const auto& [key, baud] : firmware_bench::kGsdRates) {
    if (g.keys.at(key) != "1") continue;
    Bench b(Profile::vpc3plus, do4_firmware,
            firmware_bench::gsd_configured_slave(do4_firmware, g, 5), baud);
    ASSERT_TRUE(b.master.startup()) << key;
    b.master.data_exchange({0x05, 0x01});
    EXPECT_EQ(b.master.acyclic(kC1, kC1, pdu::read_request(0, 1, 2).build()).answer, fdl::sc())
        << key;
  }
  for (const auto& [n, param] : g.params) {
    for (int v : {param.min, param.max, param.max + 1}) {
      if (v > 255) continue;
      SlaveConfig s = firmware_bench::gsd_configured_slave(do4_firmware, g, 5);
      s.user_prm.at(param.offset) = static_cast<std::uint8_t>(v);
      Bench b(Profile::vpc3plus, do4_firmware, s, 12'000'000);
      EXPECT_EQ(b.master.startup(40), v <= param.max) << "param " << n << " = " << v;
    }
  }
}

// The generated C layouts (regs/dpc31_regs.json) and the emulator's dpv1.hpp say the same.
static_assert(VPC3_SAP_Entry_SIZE == dpv1::entry::kBytes);
static_assert(VPC3_SAP_Entry_Sap == dpv1::entry::Sap);
static_assert(VPC3_SAP_Entry_Request_SA == dpv1::entry::Request_SA);
static_assert(VPC3_SAP_Entry_Request_SSAP == dpv1::entry::Request_SSAP);
static_assert(VPC3_SAP_Entry_Service_Supported == dpv1::entry::Service_Supported);
static_assert(VPC3_SAP_Entry_Ind_Buf_Ptr0 == dpv1::entry::Ind_Buf_Ptr0);
static_assert(VPC3_SAP_Entry_Ind_Buf_Ptr1 == dpv1::entry::Ind_Buf_Ptr1);
static_assert(VPC3_SAP_Entry_Resp_Buf_Ptr == dpv1::entry::Resp_Buf_Ptr);
static_assert(VPC3_SAP_Entry_Sap_Response_Sent_Msk == dpv1::entry::Response_Sent);
static_assert(VPC3_SAP_Entry_Sap_SAP_Number_Msk == dpv1::entry::SAP_Number);
static_assert(VPC3_SAP_Entry_Sap_End_Of_List == dpv1::entry::kEndOfList);
static_assert(VPC3_SAP_Entry_Request_SA_All == dpv1::entry::kAll);
static_assert(VPC3_SAP_Entry_Service_Supported_SRD_LH == dpv1::service::SRD_LH);
static_assert(VPC3_DPV1_Buf_SIZE == dpv1::header::kBytes);
static_assert(VPC3_DPV1_Buf_Control == dpv1::header::Control);
static_assert(VPC3_DPV1_Buf_Max_Length == dpv1::header::Max_Length);
static_assert(VPC3_DPV1_Buf_Length == dpv1::header::Length);
static_assert(VPC3_DPV1_Buf_Function_Code == dpv1::header::Function_Code);
static_assert(VPC3_DPV1_Buf_Control_USER_Msk == dpv1::header::USER);
static_assert(VPC3_DPV1_Buf_Control_IND_Msk == dpv1::header::IND);
static_assert(VPC3_DPV1_Buf_Control_RESP_Msk == dpv1::header::RESP);
static_assert(VPC3_DPV1_Buf_Control_INUSE_Msk == dpv1::header::INUSE);
static_assert(VPC3_Prm_Status_1 == dpv1::kStatus1);
static_assert(VPC3_Prm_Status_2 == dpv1::kStatus2);
static_assert(VPC3_Prm_Status_3 == dpv1::kStatus3);
static_assert(VPC3_Prm_SIZE == dpv1::kUserPrm);
static_assert(VPC3_Prm_Status_1_DPV1_Enable_Msk == dpv1::status1::DPV1_Enable);
static_assert(VPC3_Prm_Status_1_Fail_Safe_Msk == dpv1::status1::Fail_Safe);
static_assert(VPC3_Prm_Status_2_Enable_Diagnostic_Alarm_Msk ==
              dpv1::status2::Enable_Diagnostic_Alarm);
static_assert(VPC3_Prm_Status_3_Alarm_Mode_Msk == dpv1::status3::Alarm_Mode);

}  // namespace
