// The protocol engine end to end: the built-in master on RxD/TxD, the chip, the minimal user
// side. Cycles are derived from docs/timing.md: T = round(48 MHz / baud); a request is acted on
// at the stop sample of its last character (end - T + T/2); the answer starts MinTSDR = 11 bit
// times after the request's end; the master keeps 33 idle bits (TSYN) before each request and
// waits a slot time of 100 bits; Baud_Search listens max(4096 bit times, 20 ms) per rate, 12 M
// first (tests/baud_search.hpp).
// Telegram bytes and FCS are worked out by hand.
#include <gtest/gtest.h>

#include <numeric>
#include <utility>

#include "baud_search.hpp"
#include "dp_master.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/reg_ids.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "test_util.hpp"

using namespace dpc31;
using Bytes = std::vector<std::uint8_t>;

namespace {

std::uint32_t T_of(std::uint32_t baud) {
  return static_cast<std::uint32_t>((48'000'000u + baud / 2) / baud);
}

struct Bench {
  Chip chip;
  Responder user;
  DpMaster master;
  std::uint64_t start;  // the cycle Start_SPC3 completed

  Bench(Profile p, std::uint32_t baud, ResponderConfig rc = {}, BusMode bus = BusMode::intel)
      : chip({p, bus, 0}),
        user(prepare(rc)),
        master(init(chip, user, rc.slave.in_len), MasterConfig{2, baud, 100, 33}, rc.slave),
        start(chip.cycle()) {
    master.set_firmware([this](BusPort& c) { user.isr(c); });
  }
  static ResponderConfig prepare(ResponderConfig rc) { return rc; }
  // The inputs A1, A2, ... of the slave's length (A1..A4 by default).
  static Chip& init(Chip& c, Responder& u, std::size_t in_len) {
    c.set_log_sink(nullptr);
    Bytes in(in_len);
    for (std::size_t i = 0; i < in_len; ++i) in[i] = static_cast<std::uint8_t>(0xA1 + i);
    u.set_inputs(std::move(in));
    DirectBus bus(c);
    u.init(bus);
    return c;
  }
  std::uint32_t T() const { return master.bit_cycles(); }
  // The cycle a request is acted on: the stop-bit sample of its last character.
  std::uint64_t acted(const Exchange& ex) const { return ex.request_end - T() + T() / 2; }
};

Bytes wire(const std::optional<fdl::Frame>& f) { return f ? fdl::encode(*f) : Bytes{}; }

}  // namespace

class Startup : public ::testing::TestWithParam<std::tuple<Profile, std::uint32_t>> {};

TEST_P(Startup, ReachesDataExchangeAtExactCycles) {
  const auto [profile, baud] = GetParam();
  Bench b(profile, baud);
  const std::uint64_t t = b.T();
  ASSERT_EQ(t, T_of(baud));
  ASSERT_TRUE(b.master.startup());
  const auto& h = b.master.history();

  // Baud_Search: the window of the searched rate opens after the windows of the faster rates.
  std::size_t rate = 0;
  while (kBaudRates[rate] != baud) ++rate;
  const std::uint64_t window = b.start + testutil::baud_search_opens(baud);
  // Unanswered FDL_Status requests repeat every 6*11 + 100 + 33 = 199 bit times; the first one
  // starting TSYN after the window opens is heard.
  std::size_t first = 0;
  while (b.start + 33 * t + first * 199 * t < window + 33 * t) ++first;
  ASSERT_GT(h.size(), first + 4);
  for (std::size_t k = 0; k < first; ++k) {
    EXPECT_FALSE(h[k].answer) << k;
    EXPECT_EQ(h[k].request_start, b.start + 33 * t + k * 199 * t) << k;
  }
  const Bytes kFdlStatusAnswer = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};
  const Bytes kDiagPrmReq = {0x68, 0x0B, 0x0B, 0x68, 0x82, 0x85, 0x08, 0x3E, 0x3C,
                             0x02, 0x05, 0x00, 0xFF, 0x0C, 0x31, 0xCC, 0x16};
  const Bytes kDiagReady = {0x68, 0x0B, 0x0B, 0x68, 0x82, 0x85, 0x08, 0x3E, 0x3C,
                            0x00, 0x0C, 0x00, 0x02, 0x0C, 0x31, 0xD4, 0x16};
  const std::vector<std::pair<std::size_t, Bytes>> expected = {
      {6, kFdlStatusAnswer},  // FDL_Status
      {11, kDiagPrmReq},      // Slave_Diag: Station_Not_Ready, Prm_Req
      {19, {0xE5}},           // Set_Prm (8 bytes)
      {13, {0xE5}},           // Chk_Cfg (2 bytes)
      {11, kDiagReady},       // Slave_Diag: ready, WD_On, locked by master 2
  };
  ASSERT_EQ(h.size(), first + expected.size());
  std::uint64_t next = b.start + 33 * t + first * 199 * t;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const Exchange& ex = h[first + k];
    SCOPED_TRACE(k);
    EXPECT_EQ(ex.request_start, next);
    EXPECT_EQ(ex.request_end, ex.request_start + expected[k].first * 11 * t);
    EXPECT_EQ(wire(ex.answer), expected[k].second);
    EXPECT_EQ(ex.answer_start, ex.request_end + 11 * t);
    EXPECT_EQ(ex.answer_end, ex.answer_start + expected[k].second.size() * 11 * t);
    next = ex.answer_end + 33 * t;
  }
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  EXPECT_EQ((b.chip.peek_reg(RegId::Status_Reg) >> 8) & 0x0F, rate);  // the baud code

  // One Data_Exchange: 4 outputs in, the user's 4 inputs back (FCS 02+05+08+A1..A4 = 99h).
  const Exchange dx = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(dx.request_start, next);
  EXPECT_EQ(wire(dx.answer),
            (Bytes{0x68, 0x07, 0x07, 0x68, 0x02, 0x05, 0x08, 0xA1, 0xA2, 0xA3, 0xA4, 0x99, 0x16}));
  EXPECT_EQ(dx.answer_start, dx.request_end + 11 * t);
  ASSERT_FALSE(b.user.outputs.empty());
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x01, 0x02, 0x03, 0x04}));
  EXPECT_FALSE(b.user.outputs.back().cleared);
}

INSTANTIATE_TEST_SUITE_P(ProfilesAndBaudRates, Startup,
                         ::testing::Combine(::testing::ValuesIn(kAllProfiles),
                                            ::testing::Values(9600u, 187500u, 1500000u, 12000000u)),
                         testutil::profile_rate_name);

