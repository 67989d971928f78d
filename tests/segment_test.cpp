// A bus segment (docs/segment.md): several chips on one line with the built-in master, driven
// only through the line and the chips' own user sides. Expected cycles come from docs/timing.md:
// an answer's first start bit at the request's end + max(11, MinTSDR) T (MinTSDR_Val resets to
// 11); a request is acted on at the stop sample of its last character (end - T + floor(T/2));
// the DP watchdog expires at that restart + TWD, TWD = ceil(base x WD_Fact_1 x WD_Fact_2 x f).
#include "segment.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <typeinfo>
#include <vector>

#include "bus_check.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "heap_in_use.hpp"
#include "responder.hpp"
#include "scenario_segment.hpp"
#include "vocabulary.hpp"

namespace dpc31 {
namespace {

constexpr std::uint32_t kBaud = 1'500'000;

// Three chips of the three profiles, each with the minimal user side, and a master.
struct Line {
  explicit Line(std::uint32_t baud = kBaud, std::vector<std::uint8_t> addresses = {5, 6, 7},
                std::uint8_t wd_fact = 1, bool reference_line = false)
      : seg(baud) {
    seg.use_reference_line(reference_line);
    const Profile profiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31};
    const char* names[] = {"spc3", "vpc3plus", "dpc31"};
    for (std::size_t i = 0; i < addresses.size(); ++i) {
      SlaveConfig sc;
      sc.address = addresses[i];
      sc.wd_fact1 = wd_fact;
      sc.wd_fact2 = wd_fact;
      // The master polls an address once; two chips on one address collide (a test below).
      if (std::none_of(slaves.begin(), slaves.end(),
                       [&sc](const SlaveConfig& s) { return s.address == sc.address; }))
        slaves.push_back(sc);
      ResponderConfig rc;
      rc.slave = sc;
      users.push_back(std::make_unique<Responder>(rc));
      users.back()->set_inputs({static_cast<std::uint8_t>(0x10 * (i + 1)), 1, 2, 3});
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

// What a sender hears of another's good telegram (Segment::take_line): its characters whole from
// their start bits, as far as those are on the line, back to back, the rest at a later look; a
// pulse of the telegram's sender inside it (no collision: the line is its own) between the two
// characters around it, as edges.
struct TakenRun {
  std::vector<std::uint8_t> bytes;
  std::uint64_t start = 0;
  std::vector<std::pair<std::uint64_t, bool>> edges;
  bool operator==(const TakenRun&) const = default;
};

std::vector<TakenRun> heard_by(Segment& seg, std::size_t listener) {
  std::vector<TakenRun> got;
  seg.take_line(listener, [&got](const TxdRun& r) {
    got.push_back({{r.bytes.begin(), r.bytes.end()}, r.start, {r.edges.begin(), r.edges.end()}});
  });
  return got;
}

const std::vector<std::uint8_t> kDataExchange = fdl::encode(fdl::make_frame(
    9, 2, fdl::make_request_fc(fdl::Function::SRD_high, true, true), {1, 2, 3, 4, 5, 6, 7, 8}));

// A Data_Exchange request sent by "a" from cycle 1000 on a segment where "b" listens.
struct SentDataExchange {
  Segment seg{kBaud};
  std::size_t a = seg.add_sender("a");
  std::size_t b = seg.add_sender("b");
  std::uint64_t t = seg.bit_cycles();
  std::uint64_t frame = 11 * t;
  std::uint64_t start = 1000;
  const std::vector<std::uint8_t>& bytes = kDataExchange;
  std::uint64_t end = seg.send(a, bytes, start);
};

TEST(Segment, ASenderTakesACharacterOnceItsStartBitIsOnTheLine) {
  SentDataExchange x;
  auto& [seg, a, b, t, frame, start, bytes, end] = x;
  seg.run_until(start + 4 * frame);  // the fifth character's start bit
  EXPECT_EQ(heard_by(seg, b),
            (std::vector<TakenRun>{{{bytes.begin(), bytes.begin() + 5}, start, {}}}));
  seg.run_until(start + 4 * frame + frame / 2);
  EXPECT_TRUE(heard_by(seg, b).empty());
  seg.pulse(a, end + 20 * t, 3 * t);
  seg.run_until(end + 30 * t);
  EXPECT_EQ(heard_by(seg, b),
            (std::vector<TakenRun>{{{bytes.begin() + 5, bytes.end()}, start + 5 * frame, {}},
                                   {{}, 0, {{end + 20 * t, false}, {end + 23 * t, true}}}}));
}

TEST(Segment, APulseInsideATelegramIsHeardBetweenItsCharacters) {
  SentDataExchange x;
  auto& [seg, a, b, t, frame, start, bytes, end] = x;
  const std::uint64_t pulse = start + 5 * frame + 3 * t;  // inside the sixth character
  seg.pulse(a, pulse, 2 * t);
  seg.run_until(end);
  EXPECT_EQ(heard_by(seg, b),
            (std::vector<TakenRun>{{{bytes.begin(), bytes.begin() + 6}, start, {}},
                                   {{}, 0, {{pulse, false}, {pulse + 2 * t, true}}},
                                   {{bytes.begin() + 6, bytes.end()}, start + 6 * frame, {}}}));
}

// A sender's telegram before the cycle the chips stand at (a user side ran one ahead with its
// own steps; the line brings the others there first) breaks the line's order: thrown with the
// sender's name, the first chip's and both cycles, never heard late.
// A low of 12 bit times from S (a break): the start bit and the eight data bits read low, parity
// and stop bit too (a framing error). The line's telegram holds the character as its data bits
// read (segment.hpp, LineTelegram: 0x00), from S for one character time (11 bit times). The
// receiver ends it only at the rise (its stop sample lay before): the line's decoder must hand a
// character it holds while it receives nothing more (Segment::close_telegrams).
TEST(Segment, ABreakIsOneBrokenCharacterOnTheLine) {
  Segment seg(1500000);
  const std::size_t noise = seg.add_sender("noise");
  std::vector<LineTelegram> got;
  seg.on_telegram = [&got](const LineTelegram& tg) { got.push_back(tg); };
  const std::uint64_t t = seg.bit_cycles();
  const std::uint64_t s = 100 * t;
  seg.pulse(noise, s, 12 * t);
  seg.run_until(s + 40 * t);
  seg.flush();
  ASSERT_EQ(got.size(), 1U);
  EXPECT_EQ(got[0].from, noise);
  EXPECT_EQ(got[0].bytes, (std::vector<std::uint8_t>{0x00}));
  EXPECT_EQ(got[0].start, s);
  EXPECT_EQ(got[0].end, s + 11 * t);
}

TEST(Segment, ASendBeforeTheChipsCycleThrowsWithBothNames) {
  Segment seg(kBaud);
  (void)seg.add_chip("slave a", ChipOptions{});
  const std::size_t b = seg.add_chip("slave b", ChipOptions{});
  const std::size_t m = seg.add_sender("master");
  seg.chip(b).step(5000);
  const std::vector<std::uint8_t> token{fdl::SD4, 9, 2};
  try {
    seg.send(m, token, 1000);
    ADD_FAILURE() << "no exception";
  } catch (const std::logic_error& e) {
    // The chip stepped past the start; slave a, without an event, stays where it stood.
    EXPECT_STREQ(e.what(), "segment: master sends at cycle 1000, slave b is at cycle 5000");
  }
}

// The chips find only the PROFIBUS rates (docs/timing.md, "Baud_Search"): a segment at another
// would have nobody answer; refused at every door (the scenario's `segment baud=`, Python's
// Segment(baud), this constructor) with one message.
TEST(Segment, ALineAtARateNoChipFindsIsRefused) {
  try {
    Segment seg(12345);
    ADD_FAILURE() << "a segment at 12345 baud";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "baud 12345 is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, 500000, "
                 "1500000, 3000000, 6000000, 12000000)");
  }
  for (const std::uint32_t b : {9600u, 45450u, 12000000u}) EXPECT_NO_THROW(Segment{b}) << b;
}

// Only a sender drives the line with send() and pulse(): no station, a chip's, and a telegram
// that would end past the last cycle (its end wrapped) are refused with a line, the line untouched.
TEST(Segment, ASendOrPulseNeedsASenderAndAnEndBeforeTheLastCycle) {
  Segment seg(kBaud);
  const std::size_t chip = seg.add_chip("slave a", ChipOptions{});
  const std::size_t m = seg.add_sender("master");
  const std::vector<std::uint8_t> token{fdl::SD4, 9, 2};
  const auto message = [](auto f) {
    try {
      f();
    } catch (const std::exception& e) {
      return std::string(typeid(e) == typeid(std::out_of_range) ? "out_of_range: " : "") + e.what();
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message([&] { seg.send(7, token, 1000); }),
            "out_of_range: station 7: the segment has 2 stations");
  EXPECT_EQ(message([&] { seg.pulse(7, 1000, 10); }),
            "out_of_range: station 7: the segment has 2 stations");
  EXPECT_EQ(message([&] { seg.send(chip, token, 1000); }),
            "station 0 (slave a) is a chip: its chip drives the line, send from a sender "
            "(add_sender)");
  EXPECT_EQ(message([&] { seg.send(m, token, UINT64_MAX - 1); }),
            "start 18446744073709551614: 1056 cycles from there end past the last cycle "
            "(4611686018427387903)");
  EXPECT_EQ(message([&] { seg.pulse(m, 1000, UINT64_MAX - 1000); }),
            "start 1000: 18446744073709550615 cycles from there end past the last cycle "
            "(4611686018427387903)");
  EXPECT_EQ(seg.cycle(), 0u);
  EXPECT_EQ(seg.send(m, token, 1000), 1000 + 3 * 11 * seg.bit_cycles());
}

// A segment's master keeps one FCB state per slave (EN 50170: the FCB alternates per station), so
// it polls each at most once a cycle: an empty list or an address twice is refused.
TEST(Segment, AMastersSlavesAreAtLeastOneAndEachOnce) {
  Segment seg(kBaud);
  const std::size_t m = seg.add_sender("master");
  SlaveConfig a;
  a.address = 5;
  SlaveConfig b;
  b.address = 6;
  const auto message = [&](std::vector<SlaveConfig> slaves) {
    try {
      DpMaster master(seg, m, MasterConfig{2, kBaud}, std::move(slaves));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message({}), "DpMaster: a master needs at least one slave");
  EXPECT_EQ(message({a, b, a}), "DpMaster: slave 5 is listed twice (a slave has one FCB)");
  EXPECT_EQ(message({a, b}), "no exception");
}

// The master's next request follows TSYN after the answer's last stop bit (docs/decisions.md:
// TSYN, 33 bit times, before every request), whatever the answer's characters are: between two
// characters of an answer the line is its sender's, and no start bit inside it wakes the master,
// who must not sleep to the slot time's end there (it did where a firmware's main loop ran, its
// rounds ending at the line's stop samples: after a one-character SD1 length, 12 bit times
// late). At both line modes and both rates the bench runs.
TEST(Segment, TheNextRequestFollowsTsynAfterTheAnswersEnd) {
  for (const std::uint32_t baud : {kBaud, 12'000'000u}) {
    for (const bool reference : {false, true}) {
      Line line(baud, {5, 6, 7}, 1, reference);
      // The third slave's firmware polls in its main loop: it runs in every round.
      Cpu::Program p;
      Responder* r = line.users[2].get();
      p.isr = [r](BusPort& b) { r->isr(b); };
      p.main_step = [](BusPort& b) { (void)b.read(0x00); };
      line.seg.set_firmware(line.chips[2], std::move(p));
      const std::uint64_t t = line.seg.bit_cycles();
      ASSERT_TRUE(line.master->startup_all());
      line.master->select(1);
      const Exchange a = line.master->fdl_status();  // answered with SD1: 6 characters
      ASSERT_TRUE(a.answer) << baud << " " << reference;
      EXPECT_EQ(a.answer_end, a.answer_start + 6 * 11 * t);
      const Exchange b = line.master->fdl_status();
      EXPECT_EQ(b.request_start, a.answer_end + 33 * t) << baud << " " << reference;
      const std::vector<Exchange> cycle = line.master->dp_cycle();
      for (std::size_t i = 1; i < cycle.size(); ++i) {
        ASSERT_TRUE(cycle[i - 1].answer);
        EXPECT_EQ(cycle[i].request_start, cycle[i - 1].answer_end + 33 * t)
            << baud << " " << reference << " " << i;
      }
    }
  }
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

// dp_cycle(outputs, out) reuses out's exchanges (their data units, the answers' frames): what it
// leaves there is what dp_cycle(outputs) returns, also where an answer follows none, none follows
// one, or other inputs follow.
TEST(Segment, ADpCycleIntoAKeptVectorIsTheReturnedOne) {
  Line returned;
  Line kept;
  ASSERT_TRUE(returned.master->startup_all());
  ASSERT_TRUE(kept.master->startup_all());
  std::vector<Exchange> out;
  for (int n = 0; n < 5; ++n) {
    // Cycle 1 sends slave 6's requests to address 9 (no answer), cycle 2 back to 6; slave 7's
    // user hands over other inputs from cycle 2 on (the answers carry them a cycle later).
    for (Line* l : {&returned, &kept}) {
      l->master->select(1);
      l->master->set_target(n == 1 ? 9 : 6);
      l->master->select(0);
      if (n == 2) l->users[2]->set_inputs({0x77, 7, 7, 7});
    }
    const auto b = static_cast<std::uint8_t>(n);
    const std::vector<std::vector<std::uint8_t>> outputs = {{b, 0, 0, 0}, {0, b, 0, 0}};
    const std::vector<Exchange> want = returned.master->dp_cycle(outputs);
    kept.master->dp_cycle(outputs, out);
    ASSERT_EQ(out.size(), want.size());
    EXPECT_EQ(want[1].answer.has_value(), n != 1);
    ASSERT_TRUE(want[2].answer);
    EXPECT_EQ(want[2].answer->du.at(0), n < 3 ? 0x30 : 0x77) << n;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(out[i].request, want[i].request) << n << " " << i;
      EXPECT_EQ(out[i].request_start, want[i].request_start) << n << " " << i;
      EXPECT_EQ(out[i].request_end, want[i].request_end) << n << " " << i;
      EXPECT_EQ(out[i].answer, want[i].answer) << n << " " << i;
      EXPECT_EQ(out[i].answer_start, want[i].answer_start) << n << " " << i;
      EXPECT_EQ(out[i].answer_end, want[i].answer_end) << n << " " << i;
    }
  }
  // An exception midway (slave 6's outputs over DP's 244 bytes, refused before they go out):
  // `out` holds this cycle's exchange with slave 5 alone, nothing of the cycle before.
  const std::vector<std::vector<std::uint8_t>> too_long = {{9, 0, 0, 0},
                                                           std::vector<std::uint8_t>(245)};
  EXPECT_THROW(kept.master->dp_cycle(too_long, out), std::invalid_argument);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].request.du.at(0), 9);
  // More outputs than slaves: refused before any exchange, so `out` holds none.
  EXPECT_THROW(kept.master->dp_cycle(std::vector<std::vector<std::uint8_t>>(4), out),
               std::invalid_argument);
  EXPECT_TRUE(out.empty());
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

// The audit's lb.scn on both lines: a scripted Set_Prm (SA 2, Lock_Req, min TSDR FFh) gives
// station 5 a min TSDR of 255 bit times, beyond the slot time (100): its answers are late and
// collide with what comes next. docs/segment.md "Collisions": the first driver keeps the line, the
// collision is reported, the run goes on; the telegram-level line is the reference line (until the
// thirtieth session it threw "line order broken" unless an on_line observer was attached).
struct LateSlave {
  std::vector<Collision> collisions;
  std::vector<std::string> line;  // every telegram of the line
  std::vector<std::vector<Exchange>> cycles;
};
LateSlave late_slave(bool reference) {
  Line l(kBaud, {5, 6}, 1, reference);
  const std::size_t rogue = l.seg.add_sender("rogue");
  LateSlave out;
  l.seg.on_telegram = [&](const LineTelegram& t) {
    out.line.push_back(fmt::format("{} {}..{} {:02X}", l.seg.name(t.from), t.start, t.end,
                                   fmt::join(t.bytes, " ")));
  };
  EXPECT_TRUE(l.master->startup_all());
  // lb.scn's Set_Prm without its user parameter byte (Line's slaves have none), FCB 1 (FC 7Dh:
  // the start-up's last request to 5, Slave_Diag, had FCB 0), FCS 20h more.
  const std::vector<std::uint8_t> set_prm{0x68, 0x0C, 0x0C, 0x68, 0x85, 0x82, 0x7D, 0x3D, 0x3E,
                                          0x88, 0x0A, 0x0A, 0xFF, 0x0C, 0x31, 0x00, 0xD7, 0x16};
  // After TSYN from the end of the last answer (the master returned inside its stop bit).
  const std::uint64_t end = l.seg.send(rogue, set_prm, l.seg.cycle() + 40 * l.seg.bit_cycles());
  l.seg.run_until(end + 1500 * l.seg.bit_cycles());  // 1 ms
  EXPECT_TRUE(l.seg.collisions().empty());
  for (int i = 0; i < 3; ++i) out.cycles.push_back(l.master->dp_cycle());
  l.seg.run_until(l.seg.cycle() + 1500 * l.seg.bit_cycles());
  l.seg.flush();
  out.collisions = l.seg.collisions();
  return out;
}

TEST(Segment, ASlaveAnsweringAfterTheSlotTimeCollidesAndTheLineGoesOnOnBothLines) {
  const LateSlave fast = late_slave(false);
  const LateSlave ref = late_slave(true);
  const std::uint64_t t = 32;  // clocks a bit at 1.5 Mbaud
  ASSERT_EQ(fast.cycles.size(), 3U);
  ASSERT_FALSE(fast.collisions.empty()) << fmt::format("{}", fmt::join(fast.line, "\n"));
  // Station 5's answer to the first Data_Exchange starts 255 T after the request's end, inside
  // the master's next request (to 6: TSL + TSYN = 133 T after that end, 13 characters of 11 T):
  // the master keeps the line, station 5 (spc3, station 0) drove into it.
  const Exchange& first = fast.cycles[0][0];
  EXPECT_FALSE(first.answer);
  EXPECT_EQ(fast.cycles[0][1].request_start, first.request_end + 133 * t);
  EXPECT_EQ(fast.collisions[0].cycle, first.request_end + 255 * t);
  EXPECT_EQ(fast.collisions[0].first, 2U);  // master 2 (after spc3, vpc3plus)
  EXPECT_EQ(fast.collisions[0].second, 0U);
  ASSERT_EQ(fast.collisions.size(), ref.collisions.size());
  for (std::size_t i = 0; i < fast.collisions.size(); ++i) {
    EXPECT_EQ(fast.collisions[i].cycle, ref.collisions[i].cycle) << i;
    EXPECT_EQ(fast.collisions[i].first, ref.collisions[i].first) << i;
    EXPECT_EQ(fast.collisions[i].second, ref.collisions[i].second) << i;
  }
  EXPECT_EQ(fast.line, ref.line);
  for (std::size_t c = 0; c < 3; ++c) {
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(fast.cycles[c][i].request_end, ref.cycles[c][i].request_end) << c << " " << i;
      EXPECT_EQ(fast.cycles[c][i].answer_start, ref.cycles[c][i].answer_start) << c << " " << i;
      EXPECT_EQ(fast.cycles[c][i].wait_end, ref.cycles[c][i].wait_end) << c << " " << i;
    }
  }
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

// The token's visits (docs/segment.md, "The token"; IEC 61158-4-3 / EN 50170 part 2): a master
// alone on the line passes the token to itself, so each visit's TRR is from the end of one SD4 to
// the end of the next. The cycles of a visit, by hand at 1.5 Mbaud (T = 32 clocks): a
// Data_Exchange of 4 bytes out and 4 in is a 13-character request (SD2, LE 7: 143 T), the answer
// MinTSDR = 11 T after it (the chips' MinTSDR_Val resets to 11), 13 characters (143 T): 297 T
// from its request's first start bit to the answer's end; every request and token follows TSYN =
// 33 T after the telegram before; the token is 3 characters (33 T). So from a token's arrival A,
// the n-th cycle of the visit starts at A + 33 T + 330 T x n, and the token after k cycles ends at
// A + 330 T x k + 66 T.
// The master at 2 with TTR, G and HSA as given starts its slaves up (watchdog 100 x 100 x 10 ms:
// never expiring here), then passes the token to itself: `a0` is that SD4's end.
struct TokenRing {
  TokenRing(std::uint64_t ttr_bits, std::uint8_t gap_factor, std::vector<std::uint8_t> addresses)
      : line(kBaud, std::move(addresses), 100), t(line.seg.bit_cycles()) {
    MasterConfig cfg{2, kBaud};
    cfg.ttr_bits = ttr_bits;
    cfg.gap_factor = gap_factor;
    cfg.hsa = 8;
    line.master = std::make_unique<DpMaster>(line.seg, line.master_station, cfg, line.slaves);
    line.seg.on_telegram = [this](const LineTelegram& tg) {
      if (tg.from == line.master_station) sent.push_back(tg);
    };
    EXPECT_TRUE(master().startup_all());
    master().pass_token(2);
    a0 = since(0).back().end;
  }
  DpMaster& master() { return *line.master; }
  // The master's requests from cycle `from` on (tokens included).
  std::vector<LineTelegram> since(std::uint64_t from) {
    line.seg.flush();
    std::vector<LineTelegram> out;
    for (const LineTelegram& t : sent) {
      if (t.start >= from) out.push_back(t);
    }
    return out;
  }
  Line line;
  std::uint64_t t;  // bit time in clocks
  std::vector<LineTelegram> sent;
  std::uint64_t a0 = 0;
};

// TTR = 1000 bit times, three slaves. Visit 1 (TRR 0: TTH = TTR): cycles at 33, 363, 693 T, all
// under 1000: slaves 0, 1, 2; token end A + 1056 T. Visit 2: TRR 1056 T >= TTR, a late token:
// one cycle (slave 0); token end + 396 T. Visit 3: TRR 396 T, TTH 604 T: 33 and 363 T start, 693
// T does not: slaves 1 and 2; token end + 726 T. Visit 4: TRR 726 T, TTH 274 T: the first cycle
// (slave 0) only. Visit 5: TRR 396 T again: slaves 1 and 2.
TEST(Segment, AMasterStartsCyclesOnlyWhileTheRotationIsUnderTtr) {
  TokenRing ring(1000, 0, {5, 6, 7});
  DpMaster& m = ring.master();
  const std::uint64_t t = ring.t;
  const std::vector<std::vector<std::size_t>> polled = {{0, 1, 2}, {0}, {1, 2}, {0}, {1, 2}};
  const std::uint64_t rotation[] = {0, 1056, 396, 726, 396};
  const std::uint64_t hold[] = {1000, 0, 604, 274, 604};
  std::uint64_t arrived = ring.a0;
  for (std::size_t k = 0; k < polled.size(); ++k) {
    const TokenVisit v = m.use_token(2);
    arrived += rotation[k] * t;
    EXPECT_EQ(v.arrived, arrived) << k;
    EXPECT_EQ(v.rotation, rotation[k] * t) << k;
    EXPECT_EQ(v.hold, hold[k] * t) << k;
    EXPECT_EQ(v.polled, polled[k]) << k;
    const std::vector<LineTelegram> visit = ring.since(arrived);
    ASSERT_EQ(visit.size(), polled[k].size() + 1) << k;
    for (std::size_t n = 0; n < polled[k].size(); ++n) {
      EXPECT_EQ(visit[n].start, arrived + (33 + 330 * n) * t) << k << " " << n;
      EXPECT_EQ(visit[n].bytes[4], ring.line.slaves[polled[k][n]].address) << k << " " << n;
    }
    EXPECT_EQ(visit.back().bytes, (std::vector<std::uint8_t>{fdl::SD4, 2, 2})) << k;
    EXPECT_EQ(visit.back().end, arrived + (330 * polled[k].size() + 66) * t) << k;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(ring.line.seg.chip(ring.line.chips[i]).dp_state(), DpState::Data_Exchange) << i;
  }
}

// G = 2, HSA 8, no TTR (every visit polls both slaves 5 and 6): the GAP of a master alone at 2 is
// 3..8, 0, 1. Every second visit asks one address with FDL_Status (10 DA 02 49 FCS 16) after the
// two cycles, at A + 693 T: 3 and 4 (nobody: the slot time, 100 T, then TSYN and the token: token
// end A + 925 T), then 5 and 6 (answered 11 T after the request, 6 characters: token end A + 902
// T). Without a GAP poll the token ends at A + 726 T.
TEST(Segment, EveryGRotationsTheMasterAsksOneGapAddress) {
  TokenRing ring(0, 2, {5, 6});
  DpMaster& m = ring.master();
  const std::uint64_t t = ring.t;
  std::uint64_t arrived = ring.a0;
  const std::optional<std::uint8_t> gap[] = {std::nullopt, 3, std::nullopt, 4,
                                             std::nullopt, 5, std::nullopt, 6};
  for (std::size_t k = 0; k < std::size(gap); ++k) {
    const TokenVisit v = m.use_token(2);
    EXPECT_EQ(v.arrived, arrived) << k;
    EXPECT_EQ(v.gap, gap[k]) << k;
    EXPECT_EQ(v.gap_answered, gap[k] && *gap[k] >= 5) << k;
    const std::vector<LineTelegram> visit = ring.since(arrived);
    ASSERT_EQ(visit.size(), gap[k] ? 4U : 3U) << k;
    if (gap[k]) {
      const std::uint8_t a = *gap[k];
      EXPECT_EQ(visit[2].bytes,
                (std::vector<std::uint8_t>{fdl::SD1, a, 2, 0x49,
                                           static_cast<std::uint8_t>(a + 2 + 0x49), fdl::ED}))
          << k;
      EXPECT_EQ(visit[2].start, arrived + 693 * t) << k;
    }
    arrived += (gap[k] ? (*gap[k] >= 5 ? 902 : 925) : 726) * t;
    EXPECT_EQ(visit.back().end, arrived) << k;
  }
}

// G = 1 under TTR = 1100 (slaves 5, 6): the GAP update is a low-priority job done only while the
// token hold time lasts. Visit 1 (TTH 1100 T): cycles at 33 and 363 T, FDL_Status to 3 at 693 T
// (no answer: token end A + 925 T). Visit 2: TRR 925 T, TTH 175 T: slave 0 at 33 T; slave 1 and
// the GAP at 363 T do not start; token end + 396 T. Visit 3: TRR 396 T, TTH 704 T: slave 1 at 33,
// slave 0 at 363, the postponed GAP poll (address 4) at 693 T.
TEST(Segment, TheGapUpdateWaitsForTokenHoldTime) {
  TokenRing ring(1100, 1, {5, 6});
  DpMaster& m = ring.master();
  const std::uint64_t t = ring.t;
  const TokenVisit v1 = m.use_token(2);
  const TokenVisit v2 = m.use_token(2);
  const TokenVisit v3 = m.use_token(2);
  EXPECT_EQ(v1.polled, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(v1.gap, std::optional<std::uint8_t>(3));
  EXPECT_EQ(v2.rotation, 925 * t);
  EXPECT_EQ(v2.hold, 175 * t);
  EXPECT_EQ(v2.polled, (std::vector<std::size_t>{0}));
  EXPECT_EQ(v2.gap, std::nullopt);
  EXPECT_EQ(v3.rotation, 396 * t);
  EXPECT_EQ(v3.polled, (std::vector<std::size_t>{1, 0}));
  EXPECT_EQ(v3.gap, std::optional<std::uint8_t>(4));
  EXPECT_EQ(ring.since(v3.arrived)[2].start, v3.arrived + 693 * t);
}

// The start-up under TTR (docs/segment.md, "The start-up under TTR"): a master alone at 2 with TTR
// 500 bit times brings slaves 5 (SPC3) and 6 (VPC3+) up over its visits, startup_all's requests
// in its order, each a message cycle by the rule of a DP cycle. By hand, at 1.5 Mbaud (T = 32
// clocks), times in T from the claim A1 (the line's time when the master is made, after the
// responders' inits):
// - Baud_Search (docs/timing.md): the chips' 1.5 Mbaud windows open 3 x 20 ms = 90 000 T after
//   their Start, which ends their init, at or before A1 and less than 6.25 T (200 clocks) before
//   it; a request is heard there when it starts at least TSYN = 33 T after the opening: one that
//   starts before 90 033 T is not, one that starts from 90 039 T on is.
// - Until then every FDL_Status to 5 (6 characters, 66 T) goes unanswered: the slot time (100 T)
//   and TSYN follow, so a visit's n-th request starts at A + 33 + 199 n and after k of them the
//   token (33 T after the slot, 3 characters) ends at A + 199 k + 66. Visit 1 (TRR 0, TTH 500):
//   33, 232, 431 (630 is not < 500): A2 = 663. Visit 2 (TRR 663: late): one request, A3 = 928.
//   Visit 3 (TRR 265, TTH 235): 33 and 232: A4 = A3 + 464. Visit 4 (TRR 464, TTH 36): one:
//   A5 = A4 + 265. From there on visits 3 + 2j arrive at 928 + 729 j (two requests) and 4 + 2j
//   at 1392 + 729 j (one).
// - The first request from 90 033 T on: 1160 + 729 x 122 = 90 098 (the second of visit 247,
//   A = 89 866; the one before, 89 899, is early). Answered 11 T after its end: 90 175 to 90 241;
//   the next would start at 90 274 >= A + 235: the token ends at 90 307 = A248.
// - Then one request a visit, each too long for a second (Slave_Diag 11 characters, its answer 17
//   (6 diag bytes); Set_Prm 19 (8 data bytes), Chk_Cfg 13, each answered SC (1 character);
//   FDL_Status answered 6 + 6): visit 248 (TRR 441, TTH 59) Slave_Diag to 5 (Prm_Req), 249 (TRR
//   418, TTH 82) Set_Prm, 250 (TRR 330, TTH 170) Chk_Cfg, 251 (TRR 264, TTH 236) Slave_Diag: ready;
//   252 (TRR 418) FDL_Status to 6, answered (its rate found with 5's); 253 (TRR 242, TTH 258)
//   Slave_Diag, 254 Set_Prm, 255 Chk_Cfg, 256 Slave_Diag: ready. Each request starts at its A + 33.
TEST(Segment, AMasterUnderTtrSpreadsItsStartupOverItsVisits) {
  Line line(kBaud, {5, 6}, 100);
  MasterConfig cfg{2, kBaud};
  cfg.ttr_bits = 500;
  line.master = std::make_unique<DpMaster>(line.seg, line.master_station, cfg, line.slaves);
  BusCheck check(BusTiming{line.seg.bit_cycles(), 11, 100, 33, 500, {2}});
  std::vector<LineTelegram> sent;
  line.seg.on_telegram = [&](const LineTelegram& tg) {
    check.telegram(tg);
    if (tg.from == line.master_station) sent.push_back(tg);
  };
  const std::uint64_t t = line.seg.bit_cycles();
  const std::uint64_t a1 = line.seg.cycle();
  ASSERT_LE(a1, 200U);
  DpMaster& m = *line.master;
  m.begin_startup();
  std::vector<TokenVisit> visits;
  while (m.starting_up()) visits.push_back(m.use_token(2));
  line.seg.run_until(line.seg.cycle() + 200 * t);
  line.seg.flush();
  ASSERT_TRUE(m.started_up());
  ASSERT_EQ(visits.size(), 256U);
  // Each visit's arrival and TRR (k counted from 1), and its requests' slaves.
  std::vector<std::uint64_t> arrived = {0, 663};
  for (std::uint64_t j = 0; j < 123; ++j) {
    arrived.push_back(928 + 729 * j);
    if (j < 122) arrived.push_back(1392 + 729 * j);
  }
  for (const std::uint64_t a : {90307, 90725, 91055, 91319, 91737, 91979, 92397, 92727, 92991}) {
    arrived.push_back(a);
  }
  ASSERT_EQ(arrived.size(), visits.size());
  std::size_t next = 0;  // the master's telegrams, in order
  for (std::size_t k = 0; k < visits.size(); ++k) {
    const TokenVisit& v = visits[k];
    const std::uint64_t a = arrived[k];
    EXPECT_EQ(v.arrived, a1 + a * t) << k + 1;
    EXPECT_EQ(v.rotation, k == 0 ? 0 : (a - arrived[k - 1]) * t) << k + 1;
    EXPECT_EQ(v.hold, v.rotation < 500 * t ? 500 * t - v.rotation : 0) << k + 1;
    const std::size_t requests = k == 0 ? 3 : (k >= 2 && k <= 246 && k % 2 == 0 ? 2 : 1);
    ASSERT_EQ(v.startup.size(), requests) << k + 1;
    EXPECT_TRUE(v.polled.empty()) << k + 1;
    for (std::size_t n = 0; n < requests; ++n) {
      EXPECT_EQ(v.startup[n], k < 251 ? 0U : 1U) << k + 1;
      ASSERT_LT(next, sent.size());
      EXPECT_EQ(sent[next++].start, a1 + (a + 33 + 199 * n) * t) << k + 1 << " " << n;
    }
    ASSERT_LT(next, sent.size());
    EXPECT_EQ(sent[next++].bytes, (std::vector<std::uint8_t>{fdl::SD4, 2, 2})) << k + 1;
  }
  // The requests of the last ten visits: FDL_Status (SD1, 10h), Slave_Diag (SD2 LE 5),
  // Set_Prm (LE 13), Chk_Cfg (LE 7), each to DA | 80h with its SAPs.
  const std::vector<std::vector<std::uint8_t>> last = {
      {fdl::SD1, 5}, {fdl::SD2, 5}, {fdl::SD2, 13}, {fdl::SD2, 7}, {fdl::SD2, 5},
      {fdl::SD1, 6}, {fdl::SD2, 5}, {fdl::SD2, 13}, {fdl::SD2, 7}, {fdl::SD2, 5}};
  for (std::size_t i = 0; i < last.size(); ++i) {
    const LineTelegram& r = sent[sent.size() - 2 * (last.size() - i)];
    EXPECT_EQ(r.bytes[0], last[i][0]) << i;
    EXPECT_EQ(r.bytes[1], last[i][1]) << i;
  }
  EXPECT_EQ(sent[sent.size() - 20].start, a1 + 90098 * t);
  for (const std::size_t c : line.chips) {
    EXPECT_EQ(line.seg.chip(c).dp_state(), DpState::Data_Exchange);
  }
  EXPECT_EQ(check.count(BusViolation::token_hold), 0U);
  EXPECT_EQ(check.total(), 0U);
}

}  // namespace
}  // namespace dpc31

namespace dpc31 {
namespace {

// `expect visit` from the scenario door (docs/scenario-format.md, "Segments"): a master alone
// with ttr= claims the token at its first visit (TRR 0, TTH = TTR = 1000 bit times: both cycles,
// at 33 and 363 T, start before it) and passes it to itself; a wrong field fails with what the
// visit did.
TEST(SegmentScenario, ExpectVisitChecksTheMastersLastVisit) {
  const std::string head =
      "segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\n"
      "master 2 slaves=5,6 ttr=1000\nstartup\ncycle 1\n";
  const auto run = [](const std::string& text, std::vector<std::string>& errors) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_TRUE(parse_segment_scenario(text, "v.scn", s, err)) << err.text();
    return run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); });
  };
  // The start-up's last visit (docs/segment.md, "The start-up under TTR") is the Slave_Diag that
  // finds 6 ready: TSYN 33 + request 121 (11 characters) + TSDR 11 + answer 187 (17) + TSYN 33 +
  // the token 33 = 418 T, the next visit's TRR: TTH 582, cycles at 33 and 363 (T = 32 clocks).
  std::vector<std::string> errors;
  EXPECT_EQ(run(head + "expect visit 2 polled=5,6 rotation=418 hold=582 gap=none\n", errors), 0);
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_EQ(run(head + "expect visit 2 polled=5 rotation=0\n", errors), 1);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0],
            "v.scn:7: expected visit 2 polled=5 rotation=0, got polled 5,6, rotation 418 bit "
            "times, hold 582 bit times, gap none");
  // After the start-up alone the last visit polled no one (`none`, not an empty list: the audit
  // s28 aud2, finding 7): it carried the Slave_Diag to 6. The visit before it carried 6's Chk_Cfg
  // (13 characters), so its TRR is TSYN 33 + 143 + TSDR 11 + the SC 11 + TSYN 33 + the token 33 =
  // 264 bit times, TTH 736.
  errors.clear();
  EXPECT_EQ(run("segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\n"
                "master 2 slaves=5,6 ttr=1000\nstartup\nexpect visit 2 polled=5\n",
                errors),
            1);
  EXPECT_EQ(errors, std::vector<std::string>{
                        "v.scn:6: expected visit 2 polled=5, got polled none, start-up 6, rotation "
                        "264 bit times, hold 736 bit times, gap none"});
}

