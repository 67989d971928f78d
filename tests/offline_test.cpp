// Go_Offline and a RAM access violation "after the current request" (chip-facts.md: Mode_Reg1
// bit 2 "go Offline after the current request; MAC_Reset interrupt"; IRR bit 0 MAC_Reset "ASIC
// reached Offline after finishing the current request (Go_Offline or RAM access violation)"),
// with the current request as docs/timing.md "Go_Offline" defines it, in both engines.
//
// Every cycle is derived by hand from docs/timing.md at 48 MHz and 12 Mbaud (T = 4 clocks, 11
// bit times per character): Start_SPC3 completes at s; the master's FDL_Status to station 5
// (10 05 02 49 50 16, FCS 05 + 02 + 49 = 50h) starts at s + 132 (TSYN after Start), its first
// character's stop sample is s + 132 + 10 T + T/2 = s + 174 (the request in progress from here),
// it ends at s + 132 + 6 x 11 T = s + 396; the answer 10 02 05 00 07 16 (worked example
// "Startup.ReachesDataExchangeAtExactCycles") starts MinTSDR = 11 T later at s + 440 and ends at
// s + 440 + 6 x 11 T = s + 704: the current request ends there.
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/uart.hpp"
#include "test_util.hpp"

using namespace dpc31;

// Its own namespace: the names below may meet other tests' in a unity build.
namespace offline_test {
namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

constexpr std::uint32_t kT = 4;
constexpr std::uint64_t kRequestAt = 132;  // from s
constexpr std::uint64_t kAnswerAt = 440;
constexpr std::uint64_t kAnswerEnd = 704;
const std::vector<std::uint8_t> kRequest = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
const std::vector<std::uint8_t> kAnswer = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};

// How the user takes the chip Offline: Go_Offline (Mode_Reg1_S bit 2), or a read of the first
// address past the RAM (SPC3 600h, VPC3+ 800h: the RAM access violation).
enum class How : std::uint8_t { go_offline, violation };

struct Line {
  Chip chip;
  Edges txd;
  std::uint64_t s = 0;  // the cycle Start_SPC3 completed

  // min_tsdr: a MinTSDR_Val written before Start (0: the reset value, 11). `request`: the
  // master's telegram at s + kRequestAt, with `fault` in one of its characters.
  Line(Profile p, Engine e, std::uint8_t min_tsdr = 0,
       const std::vector<std::uint8_t>& request = kRequest, UartFault fault = {})
      : chip(ChipOptions{p, BusMode::intel, 0, e}) {
    chip.set_log_sink(nullptr);
    chip.on_txd([this](std::uint64_t c, bool l) { txd.emplace_back(c, l); });
    chip.write(static_cast<std::uint32_t>(chip.addr_of(RegId::R_TS_Adr)), 5);
    if (min_tsdr != 0)
      chip.write(static_cast<std::uint32_t>(chip.addr_of(RegId::MinTSDR_Val)), min_tsdr);
    s = testutil::user_start(chip);
    if (fault.kind == UartFault::Kind::none) {
      chip.drive_rxd_chars(request, s + kRequestAt, kT);
      return;
    }
    Edges edges;
    uart_encode(request, s + kRequestAt, kT, edges, fault);
    for (const auto& [cycle, level] : edges) chip.drive_rxd(cycle, level);
  }
  // The access that takes the chip Offline, completing at s + at (a bus access takes 4 clocks).
  void offline_at(std::uint64_t at, How how) {
    chip.step(s + at - 4 - chip.cycle());
    if (how == How::go_offline) {
      chip.write(0x08, 0x04);
    } else {
      (void)chip.read(chip.profile().violation_from);
    }
    ASSERT_EQ(chip.cycle(), s + at);
  }
  void step_to(std::uint64_t at) { chip.step(s + at - chip.cycle()); }
  [[nodiscard]] bool mac_reset() const {
    return (chip.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset) != 0;
  }
  [[nodiscard]] Edges answer_edges() const {
    Edges e;
    uart_encode(kAnswer, s + kAnswerAt, kT, e);
    return e;
  }
};

