// The built-in master's DPV1 side (session/dpv1_master.hpp) against the built-in user side's
// (session/responder_dpv1.hpp) on a VPC3+ at 12 Mbaud, driven only through the wire (the master)
// and watched on the X/INT pin. Cycles from docs/timing.md (T = 4 clocks, 11 bits a character, an
// answer 11 T after the request's end, the next request 33 T after the answer's end) and the
// rules of docs/dpv1.md ("The master's side"); the derivation of each number is beside it.
#include "dpv1_master.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "dpc31/dp.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "segment.hpp"

using namespace dpc31;

namespace {

constexpr std::uint64_t kWork = 1440;  // 30 us of the user side's work per request

ResponderConfig config(std::uint64_t work) {
  ResponderConfig rc;
  rc.slave.user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable, Fail_Safe
  rc.dpv1.records = {{0, 1, {0x11, 0x22, 0x33, 0x44}}};
  rc.dpv1.work_cycles = work;
  return rc;
}

struct Rig {
  Chip chip{ChipOptions{Profile::vpc3plus, BusMode::intel, 0}};
  Responder user;
  DpMaster master;
  Dpv1Master dpv1;
  std::vector<std::uint64_t> irq_on;  // X/INT rising edges

  explicit Rig(std::uint64_t work = kWork, Dpv1Rules rules = {})
      : user(config(work)),
        master(chip, MasterConfig{2, 12'000'000, 100, 33}, config(work).slave),
        dpv1(chip, master, rules) {
    DirectBus bus(chip);
    user.init(bus);
    master.set_firmware([this](BusPort& b) { user.isr(b); });
    chip.on_irq_change([this](std::uint64_t c, bool active) {
      if (active) irq_on.push_back(c);
    });
  }
  void start() {
    ASSERT_TRUE(master.startup());
    master.idle(200);  // the firmware's last ISR done, the bus idle for the next request
    irq_on.clear();
  }
};

// A Read answered on the third poll (dpv1_c1_vpc3plus.scn derives it): request t0..t0+660, SC,
// polls acted on at t0+1362 and t0+2066 (SC: the user side's response is in at t0+2186), the
// third poll's answer (19 chars) ends at t0+3652. X/INT rises twice: FDL_Ind at the request's
// acted-on cycle t0+658, Poll_End_Ind at the response's end t0+3652 — the polls raise nothing
// ("Polling telegrams do not produce interrupts", VPC3+C p.56).
TEST(Dpv1Master, ReadPollsWithoutInterrupts) {
  Rig r;
  r.start();
  const std::size_t before = r.master.history().size();
  const Dpv1Answer a = r.dpv1.read(0, 1, 4);
  const std::uint64_t t0 = a.start;
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  EXPECT_EQ(a.du, (pdu::Bytes{0x5E, 0x00, 0x01, 0x04, 0x11, 0x22, 0x33, 0x44}));
  EXPECT_EQ(a.polls, 2u);
  EXPECT_EQ(a.end, t0 + 3652);
  EXPECT_EQ(r.master.history().size() - before, 4u);  // request, 3 polls
  // Every poll an SRD without data from SAP 51 to SAP 51, each with a new FCB.
  for (std::size_t i = before + 1; i < r.master.history().size(); ++i) {
    const fdl::Frame& p = r.master.history()[i].request;
    EXPECT_TRUE(p.du.empty());
    EXPECT_EQ(p.dsap, sap::MSAC_C1);
    EXPECT_EQ(p.ssap, sap::MSAC_C1);
    EXPECT_NE(fdl::fcb(p.fc), fdl::fcb(r.master.history()[i - 1].request.fc));
  }
  r.master.idle(200);
  EXPECT_EQ(r.irq_on, (std::vector<std::uint64_t>{t0 + 658, t0 + 3652}));
}

// The response time-out (C1_Response_Timeout 1 = 10 ms = 480 000 clocks from the request's
// start): a user side that works 1 s. The request's SC ends at t0+748, poll n's SC at
// t0+748+704n; the master gives up at the first SC at or past 480 000: n = 681 (t0+480 172).
TEST(Dpv1Master, ResponseTimeOut) {
  Dpv1Rules rules;
  rules.c1_response_timeout = 1;
  Rig r(48'000'000, rules);
  r.start();
  const Dpv1Answer a = r.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::timeout);
  EXPECT_EQ(a.polls, 681u);
  EXPECT_EQ(a.end, a.start + 748 + 704 * 681);
}

// A request nobody answers (the slave addressed as 9) is sent 1 + retries times, unchanged (the
// same FCB), then the service fails: no_answer, and no poll follows.
TEST(Dpv1Master, NoAnswerAfterRetries) {
  Dpv1Rules rules;
  rules.retries = 2;
  Rig r(kWork, rules);
  r.start();
  r.master.set_target(9);
  const std::size_t before = r.master.history().size();
  const Dpv1Answer a = r.dpv1.write(0, 1, {1, 2, 3, 4});
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
  ASSERT_EQ(r.master.history().size() - before, 3u);
  // The outcome's cycle: the slot time's end after the last try (docs/timing.md, "The master's
  // wait": TSL = 100 T = 400 clocks after its last stop bit).
  EXPECT_EQ(a.end, r.master.history().back().request_end + 400);
  for (std::size_t i = before; i < r.master.history().size(); ++i) {
    EXPECT_EQ(r.master.history()[i].request, r.master.history()[before].request);
  }
}

// A master asking station 5 on a 1.5 Mbaud line (T = 32 clocks, a character 11 T) where only a
// scripted sender answers: `bytes` TSDR 11 T after the end of request number `nth` (from 1), and
// nothing to the others. The clock's chip only gives Dpv1Master its 48 MHz (a VPC3+: it refuses
// another).
struct ScriptedLine {
  static constexpr std::uint64_t T = 32;
  Chip clock{ChipOptions{Profile::vpc3plus, BusMode::intel, 0}};
  Segment seg{1'500'000};
  std::size_t rogue = seg.add_sender("rogue");
  std::size_t m = seg.add_sender("master 2");
  DpMaster master{seg, m, MasterConfig{}, {SlaveConfig{}}};
  Dpv1Master dpv1;
  std::vector<std::uint64_t> request_end;

  ScriptedLine(std::size_t nth, std::vector<std::uint8_t> bytes, Dpv1Rules rules,
               UartFault fault = {})
      : dpv1(clock, master, rules) {
    master.on_send = [this](std::uint64_t start, std::span<const std::uint8_t> request,
                            const UartFault&) {
      request_end.push_back(start + request.size() * 11 * T);
    };
    master.scheduler = [this, nth, bytes = std::move(bytes), fault](std::uint64_t cycle) {
      if (request_end.size() == nth && !sent_) {
        sent_ = true;
        seg.run_until(request_end.back());
        seg.send(rogue, bytes, request_end.back() + 11 * T, fault);
        return;
      }
      seg.run_until(cycle);
    };
  }

 private:
  bool sent_ = false;
};