// A request handed to RxD before a Baud_Search window switch that it reaches into is heard at the
// new rate: the edges wait in the chip, not in the receiver that the switch reconfigures.
// A started dpc31 (the responder's init) on the engine of the parameter, its log off.
class AheadOfTime : public ::testing::TestWithParam<Engine> {
 protected:
  Chip chip{{Profile::dpc31, BusMode::intel, 0, GetParam()}};
  Responder user{ResponderConfig{}};
  DirectBus bus{chip};
  void SetUp() override {
    chip.set_log_sink(nullptr);
    user.init(bus);
  }
};

TEST_P(AheadOfTime, RequestDrivenBeforeAWindowSwitchIsHeardAtTheNewRate) {
  const std::uint64_t s = chip.cycle();  // Start_SPC3 completed: the 12 Mbaud window opens
  const std::uint64_t t = 8;             // 6 Mbaud
  const std::uint64_t window = s + testutil::baud_search_window(12'000'000);  // 20 ms
  std::vector<std::pair<std::uint64_t, bool>> txd;
  chip.on_txd([&](std::uint64_t c, bool l) { txd.emplace_back(c, l); });
  // FDL_Status 5 <- 2 (FCS 05+02+49 = 50h), starting TSYN after the 6 Mbaud window opens, handed
  // over now, at 12 Mbaud.
  const Bytes req = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  const std::uint64_t start = window + 33 * t;
  const std::uint64_t end = send_on_rxd(chip, req, start, t);
  ASSERT_EQ(end, start + 6 * 11 * t);
  // Acted on at the last stop sample: the rate is found (Baud_Control, baud code 1 = 6 Mbaud).
  chip.step(end - t + t / 2 - 1 - chip.cycle());
  EXPECT_EQ(chip.wd_state(), WdState::Baud_Search);
  chip.step(1);
  EXPECT_EQ(chip.wd_state(), WdState::Baud_Control);
  EXPECT_EQ((chip.peek_reg(RegId::Status_Reg) >> 8) & 0x0F, 1);
  chip.step(end + 11 * t + 6 * 11 * t - chip.cycle());
  // The answer 10 02 05 00 07 16 starts MinTSDR = 11 bit times after the request's end.
  ASSERT_FALSE(txd.empty());
  EXPECT_EQ(txd.front(), std::make_pair(end + 11 * t, false));
  EXPECT_EQ(chip.fdl_counters().requests, 1u);
}

// A gap inside a telegram ends it only when it reaches TSYN = 33 bit times: a character that
// starts after 30 bit times continues it, although its stop sample comes 40.5 bit times after
// the previous character's end.
TEST_P(AheadOfTime, CharacterStartedBeforeTsynContinuesTheTelegram) {
  const std::uint64_t t = 4;  // 12 Mbaud: the first Baud_Search window
  std::vector<std::pair<std::uint64_t, bool>> txd;
  chip.on_txd([&](std::uint64_t c, bool l) { txd.emplace_back(c, l); });
  // FDL_Status 5 <- 2 (10 05 02 49 50 16), the ED 30 bit times after the FCS.
  const std::uint64_t head_end =
      send_on_rxd(chip, Bytes{0x10, 0x05, 0x02, 0x49, 0x50}, chip.cycle() + 33 * t, t);
  const std::uint64_t end = send_on_rxd(chip, Bytes{0x16}, head_end + 30 * t, t);
  chip.step(end + 11 * t + 1 - chip.cycle());
  EXPECT_EQ(chip.fdl_counters().truncated, 0u);
  EXPECT_EQ(chip.fdl_counters().no_sync, 0u);
  ASSERT_FALSE(txd.empty());
  EXPECT_EQ(txd.front(), std::make_pair(end + 11 * t, false));  // answered after MinTSDR
}

INSTANTIATE_TEST_SUITE_P(Engines, AheadOfTime, ::testing::Values(Engine::event, Engine::per_cycle),
                         [](const auto& i) {
                           return std::string(i.param == Engine::event ? "event" : "per_cycle");
                         });

// With nobody watching TxD bit by bit, the event engine takes the answer's bits without an event
// each (docs/engine.md); the pin, interrupts and telegrams are the same as with a watcher.
TEST(TxdFastPath, UnwatchedAnswerCostsNoEventPerBitAndLooksTheSame) {
  struct Run {
    Chip chip{{Profile::dpc31, BusMode::intel, 0}};
    std::vector<std::pair<std::uint64_t, bool>> irq;
    std::vector<std::uint64_t> telegrams;
    std::vector<bool> pin;                             // TxD at every cycle of the answer
    std::vector<std::vector<std::uint8_t>> snapshots;  // at some cycles inside the answer
    std::size_t events = 0;
  };
  auto play = [](Run& r, bool watch_txd) {
    r.chip.set_log_sink(nullptr);
    Responder user(ResponderConfig{});
    DirectBus bus(r.chip);
    user.init(bus);
    r.chip.on_irq_change([&r](std::uint64_t c, bool a) { r.irq.emplace_back(c, a); });
    r.chip.on_telegram([&r](const Telegram& t) { r.telegrams.push_back(t.start); });
    r.chip.on_state_change([&r](std::uint64_t) { ++r.events; });
    if (watch_txd) r.chip.on_txd([](std::uint64_t, bool) {});
    const std::uint64_t t = 4;  // 12 Mbaud, the first Baud_Search window
    const std::uint64_t start = r.chip.cycle() + 33 * t;
    const Bytes req = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};  // FDL_Status 5 <- 2
    const std::uint64_t end = send_on_rxd(r.chip, req, start, t);
    const std::uint64_t answer = end + 11 * t;  // 10 02 05 00 07 16: 6 characters
    r.chip.step(answer - r.chip.cycle());
    const std::size_t before = r.events;
    for (std::uint64_t c = 0; c < 6 * 11 * t; ++c) {
      r.pin.push_back(r.chip.txd_pin());
      // Unwatched, the answer is kept as characters: a snapshot writes the edges they stand for.
      if (c % 17 == 3) r.snapshots.push_back(r.chip.save_state());
      r.chip.step(1);
    }
    r.events -= before;  // events inside the answer
  };
  Run watched;
  Run unwatched;
  play(watched, true);
  play(unwatched, false);
  EXPECT_EQ(unwatched.pin, watched.pin);
  EXPECT_EQ(unwatched.snapshots, watched.snapshots);
  EXPECT_EQ(unwatched.irq, watched.irq);
  EXPECT_EQ(unwatched.telegrams, watched.telegrams);
  EXPECT_EQ(unwatched.chip.save_state(), watched.chip.save_state());
  // 10 02 05 00 07 16 changes TxD 4 + 4 + 6 + 2 + 4 + 6 = 26 times; the first, at the answer's
  // start, is before the counted cycles, the end of the answer is one more event. Unwatched,
  // only the end of the answer is an event.
  EXPECT_EQ(watched.events, 26u);
  EXPECT_EQ(unwatched.events, 1u);
}

