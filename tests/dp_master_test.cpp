// The built-in master's wait for an answer (DpMaster::wait_answer) is one rule: after the last
// character on the line (its request's, then each of the answer's) it waits a slot time TSL for
// the next start bit. When TSL passes without one, the exchange is over (no answer, or a broken
// one) and the line counts as free from that cycle: the next request starts TSYN after it.
// docs/timing.md: "unanswered FDL_Status requests repeat every 199 bit times (66 + slot 100 + 33)";
// docs/decisions.md: TSYN 33 and TSL 100 bit times, the EN 50170 defaults. T = 32 cycles at
// 1.5 Mbaud (48 MHz).
#include "dp_master.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "dpc31/bus_port.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/log.hpp"
#include "dpc31/pdu.hpp"
#include "responder.hpp"
#include "segment.hpp"

namespace {

using namespace dpc31;

constexpr std::uint64_t T = 32;
constexpr std::uint64_t kTsl = 100 * T;
constexpr std::uint64_t kTsyn = 33 * T;
constexpr std::uint64_t kChar = 11 * T;

// A master polling station 5 on a line where only a scripted sender answers (or nobody).
struct Line {
  Segment seg{1'500'000};
  std::size_t rogue = seg.add_sender("rogue");
  std::size_t m = seg.add_sender("master 2");
  DpMaster master{seg, m, MasterConfig{}, {SlaveConfig{}}};
  // The rogue sends `bytes` TSDR (tsdr_bits) after the end of the master's first request (its first
  // start bit and its characters: on_send), and nothing after later ones. The scheduler returns
  // after the send, as a segment waking its master does (Segment::run_until's wake_for): the
  // master looks at the line at the start bit, not only at its wait's end.
  void rogue_answers_the_first_request(std::vector<std::uint8_t> bytes) {
    master.on_send = [this](std::uint64_t start, std::span<const std::uint8_t> request,
                            const UartFault&) {
      if (first_end == 0) first_end = start + request.size() * kChar;
    };
    master.scheduler = [this, bytes = std::move(bytes), sent = false](std::uint64_t cycle) mutable {
      if (!sent) {
        sent = true;
        seg.run_until(first_end);
        seg.send(rogue, bytes, first_end + tsdr_bits * T);
        return;
      }
      seg.run_until(cycle);
    };
  }
  std::uint64_t first_end = 0;
  std::uint64_t tsdr_bits = 11;  // the rogue's answer delay
};

// One SPC3 with the built-in user side, for masters at 12 Mbaud (T = 4) made with master().
struct OneChip {
  Chip chip{ChipOptions{Profile::spc3}};
  ResponderConfig rc;
  Responder user{rc};
  DirectBus bus{chip};
  OneChip() { user.init(bus); }
  std::unique_ptr<DpMaster> master(std::uint32_t slot_bits) {
    MasterConfig mc;
    mc.baud = 12'000'000;  // the baud search's first rate
    mc.slot_bits = slot_bits;
    auto m = std::make_unique<DpMaster>(chip, mc, rc.slave);
    m->set_firmware([this](BusPort& b) { user.isr(b); });
    return m;
  }
};

TEST(DpMaster, NoAnswerEndsTheWaitASlotTimeAfterTheRequestThenTsyn) {
  Line l;
  ASSERT_EQ(l.master.bit_cycles(), T);
  const Exchange a = l.master.fdl_status();
  EXPECT_FALSE(a.answer);
  EXPECT_EQ(a.answer_start, 0u);
  EXPECT_EQ(a.answer_end, 0u);
  EXPECT_EQ(a.request_end, a.request_start + 6 * kChar);  // SD1: 6 characters
  const Exchange b = l.master.fdl_status();
  EXPECT_EQ(b.request_start, a.request_end + kTsl + kTsyn);  // 199 bit times start to start
  EXPECT_EQ(l.master.counters().no_answer, 2u);
}

TEST(DpMaster, AnAnswerThatStopsEndsTheWaitASlotTimeAfterItsLastCharacterThenTsyn) {
  Line l;
  // The rogue starts an answer TSDR 11 after the request's end: SD2 with LE and LEr (7 data
  // bytes announced), and falls silent after those 3 characters.
  l.rogue_answers_the_first_request({fdl::SD2, 0x07, 0x07});
  const Exchange a = l.master.fdl_status();
  EXPECT_FALSE(a.answer);
  EXPECT_EQ(a.answer_start, a.request_end + 11 * T);
  EXPECT_EQ(a.answer_end, a.answer_start + 3 * kChar);
  EXPECT_EQ(l.master.counters().bad_answer, 1u);
  const Exchange b = l.master.fdl_status();
  EXPECT_EQ(b.request_start, a.answer_end + kTsl + kTsyn);
  EXPECT_FALSE(b.answer);
  const Exchange c = l.master.fdl_status();
  EXPECT_EQ(c.request_start, b.request_end + kTsl + kTsyn);
}

// An answer later than the slot time is on the line between the wait's end and the next request
// (docs/timing.md: that request starts TSYN after the wait's end): the master finds it in its
// receiver when it waits for the next answer, whose wait begins at that request's start on a
// segment (docs/segment.md, "Masters on it"). It ends no wait inside the master's own request:
// every request starts after the one before it has ended, and the line sees no collision.
TEST(DpMaster, ALateAnswerEndsNoWaitInsideTheNextRequest) {
  Line l;
  // The rogue's SC 105 bit times after the first request's end, put on the line as the master
  // is about to send its second request (on_send: the line's time is the first wait's end).
  std::uint64_t first_end = 0;
  int sent = 0;
  l.master.on_send = [&](std::uint64_t start, std::span<const std::uint8_t> request,
                         const UartFault&) {
    if (++sent == 1) first_end = start + request.size() * kChar;
    if (sent == 2)
      l.seg.send(l.rogue, std::vector<std::uint8_t>{fdl::SC}, first_end + kTsl + 5 * T);
  };
  const Exchange a = l.master.fdl_status();
  EXPECT_FALSE(a.answer);
  const Exchange b = l.master.fdl_status();
  EXPECT_EQ(b.request_start, a.request_end + kTsl + kTsyn);
  // Nor is it the answer of the request it came before: b waits its own slot time out.
  EXPECT_FALSE(b.answer);
  const Exchange c = l.master.fdl_status();
  EXPECT_EQ(c.request_start, b.request_end + kTsl + kTsyn);
  EXPECT_TRUE(l.seg.collisions().empty());
}

// The same on one chip (the audit's case, 12 Mbaud): with a slot time of 5 bit times every answer
// of the chip (TSDR at least 11) is late. Each request waits its own slot time out, none takes the
// answer to the request before it, and the next request starts TSYN after the slot time's end at
// the earliest (a bus access of the firmware may carry the run a few cycles past it).
TEST(DpMaster, OnOneChipALateAnswerIsNoLaterRequestsAnswer) {
  constexpr std::uint64_t kT12 = 4;  // cycles a bit at 12 Mbaud
  OneChip one;
  Chip& chip = one.chip;
  const std::unique_ptr<DpMaster> owner = one.master(5);
  DpMaster& master = *owner;
  bool answered_late = false;  // the chip answered at all (it found the rate)
  std::uint64_t last_end = 0;
  for (int i = 0; i < 300; ++i) {
    const Exchange ex = i % 2 == 0 ? master.fdl_status() : master.slave_diag();
    EXPECT_FALSE(ex.answer) << "request " << i;
    EXPECT_FALSE(ex.stray) << "request " << i;
    if (last_end != 0) {
      EXPECT_GE(ex.request_start, last_end + (5 + 33) * kT12) << "request " << i;
    }
    last_end = ex.request_end;
    answered_late = answered_late || chip.wd_state() != WdState::Baud_Search;
  }
  EXPECT_TRUE(answered_late) << "the chip never found the rate: nothing was late";
  EXPECT_EQ(master.counters().no_answer, 300u);
}

// A late answer that ends before the master's next request would start (the rogue's SC 105 bit
// times after the request's end, on the line before the wait ends): docs/timing.md, "The master's
// wait": the idle time counts from the end of the last telegram on the line, "whichever is
// later", so the next request starts 105 + 11 + 33 = 149 bit times after the first one's end,
// not TSL + TSYN = 133 (where the rogue's SC left only 17 bit times of idle). The SC is counted
// late (MasterCounters::late) and is no request's answer.
TEST(DpMaster, ALateAnswerMovesTheNextRequestToTsynAfterItsEnd) {
  Line l;
  l.rogue_answers_the_first_request({fdl::SC});
  l.tsdr_bits = 105;
  const Exchange a = l.master.fdl_status();
  EXPECT_FALSE(a.answer);
  EXPECT_EQ(a.wait_end, a.request_end + kTsl);
  const Exchange b = l.master.fdl_status();
  EXPECT_EQ(b.request_start, a.request_end + (105 + 11 + 33) * T);
  EXPECT_FALSE(b.answer);
  EXPECT_EQ(l.master.counters().late, 1u);
  EXPECT_EQ(l.master.counters().no_answer, 2u);
  EXPECT_TRUE(l.seg.collisions().empty());
}

// The same on one chip, 12 Mbaud (T = 4), with a slot time of 5 bit times: the chip answers
// FDL_Status (SD1, 6 characters) at the request's end + 11 T (docs/timing.md, "Telegrams":
// max(11, MinTSDR) T, MinTSDR_Val 11), to + 77 T; the next request starts TSYN after that end,
// + 110 T = 440 cycles after the first one's end (before: + 38 T, the slot time's end + TSYN).
TEST(DpMaster, OnOneChipTheRequestAfterALateAnswerWaitsTsynFromItsEnd) {
  constexpr std::uint64_t kT12 = 4;
  OneChip one;
  ASSERT_TRUE(one.master(100)->startup());  // TSL 100: the chip found the rate and answers
  const std::unique_ptr<DpMaster> owner = one.master(5);
  DpMaster& master = *owner;
  const Exchange a = master.fdl_status();
  EXPECT_FALSE(a.answer);
  EXPECT_EQ(a.wait_end, a.request_end + 5 * kT12);
  const Exchange b = master.fdl_status();
  EXPECT_EQ(b.request_start, a.request_end + (11 + 66 + 33) * kT12);
  EXPECT_FALSE(b.answer);
  EXPECT_EQ(master.counters().late, 1u);
}

// One chip, 12 Mbaud, MinTSDR 255 (a Set_Prm from the locking master with Lock/Unlock 00: only
// MinTSDR taken, CP 5613 p.198): its SC comes 1020 cycles after the request's end, past TSL
// (400). The master's Slave_Diag (SD2, 11 characters) starts TSL + TSYN = 532 cycles after the
// Set_Prm's end and ends 484 later, at + 1016, so the chip is asked while its SC still waits for
// its TSDR: half duplex, it does not act on that request (no `requests` counted, a warning), and
// the SC at + 1020 comes 1 bit time after the Slave_Diag's end, before the shortest TSDR (11):
// the master passes it over as late, not as the Slave_Diag's answer (docs/timing.md, "The
// master's wait").
TEST(DpMaster, OnOneChipAnAnswerDueWhenAskedAgainIsLateAndTheRequestNotActedOn) {
  OneChip one;
  Chip& chip = one.chip;
  std::vector<std::string> warnings;
  chip.set_log_sink([&warnings](const LogRecord& r) {
    if (r.level == LogLevel::warn) warnings.push_back(r.text);
  });
  const std::unique_ptr<DpMaster> owner = one.master(100);
  DpMaster& master = *owner;
  ASSERT_TRUE(master.startup());
  master.slave().min_tsdr = 255;
  const Exchange prm = master.set_prm_status(pdu::SetPrm::WD_On);  // Lock/Unlock 00
  EXPECT_FALSE(prm.answer);
  const std::uint32_t requests = chip.fdl_counters().requests;
  const Exchange diag = master.slave_diag();
  EXPECT_EQ(diag.request_start, prm.request_end + (100 + 33) * 4);
  EXPECT_EQ(diag.request_end, prm.request_end + 1016);
  EXPECT_FALSE(diag.answer);
  EXPECT_FALSE(diag.stray);
  EXPECT_EQ(diag.wait_end, diag.request_end + 400);
  EXPECT_EQ(chip.fdl_counters().requests, requests);
  EXPECT_EQ(master.counters().late, 1u);
  EXPECT_EQ(std::count(warnings.begin(), warnings.end(),
                       "a request from station 2 ended while the answer to the one before was "
                       "still due (armed or on the line): not acted on, not answered (half "
                       "duplex)"),
            1);
}

// The audit's start-up with MinTSDR 255 and TSL 100 (12 Mbaud): from the Set_Prm on every answer
// is late, so none is taken, and `startup()` does not report a Data_Exchange it never saw (it
// returned true from a Chk_Cfg's late SC taken as the next Slave_Diag's answer).
TEST(DpMaster, AStartUpWhoseAnswersAreAllLateFails) {
  OneChip one;
  one.rc.slave.min_tsdr = 255;
  const std::unique_ptr<DpMaster> owner = one.master(100);
  EXPECT_FALSE(owner->startup(20));
  EXPECT_GT(owner->counters().late, 0u);
}

// Station 5 played by a scripted sender: each request of the master is answered with what
// `answer` makes of it (nothing: silence), TSDR 11 bit times after the request's end.
struct ScriptedSlave {
  Segment seg{1'500'000};
  std::size_t rogue = seg.add_sender("station 5");
  std::size_t m = seg.add_sender("master 2");
  DpMaster master{seg, m, MasterConfig{}, {SlaveConfig{}}};
  std::function<std::vector<std::uint8_t>(const fdl::Frame&)> answer;
  std::vector<std::uint8_t> due;
  std::uint64_t due_at = 0;
  ScriptedSlave() {
    master.on_send = [this](std::uint64_t start, std::span<const std::uint8_t> request,
                            const UartFault&) {
      const fdl::Decoded d = fdl::decode(request);
      due = d.error == fdl::Error::none ? answer(d.frame) : std::vector<std::uint8_t>{};
      due_at = start + request.size() * kChar + 11 * T;
    };
    master.scheduler = [this](std::uint64_t cycle) {
      if (!due.empty() && cycle >= due_at) {
        seg.run_until(due_at);
        seg.send(rogue, due, due_at);
        due.clear();
        return;
      }
      seg.run_until(cycle);
    };
  }
};

// A Slave_Diag answer (DL, from SAP 60 to the master's 62) with Station_Status_1..3, Master_Add
// and the Ident_Number 0C31h (chip-facts.md, Slave_Diag).
std::vector<std::uint8_t> diag_answer(std::uint8_t st1, std::uint8_t st2, std::uint8_t master) {
  return fdl::encode(fdl::make_frame(2, 5, fdl::make_response_fc(fdl::Response::DL),
                                     {st1, st2, 0x00, master, 0x0C, 0x31}, 62, 60));
}

// docs/decisions.md, the thirty-fourth session: a start-up's Set_Prm without an answer leaves the
// slave's state unknown, so the master goes on with Slave_Diag, not Chk_Cfg (EN 50170: a master
// parameterises a slave again from its diagnosis). Station 5 answers FDL_Status and a first
// Slave_Diag with Prm_Req (Wait_Prm), is silent to Set_Prm, then reports Wait_Cfg
// (Station_Not_Ready, Master_Add 2, no Prm_Req): the master sends Set_Prm and Chk_Cfg again. The
// Slave_Diag after the silent Set_Prm starts TSL 100 + TSYN 33 bit times after its end
// (docs/timing.md).
TEST(DpMaster, AnUnansweredSetPrmIsFollowedBySlaveDiagAndParameterisedAgain) {
  ScriptedSlave l;
  int prms = 0;
  l.answer = [&prms](const fdl::Frame& req) -> std::vector<std::uint8_t> {
    using D = pdu::SlaveDiag;
    if (!req.dsap)
      return fdl::encode(fdl::make_frame(2, 5, fdl::make_response_fc(fdl::Response::OK)));
    switch (fdl::sap_number(*req.dsap)) {
      case sap::Slave_Diag:
        return prms == 0 ? diag_answer(D::St1_Station_Not_Ready, D::St2_Prm_Req | D::St2_Always_1,
                                       D::kNoMaster)
                         : diag_answer(D::St1_Station_Not_Ready, D::St2_Always_1 | D::St2_WD_On, 2);
      case sap::Set_Prm:
        ++prms;
        return {};
      default:
        return {};
    }
  };
  EXPECT_FALSE(l.master.startup(6));
  const std::vector<Exchange>& h = l.master.history();
  std::vector<std::optional<std::uint8_t>> saps;
  for (const Exchange& e : h) {
    saps.push_back(e.request.dsap ? std::optional(fdl::sap_number(*e.request.dsap)) : std::nullopt);
  }
  const std::vector<std::optional<std::uint8_t>> want = {
      std::nullopt, sap::Slave_Diag, sap::Set_Prm, sap::Slave_Diag,
      sap::Set_Prm, sap::Slave_Diag, sap::Set_Prm, sap::Slave_Diag};
  ASSERT_GE(saps.size(), want.size());
  EXPECT_EQ(std::vector(saps.begin(), saps.begin() + static_cast<std::ptrdiff_t>(want.size())),
            want);
  EXPECT_FALSE(h[2].answer);
  EXPECT_EQ(h[3].request_start, h[2].request_end + kTsl + kTsyn);
  EXPECT_EQ(std::count(saps.begin(), saps.end(), std::optional<std::uint8_t>(sap::Chk_Cfg)), 0);
}

// A master is a station too: the C++ door refuses a slave at the master's own address (a segment
// scenario's `master 5 at the address of station 5`; the Segment knows no chip's address).
TEST(DpMaster, ASlaveAtTheMastersOwnAddressIsRefused) {
  Segment seg{1'500'000};
  const std::size_t m = seg.add_sender("master 5");
  SlaveConfig five;
  five.address = 5;
  MasterConfig mc;
  mc.address = 5;
  try {
    DpMaster master(seg, m, mc, {SlaveConfig{}, five});
    ADD_FAILURE() << "master 5 polling slave 5 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "DpMaster: master 5 at the address of station 5");
  }
}

// An answer mirrors its request's addresses: a telegram in its place from another station, or to
// another, is not its answer (Exchange::stray, counted as a bad answer).
TEST(DpMaster, ATelegramAddressedOtherwiseIsNotTheAnswer) {
  // Addressed otherwise, or addressed as an answer but a request or a token (the review: a
  // response has FC bit 6 clear, EN 50170).
  for (const fdl::Frame& f :
       {fdl::make_frame(2, 7, fdl::make_response_fc(fdl::Response::OK)),
        fdl::make_frame(3, 5, fdl::make_response_fc(fdl::Response::OK)),
        fdl::make_frame(2, 5, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)),
        fdl::token(2, 5)}) {
    SCOPED_TRACE(testing::PrintToString(fdl::encode(f)));
    Line l;
    l.rogue_answers_the_first_request(fdl::encode(f));
    const Exchange a = l.master.fdl_status();
    EXPECT_FALSE(a.answer);
    ASSERT_TRUE(a.stray);
    EXPECT_EQ(*a.stray, f);
    EXPECT_EQ(l.master.counters().bad_answer, 1u);
    const Exchange b = l.master.fdl_status();
    // The master waits TSYN from the stray's end, as after an answer; a token to the master is
    // no answer either (fdl_status does not take the token).
    EXPECT_EQ(b.request_start, a.answer_end + kTsyn);
  }
}

