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
};

}  // namespace dpc31
