// The telegram-level line against the reference line (docs/segment.md, "Telegram level"): one
// segment built twice, one with Segment::use_reference_line (every station stepped in every
// round, every character and edge given to every chip as it comes: the line before issue 30
// item 6), one at telegram level, both driven by the same master and scripted station. What each
// chip shows at its own cycles — its X/INT edges, TxD edges, bus accesses of its firmware, every
// telegram it takes with its FDL counters, DP and watchdog state at that telegram's end — must be
// the same list in both, and every chip's snapshot must be the same bytes wherever the test
// stops the line: after every master transaction (the line idle, every telegram ended), and
// inside foreign telegrams (a snapshot turns a telegram heard whole back into characters). The
// master's receiver (Segment::take_line: characters whole on the telegram-level line, edges on
// the reference line) must have seen the same answers at the same cycles, and an on_line
// observer the same edges.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "responder.hpp"
#include "segment.hpp"
#include "telegram_log.hpp"

namespace dpc31 {
namespace {

std::string counters_text(const FdlCounters& n) {
  return fmt::format(
      "par {} sb {} stb {} sd {} lem {} le {} fcs {} ed {} tr {} ov {} sap {} "
      "nosync {} foreign {} usap {} fn {} na {} nr {} off {} rep {} req {}",
      n.parity, n.start_bit, n.stop_bit, n.bad_sd, n.le_mismatch, n.bad_le, n.bad_fcs, n.wrong_ed,
      n.truncated, n.oversize, n.bad_sap, n.no_sync, n.foreign_address, n.unknown_sap,
      n.unsupported_function, n.not_allowed, n.no_resource, n.offline, n.repeated, n.requests);
}

// The built-in user side of slave `sc`, kept in `users`.
Responder& add_user(std::vector<std::unique_ptr<Responder>>& users, const SlaveConfig& sc) {
  ResponderConfig rc;
  rc.slave = sc;
  users.push_back(std::make_unique<Responder>(rc));
  return *users.back();
}

// `n` (at least five) slaves of the three profiles with the built-in user side (the fifth one also
// polls a register in a main loop, so its firmware runs in every round), a master and a scripted
// station. With `watch_txd` each chip's TxD edges are logged (Chip::on_txd: every edge an event of
// the chip); without, the chips keep their answers as characters on the telegram-level line, and
// what they drove shows in the line's telegrams (logged in both) and the snapshots.
// Only the first `watched` chips get the observers (the others show what they did in their
// snapshots and counters only, so their verdicts that show nothing are no events of the line:
// Chip::line_deadline). With `watch_line` every edge of the line is logged (Segment::on_line, as
// a waveform takes it).
struct Bed {
  Bed(bool reference, std::uint32_t baud, std::size_t n, bool watch_txd = true,
      std::size_t watched = SIZE_MAX, bool watch_line = false)
      : seg(baud) {
    seg.use_reference_line(reference);
    if (watch_line) {
      seg.on_line = [this](std::size_t from, std::uint64_t cycle, bool level) {
        wire.push_back(fmt::format("{} {} {}", from, cycle, level));
      };
    }
    seg.on_telegram = [this](const LineTelegram& t) {
      line.push_back(
          fmt::format("{} {}..{} {}", seg.name(t.from), t.start, t.end, fmt::join(t.bytes, " ")));
    };
    log.reserve(n);  // the observers below keep pointers into it
    const Profile profiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31};
    for (std::size_t i = 0; i < n; ++i) {
      SlaveConfig sc;
      sc.address = static_cast<std::uint8_t>(5 + i);
      sc.wd_fact1 = 1;
      sc.wd_fact2 = 1;
      slaves.push_back(sc);
      add_user(users, sc).set_inputs({static_cast<std::uint8_t>(i), 1, 2, 3});
      const std::size_t k = seg.add_chip(fmt::format("slave {}", sc.address), {profiles[i % 3]});
      chips.push_back(k);
      log.emplace_back();
      Chip& chip = seg.chip(k);
      DirectBus bus(chip);
      users.back()->init(bus);
      Responder* r = users.back().get();
      if (i == 4) {
        Cpu::Program p;
        p.isr = [r](BusPort& b) { r->isr(b); };
        p.main_step = [](BusPort& b) { (void)b.read(0x00); };
        seg.set_firmware(k, std::move(p));
      } else {
        seg.set_firmware(k, [r](BusPort& b) { r->isr(b); });
      }
      if (i >= watched) continue;
      std::vector<std::string>* out = &log.back();
      chip.on_irq_change(
          [out](std::uint64_t cy, bool on) { out->push_back(fmt::format("{} irq {}", cy, on)); });
      if (watch_txd) {
        chip.on_txd(
            [out](std::uint64_t cy, bool l) { out->push_back(fmt::format("{} txd {}", cy, l)); });
      }
      chip.on_bus_access([out](std::uint64_t cy, const BusAccess& a) {
        out->push_back(
            fmt::format("{} bus {} {:x} {:x}", cy, a.write, a.addr, a.write ? a.data : 0));
      });
      watch_telegrams(i);
    }
    master_station = seg.add_sender("master 2");
    other = seg.add_sender("station 30");
    master = std::make_unique<DpMaster>(seg, master_station, MasterConfig{2, baud}, slaves);
  }
  // Every telegram chip i takes, with its counters and state then (added through chip(i)).
  void watch_telegrams(std::size_t i) {
    std::vector<std::string>* out = &log[i];
    Chip* c = &seg.chip(chips[i]);
    c->on_telegram([out, c](const Telegram& t) {
      out->push_back(fmt::format("{} tel {} {}..{} {} | {} dp {} wd {}", c->cycle(), t.from_chip,
                                 t.start, t.end, fmt::join(t.bytes, " "),
                                 counters_text(c->fdl_counters()), static_cast<int>(c->dp_state()),
                                 static_cast<int>(c->wd_state())));
    });
  }
  Segment seg;
  std::vector<SlaveConfig> slaves;
  std::vector<std::unique_ptr<Responder>> users;
  std::vector<std::size_t> chips;
  std::vector<std::vector<std::string>> log;
  std::vector<std::string> line;
  std::vector<std::string> wire;
  std::size_t master_station = 0;
  std::size_t other = 0;
  std::unique_ptr<DpMaster> master;
};

// Both beds at the same cycle, every chip's snapshot and everything it showed so far the same.
// What the master received: each exchange's cycles and answer.
std::vector<std::string> received_of(const DpMaster& m) {
  std::vector<std::string> out;
  for (const Exchange& e : m.history()) {
    out.push_back(fmt::format("{}..{} answer {}..{} {}", e.request_start, e.request_end,
                              e.answer_start, e.answer_end,
                              e.answer ? fmt::format("{}", fmt::join(fdl::encode(*e.answer), " "))
                                       : std::string("none")));
  }
  return out;
}

std::vector<std::string> received(const Bed& b) { return received_of(*b.master); }

void expect_same(Bed& fast, Bed& ref, const std::string& where) {
  ASSERT_EQ(fast.line, ref.line) << where << ": the line's telegrams";
  ASSERT_EQ(fast.wire, ref.wire) << where << ": the line's edges (on_line)";
  ASSERT_EQ(received(fast), received(ref)) << where << ": the master's exchanges";
  ASSERT_EQ(fast.master->counters().answered, ref.master->counters().answered) << where;
  ASSERT_EQ(fast.master->counters().bad_answer, ref.master->counters().bad_answer) << where;
  ASSERT_EQ(fast.seg.cycle(), ref.seg.cycle()) << where;
  for (std::size_t i = 0; i < fast.chips.size(); ++i) {
    const std::vector<std::string>& a = fast.log[i];
    const std::vector<std::string>& b = ref.log[i];
    std::size_t k = 0;
    while (k < a.size() && k < b.size() && a[k] == b[k]) ++k;
    ASSERT_TRUE(k == a.size() && k == b.size())
        << where << ", slave " << i << ", event " << k << ": telegram level '"
        << (k < a.size() ? a[k] : "(none)") << "', reference '" << (k < b.size() ? b[k] : "(none)")
        << "'";
    const Chip& fc = fast.seg.chip(fast.chips[i]);
    const Chip& rc = ref.seg.chip(ref.chips[i]);
    ASSERT_EQ(fc.cycle(), rc.cycle()) << where << ", slave " << i;
    ASSERT_EQ(counters_text(fc.fdl_counters()), counters_text(rc.fdl_counters()))
        << where << ", slave " << i;
    const std::vector<std::uint8_t> sa = fc.save_state();
    const std::vector<std::uint8_t> sb = rc.save_state();
    std::size_t d = 0;
    while (d < sa.size() && d < sb.size() && sa[d] == sb[d]) ++d;
    ASSERT_TRUE(d == sa.size() && d == sb.size())
        << where << ", slave " << i << ": the snapshots differ from byte " << d << " of "
        << sa.size() << " / " << sb.size();
  }
}

// A telegram of the scripted station from `start`, both beds stopped inside it and after it.
void foreign(Bed& fast, Bed& ref, const std::vector<std::uint8_t>& bytes, std::uint64_t start,
             const std::string& what, UartFault fault = {}) {
  const std::uint64_t t = fast.seg.bit_cycles();
  for (Bed* b : {&fast, &ref}) b->seg.send(b->other, bytes, start, fault);
  const std::uint64_t end = start + bytes.size() * 11 * t;
  // Inside it both lines gave every chip the whole telegram at its start; after it, once an
  // answer to it is over too (a receiver given an answer's edges as they come, on the reference
  // line, has sampled less of it than one given the answer whole: not a state a snapshot compares
  // inside a character).
  for (const std::uint64_t at :
       {start + 5 * t, start + 10 * t + t / 2, end - t / 2, end + 400 * t}) {
    for (Bed* b : {&fast, &ref}) b->seg.run_until(at);
    ASSERT_NO_FATAL_FAILURE(
        expect_same(fast, ref, fmt::format("{} from {} to {}, at {}", what, start, end, at)));
  }
}

// Foreign telegram k of a run: a request to an absent station, a token, an answer, a short
// acknowledge, a request with a bad FCS, in turn.
std::vector<std::uint8_t> foreign_telegram(std::size_t k) {
  using fdl::Function;
  std::vector<std::uint8_t> bytes;
  switch (k % 5) {
    case 0:
      return fdl::encode(fdl::make_frame(static_cast<std::uint8_t>(40 + k % 80), 30,
                                         fdl::make_request_fc(Function::FDL_Status, false, false)));
    case 1:
      return {fdl::SD4, 9, 30};
    case 2:
      return fdl::encode(
          fdl::make_frame(30, 41, fdl::make_response_fc(fdl::Response::OK), {1, 2, 3}));
    case 3:
      return {fdl::SC};
    default:
      bytes = fdl::encode(
          fdl::make_frame(43, 30, fdl::make_request_fc(Function::SRD_high, true, true), {7, 7}));
      bytes[bytes.size() - 2] ^= 1;  // a bad FCS
      return bytes;
  }
}

// Telegram k of a mixed run: foreign_telegram's five kinds; frames the assembler breaks at their
// last character (LE beyond the longest telegram: oversize; LE and LEr differ: le_mismatch; an
// unknown start delimiter alone: bad_sd), after which the MAC skips; an unknown start delimiter
// followed by more characters (its verdict at the first: not folded); a wrong end delimiter.
std::vector<std::uint8_t> mixed_telegram(std::size_t k) {
  std::vector<std::uint8_t> bytes;
  switch (k % 10) {
    case 5:
      return {fdl::SD2, 250, 250};
    case 6:
      return {fdl::SD2, 5, 6};
    case 7:
      return {0x33};
    case 8:
      return {0x33, 44, 30, 0x49};
    case 9:
      bytes = fdl::encode(
          fdl::make_frame(45, 30, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
      bytes.back() ^= 1;  // not ED
      return bytes;
    default:
      return foreign_telegram(k);
  }
}

// A segment's telegrams heard whole come from a HeardFramePool: a frame someone holds (a chip, the
// telegram log) is never handed out again; one nobody holds is, filled as HeardFrame::make fills a
// new one, nothing left of the telegram it held before.
TEST(SegmentSpeed, APoolHandsOutOnlyFramesNobodyHolds) {
  const std::vector<std::uint8_t> first = fdl::encode(fdl::make_frame(5, 2, 0x7D, {1, 2, 3}));
  const std::vector<std::uint8_t> second =
      fdl::encode(fdl::make_frame(6, 2, 0x6D, {4, 5, 6, 7}, 61, 62));
  // A broken telegram: the assembler's verdict at its fourth character (no SD2 there), nothing
  // decoded.
  const std::vector<std::uint8_t> third = {fdl::SD2, 7, 7, 0x10, 1, 2, 3};
  HeardFramePool pool;
  const auto a = pool.make(first);
  auto b = pool.make(second);
  EXPECT_NE(a.get(), b.get());
  const HeardFrame* freed = b.get();
  b.reset();
  const auto c = pool.make(third);
  EXPECT_EQ(c.get(), freed);
  const auto want = HeardFrame::make(third);
  EXPECT_EQ(c->bytes, want->bytes);
  EXPECT_EQ(c->verdict, want->verdict);
  EXPECT_EQ(c->frame.status(), want->frame.status());
  EXPECT_EQ(c->frame.error(), want->frame.error());
  EXPECT_EQ(fdl::error_name(c->decoded.error), fdl::error_name(want->decoded.error));
  EXPECT_EQ(c->decoded.frame, want->decoded.frame);
  const auto d = pool.make(second);  // all held: a new one
  EXPECT_NE(d.get(), a.get());
  EXPECT_NE(d.get(), c.get());
  EXPECT_EQ(a->bytes, first);
  EXPECT_EQ(a->decoded.frame, fdl::make_frame(5, 2, 0x7D, {1, 2, 3}));
}

// The fold (docs/segment.md): 60 telegrams of mixed_telegram's kinds whose verdicts are at their
// last character, with gaps of 0 to 100 bit times, heard by a chip offline one by one (each at its
// start, stepped to the next) and by one that hears the first, takes the others but the last as
// one run (TelegramLog::run) and hears the last: the same counters and snapshot at the end. A
// chip that did not hear the telegram before the run takes nothing of it.
TEST(SegmentSpeed, ARunFoldedIsItsTelegramsHeardOneByOne) {
  Chip one;
  Chip folded;
  Chip stranger;
  const std::uint32_t t = one.bit_cycles();
  TelegramLog log;
  const std::uint64_t gaps[] = {40, 20, 0, 33, 32, 100, 5};
  std::uint64_t at = 100 * std::uint64_t{t};
  for (std::size_t k = 0; log.end() < 60; ++k) {
    if (k % 10 == 8) continue;  // its verdict is at its first character
    const auto f = HeardFrame::make(mixed_telegram(k));
    log.append(f, at, 0, t);
    at += (f->bytes.size() * 11 + gaps[k % 7]) * t;
  }
  const auto hear = [&](Chip& c, std::uint64_t n) {
    const TelegramLog::Entry& e = log.at(n);
    c.step(e.start - c.cycle());
    c.hear_telegram(e.frame, e.start, t);
  };
  for (std::uint64_t n = 0; n < log.end(); ++n) hear(one, n);
  ASSERT_EQ(log.folds_until(1, UINT64_MAX), log.end());
  hear(folded, 0);
  folded.step(log.at(1).start - folded.cycle());
  stranger.step(log.at(1).start);
  const HeardRun run = log.run(1, log.end() - 1, t);
  ASSERT_TRUE(folded.hear_run(run));
  ASSERT_FALSE(stranger.hear_run(run));
  hear(folded, log.end() - 1);
  for (Chip* c : {&one, &folded, &stranger}) c->step(at - c->cycle());
  EXPECT_EQ(counters_text(folded.fdl_counters()), counters_text(one.fdl_counters()));
  EXPECT_GT(one.fdl_counters().no_sync, 3U);
  EXPECT_GT(one.fdl_counters().offline, 3U);
  EXPECT_GT(one.fdl_counters().oversize + one.fdl_counters().le_mismatch, 3U);
  EXPECT_EQ(folded.save_state(), one.save_state());
  EXPECT_EQ(stranger.fdl_counters(), FdlCounters{});
}

// The end of a run of foreign telegrams: both lines to `at`, then slave 8 (chip 3) addressed.
void slave_8_after(Bed& fast, Bed& ref, std::uint64_t at, const std::string& run) {
  for (Bed* b : {&fast, &ref}) b->seg.run_until(at);
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "after the " + run));
  for (Bed* b : {&fast, &ref}) {
    b->master->select(3);
    b->master->data_exchange({5, 6, 7, 8});
  }
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "slave 8 after the " + run));
}

