#include <array>

#include "fuzz_targets.hpp"

namespace dpc31::fuzz {

std::span<const Target> targets() {
  static constexpr std::array<Target, 8> kTargets = {{
      {"chip_bits", chip_bits, chip_bits_check},
      {"chip_bytes", chip_bytes, chip_bytes_check},
      {"trace_parser", trace_parser, trace_parser_check},
      {"scenario_parser", scenario_parser, scenario_parser_check},
      {"vcd_reader", vcd_reader, vcd_reader_check},
      {"fst_reader", fst_reader, fst_reader_check},
      {"serve_lines", serve_lines, serve_lines_check},
      {"snapshot_loader", snapshot_loader, snapshot_loader_check},
  }};
  return kTargets;
}

}  // namespace dpc31::fuzz
