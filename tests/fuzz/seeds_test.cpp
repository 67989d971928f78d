// Every fuzz target's seeds pass its parser's first check (fuzz_targets.hpp, Target::check): a
// format change that leaves the seeds behind fails here, instead of leaving the fuzzer at the
// header (issue 29: the snapshot seeds were format version 2 while the loader read version 3, so
// every one was refused there; coverage 456 instead of 1 268). That the generated seeds are what
// the current writers produce is CTest FuzzSeeds.generated_are_current (tests/fuzz/CMakeLists.txt).
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

class FuzzSeeds : public ::testing::TestWithParam<dpc31::fuzz::Target> {};

TEST_P(FuzzSeeds, EverySeedPassesTheParsersFirstCheck) {
  const dpc31::fuzz::Target& t = GetParam();
  const fs::path dir = fs::path(FUZZ_DIR) / "corpus" / std::string(t.name);
  std::vector<fs::path> seeds;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file()) seeds.push_back(e.path());
  }
  std::sort(seeds.begin(), seeds.end());
  ASSERT_FALSE(seeds.empty()) << dir;
  for (const fs::path& p : seeds) {
    std::ifstream f(p, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(f)),
                                  std::istreambuf_iterator<char>());
    EXPECT_EQ(t.check(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "")
        << p.filename().string();
  }
}

// The check can fail: a snapshot seed with the format version of issue 29's finding (2) is
// refused at its header, as every seed was before.
TEST(FuzzSeeds, AStaleSnapshotSeedFailsTheCheck) {
  const dpc31::fuzz::Target* loader = nullptr;
  for (const auto& t : dpc31::fuzz::targets()) {
    if (t.name == "snapshot_loader") loader = &t;
  }
  ASSERT_NE(loader, nullptr);
  std::ifstream f(fs::path(FUZZ_DIR) / "corpus" / "snapshot_loader" / "spc3_intel_fresh",
                  std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  ASSERT_GE(bytes.size(), 36u);
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());
  ASSERT_EQ(loader->check(data, bytes.size()), "");
  bytes[8] = 2;  // docs/snapshots.md: the format version, bytes 8..11, little-endian
  bytes[9] = bytes[10] = bytes[11] = 0;
  EXPECT_NE(loader->check(data, bytes.size()), "");
  // And the other checks refuse what is no input of theirs.
  for (const auto& t : dpc31::fuzz::targets()) {
    const std::uint8_t junk[] = {0x01};
    EXPECT_NE(t.check(junk, sizeof junk), "") << t.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzSeeds,
                         ::testing::ValuesIn(dpc31::fuzz::targets().begin(),
                                             dpc31::fuzz::targets().end()),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