// Chip::on_answer (what a segment learns its stations' answers from): each answer the chip arms,
// when it arms it, as on_telegram reports it; none of the frames it hears.
TEST(ChipAnswers, OnAnswerReportsTheArmedAnswerAndNoFrameHeard) {
  Chip chip({Profile::dpc31, BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  Responder user(ResponderConfig{});
  DirectBus bus(chip);
  user.init(bus);
  std::vector<Telegram> answers, own;  // on_answer's, on_telegram's from the chip
  std::size_t heard = 0;
  std::uint64_t armed_at = 0;
  chip.on_answer([&](const Telegram& t) {
    answers.push_back(t);
    armed_at = chip.cycle();
  });
  chip.on_telegram([&](const Telegram& t) { t.from_chip ? own.push_back(t) : void(++heard); });
  const std::uint64_t t = 4;  // 12 Mbaud, the first Baud_Search window
  // A request to another station (9): heard, counted foreign, not answered.
  std::uint64_t end =
      send_on_rxd(chip, Bytes{0x10, 0x09, 0x02, 0x49, 0x54, 0x16}, chip.cycle() + 33 * t, t);
  chip.step(end + 100 * t - chip.cycle());
  EXPECT_TRUE(answers.empty());
  // FDL_Status 5 <- 2: armed at the stop sample of its last character (docs/timing.md), sent
  // min TSDR = 11 bit times after its end, 6 characters of 11 bits.
  end = send_on_rxd(chip, Bytes{0x10, 0x05, 0x02, 0x49, 0x50, 0x16}, chip.cycle() + 33 * t, t);
  chip.step(end + 100 * t - chip.cycle());
  EXPECT_EQ(heard, 2u);
  ASSERT_EQ(answers.size(), 1u);
  ASSERT_EQ(own.size(), 1u);
  EXPECT_TRUE(answers[0].from_chip);
  EXPECT_EQ(answers[0].bytes, own[0].bytes);
  EXPECT_EQ(answers[0].bytes, (Bytes{0x10, 0x02, 0x05, 0x00, 0x07, 0x16}));
  EXPECT_EQ(answers[0].start, end + 11 * t);
  EXPECT_EQ(answers[0].end, end + 11 * t + 6 * 11 * t);
  EXPECT_EQ(armed_at, end - t + t / 2);  // the middle of the last stop bit
}

class Protocol : public ::testing::TestWithParam<Profile> {
 protected:
  static ResponderConfig config() {
    ResponderConfig rc;
    rc.substitute = {0x5A, 0x5B, 0x5C, 0x5D};
    return rc;
  }
};

class ProtocolSpcVpc : public Protocol {};

TEST_P(Protocol, MaximumDataLengthsRoundTrip) {
  if (GetParam() == Profile::spc3) {
    // 3 x 244 output + 3 x 244 input buffers need 1464 of the SPC3's 1472 user bytes: no room
    // for the Prm, Cfg, Aux and diag buffers (docs/decisions.md).
    return;
  }
  ResponderConfig rc = config();
  rc.slave.in_len = 244;
  rc.slave.out_len = 244;
  rc.substitute.assign(244, 0x5A);  // the clear buffer C is out_len bytes too
  rc.slave.cfg = {0xC0, 0xBC, 0xBC, 0xC0, 0xBC, 0xBC,
                  0xC0, 0xBC, 0xBC, 0xC0, 0xBC, 0xBC};  // 4 x 61
  Bytes in(244), out(244);
  for (std::size_t i = 0; i < 244; ++i) {
    in[i] = static_cast<std::uint8_t>(i * 7 + 3);
    out[i] = static_cast<std::uint8_t>(255 - i);
  }
  Bench b(GetParam(), 12'000'000, rc);
  b.user.set_inputs(in);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange(out);  // the first answer carries the inputs given at init
  b.user.set_inputs(in);
  const Exchange dx = b.master.data_exchange(out);
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(dx.answer->du, in);
  EXPECT_EQ(dx.request_end - dx.request_start, (244u + 9u) * 11 * 4);  // LE = 247
  EXPECT_EQ(dx.answer_start, dx.request_end + 11 * 4);
  EXPECT_EQ(b.user.outputs.back().data, out);
}

TEST_P(Protocol, GlobalControlSyncHoldsOutputsUntilUnsync) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({1, 1, 1, 1});
  const std::size_t before = b.user.outputs.size();
  b.master.global_control(
      0x20);  // Sync: what D holds goes to N now (DX_Out), later data stays in D
  b.master.idle(2000);
  EXPECT_EQ(b.chip.peek(b.chip.addr_of(RegId::R_GC_Command)), 0x20);
  b.master.data_exchange({2, 2, 2, 2});
  b.master.data_exchange({3, 3, 3, 3});
  // D held nothing new at the Sync (1,1,1,1 was already handed over); later data stays in D.
  EXPECT_EQ(b.user.outputs.size(), before);
  b.master.global_control(0x20);  // the next Sync delivers the newest outputs
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{3, 3, 3, 3}));
  b.master.data_exchange({4, 4, 4, 4});
  b.master.global_control(0x10);  // Unsync: hands over D and ends the Sync mode
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{4, 4, 4, 4}));
  b.master.data_exchange({5, 5, 5, 5});
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{5, 5, 5, 5}));
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[1] & 0x20, 0);  // Sync_Mode off again
}

