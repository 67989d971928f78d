// What Chip::load_state promises beyond the state (docs/snapshots.md, "Loading"): the TxD edges
// already on the line reach the batch observers, a wake-up asked for stays, a load from inside an
// observer is refused; and the sizes the document gives are the build's.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "trace.hpp"

using namespace dpc31;

namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

Trace golden(const std::string& name) {
  Trace t;
  TraceError e;
  EXPECT_TRUE(load_trace(std::string(SOURCE_DIR) + "/traces/" + name, t, e)) << e.text();
  return t;
}

// The golden trace's stimulus (its rx, rxd, wr and rd lines) on `chip`, each at its cycle, until
// `stop` says so before a line (it may act on the chip there); true when it did.
template <typename Stop>
bool replay(Chip& chip, const Trace& t, Stop stop) {
  const std::uint32_t bit = chip.clock_hz() / t.baud;
  const auto step_to = [&](std::uint64_t c) {
    if (c > chip.cycle()) chip.step(c - chip.cycle());
  };
  for (const TraceLine& l : t.lines) {
    if (stop(l)) return true;
    switch (l.kind) {
      case TraceKind::rx:
        step_to(l.cycle);
        chip.drive_rxd_chars(l.bytes, l.start, bit, l.fault);
        break;
      case TraceKind::rxd:
        step_to(l.cycle);
        for (const auto& [c, v] : l.edges) chip.drive_rxd(c, v);
        break;
      case TraceKind::wr:
        step_to(l.cycle - chip.bus_access_cycles());
        chip.write(l.addr, l.data);
        break;
      case TraceKind::rd:
        step_to(l.cycle - chip.bus_access_cycles());
        (void)chip.read(l.addr);
        break;
      case TraceKind::end:
        step_to(l.cycle);
        break;
      default:
        break;
    }
  }
  return false;
}

// The answers' edges as the golden trace's tx lines give them (each checked by hand against
// docs/timing.md in the trace's notes): its bytes back to back from its start bit.
Edges answers(const Trace& t, std::uint32_t bit) {
  Edges e;
  for (const TraceLine& l : t.lines)
    if (l.kind == TraceKind::tx) uart_encode(l.bytes, l.start, bit, e);
  return e;
}

// A chip that loads its own state in the middle of an answer changes nothing: the batch observers
// (on_txd_edges, on_txd_chars: the built-in master's, the bridge's, a segment's) get every edge,
// the ones on the line before the load too (handed over at the load, as take_txd() would). Before,
// the 14 edges from the first answer's start bit at 2 888 416 to the load 40 bit times later
// (2 888 416 + 40 x 32 = 2 889 696) never came: 302 of 316. traces/startup_spc3_1m5.trace at 1.5
// Mbaud (32 clocks a bit): seven answers, 316 edges.
TEST(SnapshotLoad, TheBatchObserversGetTheEdgesOnTheLineBeforeTheLoad) {
  const Trace t = golden("startup_spc3_1m5.trace");
  ASSERT_EQ(t.baud, 1'500'000u);
  const Edges want = answers(t, 32);
  ASSERT_EQ(want.size(), 316u);
  ASSERT_EQ(want.front(), std::make_pair(std::uint64_t{2'888'416}, false));
  for (const bool chars : {false, true}) {
    Chip chip(t.chip);
    chip.set_log_sink(nullptr);
    Edges got;
    if (chars) {
      chip.on_txd_chars([&](const TxdRun& r) {
        if (!r.bytes.empty()) uart_encode(r.bytes, r.start, r.bit_cycles, got);
        got.insert(got.end(), r.edges.begin(), r.edges.end());
      });
    } else {
      chip.on_txd_edges([&](std::span<const std::pair<std::uint64_t, bool>> e) {
        got.insert(got.end(), e.begin(), e.end());
      });
    }
    constexpr std::uint64_t kLoad = 2'889'696;
    bool loaded = false;
    replay(chip, t, [&](const TraceLine& l) {
      if (!loaded && l.cycle > kLoad) {
        chip.step(kLoad - chip.cycle());
        chip.load_state(chip.save_state());
        loaded = true;
      }
      return false;
    });
    chip.take_txd();
    ASSERT_TRUE(loaded);
    EXPECT_EQ(got, want) << (chars ? "on_txd_chars" : "on_txd_edges");
  }
}