// clear_history() lends the forgotten exchanges' memory to the next ones (DpMaster::spare_):
// history() shows each new exchange as it was returned, an unanswered one after an answered one
// too.
TEST(DpMaster, AnExchangeAfterClearHistoryIsInTheHistoryAsReturned) {
  Line l;
  l.rogue_answers_the_first_request(
      fdl::encode(fdl::make_frame(2, 5, fdl::make_response_fc(fdl::Response::OK), {1, 2, 3})));
  const Exchange a = l.master.fdl_status();
  ASSERT_TRUE(a.answer);
  EXPECT_EQ(a.answer->du, (std::vector<std::uint8_t>{1, 2, 3}));
  l.master.clear_history();
  EXPECT_TRUE(l.master.history().empty());
  const Exchange b = l.master.fdl_status();
  ASSERT_FALSE(b.answer);
  ASSERT_EQ(l.master.history().size(), 1u);
  const Exchange& h = l.master.history()[0];
  EXPECT_EQ(h.request, b.request);
  EXPECT_FALSE(h.answer);
  EXPECT_EQ(h.request_start, b.request_start);
  EXPECT_EQ(h.request_end, b.request_end);
  EXPECT_EQ(h.answer_start, 0u);
  EXPECT_EQ(h.answer_end, 0u);
}