TEST_P(Protocol, GlobalControlFreezeHoldsInputsUntilUnfreeze) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0, 0, 0, 0});
  b.master.global_control(0x08);  // Freeze: the newest inputs (A1..A4) are taken and frozen
  b.user.set_inputs({0xB1, 0xB2, 0xB3, 0xB4});
  b.master.data_exchange({0, 0, 0, 0});  // the user hands B1.. over on this DX_Out
  Exchange dx = b.master.data_exchange({0, 0, 0, 0});
  EXPECT_EQ(dx.answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
  const Exchange diag = b.master.slave_diag();
  EXPECT_NE(diag.answer->du[1] & 0x10, 0);  // Freeze_Mode
  b.master.global_control(0x04);            // Unfreeze: N -> D, inputs flow again
  dx = b.master.data_exchange({0, 0, 0, 0});
  EXPECT_EQ(dx.answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
}

TEST_P(Protocol, GlobalControlClearData) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({9, 9, 9, 9});
  b.master.global_control(0x02);
  b.master.idle(2000);  // the user's ISR fetches on DX_Out
  ASSERT_FALSE(b.user.outputs.empty());
  const Responder::Output& o = b.user.outputs.back();
  EXPECT_TRUE(o.cleared);
  // SPC3 / VPC3+: D is cleared and passed on. DPC31: the C buffer with the substitute values.
  EXPECT_EQ(o.data,
            GetParam() == Profile::dpc31 ? (Bytes{0x5A, 0x5B, 0x5C, 0x5D}) : (Bytes{0, 0, 0, 0}));
  EXPECT_EQ(b.chip.peek(static_cast<std::uint32_t>(b.chip.addr_of(RegId::R_GC_Command))), 0x02);
}

TEST_P(Protocol, FailsafeDataExchangeWithoutOutputs) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({7, 7, 7, 7});
  const Exchange dx = b.master.data_exchange({});  // Spec_Clear_Mode: accepted with 0 bytes
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(dx.answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));  // inputs keep being fetched
  const Responder::Output& o = b.user.outputs.back();
  EXPECT_TRUE(o.cleared);
  EXPECT_EQ(o.data,
            GetParam() == Profile::dpc31 ? (Bytes{0x5A, 0x5B, 0x5C, 0x5D}) : (Bytes{0, 0, 0, 0}));
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

// The built-in user side without substitute values: every clear hands the user 00h, as the
// SPC3 and VPC3+ clear D. On the dpc31 the first C fetch leaves the old U buffer (outputs 01..04)
// in the new C; the responder zeroes it, so the second clear does not hand old outputs over as
// substitute values (they came back as 01 02 03 04, flagged cleared).
TEST_P(Protocol, WithoutSubstituteValuesEveryClearHandsOverZeros) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  for (const std::uint8_t first : {0x01, 0x11}) {
    SCOPED_TRACE(int(first));
    b.master.data_exchange({first, static_cast<std::uint8_t>(first + 1),
                            static_cast<std::uint8_t>(first + 2),
                            static_cast<std::uint8_t>(first + 3)});
    b.master.idle(2000);
    ASSERT_EQ(b.user.outputs.back().data[0], first);
    b.master.global_control(0x02);
    b.master.idle(2000);  // the user's ISR fetches on DX_Out
    EXPECT_TRUE(b.user.outputs.back().cleared);
    EXPECT_EQ(b.user.outputs.back().data, (Bytes{0, 0, 0, 0}));
    b.master.global_control(0x00);  // Operate: the next outputs end the clear
  }
}

TEST_P(Protocol, GlobalControlReservedBitGivesNotSupportedAndWaitPrm) {
  for (std::uint8_t bad : {std::uint8_t{0x01}, std::uint8_t{0x40}, std::uint8_t{0x80}}) {
    Bench b(GetParam(), 12'000'000, config());
    ASSERT_TRUE(b.master.startup());
    b.master.global_control(bad);
    EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm) << int(bad);
    const Exchange diag = b.master.slave_diag();
    ASSERT_TRUE(diag.answer);
    EXPECT_EQ(diag.answer->du[0], 0x02 | 0x10) << int(bad);  // Station_Not_Ready, Not_Supported
    EXPECT_EQ(diag.answer->du[3], 0xFF);                     // unlocked
  }
}

TEST_P(Protocol, SyncWithoutSupportIsTreatedLikeAReservedBit) {
  ResponderConfig rc = config();
  rc.sync_supported = false;
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(0x20);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_NE(b.master.slave_diag().answer->du[0] & 0x10, 0);
}

TEST_P(Protocol, NewGcCommandOnAChangedCommandByteOrVpc3plusEveryOne) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  const auto gc_interrupts = [&] {
    std::size_t n = 0;
    for (const auto& [cycle, ir] : b.user.interrupts) n += (ir & irq::New_GC_Command) != 0 ? 1 : 0;
    return n;
  };
  b.master.global_control(0x08);
  b.master.global_control(0x08);
  b.master.global_control(0x04);
  b.master.idle(2000);
  // VPC3+: GC_Int_Mode = 1 is the default (VPC3+C p.50): every Global_Control interrupts.
  EXPECT_EQ(gc_interrupts(), GetParam() == Profile::vpc3plus ? 3u : 2u);
  EXPECT_EQ(b.chip.peek(b.chip.addr_of(RegId::R_GC_Command)), 0x04);
  b.master.global_control(0x08, 0x02);  // Group_Select 2, our Group_Ident 0: not for us
  EXPECT_EQ(b.chip.peek(b.chip.addr_of(RegId::R_GC_Command)), 0x04);
}

TEST_P(Protocol, DpWatchdogExpiresAtTheExactCycle) {
  Bench b(GetParam(), 12'000'000, config());  // WD 10 x 10 x 10 ms = 1 s
  ASSERT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({6, 6, 6, 6});
  const std::uint64_t expiry = b.acted(dx) + 48'000'000;
  b.master.idle(expiry - 1 - b.chip.cycle());  // cable pulled
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  b.chip.step(1);
  EXPECT_EQ(b.chip.cycle(), expiry);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
  EXPECT_NE(b.chip.peek_reg(RegId::Int_Req_Reg) & irq::WD_DP_Control_Timeout, 0u);
  EXPECT_NE(b.chip.peek_reg(RegId::Int_Req_Reg) & irq::Go_Leave_Data_Exchange, 0u);
  b.master.idle(1000);  // the user fetches the outputs the ASIC cleared
  EXPECT_TRUE(b.user.outputs.back().cleared);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0, 0, 0, 0}));
}

