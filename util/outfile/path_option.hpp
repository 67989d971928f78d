// The one check of every command-line option that names a file or a directory: given, it is
// never empty. '' is not "not given": it would silently write nothing, or read the default
// (docs/bad-input.md). A CLI11 validator, so the error is `dpc31 SUB: --opt: why`, exit 2.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "outfile.hpp"

namespace dpc31::outfile {

enum class Use { read, write };

inline CLI::Validator named(Use use) {
  return CLI::Validator(
      [use](std::string& path) -> std::string {
        if (!path.empty()) return {};
        return std::string(use == Use::write ? kEmptyName : kEmptyReadName);
      },
      "", "named");
}

// The same for an option whose value is not a file (--cpu, --ports, --board-address, --tcp...):
// '' is refused, never taken as "not given" and silently the default.
inline CLI::Validator given() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        return value.empty() ? "an empty value: give one, or leave the option out" : "";
      },
      "", "given");
}

}  // namespace dpc31::outfile
