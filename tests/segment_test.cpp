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
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <typeinfo>
#include <vector>

#include "bus_check.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "responder.hpp"
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

// A station's name is at most 64 bytes at the C++ door too (docs/capture.md: a segment's capture
// comments hold the names): the review of s31 found add_chip and add_sender took any length where
// the scenario and Python refused 65 bytes. The refusal leaves nothing behind: a 64-byte name is
// still free, and the next station gets the next index.
TEST(Segment, AStationNameLongerThan64BytesIsRefusedBeforeTheStationIsMade) {
  dpc31::Segment seg(1500000);
  const std::string long_name(65, 'n');
  try {
    seg.add_chip(long_name, dpc31::ChipOptions{dpc31::Profile::spc3});
    ADD_FAILURE() << "add_chip took a 65-byte name";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "segment: a name of 65 bytes for station 0: at most 64");
  }
  EXPECT_THROW(seg.add_sender(long_name), std::invalid_argument);
  EXPECT_EQ(seg.size(), 0u);
  EXPECT_EQ(seg.add_chip(std::string(64, 'n'), dpc31::ChipOptions{dpc31::Profile::spc3}), 0u);
  EXPECT_EQ(seg.add_sender("master"), 1u);
}

// A door whose station fails to set up after add_chip (Python's add_station, a firmware's init
// refused) takes the chip off again (Segment::remove_last_chip): its init ran it past the line's
// time, and afterwards the line's time, size and next index are as before and the line runs as on
// a segment that never had it, on both lines.
TEST(Segment, AChipTakenOffBeforeItDroveLeavesTheLineAsItWas) {
  for (const bool reference : {false, true}) {
    Line plain(kBaud, {5, 6}, 1, reference);
    Line line(kBaud, {5, 6}, 1, reference);
    ASSERT_TRUE(plain.master->startup_all());
    ASSERT_TRUE(line.master->startup_all());
    const std::uint64_t cycle = line.seg.cycle();
    const std::size_t late = line.seg.add_chip("late", ChipOptions{Profile::spc3});
    ResponderConfig rc;
    rc.slave.address = 7;
    Responder user(rc);
    DirectBus bus(line.seg.chip(late));
    user.init(bus);
    ASSERT_GT(line.seg.cycle(), cycle) << reference;
    line.seg.remove_last_chip();
    EXPECT_EQ(line.seg.size(), 3U) << reference;
    EXPECT_EQ(line.seg.cycle(), cycle) << reference;
    const std::vector<Exchange> a = plain.master->dp_cycle();
    const std::vector<Exchange> b = line.master->dp_cycle();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(b[i].request_start, a[i].request_start) << reference << " " << i;
      EXPECT_EQ(b[i].answer_start, a[i].answer_start) << reference << " " << i;
      EXPECT_EQ(b[i].answer_end, a[i].answer_end) << reference << " " << i;
      EXPECT_EQ(b[i].answer.has_value(), a[i].answer.has_value()) << reference << " " << i;
    }
    EXPECT_TRUE(line.seg.collisions().empty());
    EXPECT_EQ(line.seg.add_chip("late", ChipOptions{Profile::spc3}), late);
  }
}

// Only a chip added last that never drove the line leaves: what it drove is in the others.
TEST(Segment, RemoveLastChipRefusesASenderAndAChipThatAnswered) {
  Segment seg(kBaud);
  const std::size_t master = seg.add_sender("master 2");
  EXPECT_THROW(seg.remove_last_chip(), std::logic_error);
  SlaveConfig sc;
  sc.address = 5;
  ResponderConfig rc;
  rc.slave = sc;
  Responder user(rc);
  const std::size_t chip = seg.add_chip("spc3", ChipOptions{Profile::spc3});
  DirectBus bus(seg.chip(chip));
  user.init(bus);
  seg.set_firmware(chip, [&user](BusPort& b) { user.isr(b); });
  DpMaster m(seg, master, MasterConfig{2, kBaud}, {sc});
  ASSERT_TRUE(m.startup_all());
  try {
    seg.remove_last_chip();
    ADD_FAILURE() << "a chip that answered left the line";
  } catch (const std::logic_error& e) {
    EXPECT_EQ(std::string(e.what()), "segment: station spc3 drove the line: it stays on it");
  }
  EXPECT_EQ(seg.size(), 2U);
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

// A pulse of no clocks put its rising edge at its falling edge's cycle: a "line order broken"
// logic_error from the line, or a start_bit error counted for nothing (audit s35 aTb finding 4).
// Refused before the line is touched: the segment has not run to the start.
TEST(Segment, APulseOfNoClocksIsRefused) {
  Segment seg(kBaud);
  seg.add_chip("slave a", ChipOptions{});
  const std::size_t m = seg.add_sender("rogue");
  try {
    seg.pulse(m, 1000, 0);
    ADD_FAILURE() << "a pulse of 0 clocks was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "pulse: low_cycles 0: a pulse lasts 1 clock or more");
  }
  EXPECT_EQ(seg.cycle(), 0u);
  EXPECT_NO_THROW(seg.pulse(m, 1000, 1));  // one clock is a pulse
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
// The audit s35 aMix, finding 2: a master drives no busy line (RS-485 half duplex); its TSYN
// counts from the end of the last telegram on the line, also one still in progress when it
// decides or one that starts after that, before its own start (docs/segment.md "Masters on it").
// A scripted station's FDL_Status to the SPC3 at 5 (SA 9): the SPC3 answers it TSDR 11 bit times
// after its end (6 characters: 66 T), so the master's next Data_Exchange starts 33 T after that
// answer's end, and nothing is a late answer of the master's, which asked nothing unanswered
// (docs/timing.md "The master's wait"). Twice: the master decides at the scripted telegram's end,
// before the answer starts (the scenario's `send`, then `cycle`), and while the telegram is on
// the line (Python's `Segment.send` with its default start, then `dp_cycle`). Until the
// thirty-fifth session it started 33 T after the scripted telegram's start or end: a collision with
// it or with the answer, its Data_Exchange lost, counters().late 1 (the first case first: after an
// exchange without an answer the master watched the line before its next request already).
TEST(Segment, AMasterStartsNoRequestIntoAnotherStationsTelegram) {
  Line line(kBaud, {5});
  DpMaster& m = *line.master;
  const std::size_t tool = line.seg.add_sender("tool");
  ASSERT_TRUE(m.startup_all());
  m.dp_cycle();
  const std::vector<std::uint8_t> status = {0x10, 0x05, 0x09, 0x49, 0x57, 0x16};
  const std::uint64_t t = line.seg.bit_cycles();
  for (const bool decide_inside : {false, true}) {
    SCOPED_TRACE(decide_inside ? "decided while the telegram is on the line" : "at its end");
    const std::uint64_t end = line.seg.send(tool, status, line.seg.cycle() + 40 * t);
    line.seg.run_until(decide_inside ? end - 20 * t : end);
    const std::vector<Exchange> x = m.dp_cycle();
    ASSERT_EQ(x.size(), 1U);
    const std::uint64_t answer_end = end + 11 * t + 6 * 11 * t;
    EXPECT_EQ(x[0].request_start, answer_end + 33 * t);
    EXPECT_TRUE(x[0].answer);
  }
  EXPECT_TRUE(line.seg.collisions().empty());
  EXPECT_EQ(m.counters().late, 0U);
}

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