// A failed `expect tsdr` says the delays in bit times, as the check is written (docs/scenario-
// format.md: "expected X, got Y" in the check's own terms; the audit s28 aud2, finding 7). The
// start-up's five answers (FDL_Status, Slave_Diag, Set_Prm's SC, Chk_Cfg's SC, Slave_Diag) each
// start 11 T after their request's end (docs/timing.md: max(11, MinTSDR) with MinTSDR 11 after
// Start and no Set_Prm byte 3).
TEST(SegmentScenario, ExpectTsdrSaysTheDelaysInBitTimes) {
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario("segment\nstation 5 profile=spc3\nstartup\nexpect tsdr 12\n",
                                     "t.scn", s, err))
      << err.text();
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); }),
            1);
  EXPECT_EQ(errors, std::vector<std::string>{
                        "t.scn:4: expected tsdr 12, got 5 answers, delays 11..11 bit times"});
}

// Two stations on one address and no `master` line: the default master polls every address once
// (one FCB state per slave). Both answer each of the start-up's five requests (docs/segment.md:
// FDL_Status, Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag) at the same MinTSDR: five collisions, the
// first driver keeping the line, so the master hears one answer and the start-up completes.
TEST(SegmentScenario, TwoStationsOnOneAddressArePolledOnceAndCollide) {
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(
      parse_segment_scenario("segment\nstation 5\nstation 5 name=twin profile=vpc3plus\nstartup\n"
                             "expect collisions 5\nexpect state 5 Data_Exchange\n",
                             "c.scn", s, err))
      << err.text();
  ASSERT_EQ(s.masters.size(), 1U);
  EXPECT_EQ(s.masters[0].slaves, (std::vector<std::uint8_t>{5}));
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); }),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
}

