// The fuzz targets' entry functions (docs/robustness.md). Each takes one input, never throws,
// and returns 0; a bug shows as a sanitizer report, an abort (the invariant checker) or a hang.
// libFuzzer calls them through fuzz_main.cpp; the default (gcc) test suite replays every corpus
// and regression file through the same functions (replay_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace dpc31::fuzz {

using Entry = int (*)(const std::uint8_t* data, std::size_t size);

int chip_bits(const std::uint8_t* data, std::size_t size);   // RxD edges with timing
int chip_bytes(const std::uint8_t* data, std::size_t size);  // UART characters with gaps
int trace_parser(const std::uint8_t* data, std::size_t size);
int scenario_parser(const std::uint8_t* data, std::size_t size);
int vcd_reader(const std::uint8_t* data, std::size_t size);
int fst_reader(const std::uint8_t* data, std::size_t size);
int serve_lines(const std::uint8_t* data, std::size_t size);
int snapshot_loader(const std::uint8_t* data, std::size_t size);

// The first check a target's parser makes of an input (a snapshot's header and CRC, a trace's or
// a scenario's syntax, a waveform's header, the first line `serve` accepts, a chip input's set-up
// byte and first item): "" if the input passes it, else why not. Every seed must pass (a stale
// seed refused at the header fuzzes nothing but the header: issue 29), seeds_test.cpp.
using Check = std::string (*)(const std::uint8_t* data, std::size_t size);

std::string chip_bits_check(const std::uint8_t* data, std::size_t size);
std::string chip_bytes_check(const std::uint8_t* data, std::size_t size);
std::string trace_parser_check(const std::uint8_t* data, std::size_t size);
std::string scenario_parser_check(const std::uint8_t* data, std::size_t size);
std::string vcd_reader_check(const std::uint8_t* data, std::size_t size);
std::string fst_reader_check(const std::uint8_t* data, std::size_t size);
std::string serve_lines_check(const std::uint8_t* data, std::size_t size);
std::string snapshot_loader_check(const std::uint8_t* data, std::size_t size);

struct Target {
  std::string_view name;  // also the directory under tests/fuzz/corpus and regressions
  Entry entry;
  Check check;
};
std::span<const Target> targets();

}  // namespace dpc31::fuzz