// The no_answer cycle after an answer cut short (review B, finding 1; docs/timing.md, "The master's
// wait"): the wait ends a slot time (TSL = 100 T) after the answer's last character, not after
// the request's. A Read answered by the first 6 characters of an SD2 response (68 07 07 68 02
// 05): they end 11 T + 6 x 11 T = 77 T after the request, the master gives up at 177 T. A valid
// telegram addressed otherwise (SD1 from 7, 6 characters) frees the line at its end, 77 T.
// Before, both were request's end + 100 T.
TEST(Dpv1Master, NoAnswerAfterACutShortAnswerEndsASlotTimeAfterIt) {
  Dpv1Rules rules;
  rules.retries = 0;
  {
    ScriptedLine l(1, {0x68, 0x07, 0x07, 0x68, 0x02, 0x05}, rules);
    const Dpv1Answer a = l.dpv1.read(0, 1, 4);
    EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
    ASSERT_EQ(l.request_end.size(), 1u);
    EXPECT_EQ(a.end, l.request_end[0] + 177 * ScriptedLine::T);
  }
  {
    ScriptedLine l(1, fdl::encode(fdl::make_frame(2, 7, fdl::make_response_fc(fdl::Response::OK))),
                   rules);
    const Dpv1Answer a = l.dpv1.read(0, 1, 4);
    EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
    ASSERT_EQ(l.request_end.size(), 1u);
    EXPECT_EQ(a.end, l.request_end[0] + 77 * ScriptedLine::T);
  }
}

// A complete answer with a bad FCS (a collision can make one; docs/timing.md, "The master's
// wait"): the master's receiver knows it complete at its last character (SD1: 6 characters),
// so the wait ends at its end, and so does no_answer, as a telegram addressed otherwise frees
// the line there. SD1 DA 2 SA 5 FC 08h, FCS 00h (the right one is 02h + 05h + 08h = 0Fh), ED
// 16h: 11 T after the request's end, 6 x 11 T long, it ends 77 T after the request. Before, the
// outcome's cycle was a slot time later, 177 T, as after an answer cut short.
TEST(Dpv1Master, NoAnswerAfterACompleteAnswerWithABadFcsEndsAtItsEnd) {
  Dpv1Rules rules;
  rules.retries = 0;
  ScriptedLine l(1, {0x10, 0x02, 0x05, 0x08, 0x00, 0x16}, rules);
  const Dpv1Answer a = l.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
  ASSERT_EQ(l.request_end.size(), 1u);
  EXPECT_EQ(a.end, l.request_end[0] + 77 * ScriptedLine::T);
  const Exchange& ex = l.master.history().back();
  EXPECT_FALSE(ex.answer);
  EXPECT_FALSE(ex.stray);
  EXPECT_EQ(ex.answer_end, l.request_end[0] + 77 * ScriptedLine::T);
  EXPECT_EQ(ex.wait_end, ex.answer_end);
}

// An answer broken by a bad character (review A, finding 9; docs/timing.md, "The master's wait":
// "one broken by a bad character ends it at the last character the master took"): the SD1
// answer of the test above with the right FCS (0Fh), its third character (SA) sent with a wrong
// parity bit. The master's receiver takes every character on the line, the three after the bad
// one too (back to back, each within a slot time of the last), so the last it took is the sixth:
// the wait ends 11 T + 6 x 11 T = 77 T after the request, not a slot time after it (177 T).
TEST(Dpv1Master, NoAnswerAfterABadCharacterEndsAtTheLastCharacterTaken) {
  Dpv1Rules rules;
  rules.retries = 0;
  ScriptedLine l(1, {0x10, 0x02, 0x05, 0x08, 0x0F, 0x16}, rules,
                 UartFault{2, UartFault::Kind::parity});
  const Dpv1Answer a = l.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
  ASSERT_EQ(l.request_end.size(), 1u);
  const Exchange& ex = l.master.history().back();
  EXPECT_FALSE(ex.answer);
  EXPECT_EQ(ex.wait_end, l.request_end[0] + 77 * ScriptedLine::T);
  EXPECT_EQ(a.end, ex.wait_end);
}

// `start` is the request's first start bit, the first try's (review B, finding 9; docs/dpv1.md,
// "The outcome's cycle"), and the C1 time-out counts from it. The first try of a Read (15
// characters) is lost, the retry gets SC (E5), its poll and the poll's retry nobody answers. The
// retry starts TSL + TSYN = 133 T after the first try's end; the first try began 15 x 11 T before
// that end. Before, `start` was the retry's.
TEST(Dpv1Master, StartIsTheFirstTrysStartBit) {
  Dpv1Rules rules;
  rules.retries = 1;
  ScriptedLine l(2, {0xE5}, rules);
  const std::size_t before = l.master.history().size();
  const Dpv1Answer a = l.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_answer);
  ASSERT_EQ(l.master.history().size() - before, 4u);  // the Read twice, the poll twice
  const Exchange& second = l.master.history()[before + 1];
  ASSERT_TRUE(second.answer);
  EXPECT_EQ(a.start, second.request_start - 133 * ScriptedLine::T - 15 * 11 * ScriptedLine::T);
  EXPECT_EQ(a.start, l.master.history()[before].request_start);
}

// The negative response is parsed as such: a Write of the wrong length.
TEST(Dpv1Master, NegativeResponse) {
  Rig r;
  r.start();
  const Dpv1Answer a = r.dpv1.write(0, 1, {1, 2});
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::negative);
  EXPECT_EQ(a.error, (pdu::ErrorResponse{pdu::Function::Write, pdu::Error_Decode_DPV1,
                                         pdu::error::Write_Length_Error, 0}));
  EXPECT_EQ(r.user.dpv1()->records().front().data, (pdu::Bytes{0x11, 0x22, 0x33, 0x44}));
}

// A data response (DL) that carries no data is malformed, not refused: refused is the slave's RS
// or RR (docs/dpv1.md, "Outcomes"; audit s30 a-dpv1, finding 7: it was called refused). The
// firmware's SAP list by hand (VPC3+C p.54-56): SAP 51 at 600h, its indication buffer at 640h
// (segment C8h), its response buffer at 680h (D0h) armed before the request with RESP + USER,
// Length 0, FC 08h. The Read (15 characters, t0..t0+660) is answered at once with that response:
// 68 05 05 68 82 85 08 33 33 75 16 (FCS 82+85+08+33+33 = 175h), 11 T after the request's end,
// 11 characters of 44 clocks: it ends at t0 + 660 + 44 + 484 = t0 + 1188, the outcome's cycle.
TEST(Dpv1Master, ADataResponseWithoutDataIsMalformed) {
  ResponderConfig rc;
  rc.slave.user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable: the SAP list on; no records
  Chip chip{ChipOptions{Profile::vpc3plus, BusMode::intel, 0}};
  Responder user(rc);
  DpMaster master(chip, MasterConfig{2, 12'000'000, 100, 33}, rc.slave);
  Dpv1Master dpv1(chip, master);
  DirectBus bus(chip);
  user.init(bus);
  master.set_firmware([&user](BusPort& b) { user.isr(b); });
  ASSERT_TRUE(master.startup());
  master.idle(200);
  const std::array<std::uint8_t, 8> list = {51, 0x7F, 0x7F, 0x00, 0xC8, 0x00, 0xD0, 0xFF};
  const std::array<std::uint8_t, 4> ind = {0x00, 20, 0, 0};
  const std::array<std::uint8_t, 4> resp = {0xA0, 20, 0, 0x08};  // RESP + USER, Length 0, DL
  chip.write_block(0x600, list);
  chip.write_block(0x640, ind);
  chip.write_block(0x680, resp);
  chip.write(static_cast<std::uint32_t>(chip.addr_of(RegId::R_FDL_SAP_List_Ptr)), 0xC0);
  const Dpv1Answer a = dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::malformed);
  ASSERT_TRUE(a.last);
  EXPECT_EQ(fdl::encode(*a.last),
            (pdu::Bytes{0x68, 0x05, 0x05, 0x68, 0x82, 0x85, 0x08, 0x33, 0x33, 0x75, 0x16}));
  EXPECT_TRUE(a.du.empty());
  EXPECT_EQ(a.polls, 0u);
  EXPECT_EQ(a.end, a.start + 1188);
  EXPECT_EQ(answer_summary(a), "malformed DL without data after 0 polls");  // the walk's words
}

