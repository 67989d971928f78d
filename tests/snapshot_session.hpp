// The live DP session the snapshot tests share (snapshot_test.cpp, snapshot_format_test.cpp,
// snapshot_file_test.cpp): its recorded stimulus, the recorder of what a user sees, a replay of
// the stimulus and a chip stopped in the middle of the session.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "harness.hpp"
#include "responder.hpp"
#include "snapshot.hpp"
#include "test_util.hpp"

namespace snapshot_session {

using namespace dpc31;
using Bytes = std::vector<std::uint8_t>;

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
inline ShownState observable_state(const Chip& c) {
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

inline ResponderConfig responder_config() {
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
inline Live live_session(testutil::ChipParam p) {
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
inline std::size_t drive(Chip& c, const std::vector<Action>& acts, std::size_t i, std::size_t j,
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
inline std::size_t first_action_at(const std::vector<Action>& acts, std::uint64_t cycle) {
  return static_cast<std::size_t>(
      std::find_if(acts.begin(), acts.end(), [&](const Action& a) { return a.at >= cycle; }) -
      acts.begin());
}

inline std::vector<std::uint8_t> memory_image(const Chip& c) {
  std::vector<std::uint8_t> m(std::size_t{1} << c.profile().address_bits);
  for (std::size_t a = 0; a < m.size(); ++a) m[a] = c.peek(static_cast<std::uint32_t>(a));
  return m;
}

// A chip in the middle of a session, halfway through the first telegram longer than 10 bytes
// on RxD (a request, edges driven ahead of time) or, `answering`, on TxD (the chip's answer).
inline Chip mid_session(Profile p, BusMode bus = BusMode::intel, std::uint32_t clock_hz = 0,
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

}  // namespace snapshot_session
