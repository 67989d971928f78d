// dpc31_bench: Google Benchmark's main, plus the options of bench_options.hpp. `dpc31 bench`
// runs this binary and tabulates the results against the targets (tools/cli/bench.cpp).
#include <benchmark/benchmark.h>

#include <charconv>
#include <cstdio>
#include <string_view>
#include <vector>

#include "bench_options.hpp"
#include "child.hpp"
#include "cleanup.hpp"

namespace dpc31::bench {

Options& options() {
  static Options o = [] {
    Options d;
    d.dpc31_cli = DPC31_CLI;
    return d;
  }();
  return o;
}

void files_made() {
  static bool once = false;
  if (once) return;
  once = true;
  child::stop_point("dpc31_bench item " + options().item + " files");
}

}  // namespace dpc31::bench

namespace {

// Takes --NAME=VALUE out of argv; false with a message if VALUE is bad.
bool take_options(int& argc, char** argv) {
  auto& o = dpc31::bench::options();
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    const std::string_view a = argv[i];
    const auto value = [&](std::string_view name) -> std::string_view {
      return a.substr(0, name.size()) == name ? a.substr(name.size()) : std::string_view{};
    };
    if (i > 0 && !value("--dpc31_cli=").empty()) {
      o.dpc31_cli = value("--dpc31_cli=");
    } else if (i > 0 && !value("--dpc31_item=").empty()) {
      o.item = value("--dpc31_item=");
    } else if (i > 0 && !value("--wavediff_dir=").empty()) {
      o.wavediff_dir = value("--wavediff_dir=");
    } else if (i > 0 && !value("--wavediff_mb=").empty()) {
      const std::string_view v = value("--wavediff_mb=");
      const auto r = std::from_chars(v.data(), v.data() + v.size(), o.wavediff_mb);
      if (r.ec != std::errc{} || r.ptr != v.data() + v.size() || o.wavediff_mb == 0) {
        std::fprintf(stderr, "dpc31_bench: --wavediff_mb takes a whole number > 0, not '%.*s'\n",
                     static_cast<int>(v.size()), v.data());
        return false;
      }
    } else {
      rest.push_back(argv[i]);
    }
  }
  for (std::size_t i = 0; i < rest.size(); ++i) argv[i] = rest[i];
  argc = static_cast<int>(rest.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  dpc31::cleanup::install();  // the large files of a benchmark go when a signal ends it
  if (!take_options(argc, argv)) return 2;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  dpc31::child::stop_point("dpc31_bench item " + dpc31::bench::options().item);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