// The SAP list and its buffers are buffers the chip uses (review s32 rev1, finding 3: pointers
// below 016h were served from the RAM behind the registers without a word): they log as the DP
// buffers do. SAP 51's Ind_Buf_Ptr[0] = 01h (008h): the hidden bytes there are 00h, Max_Length 0,
// so the Read is refused (RR); then the list itself at segment 02h (010h), where the hidden 00h
// bytes hold no SAP 51 (RS).
TEST(Dpv1Master, SapBuffersOverTheRegistersAreLogged) {
  Rig r;
  r.start();
  Chip& chip = r.chip;
  Dpv1Master& dpv1 = r.dpv1;
  std::vector<std::string> log;
  chip.set_log_sink([&log](const LogRecord& rec) {
    if (rec.text.find("over the registers") != std::string::npos) log.push_back(rec.text);
  });
  chip.write_block(0x600,
                   std::array<std::uint8_t, 8>{51, 0x7F, 0x7F, 0x00, 0x01, 0x00, 0xD0, 0xFF});
  const auto list_ptr = static_cast<std::uint32_t>(chip.addr_of(RegId::R_FDL_SAP_List_Ptr));
  chip.write(list_ptr, 0xC0);
  EXPECT_EQ(dpv1.read(0, 1, 4).outcome, Dpv1Answer::Outcome::refused);
  ASSERT_GE(log.size(), 1u);
  EXPECT_EQ(log[0],
            "SAP 51's Ind_Buf_Ptr[0] = 01h puts its buffer at 0x008, over the registers (below "
            "0x016): the chip keeps its bytes in RAM the CPU does not see there (modelled); "
            "further such uses are counted");
  log.clear();
  chip.write(list_ptr, 0x02);
  EXPECT_EQ(dpv1.read(0, 1, 4).outcome, Dpv1Answer::Outcome::refused);
  ASSERT_GE(log.size(), 1u);
  EXPECT_EQ(log[0], "R_FDL_SAP_List_Ptr = 02h puts its buffer at 0x010, over the registers");
}

// MSAC_C2: Initiate gets the connection's SAP from the resource manager; Read on it; Abort closes
// it on both sides (a new Initiate is taken); without a request for Send_Timeout the user side
// closes it (its SAP answers RS).
TEST(Dpv1Master, ClassTwoConnection) {
  Rig r;
  r.start();
  const pdu::Initiate req = pdu::initiate_request(1);  // Send_Timeout 10 ms
  Dpv1Answer a = r.dpv1.initiate(req);
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  ASSERT_EQ(r.dpv1.c2_sap(), std::optional<std::uint8_t>(40));
  a = r.dpv1.c2_read(0, 1, 2);
  EXPECT_EQ(a.du, (pdu::Bytes{0x5E, 0x00, 0x01, 0x02, 0x11, 0x22}));
  a = r.dpv1.c2_abort({0, 2, 3, 0});
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  EXPECT_FALSE(r.dpv1.c2_sap());
  a = r.dpv1.initiate(req);
  ASSERT_EQ(a.outcome, Dpv1Answer::Outcome::positive);
  r.master.idle(48'000 * 15);
  EXPECT_EQ(r.user.dpv1()->timeouts, 1u);
  a = r.dpv1.c2_idle();
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::refused);
}

// MSAC_C2 without an open connection (audit a20, finding 7): the master has no SAP to send it
// to, so nothing goes on the line and the outcome is no_connection (not refused: no slave
// answered RS or RR), at the cycle the service was asked for. Before: refused at cycle 0.
TEST(Dpv1Master, NoConnectionSendsNothing) {
  Rig r;
  r.start();
  const std::size_t sent = r.master.history().size();
  const std::uint64_t requests = r.master.counters().requests;
  const std::uint64_t now = r.chip.cycle();
  for (const Dpv1Answer& a :
       {r.dpv1.c2_read(0, 1, 4), r.dpv1.c2_write(0, 1, {1}), r.dpv1.c2_transport(0, 1, {1}),
        r.dpv1.c2_idle(), r.dpv1.c2_abort({0, 2, 0, 0})}) {
    EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_connection);
    EXPECT_EQ(a.start, now);
    EXPECT_EQ(a.end, now);
    EXPECT_EQ(a.polls, 0u);
    EXPECT_FALSE(a.last);
    EXPECT_EQ(answer_summary(a), "no connection, nothing sent");
  }
  EXPECT_EQ(r.chip.cycle(), now);
  EXPECT_EQ(r.master.history().size(), sent);
  EXPECT_EQ(r.master.counters().requests, requests);
  EXPECT_TRUE(r.irq_on.empty());
}

// A long response time-out keeps the master's history flat (audit s32-dpv1m, finding 2: every
// poll stayed, ~290 bytes each, 20 MB per chip second at 12 Mbaud): the request, the first
// kKeptPolls polls and the newest stay, the polls between are counted, not kept. A user side
// that works 1 s, C1_Response_Timeout 50 = 0.5 s = 24 000 000 clocks: the Read's SC ends at
// t0+748, poll n's at t0+748+704n (Dpv1Master.ResponseTimeOut); the first at or past the
// time-out is n = 34 090 (t0+24 000 108). Before: 34 091 history records.
TEST(Dpv1Master, ALongTimeOutKeepsTheHistoryFlat) {
  Dpv1Rules rules;
  rules.c1_response_timeout = 50;
  Rig r(48'000'000, rules);
  r.start();
  const std::size_t before = r.master.history().size();
  const Dpv1Answer a = r.dpv1.read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::timeout);
  EXPECT_EQ(a.polls, 34'090u);
  EXPECT_EQ(a.end, a.start + 748 + 704 * 34'090);
  EXPECT_EQ(r.master.history().size() - before, 1 + Dpv1Master::kKeptPolls + 1);
  EXPECT_EQ(r.master.history().back().answer_end, a.end);  // the newest poll is the last one
}

// The slave's refusal of an Initiate (audit s32-dpv1m, findings 1 and 3): the built-in user side
// checks the request as the Profichip driver's MSAC_C2_RealizeIndRecv does; a Type 0 S_Addr of
// 1 byte (Len 1, not 2) gets the driver's Abort on the connection's SAP: 58h, Subnet 0,
// Instance MSAC_C2 (1) | Reason_Code FE (2), 0. The master's outcome is `aborted` with that
// Abort, and it knows no connection.
TEST(Dpv1Master, AnInitiateTheSlaveAbortsIsAborted) {
  Rig r;
  r.start();
  pdu::Initiate req = pdu::initiate_request(100);
  req.s_addr = {0x00};
  const Dpv1Answer a = r.dpv1.initiate(req);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::aborted);
  EXPECT_EQ(a.du, (pdu::Bytes{0x58, 0x00, 0x12, 0x00}));
  EXPECT_EQ(a.abort, (pdu::Abort{0, 1, 2, 0}));
  EXPECT_FALSE(r.dpv1.c2_sap());
  EXPECT_EQ(answer_summary(a), "aborted 58 00 12 00 (instance 1, reason 2) after 2 polls");
}

