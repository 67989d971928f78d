// `dpc31 wavediff` on two large VCD files (issue 7 item f: >= 300 MB/s with peak RSS < 64 MB).
// The pair is generated at run time into a temporary directory (lib/wavediff/synthetic_vcd:
// RTL-dump-shaped, four one-bit differences), --wavediff_mb MB each (default 1000); the real
// command runs as a child process, its wall time is the iteration time and wait4's ru_maxrss its
// peak RSS. That figure also counts what this process had resident when it spawned the child (a
// few MB; `peak_rss_parent_MB`), so it is an upper bound.
// BM_WavediffEmulatorPair: the same on what users compare, the emulator's own VCD (`dpc31 run
// --vcd` of a Data_Exchange run at 12 Mbaud, 32 + 32 bytes; about 5.7 MB per 1000 exchanges, so
// 33 x --wavediff_mb exchanges: 190 MB at the default) against a copy with four one-bit signal
// changes flipped, at a quarter, half, three quarters and near the end of the file.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "bench_options.hpp"
#include "child.hpp"
#include "cleanup.hpp"
#include "synthetic_vcd.hpp"

namespace {

namespace fs = std::filesystem;

using MakePair = bool (*)(const fs::path& dir, const std::string& a, const std::string& b,
                          std::string& error);

bool synthetic_pair(const fs::path& /*dir*/, const std::string& a, const std::string& b,
                    std::string& error) {
  dpc31::wavediff::SyntheticVcd spec;
  spec.steps = dpc31::wavediff::synthetic_steps_for_megabytes(dpc31::bench::options().wavediff_mb);
  spec.diff_steps = {spec.steps / 4, spec.steps / 2, spec.steps * 3 / 4, spec.steps - 10};
  return dpc31::wavediff::write_synthetic_vcd_pair(a, b, spec, error);
}

// The next one-bit value change ("0x" / "1x" at the start of a line) from `from` on, flipped.
bool flip_scalar_change(std::string& vcd, std::size_t from) {
  for (std::size_t at = vcd.find('\n', from); at != std::string::npos && at + 2 < vcd.size();
       at = vcd.find('\n', at + 1)) {
    char& v = vcd[at + 1];
    if ((v == '0' || v == '1') && vcd[at + 2] != '\n') {
      v = v == '0' ? '1' : '0';
      return true;
    }
  }
  return false;
}

bool emulator_pair(const fs::path& dir, const std::string& a, const std::string& b,
                   std::string& error) {
  const auto& opt = dpc31::bench::options();
  const std::string scn = (dir / "dx.scn").string();
  {
    std::ofstream f(scn);
    f << "profile dpc31\nbaud 12000000\nslave in=32 out=32\nstartup\nexchange "
      << std::max<std::uint64_t>(1000, 33 * opt.wavediff_mb) << "\n";
    if (!f.flush()) {
      error = scn + ": cannot write";
      return false;
    }
  }
  const dpc31::child::Result r =
      dpc31::child::run({opt.dpc31_cli, "run", "--quiet", "--vcd", a, scn});
  if (r.exit_code != 0) {
    error = "dpc31 run --vcd exited with " + std::to_string(r.exit_code) + " " + r.error;
    return false;
  }
  std::ifstream in(a, std::ios::binary);
  std::string vcd((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t body = vcd.find("$enddefinitions");
  const std::size_t n = vcd.size();
  for (const std::size_t at : {n / 4, n / 2, n * 3 / 4, n - n / 100}) {
    if (body == std::string::npos || !flip_scalar_change(vcd, std::max(at, body))) {
      error = a + ": no one-bit value change to flip";
      return false;
    }
  }
  std::ofstream out(b, std::ios::binary);
  if (!out.write(vcd.data(), static_cast<std::streamsize>(vcd.size())) || !out.flush()) {
    error = b + ": cannot write";
    return false;
  }
  return true;
}

// Makes the pair in `dir` and runs `dpc31 wavediff` on it.
void generate_and_compare(benchmark::State& st, const fs::path& dir, MakePair make) {
  const auto& opt = dpc31::bench::options();
  const std::string a = (dir / "a.vcd").string();
  const std::string b = (dir / "b.vcd").string();
  std::string error;
  if (!make(dir, a, b, error)) {
    st.SkipWithError(error.c_str());
    return;
  }
  dpc31::bench::files_made();
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

// The pair (gigabytes each) in a new private directory, removed with all in it when the benchmark
// ends, also when a signal ends this process (dpc31 bench passes its own on and waits for us).
void in_own_dir(benchmark::State& st, MakePair make) {
  const std::string& base = dpc31::bench::options().wavediff_dir;
  std::string dir =
      ((base.empty() ? fs::temp_directory_path() : fs::path(base)) / "dpc31-bench-wavediff-XXXXXX")
          .string();
  if (::mkdtemp(dir.data()) == nullptr) {
    st.SkipWithError(("cannot create " + dir + ": " + std::strerror(errno)).c_str());
    return;
  }
  const dpc31::cleanup::Entry gone = dpc31::cleanup::Entry::tree(dir);
  generate_and_compare(st, dir, make);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

void BM_WavediffLargePair(benchmark::State& st) { in_own_dir(st, synthetic_pair); }
BENCHMARK(BM_WavediffLargePair)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

void BM_WavediffEmulatorPair(benchmark::State& st) { in_own_dir(st, emulator_pair); }
BENCHMARK(BM_WavediffEmulatorPair)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