// A run of 24 foreign telegrams back to back after TSYN (requests to absent stations, tokens,
// answers, short acknowledges, a bad FCS), the line looked at inside some of them; at the
// twelfth chip 3 gets an on_telegram observer through chip(i); then slave 8 (chip 3) addressed.
void foreign_run(Bed& fast, Bed& ref) {
  const std::uint64_t t = fast.seg.bit_cycles();
  std::uint64_t at = fast.seg.cycle() + 40 * t;
  for (std::size_t k = 0; k < 24; ++k) {
    const std::vector<std::uint8_t> bytes = foreign_telegram(k);
    std::uint64_t end = 0;
    for (Bed* b : {&fast, &ref}) end = b->seg.send(b->other, bytes, at);
    if (k % 7 == 3) {
      for (Bed* b : {&fast, &ref}) b->seg.run_until(end - t / 2);
      ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, fmt::format("foreign run, telegram {}", k)));
    }
    if (k == 12) {
      for (Bed* b : {&fast, &ref}) b->watch_telegrams(3);
    }
    at = end + 40 * t;
  }
  ASSERT_NO_FATAL_FAILURE(slave_8_after(fast, ref, at, "foreign run"));
}

void run_both_ways(std::uint32_t baud, std::size_t n = 5, bool watch_txd = true,
                   std::size_t watched = SIZE_MAX, bool watch_line = false) {
  Bed fast(false, baud, n, watch_txd, watched, watch_line);
  Bed ref(true, baud, n, watch_txd, watched, watch_line);
  for (Bed* b : {&fast, &ref}) ASSERT_TRUE(b->master->startup_all());
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "after the start-up"));
  for (int round = 0; round < 2; ++round) {
    for (std::size_t i = 0; i < n; ++i) {
      for (Bed* b : {&fast, &ref}) {
        b->master->select(i);
        b->master->data_exchange({static_cast<std::uint8_t>(round), 2, 3, 4});
      }
      ASSERT_NO_FATAL_FAILURE(
          expect_same(fast, ref, fmt::format("round {}, Data_Exchange with slave {}", round, i)));
    }
  }
  ASSERT_NO_FATAL_FAILURE(foreign_run(fast, ref));
  const std::uint64_t t = fast.seg.bit_cycles();
  using fdl::Function;
  const auto req = [](std::uint8_t da, Function f) {
    return fdl::encode(fdl::make_frame(da, 30, fdl::make_request_fc(f, false, false)));
  };
  std::uint64_t at = fast.seg.cycle() + 40 * t;
  // A token, a request to an absent station, one to slave 6 without TSYN before it, line noise
  // that is no frame, a damaged telegram, a frame for another station after noise.
  ASSERT_NO_FATAL_FAILURE(foreign(fast, ref, {fdl::SD4, 9, 30}, at, "token"));
  at = fast.seg.cycle() + 40 * t;
  ASSERT_NO_FATAL_FAILURE(
      foreign(fast, ref, req(40, Function::FDL_Status), at, "request to station 40"));
  // 20 bit times after a token: less than TSYN.
  at = fast.seg.cycle() + 40 * t;
  for (Bed* b : {&fast, &ref})
    b->seg.send(b->other, std::vector<std::uint8_t>{fdl::SD4, 9, 30}, at);
  at += 3 * 11 * t + 20 * t;
  ASSERT_NO_FATAL_FAILURE(
      foreign(fast, ref, req(6, Function::FDL_Status), at, "request without TSYN"));
  at = fast.seg.cycle() + 40 * t;
  ASSERT_NO_FATAL_FAILURE(foreign(fast, ref, {0x10, 0x33}, at, "noise"));
  at = fast.seg.cycle() + 40 * t;
  ASSERT_NO_FATAL_FAILURE(foreign(fast, ref, req(41, Function::FDL_Status), at, "parity fault",
                                  {1, UartFault::Kind::parity}));
  at = fast.seg.cycle() + 40 * t;
  ASSERT_NO_FATAL_FAILURE(
      foreign(fast, ref, req(42, Function::FDL_Status), at, "request to station 42"));
  // Slave 6 answers the scripted station, which drives into the answer (a collision: the answer
  // keeps the line, the token is not heard); the master takes the answer's characters as strays.
  at = fast.seg.cycle() + 40 * t;
  std::uint64_t end = 0;
  for (Bed* b : {&fast, &ref}) end = b->seg.send(b->other, req(6, Function::FDL_Status), at);
  for (Bed* b : {&fast, &ref}) {
    b->seg.send(b->other, std::vector<std::uint8_t>{fdl::SD4, 9, 30}, end + 40 * t);
    b->seg.run_until(end + 400 * t);
  }
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "a collision with slave 6's answer"));
  ASSERT_EQ(fast.seg.collisions().size(), ref.seg.collisions().size());
  ASSERT_FALSE(fast.seg.collisions().empty());
  EXPECT_EQ(fast.seg.collisions().back().cycle, ref.seg.collisions().back().cycle);
  // The master's own faults: a damaged request (no answer), a glitch and line noise, then an
  // exchange.
  for (Bed* b : {&fast, &ref}) {
    b->master->select(1);
    b->master->transact(
        fdl::make_frame(6, 2, fdl::make_request_fc(Function::FDL_Status, false, false)),
        {2, UartFault::Kind::parity});
    b->master->glitch(t / 3);
    b->master->line_noise(std::vector<std::uint8_t>{0x55, 0x0f}, 33);
    b->master->slave_diag();
  }
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "the master's faults"));
  // A broadcast Global_Control, then slave 7 no longer polled until its DP watchdog expires.
  for (Bed* b : {&fast, &ref}) b->master->global_control(0x08);
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "Global_Control"));
  for (int k = 0; k < 1000 && fast.seg.chip(fast.chips[2]).dp_state() == DpState::Data_Exchange;
       ++k) {
    for (Bed* b : {&fast, &ref}) {
      b->master->select(0);
      b->master->data_exchange({9, 9, 9, 9});
    }
    ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "slave 7 not polled"));
  }
  EXPECT_EQ(fast.seg.chip(fast.chips[2]).dp_state(), DpState::Wait_Prm);
}