struct Param {
  Profile profile;
  Engine engine;
  How how;
};

class OfflineAfterRequest : public ::testing::TestWithParam<Param> {
 protected:
  Line line() const { return Line(GetParam().profile, GetParam().engine); }
  How how() const { return GetParam().how; }
  // No request in progress at `at`: Offline with MAC_Reset at once; by cycle 2000 the line
  // carries `txd` and `heard_offline` telegrams were heard Offline (counted, not answered).
  void expect_offline_at_once(std::uint64_t at, const Edges& txd, unsigned heard_offline) const {
    SCOPED_TRACE(at);
    Line l = line();
    l.offline_at(at, how());
    EXPECT_FALSE(l.chip.started());
    EXPECT_TRUE(l.mac_reset());
    l.step_to(2000);
    EXPECT_EQ(l.txd, txd);
    EXPECT_EQ(l.chip.fdl_counters().offline, heard_offline);
  }
};

// Still started until s + kAnswerEnd, then Offline with MAC_Reset in that cycle.
void expect_offline_at_answer_end(Line& l) {
  l.step_to(kAnswerEnd - 1);
  EXPECT_TRUE(l.chip.started());
  EXPECT_FALSE(l.mac_reset());
  l.step_to(kAnswerEnd);
  EXPECT_FALSE(l.chip.started());
  EXPECT_TRUE(l.mac_reset());
  EXPECT_EQ(l.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(l.chip.peek_reg(RegId::Status_Reg) & 0xC1, 0);  // Offline, WD state Baud_Search
  l.step_to(2000);
  EXPECT_EQ(l.txd, l.answer_edges());  // the answer whole, at its cycles, and nothing after
}

}  // namespace

TEST_P(OfflineAfterRequest, WhileTheRequestIsReceivedTheAnswerIsSentWhole) {
  Line l = line();
  l.offline_at(204, how());  // after the first character's stop sample (s + 174)
  EXPECT_TRUE(l.chip.started());
  EXPECT_FALSE(l.mac_reset());
  // Status bit 0 still Passive_Idle; Go_Offline reads 1 while it waits (SPC3 has no read-back).
  EXPECT_EQ(l.chip.read(0x04) & 0x01, 0x01);
  if (how() == How::go_offline) {
    EXPECT_EQ(l.chip.peek_reg(RegId::Mode_Reg1) & 0x04, 0x04);
  }
  // A Start written meanwhile finds the chip started: no effect, the Offline stays due.
  l.chip.write(0x08, 0x01);
  expect_offline_at_answer_end(l);
}

TEST_P(OfflineAfterRequest, WhileTheAnswerIsSentItIsNotCut) {
  Line l = line();
  l.offline_at(500, how());  // 60 clocks (15 bit times) into the answer
  EXPECT_TRUE(l.chip.started());
  expect_offline_at_answer_end(l);
}

TEST_P(OfflineAfterRequest, WhileTheAnswerIsArmedItIsSent) {
  Line l = line();
  l.offline_at(420, how());  // the request acted on at s + 394, the answer starts at s + 440
  expect_offline_at_answer_end(l);
}

TEST_P(OfflineAfterRequest, WhileIdleAtOnce) {
  // Before the request: it is heard Offline (counted), not answered; after the answer: whole.
  expect_offline_at_once(100, Edges{}, 1);
  expect_offline_at_once(800, line().answer_edges(), 0);
}

// Inside the first character, before its stop sample (s + 174), no request is in progress yet
// (docs/timing.md): Offline at once, the telegram is heard Offline. The cycle before it is the
// last one so.
TEST_P(OfflineAfterRequest, BeforeTheFirstStopSampleAtOnce) {
  expect_offline_at_once(172, Edges{}, 1);
  expect_offline_at_once(173, Edges{}, 1);
}

