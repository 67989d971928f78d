// Snapshots of the whole chip state (docs/snapshots.md): the error every refused snapshot throws.
#pragma once

#include <stdexcept>

namespace dpc31 {

// A snapshot that cannot be written or loaded. what() is one line: for the file functions
// "PATH: reason", for load_state the reason alone ("not a dpc31emu snapshot (bad magic)", ...).
struct SnapshotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace dpc31