// A no_connection right after a service (audit s32-dpv1m, finding 6): the master acted on the
// Abort's SC at its last stop bit's sample, 2 clocks (end - T + floor(T/2), T = 4) before the
// SC's end, the Abort's outcome cycle; the next service is asked after that outcome, so
// docs/dpv1.md "The outcome's cycle" stamps it there, not 2 clocks earlier.
TEST(Dpv1Master, NoConnectionRightAfterAServiceIsNotStampedBeforeIt) {
  Rig r;
  r.start();
  ASSERT_EQ(r.dpv1.initiate(pdu::initiate_request(100)).outcome, Dpv1Answer::Outcome::positive);
  const Dpv1Answer abort = r.dpv1.c2_abort({0, 2, 3, 0});
  ASSERT_EQ(abort.outcome, Dpv1Answer::Outcome::positive);
  ASSERT_EQ(r.chip.cycle(), abort.end - 2);  // where the master stopped
  const Dpv1Answer a = r.dpv1.c2_read(0, 1, 4);
  EXPECT_EQ(a.outcome, Dpv1Answer::Outcome::no_connection);
  EXPECT_EQ(a.start, abort.end);
  EXPECT_EQ(a.end, abort.end);
}

// `expect dpv1 sc` (docs/scenario-format.md, "DPV1"): the Abort gets SC and no response; a check
// of another outcome fails and says what came.
TEST(Dpv1Scenario, AbortIsCheckedAsSc) {
  const char* text =
      "profile vpc3plus\nslave user_prm=C0,00,00\nrecord slot=0 index=1 data=01\nstartup\n"
      "c2_initiate\nexpect dpv1 sc   # the Initiate response: fails\nc2_abort\nexpect dpv1 sc\n"
      "expect dpv1 refused   # fails\n";
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  std::vector<std::string> errors;
  const ScenarioOutcome o =
      run_scenario(s, {}, [&](const std::string& line) { errors.push_back(line); });
  EXPECT_EQ(o.passed, 1u);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_TRUE(errors[0].starts_with("t.scn:6: expected dpv1 sc, got 57 ")) << errors[0];
  EXPECT_EQ(errors[1], "t.scn:9: expected dpv1 refused, got SC after 0 polls");
}

// A failed `expect dpv1` reads as every expect's line, "expected WHAT WANT, got GOT", the word
// once (the audit a11 of 2026-12-06: "expected dpv1 sc sc", "expected dpv1 error negative ...",
// and "expected dpv1 sc -" before any exchange).
TEST(Dpv1Scenario, FailedChecksNameTheirValueOnce) {
  const char* text =
      "profile vpc3plus\nbaud 12000000\nslave user_prm=C0,00,00\nrecord slot=0 index=1 data=01\n"
      "startup\nexpect dpv1 sc\nexpect dpv1 polls 2\ndpv1_read slot=0 index=2 length=1\n"
      "expect dpv1 timeout\nexpect dpv1 error 80,B2,00\nexpect dpv1 5E,00,02,01\n"
      "expect dpv1 polls 1\nexpect dpv1 error 80,B0,00\n";
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  std::vector<std::string> errors;
  const ScenarioOutcome o =
      run_scenario(s, {}, [&](const std::string& line) { errors.push_back(line); });
  EXPECT_EQ(o.passed, 1u);
  EXPECT_EQ(errors, (std::vector<std::string>{
                        "t.scn:6: expected dpv1 sc, got no DPV1 exchange yet",
                        "t.scn:7: expected dpv1 polls 2, got no DPV1 exchange yet",
                        "t.scn:9: expected dpv1 timeout, got negative DE 80 B0 00 after 0 polls",
                        "t.scn:10: expected dpv1 error 80 B2 00, got 80 B0 00",
                        "t.scn:11: expected dpv1 response 5E 00 02 01, got negative DE 80 B0 00 "
                        "after 0 polls",
                        "t.scn:12: expected dpv1 polls 1, got 0",
                    }));
}

// Runs a scenario's text as `dpc31 run` does and returns its failed expects' lines (every expect
// held: none) and, in `walk`, its walk.
std::vector<std::string> failed_expects(const std::string& text,
                                        std::vector<std::string>* walk = nullptr) {
  Scenario s;
  ScenarioError err;
  EXPECT_TRUE(parse_scenario(text, "t.scn", s, err)) << err.text();
  std::vector<std::string> errors;
  const ScenarioOutcome o = run_scenario(
      s,
      [&](const std::string& line) {
        if (walk != nullptr) walk->push_back(line);
      },
      [&](const std::string& line) { errors.push_back(line); });
  EXPECT_GT(o.passed, 0u);
  return errors;
}

bool has_line(const std::vector<std::string>& walk, std::string_view part) {
  return std::any_of(walk.begin(), walk.end(),
                     [&](const std::string& l) { return l.find(part) != std::string::npos; });
}

constexpr const char* kHead =
    "profile vpc3plus\nbaud 12000000\nslave address=5 user_prm=C0,00,00\n"
    "record slot=0 index=1 data=11,22,33,44\n";

// A SAP list laid out by hand (VPC3+C p.55, 8-byte segments): SAP 49 (indication buffer 0710h,
// response buffer 0740h) with the resource manager's response 56 28 (SAP 40) and Send_Timeout
// `send_timeout` ready (USER + RESP), SAP 40 (0780h, 07C0h) with `sap40_response` in its response
// buffer (the Initiate response 57 F0 01 00 ... ready, or nothing: every poll there gets SC).
constexpr std::string_view kInitiateResponseReady =
    "A0,20,10,08,57,F0,01,00,00,00,00,00,00,02,00,02,00,00,00,00";
constexpr std::string_view kNoResponse = "00,20,00,00";
std::string hand_laid_connection(std::string_view send_timeout, std::string_view sap40_response) {
  return "profile vpc3plus\nbaud 12000000\nslave address=5 user_prm=C0,00,00\nstartup\n"
         "write 0x700 bytes=31,7F,7F,00,E2,00,E8,28,7F,7F,00,F0,00,F8,FF\n"
         "write 0x710 bytes=00,20,00,00\nwrite 0x740 bytes=A0,20,04,08,56,28," +
         std::string(send_timeout) +
         "\nwrite 0x780 bytes=00,20,00,00\nwrite 0x7C0 bytes=" + std::string(sap40_response) +
         "\nwrite R_FDL_SAP_List_Ptr 0xE0\n";
}

// The Initiate's response time-out (audit s28 aud1, finding 1; docs/dpv1.md, "Outcomes": the
// connection's Send_Timeout, from the request's first start bit, checked at each SC). The SAP
// list laid out by hand: SAP 49 with the resource manager's response 56 28 00 01 ready, SAP 40
// that never answers. At 12 Mbaud (T = 4 clocks,
// docs/timing.md) from t0: the Initiate (20 bytes, 31 characters = 341 T), TSDR 11 T, the
// response (15 characters = 165 T), 33 T idle: the first poll on SAP 40 at t0 + 550 T = 2200;
// its SC ends 121 + 11 + 11 T later, poll k's at t0 + 2772 + 704k. Send_Timeout 1 = 480 000
// clocks: the first SC at or past it is k = 678 (t0 + 480 084), after 679 polls. Before, the
// time-out ran again from the first poll on SAP 40 (s28).
TEST(Dpv1Scenario, TheInitiatesTimeOutRunsFromItsFirstStartBit) {
  EXPECT_EQ(failed_expects(hand_laid_connection("00,01", kNoResponse) +
                           "c2_initiate send_timeout=1\nexpect dpv1 timeout after 480084\n"
                           "expect dpv1 polls 679\n"),
            std::vector<std::string>{});
}

// Once the resource manager named a larger Send_Timeout (56 28 00 02: 20 ms) than the Initiate's
// (1: 10 ms), the Initiate's own wait on SAP 40 runs on it too (docs/dpv1.md: the connection's
// Send_Timeout is the larger one; audit s32-dpv1m, finding 4). As above, poll k's SC on SAP 40
// ends at t0 + 2772 + 704k; the first at or past 960 000 is k = 1360 (t0 + 960 212; k = 1359
// ends at t0 + 959 508), after 1361 polls. Before: t0 + 480 084, 679 polls.
TEST(Dpv1Scenario, TheInitiateWaitsOnTheResourceManagersLargerSendTimeout) {
  EXPECT_EQ(failed_expects(hand_laid_connection("00,02", kNoResponse) +
                           "c2_initiate send_timeout=1\nexpect dpv1 timeout after 960212\n"
                           "expect dpv1 polls 1361\n"),
            std::vector<std::string>{});
}