// A write to WD_Baud_Control_Val in the cycle the watchdog starts Baud_Control (docs/timing.md,
// "Order within one cycle": the protocol side and the watchdog's deadline, steps 2 and 3, come
// before a bus access completing in that cycle, step 5; "Baud_Control": WD_Baud_Control_Val x 10
// ms, x 2 on the VPC3+, taken at each (re)start). The responder wrote 10h (160 ms); the test
// writes 01h completing at the DP watchdog's expiry, 02h completing at the cycle the baud search
// finds the rate again. Each start takes the value from before that cycle's write; the next one
// takes the written value: 160, 10, then 20 ms (x 2 on the VPC3+).
TEST_P(Protocol, WdBaudControlWriteInTheCycleOfItsStartActsFromTheNextStart) {
  Bench b(GetParam(), 12'000'000, config());  // WD 10 x 10 x 10 ms = 1 s
  const std::uint64_t ms = (GetParam() == Profile::vpc3plus ? 2u : 1u) * 48'000u;
  // A write-only register: its write side (Chip::addr_of).
  const auto addr = static_cast<std::uint32_t>(b.chip.addr_of(RegId::WD_Baud_Control_Val));
  DirectBus bus(b.chip);
  // A bus write of `v` that completes at cycle `c` (an access takes 4 clocks, docs/timing.md).
  const auto write_at = [&](std::uint64_t c, std::uint8_t v) {
    b.chip.step(c - 4 - b.chip.cycle());
    bus.write(addr, v);
    ASSERT_EQ(b.chip.cycle(), c);
  };
  // Baud_Control runs from `from` for exactly `len` clocks, then Baud_Search.
  const auto baud_control = [&](std::uint64_t from, std::uint64_t len) {
    EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
    b.chip.step(from + len - 1 - b.chip.cycle());
    EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
    b.chip.step(1);
    EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Search);
  };
  // FDL_Status 5 <- 2 TSYN into the 12 Mbaud window that opens at `window` (T = 4): acted on at
  // its last stop sample, end - 2, where the rate is found and Baud_Control starts.
  const auto find_rate = [&](std::uint64_t window) {
    const Bytes req = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    return send_on_rxd(b.chip, req, window + 33 * 4, 4) - 2;
  };
  ASSERT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({6, 6, 6, 6});
  const std::uint64_t expiry = b.acted(dx) + 48'000'000;
  b.master.idle(expiry - 4 - b.chip.cycle());
  write_at(expiry, 0x01);
  baud_control(expiry, 160 * ms);
  const std::uint64_t found = find_rate(expiry + 160 * ms);
  write_at(found, 0x02);
  baud_control(found, 10 * ms);
  const std::uint64_t again = find_rate(found + 10 * ms);
  b.chip.step(again - b.chip.cycle());
  baud_control(again, 20 * ms);
}

TEST_P(Protocol, DpWatchdogWith1msBase) {
  ResponderConfig rc = config();
  rc.slave.wd_base_1ms = true;
  rc.slave.wd_fact1 = 5;
  rc.slave.wd_fact2 = 7;                        // 35 ms
  if (GetParam() == Profile::vpc3plus) return;  // VPC3+ takes the base from Mode_Reg0.WD_Base
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({6, 6, 6, 6});
  b.master.idle(b.acted(dx) + 35 * 48'000 - 1 - b.chip.cycle());
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  b.chip.step(1);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
}

TEST_P(Protocol, WatchdogOffKeepsDataExchangeThroughASilentBus) {
  ResponderConfig rc = config();
  rc.slave.wd_on = false;
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
  b.master.idle(2 * 48'000'000);  // 2 s of silence: Baud_Control runs out, DP stays
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Search);
  // Baud_Control (16 x 10 ms, x 2 on the VPC3+) ran out after the last telegram to us; from
  // there the search cycles through all ten windows, 12 M first (one round: kBaudSearchRound).
  const std::uint64_t baud_control = (GetParam() == Profile::vpc3plus ? 320u : 160u) * 48'000u;
  std::uint64_t window = b.acted(b.master.history().back()) + baud_control;
  while (window + 33 * 4 < b.chip.cycle()) window += testutil::kBaudSearchRound;
  b.master.idle(window + 33 * 4 - b.chip.cycle());  // the first request TSYN into the window
  const Exchange dx = b.master.data_exchange({8, 8, 8, 8});
  EXPECT_EQ(dx.request_start, window + 33 * 4);
  EXPECT_TRUE(dx.answer);  // found the baud rate again, still in Data_Exchange
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{8, 8, 8, 8}));
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
}

// The SPC3's and the VPC3+'s user watchdog counts Data_Exchange telegrams; the DPC31's runs on
// 10 ms through its request interface (Dpc31Requests.*, docs/dpc31.md).
TEST_P(ProtocolSpcVpc, UserWatchdogExpires) {
  ResponderConfig rc = config();
  rc.user_wd_value = 3;  // Res_User_WD only at init: three Data_Exchanges, then Leave_Master
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  EXPECT_TRUE(b.master.data_exchange({1, 1, 1, 1}).answer);    // loads 3
  EXPECT_TRUE(b.master.data_exchange({1, 1, 1, 1}).answer);    // 2
  EXPECT_TRUE(b.master.data_exchange({1, 1, 1, 1}).answer);    // 1
  const Exchange last = b.master.data_exchange({1, 1, 1, 1});  // 0: expired
  EXPECT_FALSE(last.answer);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
}

// R_User_WD_Value = 0 acts as 1 (docs/timing.md, "user watchdog"; docs/decisions.md, "The
// twenty-ninth session: s29-chip"): the Data_Exchange after the reload counts down from 0, stays
// at 0 and is not answered, as the one that counts 1 down to 0: the station leaves at the 2nd.
TEST_P(ProtocolSpcVpc, UserWatchdogValueZeroActsAsOne) {
  for (const std::uint16_t value : {0, 1}) {
    SCOPED_TRACE(value);
    ResponderConfig rc = config();
    rc.user_wd_value = value;
    Bench b(GetParam(), 12'000'000, rc);
    ASSERT_TRUE(b.master.startup());
    EXPECT_TRUE(b.master.data_exchange({1, 1, 1, 1}).answer);   // loads the value
    EXPECT_FALSE(b.master.data_exchange({1, 1, 1, 1}).answer);  // 0: expired
    EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  }
}

