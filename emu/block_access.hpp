// The one back door into a block's private state: for the snapshot (chip.cpp writes and reads
// every block's State in the order of docs/snapshots.md) and the white-box tools of the harness
// interface (emu/harness.hpp). Behaviour never goes through it.
#pragma once

namespace dpc31 {

struct BlockAccess {
  template <typename B>
  static auto& state(B& b) {
    return b.s_;
  }
  // What a block's log has said already (emu/folded_log.hpp): not its state, but in the snapshot.
  template <typename D>
  static auto& over_long(D& dp) {
    return dp.over_long_;
  }
  template <typename D>
  static auto& din_wait(D& dp) {
    return dp.din_wait_;
  }
  template <typename R>
  static auto& over_registers(R& regs) {
    return regs.over_registers_;
  }
};

}  // namespace dpc31
