// Characters on TxD (Chip::on_txd_chars, issue 19 item 1 and issue 30 item 6) against TxD
// edges as events (Chip::on_txd), the path every earlier test and golden trace was made with.
// With an on_txd observer attached the chip makes its answer's edges and every TxD edge is an
// event that reaches the master's receiver in a batch of its own, as before; without one the
// chip keeps its answer as characters (no edge is made) and hands them to the master's receiver
// when it looks, whole where all of a character's edges are on the line, else as edges
// (UartRx::take). Two chips of the same profile, each with the built-in master and the minimal
// user side: the master's exchanges (every request's and answer's start and end cycle, the
// answer's bytes), its counters, the chip's state (save_state), TxD and every edge (made from the
// characters) must be the same after every exchange. Every profile, every PROFIBUS rate; DPV1
// Reads; and an answer on the line when the user takes the chip Offline (cut by the DPC31's
// MAC_Stop, sent whole before Go_Offline acts on the SPC3 and the VPC3+).
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "dpv1_master.hpp"
#include "responder.hpp"
#include "snapshot.hpp"
#include "test_util.hpp"
#include "txd_receiver.hpp"

using namespace dpc31;

// Its own namespace: the file compiles in one unity group with rxd_chars_test.cpp (Side, Edges).
namespace txd_chars {
namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

// How a side watches TxD besides its master: every edge an event (on_txd), the edges in batches
// (on_txd_edges: the answer is made of edges too, and the master's receiver takes them so), or
// characters (on_txd_chars: the answer stays characters).
enum class Watch : std::uint8_t { bits, edges, chars };

struct Side {
  Chip chip;
  Responder user;
  DpMaster master;
  Edges txd;
  std::size_t whole = 0;  // characters handed over whole (TxdRun::bytes)

  Side(Profile p, std::uint32_t baud, Watch watch, const ResponderConfig& rc = {},
       const SlaveConfig& slave = {})
      : chip({p, BusMode::intel, 0}),
        user(rc),
        master(init(chip, user, rc.slave.in_len), MasterConfig{2, baud, 100, 33}, slave) {
    master.set_firmware([this](BusPort& c) { user.isr(c); });
    if (watch == Watch::bits) {
      chip.on_txd([this](std::uint64_t c, bool l) { txd.emplace_back(c, l); });
    } else if (watch == Watch::edges) {
      chip.on_txd_edges([this](std::span<const std::pair<std::uint64_t, bool>> e) {
        txd.insert(txd.end(), e.begin(), e.end());
      });
    } else {
      // Beside the master: gets the same runs; their characters become the edges they stand for.
      chip.on_txd_chars([this](const TxdRun& r) {
        txd.insert(txd.end(), r.edges.begin(), r.edges.end());
        uart_encode(r.bytes, r.start, r.bit_cycles, txd);
        whole += r.bytes.size();
      });
    }
  }
  // The inputs A1, A2, ... of the slave's length (A1..A4 by default).
  static Chip& init(Chip& c, Responder& u, std::size_t in_len) {
    c.set_log_sink(nullptr);
    std::vector<std::uint8_t> in(in_len);
    for (std::size_t i = 0; i < in_len; ++i) in[i] = static_cast<std::uint8_t>(0xA1 + i);
    u.set_inputs(std::move(in));
    DirectBus bus(c);
    u.init(bus);
    return c;
  }
};

std::vector<std::uint8_t> wire(const std::optional<fdl::Frame>& f) {
  return f ? fdl::encode(*f) : std::vector<std::uint8_t>{};
}

::testing::AssertionResult same_exchange(const Exchange& a, const Exchange& b) {
  if (a.request_start == b.request_start && a.request_end == b.request_end &&
      a.answer_start == b.answer_start && a.answer_end == b.answer_end &&
      wire(a.answer) == wire(b.answer)) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "request " << a.request_start << ".." << a.request_end << " / " << b.request_start
         << ".." << b.request_end << ", answer " << a.answer_start << ".." << a.answer_end << " / "
         << b.answer_start << ".." << b.answer_end << " (" << wire(a.answer).size() << " / "
         << wire(b.answer).size() << " bytes)";
}

void expect_same(Side& bits, Side& chars, const char* what) {
  SCOPED_TRACE(what);
  const auto& h = bits.master.history();
  const auto& g = chars.master.history();
  ASSERT_EQ(h.size(), g.size());
  for (std::size_t i = 0; i < h.size(); ++i) ASSERT_TRUE(same_exchange(h[i], g[i])) << i;
  const MasterCounters& m = bits.master.counters();
  const MasterCounters& n = chars.master.counters();
  ASSERT_EQ(std::tie(m.requests, m.answered, m.no_answer, m.bad_answer),
            std::tie(n.requests, n.answered, n.no_answer, n.bad_answer));
  ASSERT_EQ(bits.chip.cycle(), chars.chip.cycle());
  ASSERT_TRUE(testutil::same_state(bits.chip, chars.chip));
  ASSERT_EQ(bits.chip.txd_pin(), chars.chip.txd_pin());
  chars.chip.take_txd();
  ASSERT_EQ(bits.txd, chars.txd);
  ASSERT_EQ(bits.chip.fdl_counters(), chars.chip.fdl_counters());
}

class TxdChars : public ::testing::TestWithParam<std::tuple<Profile, std::uint32_t>> {};

constexpr std::uint64_t kNeverCut = ~std::uint64_t{0};

}  // namespace

