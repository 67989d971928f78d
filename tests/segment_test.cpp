// A bus segment (docs/segment.md): several chips on one line with the built-in master, driven
// only through the line and the chips' own user sides. Expected cycles come from docs/timing.md:
// an answer's first start bit at the request's end + max(11, MinTSDR) T (MinTSDR_Val resets to
// 11); a request is acted on at the stop sample of its last character (end - T + floor(T/2));
// the DP watchdog expires at that restart + TWD, TWD = ceil(base x WD_Fact_1 x WD_Fact_2 x f).
#include "segment.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "responder.hpp"
#include "scenario_segment.hpp"

namespace dpc31 {
namespace {

constexpr std::uint32_t kBaud = 1'500'000;

// Three chips of the three profiles, each with the minimal user side, and a master.
struct Line {
  explicit Line(std::uint32_t baud = kBaud, std::vector<std::uint8_t> addresses = {5, 6, 7},
                std::uint8_t wd_fact = 1)
      : seg(baud) {
    const Profile profiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31};
    const char* names[] = {"spc3", "vpc3plus", "dpc31"};
    for (std::size_t i = 0; i < addresses.size(); ++i) {
      SlaveConfig sc;
      sc.address = addresses[i];
      sc.wd_fact1 = wd_fact;
      sc.wd_fact2 = wd_fact;
      slaves.push_back(sc);
      ResponderConfig rc;
      rc.slave = sc;
      users.push_back(std::make_unique<Responder>(rc));
      users.back()->inputs = {static_cast<std::uint8_t>(0x10 * (i + 1)), 1, 2, 3};
      ChipOptions opt;
      opt.profile = profiles[i % 3];
      chips.push_back(seg.add_chip(names[i % 3], opt));
      DirectBus bus(seg.chip(chips.back()));
      users.back()->init(bus);
      Responder* r = users.back().get();
      seg.set_firmware(chips.back(), [r](BusPort& b) { r->isr(b); });
    }
    master_station = seg.add_sender("master 2");
    master = std::make_unique<DpMaster>(seg, master_station, MasterConfig{2, baud}, slaves);
  }
  Segment seg;
  std::vector<SlaveConfig> slaves;
  std::vector<std::unique_ptr<Responder>> users;
  std::vector<std::size_t> chips;
  std::size_t master_station = 0;
  std::unique_ptr<DpMaster> master;
};

TEST(Segment, EveryCharacterReachesEveryStationAtTheSameCycle) {
  Segment seg(kBaud);
  std::vector<std::vector<std::pair<std::uint64_t, bool>>> heard(3);
  for (int i = 0; i < 3; ++i) {
    const std::size_t s = seg.add_chip("chip", ChipOptions{});
    seg.chip(s).on_rxd([&heard, i](std::uint64_t c, bool l) { heard[i].emplace_back(c, l); });
  }
  const std::size_t m = seg.add_sender("master");
  const std::vector<std::uint8_t> bytes = fdl::encode(
      fdl::make_frame(9, 2, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
  const std::uint64_t start = 1000;
  const std::uint64_t end = seg.send(m, bytes, start);
  std::vector<std::pair<std::uint64_t, bool>> want;
  uart_encode(bytes, start, seg.bit_cycles(), want);
  EXPECT_EQ(end, start + bytes.size() * 11 * seg.bit_cycles());
  for (const auto& h : heard) EXPECT_EQ(h, want);
}

TEST(Segment, ThreeSlavesReachDataExchangeEachAnswerAtItsTsdr) {
  Line line;
  ASSERT_TRUE(line.master->startup_all());
  const std::vector<Exchange> cycle = line.master->dp_cycle();
  ASSERT_EQ(cycle.size(), 3U);
  const std::uint64_t t = line.seg.bit_cycles();
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(line.seg.chip(line.chips[i]).dp_state(), DpState::Data_Exchange) << i;
    ASSERT_TRUE(cycle[i].answer) << i;
    EXPECT_EQ(cycle[i].answer->sa, line.slaves[i].address);
    // docs/timing.md "answer": end of the request + max(11, MinTSDR) T, MinTSDR_Val = 11.
    EXPECT_EQ(cycle[i].answer_start, cycle[i].request_end + 11 * t) << i;
    // The inputs the user side handed over.
    EXPECT_EQ(cycle[i].answer->du[0], 0x10 * (i + 1)) << i;
  }
  EXPECT_TRUE(line.seg.collisions().empty());
  // Each slave ignored the others' requests (counted, not served).
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_GT(line.seg.chip(line.chips[i]).fdl_counters().foreign_address, 0U) << i;
  }
}

TEST(Segment, AnUnpolledSlavesWatchdogExpiresAtItsCycleTheOthersStay) {
  Line line;
  ASSERT_TRUE(line.master->startup_all());
  line.master->dp_cycle();
  // Stop polling the dpc31 (station 2): its last request from Master_Add restarted its DP
  // watchdog at that request's acted-on cycle.
  const Exchange last = line.master->history().back();
  ASSERT_EQ(last.request.da, 7);
  const std::uint64_t t = line.seg.bit_cycles();
  const std::uint64_t restart = last.request_end - t + t / 2;
  // WD_Fact_1 = WD_Fact_2 = 1, base 10 ms: TWD = 10 ms x 48 MHz.
  const std::uint64_t twd = 480'000;
  Chip& dpc31 = line.seg.chip(line.chips[2]);
  EXPECT_EQ(dpc31.watchdog_due(), restart + twd);
  while (line.seg.cycle() < restart + twd + 10 * t) {
    line.master->select(0);
    line.master->data_exchange({0, 0, 0, 0});
    line.master->select(1);
    line.master->data_exchange({0, 0, 0, 0});
  }
  EXPECT_EQ(dpc31.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(dpc31.wd_state(), WdState::Baud_Control);
  EXPECT_EQ(line.seg.chip(line.chips[0]).dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(line.seg.chip(line.chips[1]).dp_state(), DpState::Data_Exchange);
}

TEST(Segment, TwoSlavesOnOneAddressCollideWithBothNamesAndTheCycle) {
  Line line(kBaud, {5, 5});
  std::vector<Collision> seen;
  line.seg.on_collision = [&seen](const Collision& c) { seen.push_back(c); };
  // FDL_Status until both have found the rate (their baud search) and answer at once.
  Exchange ex;
  for (int i = 0; i < kStartupTries && line.seg.collisions().empty(); ++i)
    ex = line.master->fdl_status();
  ASSERT_EQ(line.seg.collisions().size(), 1U);
  const Collision& c = line.seg.collisions()[0];
  // Both answer at the request's end + 11 T (docs/timing.md): the second drives into the first.
  EXPECT_EQ(c.cycle, ex.request_end + 11 * line.seg.bit_cycles());
  EXPECT_EQ(line.seg.name(c.first), "spc3");
  EXPECT_EQ(line.seg.name(c.second), "vpc3plus");
  EXPECT_EQ(seen.size(), 1U);
}

TEST(Segment, TwoMastersPassTheTokenAndReachDataExchangeWithASlaveEach) {
  Segment seg(kBaud);
  std::vector<std::unique_ptr<Responder>> users;
  std::vector<std::size_t> chips;
  std::vector<SlaveConfig> sc(2);
  sc[0].address = 5;
  sc[1].address = 6;
  for (int i = 0; i < 2; ++i) {
    ResponderConfig rc;
    rc.slave = sc[i];
    users.push_back(std::make_unique<Responder>(rc));
    chips.push_back(seg.add_chip(i == 0 ? "spc3" : "dpc31",
                                 ChipOptions{i == 0 ? Profile::spc3 : Profile::dpc31}));
    DirectBus bus(seg.chip(chips.back()));
    users.back()->init(bus);
    Responder* r = users.back().get();
    seg.set_firmware(chips.back(), [r](BusPort& b) { r->isr(b); });
  }
  const std::size_t s2 = seg.add_sender("master 2");
  const std::size_t s3 = seg.add_sender("master 3");
  DpMaster m2(seg, s2, MasterConfig{2, kBaud}, {sc[0]});
  DpMaster m3(seg, s3, MasterConfig{3, kBaud}, {sc[1]});
  std::vector<LineTelegram> tokens;
  seg.on_telegram = [&tokens](const LineTelegram& t) {
    if (!t.bytes.empty() && t.bytes[0] == fdl::SD4) tokens.push_back(t);
  };
  // Each master in turn: its slave's start-up, then the token to the other.
  ASSERT_TRUE(m2.startup());
  m2.pass_token(3);
  ASSERT_TRUE(m3.wait_token(1000 * seg.bit_cycles()));
  ASSERT_TRUE(m3.startup());
  m3.pass_token(2);
  ASSERT_TRUE(m2.wait_token(1000 * seg.bit_cycles()));
  m2.dp_cycle();
  m2.pass_token(3);
  ASSERT_TRUE(m3.wait_token(1000 * seg.bit_cycles()));
  m3.dp_cycle();
  seg.flush();
  EXPECT_EQ(seg.chip(chips[0]).dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(seg.chip(chips[1]).dp_state(), DpState::Data_Exchange);
  ASSERT_EQ(tokens.size(), 3U);
  EXPECT_EQ(tokens[0].bytes, (std::vector<std::uint8_t>{fdl::SD4, 3, 2}));
  EXPECT_EQ(tokens[0].from, s2);
  EXPECT_EQ(tokens[1].from, s3);
  // TRR of master 3: from its first token's end to its second's.
  EXPECT_EQ(m3.token_rotation(), tokens[2].end - tokens[0].end);
  EXPECT_TRUE(seg.collisions().empty());
}

}  // namespace
}  // namespace dpc31

namespace dpc31 {
namespace {

// Bad input in a segment scenario: one line, FILE:LINE, nothing run (docs/bad-input.md).
TEST(SegmentScenario, BadLinesAreOneErrorWithTheirLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"segment\nstation 5\nbogus 3\n", "f.scn:3: unknown command 'bogus'"},
      {"station 5\n", "f.scn:1: a segment scenario begins with 'segment'"},
      {"segment\nstation 5 firmware=DO4\nstation 6 firmware=./libmine.so\n",
       "f.scn:3: a segment station runs a built-in firmware"},
      {"segment\nstation 5\nexpect state 9 Data_Exchange\n", "f.scn:3: no station 9"},
      {"segment\nstation 5\nstartup\nstation 6\n", "f.scn:4: 'station' after the first action"},
  };
  for (const auto& [text, want] : cases) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_FALSE(parse_segment_scenario(text, "f.scn", s, err)) << text;
    EXPECT_EQ(err.text(), want);
  }
  EXPECT_TRUE(is_segment_scenario("# a comment\n\nsegment baud=12000000\n"));
  EXPECT_FALSE(is_segment_scenario("profile spc3\n"));
}

}  // namespace
}  // namespace dpc31
