// The one check of every command-line option that names a file or a directory: given, it is
// never empty. '' is not "not given": it would silently write nothing, or read the default
// (docs/bad-input.md). A CLI11 validator, so the error is `dpc31 SUB: --opt: why`, exit 2.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "outfile.hpp"

namespace dpc31::outfile {

// `read` and `write`: a file; `place`: a directory, a socket or a link, made or read.
enum class Use { read, write, place };

// `-` is the standard input of a file read and the standard output of a file written, as the
// common convention has it: handed on as /dev/stdin or /dev/stdout, which every door already
// takes (a descriptor, written in place; the standard output's own file rule). `./-` names a
// file called `-`. A place cannot be a stream: `-` is refused there.
inline CLI::Validator named(Use use) {
  return CLI::Validator(
      [use](std::string& path) -> std::string {
        if (path == "-") {
          if (use == Use::place)
            return "'-' is the standard input or output, which this option cannot name: ./- names "
                   "one called -";
          path = use == Use::read ? "/dev/stdin" : "/dev/stdout";
          return {};
        }
        if (!path.empty()) return {};
        return std::string(use == Use::read ? kEmptyReadName : kEmptyName);
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
