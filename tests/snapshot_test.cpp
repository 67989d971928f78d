// Snapshots (docs/snapshots.md). The main test runs a live DP session (built-in master on RxD,
// the responder firmware on its CPU thread) and records its stimulus: every RxD edge with the
// cycle it was driven at, every bus access with its start cycle. A replay of that stimulus on a
// fresh chip is stopped at a save point and saved; a third chip loads the snapshot and runs the
// rest of the stimulus. Both must then show the same TxD edges, X/INT changes, telegrams, block
// events and read values, the same memory image and the same final snapshot.
#include "snapshot.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "harness.hpp"
#include "responder.hpp"
#include "test_util.hpp"

using namespace dpc31;
using Bytes = std::vector<std::uint8_t>;
namespace fs = std::filesystem;

namespace {

// One thing the outside world did to the chip.
struct Action {
  enum class Kind : std::uint8_t { rxd, read, write } kind;
  std::uint64_t at;  // the chip's cycle when it was done (a bus access: when it started)
  std::uint64_t edge = 0;
  bool level = false;
  std::uint32_t addr = 0;
  std::uint8_t data = 0;
};

// What a user sees of the chip's state: probe() and the FDL counters (a checksum of them).
using ShownState = std::array<std::uint32_t, 8>;
ShownState observable_state(const Chip& c) {
  const ChipProbe p = c.probe();
  const FdlCounters& n = c.fdl_counters();
  static_assert(std::has_unique_object_representations_v<FdlCounters>);
  return {static_cast<std::uint32_t>(p.dp_state),
          static_cast<std::uint32_t>(p.wd_state),
          p.baud_code,
          p.irr,
          p.dout_buffer_sm,
          p.din_buffer_sm,
          p.diag_buffer_sm,
          snap::crc32({reinterpret_cast<const std::uint8_t*>(&n), sizeof n})};
}

// Everything observable, one line per observation; the state apart, as it changes.
struct Recorder {
  std::vector<std::string> lines;
  // The observable state at the end of each cycle at which on_state_change showed it different
  // from the last one recorded. How many calls the engine makes is its business, not the
  // contract (docs/decisions.md): a telegram heard whole has fewer events than its edges.
  std::vector<std::string> states;
  ShownState shown{};  // the state `states` ends with (or the chip's when primed)
  std::uint64_t pending_cycle = 0;
  std::optional<ShownState> pending;
  void settle() {
    if (pending && *pending != shown) {
      const ShownState& v = *pending;
      states.push_back(fmt::format(
          "state {} dp {} wd {} baud {} irr {:04x} sm {:02x} {:02x} {:02x} counters {:08x}",
          pending_cycle, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]));
      shown = v;
    }
    pending.reset();
  }
  // The chip's state now is what was shown last (a fresh or a just loaded chip).
  void prime(const Chip& c) {
    settle();
    shown = observable_state(c);
  }
  void attach(Chip& c) {
    prime(c);
    c.on_txd([this](std::uint64_t t, bool l) { lines.push_back(fmt::format("txd {} {}", t, l)); });
    c.on_rxd([this](std::uint64_t t, bool l) { lines.push_back(fmt::format("rxd {} {}", t, l)); });
    c.on_irq_change(
        [this](std::uint64_t t, bool a) { lines.push_back(fmt::format("x/int {} {}", t, a)); });
    c.on_state_change([this, &c](std::uint64_t t) {
      if (t != pending_cycle) settle();
      pending_cycle = t;
      pending = observable_state(c);
    });
    c.on_telegram([this](const Telegram& g) {
      lines.push_back(fmt::format("telegram {} {}..{} {:02x}", g.from_chip ? "tx" : "rx", g.start,
                                  g.end, fmt::join(g.bytes, " ")));
    });
    harness::on_block_event(c, [this](std::uint64_t t, const BlockEvent& e) {
      lines.push_back(fmt::format("block {} {} {} {}", t, static_cast<int>(e.kind), e.value,
                                  static_cast<int>(e.data)));
    });
  }
};

struct Live {
  std::vector<Action> actions;
  std::vector<std::string> record;
  std::vector<std::string> states;
  std::vector<Telegram> telegrams;
  std::vector<Exchange> history;
  std::size_t second_search = 0;  // index in history of the first request after the cable pull
  std::uint64_t short_gap = 0;    // between two telegrams 20 bit times apart
  std::uint64_t end = 0;
};

ResponderConfig responder_config() {
  ResponderConfig rc;
  rc.substitute = {0x5A, 0x5B, 0x5C, 0x5D};
  rc.slave.wd_fact1 = 1;  // DP watchdog 5 x 10 ms
  rc.slave.wd_fact2 = 5;
  rc.slave.min_tsdr = 15;  // answers 15 bit times after the request
  return rc;
}

constexpr std::uint32_t kBaud = 1'500'000;
// Three 20 ms search windows less 1 ms, at 48 MHz.
constexpr std::uint64_t kSearchLead = 59 * 48'000;