// A long `cycle N` keeps the run's memory flat (docs/decisions.md): the masters' histories are
// not kept, nor the responders' output fetches. What the heap grew by over the `cycle` step
// (from its start to its end) with 2 000 DP cycles of two slaves is within 16 KiB of that with
// 200; without the trim every exchange's history stayed (about 0.5 MB more). ASan's allocator is
// not malloc's: there only the run.
TEST(SegmentScenario, ALongCycleStepKeepsTheMemoryFlat) {
  struct Heap : SegmentObserver {
    void step_begins(const SegmentStep& st, std::string_view) override {
      if (st.kind == SegmentStep::Kind::cycle) at_start = test::heap_in_use();
    }
    void step_ends(const SegmentStep& st) override {
      if (st.kind == SegmentStep::Kind::cycle) grown = test::heap_in_use() - at_start;
    }
    std::int64_t at_start = 0;
    std::int64_t grown = 0;
  };
  const auto grown = [](int cycles) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_TRUE(parse_segment_scenario(
        fmt::format("segment\nstation 5 profile=spc3 firmware=DO4 wd=1,1\n"
                    "station 6 profile=vpc3plus firmware=CNT2 wd=1,1\nmaster 2 slaves=5,6\n"
                    "startup\ncycle {}\nexpect state 5 Data_Exchange\n"
                    "expect state 6 Data_Exchange\n",
                    cycles),
        "long.scn", s, err))
        << err.text();
    Heap heap;
    std::vector<std::string> errors;
    EXPECT_EQ(run_segment_scenario(
                  s, {}, [&errors](const std::string& e) { errors.push_back(e); }, &heap),
              0);
    EXPECT_TRUE(errors.empty()) << errors.front();
    return heap.grown;
  };
  const std::int64_t short_run = grown(200);
  const std::int64_t long_run = grown(2000);
  if (test::kHeapCounted) {
    EXPECT_LE(long_run, short_run + 16 * 1024)
        << "grown by " << short_run << " bytes over 200 DP cycles, " << long_run << " over 2 000";
  }
}