// A master destroyed while its chip runs on takes its TxD observer away (~DpMaster): the chip
// no longer writes into the memory the master had (here the test's own) when the next master's
// exchanges put characters on TxD.
// An idle of any length ends at the chip's last cycle at the latest (include/dpc31/chip.hpp):
// UINT64_MAX, a caller's "no limit", wrapped to a cycle already past and idled for nothing.
TEST(DpMaster, AnIdleOfUint64MaxRunsTheChipToItsLastCycle) {
  Chip chip(ChipOptions{Profile::spc3});
  DpMaster master(chip, MasterConfig{}, SlaveConfig{});
  master.idle(1000);
  EXPECT_EQ(chip.cycle(), 1000u);
  master.idle(std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(chip.cycle(), Chip::kLastCycle);
  // A request there ends its waits at the last cycle too (the review's case: the wait for the
  // answer's slot time looped, the chip unable to move).
  EXPECT_FALSE(master.fdl_status().answer);
  EXPECT_EQ(chip.cycle(), Chip::kLastCycle);
}

TEST(DpMaster, AMasterDestroyedLeavesNoObserverOnItsChip) {
  Chip chip(ChipOptions{Profile::spc3});
  ResponderConfig rc;
  Responder user(rc);
  user.set_inputs({1, 2, 3, 4});
  DirectBus bus(chip);
  user.init(bus);
  const auto isr = [&user](BusPort& b) { user.isr(b); };
  alignas(DpMaster) std::array<std::byte, sizeof(DpMaster)> memory{};
  auto* gone = new (memory.data()) DpMaster(chip, MasterConfig{2, 1'500'000}, rc.slave);
  gone->set_firmware(isr);
  ASSERT_TRUE(gone->startup());
  gone->~DpMaster();
  memory.fill(std::byte{0xA5});  // what an observer left behind would take for a receiver
  const auto left = memory;
  DpMaster m(chip, MasterConfig{2, 1'500'000}, rc.slave);
  m.set_firmware(isr);
  ASSERT_TRUE(m.startup());
  const Exchange x = m.data_exchange({5, 6, 7, 8});
  ASSERT_TRUE(x.answer);
  EXPECT_EQ(x.answer->du, user.inputs());
  EXPECT_EQ(memory, left) << "the chip wrote into a gone master";
}

// The built-in user side takes inputs of the slave's length or none: other lengths reached the
// chip cut, or padded with the buffer's stale bytes (std::invalid_argument, in the scenario's
// words; the inputs as they were).
TEST(Responder, InputsOfAnotherLengthThanInAreRefused) {
  ResponderConfig rc;
  rc.slave.in_len = 2;
  Responder user(rc);
  user.set_inputs({1, 2});
  for (const std::vector<std::uint8_t>& bad :
       {std::vector<std::uint8_t>{9}, std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6}}) {
    try {
      user.set_inputs(bad);
      ADD_FAILURE() << bad.size() << " bytes taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                fmt::format("inputs: {} bytes for a slave with in=2: inputs are exactly in= "
                            "bytes, or none",
                            bad.size()));
    }
    EXPECT_EQ(user.inputs(), (std::vector<std::uint8_t>{1, 2}));
  }
  user.set_inputs({});
  EXPECT_TRUE(user.inputs().empty());
}