// A Set_Prm with WD_Fact_1 = 0 and WD_On = 1 (a raw telegram: every door of ours refuses factor
// 0): the chip does not check it (seed 002: "The circuit does not check this setting"), the user
// accepts it, and TWD = 0 x 10 x 10 ms = 0 clocks, so the DP watchdog expires in the very cycle the
// User_Prm_Data_Okay read completes: WD_DP_Control_Timeout, Baud_Control, Leave_Master (Wait_Prm)
// all in that cycle (docs/timing.md, "DP watchdog").
TEST_P(Protocol, WdFactorZeroExpiresAtTheOkay) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  b.master.set_firmware([](BusPort&) {});  // the test is the user side from here
  b.master.slave().wd_fact1 = 0;
  const Exchange prm = b.master.set_prm();
  EXPECT_EQ(wire(prm.answer), Bytes{0xE5});
  b.master.idle(1000);
  ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  ASSERT_EQ(b.chip.wd_state(), WdState::DP_Control);  // the old TWD still runs
  const int irr = b.chip.addr_of(RegId::Int_Req_Reg);
  testutil::bus_write16(b.chip, irr, 16, 0x0000);  // the user clears what it saw
  ASSERT_EQ(b.chip.peek_reg(RegId::Int_Req_Reg) & irq::WD_DP_Control_Timeout, 0u);
  testutil::LogCapture log;
  log.attach(b.chip);
  DirectBus bus(b.chip);
  EXPECT_EQ(bus.read(static_cast<std::uint32_t>(b.chip.addr_of(RegId::User_Prm_Data_Okay))),
            0x00);  // accepted: Wait_Cfg, DP_Control with TWD 0, due now
  const std::uint64_t okay = b.chip.cycle();
  b.chip.step(1);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
  EXPECT_NE(b.chip.peek_reg(RegId::Int_Req_Reg) & irq::WD_DP_Control_Timeout, 0u);
  std::vector<std::uint64_t> expiries;
  for (const LogRecord& r : log.records) {
    if (r.text.starts_with("DP watchdog expired")) expiries.push_back(r.cycle);
  }
  EXPECT_EQ(expiries, std::vector<std::uint64_t>{okay});
}

TEST_P(Protocol, SecondMasterCannotParameteriseALockedSlave) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  DpMaster other(b.chip, MasterConfig{7, 12'000'000, 100, 33}, config().slave);
  other.set_firmware([&](BusPort& c) { b.user.isr(c); });
  other.fdl_status();
  const Exchange prm = other.set_prm();
  EXPECT_EQ(wire(prm.answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.fdl_counters().not_allowed, 1u);
  const Exchange diag = other.slave_diag();
  EXPECT_EQ(diag.answer->du[3], 2);  // Master_Add: locked by master 2
}

TEST_P(Protocol, SetSlaveAddress) {
  Bench b(GetParam(), 12'000'000, config());
  b.master.fdl_status();
  ASSERT_EQ(b.chip.station_address(), 5);
  const Exchange ex = b.master.set_slave_address(9, false);
  EXPECT_EQ(wire(ex.answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.station_address(), 9);
  b.master.idle(2000);
  ASSERT_FALSE(b.user.interrupts.empty());
  EXPECT_NE(b.user.interrupts.back().second & irq::New_SSA_Data, 0u);
  EXPECT_FALSE(b.chip.ssa_buffer_free());
  b.master.set_target(9);
  EXPECT_TRUE(b.master.fdl_status().answer);
  // SSA buffer still held by the user: a second request gets RR (no resource).
  const Exchange again = b.master.set_slave_address(10, false);
  EXPECT_EQ(wire(again.answer), (Bytes{0x10, 0x02, 0x09, 0x02, 0x0D, 0x16}));
}

TEST_P(Protocol, ReadInputsAndOutputsAndGetCfg) {
  Bench b(GetParam(), 12'000'000, config());
  // Before Data_Exchange: no service activated (RS), 10 02 05 03 0A 16.
  EXPECT_EQ(wire(b.master.read_inputs().answer), (Bytes{0x10, 0x02, 0x05, 0x03, 0x0A, 0x16}));
  ASSERT_TRUE(b.master.startup());
  const Exchange cfg = b.master.get_cfg();
  EXPECT_EQ(cfg.answer->du, (Bytes{0x13, 0x23}));
  b.master.data_exchange({4, 3, 2, 1});
  EXPECT_EQ(b.master.read_outputs().answer->du, (Bytes{4, 3, 2, 1}));  // served from U
  EXPECT_EQ(b.master.read_inputs().answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
}

TEST_P(Protocol, RepeatedFcbGetsThePreviousAnswerAgain) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  const Exchange first = b.master.data_exchange({1, 1, 1, 1});
  b.master.idle(2000);
  const std::size_t fetched = b.user.outputs.size();
  b.user.set_inputs({0xC1, 0xC2, 0xC3, 0xC4});
  // The master lost the answer and repeats: same FC (FCV = 1, same FCB), other data.
  fdl::Frame again = first.request;
  again.du = {2, 2, 2, 2};
  const Exchange repeat = b.master.transact(again);
  EXPECT_EQ(wire(repeat.answer), wire(first.answer));
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.size(), fetched);  // nothing was taken
  EXPECT_EQ(b.chip.fdl_counters().repeated, 1u);
  // The user hands new inputs over in its DX_Out ISR, so they appear one exchange later.
  EXPECT_EQ(b.master.data_exchange({3, 3, 3, 3}).answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
  EXPECT_EQ(b.master.data_exchange({4, 4, 4, 4}).answer->du, (Bytes{0xC1, 0xC2, 0xC3, 0xC4}));
}

TEST_P(Protocol, NewDiagnosticsAreAnnouncedWithHighPriorityAnswers) {
  Bench b(GetParam(), 12'000'000, config());
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, 0x08);  // DL
  // The user writes extended diagnostics into its diag buffer and hands it over.
  Chip& c = b.chip;
  const std::uint8_t sm = c.read(c.addr_of(RegId::Diag_Buffer_SM));
  const RegId ptr = (sm & 0x03) == 0x01 ? RegId::R_Diag_Buf_Ptr1 : RegId::R_Diag_Buf_Ptr2;
  const RegId len = (sm & 0x03) == 0x01 ? RegId::R_Len_Diag_Buf1 : RegId::R_Len_Diag_Buf2;
  const std::uint32_t base = static_cast<std::uint32_t>(c.read(c.addr_of(ptr)))
                             << c.profile().segment_shift;
  const Bytes ext = {0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x42, 0x43};  // Ext_Diag, Stat_Diag
  for (std::size_t i = 0; i < ext.size(); ++i)
    c.write(base + static_cast<std::uint32_t>(i), ext[i]);
  c.write(c.addr_of(len), static_cast<std::uint8_t>(ext.size()));
  c.read(c.addr_of(RegId::New_Diag_Buffer_Cmd));
  EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x04, 0u);               // Diag_Flag
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, 0x0A);  // DH
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  // St1 Ext_Diag, St2 Stat_Diag | 1 | WD_On, St3 0, Master_Add 2, ident, then the user's bytes.
  EXPECT_EQ(diag.answer->du, (Bytes{0x08, 0x0E, 0x00, 0x02, 0x0C, 0x31, 0x42, 0x43}));
  // Stat_Diag: the flag stays after the fetch, the master keeps asking.
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, 0x0A);
}