// From the first character's stop sample (s + 174) on, the request is in progress: the Offline
// waits for the answer's end.
TEST_P(OfflineAfterRequest, AtTheFirstStopSampleItWaits) {
  Line l = line();
  l.offline_at(174, how());
  EXPECT_TRUE(l.chip.started());
  EXPECT_FALSE(l.mac_reset());
  expect_offline_at_answer_end(l);
  EXPECT_EQ(l.chip.fdl_counters().offline, 0u);
}

namespace {

// A request that ends without an answer, the Offline due since s + 204 (after the first stop
// sample, s + 174): still started at s + at - 1, Offline with MAC_Reset at s + at, the cycle the
// MAC drops the telegram (docs/timing.md "Go_Offline"). The FDL_Status to station 5 driven at
// s + 1000 (TSYN after any of them) is then heard Offline: counted, never answered.
void expect_offline_when_dropped(Line& l, How how, std::uint64_t at) {
  l.offline_at(204, how);
  l.step_to(at - 1);
  EXPECT_TRUE(l.chip.started());
  EXPECT_FALSE(l.mac_reset());
  l.step_to(at);
  EXPECT_FALSE(l.chip.started());
  EXPECT_TRUE(l.mac_reset());
  EXPECT_EQ(l.chip.dp_state(), DpState::Wait_Prm);
  l.chip.drive_rxd_chars(kRequest, l.s + 1000, kT);
  l.step_to(2000);
  EXPECT_EQ(l.txd, Edges{});
  EXPECT_EQ(l.chip.fdl_counters().offline, 1u);
}

// The last stop sample of `chars` characters from s + kRequestAt: the last one's start + 10 T +
// T/2 (docs/timing.md).
constexpr std::uint64_t last_stop_sample(std::uint64_t chars) {
  return kRequestAt + (chars - 1) * 11 * kT + 10 * kT + kT / 2;
}

}  // namespace

// Global_Control (SDN, DSAP 58 = 3Ah, SSAP 62 = 3Eh) to the broadcast address 127 (DA FFh with
// the address extension), Control_Command and Group_Select 00h: FCS = FF + 82 + 44 + 3A + 3E =
// 3Dh (mod 100h). No answer is due: Offline at its last stop sample, s + 132 + 12 x 44 + 42.
TEST_P(OfflineAfterRequest, ABroadcastEndsAtItsLastStopSample) {
  const std::vector<std::uint8_t> gc = {0x68, 0x07, 0x07, 0x68, 0xFF, 0x82, 0x44,
                                        0x3A, 0x3E, 0x00, 0x00, 0x3D, 0x16};
  Line l(GetParam().profile, GetParam().engine, 0, gc);
  expect_offline_when_dropped(l, how(), last_stop_sample(13));
}

// An FDL_Status to station 6 (FCS 06 + 02 + 49 = 51h): a foreign address, no answer: Offline at
// its last stop sample, s + 394.
TEST_P(OfflineAfterRequest, AForeignAddressEndsAtItsLastStopSample) {
  Line l(GetParam().profile, GetParam().engine, 0, {0x10, 0x06, 0x02, 0x49, 0x51, 0x16});
  expect_offline_when_dropped(l, how(), last_stop_sample(6));
}

// The FDL_Status cut after 5 of its 6 characters: the 5th ends at s + 132 + 5 x 44 = s + 352,
// the line idle for TSYN (33 T) drops it as truncated at s + 484 (docs/timing.md "inside a
// telegram").
TEST_P(OfflineAfterRequest, ATruncatedTelegramEndsAtTheTsynTimeout) {
  const std::vector<std::uint8_t> cut(kRequest.begin(), kRequest.end() - 1);
  Line l(GetParam().profile, GetParam().engine, 0, cut);
  expect_offline_when_dropped(l, how(), kRequestAt + 5 * 11 * kT + 33 * kT);
}