// The dpc31 clear buffer C takes substitute values of the slave's out_len or none: 2 bytes for 4
// outputs reached the user as 5A 5B and the C buffer's stale bytes (old outputs after a cleared
// fetch), 6 were cut to 4 (std::invalid_argument, in the scenario's words).
TEST(Responder, SubstituteValuesOfAnotherLengthThanOutAreRefused) {
  ResponderConfig rc;  // out_len 4
  for (const std::vector<std::uint8_t>& bad :
       {std::vector<std::uint8_t>{0x5A, 0x5B}, std::vector<std::uint8_t>(6, 0x5A)}) {
    rc.substitute = bad;
    try {
      const Responder user(rc);
      ADD_FAILURE() << bad.size() << " bytes taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                fmt::format("substitute: {} bytes for a slave with out=4: substitute values are "
                            "exactly out= bytes, or none",
                            bad.size()));
    }
  }
  for (const std::size_t ok : {0, 4}) {
    rc.substitute.assign(ok, 0x5A);
    EXPECT_NO_THROW(const Responder user(rc)) << ok;
  }
}

// The built-in user side's buffers must fit the profile's RAM (audit s32 siblings, finding 1:
// on the SPC3 in=out=235 put them past 5FFh without a word, a RAM access violation, the chip
// Offline). SPC3: 8-byte segments from 40h (segment 8), 3 x out, 3 x in, 2 diag buffers of 6
// bytes and 6 aux buffers of 8 (1 segment each). in = out = 232: 29 segments each, 8 + 174 + 8
// = 190 segments, the last byte 0x5EF; in = out = 233: 30 each, 8 + 180 + 8 = 196, the last
// byte 0x61F, past 0x5FF. Refused before any bus access, in every door's words.
TEST(Responder, BuffersPastTheRamAreRefusedBeforeAnyWrite) {
  ResponderConfig rc;
  rc.slave.in_len = rc.slave.out_len = 233;
  Chip chip(ChipOptions{Profile::spc3});
  DirectBus bus(chip);
  Responder user(rc);
  try {
    user.init(bus);
    ADD_FAILURE() << "taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "in=233 out=233 cfg of 2 bytes user_prm of 0 bytes: the built-in user side's "
              "buffers would end at 0x61f, past the 1536 bytes of RAM of profile spc3 (its user "
              "area 0x040..0x5ff)");
  }
  EXPECT_EQ(chip.cycle(), 0u) << "a bus access before the refusal";
  EXPECT_EQ(responder_layout(chip.profile(), rc).end, 0x620u);
  rc.slave.in_len = rc.slave.out_len = 232;
  EXPECT_EQ(responder_layout(chip.profile(), rc).end, 0x5F0u);
  Responder fits(rc);
  std::vector<std::uint8_t> in(232);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<std::uint8_t>(i);
  fits.set_inputs(in);
  fits.init(bus);
  DpMaster m(chip, MasterConfig{2, 1'500'000}, rc.slave);
  m.set_firmware([&fits](BusPort& b) { fits.isr(b); });
  ASSERT_TRUE(m.startup());
  const Exchange x = m.data_exchange(std::vector<std::uint8_t>(232, 0x5A));
  ASSERT_TRUE(x.answer);
  EXPECT_EQ(x.answer->du, in);
  EXPECT_EQ(chip.peek_reg(RegId::Status_Reg) & fields::Status_Reg::RAM_Access_Violation, 0);
  // The other profiles hold 244 each way: the VPC3+ still in 2 KB (8-byte segments, 8 to 202:
  // 3 x 31 out, 3 x 31 in, 2 diag, 6 x 1 aux: 202; 0x64F), the DPC31 from 08A0h (32-byte segments,
  // 69 to 135 with its clear buffer C and its queues: 0x10DF).
  rc.slave.in_len = rc.slave.out_len = 244;
  EXPECT_EQ(responder_layout(profile_desc(Profile::vpc3plus), rc).end, 0x650u);
  EXPECT_EQ(responder_layout(profile_desc(Profile::dpc31), rc).end, 0x10E0u);
  EXPECT_NE(responder_layout_problem(profile_desc(Profile::spc3), rc), "");
}