// The telegram log (docs/segment.md, "The telegram log"): all slaves but the first unwatched, so
// they take the 240 foreign telegrams back to back (more than the log keeps before it brings the
// laggards up) at their next step; the line is looked at through chip(i) inside some of them
// (counters, snapshots), slave 7 gets an on_telegram observer in the middle, the master sends a
// Global_Control broadcast and a Data_Exchange to the last slave inside the run (slave 9's
// firmware runs in every round), then slave 8 is addressed. `mixed`: mixed_telegram's kinds, with
// gaps of 0 to 100 bit times (TSYN or not: counted as no_sync, skipped; the fold, docs/segment.md).
void log_run(std::uint32_t baud, std::size_t n, bool mixed = false) {
  Bed fast(false, baud, n, false, 1);
  Bed ref(true, baud, n, false, 1);
  for (Bed* b : {&fast, &ref}) ASSERT_TRUE(b->master->startup_all());
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "after the start-up"));
  const std::uint64_t t = fast.seg.bit_cycles();
  std::uint64_t at = fast.seg.cycle() + 40 * t;
  const std::uint64_t gaps[] = {40, 20, 0, 33, 32, 100, 5};
  for (std::size_t k = 0; k < 240; ++k) {
    std::uint64_t end = 0;
    const std::vector<std::uint8_t> bytes = mixed ? mixed_telegram(k) : foreign_telegram(k);
    for (Bed* b : {&fast, &ref}) end = b->seg.send(b->other, bytes, at);
    at = end + (mixed ? gaps[k % 7] : 40) * t;
    if (k % 37 == 11) {
      for (Bed* b : {&fast, &ref}) b->seg.run_until(end - t / 2);
      ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, fmt::format("log run, telegram {}", k)));
    }
    if (k == 60) {
      for (Bed* b : {&fast, &ref}) b->watch_telegrams(2);
    }
    if (k == 100 || k == 170) {
      for (Bed* b : {&fast, &ref}) {
        b->seg.run_until(at);
        if (k == 100) {
          b->master->global_control(0x08);
        } else {
          b->master->select(n - 1);
          const Exchange ex = b->master->data_exchange({4, 3, 2, 1});
          // The wait ends at the answer's last stop sample (docs/timing.md: end - T + floor(T/2)),
          // not a slot time after a character whose stop sample left the receiver idle. The
          // request keeps TSYN after the telegram before it, whoever sent it (docs/timing.md, "The
          // master's wait"), so the slave takes it also in the `mixed` run, where that telegram's
          // gap is 0 (until the twenty-eighth session the master sent back to back there: the
          // slave counted no_sync and did not answer).
          ASSERT_TRUE(ex.answer.has_value());
          EXPECT_EQ(b->seg.cycle(), ex.answer_end - t + t / 2);
        }
      }
      at = fast.seg.cycle() + 40 * t;
    }
  }
  ASSERT_NO_FATAL_FAILURE(slave_8_after(fast, ref, at, "log run"));
}