// The user watchdog of a station with the built-in user side (docs/timing.md: it counts
// Data_Exchange telegrams; Res_User_WD, which the user side sets with Start_SPC3, loads
// R_User_WD_Value at the next Data_Exchange, each later one counts down, and the one that reaches
// 0 is not answered and makes Leave_Master). So with R_User_WD_Value = N and no service, the
// station answers Data_Exchanges 1..N and not N + 1. What each station did with every
// Data_Exchange request to it, in order: answered with its 4 input bytes, or not at all.
struct DataExchanges : SegmentObserver {
  enum class Answer : std::uint8_t { none, data, other };
  explicit DataExchanges(const SegmentScenario& s) {
    for (const SegmentStation& st : s.stations) address.push_back(st.slave.address);
  }
  void telegram(const LineTelegram& t) override {
    const fdl::Decoded d = fdl::decode(t.bytes);
    if (d.error != fdl::Error::none) return;
    if (t.from >= address.size()) {  // a master: the request a chip's next telegram answers
      asked.reset();
      if (d.frame.sd != fdl::SD4 && fdl::is_request(d.frame.fc) &&
          service_name(d.frame) == "Data_Exchange") {
        asked = d.frame.da;
        answers[d.frame.da].push_back(Answer::none);
      }
    } else if (asked && *asked == address[t.from]) {
      answers[*asked].back() = d.frame.du.size() == 4 ? Answer::data : Answer::other;
      asked.reset();
    }
  }
  std::vector<std::uint8_t> address;  // each chip station's, by its index on the segment
  std::optional<std::uint8_t> asked;
  std::map<std::uint8_t, std::vector<Answer>> answers;
};