// Start-up at 1.5 Mbaud (Baud_Search through 12, 6 and 3 Mbaud first), Data_Exchange, Clear,
// diagnostics, a parity error and a broken telegram, the cable pulled until the DP watchdog and
// Baud_Control have run out, and a second start-up through Baud_Search.
Live live_session(testutil::ChipParam p) {
  Live live;
  Chip chip({p.profile, p.bus, 0});
  chip.set_log_sink(nullptr);
  Recorder rec;
  rec.attach(chip);
  const std::uint32_t access = chip.bus_access_cycles();
  chip.on_rxd([&](std::uint64_t at, bool level) {
    live.actions.push_back({Action::Kind::rxd, chip.cycle(), at, level});
  });
  chip.on_bus_access([&](std::uint64_t t, const BusAccess& e) {
    const auto kind = e.write ? Action::Kind::write : Action::Kind::read;
    live.actions.push_back({kind, t - access, 0, false, e.addr, e.data});
  });
  chip.on_telegram([&](const Telegram& g) { live.telegrams.push_back(g); });

  const ResponderConfig rc = responder_config();
  Responder user(rc);
  user.set_inputs({0xA1, 0xA2, 0xA3, 0xA4});
  DirectBus bus(chip);
  user.init(bus);
  {
    DpMaster master(chip, MasterConfig{2, kBaud, 100, 33}, rc.slave);
    master.set_firmware([&](BusPort& c) { user.isr(c); });
    // The search listens 20 ms each at 12, 6 and 3 Mbaud before 1.5 Mbaud (docs/timing.md,
    // "Baud_Search"): the master comes 1 ms before the 1.5 Mbaud window, so a few FDL_Status
    // still fall on another rate, not the 450 of a master polling from Start (each of their
    // edges a save point below).
    master.idle(kSearchLead);
    EXPECT_TRUE(master.startup());
    const Exchange first = master.data_exchange({1, 2, 3, 4});
    // The master lost the answer and repeats (same FCB): the previous answer comes again.
    fdl::Frame again = first.request;
    again.du = {2, 2, 2, 2};
    master.transact(again);
    user.set_inputs({0xB1, 0xB2, 0xB3, 0xB4});
    master.data_exchange({5, 6, 7, 8});
    master.global_control(0x20);  // Sync: outputs wait in D
    master.data_exchange({21, 22, 23, 24});
    master.global_control(0x10);  // Unsync
    master.global_control(0x08);  // Freeze: the inputs given from now on wait for Unfreeze
    user.set_inputs({0xC1, 0xC2, 0xC3, 0xC4});
    master.data_exchange({25, 26, 27, 28});
    master.data_exchange({29, 30, 31, 32});
    master.global_control(0x04);  // Unfreeze
    master.global_control(0x02);  // Clear_Data
    master.idle(2000);
    // The user hands over new diagnostics: Diag_Flag, answers DH until the master fetched them.
    {
      const std::uint8_t sm = chip.read(chip.addr_of(RegId::Diag_Buffer_SM));
      const bool first_buffer = (sm & 0x03) == 0x01;
      const RegId ptr = first_buffer ? RegId::R_Diag_Buf_Ptr1 : RegId::R_Diag_Buf_Ptr2;
      const RegId len = first_buffer ? RegId::R_Len_Diag_Buf1 : RegId::R_Len_Diag_Buf2;
      const std::uint32_t base = std::uint32_t{chip.read(chip.addr_of(ptr))}
                                 << chip.profile().segment_shift;
      const Bytes ext = {0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x42, 0x43};  // Ext_Diag
      for (std::size_t k = 0; k < ext.size(); ++k)
        chip.write(base + static_cast<std::uint32_t>(k), ext[k]);
      chip.write(chip.addr_of(len), static_cast<std::uint8_t>(ext.size()));
      chip.read(chip.addr_of(RegId::New_Diag_Buffer_Cmd));
    }
    master.data_exchange({33, 34, 35, 36});
    master.slave_diag();
    master.data_exchange({9, 10, 11, 12});
    // FDL_Status with a parity error in its FC, an SD2 whose LEr differs from LE, and one that
    // stops after five bytes (truncated when the line has been idle for TSYN).
    master.transact_raw({0x10, 0x05, 0x02, 0x49, 0x50, 0x16},
                        UartFault{3, UartFault::Kind::parity});
    master.transact_raw({0x68, 0x05, 0x06, 0x68, 0x85, 0x82, 0x6D, 0x3E, 0x3C, 0x00, 0x16});
    master.transact_raw({0x68, 0x05, 0x05, 0x68, 0x85});
    // Two telegrams of other stations only 20 bit times apart: the second lacks TSYN.
    {
      const std::uint64_t t = master.bit_cycles();
      const Bytes other = {0x10, 0x09, 0x02, 0x49, 0x54, 0x16};
      const std::uint64_t first_start = chip.cycle() + 40 * t;
      const std::uint64_t first_end = first_start + other.size() * 11 * t;
      std::vector<std::pair<std::uint64_t, bool>> edges;
      uart_encode(other, first_start, static_cast<std::uint32_t>(t), edges);
      uart_encode(other, first_end + 20 * t, static_cast<std::uint32_t>(t), edges);
      for (const auto& [cycle, level] : edges) chip.drive_rxd(cycle, level);
      live.short_gap = first_end + 10 * t;
      master.idle(300 * t);
    }
    master.data_exchange({13, 14, 15, 16});
    // Cable pulled until the DP watchdog (50 ms) and Baud_Control (160 ms, VPC3+ 320 ms) have
    // run out; the master is back within 1 ms of the search restarting at 12 Mbaud.
    for (int ms = 0; ms < 1000 && chip.wd_state() != WdState::Baud_Search; ++ms)
      master.idle(48'000);
    EXPECT_EQ(chip.wd_state(), WdState::Baud_Search);
    master.idle(kSearchLead - 48'000);  // found within 1 ms of the search's restart
    live.second_search = master.history().size();
    EXPECT_TRUE(master.startup());
    master.data_exchange({17, 18, 19, 20});
    master.read_inputs();
    live.history = master.history();
  }
  live.end = chip.cycle() + 5000;
  chip.step(live.end - chip.cycle());
  live.record = rec.lines;
  rec.settle();
  live.states = rec.states;
  return live;
}

// Does actions [i, j) at their cycles, then steps to `until` unless the last access already
// ended later. Returns j.
std::size_t drive(Chip& c, const std::vector<Action>& acts, std::size_t i, std::size_t j,
                  std::uint64_t until, Recorder& rec) {
  for (; i < j; ++i) {
    const Action& a = acts[i];
    if (a.at < c.cycle()) {
      ADD_FAILURE() << "stimulus out of order at action " << i;
      return j;
    }
    if (a.at > c.cycle()) c.step(a.at - c.cycle());
    switch (a.kind) {
      case Action::Kind::rxd:
        c.drive_rxd(a.edge, a.level);
        break;
      case Action::Kind::read:
        rec.lines.push_back(fmt::format("probe {} read {:02x}", c.cycle(), c.read(a.addr)));
        break;
      case Action::Kind::write:
        c.write(a.addr, a.data);
        break;
    }
    // Pins and counters: a field that only delays a change (a pin level until the next edge, a
    // count until the next telegram) shows up here.
    const FdlCounters& n = c.fdl_counters();
    static_assert(std::has_unique_object_representations_v<FdlCounters>);
    rec.lines.push_back(
        fmt::format("probe {} pins {} {} counters {:08x}", c.cycle(), c.txd_pin(), c.x_int_pin(),
                    snap::crc32({reinterpret_cast<const std::uint8_t*>(&n), sizeof n})));
  }
  if (c.cycle() < until) c.step(until - c.cycle());
  return j;
}

// The index of the first action at or after `cycle`.
std::size_t first_action_at(const std::vector<Action>& acts, std::uint64_t cycle) {
  return static_cast<std::size_t>(
      std::find_if(acts.begin(), acts.end(), [&](const Action& a) { return a.at >= cycle; }) -
      acts.begin());
}

// The first difference of two records, with its index, or "" if they are equal.
std::string first_difference(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (a[i] != b[i]) return fmt::format("entry {}: '{}' versus '{}'", i, a[i], b[i]);
  }
  if (a.size() != b.size()) {
    return fmt::format("lengths {} and {}; next: '{}'", a.size(), b.size(),
                       a.size() > n ? a[n] : b[n]);
  }
  return "";
}

std::vector<std::uint8_t> memory_image(const Chip& c) {
  std::vector<std::uint8_t> m(std::size_t{1} << c.profile().address_bits);
  for (std::size_t a = 0; a < m.size(); ++a) m[a] = c.peek(static_cast<std::uint32_t>(a));
  return m;
}

// The live session has no probes (read values, pins after each action).
std::vector<std::string> without_probes(const std::vector<std::string>& r) {
  std::vector<std::string> out;
  for (const std::string& s : r) {
    if (s.rfind("probe ", 0) != 0) out.push_back(s);
  }
  return out;
}

// A checked condition at the save point (the reason it was chosen).
using Condition = bool (*)(const Chip&);

// Save after actions [0, next) at `cycle` (no earlier than the last of them ended).
struct SavePoint {
  std::string name;
  std::size_t next;
  std::uint64_t cycle;
  Condition condition = nullptr;
};

bool receiving_with_edges_ahead(const Chip& c) {
  const Mac::State& m = BlockAccess::state(harness::core(c).mac);
  return m.in_frame && m.rx.next_deadline() != UartRx::kIdle;
}
bool transmitting(const Chip& c) {
  const Mac::State& m = BlockAccess::state(harness::core(c).mac);
  if (m.tx_chars.active()) return m.tx_chars.taken >= m.tx_chars.start && c.cycle() < m.tx_end;
  return m.tx_next > 0 && m.tx_next < m.tx_edges.size();
}
bool searching(const Chip& c) { return c.wd_state() == WdState::Baud_Search && c.started(); }

std::vector<SavePoint> save_points(const Live& live) {
  std::vector<SavePoint> v;
  auto at = [&](std::string name, std::uint64_t cycle, Condition cond) {
    v.push_back({std::move(name), first_action_at(live.actions, cycle), cycle, cond});
  };
  auto mid = [](std::uint64_t a, std::uint64_t b) { return a + (b - a) / 2; };
  for (const Telegram& g : live.telegrams) {
    if (!g.from_chip && g.bytes.size() > 10) {
      at("receiving a request", mid(g.start, g.end), receiving_with_edges_ahead);
      break;
    }
  }
  for (const Telegram& g : live.telegrams) {
    if (g.from_chip && g.bytes.size() > 6) {
      at("transmitting an answer", mid(g.start, g.end), transmitting);
      break;
    }
  }
  const Exchange& first = live.history.at(1);  // FDL_Status at a rate the chip is not on yet
  at("Baud_Search after Start", mid(first.request_start, first.request_end), searching);
  const Exchange& again = live.history.at(live.second_search);
  at("Baud_Search after the cable pull", mid(again.request_start, again.request_end), searching);
  at("between two telegrams without TSYN", live.short_gap, nullptr);
  // And before every single action (between two edges of one telegram, inside an ISR, ...),
  // and half-way between actions: a block field left out of the snapshot shows up somewhere.
  for (std::size_t j = 0; j <= live.actions.size(); ++j) {
    const std::uint64_t t = j < live.actions.size() ? live.actions[j].at : live.end;
    v.push_back({fmt::format("before action {}", j), j, 0});
    const std::uint64_t prev = j > 0 ? live.actions[j - 1].at : 0;
    if (t > prev + 1)
      v.push_back({fmt::format("between actions {} and {}", j - 1, j), j, mid(prev, t)});
  }
  std::stable_sort(v.begin(), v.end(), [](const SavePoint& x, const SavePoint& y) {
    return x.next != y.next ? x.next < y.next : x.cycle < y.cycle;
  });
  return v;
}

struct Saved {
  const SavePoint* point;
  Bytes snapshot;
  std::size_t record_from;
  std::size_t states_from;
  std::uint64_t cycle;
  bool txd;
  bool x_int;
};

class Snapshot : public ::testing::TestWithParam<testutil::ChipParam> {};

TEST_P(Snapshot, ContinuesLikeTheOriginal) {
  const testutil::ChipParam p = GetParam();
  const Live live = live_session(p);
  ASSERT_FALSE(HasFailure());
  ASSERT_GT(live.history.size(), live.second_search + 2);
  const std::vector<SavePoint> points = save_points(live);

  // Chip A replays the session, saving at every save point on the way.
  Chip a({p.profile, p.bus, 0});
  a.set_log_sink(nullptr);
  Recorder rec_a;
  rec_a.attach(a);
  std::vector<Saved> saved;
  std::size_t i = 0;
  for (const SavePoint& sp : points) {
    i = drive(a, live.actions, i, sp.next, sp.cycle, rec_a);
    if (sp.condition != nullptr) {
      EXPECT_TRUE(sp.condition(a)) << sp.name << ": the save point does not show what it is for";
    }
    rec_a.settle();
    saved.push_back({&sp, a.save_state(), rec_a.lines.size(), rec_a.states.size(), a.cycle(),
                     a.txd_pin(), a.x_int_pin()});
  }
  drive(a, live.actions, i, live.actions.size(), live.end, rec_a);
  rec_a.settle();
  // The replay (every RxD edge by itself) reproduces the live session (the master's telegrams
  // heard whole) exactly: every observation, and the state at every cycle it changes.
  ASSERT_EQ(first_difference(live.record, without_probes(rec_a.lines)), "");
  ASSERT_EQ(first_difference(live.states, rec_a.states), "");
  const Bytes final_state = a.save_state();
  const Bytes final_memory = memory_image(a);

  // Chip B loads each snapshot and runs on with the same stimulus: the named save points and
  // every 16th to the end of the session, the others 40 save points far, where B's state must
  // be byte for byte the snapshot A took there.
  constexpr std::size_t kWindow = 40;
  constexpr std::size_t kFullEvery = 16;
  int failures = 0;
  for (std::size_t k = 0; k < saved.size(); ++k) {
    const Saved& s = saved[k];
    SCOPED_TRACE(fmt::format("save point '{}' at cycle {}", s.point->name, s.cycle));
    Chip b({p.profile, p.bus, 0});
    b.set_log_sink(nullptr);
    Recorder rec_b;
    rec_b.attach(b);
    b.load_state(s.snapshot);
    rec_b.prime(b);
    EXPECT_EQ(b.save_state(), s.snapshot) << "save -> load -> save";
    EXPECT_EQ(b.txd_pin(), s.txd);
    EXPECT_EQ(b.x_int_pin(), s.x_int);
    const bool to_end = s.point->condition != nullptr || k % kFullEvery == 0 ||
                        k + kWindow >= saved.size() || s.point->name.rfind("between two", 0) == 0;
    std::size_t record_to = rec_a.lines.size();
    std::size_t states_to = rec_a.states.size();
    if (to_end) {
      drive(b, live.actions, s.point->next, live.actions.size(), live.end, rec_b);
      EXPECT_EQ(memory_image(b), final_memory);
      EXPECT_EQ(b.save_state(), final_state);
    } else {
      const Saved& e = saved[k + kWindow];
      drive(b, live.actions, s.point->next, e.point->next, e.point->cycle, rec_b);
      record_to = e.record_from;
      states_to = e.states_from;
      EXPECT_EQ(b.save_state(), e.snapshot) << "at save point '" << e.point->name << "'";
    }
    const std::vector<std::string> after_a(
        rec_a.lines.begin() + static_cast<std::ptrdiff_t>(s.record_from),
        rec_a.lines.begin() + static_cast<std::ptrdiff_t>(record_to));
    EXPECT_EQ(first_difference(after_a, rec_b.lines), "");
    rec_b.settle();
    const std::vector<std::string> states_a(
        rec_a.states.begin() + static_cast<std::ptrdiff_t>(s.states_from),
        rec_a.states.begin() + static_cast<std::ptrdiff_t>(states_to));
    EXPECT_EQ(first_difference(states_a, rec_b.states), "");
    if (HasFailure() && ++failures >= 3) break;  // the first few are enough to see the pattern
  }
  EXPECT_GT(saved.size(), live.actions.size());
  RecordProperty("save_points", static_cast<int>(saved.size()));
  RecordProperty("actions", static_cast<int>(live.actions.size()));
}

INSTANTIATE_TEST_SUITE_P(AllChips, Snapshot, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

// A chip in the middle of a session, halfway through the first telegram longer than 10 bytes
// on RxD (a request, edges driven ahead of time) or, `answering`, on TxD (the chip's answer).
Chip mid_session(Profile p, BusMode bus = BusMode::intel, std::uint32_t clock_hz = 0,
                 bool answering = false) {
  const Live live = live_session({p, bus});
  Chip c({p, bus, clock_hz});
  c.set_log_sink(nullptr);
  Recorder rec;
  std::uint64_t at = live.end / 3;
  for (const Telegram& g : live.telegrams) {
    if (g.from_chip == answering && g.bytes.size() > 10) {
      at = g.start + (g.end - g.start) / 2;
      break;
    }
  }
  drive(c, live.actions, 0, first_action_at(live.actions, at), at, rec);
  return c;
}

TEST(SnapshotFormat, RoundTripGivesIdenticalBytes) {
  for (const Profile p : kAllProfiles) {
    SCOPED_TRACE(testutil::pname(p));
    Chip fresh({p, BusMode::intel, 0});
    Chip again({p, BusMode::intel, 0});
    again.load_state(fresh.save_state());
    EXPECT_EQ(again.save_state(), fresh.save_state());

    const Chip busy = mid_session(p);
    const Bytes s = busy.save_state();
    Chip c({p, BusMode::intel, 0});
    c.load_state(s);
    EXPECT_EQ(c.save_state(), s);
    EXPECT_EQ(c.cycle(), busy.cycle());
    EXPECT_EQ(memory_image(c), memory_image(busy));
  }
}

// An event latched in the save cycle still survives an acknowledge landing in that cycle (the
// lockstep harness strobes accesses per cycle, docs/timing.md "Order within one cycle").
TEST(SnapshotFormat, EventOfTheSaveCycleSurvivesAnAcknowledgeAfterLoad) {
  Chip a({Profile::spc3, BusMode::intel, 0});
  a.set_log_sink(nullptr);
  a.step(100);
  harness::asic_raise(a, irq::User_Timer_Clock);
  Chip b({Profile::spc3, BusMode::intel, 0});
  b.set_log_sink(nullptr);
  b.load_state(a.save_state());
  for (Chip* c : {&a, &b}) {
    harness::core(*c).write_now(static_cast<std::uint32_t>(c->addr_of(RegId::Int_Ack_Reg)),
                                static_cast<std::uint8_t>(irq::User_Timer_Clock));
    EXPECT_NE(c->peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0u);
  }
}

TEST(SnapshotFormat, HeaderFields) {
  const Chip c({Profile::vpc3plus, BusMode::motorola, 20'000'000});
  const Bytes s = c.save_state();
  ASSERT_GE(s.size(), snap::kHeaderSize);
  EXPECT_EQ(std::string(s.begin(), s.begin() + 8), "DPC31SNP");
  EXPECT_EQ(s[8], snap::kFormatVersion);
  EXPECT_EQ(s[12], static_cast<std::uint8_t>(Profile::vpc3plus));
  EXPECT_EQ(s[13], static_cast<std::uint8_t>(BusMode::motorola));
  EXPECT_EQ(s[16] | s[17] << 8 | s[18] << 16 | s[19] << 24, 20'000'000);
  std::uint64_t length = 0;
  for (int i = 0; i < 8; ++i) length |= std::uint64_t{s[24 + i]} << (8 * i);
  EXPECT_EQ(length, s.size() - snap::kHeaderSize);
  // CRC-32 check value of "123456789".
  const std::string check = "123456789";
  EXPECT_EQ(snap::crc32({reinterpret_cast<const std::uint8_t*>(check.data()), check.size()}),
            0xCBF43926u);
}

// Each section's size after reset, summed from docs/snapshots.md's table (counts are u32; cycles
// u64; `b` and `u8` one byte): a field the code writes and the table lacks shows here.
TEST(SnapshotFormat, AfterResetEachSectionHasTheSizeTheTableGives) {
  const std::vector<std::pair<std::string, std::size_t>> kSections = {
      {"CORE", 8 + 1 + 1 + 1 + 1 + 2 + 1 + 1 + 1 + 1 + 4 + 1},
      {"LTCH", 4 + 2 * kRegIdCount},
      {"MEM ", 0},  // 4 + 2^address_bits, below
      {"IRQC", 8 + 8 + 8 + 2},
      {"BUFS", 4 + 4 + 2 + 7},
      {"DPSM", 1 + 2 + 2 + 4 + 1 + 1 + 3 + 1 + 2 + 2 + 1 + 1 + 3 + 2 + 2 + 1 + 4 + 1},
      {"TIMR", 8 + 1 + 8 + 1 + 8 + 8 + 8},
      {"MAC ", 0},  // its own fields lie between FDLA and USMP
      {"UART", 4 + 1 + 8 + 8 + 4 + 8 + 2 + 8 + 4},
      {"FDLA", (4 + 4 + 1 + 1) + (3 + 8 + 1 + 8 + 4 + 4 + 8 + 1)},  // then the MAC's fields
      {"USMP",
       (4 + 3 + 4 + 8 + 8 + 2 + 8 + 8 + 8) + 3 * (1 + 4 + 4 + 4) + (1 + 4 + 4 + 4 + 4 + 4) + 1},
      {"CNTR", 20 * 4},
      {"RQIF", 8 + 8 + 2 + 1},
      {"SAPL", 1 + 1 + 4 + 4}};
  for (const auto& [profile, mem, total] :
       {std::tuple{Profile::spc3, 2048u, 2813u}, std::tuple{Profile::vpc3plus, 4096u, 4861u},
        std::tuple{Profile::dpc31, 8192u, 8957u}}) {
    const Bytes s = Chip(ChipOptions{profile}).save_state();
    EXPECT_EQ(s.size(), total) << "docs/snapshots.md gives the size after reset";
    std::size_t at = snap::kHeaderSize;
    for (std::size_t i = 0; i < kSections.size(); ++i) {
      const auto& [tag, size] = kSections[i];
      ASSERT_LE(at + 4, s.size());
      ASSERT_EQ(std::string(s.begin() + static_cast<std::ptrdiff_t>(at),
                            s.begin() + static_cast<std::ptrdiff_t>(at + 4)),
                tag);
      at += 4 + (tag == "MEM " ? 4 + mem : size);
    }
    EXPECT_EQ(at, s.size()) << "the payload ends after SAPL";
  }
}

// Loading `bytes` into `c` throws a SnapshotError whose message contains `expected`, and leaves
// the chip as it was.
void expect_refused(Chip& c, const Bytes& bytes, const std::string& expected) {
  const Bytes before = c.save_state();
  try {
    c.load_state(bytes);
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const SnapshotError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
        << "message: " << e.what() << "\nexpected: " << expected;
  }
  EXPECT_EQ(c.save_state(), before) << "a refused snapshot changed the chip";
}

void set_le(Bytes& b, std::size_t off, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) b[off + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Recomputes the CRC (a crafted file: the container is fine, the payload is not).
void reseal(Bytes& b) {
  set_le(b, 24, b.size() - snap::kHeaderSize, 8);
  const std::span<const std::uint8_t> all(b);
  const std::uint32_t crc = snap::crc32(all.subspan(snap::kHeaderSize), snap::crc32(all.first(32)));
  set_le(b, 32, crc, 4);
}

TEST(SnapshotFormat, BadFilesAreRefusedAndLeaveTheChipUnchanged) {
  Chip target = mid_session(Profile::dpc31);
  const Bytes good = target.save_state();
  target.step(1000);  // the chip that refuses is in another state than the snapshot
  ASSERT_NE(good, target.save_state());

  Bytes b = good;
  b[0] = 'X';
  expect_refused(target, b, "not a dpc31emu snapshot (bad magic)");
  expect_refused(target, Bytes{'h', 'e', 'l', 'l', 'o', '\n'}, "bad magic");

  b = good;
  set_le(b, 8, snap::kFormatVersion + 1, 4);
  expect_refused(target, b, "snapshot format version 6 is newer than this build reads (5)");
  set_le(b, 8, 0, 4);
  expect_refused(target, b, "snapshot format version 0 is not supported");

  for (std::size_t n = 0; n < good.size(); ++n) {
    SCOPED_TRACE(n);
    expect_refused(target, Bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n)),
                   "truncated snapshot: ");
    if (HasFailure()) break;
  }

  b = good;
  b.push_back(0);
  expect_refused(target, b, "trailing garbage: the file is");

  for (std::size_t i = snap::kHeaderSize; i < good.size(); ++i) {
    b = good;
    b[i] ^= 0x10;
    expect_refused(target, b, "corrupted snapshot: CRC32");
    if (HasFailure()) break;
  }
  b = good;
  b[32] ^= 0xFF;
  expect_refused(target, b, "corrupted snapshot: CRC32");

  expect_refused(target, Chip({Profile::spc3, BusMode::intel, 0}).save_state(),
                 "snapshot of a spc3 chip cannot be loaded into a dpc31 chip");
  expect_refused(target, Chip({Profile::dpc31, BusMode::motorola, 0}).save_state(),
                 "snapshot of a chip on the motorola bus cannot be loaded into a chip on the "
                 "intel bus");
  expect_refused(target, Chip({Profile::dpc31, BusMode::intel, 20'000'000}).save_state(),
                 "snapshot of a chip clocked at 20000000 Hz cannot be loaded into a chip "
                 "clocked at 48000000 Hz");
  b = good;
  set_le(b, 20, 0x12345678, 4);
  reseal(b);
  expect_refused(target, b, "snapshot written with another register description");
  // The engine is read with the payload, after the header's checks (docs/snapshots.md).
  expect_refused(target, Chip({Profile::dpc31, BusMode::intel, 0, Engine::per_cycle}).save_state(),
                 "malformed snapshot payload (section CORE, byte 22): the snapshot is of the other "
                 "engine (event / per_cycle)");
}

TEST(SnapshotFormat, CraftedPayloadsAreRefusedNotLoaded) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  target.step(1000);
  const std::size_t payload = good.size() - snap::kHeaderSize;

  // A payload cut anywhere, with a header that agrees: the reader notices where it ends.
  for (std::size_t n = 0; n < payload; n += (n < 200 || n + 300 > payload) ? 1 : 37) {
    SCOPED_TRACE(n);
    Bytes b(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(snap::kHeaderSize + n));
    reseal(b);
    expect_refused(target, b, "malformed snapshot payload");
    if (HasFailure()) break;
  }
  Bytes b = good;
  b.push_back(0);
  reseal(b);
  expect_refused(target, b, "1 bytes after the last section");

  // Values no chip can hold. CORE: tag, now (8), started, violation, large_ram, baud_code.
  // A cycle past the chip's last (Chip::kLastCycle, 2^62 - 1): the next step would wrap it.
  b = good;
  b[snap::kHeaderSize + 4 + 7] = 0x40;  // little-endian: bit 62 set
  reseal(b);
  expect_refused(target, b, "out of range (at most 4611686018427387903)");
  b = good;
  b[snap::kHeaderSize + 4 + 8 + 3] = 10;
  reseal(b);
  expect_refused(target, b, "(section CORE, byte 16): value 10 out of range (at most 9)");
  b = good;
  b[snap::kHeaderSize + 4 + 8] = 2;
  reseal(b);
  expect_refused(target, b, "boolean 2 is neither 0 nor 1");
  b = good;
  b[snap::kHeaderSize] = 'K';
  reseal(b);
  expect_refused(target, b, "section 'CORE' expected at byte 0");

  // Random damage with a valid CRC: refused or loaded, never a crash or a half-loaded chip.
  std::mt19937 rng(31);
  int refused = 0;
  for (int k = 0; k < 2000; ++k) {
    b = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) {
      b[snap::kHeaderSize + rng() % payload] = static_cast<std::uint8_t>(rng());
    }
    reseal(b);
    Chip c({Profile::spc3, BusMode::intel, 0});
    const Bytes before = c.save_state();
    try {
      c.load_state(b);
      EXPECT_EQ(c.save_state(), b);
    } catch (const SnapshotError&) {
      ++refused;
      EXPECT_EQ(c.save_state(), before);
    }
  }
  EXPECT_GT(refused, 0);
}