TEST(SegmentSpeed, TheTelegramLogOfFiveSlavesShowsWhatTheReferenceLineShowsAt1M5) {
  log_run(1'500'000, 5);
}

TEST(SegmentSpeed, TheTelegramLogOfFiveSlavesShowsWhatTheReferenceLineShowsAt12M) {
  log_run(12'000'000, 5);
}

TEST(SegmentSpeed, TheTelegramLogOfThirtyThreeSlavesShowsWhatTheReferenceLineShowsAt1M5) {
  log_run(1'500'000, 33);
}

TEST(SegmentSpeed, TheTelegramLogOfThirtyThreeSlavesShowsWhatTheReferenceLineShowsAt12M) {
  log_run(12'000'000, 33);
}

// The log's trim (docs/segment.md, "The telegram log"): slaves 6, 7 and 8 (unwatched) polled in
// turn with ten foreign telegrams after each exchange (the last a request to an absent station),
// so that the log outgrows its bound (64 + 4 per station, 92 here) while none of them lags by half
// of it: the entries all three took are forgotten and none is brought up early; each takes the
// rest, folded, when next polled. Every chip's counters, snapshot and telegrams against the
// reference line at the end.
void polled_log_run(std::uint32_t baud) {
  Bed fast(false, baud, 5, false, 1);
  Bed ref(true, baud, 5, false, 1);
  for (Bed* b : {&fast, &ref}) ASSERT_TRUE(b->master->startup_all());
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "after the start-up"));
  const std::uint64_t t = fast.seg.bit_cycles();
  for (std::size_t k = 0; k < 60; ++k) {
    for (Bed* b : {&fast, &ref}) {
      b->master->select(1 + k % 3);
      b->master->data_exchange({static_cast<std::uint8_t>(k), 1, 2, 3});
    }
    std::uint64_t at = fast.seg.cycle() + 40 * t;
    for (std::size_t j = 0; j < 10; ++j) {
      std::uint64_t end = 0;
      for (Bed* b : {&fast, &ref}) end = b->seg.send(b->other, foreign_telegram(5 * k + j + 1), at);
      at = end + 40 * t;
    }
    for (Bed* b : {&fast, &ref}) b->seg.run_until(at);
  }
  ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, "slaves polled in turn"));
  EXPECT_GT(fast.seg.chip(fast.chips[1]).fdl_counters().foreign_address, 100U);
}

