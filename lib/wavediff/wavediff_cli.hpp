// The `dpc31 wavediff` subcommand: CLI11 options and the glue to dpc31::wavediff::run.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "wavediff.hpp"

namespace dpc31::wavediff {

// Options as typed: times and policies stay text until run_cli checks them.
struct CliArgs {
  Options opt;
  std::string strip;  // "auto"
  std::string start;
  std::string end;
  std::string tolerance;
  std::string xz = "strict";
  std::string edge = "rising";
};

// Adds the subcommand with all its options to `app`.
CLI::App* add_subcommand(CLI::App& app, CliArgs& a);

// Checks the text options, runs the comparison, prints the report to `out` and errors to `err`.
// Exit code 0 same, 1 different, 2 bad input.
int run_cli(CliArgs a, std::FILE* out, std::FILE* err);

}  // namespace dpc31::wavediff
