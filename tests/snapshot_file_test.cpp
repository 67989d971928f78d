// Snapshot files (docs/snapshots.md): save writes exactly the file, a failed save leaves no
// temporary file, load errors name the path.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "snapshot_session.hpp"

using namespace dpc31;
using namespace snapshot_session;
namespace fs = std::filesystem;

namespace {

class SnapshotFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           fmt::format("dpc31-snapshot-{}-{}", ::getpid(),
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, ec);
    fs::remove_all(dir_, ec);
  }
  std::vector<std::string> listing(const fs::path& d) const {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(d)) v.push_back(e.path().filename().string());
    std::sort(v.begin(), v.end());
    return v;
  }
  fs::path dir_;
};

TEST_F(SnapshotFile, SaveWritesExactlyTheFileAndLoadRestoresIt) {
  const Chip a = mid_session(Profile::vpc3plus);
  const std::string path = (dir_ / "a.snap").string();
  a.save_state_file(path);
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"a.snap"});
  // Over an existing file made private: it stays so (docs/bad-input.md: a replaced file
  // keeps its permission bits), as every door that saves a snapshot (serve's `save`, Python) has
  // it.
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  a.save_state_file(path);
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"a.snap"});
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  Chip b({Profile::vpc3plus, BusMode::intel, 0});
  b.load_state_file(path);
  EXPECT_EQ(b.save_state(), a.save_state());
}

TEST_F(SnapshotFile, FailedSaveThrowsAndLeavesNoTemporaryFile) {
  const Chip a({Profile::dpc31, BusMode::intel, 0});
  auto expect_throw = [&](const std::string& path) {
    try {
      a.save_state_file(path);
      ADD_FAILURE() << "saved to " << path;
    } catch (const SnapshotError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
  };
  // The target is a directory: the temporary file is written, the rename fails.
  fs::create_directory(dir_ / "taken");
  fs::create_directory(dir_ / "taken" / "inside");
  expect_throw((dir_ / "taken").string());
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"taken"});
  // A directory that does not exist.
  expect_throw((dir_ / "missing" / "a.snap").string());
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"taken"});
  // A directory without write permission (root may write anyway: then /proc, where nobody can
  // create files, stands in for it).
  const fs::path ro = dir_ / "read-only";
  fs::create_directory(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  if (::geteuid() != 0) {
    expect_throw((ro / "a.snap").string());
    EXPECT_TRUE(listing(ro).empty());
  } else {
    expect_throw("/proc/dpc31-snapshot-test.snap");
  }
  // No name: refused before a temporary file ".dpc31-PID.tmp" is made in the working directory.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  try {
    a.save_state_file("");
    ADD_FAILURE() << "saved to an empty name";
  } catch (const SnapshotError& e) {
    EXPECT_STREQ(e.what(), "an empty file name: nothing can be written there");
  }
  fs::current_path(cwd);
  EXPECT_EQ(listing(dir_), (std::vector<std::string>{"read-only", "taken"}));
}

TEST_F(SnapshotFile, LoadErrorsNameThePath) {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  const Bytes before = c.save_state();
  // Loading `path` throws SnapshotError with "PATH: why".
  auto expect_error = [&c](const std::string& path, const std::string& why) {
    try {
      c.load_state_file(path);
      ADD_FAILURE() << path << " loaded";
    } catch (const SnapshotError& e) {
      EXPECT_EQ(std::string(e.what()), path + ": " + why);
    }
  };
  expect_error((dir_ / "none.snap").string(), "no such file");
  // No name: the words of `--load-state ''` (util/outfile/path_option.hpp), no ": no such file".
  try {
    c.load_state_file("");
    ADD_FAILURE() << "loaded an empty name";
  } catch (const SnapshotError& e) {
    EXPECT_STREQ(e.what(), "an empty file name: nothing can be read there");
  }
  const std::string foreign = (dir_ / "foreign.snap").string();
  std::ofstream(foreign) << "# a scenario, not a snapshot\n";
  expect_error(foreign, "not a dpc31emu snapshot (bad magic)");
  EXPECT_EQ(c.save_state(), before);
}

}  // namespace