TEST(SegmentSpeed, TheTelegramLogOfSlavesPolledInTurnShowsWhatTheReferenceLineShowsAt1M5) {
  polled_log_run(1'500'000);
}

TEST(SegmentSpeed, TheTelegramLogOfSlavesPolledInTurnShowsWhatTheReferenceLineShowsAt12M) {
  polled_log_run(12'000'000);
}

TEST(SegmentSpeed, AMixedTelegramLogOfFiveSlavesShowsWhatTheReferenceLineShowsAt1M5) {
  log_run(1'500'000, 5, true);
}

TEST(SegmentSpeed, AMixedTelegramLogOfThirtyThreeSlavesShowsWhatTheReferenceLineShowsAt12M) {
  log_run(12'000'000, 33, true);
}

// The segment of bench/bench_segment.cpp (8 + 8 bytes, the user side on each SPC3's host CPU,
// nobody watching the chips): its DP cycles on both lines, the line's time and every chip's
// counters and snapshot compared after each (most chips take their telegrams from the log).
void bench_cycles(std::uint32_t baud, std::size_t n) {
  std::vector<std::unique_ptr<Segment>> segs;
  std::vector<std::unique_ptr<Responder>> users;
  std::vector<std::unique_ptr<DpMaster>> masters;
  for (const bool reference : {false, true}) {
    segs.push_back(std::make_unique<Segment>(baud));
    Segment& seg = *segs.back();
    seg.use_reference_line(reference);
    std::vector<SlaveConfig> slaves;
    for (std::size_t i = 0; i < n; ++i) {
      SlaveConfig sc;
      sc.address = static_cast<std::uint8_t>(3 + i);
      sc.cfg = {0x17, 0x27};  // 8 bytes in, 8 bytes out
      sc.in_len = 8;
      sc.out_len = 8;
      slaves.push_back(sc);
      add_user(users, sc).set_inputs(std::vector<std::uint8_t>(8, static_cast<std::uint8_t>(i)));
      const std::size_t k = seg.add_chip("slave", ChipOptions{Profile::spc3});
      DirectBus bus(seg.chip(k));
      users.back()->init(bus);
      Responder* r = users.back().get();
      seg.set_firmware(k, [r](BusPort& b) { r->isr(b); });
    }
    const std::size_t m = seg.add_sender("master");
    masters.push_back(std::make_unique<DpMaster>(seg, m, MasterConfig{2, baud}, slaves));
    ASSERT_TRUE(masters.back()->startup_all());
  }
  const std::vector<std::vector<std::uint8_t>> outputs(n, std::vector<std::uint8_t>(8, 0x55));
  for (int cycle = 0; cycle < 12; ++cycle) {
    for (auto& m : masters) m->dp_cycle(outputs);
    ASSERT_EQ(segs[0]->cycle(), segs[1]->cycle()) << "DP cycle " << cycle;
    for (std::size_t i = 0; i < n; ++i) {
      const Chip& a = segs[0]->chip(i);
      const Chip& b = segs[1]->chip(i);
      ASSERT_EQ(a.cycle(), b.cycle()) << "DP cycle " << cycle << ", slave " << i;
      ASSERT_EQ(counters_text(a.fdl_counters()), counters_text(b.fdl_counters()))
          << "DP cycle " << cycle << ", slave " << i;
      ASSERT_EQ(a.save_state(), b.save_state()) << "DP cycle " << cycle << ", slave " << i;
    }
  }
}