// A wake_on_txd(true) is the stepper's, not state: a load keeps it, and the step stops right
// after the answer's start bit. traces/gc_clear_spc3.trace at 12 Mbaud (4 clocks a bit): the
// FDL_Status from 324 ends 6 x 11 bit times later at 588, the answer starts TSDR = 11 bit times
// after it, at 588 + 44 = 632 (the trace's `tx 632`). X/INT is active from Start (192) and not
// acknowledged here, so no interrupt ends the step first. Before, the load switched the wake-up
// off and the step ran its 10 000 000 cycles.
TEST(SnapshotLoad, AWakeOnTxdStaysAcrossALoad) {
  const Trace t = golden("gc_clear_spc3.trace");
  ASSERT_EQ(t.baud, 12'000'000u);
  for (const bool load : {false, true}) {
    Chip chip(t.chip);
    chip.set_log_sink(nullptr);
    bool fed = false;
    replay(chip, t, [&](const TraceLine& l) {
      if (fed) return true;
      fed = l.kind == TraceKind::rx;
      return false;
    });
    ASSERT_TRUE(fed);
    ASSERT_EQ(chip.cycle(), 192u);
    ASSERT_TRUE(chip.irq_active());
    chip.wake_on_txd(true);
    if (load) chip.load_state(chip.save_state());
    EXPECT_FALSE(chip.step_until_irq(10'000'000));
    EXPECT_EQ(chip.cycle(), 632u) << (load ? "after a load" : "without a load");
    EXPECT_TRUE(chip.stop_requested());
    EXPECT_FALSE(chip.txd_pin());
  }
}

// load_state from inside an observer while the chip calls it would free the blocks under the
// access in progress (the audit: valgrind's invalid reads in bus_write_ref after an
// on_irq_change observer loaded a snapshot during the write of Start_SPC3). It is refused,
// std::logic_error, as Python refuses it, the chip unchanged; after the call has returned the
// load is taken. Start_SPC3 (Mode_Reg1_S, 08h on the SPC3) latches DX_Out at the write's
// completion (docs/timing.md, Start_SPC3), unmasked here: the observer is called inside the write.
TEST(SnapshotLoad, ALoadFromInsideAnObserverIsRefused) {
  Chip chip({Profile::spc3, BusMode::intel});
  chip.set_log_sink(nullptr);
  const std::vector<std::uint8_t> fresh = chip.save_state();
  chip.write(0x04, 0x00);  // Int_Mask_Reg: everything unmasked
  chip.write(0x05, 0x00);
  std::vector<std::uint8_t> inside;
  std::string refused;
  chip.on_irq_change([&](std::uint64_t, bool active) {
    if (!active || !refused.empty()) return;
    inside = chip.save_state();
    try {
      chip.load_state(fresh);
    } catch (const std::logic_error& e) {
      refused = e.what();
    }
    EXPECT_EQ(chip.save_state(), inside) << "the refused load changed the chip";
  });
  chip.write(0x08, 0x01);
  EXPECT_EQ(refused,
            "load_state from inside the chip's observer or log sink: the chip is in the middle of "
            "an event or access (load it after the call that runs the chip has returned)");
  EXPECT_TRUE(chip.started());
  chip.load_state(fresh);
  EXPECT_FALSE(chip.started());
  EXPECT_EQ(chip.cycle(), 0u);
}

}  // namespace

// docs/snapshots.md gives the snapshot's size after reset per profile (one byte short for a
// while: version 5's Offline byte was not added); the sentence must give the build's sizes.
TEST(Docs, SnapshotSizesAfterResetAreTheBuilds) {
  const auto spaced = [](std::size_t n) {
    return n < 1000 ? std::to_string(n) : fmt::format("{} {:03}", n / 1000, n % 1000);
  };
  const auto size = [&](Profile p) { return spaced(Chip(ChipOptions{p}).save_state().size()); };
  const std::string want =
      fmt::format("After reset a snapshot is {} bytes (spc3), {} (vpc3plus) or {} (dpc31)",
                  size(Profile::spc3), size(Profile::vpc3plus), size(Profile::dpc31));
  std::ifstream f(std::string(SOURCE_DIR) + "/docs/snapshots.md");
  ASSERT_TRUE(f) << "docs/snapshots.md";
  std::string text, word;
  while (f >> word) text += (text.empty() ? "" : " ") + word;  // a sentence may break across lines
  EXPECT_NE(text.find(want), std::string::npos) << "docs/snapshots.md should say: " << want;
}
