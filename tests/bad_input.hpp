// The fixture of the bad-input tests (tests/bad_input_test.cpp, tests/bad_output_test.cpp): the
// real `dpc31` binary run in a scratch directory, and what "one line on stderr, exit 2, nothing
// written" means as assertions.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "run_command.hpp"
#include "test_files.hpp"

extern char** environ;

namespace badinput {

namespace fs = std::filesystem;

inline const std::string kCli = DPC31_CLI;
inline const std::string kTraces = std::string(SOURCE_DIR) + "/traces/";

using testutil::slurp;

inline void spit(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
}

struct Outcome {
  int rc = -1;
  std::string out;
  std::string err;
};

// Each test in a directory of its own: the inputs and outputs live in `work`, stdout and stderr
// of the command go to `io` (so that they never count as files the command left behind).
class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "dpc31-bad-input-XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    root_ = tmpl;
    fs::create_directory(root_ / "work");
    fs::create_directory(root_ / "io");
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(root_ / "work" / "ro", fs::perms::owner_all, ec);
    fs::remove_all(root_, ec);
  }

  [[nodiscard]] std::string path(const std::string& name) const {
    return (root_ / "work" / name).string();
  }
  std::string file(const std::string& name, const std::string& text) {
    spit(path(name), text);
    return path(name);
  }
  std::string copy(const std::string& from, const std::string& name) {
    fs::copy_file(from, path(name), fs::copy_options::overwrite_existing);
    return path(name);
  }
  // The first `keep` bytes of `from`: a file cut off in the middle.
  std::string truncated(const std::string& from, const std::string& name, std::size_t keep) {
    const std::string text = slurp(from);
    EXPECT_LT(keep, text.size());
    return file(name, text.substr(0, keep));
  }

  // `env`: NAME=VALUE settings for the command.
  Outcome dpc31(const std::string& args, const std::string& env = {}) const {
    const std::string out = (root_ / "io" / "out").string();
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult r =
        testutil::run_command("cd " + (root_ / "work").string() + " && " + env + " " + kCli + " " +
                              args + " >" + out + " 2>" + err);
    return {r.rc, slurp(out), slurp(err)};
  }

  // `dpc31 CMD ARGS --json F` checks F before it runs anything: F a directory, F in a missing
  // directory; then each of `bad` (whole argument lists) is refused; nothing is left behind.
  void expect_json_checked_first(const std::string& cmd, const std::string& args,
                                 std::initializer_list<const char*> bad);

  [[nodiscard]] std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(root_ / "work")) {
      names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path root_;
};

// Starts `argv` in `dir` without waiting: its standard output on /dev/null, its standard error on
// `stderr_file` (or the test's); in a process group of its own if `own_group`.
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& dir,
                   const std::string& stderr_file = {}, bool own_group = false,
                   const std::string& stdout_file = "/dev/null") {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (!stderr_file.empty()) {
    posix_spawn_file_actions_addopen(&fa, 2, stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
  }
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  if (own_group) {
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
  }
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, args[0], &fa, &attr, args.data(), environ), 0);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

// Waits up to 60 s for `done`, an event (a file, a process state), looking every 10 ms.
template <typename F>
bool eventually(F done) {
  for (int i = 0; i < 6000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Exit 2 and exactly this one line on stderr.
inline void expect_bad(const Outcome& r, const std::string& line, const std::string& what) {
  EXPECT_EQ(r.rc, 2) << what << "\n" << r.err;
  EXPECT_EQ(r.err, line + "\n") << what;
}

// Exit 2 and one line on stderr that starts with `prefix` (the rest is CLI11's or the system's
// wording, not ours).
inline void expect_bad_prefix(const Outcome& r, const std::string& prefix,
                              const std::string& what) {
  EXPECT_EQ(r.rc, 2) << what << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << what << ": " << r.err;
}

inline void BadInput::expect_json_checked_first(const std::string& cmd, const std::string& args,
                                                std::initializer_list<const char*> bad) {
  fs::create_directory(path("taken"));
  spit(path("old.json"), "old");
  const auto before = listing();
  const std::string who = "dpc31 " + cmd + ": ";
  expect_bad(dpc31(cmd + " " + args + " --json taken"), who + "taken: cannot write: is a directory",
             "json directory");
  expect_bad_prefix(dpc31(cmd + " " + args + " --json no/such/x.json"),
                    who + "no/such/x.json: cannot create the temporary file ", "json dir");
  for (const char* a : bad) expect_bad_prefix(dpc31(a), who, a);
  EXPECT_EQ(slurp(path("old.json")), "old");
  EXPECT_EQ(listing(), before);
}

inline std::string fmt_line(const std::string& file, std::ptrdiff_t line, const std::string& what) {
  return file + ":" + std::to_string(line) + ": " + what;
}

// A directory the command cannot create files in: read-only for a user; root writes anyway, so
// there /proc, where nobody can create files, stands in for it.
inline std::string unwritable_dir(const std::string& ro) {
  if (::geteuid() == 0) return "/proc";
  fs::create_directory(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  return ro;
}

// A 64 KiB tmpfs mounted on `dir` (made here) while it lives: a file system that fills up
// (mounting needs root; the suite runs as root in CI and here).
class SmallTmpfs {
 public:
  explicit SmallTmpfs(std::string dir) : dir_(std::move(dir)) {
    fs::create_directory(dir_);
    if (::mount("tmpfs", dir_.c_str(), "tmpfs", 0, "size=64k") != 0) error_ = std::strerror(errno);
  }
  ~SmallTmpfs() {
    if (error_.empty()) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallTmpfs(const SmallTmpfs&) = delete;
  SmallTmpfs& operator=(const SmallTmpfs&) = delete;
  // "" once mounted, else why not.
  [[nodiscard]] const std::string& error() const { return error_; }
  // Writes the file `fill` until nothing more fits.
  void fill() const {
    std::ofstream f(dir_ + "/fill", std::ios::binary);
    const std::string block(4096, 'x');
    while (f.write(block.data(), static_cast<std::streamsize>(block.size()))) {
    }
  }

 private:
  std::string dir_;
  std::string error_;
};

// The FST block chain (fstapi.h): type byte, big-endian length counting itself, data.
struct FstBlock {
  std::size_t pos;
  unsigned type;
  std::size_t len;
};
inline std::vector<FstBlock> fst_blocks(const std::string& b) {
  std::vector<FstBlock> out;
  for (std::size_t pos = 0; pos + 9 <= b.size();) {
    std::size_t len = 0;
    for (std::size_t i = 1; i < 9; ++i) len = len << 8 | static_cast<unsigned char>(b[pos + i]);
    out.push_back({pos, static_cast<unsigned char>(b[pos]), len});
    pos += 1 + len;
  }
  return out;
}

// " --json taken --vcd new-vcd ...": every output option, `taken` (a directory) for `bad`, a new
// file for the others. Appended piece by piece: the operator+ chain it replaces made GCC 12 at
// -O3 report a false -Wrestrict (issue 17).
inline std::string outputs_one_taken(std::initializer_list<const char*> options,
                                     const std::string& bad) {
  std::string all;
  for (const char* opt : options) {
    all += ' ';
    all += opt;
    if (opt == bad) {
      all += " taken";
    } else {
      all += " new";
      all += opt + 1;
    }
  }
  return all;
}

// A file input and the one line expected on stderr for it.
struct FileCase {
  std::string name;
  std::string path;
  std::string line;  // the one line expected on stderr
};

}  // namespace badinput