TEST(SegmentSpeed, TheBenchsDpCyclesAreTheReferenceLinesAt1M5) { bench_cycles(1'500'000, 8); }

TEST(SegmentSpeed, TheBenchsDpCyclesAreTheReferenceLinesAt12M) { bench_cycles(12'000'000, 8); }

TEST(SegmentSpeed, TheTelegramLevelLineShowsWhatTheReferenceLineShowsAt1M5) {
  run_both_ways(1'500'000);
}

TEST(SegmentSpeed, TheTelegramLevelLineShowsWhatTheReferenceLineShowsAt12M) {
  run_both_ways(12'000'000);
}

// Seventeen slaves and two senders: the round's tree of next events (Segment::due_by) four
// levels deep, chips due in both halves of it in one round.
TEST(SegmentSpeed, SeventeenSlavesShowWhatTheReferenceLineShowsAt12M) {
  run_both_ways(12'000'000, 17);
}

// Nobody watching the chips' TxD: their answers stay characters, and the line relays them from the
// answers the chips armed (Chip::on_answer), checked against Chip::on_txd_chars.
TEST(SegmentSpeed, AnswersKeptAsCharactersShowWhatTheReferenceLineShowsAt1M5) {
  run_both_ways(1'500'000, 5, false);
}

TEST(SegmentSpeed, AnswersKeptAsCharactersShowWhatTheReferenceLineShowsAt12M) {
  run_both_ways(12'000'000, 5, false);
}

