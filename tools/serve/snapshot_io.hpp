// `save PATH` / `load PATH`: the only place that touches the chip's snapshot API
// (dpc31/snapshot.hpp: Chip::save_state_file / load_state_file, throwing SnapshotError). Builds
// without that header answer `ERR unsupported`.
#pragma once

#include <string>

#include "dpc31/chip.hpp"

namespace dpc31::serve {

// Whether this build has the snapshot API.
[[nodiscard]] bool snapshot_supported();

// Each returns "" on success, else why it failed (the chip is unchanged when load fails, as far
// as the snapshot API guarantees it).
[[nodiscard]] std::string save_chip(const Chip& chip, const std::string& path);
[[nodiscard]] std::string load_chip(Chip& chip, const std::string& path);

}  // namespace dpc31::serve
