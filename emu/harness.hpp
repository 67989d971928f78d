// The emulator's harness interface: the blocks of a Chip for the tools that check them block by
// block (the lockstep adapter tools/cosim/cpp_dut.cpp, the cosim session recorder) and for the
// tests that break an invariant on purpose (tests/fuzz/invariants_test.cpp) or look at a
// block's inside (tests/snapshot_test.cpp). Not part of the public API (include/dpc31): whatever
// a user of the chip needs is a documented call of dpc31::Chip (probe(), next_deadline(), ...).
#pragma once

#include <cstdint>
#include <functional>

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
// effect at the current cycle: for the tests of one block.
inline void asic_raise(Chip& c, std::uint16_t irq_bits) { core(c).irq.raise(irq_bits); }  // IRR
inline void asic_dout_received(Chip& c) { core(c).buffers.dout_received(); }  // D -> N, DX_Out
inline void asic_dout_clear(Chip& c) { core(c).buffers.dout_clear(); }  // clear D, D -> N, DX_Out
// N -> D if new; returns the D buffer index.
inline std::uint8_t asic_din_fetch(Chip& c) { return core(c).buffers.din_fetch(); }
inline void asic_diag_send_begin(Chip& c) { core(c).buffers.diag_send_begin(); }
inline void asic_diag_send_end(Chip& c) {
  core(c).buffers.diag_send_end(core(c).buffers.sent_diag_has_stat_diag());
}
inline void asic_prm_received(Chip& c) { core(c).dp.prm_accepted(); }  // New_Prm_Data
inline void asic_cfg_received(Chip& c) { core(c).dp.cfg_accepted(); }  // New_Cfg_Data
inline void asic_ssa_received(Chip& c) { core(c).dp.ssa_accepted(); }  // New_SSA_Data

}  // namespace harness

}  // namespace dpc31
