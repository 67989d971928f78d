// The `dpc31 serve` subcommand: CLI11 options and the glue to dpc31::serve::Server.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdio>
#include <string>

#include "chip_choice.hpp"

namespace dpc31::cli {

struct ServeArgs {
  std::string tcp;        // "" = no TCP endpoint
  std::string unix_path;  // "" = no Unix socket
  std::string profile = "dpc31";
  std::string bus = "intel";
  ChipChoice chip;          // --variant, --irq-controller
  std::string state_dir;    // "" = save/load refused
  std::string secret_file;  // "" = no auth on TCP
  // --cpu 80c32[:HZ] | c31[:HZ] with --firmware FILE.ihx (docs/protocol.md, "A CPU on the bus")
  std::string cpu, firmware, code, board_address, ports;
  std::string address;  // the address switch on port 1 (empty: 5)
  std::size_t max_clients = 16;
  double idle_timeout = 300;  // seconds, 0 = never
};

// Adds the subcommand with all its options to `app`.
CLI::App* add_serve_subcommand(CLI::App& app, ServeArgs& a);

// Binds, prints one "listening ..." line per endpoint to `out` (flushed), serves until a client
// sends `shutdown` or SIGINT/SIGTERM arrives. Exit code 0, or 2 with one line on `err` when
// nothing can be bound.
int run_serve(const ServeArgs& a, std::FILE* out, std::FILE* err);

}  // namespace dpc31::cli