DataExchanges run_exchanges(const std::string& text) {
  SegmentScenario s;
  ScenarioError err;
  EXPECT_TRUE(parse_segment_scenario(text, "uwd.scn", s, err)) << err.text();
  DataExchanges dx(s);
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(
                s, {}, [&errors](const std::string& e) { errors.push_back(e); }, &dx),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
  return dx;
}

// The default (R_User_WD_Value 0x1FF = 511, not served): Data_Exchanges 1..511 answered, the 512th
// not, and none answered with data after it (the station is in Wait_Prm; the master does not
// parameterise it again within `cycle`).
TEST(SegmentScenario, AStationWithoutUserWdLeavesDataExchangeAtIts512thDataExchange) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\nstartup\n"
      "cycle 511\nexpect state 5 Data_Exchange\nexpect state 6 Data_Exchange\ncycle 2\n"
      "expect state 5 Wait_Prm\nexpect state 6 Wait_Prm\n");
  for (const std::uint8_t a : {5, 6}) {
    const std::vector<A>& got = dx.answers.at(a);
    ASSERT_GE(got.size(), 513U) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin(), got.begin() + 511, A::data), 511) << "station " << int{a};
    EXPECT_EQ(got[511], A::none) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin() + 512, got.end(), A::data), 0) << "station " << int{a};
  }
}

// `user_wd=1`: the user side sets Res_User_WD on every DX_Out, so the count is loaded again at
// every next Data_Exchange and never reaches 0: 1 500 DP cycles, every Data_Exchange answered
// (the DPC31's DPS_User_Watchdog reset on every DX_Out as well).
TEST(SegmentScenario, AStationThatServesItsUserWatchdogStaysInDataExchange) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3 user_wd=1\n"
      "station 6 profile=vpc3plus user_wd=1\nstation 7 profile=dpc31 user_wd=1\nstartup\n"
      "cycle 1500\nexpect state 5 Data_Exchange\nexpect state 6 Data_Exchange\n"
      "expect state 7 Data_Exchange\n");
  for (const std::uint8_t a : {5, 6, 7}) {
    const std::vector<A>& got = dx.answers.at(a);
    EXPECT_EQ(got.size(), 1500U) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin(), got.end(), A::data), 1500) << "station " << int{a};
  }
}

// `user_wd_value=3` without the service: Data_Exchanges 1..3 answered, the 4th not (the count
// loaded at the first, 2 and 1 at the next two, 0 at the fourth). The station beside it keeps
// the default.
TEST(SegmentScenario, UserWdValueSetsTheDataExchangeThatIsNotAnswered) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3 user_wd_value=3\nstation 6 profile=spc3\n"
      "startup\ncycle 3\nexpect state 5 Data_Exchange\ncycle 2\nexpect state 5 Wait_Prm\n"
      "expect state 6 Data_Exchange\n");
  const std::vector<A>& got = dx.answers.at(5);
  ASSERT_GE(got.size(), 5U);
  EXPECT_EQ(std::vector<A>(got.begin(), got.begin() + 4),
            (std::vector<A>{A::data, A::data, A::data, A::none}));
  EXPECT_EQ(std::count(got.begin() + 4, got.end(), A::data), 0);
  EXPECT_EQ(std::count(dx.answers.at(6).begin(), dx.answers.at(6).end(), A::data), 5);
}