// A parity error in the 3rd character (index 2): dropped at that character's stop sample,
// s + 132 + 2 x 44 + 42 = s + 262.
TEST_P(OfflineAfterRequest, ABadCharacterEndsAtItsStopSample) {
  Line l(GetParam().profile, GetParam().engine, 0, kRequest, UartFault{2, UartFault::Kind::parity});
  expect_offline_when_dropped(l, how(), last_stop_sample(3));
}

// A telegram whose first character's stop sample comes after the write is not a new request
// (docs/timing.md "Go_Offline"). MinTSDR_Val = 255 (written before Start) holds the answer back:
// it starts 255 T after the request's end, at s + 396 + 1020 = s + 1416, and ends at s + 1416 +
// 264 = s + 1680. A second FDL_Status TSYN after the first one's end (s + 396 + 33 T = s + 528,
// ending at s + 792) is heard while the Offline waits for the answer: counted offline, not
// served (no second answer, the answer armed is sent at its cycles), Offline at s + 1680.
TEST_P(OfflineAfterRequest, ATelegramAfterTheWriteIsNotANewRequest) {
  Line l(GetParam().profile, GetParam().engine, 255);
  l.offline_at(420, how());  // the answer armed, not yet on the line
  l.chip.drive_rxd_chars(kRequest, l.s + 528, kT);
  l.step_to(1679);
  EXPECT_TRUE(l.chip.started());
  EXPECT_EQ(l.chip.fdl_counters().offline, 1u);
  l.step_to(1680);
  EXPECT_FALSE(l.chip.started());
  EXPECT_TRUE(l.mac_reset());
  l.step_to(3000);
  Edges e;
  uart_encode(kAnswer, l.s + 1416, kT, e);
  EXPECT_EQ(l.txd, e);
}

// A snapshot taken while the Offline waits carries it (format version 5): the restored chip goes
// Offline at the same cycle.
TEST_P(OfflineAfterRequest, ThePendingOfflineSurvivesASnapshot) {
  Line l = line();
  l.offline_at(500, how());
  Line m = line();
  m.chip.load_state(l.chip.save_state());
  m.txd = l.txd;
  EXPECT_TRUE(m.chip.started());
  expect_offline_at_answer_end(m);
}

namespace {

std::vector<Param> params() {
  std::vector<Param> v;
  for (Profile p : {Profile::spc3, Profile::vpc3plus}) {
    for (Engine e : {Engine::event, Engine::per_cycle}) {
      for (How h : {How::go_offline, How::violation}) v.push_back({p, e, h});
    }
  }
  return v;
}

}  // namespace

INSTANTIATE_TEST_SUITE_P(Chips, OfflineAfterRequest, ::testing::ValuesIn(params()),
                         [](const ::testing::TestParamInfo<Param>& i) {
                           return testutil::pname(i.param.profile) +
                                  (i.param.engine == Engine::event ? "_event" : "_per_cycle") +
                                  (i.param.how == How::go_offline ? "_go_offline" : "_violation");
                         });

// The DPC31's MAC_Stop has no "after the current request" (Table 5.1-3: "MAC enters Offline"),
// and its confirmation 11h / 00h is in the Indication_Queue at once: Offline at the completion
// cycle of the InstQ_Wr write even while a request is received (docs/decisions.md).
TEST(OfflineDpc31, MacStopActsAtOnceDuringARequest) {
  for (Engine e : {Engine::event, Engine::per_cycle}) {
    SCOPED_TRACE(static_cast<int>(e));
    Chip c(ChipOptions{Profile::dpc31, BusMode::intel, 0, e});
    c.set_log_sink(nullptr);
    const std::uint64_t s = testutil::user_start(c);
    c.drive_rxd_chars(kRequest, s + kRequestAt, kT);
    c.step(s + 300 - c.cycle());  // inside the request (first stop sample at s + 174)
    const std::uint64_t done = testutil::user_go_offline(c);
    EXPECT_FALSE(c.started());
    EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
    EXPECT_LT(done, s + 396);
  }
}