// Only slaves 5 and 6 watched: the verdicts of the others that show nothing (foreign requests,
// tokens, answers, a bad FCS) are no events of the line (Chip::line_deadline); slave 9's firmware
// runs in every round.
TEST(SegmentSpeed, QuietVerdictsShowWhatTheReferenceLineShowsAt1M5) {
  run_both_ways(1'500'000, 5, false, 2);
}

TEST(SegmentSpeed, QuietVerdictsShowWhatTheReferenceLineShowsAt12M) {
  run_both_ways(12'000'000, 5, false, 2);
}

TEST(SegmentSpeed, QuietVerdictsOfSeventeenSlavesShowWhatTheReferenceLineShowsAt12M) {
  run_both_ways(12'000'000, 17, false, 0);
}

// Chip::line_deadline on a started slave at 1.5 Mbaud hearing telegrams whole: the verdict of a
// frame is at the stop sample of its last character (docs/timing.md "Serial line": a request is
// acted on at the stop-bit sample of its last character, T/2 into the stop bit, bit 10 of 11).
// It is an event of the line only where it shows something: a request to the chip, or any frame
// while an on_telegram observer watches.
TEST(SegmentSpeed, AVerdictThatShowsNothingIsNoEventOfTheLine) {
  Bed bed(false, 1'500'000, 5, false, 0);
  ASSERT_TRUE(bed.master->startup_all());
  const std::uint64_t t = bed.seg.bit_cycles();
  ASSERT_EQ(t, 32u);  // 48 MHz / 1.5 Mbaud
  using fdl::Function;
  const auto verdict_of = [&](std::uint8_t da) {
    const auto bytes = fdl::encode(
        fdl::make_frame(da, 30, fdl::make_request_fc(Function::FDL_Status, false, false)));
    const std::uint64_t start = bed.seg.cycle() + 40 * t;
    bed.seg.send(bed.other, bytes, start);
    const Chip& c = bed.seg.chip(bed.chips[0]);  // slave 5, at `start` now
    EXPECT_EQ(c.cycle(), start);
    const std::uint64_t verdict = start + (11 * (bytes.size() - 1) + 10) * t + t / 2;
    EXPECT_EQ(c.next_deadline(), verdict);
    const std::uint64_t line = c.line_deadline();
    bed.seg.run_until(verdict + 400 * t);
    return std::pair{verdict, line};
  };
  const auto [foreign_at, foreign_line] = verdict_of(40);
  EXPECT_GT(foreign_line, foreign_at) << "a request to station 40 shows nothing in slave 5";
  const auto [own_at, own_line] = verdict_of(5);
  EXPECT_EQ(own_line, own_at) << "a request to slave 5 is served there";
  bed.watch_telegrams(0);
  const auto [watched_at, watched_line] = verdict_of(40);
  EXPECT_EQ(watched_line, watched_at) << "its on_telegram observer is told of it there";
}

// A waveform's observer of the line (Segment::on_line): the requests' and answers' edges are made
// for it, the same as the reference line's.
TEST(SegmentSpeed, TheLinesEdgesForAnObserverAreTheReferenceLinesAt1M5) {
  run_both_ways(1'500'000, 5, false, SIZE_MAX, true);
}

TEST(SegmentSpeed, TheLinesEdgesForAnObserverAreTheReferenceLinesAt12M) {
  run_both_ways(12'000'000, 5, false, SIZE_MAX, true);
}

// A User_Timer_Clock tick (every 1 ms while the chip is started: SPC3 manual, Mode_Reg0
// User_Time_Base) is an event of the line only while its IRR bit is clear: with the bit set it
// changes nothing anyone sees until a bus access acknowledges it, and the chip takes it inside its
// next step (Chip::line_deadline).
TEST(SegmentSpeed, AUserTimerTickWhileItsBitIsSetIsNoEventOfTheLine) {
  Chip chip({Profile::spc3});
  std::vector<std::unique_ptr<Responder>> users;
  DirectBus bus(chip);
  add_user(users, SlaveConfig{}).init(bus);
  const std::uint64_t ms = chip.clock_hz() / 1000;
  const std::uint64_t tick = chip.next_deadline();
  ASSERT_LE(tick, chip.cycle() + ms);
  EXPECT_EQ(chip.line_deadline(), tick);  // the bit is clear: the tick raises it
  chip.step(tick - chip.cycle());
  ASSERT_NE(chip.probe().irr & irq::User_Timer_Clock, 0);
  EXPECT_EQ(chip.next_deadline(), tick + ms);
  EXPECT_GT(chip.line_deadline(), tick + ms);
}

