#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/regdesc.hpp"

namespace dpc31::cli {

struct CosimOptions {
  Profile profile = Profile::dpc31;
  std::string profile_name = "dpc31";
  bool profile_given = false;  // --profile and --mutant on the command line: a replayed trace's
  bool mutant_given = false;   // header must not contradict them, nor --bus and --variant
  bool bus_given = false;
  BusMode bus = BusMode::intel;
  std::string variant_name;  // --variant as given ("" none): applied once the profile is known
  std::optional<Vpc3Variant> variant = std::nullopt;  // ... as the chip takes it (vpc3plus)
  std::uint64_t seeds = 10;
  std::uint64_t seed_base = 1;
  std::uint64_t cycles = 20'000;
  std::uint64_t shard = 1;  // 1..shards
  std::uint64_t shards = 1;
  // Your RTL at run time (docs/golden-model.md): Verilog sources Verilated and built into the
  // cache, or a model built by dpc31emu_verilate_model().
  std::vector<std::string> rtl_sources;
  std::string top;
  std::vector<std::string> defines;
  std::string rtl_model;
  bool rtl_host_code = false;  // --rtl-host-code: $system, $c, ... in the --rtl sources
  std::string junit;
  std::string vcd_dir;
  std::string out_dir;   // where shrunk traces go
  std::string replay;    // a trace file instead of random seeds
  std::string mutant;    // an RTL mutant instead of the real model
  std::string session;   // chip-session mode: a scenario file
  std::string dump_dir;  // write both sides' whole run (first seed or the replay) here
  std::uint64_t window = 50;
  bool keep_going = false;
  bool quiet = false;
};

int run_cosim(const CosimOptions& o);

// dpc31 cosim merge: the JSON summaries of the shards of one run into the summary (stdout) and
// JUnit file of the whole run (docs/regression.md). Exit 0 / 1 as the run's verdict, 2 bad input.
struct MergeOptions {
  std::vector<std::string> inputs;
  std::string junit;
};
int run_cosim_merge(const MergeOptions& o);

}  // namespace dpc31::cli