// Where section `tag` begins in a snapshot (its first occurrence: the sections come before any
// RAM bytes that could spell it only where the test looks after them).
std::size_t section_at(const Bytes& b, std::string_view tag) {
  const auto at = std::search(b.begin(), b.end(), tag.begin(), tag.end());
  EXPECT_NE(at, b.end()) << "no section " << tag;
  return static_cast<std::size_t>(at - b.begin());
}

// The answer kept for an FCB repetition is sent again as it is (DpStateMachine::service), so a
// snapshot whose kept answer is no valid telegram is refused: the chip would send it (found in
// the review of Fuzz.snapshot_loader's finding 9, docs/robustness.md). The kept answer is the
// DPSM section's only length-prefixed valid frame.
TEST(SnapshotFormat, AKeptAnswerThatIsNoTelegramIsRefused) {
  for (const Profile p : kAllProfiles) {
    SCOPED_TRACE(testutil::pname(p));
    Chip target = mid_session(p);
    const Bytes good = target.save_state();
    const std::size_t from = section_at(good, "DPSM"), to = section_at(good, "TIMR");
    ASSERT_LT(from, to);
    std::vector<std::pair<std::size_t, std::size_t>> kept;  // (first byte, length)
    for (std::size_t i = from; i + 4 < to; ++i) {
      const std::size_t n = good[i] | good[i + 1] << 8 | good[i + 2] << 16 | good[i + 3] << 24;
      if (n == 0 || i + 4 + n > to) continue;
      const std::span<const std::uint8_t> frame(good.data() + i + 4, n);
      if (fdl::decode(frame).error == fdl::Error::none) kept.emplace_back(i + 4, n);
    }
    ASSERT_EQ(kept.size(), 1u) << "the kept answer is not found in the snapshot";
    const auto [at, n] = kept.front();
    Bytes b = good;
    b[at + n - 1] ^= 0xFF;  // its last byte: the ED, or the short acknowledgement itself
    reseal(b);
    expect_refused(target, b, "the answer kept for a repetition is not a valid telegram");
    Chip again({p, BusMode::intel, 0});
    again.load_state(good);  // the one it really kept loads
    EXPECT_EQ(again.save_state(), good);
  }
}