// A user may step a chip through the Chip& chip(i) gave it, between runs (a DirectBus): the line's
// time follows it (Segment::cycle, which looks at no chip: Chip::on_cycle tells it), back too where
// a snapshot takes the chip back, and the line goes on from there as the reference line does.
TEST(SegmentSpeed, AChipSteppedThroughItsChipReferenceMovesTheLinesTime) {
  Bed fast(false, 1'500'000, 5, false, 0);
  Bed ref(true, 1'500'000, 5, false, 0);
  for (Bed* b : {&fast, &ref}) ASSERT_TRUE(b->master->startup_all());
  const auto exchanges = [&](const std::string& where) {
    for (std::size_t i = 0; i < 5; ++i) {
      for (Bed* b : {&fast, &ref}) {
        b->master->select(i);
        b->master->data_exchange({1, 2, 3, 4});
      }
    }
    ASSERT_NO_FATAL_FAILURE(expect_same(fast, ref, where));
  };
  ASSERT_NO_FATAL_FAILURE(exchanges("after the start-up"));
  for (Bed* b : {&fast, &ref}) {
    Chip& c = b->seg.chip(b->chips[1]);  // slave 6, at the line's time
    const std::uint64_t now = b->seg.cycle();
    ASSERT_EQ(c.cycle(), now);
    const std::vector<std::uint8_t> before = c.save_state();
    c.step(1000);
    EXPECT_EQ(b->seg.cycle(), now + 1000) << "step";
    (void)c.read(static_cast<std::uint32_t>(c.addr_of(RegId::Status_Reg)));
    EXPECT_EQ(b->seg.cycle(), now + 1000 + c.bus_access_cycles()) << "a bus access";
    c.load_state(before);
    EXPECT_EQ(b->seg.cycle(), now) << "back to the snapshot";
    c.step(777);
    EXPECT_EQ(b->seg.cycle(), now + 777) << "step after the snapshot";
  }
  ASSERT_NO_FATAL_FAILURE(exchanges("after slave 6 was stepped alone"));
}

// Two chips at one address, each with the built-in user side on its host CPU, answer every
// request at once (docs/segment.md, "A firmware across a round's end", case 3): the second
// driver's answer collides while both ISRs run. Every bus access of both firmwares, the
// collisions and the snapshots are the reference line's (the rounds a collision ends are the
// colliding edges, its chip's deadlines, on both lines).
void twins(std::uint32_t baud) {
  struct Twins {
    Segment seg;
    std::vector<std::unique_ptr<Responder>> users;
    std::vector<std::vector<std::string>> log{2};
    std::unique_ptr<DpMaster> master;
    explicit Twins(std::uint32_t b) : seg(b) {}
  };
  SlaveConfig sc;
  sc.address = 5;
  std::vector<std::unique_ptr<Twins>> beds;
  for (const bool reference : {false, true}) {
    beds.push_back(std::make_unique<Twins>(baud));
    Twins& b = *beds.back();
    b.seg.use_reference_line(reference);
    for (const Profile p : {Profile::spc3, Profile::dpc31}) {
      add_user(b.users, sc).set_inputs({static_cast<std::uint8_t>(p), 1, 2, 3});
      const std::size_t k = b.seg.add_chip(fmt::format("twin {}", profile_name(p)), {p});
      Chip& chip = b.seg.chip(k);
      DirectBus bus(chip);
      b.users.back()->init(bus);
      Responder* r = b.users.back().get();
      b.seg.set_firmware(k, [r](BusPort& bp) { r->isr(bp); });
      std::vector<std::string>* out = &b.log[k];
      chip.on_bus_access([out](std::uint64_t cy, const BusAccess& a) {
        out->push_back(
            fmt::format("{} bus {} {:x} {:x}", cy, a.write, a.addr, a.write ? a.data : 0));
      });
    }
    b.master = std::make_unique<DpMaster>(b.seg, b.seg.add_sender("master"), MasterConfig{2, baud},
                                          std::vector<SlaveConfig>{sc});
    ASSERT_TRUE(b.master->startup_all());
    for (std::uint8_t k = 0; k < 4; ++k) b.master->data_exchange({k, 2, 3, 4});
  }
  const Twins& fast = *beds[0];
  const Twins& ref = *beds[1];
  ASSERT_FALSE(fast.seg.collisions().empty());
  ASSERT_EQ(fast.seg.collisions().size(), ref.seg.collisions().size());
  for (std::size_t i = 0; i < fast.seg.collisions().size(); ++i)
    EXPECT_EQ(fast.seg.collisions()[i].cycle, ref.seg.collisions()[i].cycle) << "collision " << i;
  EXPECT_EQ(received_of(*fast.master), received_of(*ref.master));
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(fast.log[k], ref.log[k]) << "twin " << k << "'s bus accesses";
    EXPECT_EQ(fast.seg.chip(k).save_state(), ref.seg.chip(k).save_state()) << "twin " << k;
  }
}

TEST(SegmentSpeed, TwinsWhoseFirmwaresRunThroughACollisionAreTheReferenceLinesAt12M) {
  twins(12'000'000);
}

TEST(SegmentSpeed, TwinsWhoseFirmwaresRunThroughACollisionAreTheReferenceLinesAt1M5) {
  twins(1'500'000);
}

}  // namespace
}  // namespace dpc31