TEST_P(Protocol, SetPrmFaults) {
  // Wrong Ident_Number, then a reserved Station_Status bit: Prm_Fault each time, no New_Prm_Data.
  for (int variant = 0; variant < 2; ++variant) {
    ResponderConfig rc = config();
    Bench b(GetParam(), 12'000'000, rc);
    b.master.fdl_status();
    if (variant == 0) b.master.slave().ident = 0x1234;
    const Exchange prm = b.master.set_prm(variant == 1 ? 0x01 : 0x00);
    EXPECT_EQ(wire(prm.answer), Bytes{0xE5});
    b.master.idle(2000);
    EXPECT_EQ(b.user.prm_accepted, 0u) << variant;
    b.master.slave().ident = 0x0C31;
    const Exchange diag = b.master.slave_diag();
    EXPECT_EQ(diag.answer->du[0], 0x02 | 0x40) << variant;  // Station_Not_Ready, Prm_Fault
    EXPECT_EQ(diag.answer->du[1] & 0x01, 0x01) << variant;  // Prm_Req
    EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  }
}

// Spec_User_Prm_Byte bits 0/1 on the SPC3 and the VPC3+ (the DPC31 keeps that byte, p.26).
TEST_P(ProtocolSpcVpc, StopBitCheckOffByParameterisation) {
  ResponderConfig rc = config();
  rc.slave.user_prm = {0x02};  // Spec_User_Prm_Byte: Dis_Stopbit
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.peek_reg(RegId::Mode_Reg0) & 0x0003, 0x0002);  // Dis_Stop_Control from Set_Prm
  // A zero stop bit in the last character (the line returns high before the next start). The
  // start-up's SRDs carried FCB 1, 0, 1, 0, so this one has FCB 1: FC 7Dh.
  const Exchange dx =
      b.master.transact(fdl::make_frame(5, 2, 0x7D, {5, 5, 5, 5}), {12, UartFault::Kind::stop});
  EXPECT_TRUE(dx.answer);
  EXPECT_EQ(b.chip.fdl_counters().stop_bit, 0u);
  EXPECT_EQ(b.chip.fdl_counters().repeated, 0u);
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{5, 5, 5, 5}));
}

TEST_P(Protocol, DataExchangeInSd3) {
  ResponderConfig rc = config();
  rc.slave.in_len = 8;
  rc.slave.out_len = 8;
  rc.substitute.assign(8, 0x5A);  // the clear buffer C is out_len bytes too
  rc.slave.cfg = {0x17, 0x27};    // 8 in, 8 out
  Bench b(GetParam(), 12'000'000, rc);
  b.user.set_inputs({1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_TRUE(b.master.startup());
  fdl::Frame sd3 = fdl::make_frame(5, 2, 0x7D, {8, 7, 6, 5, 4, 3, 2, 1});  // FCB 1 (see above)
  sd3.sd = fdl::SD3;
  const Exchange dx = b.master.transact(sd3);
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(dx.request_end - dx.request_start, 14u * 11 * 4);  // SD3: 14 characters
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{8, 7, 6, 5, 4, 3, 2, 1}));
}

INSTANTIATE_TEST_SUITE_P(Profiles, Protocol, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });
INSTANTIATE_TEST_SUITE_P(Profiles, ProtocolSpcVpc,
                         ::testing::Values(Profile::spc3, Profile::vpc3plus),
                         [](const auto& i) { return testutil::pname(i.param); });

TEST(Dpc31, NewGcIntModeOneInterruptsOnEveryGlobalControl) {
  Bench b(Profile::dpc31, 12'000'000);
  ASSERT_TRUE(b.master.startup());
  b.chip.write(static_cast<std::uint32_t>(b.chip.addr_of(RegId::Param_Reg)),
               0x01);  // Param_Reg.New_GC_Int_Mode
  b.master.global_control(0x08);
  b.master.global_control(0x08);
  b.master.global_control(0x08);
  b.master.idle(2000);
  std::size_t n = 0;
  for (const auto& [cycle, ir] : b.user.interrupts) n += (ir & irq::New_GC_Command) != 0 ? 1 : 0;
  EXPECT_EQ(n, 3u);
  EXPECT_EQ(b.chip.peek(0x0866), 0x08);  // R_GC_Command (cell 3Ch at 0840h + 26h)
}

TEST(Dpc31, ClearBufferCycle) {
  ResponderConfig rc;
  rc.substitute = {0x5A, 0x5B, 0x5C, 0x5D};
  Bench b(Profile::dpc31, 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({1, 2, 3, 4});
  b.master.global_control(0x02);  // Clear_Data: N_Cl, DX_Out, the user gets C
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x5A, 0x5B, 0x5C, 0x5D}));
  EXPECT_EQ(b.chip.read(0x0A) & 0x80, 0);  // N_Cl consumed by the fetch
  const std::size_t fetched = b.user.outputs.size();
  b.master.data_exchange({});  // fail-safe while the user already holds C: nothing new
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.size(), fetched);
  b.master.data_exchange({9, 9, 9, 9});  // Operate again
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{9, 9, 9, 9}));
  EXPECT_FALSE(b.user.outputs.back().cleared);
  b.master.data_exchange({});  // Clear again: the C buffer the firmware refilled
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x5A, 0x5B, 0x5C, 0x5D}));
  EXPECT_TRUE(b.user.outputs.back().cleared);
}

// Every malformed frame class: the documented reaction (no answer) and its counter.
class Malformed : public ::testing::TestWithParam<Profile> {};