// Bad input in a segment scenario: one line, FILE:LINE, nothing run (docs/bad-input.md).
TEST(SegmentScenario, BadLinesAreOneErrorWithTheirLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"segment\nstation 5\nbogus 3\n", "f.scn:3: unknown command 'bogus'"},
      {"station 5\n", "f.scn:1: a segment scenario begins with 'segment'"},
      {"segment\nstation 5 firmware=DO4\nstation 6 firmware=NOPE\n",
       "f.scn:3: unknown firmware 'NOPE' (DO4, CNT2, or a plug-in path such as ./libmine.so)"},
      // The token's options (docs/scenario-format.md, "Segments").
      {"segment\nstation 5\nmaster 2 hsa=9\n",
       "f.scn:3: hsa= without gap=: the HSA bounds the GAP the master polls"},
      {"segment\nstation 5\nmaster 9 gap=1 hsa=8\n", "f.scn:3: hsa=8 below the master's address 9"},
      {"segment\nstation 5\nmaster 2 ttr=1000\nmaster 3 ttr=2000\n",
       "f.scn:4: ttr=2000 differs from master 2's ttr=1000: give the bus check's TTR on the "
       "segment "
       "line (segment ttr=BITS)"},
      {"segment\nstation 5\nmaster 2 gap=0\n", "f.scn:3: gap 0 out of range (1..100)"},
      {"segment\nstation 5\nmaster 2 ttr=1000\ncycle 1 skip=5\n",
       "f.scn:4: cycle skip=: master 2 obeys the token (ttr=, gap=) and polls all its slaves"},
      {"segment\nstation 5\nmaster 2\nexpect visit 2\n",
       "f.scn:4: master 2 does not obey the token: give it ttr= or gap="},
      {"segment\nstation 5\nmaster 2 gap=1\nexpect visit 3\n", "f.scn:4: no master 3"},
      {"segment\nstation 5\nmaster 2 gap=1\nexpect visit 2 gap_answered=maybe\n",
       "f.scn:4: gap_answered='maybe': yes or no"},
      {"segment\nstation 5\nexpect state 9 Data_Exchange\n", "f.scn:3: no station 9"},
      {"segment\nstation 5\nstartup\nstation 6\n", "f.scn:4: 'station' after the first action"},
      // The built-in user side's options, checked as the single chip's `user` step checks them.
      {"segment\nstation 5\nstation 6 profile=spc3 firmware=DO4 user_wd=1\n",
       "f.scn:3: 'user_wd' configures the built-in user side; a firmware configures itself"},
      {"segment\nstation 5 user_wd_value=9 firmware=CNT2 profile=vpc3plus\n",
       "f.scn:2: 'user_wd_value' configures the built-in user side; a firmware configures itself"},
      {"segment\nstation 5\nstation 6 profile=dpc31 user_wd_value=5\n",
       "f.scn:3: user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads "
       "R_User_WD_Value only through its requests"},
      {"segment\nstation 5 user_wd_value=5\n",
       "f.scn:2: user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads "
       "R_User_WD_Value only through its requests"},
      {"segment\nstation 5 profile=spc3 user_wd=yes\n",
       "f.scn:2: bad value 'yes' for user_wd: 0 or 1"},
      {"segment\nstation 5 profile=spc3 user_wd_value=65536\n",
       "f.scn:2: user_wd_value 65536 out of range (0..65535)"},
      // A master's slaves are stations of the segment, named before or after it.
      {"segment\nstation 5\nmaster 2 slaves=9\nstartup\n", "f.scn:3: slaves=9: no station 9"},
      {"segment\nmaster 2 slaves=5,9\nstation 5\nstartup\n", "f.scn:2: slaves=5,9: no station 9"},
      // One FCB state per slave (EN 50170): a slave listed twice would see its FCB repeated.
      {"segment\nstation 5\nstation 6\nmaster 2 slaves=5,6,5\nstartup\n",
       "f.scn:4: slaves=5,6,5: station 5 twice"},
      // One name a station, chips, senders and masters alike: it is the station's scope in the
      // waveforms and names it in the log and in `send from=`.
      {"segment\nstation 5 name=a\nstation 6 name=a\nstartup\n",
       "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=a\nsender a\nstartup\n", "f.scn:3: a second station named 'a'"},
      {"segment\nsender x\nstation 5\nsender x\nstartup\n", "f.scn:4: a second station named 'x'"},
      {"segment\nstation 5\nmaster 2 slaves=5\nmaster 2 slaves=5\nstartup\n",
       "f.scn:4: a second station named 'master 2'"},
      {"segment\nstation 5\nmaster 2\nstartup\npass_token from=9 to=2\n",
       "f.scn:5: pass_token from=9: no master of that address"},
      {"segment\nstation 5\n", "f.scn: only header commands: nothing to run"},
      // A word no command takes (a mistyped option: its `=` missing) is refused, never ignored,
      // in the single chip's words.
      {"segment\nstation 5\nstartup\nexpect state 5 Data_Exchange after_request 999999\n",
       "f.scn:4: 'expect state' takes a station and a DP state; unexpected 'after_request'"},
      {"segment\nstation 5\nstartup\nexpect state 5 Data_Exchange wd DP_Control\n",
       "f.scn:4: 'expect state' takes a station and a DP state; unexpected 'wd'"},
      {"segment\nstation 5\nstartup\nexpect tsdr 11 foo\n",
       "f.scn:4: 'expect tsdr' takes the bit times; unexpected 'foo'"},
      {"segment\nstation 5\nstartup\nexpect bus_violation collision 0 extra\n",
       "f.scn:4: 'expect bus_violation' takes a violation kind and a count; unexpected 'extra'"},
      {"segment baud=12000000 extra\n",
       "f.scn:1: 'segment' takes no arguments; unexpected 'extra'"},
      {"segment\nstation 5 6\n", "f.scn:2: 'station' takes a station address; unexpected '6'"},
      {"segment\nstation 5\nstartup foo\n",
       "f.scn:3: 'startup' takes no arguments; unexpected 'foo'"},
      {"segment\nstation 5\ncycle 2 3\n",
       "f.scn:3: 'cycle' takes the number of rotations; unexpected '3'"},
      {"segment\nstation 5\nrun 1ms 2ms\n", "f.scn:3: 'run' takes a time; unexpected '2ms'"},
      // The walk's form of a telegram (spaces) copied back, as the single chip's `send` says it.
      {"segment\nsender a\nsend from=a 10 05 02 49 50 16\n",
       "f.scn:3: send: the bytes are separated by commas (10,05,...); unexpected '05'"},
      // Every station is one: a name, and a master's address, once.
      {"segment\nsender a\nsender a\n", "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=a\nsender a\n", "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=\n", "f.scn:2: empty name for station 5"},
      {"segment\nstation 5\nmaster 2\nmaster 2\n", "f.scn:4: a second station named 'master 2'"},
      {"segment\nstation 5\nmaster 5\n", "f.scn:3: master 5 at the address of station 5"},
      {"segment\nmaster 5\nstation 5\n", "f.scn:3: station 5 at the address of master 5"},
      {"segment\nstation 5\nstation 2\nstartup\n",
       "f.scn:3: station 2 at the address of master 2, the default master: give a 'master' line"},
      // token_hold needs a TTR and a token passed between masters: else it could only count 0.
      {"segment\nstation 5\nstation 6\nmaster 2 slaves=5\nmaster 3 slaves=6\nstartup\n"
       "expect bus_violation token_hold 0\n",
       "f.scn:7: token_hold is checked on a line with two or more masters and a TTR (segment "
       "ttr=BITS or master ... ttr=BITS): without them it would always count 0"},
      {"segment ttr=1000\nstation 5\nstartup\nexpect bus_violation token_hold 0\n",
       "f.scn:4: token_hold is checked on a line with two or more masters and a TTR (segment "
       "ttr=BITS or master ... ttr=BITS): without them it would always count 0"},
      // A second `segment` line would replace the first's settings (docs/scenario-format.md: a
      // repeated header command is a parse error naming the first's line; the audit s28 aud2,
      // finding 6: the run was silently at the second's rate).
      {"# the line\nsegment baud=1500000\nsegment slot=200\nstation 5\nstartup\n",
       "f.scn:3: 'segment' given twice: first at line 2"},
      {"segment\nsegment baud=1500000\nstation 5\nstartup\n",
       "f.scn:2: 'segment' given twice: first at line 1"},
      // One slot range at every door (vocabulary.hpp kSlotBits).
      {"segment slot=36\nstation 5\nstartup\n", "f.scn:1: slot 36 out of range (37..16383)"},
      // The only rates the chips' baud search finds, refused in the single chip's words.
      {"segment baud=12345\nstation 5\nstartup\n",
       "f.scn:1: baud 12345 is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, 500000, "
       "1500000, 3000000, 6000000, 12000000)"},
  };
  for (const auto& [text, want] : cases) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_FALSE(parse_segment_scenario(text, "f.scn", s, err)) << text;
    EXPECT_EQ(err.text(), want);
  }
  // With the segment line silent, the bus check takes the TTR its masters obey.
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario(
      "segment\nstation 5\nmaster 2 ttr=1200\nmaster 3 ttr=1200 gap=2 hsa=9\nstartup\n", "f.scn", s,
      err))
      << err.text();
  EXPECT_EQ(s.ttr_bits, 1200U);
  EXPECT_EQ(s.masters[1].gap_factor, 2U);
  EXPECT_EQ(s.masters[1].hsa, 9U);
  EXPECT_TRUE(s.masters[1].obeys_token);
  EXPECT_TRUE(is_segment_scenario("# a comment\n\nsegment baud=12000000\n"));
  EXPECT_FALSE(is_segment_scenario("profile spc3\n"));
  // A UTF-8 BOM from an editor is skipped, as the single chip's parser skips it.
  EXPECT_TRUE(is_segment_scenario("\xEF\xBB\xBFsegment\nstation 5\nstartup\n"));
  ASSERT_TRUE(parse_segment_scenario("\xEF\xBB\xBFsegment\nstation 5\nstartup\n", "f.scn", s, err))
      << err.text();
  EXPECT_EQ(s.stations.size(), 1U);
}

// A segment scenario's text run: its exit code, the walk and the failed checks.
struct ScenarioRun {
  int code = 0;
  std::vector<std::string> walk;
  std::vector<std::string> errors;
  // The cycle of the walk's last line that contains `text` (0 when none does).
  [[nodiscard]] std::uint64_t cycle_of(std::string_view text) const {
    for (auto l = walk.rbegin(); l != walk.rend(); ++l) {
      if (l->find(text) != std::string::npos) return std::stoull(l->substr(l->find("cycle") + 5));
    }
    ADD_FAILURE() << "no walk line with " << text;
    return 0;
  }
};

ScenarioRun run_scenario_text(const std::string& text) {
  SegmentScenario s;
  ScenarioError err;
  EXPECT_TRUE(parse_segment_scenario(text, "s.scn", s, err)) << err.text();
  ScenarioRun r;
  r.code = run_segment_scenario(
      s, [&r](const std::string& l) { r.walk.push_back(l); },
      [&r](const std::string& e) { r.errors.push_back(e); });
  return r;
}

// The same for a run whose every check passes: exit 0, no failure.
ScenarioRun run_passing(const std::string& text) {
  ScenarioRun r = run_scenario_text(text);
  EXPECT_EQ(r.errors, std::vector<std::string>{});
  EXPECT_EQ(r.code, 0);
  return r;
}

// docs/scenario-format.md: `expect tsdr` counts the answers the bus check pairs with their
// requests (docs/segment.md "Bus checks"): a scripted station's answer to an FDL_Status to 9
// 132 bit times after its end is the asked station's late answer (before TSL + TSYN = 133) and
// its delay counts; at 133 bit times the bus check calls it unsolicited and `expect tsdr 11`
// (the start-up's answers, each 11 bit times) holds. The audit's u133.scn.
TEST(SegmentScenario, ExpectTsdrCountsOnlyWhatTheBusCheckCallsAnAnswer) {
  for (const int after : {132, 133}) {
    const bool late = after == 132;
    const ScenarioRun r = run_scenario_text(fmt::format(
        "segment baud=1500000 slot=100\nstation 5 profile=spc3\nsender asker\nsender nine\n"
        "startup\nsend from=asker after=33bits 10,09,03,49,55,16\n"
        "send from=nine after={}bits 10,03,09,00,0C,16\nrun 1ms\n"
        "expect bus_violation late_answer {}\nexpect bus_violation unsolicited {}\n"
        "expect tsdr 11\n",
        after, late ? 1 : 0, late ? 0 : 1));
    ASSERT_EQ(r.errors.size(), late ? 1U : 0U) << after;
    if (late) {
      EXPECT_EQ(r.errors[0].substr(0, 27), "s.scn:11: expected tsdr 11,") << r.errors[0];
      EXPECT_NE(r.errors[0].find("delays 11..132 bit times"), std::string::npos) << r.errors[0];
    }
    EXPECT_EQ(r.code, late ? 1 : 0) << after;
  }
}

