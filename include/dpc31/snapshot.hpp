// Snapshots of the whole chip state (docs/snapshots.md): the error every refused snapshot throws.
#pragma once

#include <cstddef>
#include <stdexcept>

namespace dpc31 {

// The largest snapshot file the chip reads (a snapshot is a few kB; the bound keeps a wrong file
// from being read whole).
inline constexpr std::size_t kMaxSnapshotFileBytes = std::size_t{64} << 20;

// A snapshot that cannot be written or loaded. what() is one line: for the file functions
// "PATH: reason", for load_state the reason alone ("not a dpc31emu snapshot (bad magic)", ...).
struct SnapshotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace dpc31