// One rule for every length cell an answer reads (docs/timing.md, "Length cells"): a DP data
// unit carries at most 244 bytes (chip-facts.md §1.2), so R_Len_Din_Buf, R_Len_Read_Cfg_Data
// and R_Len_Diag_Buf beyond it send the buffer's first 244 bytes, and the chip says so once per
// cell and value (audit s32 siblings, finding 4: from 247 no answer to a Data_Exchange, 245 and
// 246 input bytes sent, Get_Cfg and Rd_Inp unanswered from 245, the diag cut without a word).
TEST(Responder, LengthCellsBeyondADataUnitSendTheFirst244BytesAndSaySo) {
  for (const Profile p : {Profile::spc3, Profile::vpc3plus, Profile::dpc31}) {
    SCOPED_TRACE(std::string(profile_desc(p).name));
    Chip chip(ChipOptions{p});
    std::vector<std::string> log;
    chip.set_log_sink([&log](const LogRecord& r) { log.push_back(r.text); });
    const auto logged = [&log](const std::string& text) {
      return std::count_if(log.begin(), log.end(),
                           [&text](const std::string& l) { return l.find(text) == 0; });
    };
    const auto cell = [&chip](const char* name) {
      return static_cast<std::uint32_t>(find_reg(chip.profile(), name)->read_addr);
    };
    ResponderConfig rc;
    rc.slave.in_len = 244;
    Responder user(rc);
    std::vector<std::uint8_t> in(244);
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<std::uint8_t>(i + 1);
    user.set_inputs(in);
    DirectBus bus(chip);
    user.init(bus);
    DpMaster m(chip, MasterConfig{2, 1'500'000}, rc.slave);
    m.set_firmware([&user](BusPort& b) { user.isr(b); });
    ASSERT_TRUE(m.startup());
    const std::string beyond =
        ": beyond the 244 bytes of a DP data unit: the answer sends the "
        "buffer's first 244 (modelled)";
    for (const int len : {245, 246, 247, 255, 255, 244, 245}) {
      SCOPED_TRACE(len);
      chip.write(cell("R_Len_Din_Buf"), static_cast<std::uint8_t>(len));
      Exchange x = m.data_exchange({0, 0, 0, 0});
      ASSERT_TRUE(x.answer);
      EXPECT_EQ(x.answer->du, in);
      x = m.read_inputs();
      ASSERT_TRUE(x.answer);
      EXPECT_EQ(x.answer->du, in);
    }
    // Once per value it was set to (245 twice: 244 came between), never at 244 itself.
    EXPECT_EQ(logged("R_Len_Din_Buf = 245" + beyond), 2);
    for (const int len : {246, 247, 255}) {
      EXPECT_EQ(logged(fmt::format("R_Len_Din_Buf = {}", len) + beyond), 1);
    }
    EXPECT_EQ(logged("R_Len_Din_Buf = 244"), 0);

    // Get_Cfg: the Read_Cfg buffer's 244 bytes from its segment on, as the user reads them.
    const std::uint32_t read_cfg = static_cast<std::uint32_t>(chip.read(cell("R_Read_Cfg_Buf_Ptr")))
                                   << chip.profile().segment_shift;
    std::vector<std::uint8_t> ram(244);
    for (std::uint32_t i = 0; i < ram.size(); ++i) ram[i] = chip.read(read_cfg + i);
    chip.write(cell("R_Len_Read_Cfg_Data"), 250);
    Exchange x = m.get_cfg();
    ASSERT_TRUE(x.answer);
    EXPECT_EQ(x.answer->du, ram);
    EXPECT_EQ(logged("R_Len_Read_Cfg_Data = 250" + beyond), 1);

    // Slave_Diag: cut to 244 as before, now with its line (whichever diag buffer is sent).
    chip.write(cell("R_Len_Diag_Buf1"), 250);
    chip.write(cell("R_Len_Diag_Buf2"), 250);
    x = m.slave_diag();
    ASSERT_TRUE(x.answer);
    EXPECT_EQ(x.answer->du.size(), 244u);
    EXPECT_EQ(logged("R_Len_Diag_Buf1 = 250" + beyond) + logged("R_Len_Diag_Buf2 = 250" + beyond),
              1);
  }
}