TEST_P(TxdChars, TheMasterSeesWhatTheEdgesShowed) {
  const auto [profile, baud] = GetParam();
  Side bits(profile, baud, Watch::bits);
  Side chars(profile, baud, Watch::chars);
  // The start-up: FDL_Status through the baud search, Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag.
  ASSERT_TRUE(bits.master.startup());
  ASSERT_TRUE(chars.master.startup());
  expect_same(bits, chars, "start-up");
  for (int i = 0; i < 6; ++i) {
    const std::vector<std::uint8_t> out{static_cast<std::uint8_t>(i), 0x55, 0xAA,
                                        static_cast<std::uint8_t>(0xF0 | i)};
    bits.master.data_exchange(out);
    chars.master.data_exchange(out);
    expect_same(bits, chars, "Data_Exchange");
  }
  // A damaged request goes unanswered on both; the master waits the slot time out.
  bits.master.data_exchange({1, 2, 3, 4}, {2, UartFault::Kind::parity});
  chars.master.data_exchange({1, 2, 3, 4}, {2, UartFault::Kind::parity});
  expect_same(bits, chars, "Data_Exchange with a parity error");
  bits.master.get_cfg();
  chars.master.get_cfg();
  expect_same(bits, chars, "Get_Cfg");
  bits.master.read_inputs();
  chars.master.read_inputs();
  expect_same(bits, chars, "Rd_Inp");
  bits.master.slave_diag();
  chars.master.slave_diag();
  expect_same(bits, chars, "Slave_Diag");
  bits.master.global_control(0x02);  // Clear_Data: no answer (SDN)
  chars.master.global_control(0x02);
  expect_same(bits, chars, "Global_Control");
  bits.master.idle(1000);
  chars.master.idle(1000);
  expect_same(bits, chars, "idle");
  EXPECT_GE(chars.whole, 20u) << "the whole path was rarely taken";
}

// DPV1 (docs/dpv1.md): MSAC_C1 Reads of a 240-byte record on a VPC3+, the long answers of row k
// of dpc31 bench, and a Read whose request is damaged (no answer, the master retries).
class TxdCharsDpv1 : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(TxdCharsDpv1, ReadsLookTheSame) {
  const std::uint32_t baud = GetParam();
  ResponderConfig rc;
  rc.slave.user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable, Fail_Safe
  rc.dpv1.records = {{0, 1, std::vector<std::uint8_t>(240, 0xA5)}, {0, 2, {1, 2, 3, 0x7E}}};
  Side bits(Profile::vpc3plus, baud, Watch::bits, rc, rc.slave);
  Side chars(Profile::vpc3plus, baud, Watch::chars, rc, rc.slave);
  Dpv1Master a(bits.chip, bits.master);
  Dpv1Master b(chars.chip, chars.master);
  ASSERT_TRUE(bits.master.startup());
  ASSERT_TRUE(chars.master.startup());
  expect_same(bits, chars, "start-up");
  for (std::uint8_t index : {1, 2, 1}) {
    const Dpv1Answer x = a.read(0, index, 240);
    const Dpv1Answer y = b.read(0, index, 240);
    ASSERT_EQ(x.outcome, Dpv1Answer::Outcome::positive);
    ASSERT_EQ(x.outcome, y.outcome);
    ASSERT_EQ(x.du, y.du);
    expect_same(bits, chars, "Read");
  }
  bits.master.data_exchange({1, 2, 3, 4}, {5, UartFault::Kind::stop});
  chars.master.data_exchange({1, 2, 3, 4}, {5, UartFault::Kind::stop});
  expect_same(bits, chars, "Data_Exchange with a stop bit error");
  // The two responses of 240 bytes (253 characters each) went as characters, but for a few.
  EXPECT_GE(chars.whole, 500u) << "the whole path was rarely taken";
}

INSTANTIATE_TEST_SUITE_P(Rates, TxdCharsDpv1,
                         ::testing::Values(9'600u, 187'500u, 1'500'000u, 12'000'000u));

