// A signal to `dpc31 bench` (docs/security.md, "child processes"; issue 35): whatever phase it
// lands in, dpc31 ends by it only after its child dpc31_bench (and what that started) has ended,
// and by then every file any of them made is gone. The phases are exact, not a sleep's chance:
// DPC31_STOP_AT (util/child's stop_point) stops the process tree at one named phase, the test sees
// the stop in /proc, signals dpc31 and continues the stopped process once the signal has reached
// it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bad_input.hpp"

using namespace badinput;

namespace {

// /proc/PID/stat: the state letter (0 if the process is gone) and the parent.
struct ProcStat {
  char state = 0;
  pid_t ppid = 0;
};
ProcStat proc_stat(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  std::getline(f, text);
  ProcStat s;
  const auto close = text.rfind(')');
  if (close == std::string::npos) return s;
  std::istringstream rest(text.substr(close + 2));
  rest >> s.state >> s.ppid;
  return s;
}

std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string n = e.path().filename().string();
    if (n.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = std::stoi(n);
    if (proc_stat(pid).ppid == parent) out.push_back(pid);
  }
  return out;
}

// Whether `sig` is pending for the process as a whole (ShdPnd of /proc/PID/status): a signal sent
// to a stopped process waits there until it continues.
bool pending(pid_t pid, int sig) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("ShdPnd:", 0) == 0) {
      return (std::stoull(line.substr(7), nullptr, 16) >> (sig - 1) & 1) != 0;
    }
  }
  return false;
}

// `dpc31 bench --quick --items ITEM [extra]` with TMPDIR = the work directory and DPC31_STOP_AT
// = `stop`; its standard error in io/err. In a process group of its own: a stopped process in the
// test runner's group would, were that group orphaned (a suite started under nohup), bring SIGHUP
// to every test running beside it (POSIX: a newly orphaned group with a stopped member gets SIGHUP
// and SIGCONT).
pid_t start_bench(const fs::path& root, const std::string& item, const std::string& stop,
                  const std::vector<std::string>& extra = {}) {
  const std::string work = (root / "work").string();
  std::vector<std::string> argv = {kCli, "bench", "--quick", "--items", item};
  argv.insert(argv.end(), extra.begin(), extra.end());
  ::setenv("TMPDIR", work.c_str(), 1);
  if (!stop.empty()) ::setenv("DPC31_STOP_AT", stop.c_str(), 1);
  const pid_t pid = spawn(argv, work, (root / "io" / "err").string(), true);
  ::unsetenv("TMPDIR");
  ::unsetenv("DPC31_STOP_AT");
  return pid;
}

// On the way out of a case, also a failed one: dpc31's group killed (its child, stopped or not,
// dies with it: PR_SET_PDEATHSIG) and reaped, so that no stopped process outlives the test.
struct KillOnExit {
  pid_t pid;
  ~KillOnExit() {
    if (::kill(-pid, SIGKILL) == 0) ::waitpid(pid, nullptr, 0);
  }
};

// dpc31 ended by SIGTERM.
void expect_ended_by_sigterm(pid_t pid, const std::string& what) {
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid) << what;
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << what << ": status " << status;
}

// Every phase of every item of `dpc31 bench --quick`: dpc31 before the item's dpc31_bench starts,
// dpc31_bench started (its log open, dpc31's output file about to be), and, for the items that
// make files of their own, dpc31_bench with them made (f: the generated VCD pair in its private
// directory; g: the Unix socket; i: the traced run's VCD). SIGTERM to dpc31 at each.
TEST_F(BadInput, ASignalToBenchEndsItsChildAndRemovesTheFiles) {
  std::vector<std::pair<std::string, std::string>> phases;  // item, stop point
  for (const std::string item : {"a", "b", "b'", "c", "d", "e", "f", "g", "i"}) {
    phases.emplace_back(item, "dpc31 bench item " + item);
    phases.emplace_back(item, "dpc31_bench item " + item);
  }
  for (const std::string item : {"f", "g", "i"}) {
    phases.emplace_back(item, "dpc31_bench item " + item + " files");
  }
  for (const auto& [item, stop] : phases) {
    const pid_t pid = start_bench(root_, item, stop);
    ASSERT_GT(pid, 0);
    const KillOnExit reap{pid};
    // The stopped process: dpc31 itself or its child dpc31_bench.
    pid_t stopped = -1;
    bool ended = false;
    ASSERT_TRUE(eventually([&] {
      for (const pid_t p : [&] {
             std::vector<pid_t> tree = children_of(pid);
             tree.insert(tree.begin(), pid);
             return tree;
           }()) {
        if (proc_stat(p).state == 'T') {
          stopped = p;
          return true;
        }
      }
      int status = 0;
      ended = ::waitpid(pid, &status, WNOHANG) == pid;
      return ended;
    })) << stop;
    ASSERT_FALSE(ended) << stop << ": dpc31 ended without stopping there: "
                        << slurp((root_ / "io" / "err").string());
    ASSERT_EQ(::kill(pid, SIGTERM), 0);
    // dpc31 passes the signal on to its child's group; the child takes it once continued.
    if (stopped != pid) {
      EXPECT_TRUE(eventually([&] { return pending(stopped, SIGTERM); })) << stop;
    }
    ASSERT_EQ(::kill(stopped, SIGCONT), 0);
    expect_ended_by_sigterm(pid, stop);
    // No waiting: by the time dpc31 has ended, its child is gone and so are the files of both.
    if (stopped != pid) {
      EXPECT_EQ(proc_stat(stopped).state, 0) << stop << ": the child is left";
    }
    EXPECT_EQ(listing(), std::vector<std::string>{})
        << stop << ": left " << ::testing::PrintToString(listing());
    if (stopped == pid) {
      EXPECT_NE(slurp((root_ / "io" / "err").string()).find("stopped at " + stop),
                std::string::npos)
          << stop;
    }
  }
}

// A child that needs time to remove its own file when signalled (a stand-in for dpc31_bench: a
// shell script that traps SIGTERM, waits half a second, removes the file it made): dpc31 passes
// SIGTERM on and ends only after the child has cleaned up. Ending at once (the child then killed
// by its PR_SET_PDEATHSIG, mid-cleanup) would leave the file.
TEST_F(BadInput, ASignalToBenchWaitsForItsChildToCleanUp) {
  const std::string held = path("held-by-child");
  const std::string fake = (root_ / "io" / "fake_dpc31_bench").string();
  spit(fake, "#!/bin/sh\ntrap 'sleep 0.5; rm -f \"" + held + "\"; exit 143' TERM\n: > \"" + held +
                 "\"\nwhile :; do sleep 0.05; done\n");
  fs::permissions(fake, fs::perms::owner_all);
  const pid_t pid = start_bench(root_, "a", "", {"--bench", fake});
  ASSERT_GT(pid, 0);
  const KillOnExit reap{pid};
  ASSERT_TRUE(eventually([&] { return fs::exists(held); }));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  expect_ended_by_sigterm(pid, "stand-in");
  EXPECT_EQ(listing(), std::vector<std::string>{})
      << "left " << ::testing::PrintToString(listing());
}

}  // namespace