// What the log has said is in the snapshot (docs/snapshots.md, section LOGS): a chip restored
// from one says nothing the original run would not have said. Before the snapshot each cause
// once: R_Len_Din_Buf 250 (a line per cell and value, docs/timing.md "Length cells"), the Dout
// and Din pointers 00h (a Data_Exchange is two uses of buffers over the registers: the first
// use's line, then a count at 10, 100, ...) and a read at 0x802 beyond the SPC3's 11-bit bus (the
// bus side's folded log, as unmapped accesses have). After the load the same causes again: no
// line at all, and the 10th use of a buffer over the registers (the 5th Data_Exchange in all)
// gives its count, as in the run that was never saved.
TEST(Responder, ARestoredChipDoesNotRepeatItsLog) {
  Chip chip(ChipOptions{Profile::spc3});
  std::vector<std::string> log;
  chip.set_log_sink([&log](const LogRecord& r) {
    if (r.level == LogLevel::warn) log.push_back(r.text);
  });
  ResponderConfig rc;
  Responder user(rc);
  DirectBus bus(chip);
  user.init(bus);
  DpMaster m(chip, MasterConfig{2, 1'500'000}, rc.slave);
  m.set_firmware([&user](BusPort& b) { user.isr(b); });
  ASSERT_TRUE(m.startup());
  const auto cell = [&chip](const char* name) {
    return static_cast<std::uint32_t>(find_reg(chip.profile(), name)->read_addr);
  };
  for (const char* ptr : {"R_Dout_Buf_Ptr1", "R_Dout_Buf_Ptr2", "R_Dout_Buf_Ptr3", "R_Din_Buf_Ptr1",
                          "R_Din_Buf_Ptr2", "R_Din_Buf_Ptr3"}) {
    chip.write(cell(ptr), 0x00);
  }
  chip.write(cell("R_Len_Din_Buf"), 250);
  const auto causes = [&] {
    ASSERT_TRUE(m.data_exchange({1, 2, 3, 4}).answer);
    chip.read(0x802);
  };
  log.clear();
  causes();
  ASSERT_EQ(log.size(), 3u) << "each cause's first line";
  chip.load_state(chip.save_state());
  log.clear();
  causes();
  EXPECT_EQ(log, std::vector<std::string>{});
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(m.data_exchange({1, 2, 3, 4}).answer);  // uses 5..10
  ASSERT_EQ(log.size(), 1u);
  EXPECT_TRUE(
      log[0].starts_with("10 uses of buffers over the registers so far (the latest: R_Din_Buf_Ptr"))
      << log[0];
}

// The firmware of the two tests below: the built-in user side with New_Cfg_Data masked (C0F0h is
// its own mask, every interrupt it serves enabled), so that the test gives the Cfg verdict for it
// (User_Cfg_Data_Okay, 00h finished) and chooses whether New_Din_Buffer_Cmd is read after it.
struct CfgVerdictByHand {
  explicit CfgVerdictByHand(Profile p) : chip(ChipOptions{p}) {
    chip.set_log_sink([this](const LogRecord& r) {
      if (r.level == LogLevel::warn) log.emplace_back(r.cycle, r.text);
    });
  }
  [[nodiscard]] std::uint32_t at(RegId id) const {
    return static_cast<std::uint32_t>(chip.addr_of(id));
  }
  // Start-up to the Cfg verdict, given: Wait_Cfg until the VPC3+ and DPC31 enter Data_Exchange.
  void to_the_verdict() {
    DirectBus bus(chip);
    user.init(bus);
    constexpr std::uint16_t kMask = 0xC0F0 | irq::New_Cfg_Data;
    chip.write(at(RegId::Int_Mask_Reg), static_cast<std::uint8_t>(kMask));  // Intel: low first
    chip.write(at(RegId::Int_Mask_Reg) + 1, static_cast<std::uint8_t>(kMask >> 8));
    master.set_firmware([this](BusPort& b) { user.isr(b); });
    while (!master.fdl_status().answer) {
    }
    ASSERT_EQ(master.set_prm().answer->sd, fdl::SC);
    ASSERT_EQ(master.chk_cfg().answer->sd, fdl::SC);
    ASSERT_EQ(chip.dp_state(), DpState::Wait_Cfg);
    ASSERT_EQ(chip.read(at(RegId::User_Cfg_Data_Okay)), 0x00);
  }
  Chip chip;
  std::vector<std::pair<std::uint64_t, std::string>> log;  // the warnings
  ResponderConfig rc;
  Responder user{rc};
  DpMaster master{chip, MasterConfig{2, 1'500'000}, rc.slave};
};