// The resource manager's one buffer (audit a11, finding 1): master 9's Initiate (Send_Timeout 1 =
// 10 ms) is taken and answered, but master 9 never polls for the answer. While its response
// waits there, the chip answers every Initiate RR ("no free buffer", VPC3+C p.56); the user side
// withdraws it at the first tick at least that Send_Timeout after it was handed over (master 9's
// connection, silent as long, is closed at the same tick), so our Initiate 25 ms later is taken:
// the Initiate response after 2 polls, as in dpv1_c2_vpc3plus.scn. Before, SAP 49 answered RR
// for ever.
TEST(Dpv1Scenario, AnUncollectedResourceManagerResponseIsWithdrawnAfterItsSendTimeout) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=1440\nstartup\n"
                           "send from=9 fc=0x6D dsap=49 ssap=48 "
                           "du=57,00,00,00,00,01,01,00,00,00,00,00,00,02,00,02,00,00,00,00\n"
                           "expect answer sc\nsilence 5ms\n"
                           "c2_initiate send_timeout=100\nexpect dpv1 refused\nexpect answer rr\n"
                           "silence 20ms\n"
                           "c2_initiate send_timeout=100\n"
                           "expect dpv1 57,F0,01,00,00,00,00,00,00,02,00,02,00,00,00,00\n"
                           "expect dpv1 polls 2\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// The Initiate request (audit s32-dpv1m, finding 1), as the Profichip VPC3+ driver reads it
// (its INITIATE_REQ_PDU: Send_Timeout, bFeaturesSupported1, bFeaturesSupported2, ...; DpCfg.h
// C2_FEATURES_SUPPORTED_1 01h "Read and Write supported", _2 00h) and as IEC 61158-6 has the
// Add_Addr_Param: S_Type 0, S_Len 2, D_Type 0, D_Len 2, then S_Addr and D_Addr (API, SCL each):
// 57 00 00 00 | 00 64 | 01 00 | 00 00 | 00 00 | 00 02 00 02 | 00 11 | 00 22, 20 bytes (the
// driver's MSAC_C2_MIN_CR_PDU_SIZE). The built-in user side answers as the driver's
// MSAC_C2_InitiateReqToRes: Max_Len_Data_Unit F0h, its own Features 01 00, no profile, S and D
// swapped (S_Addr = the request's D_Addr). Before: Features 00 01 and no addresses (16 bytes).
TEST(Dpv1Scenario, TheInitiateClaimsReadWriteInItsFirstFeaturesByteWithTypeZeroAddresses) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=1440\nstartup\nc2_initiate s_addr=00,11 d_addr=00,22\n"
                           "expect dpv1 57,F0,01,00,00,00,00,00,00,02,00,02,00,22,00,11\n";
  std::vector<std::string> walk;
  EXPECT_EQ(failed_expects(text, &walk), std::vector<std::string>{});
  EXPECT_TRUE(has_line(walk, "57 00 00 00 00 64 01 00 00 00 00 00 00 02 00 02 00 11 00 22"));
}

// What the Profichip driver refuses, the built-in user side refuses alike (audit s32-dpv1m,
// finding 1), each on the connection's SAP after the resource manager's 56h, and closes the
// connection once it is sent: a Type 0 address of Len 1: Abort 58 00 12 00 (Instance MSAC_C2,
// FE); Type 1 addresses of no bytes (16 bytes, under MSAC_C2_MIN_CR_PDU_SIZE 20): Abort
// 58 00 17 00 (IA); D_Type 1 (the slave is not the connection's end): the driver's example user
// answers Initiate | 80h, application / not supported (A9h). A correct Initiate is then taken.
TEST(Dpv1Scenario, TheUserSideRefusesTheInitiatesTheProfichipDriverRefuses) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=1440\nstartup\n"
                           "c2_initiate s_addr=00\nexpect dpv1 aborted\nexpect dpv1 58,00,12,00\n"
                           "c2_read slot=0 index=1 length=4\nexpect dpv1 no_connection\n"
                           "c2_initiate s_type=1 s_addr=- d_type=1 d_addr=-\n"
                           "expect dpv1 58,00,17,00\n"
                           "c2_initiate d_type=1\nexpect dpv1 error 80,A9,00\n"
                           "c2_initiate d_addr=01,00\nexpect dpv1 58,00,17,00\n"
                           "c2_initiate\nexpect dpv1 positive\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// s32-rev2 (review finding 2): the largest Initiate the doors take, S_Addr and D_Addr 16 bytes