// Where a snapshot's queue of line edges begins: its 32-bit count, found back from the field
// after it (`after` bytes before section `next`): count, then 9 bytes per edge (cycle, level).
std::size_t edge_queue_at(const Bytes& b, std::string_view next, std::size_t after) {
  const std::size_t end = section_at(b, next) - after;
  for (std::size_t n = 0; 9 * n + 4 <= end; ++n) {
    const std::size_t at = end - 9 * n - 4;
    if ((b[at] | b[at + 1] << 8 | b[at + 2] << 16 | std::size_t{b[at + 3]} << 24) == n) return at;
  }
  ADD_FAILURE() << "no edge queue before " << next;
  return 0;
}

std::uint64_t edge_cycle(const Bytes& b, std::size_t queue, std::size_t k) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v |= std::uint64_t{b[queue + 4 + 9 * k + i]} << (8 * i);
  return v;
}

// Chip::drive_rxd takes edges at non-decreasing cycles, and the chip's answer goes out in time
// order: a snapshot whose queued RxD or TxD edges run back in time is refused (the loader
// checked only that the RxD edges lie after the snapshot's cycle; found in the same review).
TEST(SnapshotFormat, LineEdgesOutOfTimeOrderAreRefused) {
  Chip target = mid_session(Profile::spc3);
  Bytes good = target.save_state();
  // CORE ends with the RxD queue and the line level (1 byte), then LTCH.
  const std::size_t rx = edge_queue_at(good, "LTCH", 1);
  ASSERT_GE(good[rx], 2u) << "the request on RxD has edges driven ahead";
  Bytes b = good;
  const std::uint64_t second = edge_cycle(good, rx, 1);
  set_le(b, rx + 4, second + 1, 8);  // the first edge after the second
  reseal(b);
  expect_refused(target, b, "RxD edges driven ahead out of time order");
  b = good;
  set_le(b, rx + 4, 0, 8);  // the first edge before the snapshot's cycle
  reseal(b);
  expect_refused(target, b, "or at or before the snapshot's cycle");

  Chip sending = mid_session(Profile::spc3, BusMode::intel, 0, true);
  good = sending.save_state();
  // The TxD queue: count, edges, then tx_next (4), tx_end (8), txd (1), then section USMP.
  const std::size_t tx = edge_queue_at(good, "USMP", 13);
  const std::size_t edges = good[tx] | good[tx + 1] << 8;
  const std::size_t next_at = tx + 4 + 9 * edges;
  const std::size_t next = good[next_at] | good[next_at + 1] << 8;
  ASSERT_GT(next, 0u) << "half the answer is out";
  ASSERT_LT(next + 1, edges) << "half the answer is still to come";
  b = good;
  set_le(b, tx + 4 + 9 * (next + 1), edge_cycle(good, tx, next) - 1, 8);  // before the one before
  reseal(b);
  expect_refused(sending, b, "TxD edges out of time order");
  b = good;
  set_le(b, next_at, 0, 4);  // the edges out already marked as still to come
  reseal(b);
  expect_refused(sending, b, "taken and to come on the wrong side of now");
  Chip again({Profile::spc3, BusMode::intel, 0});
  again.load_state(good);
  EXPECT_EQ(again.save_state(), good);
}

