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
#include "snapshot_session.hpp"
#include "test_util.hpp"

using namespace dpc31;
using namespace snapshot_session;

namespace {

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
  bool irq;
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
                     a.txd_pin(), a.x_int_pin(), a.irq_active()});
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
    // B's observer saw a fresh chip's interrupt (inactive): the load shows it the snapshot's at
    // the loaded cycle (docs/snapshots.md).
    EXPECT_EQ(rec_b.lines, s.irq ? std::vector<std::string>{fmt::format("x/int {} true", s.cycle)}
                                 : std::vector<std::string>{});
    rec_b.lines.clear();
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

}  // namespace
