// --variant b|c|s, the VPC3+ variant, on every subcommand that takes --profile (demo, cosim,
// serve, bridge, soak): Status_Reg bits 15..12 then read Bh, Ch or Eh (docs/decisions.md).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "dpc31/chip.hpp"

namespace dpc31::cli {

inline CLI::Option* add_variant_option(CLI::App* cmd, std::string& variant) {
  return cmd
      ->add_option("--variant", variant,
                   "VPC3+ variant (with --profile vpc3plus): b, c or s; Status_Reg bits 15..12 "
                   "read B, C or E (default c)")
      ->check(CLI::IsMember({"b", "c", "s"}));
}

// Puts the variant (empty: none given) into the chip options. Returns the one-line complaint
// for a variant with a profile other than vpc3plus, empty when all is well.
inline std::string apply_variant(const std::string& variant, ChipOptions& o) {
  if (variant.empty()) return {};
  Vpc3Variant v{};
  if (!parse_vpc3_variant(variant, v)) return "--variant '" + variant + "' must be b, c or s";
  if (o.profile != Profile::vpc3plus) {
    return "--variant is for --profile vpc3plus: only the VPC3+ has variants";
  }
  o.variant = v;
  return {};
}

}  // namespace dpc31::cli
