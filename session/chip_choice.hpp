// The chip's make on every subcommand that takes --profile: --variant b|c|s, the VPC3+ variant
// (Status_Reg bits 15..12 read Bh, Ch or Eh, docs/decisions.md), and --irq-controller
// external|c31, the DPC31 interrupt controller the bus reaches (docs/dpc31.md). cosim takes
// --variant only: the blocks it compares behave the same behind either controller. In session/, not
// util/: it names the chip's types, and util/ is below the chip.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "dpc31/chip.hpp"

namespace dpc31::cli {

struct ChipChoice {
  std::string variant;         // empty: none given
  std::string irq_controller;  // empty: none given (external)
};

inline CLI::Option* add_variant_option(CLI::App* cmd, std::string& variant) {
  return cmd
      ->add_option("--variant", variant,
                   "VPC3+ variant (with --profile vpc3plus): b, c or s; Status_Reg bits 15..12 "
                   "read B, C or E (default c)")
      ->check(CLI::IsMember({"b", "c", "s"}));
}

inline void add_chip_options(CLI::App* cmd, ChipChoice& choice) {
  add_variant_option(cmd, choice.variant);
  cmd->add_option("--irq-controller", choice.irq_controller,
                  "the interrupt controller the bus reaches (with --profile dpc31): external "
                  "(drives X/INT, the default) or c31 (the internal core's; X/INT stays inactive)")
      ->check(CLI::IsMember({"external", "c31"}));
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

// The same for the whole choice (after o.profile is set).
inline std::string apply_chip_choice(const ChipChoice& choice, ChipOptions& o) {
  if (std::string why = apply_variant(choice.variant, o); !why.empty()) return why;
  if (choice.irq_controller.empty()) return {};
  IrqController c{};
  if (!parse_irq_controller(choice.irq_controller, c)) {
    return "--irq-controller '" + choice.irq_controller + "' must be external or c31";
  }
  // external too: on another profile it is no choice, so it would be a silent option.
  if (o.profile != Profile::dpc31) {
    return "--irq-controller " + choice.irq_controller +
           " is for --profile dpc31: only the DPC31 has a C31 core";
  }
  o.irq_controller = c;
  return {};
}

}  // namespace dpc31::cli
