// dpc31 bridge: the emulated slave's RS-485 side as a Linux pseudo-terminal (docs/bridge.md).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "chip_choice.hpp"

namespace dpc31::cli {

// Every option is kept as text and checked by run_bridge, so a bad value gives one line on
// stderr and exit code 2 (CLI11's own messages take two lines).
struct BridgeOptions {
  std::string pty;            // the symlink to create
  std::string tcp;            // or "[HOST:]PORT": a TCP port (docs/bridge.md, "Over TCP")
  bool allow_remote = false;  // --tcp on an address that is not the loopback
  std::string pcap;           // the line as pcapng, written when the bridge stops
  std::string baud = "19200";
  std::string profile = "dpc31";
  ChipChoice chip;  // --variant, --irq-controller
  std::string firmware;
  std::string address = "5";
  std::string pacing = "realtime";
  std::string log;  // "" = stdout
  std::string log_level = "events";
  std::string slot = "100";
  std::string
      cpu;  // "80c32[:HZ]" or "c31[:HZ]": --firmware is an Intel HEX image for it (docs/cpu.md)
  std::string code;           // --code A: the C31's code area (c31 only)
  std::string board_address;  // --board-address A: the chip's window in the 80C32's XDATA
  std::string trace_cpu;      // every 80C32 / C31 instruction with its cycle, to this file
  // --trace-cpu-from / --trace-cpu-to C: only the steps whose first chip cycle lies in [from, to)
  std::optional<std::uint64_t> trace_cpu_from, trace_cpu_to;
  // --slave ADDR:FIRMWARE[:PROFILE[:VARIANT]], repeated: stations on one line (docs/bridge.md,
  // "Several slaves")
  std::vector<std::string> slaves;
  std::vector<std::string> single;  // the single-slave options given (refused beside --slave)
  std::string ports;                // the 80C32 latch bytes by name, as `ports=`; empty: DO4's
  std::vector<std::string> extra;   // unknown arguments, refused by run_bridge
};

CLI::App* add_bridge_subcommand(CLI::App& app, BridgeOptions& o);

// Runs until SIGINT or SIGTERM: 0 then; 2 for bad options or when the pty cannot be set up; 1
// for a failure while running. Errors go to `err` (one line); the log to `out` unless --log.
int run_bridge(const BridgeOptions& o, std::FILE* out, std::FILE* err);

}  // namespace dpc31::cli