// Each latch is the register's flip-flops: no more bits than the register has (docs/registers.md
// gives the widths), none for a register the profile lacks. Fuzz.snapshot_loader's finding 9
// (docs/robustness.md): MinTSDR_Val (8 bits) loaded as FFFFh delayed the answer by 65 535 bit
// times, past what any request could explain.
TEST(SnapshotFormat, ALatchWiderThanItsRegisterIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t ltch = section_at(good, "LTCH");
  const auto latch_at = [&](RegId id) { return ltch + 8 + 2 * static_cast<std::size_t>(id); };
  Bytes b = good;
  set_le(b, latch_at(RegId::MinTSDR_Val), 0xFFFF, 2);
  reseal(b);
  expect_refused(target, b, "latch MinTSDR_Val is FFFFh: more than its 8 bits");
  b = good;
  set_le(b, latch_at(RegId::MinTSDR_Val), 0x00FF, 2);  // the widest an 8-bit register holds
  reseal(b);
  Chip widest({Profile::spc3, BusMode::intel, 0});
  widest.load_state(b);
  EXPECT_EQ(widest.save_state(), b);
  // The SPC3 has no DPC31 C31_Control.
  ASSERT_EQ(find_reg(profile_desc(Profile::spc3), RegId::C31_Control), nullptr);
  b = good;
  set_le(b, latch_at(RegId::C31_Control), 0x0001, 2);
  reseal(b);
  expect_refused(target, b, "is 0001h on a chip without that register");
}

