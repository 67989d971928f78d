// Large synthetic VCD pairs for the streaming test and the wavediff benchmark: deterministic
// content shaped like an RTL dump (a clock, 1-bit controls and 16-bit buses changing in every
// step), written once and twice to disk, the second copy with a few one-bit differences.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace dpc31::wavediff {

struct SyntheticVcd {
  std::uint64_t steps = 0;  // time steps (10 ps apart), about 100 bytes each
  // Steps at which B's last 16-bit write of the step has its lowest bit flipped (the value stays,
  // so each is a difference lasting until that bus is written again). Ascending.
  std::vector<std::uint64_t> diff_steps;
};

// Writes A to `path_a` and B to `path_b` (same size); false with a reason if a file cannot be
// written.
bool write_synthetic_vcd_pair(const std::string& path_a, const std::string& path_b,
                              const SyntheticVcd& spec, std::string& error);

// Steps that make files of about `megabytes` MB each (1 MB = 10^6 bytes).
std::uint64_t synthetic_steps_for_megabytes(std::uint64_t megabytes);

}  // namespace dpc31::wavediff