// A firmware that gives its Cfg verdict (User_Cfg_Data_Okay, 00h finished) but never reads
// New_Din_Buffer_Cmd, which the built-in user side does at once: its New_Cfg_Data is masked and the
// test reads the verdict for it. SPC3 p.31: "the transition to 'DATA_EX' takes place immediately,
// if no Din_buffer is present (R_Len_Din_Puf = 00H) ... Otherwise" (cut off; modelled: at the
// user's next New_Din_Buffer_Cmd, docs/decisions.md), so with R_Len_Din_Buf = 4 the SPC3 stays in
// Wait_Cfg and its Slave_Diag shows Station_Not_Ready. The first poll from Master_Add acted on
// (docs/timing.md: at the stop sample of the request's last character, end - T + T/2) 10 ms =
// 480 000 cycles (48 MHz) or more after the verdict read's completion cycle gets the warning, and
// nothing after it does (a Data_Exchange answered RS neither). The snapshot carries when the wait
// began and that it was said (docs/snapshots.md, LOGS): a chip restored from before the warning
// says it at its own first poll past the same cycle, one restored from after it never. The VPC3+
// (VPC3+C p.43: "immediately, if trigger counters ... are at 0") and the DPC31 enter
// Data_Exchange at the verdict itself: no wait, no line.
TEST(Responder, AnSpc3FirmwareThatNeverReadsNewDinBufferCmdIsToldOnce) {
  using D = pdu::SlaveDiag;
  const auto warning = [](const char* refused) {
    return fmt::format(
        "master 2 is refused ({}): the SPC3 is still in Wait_Cfg at least 10 ms after "
        "User_Cfg_Data_Okay, because the firmware has not read New_Din_Buffer_Cmd since; with "
        "R_Len_Din_Buf = 4 it enters Data_Exchange only at that read (SPC3 p.31, modelled). Hand "
        "the inputs over once after User_Cfg_Data_Okay: write them into the U buffer, then read "
        "New_Din_Buffer_Cmd (docs/bring-up.md)",
        refused);
  };
  const std::string by_diag = warning("Slave_Diag with Station_Not_Ready");
  for (const Profile p : {Profile::spc3, Profile::vpc3plus, Profile::dpc31}) {
    SCOPED_TRACE(std::string(profile_desc(p).name));
    CfgVerdictByHand f(p);
    ASSERT_NO_FATAL_FAILURE(f.to_the_verdict());
    Chip& chip = f.chip;
    DpMaster& m = f.master;
    const auto& log = f.log;
    if (p != Profile::spc3) {
      EXPECT_EQ(chip.dp_state(), DpState::Data_Exchange);
      for (int i = 0; i < 60; ++i) ASSERT_TRUE(m.slave_diag().answer);  // 60 x 233 us: 14 ms
      EXPECT_EQ(log, (std::vector<std::pair<std::uint64_t, std::string>>{}));
      continue;
    }
    const std::uint64_t due = chip.cycle() + 480'000;
    // Polls with Slave_Diag (or Data_Exchange, `dx`) until one is acted on at `due` or later,
    // and returns that cycle; the chip's snapshot after the first poll acted on 5 ms or more
    // before `due` goes to `half_way`.
    const auto poll_past = [&due](DpMaster& master, Chip& c, std::vector<std::uint8_t>* half_way,
                                  const std::vector<std::pair<std::uint64_t, std::string>>& l,
                                  bool dx = false) {
      for (;;) {
        const Exchange d = dx ? master.data_exchange({1, 2, 3, 4}) : master.slave_diag();
        EXPECT_TRUE(d.answer && (dx ? fdl::response_code(d.answer->fc) == fdl::Response::RS
                                    : (d.answer->du.at(0) & D::St1_Station_Not_Ready) != 0));
        const std::uint64_t acted = d.request_end - T + T / 2;
        if (acted >= due) return acted;
        EXPECT_EQ(l.size(), 0u) << "said at the poll acted on at " << acted;
        if (half_way != nullptr && half_way->empty() && acted + 240'000 >= due)
          *half_way = c.save_state();
      }
    };
    std::vector<std::uint8_t> half_way;
    const std::uint64_t acted = poll_past(m, chip, &half_way, log);
    ASSERT_EQ(log.size(), 1u);
    EXPECT_EQ(log[0], std::pair(acted, by_diag));
    std::vector<std::uint8_t> said = chip.save_state();
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(m.slave_diag().answer);
    EXPECT_EQ(fdl::response_code(m.data_exchange({1, 2, 3, 4}).answer->fc), fdl::Response::RS);
    EXPECT_EQ(log.size(), 1u) << log.back().second;
    EXPECT_EQ(chip.dp_state(), DpState::Wait_Cfg);

    // Restored from half-way: polled by Slave_Diag, by Data_Exchange, by another master (3, which
    // has not locked the slave: its polls past `due` say nothing, master 2's next one does); from
    // after the line.
    enum class Poll { diag, dx, other_master, after_the_line };
    for (const Poll how : {Poll::diag, Poll::dx, Poll::other_master, Poll::after_the_line}) {
      SCOPED_TRACE(static_cast<int>(how));
      Chip restored(ChipOptions{p});
      std::vector<std::pair<std::uint64_t, std::string>> restored_log;
      restored.set_log_sink([&restored_log](const LogRecord& r) {
        if (r.level == LogLevel::warn) restored_log.emplace_back(r.cycle, r.text);
      });
      restored.load_state(how == Poll::after_the_line ? said : half_way);
      DpMaster mr(restored, MasterConfig{2, 1'500'000}, f.rc.slave);
      if (how == Poll::other_master) {
        DpMaster other(restored, MasterConfig{3, 1'500'000}, f.rc.slave);
        poll_past(other, restored, nullptr, restored_log);
        for (int i = 0; i < 10; ++i) ASSERT_TRUE(other.slave_diag().answer);
        EXPECT_EQ(restored_log.size(), 0u);
        const Exchange d = mr.slave_diag();
        ASSERT_EQ(restored_log.size(), 1u);
        EXPECT_EQ(restored_log[0], std::pair(d.request_end - T + T / 2, by_diag));
      } else if (how != Poll::after_the_line) {
        const bool dx = how == Poll::dx;
        const std::uint64_t restored_acted = poll_past(mr, restored, nullptr, restored_log, dx);
        ASSERT_EQ(restored_log.size(), 1u);
        EXPECT_EQ(restored_log[0],
                  std::pair(restored_acted, dx ? warning("Data_Exchange answered RS") : by_diag));
      } else {
        for (int i = 0; i < 10; ++i) ASSERT_TRUE(mr.slave_diag().answer);
        EXPECT_EQ(restored_log.size(), 0u);
      }
    }
  }
}

// The same SPC3 firmware that does read New_Din_Buffer_Cmd, 5 ms after its Cfg verdict: the
// chip enters Data_Exchange at that read (docs/decisions.md), and polls for 20 ms after the
// verdict give no warning; nor does the built-in user side, which reads it at once.
TEST(Responder, AnSpc3FirmwareThatReadsNewDinBufferCmdIsNotWarned) {
  CfgVerdictByHand f(Profile::spc3);
  ASSERT_NO_FATAL_FAILURE(f.to_the_verdict());
  Chip& chip = f.chip;
  DpMaster& m = f.master;
  const std::uint64_t verdict = chip.cycle();
  while (chip.cycle() < verdict + 240'000) ASSERT_TRUE(m.slave_diag().answer);
  EXPECT_EQ(chip.dp_state(), DpState::Wait_Cfg);
  chip.read(f.at(RegId::New_Din_Buffer_Cmd));
  EXPECT_EQ(chip.dp_state(), DpState::Data_Exchange);
  while (chip.cycle() < verdict + 960'000) ASSERT_TRUE(m.slave_diag().answer);
  EXPECT_EQ(f.log.size(), 0u) << f.log.front().second;

  Chip fine(ChipOptions{Profile::spc3});
  std::vector<std::string> log;  // the warnings
  fine.set_log_sink([&log](const LogRecord& r) {
    if (r.level == LogLevel::warn) log.push_back(r.text);
  });
  Responder fine_user(f.rc);
  DirectBus fine_bus(fine);
  fine_user.init(fine_bus);
  DpMaster fm(fine, MasterConfig{2, 1'500'000}, f.rc.slave);
  fm.set_firmware([&fine_user](BusPort& b) { fine_user.isr(b); });
  ASSERT_TRUE(fm.startup());
  const std::uint64_t ready = fine.cycle();
  while (fine.cycle() < ready + 960'000) ASSERT_TRUE(fm.data_exchange({1, 2, 3, 4}).answer);
  EXPECT_EQ(log, std::vector<std::string>{});
}

// A buffer pointer that puts a buffer over the registers (00h, the reset value: a driver that
// forgot them) is served from the RAM behind them, which the CPU does not see there (modelled):
// the log says so the first time, then counts the uses as unmapped accesses are counted, at 10,
// 100, ... (audit s32 siblings, finding 5: silent). Each Data_Exchange with outputs is two uses:
// the outputs stored into D, the inputs read from D. The outputs FF come back as the inputs (the
// same hidden bytes at 000h) while a bus read of 000h gives Int_Req_Reg's low byte.
TEST(Responder, BuffersOverTheRegistersAreLogged) {
  Chip chip(ChipOptions{Profile::spc3});
  std::vector<std::string> log;  // the warnings
  chip.set_log_sink([&log](const LogRecord& r) {
    if (r.level == LogLevel::warn) log.push_back(r.text);
  });
  ResponderConfig rc;
  Responder user(rc);  // no inputs: the user side writes no buffer itself
  DirectBus bus(chip);
  user.init(bus);
  DpMaster m(chip, MasterConfig{2, 1'500'000}, rc.slave);
  m.set_firmware([&user](BusPort& b) { user.isr(b); });
  ASSERT_TRUE(m.startup());
  for (const char* ptr : {"R_Dout_Buf_Ptr1", "R_Dout_Buf_Ptr2", "R_Dout_Buf_Ptr3", "R_Din_Buf_Ptr1",
                          "R_Din_Buf_Ptr2", "R_Din_Buf_Ptr3"}) {
    chip.write(static_cast<std::uint32_t>(find_reg(chip.profile(), ptr)->read_addr), 0x00);
  }
  log.clear();
  const Exchange x = m.data_exchange({0xFF, 0xFF, 0xFF, 0xFF});
  ASSERT_TRUE(x.answer);
  EXPECT_EQ(x.answer->du, (std::vector<std::uint8_t>{0xFF, 0xFF, 0xFF, 0xFF}));
  ASSERT_EQ(log.size(), 1u);
  EXPECT_TRUE(log[0].starts_with("R_Dout_Buf_Ptr")) << log[0];
  EXPECT_TRUE(
      log[0].ends_with(" = 00h puts its buffer at 0x000, over the registers (below "
                       "0x016): the chip keeps its bytes in RAM the CPU does not see "
                       "there (modelled); further such uses are counted"))
      << log[0];
  EXPECT_NE(chip.read(0x000), 0xFF);
  for (int i = 0; i < 4; ++i) m.data_exchange({0xFF, 0xFF, 0xFF, 0xFF});  // uses 3..10
  ASSERT_EQ(log.size(), 2u);
  EXPECT_TRUE(
      log[1].starts_with("10 uses of buffers over the registers so far (the latest: R_Din_Buf_Ptr"))
      << log[1];
}

// The DPC31's queues are buffers the chip uses as well (review s32 rev1, finding 3: InstQ_Base
// and IndQ_Base, 00h at reset, were read and written behind the registers without a word):
// pointers below 0800h log as the DP buffers do. MAC_Stop (11h) from a queue at segment 50h
// (0A00h) confirms into an Indication_Queue at segment 01h (020h); then InstQ_Base 00h has the
// chip read entry 1 at 002h, behind the registers: 00h, no request.
TEST(Requests, QueuesOverTheRegistersAreLogged) {
  Chip chip(ChipOptions{Profile::dpc31});
  std::vector<std::string> log;
  chip.set_log_sink([&log](const LogRecord& r) {
    if (r.level == LogLevel::warn) log.push_back(r.text);
  });
  const auto at = [&chip](RegId id) { return static_cast<std::uint32_t>(chip.addr_of(id)); };
  chip.write(at(RegId::InstQ_Base), 0x50);
  chip.write(at(RegId::InstQ_Len), 4);
  chip.write(at(RegId::IndQ_Base), 0x01);
  chip.write(at(RegId::IndQ_Len), 4);
  chip.write_block(0xA00, std::array<std::uint8_t, 2>{request::MAC_Stop, 0x00});
  chip.write(at(RegId::InstQ_Wr), 1);
  ASSERT_EQ(log.size(), 1u);
  EXPECT_EQ(log[0],
            "IndQ_Base = 01h puts its buffer at 0x020, over the registers (below 0x800): the chip "
            "keeps its bytes in RAM the CPU does not see there (modelled); further such uses are "
            "counted");
  EXPECT_EQ(chip.read(at(RegId::IndQ_Wr)), 1);
  chip.write(at(RegId::InstQ_Base), 0x00);
  chip.write(at(RegId::InstQ_Wr), 2);
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[1], "InstQ_Base = 00h puts its buffer at 0x000, over the registers");
  EXPECT_EQ(log[2], "unknown request code 00h (parameter 00h): skipped");
}

}  // namespace