// The chip's own RAM access violation while it serves a request waits for that request's end
// like the user's (IRR MAC_Reset "after finishing the current request (Go_Offline or RAM access
// violation)"). SPC3 with DP_Mode: R_Read_Cfg_Buf_Ptr C0h puts the Read_Cfg buffer at C0h x 8 =
// 600h, the first address past the 1.5 kB RAM, read back at 600h - 400h = 200h (chip-facts.md),
// where the test wrote 11h 22h; R_Len_Read_Cfg_Data 2. Get_Cfg to station 5 (SRD_high 4Dh, DSAP
// 59 = 3Bh, SSAP 62 = 3Eh): 68 05 05 68 85 82 4D 3B 3E CD 16, FCS 85 + 82 + 4D + 3B + 3E = CDh,
// 11 characters from r: acted on at its last stop sample r + 10 x 44 + 42 = r + 482 (the
// violation then), ended at r + 484. The answer DL from station 5, 68 07 07 68 82 85 08 3E 3B 11
// 22 BB 16 (FCS 82 + 85 + 08 + 3E + 3B + 11 + 22 = BBh), starts MinTSDR = 11 T later at r + 528
// and ends 13 x 44 later at r + 1100: Offline there, the answer whole.
// `heard`: the event engine's telegram heard whole (Chip::hear_telegram, outside Baud_Search: the
// FDL_Status of the file's header ends it first, answered by s + 704), at r = s + 1000; else
// driven as characters at r = s + 132.
void expect_asic_violation_waits(Engine e, bool heard) {
  Chip c(ChipOptions{Profile::spc3, BusMode::intel, 0, e});
  c.set_log_sink(nullptr);
  Edges txd;
  c.on_txd([&txd](std::uint64_t cycle, bool l) { txd.emplace_back(cycle, l); });
  c.write(0x07, 0x01);  // Mode_Reg0 bit 8 DP_Mode: the DP SAPs (Get_Cfg) set up
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::R_TS_Adr)), 5);
  const std::uint64_t s = testutil::user_start(c);
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::R_Read_Cfg_Buf_Ptr)), 0xC0);
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::R_Len_Read_Cfg_Data)), 2);
  c.write(0x200, 0x11);
  c.write(0x201, 0x22);
  const std::vector<std::uint8_t> get_cfg = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82,
                                             0x4D, 0x3B, 0x3E, 0xCD, 0x16};
  std::uint64_t r = s + kRequestAt;
  if (heard) {
    c.drive_rxd_chars(kRequest, r, kT);
    r = s + 1000;
    c.step(r - c.cycle());
    txd.clear();
    c.hear_telegram(get_cfg, r, kT);
  } else {
    c.drive_rxd_chars(get_cfg, r, kT);
  }
  c.step(r + 482 - c.cycle());
  EXPECT_NE(c.read(0x04) & 0x08, 0);  // Status bit 3: the violation happened
  c.step(r + 1099 - c.cycle());
  EXPECT_TRUE(c.started());
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
  c.step(1);
  EXPECT_FALSE(c.started());
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
  c.step(2000);
  Edges want;
  uart_encode(std::vector<std::uint8_t>{0x68, 0x07, 0x07, 0x68, 0x82, 0x85, 0x08, 0x3E, 0x3B, 0x11,
                                        0x22, 0xBB, 0x16},
              r + 528, kT, want);
  EXPECT_EQ(txd, want);
}

TEST(OfflineAsicViolation, WaitsForTheAnswer) {
  for (Engine e : {Engine::event, Engine::per_cycle}) {
    SCOPED_TRACE(static_cast<int>(e));
    expect_asic_violation_waits(e, false);
  }
}

TEST(OfflineAsicViolation, WaitsForTheAnswerToATelegramHeardWhole) {
  expect_asic_violation_waits(Engine::event, true);
}

}  // namespace offline_test