// together (a Type 1 S_Addr of 14: API 0, SCL 0, 12 more; a Type 0 D_Addr 00 00), is 32 bytes,
// the resource manager's Max_Length: the built-in user side takes it and answers S and D swapped:
// 57 F0 01 00 00 00 00 00, S_Type 0 S_Len 2, D_Type 1 D_Len 14, 00 00, then the 14 bytes. Before,
// the doors took 16 bytes an address, and a 34-byte Initiate got RR (`refused`).
TEST(Dpv1Scenario, TheLargestInitiateTheDoorsTakeFitsTheResourceManager) {
  const std::string addr = "00,00,01,02,03,04,05,06,07,08,09,0A,0B,0C";
  const std::string text =
      std::string(kHead) + "dpv1 work=1440\nstartup\nc2_initiate s_type=1 s_addr=" + addr +
      " d_addr=00,00\nexpect dpv1 57,F0,01,00,00,00,00,00,00,02,01,0E,00,00," + addr + "\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// s32-rev2 (review findings 3 and 4): the driver's example user serves API 0 only and aborts an
// Initiate to another API (the first byte of D_Addr; here API 1) with 58 00 17 00 (Instance
// MSAC_C2, IA) before it looks at D_Type; and the driver aborts any Initiate shorter than 20
// bytes IA, one too short to hold its Send_Timeout (57 00 00 00 00, 5 bytes) too. That one's
// resource manager answer carries the driver's own Send_Timeout 100 (pdu::kMsacC2TimeoutMin):
// DL, DSAP 48 (30h), SSAP 49 (31h), 56 28 00 64, FCS 52h; the poll on SAP 40 (28h) gets the Abort,
// FCS D6h, and the connection closes once it is sent. Before: API 1 positive, and no answer at
// all to the 5 bytes (every poll SC).
TEST(Dpv1Scenario, TheUserSideAbortsAnotherApiAndAnInitiateWithoutSendTimeout) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=1440\nstartup\n"
                           "c2_initiate d_addr=01,00\nexpect dpv1 aborted\n"
                           "expect dpv1 58,00,17,00\n"
                           "send from=2 fc=0x6D dsap=49 ssap=48 du=57,00,00,00,00\n"
                           "expect answer sc\nsilence 1ms\n"
                           "send from=2 fc=0x5D dsap=49 ssap=48\n"
                           "expect answer 68,09,09,68,82,85,08,30,31,56,28,00,64,52,16\n"
                           "send from=2 fc=0x7D dsap=40 ssap=48\n"
                           "expect answer 68,09,09,68,82,85,08,30,28,58,00,17,00,D6,16\n"
                           "silence 1ms\nc2_initiate\nexpect dpv1 positive\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// A slave's Abort in answer to a service on the connection (audit s32-dpv1m, finding 3): the SAP
// list laid out by hand, SAP 49's response 56 28 00 64 and SAP 40's Initiate response ready; then
// SAP 40's response buffer gets 58 00 13 00 (Instance MSAC_C2, TO), which answers the Idle at once.
// The outcome is `aborted` (its bytes checkable), the walk names Instance and Reason_Code, and the
// master forgets the connection: the next Read is no_connection, nothing sent. Before: `malformed`.
TEST(Dpv1Scenario, AnAbortInAnswerToAServiceIsAborted) {
  const std::string text =
      hand_laid_connection("00,64", kInitiateResponseReady) +
      "c2_initiate\nexpect dpv1 positive\n"
      "write 0x7C0 bytes=A0,20,04,08,58,00,13,00\n"
      "c2_idle\nexpect dpv1 aborted\nexpect dpv1 58,00,13,00\nexpect dpv1 polls 0\n"
      "c2_read slot=0 index=1 length=4\nexpect dpv1 no_connection\n";
  std::vector<std::string> walk;
  EXPECT_EQ(failed_expects(text, &walk), std::vector<std::string>{});
  EXPECT_TRUE(has_line(walk, "c2_idle: aborted 58 00 13 00 (instance 1, reason 3) after 0 polls"));
}

// The connection's Send_Timeout is the larger of the Initiate's and the resource manager's
// (audit s32-dpv1m, finding 4): the Profichip driver runs the connection on max(the request's,
// its own minimum) and names its own in the 56h response, so a master that asked for less would
// give up while the slave still works. The layout above, the resource manager answering
// 56 28 00 02 (20 ms) to an Initiate with Send_Timeout 1 (10 ms); SAP 40's response buffer then
// holds nothing, so the Read on the connection gets SC for ever. At 12 Mbaud: the Read's SC ends
// at t0+748, poll n's at t0+748+704n (Dpv1Master.ResponseTimeOut); the first at or past
// 2 x 480 000 = 960 000 is n = 1363 (t0+960 300; n = 1362 ends at t0+959 596). Before: the
// master's own 10 ms, 681 polls, t0+480 172.
TEST(Dpv1Scenario, TheConnectionRunsOnTheLargerSendTimeout) {
  const std::string text = hand_laid_connection("00,02", kInitiateResponseReady) +
                           "c2_initiate send_timeout=1\nexpect dpv1 positive\n"
                           "c2_read slot=0 index=1 length=4\nexpect dpv1 timeout after 960300\n"
                           "expect dpv1 polls 1363\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// MSAC_C1 after a response time-out (finding 4): the user side's response comes 15 ms after the
// request, the master gave up at 10 ms (681 polls, Dpv1Master.ResponseTimeOut), so it waits in
// SAP 51's one buffer for a poll that never comes: the next Read gets RR. The class-1 master then
// parameterises the slave again (the standard's answer to a C1 time-out): the new Set_Prm frees
// the buffer, and the Read is taken again (and times out again: the same work). Before, the
// slave answered RR for ever, restart included.
TEST(Dpv1Scenario, AMsacC1ResponseNobodyCollectedIsFreedByTheNextSetPrm) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=720000 c1_timeout=1\nstartup\n"
                           "dpv1_read slot=0 index=1 length=4\nexpect dpv1 timeout\n"
                           "silence 20ms\n"
                           "dpv1_read slot=0 index=1 length=4\nexpect dpv1 refused\n"
                           "expect answer rr\nsilence 20ms\n"
                           "restart\nexpect dp_state Data_Exchange\n"
                           "dpv1_read slot=0 index=1 length=4\nexpect dpv1 timeout\n"
                           "expect dpv1 polls 681\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// MSAC_C1 is the locking class-1 master's (manual-quotes.md, "DPV1"; finding 6): after the DP
// watchdog (10 x 10 x 10 ms) sent the slave back to Wait_Prm (Leave_Master) nobody locks it, and
// SAP 51 answers RS (its entry switched off, VPC3+C p.55); the class-2 connection does not depend
// on the class-1 master and still answers.
TEST(Dpv1Scenario, MsacC1IsServedInDataExchangeOnly) {
  const std::string text =
      std::string(kHead) +
      "startup\nc2_initiate send_timeout=300\nsilence 1100ms\n"
      "expect dp_state Wait_Prm\nc2_idle\nexpect dpv1 48,00\n"
      "dpv1_read slot=0 index=1 length=1\nexpect dpv1 refused\n"
      "expect answer rs\n"
      "startup\ndpv1_read slot=0 index=1 length=1\nexpect dpv1 5E,00,01,01,11\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// An SDN to SAP 51 from the class-1 master (audit s28 aud1, finding 2): MSAC_C1 and MSAC_C2 are
// SRD services, so the built-in user side lists its SAPs with Service_Supported 0Bh (SRD low and
// high; docs/dpv1.md "Service_Supported codes"), and the chip refuses the SDN at the check (RS,
// which an SDN does not answer, VPC3+C p.55): nothing stored, no FDL_Ind, and the class-1
// master's Reads are served. Before, the SDN was stored, the user side put a Read response into
// the one C1 buffer that no SDN polls for, and every MSAC_C1 request got RR until a new Set_Prm.
TEST(Dpv1Scenario, AnSdnToTheC1SapDoesNotBlockMsacC1) {
  // The SDN (FC 46h: SDN high) gets no answer and raises nothing; both Reads are answered.
  const std::string sdn = "send from=2 fc=0x46 dsap=51 ssap=51 du=5E,00,01,04\n";
  EXPECT_EQ(
      failed_expects(std::string(kHead) + "startup\n" + sdn +
                     "expect answer none\nexpect irq count 0\n"
                     "dpv1_read slot=0 index=1 length=4\nexpect dpv1 5E,00,01,04,11,22,33,44\n"
                     "dpv1_read slot=0 index=1 length=2\nexpect dpv1 5E,00,01,02,11,22\n"),
      std::vector<std::string>{});
}

// Alarm_Ack on SAP 50 or 51 (manual-quotes.md, "DPV1"; finding 7): `alarm_ack sap=51` sends it
// from SAP 51 to SAP 51, and the built-in user side answers it there as on SAP 50: the 4 bytes
// echoed. Before, the master could not send it there and the user side never answered it (the
// master timed out).
TEST(Dpv1Scenario, AlarmAckOnSap51) {
  const std::string text = std::string(kHead) +
                           "dpv1 c1_timeout=1\nstartup\n"
                           "alarm_ack slot=0 type=1 seq=3 sap=51\nexpect dpv1 5C,00,01,18\n"
                           "alarm_ack slot=0 type=1 seq=4\nexpect dpv1 5C,00,01,20\n";
  std::vector<std::string> walk;
  EXPECT_EQ(failed_expects(text, &walk), std::vector<std::string>{});
  EXPECT_TRUE(has_line(walk, "2 -> 5 MSAC_C1 5C 00 01 18 => SC"));
  EXPECT_TRUE(has_line(walk, "2 -> 5 MSAC_C1_Alarm 5C 00 01 20 => SC"));
}

// A refused Abort leaves the connection known (finding 5): a Read on the connection that nobody
// polls leaves its response in the connection's one buffer, so the Abort gets RR (VPC3+C p.56).
// The master keeps the connection; once the response is fetched the Abort is sent again and
// taken (SC). Before, the master forgot the connection at the RR and the second Abort was
// refused without being sent.
TEST(Dpv1Scenario, ARefusedAbortLeavesTheConnectionKnown) {
  const std::string text = std::string(kHead) +
                           "dpv1 work=1440\nstartup\nc2_initiate send_timeout=100\n"
                           "expect dpv1 polls 2\n"
                           "send from=2 fc=0x4D dsap=40 ssap=48 du=5E,00,01,04\n"
                           "expect answer sc\nsilence 1ms\n"
                           "c2_abort reason=1\nexpect dpv1 refused\nexpect answer rr\n"
                           "send from=2 fc=0x4D dsap=40 ssap=48\nexpect answer data\n"
                           "c2_abort reason=1\nexpect dpv1 sc\n";
  std::vector<std::string> walk;
  EXPECT_EQ(failed_expects(text, &walk), std::vector<std::string>{});
  EXPECT_TRUE(has_line(walk, "2 -> 5 SAP 40 58 00 21 00 => SC"));
}

// The cycle of a DPV1 outcome (audit a20, finding 8; docs/dpv1.md, "The outcome's cycle"): the
// walk's result line, `expect dpv1 ... after` and Dpv1Answer::end are one cycle. A Read answered
// on poll 3 (dpv1_c1_vpc3plus.scn): the response's last stop bit at t0+3652. A Read to a slave
// gone Offline (Mode_Reg1 Go_Offline, bit 2) with retries=2: three tries of 15 characters (660
// clocks), each waiting TSL = 100 T = 400 clocks, TSYN = 132 before the next: the last from
// t0+2384 to t0+3044, the master gives up at its slot time's end, t0+3444. And MSAC_C2 without a
// connection: no_connection at t0 itself. Before, the walk printed the response 2 clocks early
// (the stop sample) and `after` checked no_answer at the last request's end (t0+3044).
TEST(Dpv1Scenario, TheWalkAndTheCheckShareTheOutcomesCycle) {
  const std::string text = std::string(kHead) +
                           "master retries=2\ndpv1 work=1440\nstartup\n"
                           "dpv1_read slot=0 index=1 length=4\n"
                           "expect dpv1 5E,00,01,04,11,22,33,44 after 3652\n"
                           "c2_read slot=0 index=1 length=4\n"
                           "expect dpv1 no_connection after 0\nexpect dpv1 polls 0\n"
                           "write Mode_Reg1_S 0x04\n"
                           "dpv1_read slot=0 index=1 length=4\n"
                           "expect dpv1 no_answer after 3444\n";
  std::vector<std::string> walk;
  EXPECT_EQ(failed_expects(text, &walk), std::vector<std::string>{});
  // "[cycle N] line L: TEXT" where the step begins, "[cycle N] NAME: OUTCOME" at its outcome.
  const auto cycle_of = [&](std::string_view part) -> std::uint64_t {
    const auto it = std::find_if(walk.begin(), walk.end(), [&](const std::string& l) {
      return l.find(part) != std::string::npos;
    });
    if (it == walk.end()) {
      ADD_FAILURE() << "no walk line with " << part;
      return 0;
    }
    return std::stoull(it->substr(7, 10));
  };
  EXPECT_EQ(cycle_of("] dpv1_read: 5E 00 01 04 11 22 33 44 after 2 polls") -
                cycle_of("line 8: dpv1_read"),
            3652u);
  EXPECT_EQ(cycle_of("] c2_read: no connection, nothing sent") - cycle_of("line 10: c2_read"), 0u);
  EXPECT_EQ(cycle_of("] dpv1_read: no answer after 0 polls") - cycle_of("line 14: dpv1_read"),
            3444u);
}

// DO4 (a firmware) with the master's `dpv1 c1_timeout=1` (audit a20, finding 2: refused before):
// the master gives up at the first SC at or past 10 ms = 480 000 clocks from the request's start.
// DO4's interrupts are masked (Int_Mask_Reg FFFFh), so its ISR never takes the request and every
// poll gets SC. At 1.5 Mbaud (T = 32, a character 352 clocks, TSYN 1056, an answer 11 T = 352
// after the request, docs/timing.md): the Read request (15 characters) ends at t0+5280, its SC
// ends at t0+5984; poll k (11 characters, 3872) starts 1056 after the last SC and its SC ends
// 3872+704 after its start: at t0+5984+5632k. The first at or past 480 000: k = 85 (t0+484 704;
// k = 84 ends at t0+479 072). The slave and the first Data_Exchange (after which DO4 opens SAP
// 51 to its master) as traces/do4_dpv1_vpc3plus.scn has them.
TEST(Dpv1Scenario, Do4ResponseTimeOut) {
  const std::string text =
      "profile vpc3plus\nbaud 1500000\nfirmware DO4\n"
      "slave address=5 wd=2,5 user_prm=C0,20,00,01,09,00\ndpv1 c1_timeout=1\n"
      "startup\nexpect dp_state Data_Exchange\nexchange outputs=05,01\n"
      "write Int_Mask_Reg 0xFFFF\n"
      "dpv1_read slot=0 index=1 length=2\nexpect dpv1 timeout after 484704\n"
      "expect dpv1 polls 85\n";
  EXPECT_EQ(failed_expects(text), std::vector<std::string>{});
}

// Every outcome docs/dpv1.md lists is a word of `expect dpv1` (audit s28 aud1, finding 7):
// positive and negative from the built-in user side; malformed from a SAP list laid out by hand
// (VPC3+C p.55) whose SAP 51 has the response 01 02 ready (USER + RESP): the Read's request is
// stored in buffer 0710h and answered with it, neither a Read response nor a negative one.
// Before, each of these words was "bad byte ... in dpv1 response".
TEST(Dpv1Scenario, EveryOutcomeTheDocsListCanBeExpected) {
  EXPECT_EQ(failed_expects(std::string(kHead) +
                           "startup\ndpv1_read slot=0 index=1 length=4\nexpect dpv1 positive\n"
                           "dpv1_read slot=0 index=2 length=4\nexpect dpv1 negative\n"),
            std::vector<std::string>{});
  EXPECT_EQ(failed_expects("profile vpc3plus\nbaud 12000000\nslave address=5 user_prm=C0,00,00\n"
                           "startup\nwrite 0x700 bytes=33,7F,7F,00,E2,00,E8,FF\n"
                           "write 0x710 bytes=00,20,00,00\nwrite 0x740 bytes=A0,20,02,08,01,02\n"
                           "write R_FDL_SAP_List_Ptr 0xE0\n"
                           "dpv1_read slot=0 index=1 length=4\nexpect dpv1 malformed\n"),
            std::vector<std::string>{});
}

// Bad DPV1 lines are parse errors with their line (docs/scenario-format.md, "DPV1"): nothing
// runs.
TEST(Dpv1Scenario, ParseErrorsNameTheLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"profile spc3\nrecord slot=0 index=1 data=01\n",
       "t.scn:2: 'record' needs 'profile vpc3plus' before it: DPV1 is modelled on the VPC3+ only "
       "(the DPC31's is not modelled; the SPC3 has none)"},
      // docs/dpv1.md: the DPC31 has DPV1 in silicon, its interface not modelled.
      {"profile dpc31\ndpv1_read slot=0 index=1 length=1\n",
       "t.scn:2: 'dpv1_read' needs 'profile vpc3plus': DPV1 is modelled on the VPC3+ only (the "
       "DPC31's is not modelled; the SPC3 has none)"},
      // The built-in user side's lines with a firmware (it answers DPV1 itself); the master's
      // c1_timeout= and c2_ssap= are taken (Dpv1Scenario.Do4ResponseTimeOut).
      {"profile vpc3plus\nfirmware DO4\nrecord slot=0 index=1 data=01\n",
       "t.scn:3: 'record' is the built-in user side's; a firmware answers DPV1 itself (the "
       "master's "
       "'dpv1 c1_timeout=' and 'c2_ssap=' are allowed)"},
      {"profile vpc3plus\nfirmware DO4\ndpv1 c1_timeout=1 work=10\n",
       "t.scn:3: 'dpv1 work=' is the built-in user side's; a firmware answers DPV1 itself (the "
       "master's 'dpv1 c1_timeout=' and 'c2_ssap=' are allowed)"},
      {"profile vpc3plus\ndpv1 work=10\nfirmware DO4\nstartup\n",
       "t.scn:2: 'dpv1 work=' is the built-in user side's; a firmware answers DPV1 itself (the "
       "master's 'dpv1 c1_timeout=' and 'c2_ssap=' are allowed)"},
      {"profile vpc3plus\nstartup\ndpv1_read slot=0 index=1\n",
       "t.scn:3: dpv1_read needs slot=N index=N length=N"},
      // A misspelt outcome word gets the list of words (audit s28 aud1, finding 7), a bad byte
      // in a byte list the byte's error.
      {"profile vpc3plus\nstartup\nexpect dpv1 no-answer\n",
       "t.scn:3: unknown DPV1 outcome 'no-answer': "
       "positive|negative|refused|no_answer|timeout|malformed|no_connection|aborted|sc, or the "
       "response's "
       "hex bytes"},
      {"profile vpc3plus\nstartup\nexpect dpv1 5E,0x100\n",
       "t.scn:3: bad byte '0x100' in dpv1 response (hex bytes separated by commas)"},
      {"profile vpc3plus\nstartup\nexpect dpv1 polls\n",
       "t.scn:3: expected 'expect dpv1 BYTES', 'expect dpv1 error DECODE,CODE1,CODE2', 'expect "
       "dpv1 polls N' or 'expect dpv1 "
       "positive|negative|refused|no_answer|timeout|malformed|no_connection|aborted|sc'"},
      {"profile vpc3plus\nstartup\nexpect dpv1 error 80,B0\n",
       "t.scn:3: expect dpv1 error: three bytes, Error_Decode,Error_Code_1,Error_Code_2"},
      {"profile vpc3plus\ncorrupt parity\ndpv1_read slot=0 index=1 length=4\n",
       "t.scn:2: the next action ('dpv1_read', line 3) is a DPV1 service: a fault line cannot "
       "damage it"},
      {"profile vpc3plus\nrecord slot=0 index=1 data=01\nrecord slot=0 index=1 data=02\n",
       "t.scn:3: record slot=0 index=1 given twice"},
      {"profile vpc3plus\nalarm_ack slot=0 type=1\n",
       "t.scn:2: alarm_ack needs slot=N type=N seq=N"},
      // s32-rev2 (review finding 2): S_Addr and D_Addr together past the 16 bytes the 32-byte
      // resource-manager buffer holds beside the request's 16 fixed ones (15 + 2 = 17).
      {"profile vpc3plus\nstartup\nc2_initiate s_type=1 "
       "s_addr=00,00,01,02,03,04,05,06,07,08,09,0A,0B,0C,0D d_addr=00,00\n",
       "t.scn:3: s_addr and d_addr: 17 bytes together, more than 16: the Initiate (33 bytes) "
       "would not fit the resource manager's 32-byte buffer"},
      // The Specifier's bits 1..0 (docs/dpv1.md: Seq_Nr << 3 | Add_Ack << 2 | bits 1..0).
      {"profile vpc3plus\nalarm_ack slot=0 type=1 seq=0 spec=5\n",
       "t.scn:2: spec 5 out of range (0..3)"},
      {"profile vpc3plus\nalarm_ack slot=0 type=1 seq=0 sap=49\n",
       "t.scn:2: sap 49 out of range (50..51)"},
      // Options that acted on nothing (finding 8): records the chip never hands over (no
      // DPV1_Enable: the SAP list stays off), a work time with no record to work on.
      {"profile vpc3plus\nrecord slot=0 index=1 data=01\nstartup\n",
       "t.scn:2: record needs DPV1_Enable (slave user_prm= byte 0 bit 7): without it the VPC3+ "
       "keeps the SAP list off and answers every DPV1 request RS"},
      {"profile vpc3plus\nslave user_prm=40,00,00\nrecord slot=0 index=1 data=01\nstartup\n",
       "t.scn:3: record needs DPV1_Enable (slave user_prm= byte 0 bit 7): without it the VPC3+ "
       "keeps the SAP list off and answers every DPV1 request RS"},
      {"profile vpc3plus\nslave user_prm=C0,00,00\ndpv1 work=1440\nstartup\n",
       "t.scn:3: dpv1 work= is the built-in user side's DPV1 time and needs a record: without "
       "one it serves no DPV1"},
      // The first work time past kWorkCycles (docs/scenario-format.md: 0-48000000 clocks), the
      // range Python's run_responder(work_cycles=) refuses too (Python.bad_input).
      {"profile vpc3plus\nslave user_prm=C0,00,00\nrecord slot=0 index=1 data=01\n"
       "dpv1 work=48000001\n",
       "t.scn:4: work 48000001 out of range (0..48000000)"},
  };
  for (const auto& [text, want] : cases) {
    Scenario s;
    ScenarioError err;
    EXPECT_FALSE(parse_scenario(text, "t.scn", s, err)) << text;
    EXPECT_EQ(err.text(), want);
  }
  Scenario s;
  ScenarioError err;
  // The range's last value is taken.
  EXPECT_TRUE(
      parse_scenario("profile vpc3plus\nslave user_prm=C0,00,00\nrecord slot=0 index=1 data=01\n"
                     "dpv1 work=48000000\nstartup\n",
                     "t.scn", s, err))
      << err.text();
  EXPECT_EQ(s.user.dpv1.work_cycles, 48'000'000u);
  // A Reason_Code beyond its 4 bits.
  s = Scenario{};
  EXPECT_FALSE(parse_scenario("profile vpc3plus\nc2_abort reason=16\n", "t.scn", s, err));
  EXPECT_EQ(err.line, 2);
}

// docs/dpv1.md (top): "The master's DPV1 services on another chip than the VPC3+ are refused before
// anything is sent", in the scenario's and Python's words; the C++ door at the Dpv1Master's making
// (s35 audit aMix finding 9: a Read on a DPC31 sent its request and its retry, then no_answer),
// on one chip and on a segment's station. Nothing is sent: the master's history stays empty.
TEST(Dpv1Master, AnotherChipThanTheVpc3plusIsRefusedBeforeAnythingIsSent) {
  const auto refused = [](const Chip& chip, DpMaster& master, const char* profile) {
    try {
      Dpv1Master dpv1(chip, master);
      ADD_FAILURE() << profile << ": not refused";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                fmt::format("Dpv1Master: DPV1 services need a vpc3plus, not a {}: DPV1 is "
                            "modelled on the VPC3+ only (the DPC31's is not modelled; the SPC3 "
                            "has none)",
                            profile));
    }
    EXPECT_TRUE(master.history().empty());
  };
  for (const Profile p : {Profile::dpc31, Profile::spc3}) {
    Chip chip{ChipOptions{p, BusMode::intel, 0}};
    DpMaster master(chip, MasterConfig{2, 1'500'000, 100, 33}, SlaveConfig{});
    refused(chip, master, p == Profile::dpc31 ? "dpc31" : "spc3");
    EXPECT_EQ(chip.cycle(), 0U);
  }
  Segment seg(1'500'000);
  const std::size_t station = seg.add_chip("d", ChipOptions{Profile::dpc31, BusMode::intel, 0});
  DpMaster master(seg, seg.add_sender("master 2"), MasterConfig{}, {SlaveConfig{}});
  refused(seg.chip(station), master, "dpc31");
  EXPECT_EQ(seg.cycle(), 0U);
}

}  // namespace
