// Every file of tests/fuzz/corpus/<target>/ and tests/fuzz/regressions/<target>/ through the
// target's entry function, as libFuzzer ran it (docs/robustness.md). A crash, sanitizer report
// (gcc build: none), invariant violation or abort ends the test binary: the test fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_targets.hpp"

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> v;
  if (!fs::is_directory(dir)) return v;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().filename().string().front() != '.') v.push_back(e.path());
  }
  std::sort(v.begin(), v.end());
  return v;
}

class FuzzReplay : public ::testing::TestWithParam<dpc31::fuzz::Target> {};

TEST_P(FuzzReplay, CorpusAndRegressions) {
  const dpc31::fuzz::Target& t = GetParam();
  const fs::path base(FUZZ_DIR);
  const std::vector<fs::path> corpus = files_in(base / "corpus" / std::string(t.name));
  // A target without seeds would replay nothing and pass: that is a mistake, not a success.
  ASSERT_FALSE(corpus.empty()) << "no seed corpus for " << t.name;
  std::vector<fs::path> all = corpus;
  for (const auto& p : files_in(base / "regressions" / std::string(t.name))) all.push_back(p);
  for (const auto& p : all) {
    SCOPED_TRACE(p.string());
    std::ifstream f(p, std::ios::binary);
    ASSERT_TRUE(f) << "cannot read " << p;
    const std::vector<char> bytes((std::istreambuf_iterator<char>(f)),
                                  std::istreambuf_iterator<char>());
    EXPECT_EQ(t.entry(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplay,
                         ::testing::ValuesIn(dpc31::fuzz::targets().begin(),
                                             dpc31::fuzz::targets().end()),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
