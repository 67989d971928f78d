#include <array>

#include "fuzz_targets.hpp"

namespace dpc31::fuzz {

std::span<const Target> targets() {
  static constexpr std::array<Target, 8> kTargets = {{
      {"chip_bits", chip_bits},
      {"chip_bytes", chip_bytes},
      {"trace_parser", trace_parser},
      {"scenario_parser", scenario_parser},
      {"vcd_reader", vcd_reader},
      {"fst_reader", fst_reader},
      {"serve_lines", serve_lines},
      {"snapshot_loader", snapshot_loader},
  }};
  return kTargets;
}

}  // namespace dpc31::fuzz