// A block the profile lacks stays as reset left it, and both receivers listen at the rate of the
// search code (Mac::listen). Fuzz.snapshot_loader's finding 10 (docs/robustness.md): an SPC3
// with the DPC31's DPS_User_Watchdog due read a cell the SPC3 does not have; a receiver bit time
// of 0 divided by zero.
TEST(SnapshotFormat, ABlockTheChipLacksOrABitTimeOfNoRateIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  Bytes b = good;
  set_le(b, section_at(good, "RQIF") + 4, 0, 8);  // the DPS_User_Watchdog's timer due at cycle 0
  reseal(b);
  expect_refused(target, b, "the request interface is not idle on a chip without one");
  b = good;
  b[section_at(good, "SAPL") + 4] = 1;  // DPV1_Enable taken
  reseal(b);
  expect_refused(target, b, "the SAP list is not off on a chip without one");
  const std::uint32_t t = target.bit_cycles();
  const std::string wrong = fmt::format("a receiver's bit time is not {} clocks", t);
  for (const std::string_view receiver : {"UART", "USMP"}) {  // the event and per-cycle ones
    for (const std::uint32_t other : {0u, t + 1}) {
      SCOPED_TRACE(fmt::format("{} {}", receiver, other));
      b = good;
      set_le(b, section_at(good, receiver) + 4, other, 4);
      reseal(b);
      expect_refused(target, b, wrong);
    }
  }
}