// Two masters without a TTR still pass a token, so a lost one is found (docs/segment.md, "Bus
// checks": TTO = TSL x (6 + 2 x 2) = 1000 bit times needs no TTR): the token to nobody (DC 09 02,
// 3 characters: its end 33 T = 1056 clocks after its start at 1.5 Mbaud) leaves the line idle,
// counted once at that end + 1000 T (32 000 clocks).
TEST(SegmentScenario, TwoMastersWithoutTtrCheckTheToken) {
  const ScenarioRun r = run_scenario_text(
      "segment\nstation 5 profile=spc3\nstation 6 profile=dpc31\nmaster 2 slaves=5\n"
      "master 3 slaves=6\nstartup\ncycle 2\npass_token from=2 to=9\nrun 2ms\n"
      "expect bus_violation token_lost 1\nexpect bus_violation duplicate_token 0\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  const std::uint64_t token = r.cycle_of("master 2: DC 09 02");
  EXPECT_EQ(r.cycle_of("bus: token_lost"), token + 1056 + 32000);
}

// Only actions move the line's time (docs/scenario-format.md, "Segments"): a master's action ends
// on a quiet line, at the end of the last answer's stop bit; an expect moves no time; `run T`
// lasts T; `send` counts its `after=` (33 bit times) from the quiet line and lasts to its
// telegram's end. At 12 Mbaud, T = 4 clocks.
TEST(SegmentScenario, OnlyActionsMoveTheLinesTime) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "expect state 5 Data_Exchange\nexpect state 5 Data_Exchange\n"
      "send from=a 10,05,02,49,50,16\nrun 1000\nexpect state 5 Data_Exchange\n"
      "expect bus_violation short_tsyn 0\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  // The start-up's last telegram, the Slave_Diag answer: 17 characters of 11 T from its start.
  const std::uint64_t quiet = r.cycle_of("line 6: expect");
  EXPECT_EQ(r.cycle_of("] station 5: 68 0B 0B 68 82 85 08") + 17 * 11 * 4, quiet);
  EXPECT_EQ(r.cycle_of("line 7: expect"), quiet);
  EXPECT_EQ(r.cycle_of("line 8: send"), quiet);
  const std::uint64_t sent = r.cycle_of("] a: 10 05 02 49 50 16");
  EXPECT_EQ(sent, quiet + 33 * 4);
  EXPECT_EQ(r.cycle_of("line 9: run"), sent + 6 * 11 * 4);
  EXPECT_EQ(r.cycle_of("line 10: expect"), sent + 6 * 11 * 4 + 1000);
  EXPECT_EQ(r.cycle_of("line 11: expect"), sent + 6 * 11 * 4 + 1000);
}

// A run with no telegram on the line at all (the segment has relayed none whole: its whole_start
// is "never") ends after its `run`s: nothing to finish at the end.
TEST(SegmentScenario, ALineWithoutATelegramEndsAfterItsRuns) {
  const ScenarioRun r =
      run_scenario_text("segment\nstation 5 profile=spc3\nrun 1000\nexpect state 5 Wait_Prm\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.cycle_of("line 4: expect"), r.cycle_of("line 3: run") + 1000);
  EXPECT_EQ(r.cycle_of("1 expects passed"), r.cycle_of("line 3: run") + 1000);
}

// A short TSYN names the station that sent, not the SA its frame carries: sender `a` sends a
// request in master 2's name 32 bit times after the start-up's last answer.
TEST(SegmentScenario, AShortTsynNamesItsSender) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "send from=a after=32bits 10,05,02,49,50,16\nrun 1000\nexpect bus_violation short_tsyn 1\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  EXPECT_NE(r.cycle_of("bus: short_tsyn: a sent after 32 bit times of idle (TSYN 33)"), 0U);
}

// The built-in master keeps TSYN after every telegram on the line, not only its own
// (docs/timing.md: a telegram after fewer than 33 idle bit times is ignored and counted `no_sync`;
// docs/scenario- format.md `idle=`: after the end of the line's last telegram; the audit s28 aud2,
// finding 1: it counted from its own traffic and started on the last bit of another station's
// token). At 12 Mbaud T = 4 clocks. A sender's token (DC 02 02, 3 characters: 33 T) ends 132 clocks
// after its first start bit; master 2's Data_Exchange (4 output bytes: SD2 with 13 characters)
// starts TSYN = 132 clocks later, and station 5 answers it (13 characters) 11 T after its end.
TEST(SegmentScenario, TheMasterKeepsTsynAfterAnotherStationsTelegram) {
  const ScenarioRun r = run_passing(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender r\nstartup\n"
      "cycle 1\nsend from=r after=200bits DC,02,02\ncycle 1\nexpect bus_violation short_tsyn 0\n"
      "expect state 5 Data_Exchange\n");
  const std::uint64_t token = r.cycle_of("] r: DC 02 02");
  const std::uint64_t request = r.cycle_of("] master 2: 68 07 07 68 05 02");
  EXPECT_EQ(request, token + 33 * 4 + 33 * 4);
  EXPECT_EQ(r.cycle_of("] station 5: 68 07 07 68 02 05"), request + 13 * 11 * 4 + 11 * 4);
}

// A token claimed without an SD4 is held from TSYN before the claiming master's first request
// (docs/segment.md, "The token"): the master's own TTH counts from there as the bus check's does
// (the review s28 rev2 finding 1: it counted from the claim's step, 33 bit times earlier for the
// check, and the check charged it token_hold at TTR 331..340).
TEST(SegmentScenario, AClaimedTokensHoldIsTheBusChecks) {
  for (const int ttr : {331, 335, 340}) {
    run_passing(
        fmt::format("segment baud=12000000\nstation 5 name=spc3 profile=spc3\n"
                    "station 6 name=vpc3plus profile=vpc3plus\nstation 7 name=dpc31 profile=dpc31\n"
                    "master 2 slaves=5,6 ttr={0}\nmaster 3 slaves=7 ttr={0}\nstartup\ncycle 2\n"
                    "pass_token from=2 to=9\nrun 2ms\ncycle 3\nexpect bus_violation token_hold 0\n",
                    ttr));
  }
}

// The same after another master's token: master 3, given the token by master 2, passes it back
// TSYN after master 2's token ends (each DC xx yy: 33 T), not at once (the audit's f1b).
TEST(SegmentScenario, AMasterPassesTheTokenTsynAfterTheTokenItGot) {
  const ScenarioRun r = run_passing(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nmaster 3 slaves=5\n"
      "pass_token from=2 to=3\npass_token from=3 to=2\nexpect bus_violation short_tsyn 0\n");
  EXPECT_EQ(r.cycle_of("] master 3: DC 02 03"), r.cycle_of("] master 2: DC 03 02") + 66 * 4);
}

// A master that finds a slave locked by another (its Slave_Diag's Master_Add, byte 3, neither FFh
// nor its own address: chip-facts.md, "Slave_Diag"; Master_Lock is the master's own bit) does not
// parameterise it, and its walk says so (the audit s28 aud2, finding 4: master 3 took the slave
// for ready and sent it Data_Exchange silently). At 1.5 Mbaud T = 32 clocks: master 3's Slave_Diag
// answer `00 0C 00 02 0C 31` is 17 characters; the master stops at its last stop sample, end - T
// + T/2, where the walk says it.
TEST(SegmentScenario, AMasterLeavesASlaveLockedByAnotherMasterAlone) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\nmaster 2 slaves=5,6\n"
      "master 3 slaves=5\nstartup\nexpect state 5 Data_Exchange\n");
  const std::uint64_t diag =
      r.cycle_of("] station 5: 68 0B 0B 68 83 85 08 3E 3C 00 0C 00 02 0C 31");
  EXPECT_EQ(r.cycle_of("master 3: station 5 is locked by master 2 (its Slave_Diag's Master_Add): "
                       "not parameterised, its start-up ends"),
            diag + 17 * 11 * 32 - 32 + 16);
  // No Set_Prm (DSAP 3D) nor Chk_Cfg (3E) from master 3.
  EXPECT_EQ(std::count_if(r.walk.begin(), r.walk.end(),
                          [](const std::string& l) {
                            return l.find("] master 3: 68") != std::string::npos &&
                                   (l.find(" 3D 3E ") != std::string::npos ||
                                    l.find(" 3E 3E ") != std::string::npos);
                          }),
            0);
}

// Two stations at one address answer each of the start-up's five requests and the three
// Data_Exchanges together: eight collisions, each its own line in the walk (docs/segment.md, "Bus
// checks": one log line a violation; a run of equal lines folds only where nothing comes between,
// and then its note comes right after it: the audit s28 aud2, finding 8: one line showed and the
// note came 40 lines later). The chips' state lines are in cycle order (docs/segment.md, "The
// log"; finding 9: the two twins' Data_Exchange lines came in station order).
TEST(SegmentScenario, EachCollisionIsALineAndStateLinesAreInCycleOrder) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 name=a profile=spc3\nstation 5 name=b profile=vpc3plus\n"
      "station 6 profile=dpc31\nstartup\ncycle 3\nexpect collisions 8\n");
  std::vector<std::uint64_t> states;
  std::size_t collisions = 0;
  for (const std::string& l : r.walk) {
    EXPECT_EQ(l.find("repeated"), std::string::npos) << l;
    if (l.find("] bus: collision: b drove the line while a had it") != std::string::npos)
      ++collisions;
    if (l.find(" / ") != std::string::npos) states.push_back(std::stoull(l.substr(7)));
  }
  EXPECT_EQ(collisions, 8U);
  EXPECT_TRUE(std::is_sorted(states.begin(), states.end()));
  EXPECT_GE(states.size(), 6U);  // each of the three through Wait_Cfg into Data_Exchange at least
}

