// The emulator's harness interface: the blocks of a Chip for the tools that check them block by
// block (the lockstep adapter tools/cosim/cpp_dut.cpp, the cosim session recorder) and for the
// tests that break an invariant on purpose (tests/fuzz/invariants_test.cpp) or look at a
// block's inside (tests/snapshot_test.cpp). Not part of the public API (include/dpc31): whatever
// a user of the chip needs is a documented call of dpc31::Chip (probe(), next_deadline(), ...).
#pragma once

#include <cstdint>
#include <functional>
#include <utility>

#include "block_access.hpp"
#include "core.hpp"
#include "dpc31/chip.hpp"

namespace dpc31 {

struct ChipAccess {
  static ChipCore& core(Chip& c) { return *c.core_; }
  static const ChipCore& core(const Chip& c) { return *c.core_; }
};

namespace harness {

inline ChipCore& core(Chip& c) { return ChipAccess::core(c); }
inline const ChipCore& core(const Chip& c) { return ChipAccess::core(c); }

// Every block-level event (block_event.hpp) and every CPU bus access, with its cycle; an empty
// function removes them all.
inline void on_block_event(Chip& c, std::function<void(std::uint64_t, const BlockEvent&)> cb) {
  core(c).signals.block.add(std::move(cb));
}

// The protocol side's entry points (what the DP engine does inside the chip), each taking
// effect at the current cycle as all of that cycle's protocol-side events: X/INT is looked at
// after it (docs/timing.md, "Order within one cycle", step 6). For the tests of one block.
template <class Event>
void asic(Chip& c, Event&& event) {
  std::forward<Event>(event)(core(c));
  core(c).irq.update_line();
}
inline void asic_raise(Chip& c, std::uint16_t irq_bits) {  // IRR
  asic(c, [=](ChipCore& k) { k.irq.raise(irq_bits); });
}
inline void asic_dout_received(Chip& c) {  // D -> N, DX_Out
  asic(c, [](ChipCore& k) { k.buffers.dout_received(); });
}
inline void asic_dout_clear(Chip& c) {  // clear D, D -> N, DX_Out
  asic(c, [](ChipCore& k) { k.buffers.dout_clear(); });
}
// N -> D if new; returns the D buffer index.
inline std::uint8_t asic_din_fetch(Chip& c) {
  std::uint8_t d = 0;
  asic(c, [&](ChipCore& k) { d = k.buffers.din_fetch(); });
  return d;
}
inline void asic_diag_send_begin(Chip& c) {
  asic(c, [](ChipCore& k) { k.buffers.diag_send_begin(); });
}
inline void asic_diag_send_end(Chip& c) {
  asic(c, [](ChipCore& k) { k.buffers.diag_send_end(k.buffers.sent_diag_has_stat_diag()); });
}
inline void asic_prm_received(Chip& c) {  // New_Prm_Data
  asic(c, [](ChipCore& k) { k.dp.prm_accepted(); });
}
inline void asic_cfg_received(Chip& c) {  // New_Cfg_Data
  asic(c, [](ChipCore& k) { k.dp.cfg_accepted(); });
}
inline void asic_ssa_received(Chip& c) {  // New_SSA_Data
  asic(c, [](ChipCore& k) { k.dp.ssa_accepted(); });
}

}  // namespace harness

}  // namespace dpc31