// Diag_Buffer_SM's two buffers as the manuals move them: one with the user and one with the
// ASIC, or one waiting with the ASIC while the other is sent; never Nil, never both in one state
// (SPC3 manual, Diag_Buffer_SM; the fuzz checker's "both diag buffers with the user", finding 11
// of docs/robustness.md).
TEST(SnapshotFormat, TwoDiagBuffersInOneStateAreRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t diag = section_at(good, "BUFS") + 4 + 8;  // after Dout d n u f, Din d n u f
  const auto with = [&](std::uint8_t first, std::uint8_t second) {
    Bytes b = good;
    b[diag] = first;
    b[diag + 1] = second;
    reseal(b);
    return b;
  };
  constexpr std::uint8_t nil = 0, user = 1, asic = 2, send = 3;
  for (const auto& [x, y] :
       {std::pair{user, user}, {asic, asic}, {send, send}, {nil, user}, {asic, nil}}) {
    SCOPED_TRACE(fmt::format("{} {}", x, y));
    expect_refused(target, with(x, y), "the diag buffers are both in one state, or one is Nil");
  }
  for (const auto& [x, y] : {std::pair{user, asic}, {asic, user}, {user, send}, {send, asic}}) {
    SCOPED_TRACE(fmt::format("{} {}", x, y));
    Chip c({Profile::spc3, BusMode::intel, 0});
    c.load_state(with(x, y));
    EXPECT_EQ(c.peek_reg(RegId::Diag_Buffer_SM), y << 2 | x);
  }
}

