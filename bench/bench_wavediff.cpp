// `dpc31 wavediff` on two large VCD files (issue 7 item f: >= 300 MB/s with peak RSS < 64 MB).
// The pair is generated at run time into a temporary directory (lib/wavediff/synthetic_vcd:
// RTL-dump-shaped, four one-bit differences), --wavediff_mb MB each (default 1000); the real
// command runs as a child process, its wall time is the iteration time and wait4's ru_maxrss its
// peak RSS. That figure also counts what this process had resident when it spawned the child (a
// few MB; `peak_rss_parent_MB`), so it is an upper bound.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_options.hpp"
#include "child.hpp"
#include "cleanup.hpp"
#include "synthetic_vcd.hpp"

namespace {

namespace fs = std::filesystem;

// Generates the pair in `dir` and runs `dpc31 wavediff` on it.
void generate_and_compare(benchmark::State& st, const fs::path& dir) {
  const auto& opt = dpc31::bench::options();
  const std::string a = (dir / "a.vcd").string();
  const std::string b = (dir / "b.vcd").string();
  // Gigabytes each: removed if a signal ends the run (dpc31 bench passes its own on).
  const dpc31::cleanup::Entry gone[] = {dpc31::cleanup::Entry::path(a),
                                        dpc31::cleanup::Entry::path(b)};
  dpc31::wavediff::SyntheticVcd spec;
  spec.steps = dpc31::wavediff::synthetic_steps_for_megabytes(opt.wavediff_mb);
  spec.diff_steps = {spec.steps / 4, spec.steps / 2, spec.steps * 3 / 4, spec.steps - 10};
  std::string error;
  if (!dpc31::wavediff::write_synthetic_vcd_pair(a, b, spec, error)) {
    st.SkipWithError(error.c_str());
    return;
  }
  const double mb = static_cast<double>(fs::file_size(a) + fs::file_size(b)) / 1e6;
  struct rusage self {};
  ::getrusage(RUSAGE_SELF, &self);
  long maxrss = 0;
  for (auto _ : st) {
    const auto t0 = std::chrono::steady_clock::now();
    const dpc31::child::Result r = dpc31::child::run({opt.dpc31_cli, "wavediff", a, b});
    st.SetIterationTime(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (r.exit_code != 1) {  // 1: the files differ, as they do
      st.SkipWithError(("dpc31 wavediff exited with " + std::to_string(r.exit_code) + " " +
                        r.error + " (" + opt.dpc31_cli + ")")
                           .c_str());
      return;
    }
    maxrss = std::max(maxrss, r.maxrss_kib);
  }
  st.counters["MB_per_s"] =
      benchmark::Counter(mb * static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
  st.counters["input_MB"] = mb;
  st.counters["peak_rss_MB"] = static_cast<double>(maxrss) / 1024.0;
  st.counters["peak_rss_parent_MB"] = static_cast<double>(self.ru_maxrss) / 1024.0;
}

void BM_WavediffLargePair(benchmark::State& st) {
  const std::string& base = dpc31::bench::options().wavediff_dir;
  const fs::path dir = (base.empty() ? fs::temp_directory_path() : fs::path(base)) /
                       ("dpc31-bench-wavediff-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const dpc31::cleanup::Entry gone = dpc31::cleanup::Entry::dir(dir.string());
  generate_and_compare(st, dir);
  std::error_code ec;
  fs::remove_all(dir, ec);
}
BENCHMARK(BM_WavediffLargePair)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