// An unanswered request waits for its answer only up to its slot time (docs/timing.md, "The
// master's wait"; docs/segment.md, "Bus checks"): each telegram long after it stands on its own.
// At 12 Mbaud T = 4 clocks, a 6-character telegram lasts 66 T = 264 clocks, `send` starts 33 T
// after the quiet line and ends at its telegram's end, `run 1ms` lasts 48 000 clocks, and the
// line idle for TTO = 100 x (6 + 2 x 2) = 1000 T = 4000 clocks after a telegram's end is one
// token_lost (master 2 alone). The rogue asks station 9 (nobody) in master 2's name; after a lost
// token a babbler's answer is unsolicited (no late answer, no wrong responder), and a request
// with a corrupted FCS (49 + 09 + 02 = 54, sent as 55) is one bad frame.
TEST(SegmentScenario, AnUnansweredRequestWaitsNoLongerThanItsSlotTime) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender rogue\n"
      "sender babbler\nstartup\nexpect state 5 Data_Exchange\n"
      "send from=rogue after=33bits 10,09,02,49,54,16\nrun 1ms\n"
      "send from=babbler after=33bits 10,02,07,00,09,16\n"
      "send from=rogue after=33bits 10,09,02,49,54,16\nrun 1ms\n"
      "send from=rogue after=33bits 10,09,02,49,55,16\nrun 1000\n"
      "expect bus_violation unsolicited 1\nexpect bus_violation bad_frame 1\n"
      "expect bus_violation late_answer 0\nexpect bus_violation wrong_responder 0\n"
      "expect bus_violation token_lost 2\n");
  EXPECT_EQ(r.errors, std::vector<std::string>{});
  EXPECT_EQ(r.code, 0);
  const std::uint64_t quiet = r.cycle_of("line 7: expect");
  const std::uint64_t end1 = quiet + 132 + 264;         // the first request to 9
  const std::uint64_t babble = end1 + 48000 + 132;      // the babbler's answer
  const std::uint64_t end3 = babble + 264 + 132 + 264;  // the second request to 9
  const std::uint64_t broken = end3 + 48000 + 132;      // the corrupted request
  const auto at = [](std::uint64_t cycle, std::string_view text) {
    return fmt::format("[cycle {:>10}] bus: {}", cycle, text);
  };
  const std::vector<std::string> want = {
      at(end1 + 4000,
         fmt::format("token_lost: the line idle for TTO (1000 bit times) since cycle {}", end1)),
      at(babble, "unsolicited: an answer from station 7 nobody asked for"),
      at(end3 + 4000,
         fmt::format("token_lost: the line idle for TTO (1000 bit times) since cycle {}", end3)),
      at(broken, fmt::format("bad_frame: 6 bytes from cycle {} do not decode (bad_fcs)", broken))};
  std::vector<std::string> bus;
  std::copy_if(r.walk.begin(), r.walk.end(), std::back_inserter(bus),
               [](const std::string& l) { return l.find("] bus: ") != std::string::npos; });
  EXPECT_EQ(bus, want);
}

// A telegram that ends at a step's end (its last stop bit) is over there: the walk prints it, and
// the bus check counts it, before the next step's lines at that cycle (docs/decisions.md, the
// twenty-third session; a chip's event at an expect's cycle comes before the expect in the single
// chip's walk too). Until then the segment told of it one character time later, after them. At
// 12 Mbaud T = 4 clocks: `send` starts 32 T after the start-up's quiet end (line 6's cycle) and
// ends 6 characters of 11 T later, where line 8's expect looks (docs/scenario-format.md,
// "Segments": `send` ends at its telegram's end, a check moves no time); the short TSYN is
// stamped at the telegram's start, where the idle ended too soon (the bus check is told of each
// telegram just before the log prints it).
TEST(SegmentScenario, ATelegramEndingAtAStepsEndComesBeforeItsExpects) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "expect state 5 Data_Exchange\nsend from=a after=32bits 10,05,02,49,50,16\n"
      "expect bus_violation short_tsyn 1\n");
  EXPECT_EQ(r.errors, std::vector<std::string>{});  // the short TSYN counted: exit 0
  const std::uint64_t quiet = r.cycle_of("line 6: expect");
  const std::uint64_t sent = quiet + 32 * 4;
  const std::uint64_t end = sent + 6 * 11 * 4;
  const auto at = [](std::uint64_t cycle, std::string_view text) {
    return fmt::format("[cycle {:>10}] {}", cycle, text);
  };
  const std::vector<std::string> want = {
      at(quiet, "line 7: send from=a after=32bits 10,05,02,49,50,16"),
      at(sent, "bus: short_tsyn: a sent after 32 bit times of idle (TSYN 33)"),
      at(sent, "a: 10 05 02 49 50 16"), at(end, "line 8: expect bus_violation short_tsyn 1"),
      at(end, "ok")};
  const auto from = std::find(r.walk.begin(), r.walk.end(), want.front());
  ASSERT_NE(from, r.walk.end());
  EXPECT_EQ(std::vector<std::string>(
                from, from + std::min<std::ptrdiff_t>(r.walk.end() - from, want.size())),
            want);
  EXPECT_EQ(r.code, 0);
}

// A station that never left DP_Control fails `expect watchdog_expired` saying so (not "left at
// cycle 0"), with the cycle expected: the last request's end - T + T/2 + TWD.
TEST(SegmentScenario, AWatchdogThatNeverExpiredSaysSo) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nstartup\n"
      "expect watchdog_expired 5 twd=100\n");
  EXPECT_EQ(r.code, 1);
  ASSERT_EQ(r.errors.size(), 1U);
  EXPECT_EQ(r.errors[0].substr(0, r.errors[0].find(" at cycle")),
            "s.scn:5: expected watchdog_expired 5 twd=100, got never left DP_Control, expected it");
}

// The single chip's loader on a segment's file names the segment's loader, at the `segment` line.
TEST(SegmentScenario, TheSingleChipLoaderNamesTheSegmentLoader) {
  Scenario s;
  ScenarioError err;
  EXPECT_FALSE(
      parse_scenario("# two stations\n\nsegment baud=1500000\nstation 5\n", "f.scn", s, err));
  EXPECT_EQ(err.text(),
            "f.scn:3: 'segment' begins a segment scenario (docs/scenario-format.md, \"Segments\"): "
            "load it with SegmentScenario (load_segment_scenario; dpc31.SegmentScenario in Python) "
            "or run it with `dpc31 run`");
}

// A master's slaves keep what the user set through slave() while another is selected (select()
// moves the selected one's configuration in and out, docs/decisions.md), and an index past them
// is refused.
TEST(Segment, AMastersSlaveKeepsItsConfigurationAcrossSelects) {
  Segment seg(1'500'000);
  const std::size_t m = seg.add_sender("master");
  std::vector<SlaveConfig> slaves(3);
  for (std::size_t i = 0; i < slaves.size(); ++i)
    slaves[i].address = static_cast<std::uint8_t>(3 + i);
  DpMaster master(seg, m, MasterConfig{2, 1'500'000}, slaves);
  master.select(1);
  master.slave().ident = 0x1234;
  master.slave().user_prm = {1, 2, 3};
  master.select(1);  // the slave selected: nothing moves
  EXPECT_EQ(master.slave().ident, 0x1234);
  master.select(2);
  EXPECT_EQ(master.slave().address, 5);
  master.select(0);
  EXPECT_EQ(master.slave().address, 3);
  master.select(1);
  EXPECT_EQ(master.slave().address, 4);
  EXPECT_EQ(master.slave().ident, 0x1234);
  EXPECT_EQ(master.slave().user_prm, (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_THROW(master.select(3), std::out_of_range);
  EXPECT_EQ(master.slave().address, 4);
}

}  // namespace
// What a master cannot send is refused before anything happens (std::invalid_argument, ValueError
// in Python): a data unit over DP's 244 bytes (fdl::encode would give no bytes: nothing went on
// the line and no answer was counted), a frame fdl::encode refuses, more outputs than slaves.
// Nothing reaches the line and the FCB is as it was: the next request is a fresh master's first.
TEST(Segment, AMasterRefusesWhatItCannotSend) {
  const auto make = [](Segment& seg) {
    std::vector<SlaveConfig> slaves(2);
    slaves[0].address = 5;
    slaves[1].address = 6;
    return std::make_unique<DpMaster>(seg, seg.add_sender("master"), MasterConfig{2, 1'500'000},
                                      slaves);
  };
  Segment seg(1'500'000);
  std::size_t telegrams = 0;
  seg.on_telegram = [&telegrams](const LineTelegram&) { ++telegrams; };
  const std::unique_ptr<DpMaster> master = make(seg);
  const auto refused = [](const auto& act) {
    try {
      act();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("not refused");
  };
  EXPECT_EQ(refused([&] { master->data_exchange(std::vector<std::uint8_t>(247)); }),
            "a request with 247 data bytes: a DP telegram carries at most 244");
  EXPECT_EQ(refused([&] { master->data_exchange(std::vector<std::uint8_t>(245)); }),
            "a request with 245 data bytes: a DP telegram carries at most 244");
  EXPECT_EQ(refused([&] {
              master->transact(fdl::make_frame(5, 2, 0x5D, std::vector<std::uint8_t>(250)));
            }),
            // chip-facts §8: an SD2 carries at most 246 DU bytes incl. SAP bytes; the refusal
            // names that field and its range, not a function.
            "du and SAPs: 250 + 0 bytes; an SD2 (0x68) carries 1..246 together (244 of du "
            "beside both SAPs)");
  const std::vector<std::vector<std::uint8_t>> three(3);
  EXPECT_EQ(refused([&] { master->dp_cycle(three); }),
            "3 outputs for 2 slaves: at most one per slave");
  EXPECT_EQ(refused([&] { master->use_token(2, three); }),
            "3 outputs for 2 slaves: at most one per slave");
  EXPECT_EQ(telegrams, 0U);
  EXPECT_EQ(master->selected(), 0U);
  const Exchange ex = master->data_exchange(std::vector<std::uint8_t>(244));
  EXPECT_EQ(telegrams, 1U);
  Segment other(1'500'000);
  EXPECT_EQ(ex.request, make(other)->data_exchange(std::vector<std::uint8_t>(244)).request);
}

}  // namespace dpc31