// X/INT as last shown (CORE irq_line) must be what IRR, IMR and the EOI time make it: a chip tells
// on_irq_change only where the two differ, so a stale one hid the next activation (CI's fuzz run,
// docs/robustness.md). PB3 is the DPC31's, high only while DX_Out is pending.
TEST(SnapshotFormat, XIntOrPb3OtherThanTheInterruptsMakeThemIsRefused) {
  Chip target = mid_session(Profile::spc3);
  const Bytes good = target.save_state();
  const std::size_t line = section_at(good, "CORE") + 4 + 15;  // after now, 3 b, baud, u16, b
  ASSERT_LE(good[line], 1);
  const bool active = target.irq_active();
  ASSERT_EQ(good[line], active ? 1 : 0);
  Bytes b = good;
  b[line] = active ? 0 : 1;
  reseal(b);
  expect_refused(target, b,
                 fmt::format("X/INT shown {} where IRR, IMR and the EOI time make it {}",
                             active ? "inactive" : "active", active ? "active" : "inactive"));
  b = good;
  b[line + 1] = 1;  // pb3 on an SPC3
  reseal(b);
  expect_refused(target, b, "PB3 high without a DX_Out pending on a DPC31");
}

class SnapshotFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           fmt::format("dpc31-snapshot-{}-{}", ::getpid(),
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, ec);
    fs::remove_all(dir_, ec);
  }
  std::vector<std::string> listing(const fs::path& d) const {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(d)) v.push_back(e.path().filename().string());
    std::sort(v.begin(), v.end());
    return v;
  }
  fs::path dir_;
};

TEST_F(SnapshotFile, SaveWritesExactlyTheFileAndLoadRestoresIt) {
  const Chip a = mid_session(Profile::vpc3plus);
  const std::string path = (dir_ / "a.snap").string();
  a.save_state_file(path);
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"a.snap"});
  // Over an existing file made private: it stays so (docs/bad-input.md: a replaced file
  // keeps its permission bits), as every door that saves a snapshot (serve's `save`, Python) has
  // it.
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  a.save_state_file(path);
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"a.snap"});
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  Chip b({Profile::vpc3plus, BusMode::intel, 0});
  b.load_state_file(path);
  EXPECT_EQ(b.save_state(), a.save_state());
}

TEST_F(SnapshotFile, FailedSaveThrowsAndLeavesNoTemporaryFile) {
  const Chip a({Profile::dpc31, BusMode::intel, 0});
  auto expect_throw = [&](const std::string& path) {
    try {
      a.save_state_file(path);
      ADD_FAILURE() << "saved to " << path;
    } catch (const SnapshotError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
  };
  // The target is a directory: the temporary file is written, the rename fails.
  fs::create_directory(dir_ / "taken");
  fs::create_directory(dir_ / "taken" / "inside");
  expect_throw((dir_ / "taken").string());
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"taken"});
  // A directory that does not exist.
  expect_throw((dir_ / "missing" / "a.snap").string());
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"taken"});
  // A directory without write permission (root may write anyway: then /proc, where nobody can
  // create files, stands in for it).
  const fs::path ro = dir_ / "read-only";
  fs::create_directory(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  if (::geteuid() != 0) {
    expect_throw((ro / "a.snap").string());
    EXPECT_TRUE(listing(ro).empty());
  } else {
    expect_throw("/proc/dpc31-snapshot-test.snap");
  }
  // No name: refused before a temporary file ".dpc31-PID.tmp" is made in the working directory.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  try {
    a.save_state_file("");
    ADD_FAILURE() << "saved to an empty name";
  } catch (const SnapshotError& e) {
    EXPECT_STREQ(e.what(), "an empty file name: nothing can be written there");
  }
  fs::current_path(cwd);
  EXPECT_EQ(listing(dir_), (std::vector<std::string>{"read-only", "taken"}));
}

TEST_F(SnapshotFile, LoadErrorsNameThePath) {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  const Bytes before = c.save_state();
  // Loading `path` throws SnapshotError with "PATH: why".
  auto expect_error = [&c](const std::string& path, const std::string& why) {
    try {
      c.load_state_file(path);
      ADD_FAILURE() << path << " loaded";
    } catch (const SnapshotError& e) {
      EXPECT_EQ(std::string(e.what()), path + ": " + why);
    }
  };
  expect_error((dir_ / "none.snap").string(), "no such file");
  // No name: the words of `--load-state ''` (util/outfile/path_option.hpp), no ": no such file".
  try {
    c.load_state_file("");
    ADD_FAILURE() << "loaded an empty name";
  } catch (const SnapshotError& e) {
    EXPECT_STREQ(e.what(), "an empty file name: nothing can be read there");
  }
  const std::string foreign = (dir_ / "foreign.snap").string();
  std::ofstream(foreign) << "# a scenario, not a snapshot\n";
  expect_error(foreign, "not a dpc31emu snapshot (bad magic)");
  EXPECT_EQ(c.save_state(), before);
}

}  // namespace