INSTANTIATE_TEST_SUITE_P(ProfilesAndRates, TxdChars,
                         ::testing::Combine(::testing::Values(Profile::spc3, Profile::vpc3plus,
                                                              Profile::dpc31),
                                            ::testing::ValuesIn(kBaudRates)),
                         testutil::profile_rate_name);

// The user's stop while the answer is on the line (docs/timing.md "Go_Offline"): the DPC31's
// MAC_Stop acts at once (TxD back to idle at the completion cycle), the SPC3's and the VPC3+'s
// Go_Offline after the current request, so at the end of the answer's last stop bit. The edges
// reach a batch receiver as they reached a receiver fed edge by edge, a cut included, and the
// snapshots agree in the middle of the answer.
class TxdCut : public ::testing::TestWithParam<Profile> {};

TEST_P(TxdCut, AnAnswerOnTheLineAtTheStopReachesBothReceiversAlike) {
  const Profile profile = GetParam();
  Side bits(profile, 12'000'000, Watch::bits);
  Side chars(profile, 12'000'000, Watch::chars);
  ASSERT_TRUE(bits.master.startup());
  ASSERT_TRUE(chars.master.startup());
  const std::uint32_t t = bits.master.bit_cycles();
  UartRx a(t, bits.chip.cycle());
  UartRx b(t, chars.chip.cycle());
  bits.chip.on_txd([&](std::uint64_t c, bool l) { a.edge(c, l); });
  chars.chip.on_txd_chars([&](const TxdRun& r) { b.take(r); });
  // Get_Cfg by hand, FCV = 1 and FCB = 0 as in the start-up's last request (Slave_Diag): a
  // repetition (EN 50170 FCB), so the answer is the last one again, the ready Slave_Diag of 17
  // characters (docs/timing.md worked example). It starts MinTSDR = 11 bit times after the
  // request's end and ends 17 x 11 bit times later; the stop lands 3.5 characters in.
  const std::vector<std::uint8_t> req =
      fdl::encode(fdl::make_frame(5, 2, fdl::make_request_fc(fdl::Function::SRD_high, false, true),
                                  {}, sap::Get_Cfg, sap::Master));
  const std::uint64_t start = bits.chip.cycle() + 40 * std::uint64_t{t};
  const std::uint64_t end = bits.chip.drive_rxd_chars(req, start, t);
  ASSERT_EQ(chars.chip.drive_rxd_chars(req, start, t), end);
  const std::uint64_t answer_end = end + 11 * std::uint64_t{t} + 17 * 11 * std::uint64_t{t};
  const std::uint64_t cut = end + 11 * std::uint64_t{t} + (3 * 11 + 5) * std::uint64_t{t} + 1;
  bits.chip.step(cut - bits.chip.cycle());
  chars.chip.step(cut - chars.chip.cycle());
  ASSERT_TRUE(testutil::same_state(bits.chip, chars.chip)) << "in the middle of the answer";
  testutil::user_go_offline(bits.chip);
  testutil::user_go_offline(chars.chip);
  const bool dpc31 = profile == Profile::dpc31;
  EXPECT_EQ(bits.chip.started(), !dpc31);
  if (!dpc31) {
    bits.chip.step(answer_end - 1 - bits.chip.cycle());
    EXPECT_TRUE(bits.chip.started());
    bits.chip.step(1);
    EXPECT_FALSE(bits.chip.started());
    EXPECT_NE(bits.chip.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
  }
  const std::uint64_t later = bits.chip.cycle() + 30 * 11 * std::uint64_t{t};
  bits.chip.step(later - bits.chip.cycle());
  chars.chip.step(later - chars.chip.cycle());
  chars.chip.take_txd();
  EXPECT_TRUE(bits.chip.txd_pin());
  EXPECT_TRUE(testutil::same_state(bits.chip, chars.chip));
  std::vector<UartChar> x;
  std::vector<UartChar> y;
  a.advance(later, x);
  b.advance(later, y);
  EXPECT_EQ(x, y);
  // DPC31: three whole characters and the fourth cut, its remaining bits read high; else the
  // seventeen characters whole.
  ASSERT_EQ(x.size(), dpc31 ? 4u : 17u);
  EXPECT_TRUE(x[2].ok());
  if (!dpc31) {
    for (const UartChar& ch : x) EXPECT_TRUE(ch.ok());
  }
  snap::Writer wa;
  a.save_state(wa);
  snap::Writer wb;
  b.save_state(wb);
  EXPECT_EQ(wa.bytes(), wb.bytes());
}

INSTANTIATE_TEST_SUITE_P(Profiles, TxdCut,
                         ::testing::Values(Profile::spc3, Profile::vpc3plus, Profile::dpc31),
                         [](const ::testing::TestParamInfo<Profile>& i) {
                           return testutil::pname(i.param);
                         });

// Row b of dpc31 bench (Data_Exchange of 244 + 244 bytes, DPC31) at every PROFIBUS rate: the
// answer kept as characters, which the master hands to its AnswerCollector whole once their stop
// samples are due (DpMaster::take and look: no receiver queue), against the answer made of edges
// (an on_txd_edges observer attached), which the master's receiver decodes edge run by edge run.
// Every exchange's cycles and bytes, the counters, the chip's state and TxD must agree; then one
// answer cut by MAC_Stop (the DPC31's Go_Offline, at once) 100.5 characters in (whole characters,
// the cut one as edges, then nothing): a broken answer at the same cycles on both.
class TxdDirect : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(TxdDirect, LongAnswersAndACutOneLookTheSame) {
  const std::uint32_t baud = GetParam();
  ResponderConfig rc;
  rc.slave.in_len = 244;
  rc.slave.out_len = 244;
  Side edges(Profile::dpc31, baud, Watch::edges, rc, rc.slave);
  Side chars(Profile::dpc31, baud, Watch::chars, rc, rc.slave);
  std::vector<std::uint8_t> in(244);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<std::uint8_t>(i * 7);
  for (Side* s : {&edges, &chars}) s->user.set_inputs(in);
  ASSERT_TRUE(edges.master.startup());
  ASSERT_TRUE(chars.master.startup());
  expect_same(edges, chars, "start-up");
  std::vector<std::uint8_t> out(244);
  for (int n = 0; n < 3; ++n) {
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<std::uint8_t>(i + n);
    const Exchange a = edges.master.data_exchange(out);
    chars.master.data_exchange(out);
    ASSERT_TRUE(a.answer.has_value());
    ASSERT_EQ(a.answer->du.size(), 244u);
    expect_same(edges, chars, "Data_Exchange");
  }
  const Exchange& last = edges.master.history().back();
  const std::uint64_t tsdr = last.answer_start - last.request_end;
  // From here a firmware of the test's own runs the chip (the master's scheduler), so that it can
  // take the chip offline at a cycle in the middle of the answer.
  const std::uint32_t t = edges.master.bit_cycles();
  for (Side* s : {&edges, &chars}) {
    s->master.idle(100 * std::uint64_t{t});  // the master's firmware ends its ISR
    auto cpu = std::make_shared<Cpu>(s->chip, [s](BusPort& c) { s->user.isr(c); });
    auto cut = std::make_shared<std::uint64_t>(0);
    s->master.scheduler = [s, cpu, cut, tsdr, t](std::uint64_t cycle) {
      // The first run goes to the request's end: the answer starts TSDR later.
      if (*cut == 0) *cut = cycle + tsdr + (100 * 11 + 5) * std::uint64_t{t} + 1;
      if (*cut != kNeverCut && cycle > *cut) {
        cpu->run_until(*cut);
        if (s->chip.cycle() < *cut) return;  // stopped early: the master looks first
        testutil::user_go_offline(s->chip);
        *cut = kNeverCut;
      }
      cpu->run_until(cycle);
    };
  }
  const Exchange a = edges.master.data_exchange(out);
  chars.master.data_exchange(out);
  EXPECT_FALSE(a.answer.has_value());
  EXPECT_EQ(edges.master.counters().bad_answer, 1u);
  EXPECT_GT(a.answer_end, a.answer_start + 100 * 11 * std::uint64_t{t});
  expect_same(edges, chars, "an answer cut by Go_Offline");
  EXPECT_GE(chars.whole, 3u * 240u) << "the whole path was rarely taken";
}

INSTANTIATE_TEST_SUITE_P(Rates, TxdDirect, ::testing::ValuesIn(kBaudRates));

TEST(TxdReceiver, ACharacterEndedByItsRiseIsReportedAtTheNextLook) {
  // docs/timing.md "Serial line (UART)": bit k sampled at start + k T + T/2. 00h with its stop
  // bit sent low at T = 4 from cycle 100: low through the stop sample at 100 + 40 + 2 = 142. The
  // rise at 150 takes that sample (the receiver is then idle, its character not yet handed on);
  // the look at 160 hands it on: a stop bit error, 25 idle bits before it (100 / 4).
  TxdReceiver rx(4, 0);
  rx.edge(100, false);
  rx.edge(150, true);
  std::vector<UartChar> out;
  rx.advance(160, out);
  ASSERT_EQ(out.size(), 1U);
  EXPECT_EQ(out[0].data, 0x00);
  EXPECT_TRUE(out[0].start_ok);
  EXPECT_TRUE(out[0].parity_ok);
  EXPECT_FALSE(out[0].stop_ok);
  EXPECT_EQ(out[0].start, 100U);
  EXPECT_EQ(out[0].end, 144U);
  EXPECT_EQ(out[0].idle_bits, 25U);
  EXPECT_FALSE(rx.receiving());
}

}  // namespace txd_chars