TEST_P(Malformed, EachClassIsCountedAndNotAnswered) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  const FdlCounters& n = b.chip.fdl_counters();
  const Bytes good = fdl::encode(fdl::make_frame(5, 2, 0x7D, {1, 2, 3, 4}));  // SRD_high, FCB FCV
  auto send = [&](Bytes bytes, UartFault f = {}) { return b.master.transact_raw(bytes, f); };
  auto expect_silent = [&](const Exchange& ex, const std::uint32_t& counter, const char* what) {
    EXPECT_FALSE(ex.answer) << what;
    EXPECT_EQ(ex.answer_end, 0u) << what;  // nothing at all came back
    EXPECT_EQ(counter, 1u) << what;
  };
  Bytes bad_fcs = good;
  bad_fcs[good.size() - 2] ^= 0x01;
  expect_silent(send(bad_fcs), n.bad_fcs, "bad FCS");
  expect_silent(send(good, {3, UartFault::Kind::parity}), n.parity, "parity");
  expect_silent(send(good, {5, UartFault::Kind::stop}), n.stop_bit, "stop bit");
  Bytes le = good;
  le[2] = static_cast<std::uint8_t>(le[1] + 1);
  expect_silent(send(le), n.le_mismatch, "LE != LEr");
  Bytes ed = good;
  ed.back() = 0x17;
  expect_silent(send(ed), n.wrong_ed, "wrong ED");
  expect_silent(send(Bytes(good.begin(), good.begin() + 6)), n.truncated, "truncated");
  Bytes big = {0x68, 0xFA, 0xFA, 0x68};  // LE 250: longer than any telegram
  expect_silent(send(big), n.oversize, "oversize");
  expect_silent(send({0x33, 0x05, 0x02}), n.bad_sd, "unknown SD");
  expect_silent(send(fdl::encode(fdl::make_frame(9, 2, 0x7D, {1, 2, 3, 4}))), n.foreign_address,
                "foreign address");
  // An unknown SAP is answered RS (no service activated): 10 02 05 03 0A 16.
  const Exchange sap = send(fdl::encode(fdl::make_frame(5, 2, 0x6D, {}, 50, 62)));
  EXPECT_EQ(wire(sap.answer), (Bytes{0x10, 0x02, 0x05, 0x03, 0x0A, 0x16}));
  EXPECT_EQ(n.unknown_sap, 1u);
  // The exchange goes on after every one of them.
  EXPECT_TRUE(b.master.data_exchange({1, 2, 3, 4}).answer);
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  // Offline: the receiver frames the request but nothing answers.
  testutil::user_go_offline(b.chip);  // Go_Offline (dpc31: MAC_Stop)
  ASSERT_FALSE(b.chip.started());
  expect_silent(b.master.fdl_status(), n.offline, "offline");
}

TEST_P(Malformed, GlitchIsABadStartBit) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  // A 1-clock low pulse after a long idle: falls at c, rises at c + 1, before the start sample
  // at c + T/2 = c + 2: the character has a bad start bit and is thrown away.
  const std::uint64_t c = b.chip.cycle() + 1000;
  b.chip.drive_rxd(c, false);
  b.chip.drive_rxd(c + 1, true);
  b.master.idle(2000);
  EXPECT_EQ(b.chip.fdl_counters().start_bit, 1u);
  EXPECT_TRUE(b.master.data_exchange({1, 2, 3, 4}).answer);
}

// Counters that differ between two snapshots, "name:before->after" (empty: none).
std::string changed(const FdlCounters& a, const FdlCounters& b) {
  std::string out;
  for (const CounterField& f : fdl_counter_fields()) {
    if (a.*f.member != b.*f.member) {
      out += std::string(f.name) + ":" + std::to_string(a.*f.member) + "->" +
             std::to_string(b.*f.member) + " ";
    }
  }
  return out;
}

TEST_P(Malformed, GlitchCountsOnlyItsStartBit) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  const FdlCounters before = b.chip.fdl_counters();
  // The character sampled from a glitch also reads 1 for its parity bit (data FFh, parity 1:
  // odd). One count per character, the first error sampled: the start bit.
  b.master.glitch(1);
  b.master.idle(2000);
  EXPECT_EQ(changed(before, b.chip.fdl_counters()), "start_bit:0->1 ");
  EXPECT_TRUE(b.master.data_exchange({1, 2, 3, 4}).answer);
}

// DpMaster::glitch (dp_master.hpp): 0 clocks is no pulse (it counted a start_bit error), and a
// pulse longer than the character the receiver samples from it holds the line low: the master's
// next request waits for its rise and a TSYN (33 bit times) after it, as after a segment's pulse.
// It went out 11 bit times after the pulse began, on a line held low (audit s35 aTb finding 5).
TEST_P(Malformed, AGlitchOfNoClocksIsRefusedAndALongOneHoldsTheLine) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  const Exchange last = b.master.data_exchange({1, 2, 3, 4});
  ASSERT_TRUE(last.answer);
  const FdlCounters before = b.chip.fdl_counters();
  const std::uint64_t at = b.chip.cycle();
  EXPECT_THROW(b.master.glitch(0), std::invalid_argument);
  EXPECT_EQ(b.chip.cycle(), at);
  EXPECT_EQ(changed(before, b.chip.fdl_counters()), "");
  EXPECT_EQ(b.master.counters().noise, 0u);
  // The pulse starts TSYN after the answer's end: 33 T = 132 clocks at 12 Mbaud (T = 4).
  const std::uint64_t start = last.answer_end + 33 * b.T();
  b.master.glitch(10'000);
  EXPECT_EQ(b.chip.cycle(), start + 10'000);
  const Exchange next = b.master.data_exchange({1, 2, 3, 4});
  EXPECT_EQ(next.request_start, start + 10'000 + 33 * b.T());
  EXPECT_TRUE(next.answer);
}

TEST_P(Malformed, TailOfABrokenTelegramIsNotCountedAgain) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  // A framing error discards the telegram; its remaining characters (well-formed, without TSYN
  // before them) are its tail, not a telegram of their own: no no_sync for them.
  FdlCounters before = b.chip.fdl_counters();
  const Exchange noise = b.master.transact_raw({0x33, 0x05, 0x02, 0x49, 0x16});
  EXPECT_FALSE(noise.answer);
  EXPECT_EQ(changed(before, b.chip.fdl_counters()), "bad_sd:0->1 ");
  before = b.chip.fdl_counters();
  Bytes le = fdl::encode(fdl::make_frame(5, 2, 0x7D, {1, 2, 3, 4}));
  le[2] = static_cast<std::uint8_t>(le[1] + 1);
  EXPECT_FALSE(b.master.transact_raw(le).answer);
  EXPECT_EQ(changed(before, b.chip.fdl_counters()), "le_mismatch:0->1 ");
  // After TSYN the next telegram is heard.
  before = b.chip.fdl_counters();
  EXPECT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(changed(before, b.chip.fdl_counters()), "requests:5->6 ");
}

TEST_P(Malformed, RequestWithoutTsynIsIgnored) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  // A token to station 9 and, without any idle, an FDL_Status to us: not synchronised.
  const Exchange ex = b.master.transact_raw({0xDC, 0x09, 0x02, 0x10, 0x05, 0x02, 0x49, 0x50, 0x16});
  EXPECT_FALSE(ex.answer);
  EXPECT_EQ(b.chip.fdl_counters().no_sync, 1u);
  EXPECT_TRUE(b.master.fdl_status().answer);  // with TSYN before it, answered
}

INSTANTIATE_TEST_SUITE_P(Profiles, Malformed, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });
