// dpc31 bridge with several slaves on one line (docs/bridge.md, "Several slaves"), in process: the
// engine on a Segment with the client as the station "master". Cycle-exact against docs/timing.md:
// a request goes on the line TSYN (33 bit times) after the last telegram, each answer MinTSDR
// (11 bit times, the responder's MinTSDR_Val 0Bh) after its request, every character 11 bit
// times; every answer is named with the station that drove it.
#include <gtest/gtest.h>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "../lib/bridge/engine.hpp"
#include "baud_search.hpp"
#include "bridge_engine_record.hpp"
#include "dpc31/fdl.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;
using dpc31::bridge::Engine;
using dpc31::bridge::SlaveSpec;

constexpr std::uint32_t kT = 2500;  // bit time at 19200 baud, 48 MHz

using Line = testutil::LogLine;
using testutil::Sent;

Bytes frame(std::uint8_t da, std::uint8_t fc, Bytes du = {},
            std::optional<std::uint8_t> dsap = std::nullopt) {
  const auto ssap = dsap ? std::optional<std::uint8_t>(62) : std::nullopt;
  return dpc31::fdl::encode(dpc31::fdl::make_frame(da, 2, fc, std::move(du), dsap, ssap));
}

// Two stations with the built-in user side (ident 0C31h, Cfg 13 23; docs/bridge.md): an SPC3 at
// address 5, a VPC3+ at 6.
class BridgeSegment : public ::testing::Test, protected testutil::EngineRecord {
 protected:
  void SetUp() override {
    dpc31::bridge::Setup s;
    s.log_detail = dpc31::bridge::LogDetail::telegrams;
    s.slaves = {SlaveSpec{5, {dpc31::Profile::spc3}, nullptr},
                SlaveSpec{6, {dpc31::Profile::vpc3plus}, nullptr}};
    make(s);
  }

  // FDL_Status to `da` until answered (within one round of the baud search).
  Bytes find(std::uint8_t da) {
    const std::uint64_t from = engine_->cycle();
    while (engine_->cycle() - from <= testutil::kBaudSearchRound) {
      const Bytes a = exchange(frame(da, 0x49));
      if (!a.empty()) return a;
    }
    ADD_FAILURE() << "station " << int{da} << " never answered FDL_Status";
    return {};
  }

  // FCB per station, as a master keeps it (EN 50170): 1 in the first SRD after FDL_Status.
  Bytes srd(std::uint8_t da, Bytes du, std::optional<std::uint8_t> dsap = std::nullopt) {
    bool& fcb = fcb_[da - 5];
    const auto fc = static_cast<std::uint8_t>(fcb ? 0x7D : 0x5D);
    fcb = !fcb;
    return exchange(frame(da, fc, std::move(du), dsap));
  }

  // Both stations from their baud search to Data_Exchange, each answer checked.
  void start_up();

  bool fcb_[2] = {true, true};
};

// Set_Prm: Lock_Req + WD_On, watchdog 100 x 10 (x 10 ms), MinTSDR 0, ident 0C31h, group 0,
// Spec_User_Prm_Byte 00.
const Bytes kPrm = {0x88, 0x64, 0x0A, 0x00, 0x0C, 0x31, 0x00, 0x00};
const Bytes kCfg = {0x13, 0x23};  // 4 bytes in, 4 bytes out (byte consistency)

// Slave_Diag's six standard bytes (EN 50170): Station_Status_1..3, Master_Add, Ident, in an
// SD2 answer from SAP 60 to SAP 62.
Bytes diag_answer(std::uint8_t sa, Bytes du) {
  return dpc31::fdl::encode(
      dpc31::fdl::make_frame(2, sa, 0x08, std::move(du), std::uint8_t{62}, std::uint8_t{60}));
}

void BridgeSegment::start_up() {
  find(5);
  exchange(frame(6, 0x49));
  for (std::uint8_t a : {5, 6}) {
    // Not parameterised: Station_Not_Ready; Prm_Req and the fixed bit 2; no master (FFh).
    EXPECT_EQ(srd(a, {}, 60), diag_answer(a, {0x02, 0x05, 0x00, 0xFF, 0x0C, 0x31}));
    EXPECT_EQ(srd(a, kPrm, 61), Bytes{0xE5});
    EXPECT_EQ(srd(a, kCfg, 62), Bytes{0xE5});
    // Ready: WD_On and the fixed bit 2; master 2.
    EXPECT_EQ(srd(a, {}, 60), diag_answer(a, {0x00, 0x0C, 0x00, 0x02, 0x0C, 0x31}));
  }
}

TEST_F(BridgeSegment, EachStationAnswersItsOwnRequestsAtMinTsdr) {
  // Both chips search the rate together and both find it at the same FDL_Status (docs/timing.md:
  // any frame with data at the searched rate ends the search): station 6 answers at once.
  EXPECT_EQ(find(5), (Bytes{0x10, 0x02, 0x05, 0x00, 0x07, 0x16}));
  const std::size_t before = line_.size();
  EXPECT_EQ(exchange(frame(6, 0x49)), (Bytes{0x10, 0x02, 0x06, 0x00, 0x08, 0x16}));
  ASSERT_EQ(line_.size(), before + 2);
  const Sent& answer5 = line_[before - 1];
  const Sent& req = line_[before];
  const Sent& answer6 = line_[before + 1];
  EXPECT_EQ(answer5.sender, "slave5");
  EXPECT_EQ(req.sender, "master");
  EXPECT_EQ(answer6.sender, "slave6");
  // TSYN after the last answer; the request 6 characters; the answer MinTSDR after it.
  EXPECT_EQ(req.start, answer5.end + 33 * kT);
  EXPECT_EQ(req.end, req.start + 6 * 11 * kT);
  EXPECT_EQ(answer6.start, req.end + 11 * kT);
  EXPECT_EQ(answer6.end, answer6.start + 6 * 11 * kT);
  // The log names each answer's station, stamped with its first start bit.
  const std::vector<Line> tx = tagged("TxD");
  ASSERT_GE(tx.size(), 2u);
  EXPECT_EQ(tx[tx.size() - 2].station, "slave5");
  EXPECT_EQ(tx.back().station, "slave6");
  EXPECT_EQ(tx.back().cycle, answer6.start);
  EXPECT_EQ(tx.back().text, "10 02 06 00 08 16  | OK 6->2");
  ASSERT_EQ(engine_->stations().size(), 2u);
  EXPECT_EQ(engine_->stations()[1].name, "slave6");
  EXPECT_EQ(engine_->chip(0).profile().id, dpc31::Profile::spc3);
  EXPECT_EQ(engine_->chip(1).profile().id, dpc31::Profile::vpc3plus);
}

// The start-up of both and Data_Exchange: each station's user side returns the outputs it
// fetched as its next inputs (the loop-back), so each answer proves whose data it carries. The
// outputs of exchange n are fetched on its DX_Out and handed over as inputs in the ISR of exchange
// n + 1 (New_Din_Buffer_Cmd), so exchange n + 2 answers them: the third answer carries the
// first outputs.
TEST_F(BridgeSegment, TwoStationsReachDataExchangeEachWithItsOwnData) {
  start_up();
  const Bytes out5 = {0xA5, 0x05, 0x50, 0x55};
  const Bytes out6 = {0x11, 0x22, 0x33, 0x66};
  Bytes a5;
  Bytes a6;
  for (int cycle = 0; cycle < 3; ++cycle) {
    a5 = srd(5, out5);
    a6 = srd(6, out6);
  }
  const auto dl = [](std::uint8_t sa, const Bytes& inputs) {
    return dpc31::fdl::encode(dpc31::fdl::make_frame(2, sa, 0x08, inputs));
  };
  EXPECT_EQ(a5, dl(5, out5));
  EXPECT_EQ(a6, dl(6, out6));
  engine_->flush_log();
  for (const char* who : {"slave5", "slave6"}) {
    bool reached = false;
    for (const Line& l : tagged("STATE")) {
      reached |= l.station == who && l.text.find("dp_state Wait_Cfg -> Data_Exchange") == 0;
    }
    EXPECT_TRUE(reached) << who;
  }
  // The other station ignored every request to its neighbour: counted, not answered.
  EXPECT_GT(engine_->chip(0).fdl_counters().foreign_address, 0u);
  EXPECT_GT(engine_->chip(1).fdl_counters().foreign_address, 0u);
}

// --slave ...:user_wd_value=3 and ...:user_wd=1:user_wd_value=3 (docs/timing.md: the user
// watchdog counts Data_Exchanges; the responder's Start loads R_User_WD_Value at the first, each
// later one counts down, the one that reaches 0 is not answered): station 5, unserved, answers
// Data_Exchanges 1..3 and not the 4th; station 6, served on every DX_Out, answers all six.
class BridgeSegmentUserWd : public BridgeSegment {
 protected:
  void SetUp() override {
    dpc31::bridge::Setup s;
    SlaveSpec spc3{5, {dpc31::Profile::spc3}, nullptr};
    spc3.user_wd_value = 3;
    SlaveSpec vpc3{6, {dpc31::Profile::vpc3plus}, nullptr};
    vpc3.user_watchdog = true;
    vpc3.user_wd_value = 3;
    s.slaves = {spc3, vpc3};
    make(s);
  }
};

TEST_F(BridgeSegmentUserWd, TheResponderServesItsUserWatchdogWhenAsked) {
  start_up();
  std::vector<bool> data5;
  std::vector<bool> data6;
  for (std::uint8_t n = 1; n <= 6; ++n) {
    const Bytes out = {n, n, n, n};
    const auto with_data = [](const Bytes& answer) {
      const dpc31::fdl::Decoded d = dpc31::fdl::decode(answer);
      return !answer.empty() && d.error == dpc31::fdl::Error::none && d.frame.du.size() == 4;
    };
    data5.push_back(with_data(srd(5, out)));
    data6.push_back(with_data(srd(6, out)));
  }
  EXPECT_EQ(data5, (std::vector<bool>{true, true, true, false, false, false}));
  EXPECT_EQ(data6, std::vector<bool>(6, true));
  EXPECT_EQ(engine_->chip(0).dp_state(), dpc31::DpState::Wait_Prm);
  EXPECT_EQ(engine_->chip(1).dp_state(), dpc31::DpState::Data_Exchange);
}

// An address nobody has: no answer within the slot time (100 bit times from the request's end),
// and the next request follows TSYN after it.
TEST_F(BridgeSegment, AnAddressWithoutStationTimesOutAtTheSlotTime) {
  find(5);
  EXPECT_TRUE(exchange(frame(9, 0x49)).empty());
  const std::size_t n = line_.size();
  EXPECT_EQ(exchange(frame(6, 0x49)), (Bytes{0x10, 0x02, 0x06, 0x00, 0x08, 0x16}));
  ASSERT_EQ(line_.size(), n + 2);
  const Sent& lost = line_[n - 1];
  EXPECT_EQ(lost.sender, "master");
  EXPECT_EQ(line_[n].start, lost.end + (100 + 33) * kT);
}

// Set_Slave_Add (SAP 55, in Wait_Prm) moves station 6 onto address 5; the chip answers at its new
// address at once (emu/dp_sm.cpp). The next FDL_Status to 5 is answered by both at the request's
// end + 11 T: a collision at that cycle, the first driver (slave5) keeps the line and is the
// answer the client gets, and the log says who drove into whom.
TEST_F(BridgeSegment, AStationMovedOntoAnotherAddressCollides) {
  find(5);
  exchange(frame(6, 0x49));
  EXPECT_EQ(srd(6, {0x05, 0x0C, 0x31, 0x00}, 55), Bytes{0xE5});
  const std::size_t n = line_.size();
  EXPECT_EQ(exchange(frame(5, 0x49)), (Bytes{0x10, 0x02, 0x05, 0x00, 0x07, 0x16}));
  engine_->flush_log();
  ASSERT_EQ(line_.size(), n + 2);
  EXPECT_EQ(line_[n + 1].sender, "slave5");
  EXPECT_EQ(line_[n + 1].start, line_[n].end + 11 * kT);
  const std::vector<Line> notes = tagged("NOTE");
  ASSERT_FALSE(notes.empty());
  EXPECT_EQ(notes.back().text, "collision: slave6 drove into the telegram of slave5");
  EXPECT_EQ(notes.back().cycle, line_[n + 1].start);
}

// A late answer that collides (audit s30 a-master, finding 4). Station 5 gets MinTSDR FFh (255
// bit times, beyond the slot time of 100); then the client writes Slave_Diag to 5, FDL_Status to 6
// and Slave_Diag to 6 at once. Slave_Diag to 5 (R1, 11 characters) times out, FDL_Status to 6
// (R2) follows at R1's end + (100 + 33) T, station 6 answers it at R2's end + 11 T, and station 5
// answers R1 at R1's end + 255 T, into station 6's answer (which keeps the line). The rest of
// station 5's 17 characters ends at R1's end + (255 + 17 * 11) T. docs/bridge.md, "Several
// slaves": each answer names the station whose chip drove it; "How bytes become a bus": the next
// request (R3) follows TSYN after the end of the last telegram on the bus, whoever drove it.
// Before, the rest of station 5's answer was logged as one-byte telegrams of slave6, and R3 started
// TSYN after station 6's answer, into station 5's.
TEST_F(BridgeSegment, ALateAnswerIsItsStationsAndTheNextRequestWaitsForItsEnd) {
  find(5);
  exchange(frame(6, 0x49));
  EXPECT_EQ(srd(5, {}, 60), diag_answer(5, {0x02, 0x05, 0x00, 0xFF, 0x0C, 0x31}));
  EXPECT_TRUE(srd(5, {0x88, 0x0A, 0x0A, 0xFF, 0x0C, 0x31, 0x00, 0x00}, 61).empty());  // late SC
  engine_->run_until(engine_->cycle() + 1000 * kT);
  EXPECT_EQ(engine_->take_output(), Bytes{0xE5});
  const std::size_t n = line_.size();
  Bytes three = frame(5, 0x7D, {}, 60);
  const Bytes status6 = frame(6, 0x49);
  const Bytes diag6 = frame(6, 0x7D, {}, 60);
  three.insert(three.end(), status6.begin(), status6.end());
  three.insert(three.end(), diag6.begin(), diag6.end());
  engine_->feed(three);
  EXPECT_TRUE(engine_->settle(48'000'000));
  engine_->run_until(engine_->cycle() + 1000 * kT);
  engine_->flush_log();
  ASSERT_EQ(line_.size(), n + 6);
  const Sent& r1 = line_[n];
  const Sent& r2 = line_[n + 1];
  const Sent& a2 = line_[n + 2];
  const Sent& late = line_[n + 3];
  const Sent& r3 = line_[n + 4];
  const Sent& a3 = line_[n + 5];
  EXPECT_EQ(r1.sender, "master");
  EXPECT_EQ(r1.end, r1.start + 11 * 11 * kT);
  EXPECT_EQ(r2.sender, "master");
  EXPECT_EQ(r2.start, r1.end + (100 + 33) * kT);
  EXPECT_EQ(a2.sender, "slave6");
  EXPECT_EQ(a2.start, r2.end + 11 * kT);
  EXPECT_EQ(a2.bytes, (Bytes{0x10, 0x02, 0x06, 0x00, 0x08, 0x16}));
  // What the client heard of station 5 after station 6 let go of the line: station 5's.
  EXPECT_EQ(late.sender, "slave5");
  EXPECT_EQ(late.end, r1.end + (255 + 17 * 11) * kT);
  EXPECT_EQ(r3.sender, "master");
  EXPECT_EQ(r3.start, late.end + 33 * kT);
  EXPECT_EQ(a3.sender, "slave6");
  EXPECT_EQ(a3.bytes, diag_answer(6, {0x02, 0x05, 0x00, 0xFF, 0x0C, 0x31}));
  // One collision, station 5's into station 6's answer; the master drove into nobody's.
  std::vector<std::string> collisions;
  for (const Line& l : tagged("NOTE")) {
    if (l.cycle >= r1.start && l.text.starts_with("collision")) collisions.push_back(l.text);
  }
  EXPECT_EQ(collisions,
            std::vector<std::string>{"collision: slave5 drove into the telegram of slave6"});
  // The log's TxD lines between station 6's answer and R3: the one of station 5.
  std::vector<std::string> between;
  for (const Line& l : tagged("TxD")) {
    if (l.cycle > a2.start && l.cycle < r3.start) between.push_back(l.station);
  }
  EXPECT_EQ(between, std::vector<std::string>{"slave5"});
}

TEST(BridgeSegmentSetup, RefusesTwoStationsAtOneAddressButNotSeveralFirmwares) {
  const dpc31_firmware* do4 = dpc31_find_firmware("DO4");
  const dpc31_firmware* cnt2 = dpc31_find_firmware("CNT2");
  ASSERT_NE(do4, nullptr);
  ASSERT_NE(cnt2, nullptr);
  const std::vector<SlaveSpec> same_address = {{5, {}, nullptr}, {5, {}, nullptr}};
  EXPECT_EQ(dpc31::bridge::stations_problem(same_address),
            "--slave 5: a second station at address 5 (two stations at one address both answer: "
            "a collision on every request)");
  // Each station's firmware is an instance of its own (docs/firmware.md, "Instances").
  const std::vector<SlaveSpec> firmwares = {
      {5, {}, do4}, {6, {}, nullptr}, {7, {}, cnt2}, {8, {}, do4}};
  EXPECT_EQ(dpc31::bridge::stations_problem(firmwares), "");
  dpc31::bridge::Setup s;
  s.slaves = same_address;
  EXPECT_THROW(Engine(s, {}), std::invalid_argument);
}

}  // namespace
