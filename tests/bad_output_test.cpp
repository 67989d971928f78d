// Outputs that must not destroy or half-write (docs/security.md, docs/bad-input.md): device
// nodes, FIFOs and symlinks as outputs, a full file system, a failed write to stdout, an output
// that names an input, signals during a run, the demo's private directory, numbers that are not
// finite or in range, and inputs whose size must not decide what is allocated.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bad_input.hpp"

using namespace badinput;

namespace {

// --- Outputs that must not destroy or half-write (docs/security.md, findings 2, 6, 7) -----------

const std::string kScn = kTraces + "gc_clear_spc3.scn";

std::string refused_words() { return ": an output must not replace an input"; }

// The FST writer (fstapi) unlinks the name it is given: a device or a FIFO named by --fst must
// be written in place, never replaced by a plain file (issue 14, finding 2).
TEST_F(BadInput, FstToADeviceKeepsTheDeviceNode) {
  struct stat before {};
  ASSERT_EQ(::stat("/dev/null", &before), 0);
  ASSERT_TRUE(S_ISCHR(before.st_mode));
  const Outcome r = dpc31("run " + kScn + " --quiet --fst /dev/null --vcd /dev/null");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.err, "");
  struct stat after {};
  ASSERT_EQ(::stat("/dev/null", &after), 0);
  EXPECT_TRUE(S_ISCHR(after.st_mode)) << "/dev/null is no longer a character device";
  EXPECT_EQ(after.st_rdev, before.st_rdev);
  EXPECT_EQ(after.st_ino, before.st_ino);
  // Nothing of fstapi's left in TMPDIR's scratch directory or here.
  EXPECT_EQ(listing(), std::vector<std::string>{});
}

TEST_F(BadInput, FstToAFifoWritesTheWholeFileThroughIt) {
  ASSERT_EQ(::mkfifo(path("pipe").c_str(), 0600), 0);
  const std::string got = (root_ / "io" / "got").string();
  const testutil::CommandResult r = testutil::run_command(
      "cd " + (root_ / "work").string() + " && { cat pipe > " + got + " & " + kCli + " run " +
      kScn + " --quiet --fst pipe; rc=$?; wait; exit $rc; } 2>&1");
  EXPECT_EQ(r.rc, 0) << r.out;
  struct stat st {};
  ASSERT_EQ(::lstat(path("pipe").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  // The same bytes as a run into a regular file.
  EXPECT_EQ(dpc31("run " + kScn + " --quiet --fst file.fst").rc, 0);
  const std::string bytes = slurp(got);
  EXPECT_GT(bytes.size(), 329u);
  EXPECT_EQ(bytes.substr(0, 9), slurp(path("file.fst")).substr(0, 9));
  EXPECT_EQ(fst_blocks(bytes).size(), fst_blocks(slurp(path("file.fst"))).size());
}

// A symlink to a file: the link stays, the file it names is replaced. A link to nothing is
// refused (creating what it names would write wherever its maker chose).
TEST_F(BadInput, OutputSymlinksAreFollowedOnlyToAnExistingFile) {
  spit(path("real.fst"), "old");
  fs::create_symlink("real.fst", path("link.fst"));
  EXPECT_EQ(dpc31("run " + kScn + " --quiet --fst link.fst").rc, 0);
  EXPECT_TRUE(fs::is_symlink(path("link.fst")));
  EXPECT_EQ(slurp(path("real.fst")).substr(0, 1), std::string(1, '\0'));  // an FST header block
  fs::create_symlink("nowhere/x.vcd", path("dangling.vcd"));
  const auto before = listing();
  expect_bad(dpc31("run " + kScn + " --quiet --vcd dangling.vcd"),
             "dpc31 run: dangling.vcd: cannot write: a symbolic link to a missing file",
             "dangling");
  EXPECT_EQ(listing(), before);
}

// docs/bad-input.md "Output files": a descriptor (/dev/stdout, /dev/stderr, /dev/fd/N,
// /proc/self/fd/N) is written in place, whatever its stream is: a `>>` log grows, a `>` file
// holds the walk and then the JSON, a deleted file is no reason to make one (s29-sec, finding 1).
TEST_F(BadInput, ADescriptorRedirectedToAFileIsWrittenInPlace) {
  ASSERT_EQ(dpc31("run " + kScn + " --json alone.json").rc, 0);
  const std::string walk = dpc31("run " + kScn).out;
  const std::string json = slurp(path("alone.json"));
  ASSERT_GT(walk.size(), 1000u);
  ASSERT_GT(json.size(), 500u);
  const auto sh = [this](const std::string& line) {
    return testutil::run_command("cd " + path("") + " && " + line + " 2>&1");
  };
  const std::string run = kCli + " run " + kScn;
  spit(path("results.log"), "previous 1\nprevious 2\n");
  struct stat before {};
  ASSERT_EQ(::stat(path("results.log").c_str(), &before), 0);
  EXPECT_EQ(sh(run + " --quiet --json /dev/stdout >> results.log").rc, 0);
  EXPECT_EQ(slurp(path("results.log")), "previous 1\nprevious 2\n" + json);
  struct stat after {};
  ASSERT_EQ(::stat(path("results.log").c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino) << "results.log was replaced";
  EXPECT_EQ(sh(run + " --json /dev/stdout > both.txt").rc, 0);
  EXPECT_EQ(slurp(path("both.txt")), walk + json);
  spit(path("err.log"), "earlier\n");
  EXPECT_EQ(testutil::run_command("cd " + path("") + " && " + run +
                                  " --quiet --json /dev/stderr 2>> err.log")
                .rc,
            0);
  EXPECT_EQ(slurp(path("err.log")), "earlier\n" + json);
  spit(path("fd3.log"), "three\n");
  EXPECT_EQ(sh(run + " --quiet --json /dev/fd/3 3>> fd3.log").rc, 0);
  EXPECT_EQ(slurp(path("fd3.log")), "three\n" + json);
  // The file behind standard output deleted (a rotated log): written to it, nothing made here.
  const testutil::CommandResult gone =
      sh("( exec > gone.txt; rm gone.txt; " + run + " --quiet --json /proc/self/fd/1 )");
  EXPECT_EQ(gone.rc, 0) << gone.out;
  EXPECT_EQ(gone.out, "");
  EXPECT_EQ(listing(), (std::vector<std::string>{"alone.json", "both.txt", "err.log", "fd3.log",
                                                 "results.log"}));
  // The bridge's live log: appended to, not truncated.
  spit(path("b.log"), "old bridge log\n");
  sh("timeout -s TERM 2 " + kCli + " bridge --tcp 0 --slave 5:DO4 --log /dev/stdout >> b.log");
  const std::string blog = slurp(path("b.log"));
  EXPECT_EQ(blog.rfind("old bridge log\ndpc31 bridge: ", 0), 0u) << blog;
}

// docs/bad-input.md "Output files": the replacement keeps the replaced file's permission bits (a
// file made private stays private), a hard link to it keeps the old bytes, the temporary's short
// name leaves every name the file system takes possible (255 bytes), and a name ending in '/' is
// one line (s29-sec, findings 7 and 8: 0600 became 0644; 245..255-byte names failed).
TEST_F(BadInput, AReplacedOutputKeepsItsModeAndAnyNameWorks) {
  spit(path("out.json"), "secret");
  ASSERT_EQ(::chmod(path("out.json").c_str(), 0600), 0);
  fs::create_hard_link(path("out.json"), path("link.json"));
  ASSERT_EQ(dpc31("run " + kScn + " --quiet --json out.json").rc, 0);
  struct stat st {};
  ASSERT_EQ(::stat(path("out.json").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(slurp(path("out.json")).substr(0, 1), "{");
  EXPECT_EQ(slurp(path("link.json")), "secret");  // rename: the other link keeps the old file
  const std::string longest = std::string(250, 'a') + ".json";
  const Outcome r = dpc31("run " + kScn + " --quiet --json " + longest);
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(slurp(path(longest)).substr(0, 1), "{");
  expect_bad(dpc31("run " + kScn + " --quiet --json new.json/"),
             "dpc31 run: new.json/: cannot write: a file name cannot end in '/'", "slash");
  EXPECT_EQ(listing(), (std::vector<std::string>{longest, "link.json", "out.json"}));
}

// docs/bridge.md: SIGTERM ends the bridge with exit 0 and removes its symlink, also while its
// --log FIFO has no reader yet and open() waits for one (s29-sec, finding 12: exit 2, `cannot
// write the log ...: Interrupted system call`).
TEST_F(BadInput, ASignalWhileTheLogFifoWaitsForItsReaderIsAStop) {
  ASSERT_EQ(::mkfifo(path("lf").c_str(), 0600), 0);
  const std::string err = (root_ / "io" / "err").string();
  const pid_t pid =
      spawn({kCli, "bridge", "--pty", path("dp"), "--firmware", "DO4", "--log", path("lf")},
            path(""), err);
  ASSERT_TRUE(eventually([&] { return fs::is_symlink(path("dp")); }));
  std::this_thread::sleep_for(
      std::chrono::milliseconds(300));  // into open(): nothing else shows it
  ::kill(pid, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status << " " << slurp(err);
  EXPECT_EQ(slurp(err), "");
  EXPECT_EQ(listing(), std::vector<std::string>{"lf"});
}

// A full file system: fstapi does not check its writes, so only the walk of what it wrote
// shows it. Exit 2, one line, the old file kept, no temporary left (finding 6). A small tmpfs
// mounted for the test (root; the suite runs as root in CI and here).
TEST_F(BadInput, FullFileSystemIsExit2AndKeepsTheOldFile) {
  if (::geteuid() != 0) GTEST_SKIP() << "mounting a tmpfs needs root";
  const std::string full = path("full");
  const SmallTmpfs tmpfs(full);
  ASSERT_EQ(tmpfs.error(), "");
  spit(full + "/old.fst", "old fst");
  spit(full + "/old.vcd", "old vcd");
  spit(full + "/old.json", "old json");
  spit(full + "/old.trace", "old trace");
  tmpfs.fill();  // what is left cannot hold a waveform of the whole run
  // The trace too, which is written as the run goes (s34-record).
  for (const auto& [opt, name] :
       {std::pair{"--fst", "old.fst"}, std::pair{"--vcd", "old.vcd"},
        std::pair{"--json", "old.json"}, std::pair{"--record", "old.trace"}}) {
    const Outcome r = dpc31("run " + kScn + " --quiet " + opt + " full/" + name);
    expect_bad_prefix(r, std::string("dpc31 run: full/") + name + ": cannot write", name);
  }
  EXPECT_EQ(slurp(full + "/old.fst"), "old fst");
  EXPECT_EQ(slurp(full + "/old.vcd"), "old vcd");
  EXPECT_EQ(slurp(full + "/old.json"), "old json");
  EXPECT_EQ(slurp(full + "/old.trace"), "old trace");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(full)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left,
            (std::vector<std::string>{"fill", "old.fst", "old.json", "old.trace", "old.vcd"}));
}

// Several outputs of one run are each whole or absent, written in a fixed order when the run is
// over: --record, the waveforms (--vcd, --fst, --la-vcd, each with its --gtkw), --pcap, --json
// (README "Command line", docs/bad-input.md "Output files"). A write that fails there is exit 2
// with its one line; the outputs before it are in place and whole, the failed one and those after
// it absent (the outside audit of s31: README said "no output file written" of every exit 2).
TEST_F(BadInput, SeveralOutputsAreEachWholeOrAbsentInTheirOrder) {
  const Outcome whole = dpc31("run " + kScn + " --quiet --vcd whole.vcd --record whole.trace");
  ASSERT_EQ(whole.rc, 0) << whole.err;
  const std::string vcd = slurp(path("whole.vcd"));
  const std::string trace = slurp(path("whole.trace"));
  fs::remove(path("whole.vcd"));
  fs::remove(path("whole.trace"));
  // The waveform, then the capture that fails: the waveform is kept whole, the JSON never made.
  Outcome r = dpc31("run " + kScn + " --quiet --vcd x.vcd --pcap /dev/full --json x.json");
  expect_bad_prefix(r, "dpc31 run: /dev/full: cannot write", "pcap after the vcd");
  EXPECT_EQ(listing(), std::vector<std::string>{"x.vcd"});
  EXPECT_EQ(slurp(path("x.vcd")), vcd);
  fs::remove(path("x.vcd"));
  // The waveform fails: the trace before it is kept, the capture after it is not written.
  r = dpc31("run " + kScn + " --quiet --record x.trace --vcd /dev/full --pcap x.pcapng");
  expect_bad_prefix(r, "dpc31 run: /dev/full: cannot write", "vcd after the trace");
  EXPECT_EQ(listing(), std::vector<std::string>{"x.trace"});
  EXPECT_EQ(slurp(path("x.trace")), trace);
  fs::remove(path("x.trace"));
  // Bad input found before the run writes nothing at all.
  r = dpc31("run " + kScn + " --quiet --record x.trace --vcd x.vcd --timescale 3ns");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(listing(), std::vector<std::string>{});
}

// The standard output is an output too: a write that fails is exit 2 with one line, whatever
// the command found (finding 6; wavediff found differences, exit 1 before the write). The bridge
// writes its log there and stops on the failed write with its own line, the only one (before,
// main() added "cannot write the standard output" as a second). Also where the output outgrows the
// stdio buffer, so that a write fails mid-way (the demo; a run with a walk of 12 KB): fmt's
// exception said "cannot write to file".
TEST_F(BadInput, AFailedWriteToTheStandardOutputIsExit2) {
  const std::string wave = std::string(SOURCE_DIR) + "/tests/data/wavediff/";
  const std::string full = ": cannot write the standard output: No space left on device";
  for (const auto& [args, want] : std::vector<std::pair<std::string, std::string>>{
           {"regs --profile dpc31", "dpc31 regs" + full},
           // CLI11's help and version through the same checked stream (s29-sec, finding 10).
           {"--version", "dpc31" + full},
           {"--help", "dpc31" + full},
           {"run --help", "dpc31 run" + full},
           {"regs --profile all --format c", "dpc31 regs" + full},
           {"run " + kScn, "dpc31 run" + full},
           {"replay " + kTraces + "gc_clear_spc3.trace", "dpc31 replay" + full},
           {"wavediff " + wave + "emu.vcd " + wave + "rtl.vcd", "dpc31 wavediff" + full},
           {"soak --cycles 2000000", "dpc31 soak" + full},
           {"demo --out-dir " + path("demo"), "dpc31 demo" + full},
           {"run " + kTraces + "do4_dpv1_c2_vpc3plus.scn", "dpc31 run" + full},
           {"bridge --tcp 0 --firmware DO4",
            "dpc31 bridge: cannot write the log to the standard output: No space left on "
            "device"}}) {
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult r =
        testutil::run_command(kCli + " " + args + " >/dev/full 2>" + err);
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(slurp(err), want + "\n") << args;
  }
  // The demo stopped where its write failed: none of its files was left half-written, nor the
  // directory it made for them.
  EXPECT_FALSE(fs::exists(path("demo")));
}

// A file-size limit (`ulimit -f`) ended the process with SIGXFSZ at the first write past it: no
// line, exit 153, the temporaries and the bridge's pty symlink left behind (the audit of
// 2026-12-05, run 21). dpc31 ignores the signal: the write fails with EFBIG and is reported as
// every failed write is. Its standard error is the pipe, which has no size limit.
TEST_F(BadInput, AFileSizeLimitIsAFailedWrite) {
  const std::string wave = std::string(SOURCE_DIR) + "/tests/data/wavediff/";
  const std::string too_large = ": File too large";
  const std::string out = (root_ / "io" / "out").string();
  struct Case {
    std::string args;
    std::string stdout_to;
    std::string want;
  };
  for (const Case& c :
       std::vector<Case>{{"run " + kScn + " --quiet --json o.json", "/dev/null",
                          "dpc31 run: o.json: cannot write" + too_large},
                         {"run " + kScn + " --quiet --vcd o.vcd", "/dev/null",
                          "dpc31 run: o.vcd: cannot write" + too_large},
                         {"run " + kScn + " --quiet --pcap o.pcapng", "/dev/null",
                          "dpc31 run: o.pcapng: cannot write" + too_large},
                         {"soak --cycles 2000000 --json o.json", "/dev/null",
                          "dpc31 soak: o.json: cannot write" + too_large},
                         {"wavediff " + wave + "emu.vcd " + wave + "rtl.vcd --json o.json",
                          "/dev/null", "o.json: cannot write" + too_large},  // its style: no prefix
                         {"regs --profile dpc31", out,
                          "dpc31 regs: cannot write the standard output" + too_large},
                         {"bridge --pty p --slave 5:DO4 --pacing free --log o.log --pcap o.pcapng",
                          "/dev/null", "dpc31 bridge: cannot write the log o.log" + too_large}}) {
    const testutil::CommandResult r =
        testutil::run_command("cd " + path("") + " && ulimit -f 0 && timeout 60 " + kCli + " " +
                              c.args + " 2>&1 >" + c.stdout_to);
    EXPECT_EQ(r.rc, 2) << c.args;
    EXPECT_EQ(r.out, c.want + "\n") << c.args;
  }
  // The bridge's log is live (docs/bridge.md), made before the run: the one file left, empty.
  EXPECT_EQ(listing(), std::vector<std::string>{"o.log"});
  EXPECT_EQ(slurp(path("o.log")), "");
}

// fstapi writes the value changes to scratch files in /tmp first and checks none of those writes:
// past a file-size limit (or on a full /tmp) it went on and assembled a well-formed FST of
// wrong values, exit 0 (the audit of s30, a-verif finding 1: `ulimit -f 16`, a 4.4 KB FST whose
// scratch files need more). Its fclose, gzclose and mmap are counted now (util/outfile/
// fst_hooks.h): exit 2, one line, no file, as docs/bad-input.md "Output files" says.
TEST_F(BadInput, AFailedScratchWriteOfTheFstWriterIsAFailedWrite) {
  const std::string scn = kTraces + "do4_osp_replace.scn";
  const std::string limited = "cd " + path("") + " && ulimit -f 16 && timeout 120 " + kCli + " ";
  testutil::CommandResult r =
      testutil::run_command(limited + "run --quiet " + scn + " --fst t.fst 2>&1 >/dev/null");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(r.out.starts_with("dpc31 run: t.fst: cannot write: ")) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_EQ(listing(), std::vector<std::string>{});
  // wavediff --merge's FST likewise (the inputs written first, without the limit).
  ASSERT_EQ(dpc31("run --quiet " + scn + " --vcd a.vcd").rc, 0);
  r = testutil::run_command(limited + "wavediff a.vcd a.vcd --merge m.fst 2>&1 >/dev/null");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_TRUE(r.out.starts_with("m.fst: cannot write: ")) << r.out;
  EXPECT_EQ(listing(), std::vector<std::string>{"a.vcd"});
  // Without the limit both are written and walk clean: the checks count no failure of their own.
  ASSERT_EQ(dpc31("run --quiet " + scn + " --fst t.fst").rc, 0);
  EXPECT_EQ(dpc31("wavediff a.vcd t.fst").rc, 0);
  ASSERT_EQ(dpc31("wavediff a.vcd a.vcd --merge m.fst").rc, 0);
}

// Verilator's FST tracer of `cosim --dump` mmap()ed a file it could not extend (`ulimit -f 4`):
// SIGBUS, exit 135, the summary lost and .dpc31-PID.tmp{,.hier} left (a-verif finding 2). The
// model traces in a child process now, its fstapi's mmap is checked: exit 2 after the summary,
// one line naming the file, nothing left: not d either, which the run made and did not fill.
TEST_F(BadInput, ACosimDumpPastAFileSizeLimitKeepsTheSummary) {
  const testutil::CommandResult r = testutil::run_command(
      "cd " + path("") + " && ulimit -f 4 && timeout 300 " + kCli +
      " cosim --seeds 1 --cycles 20000 --quiet --dump d 2>" + (root_ / "io" / "err").string());
  EXPECT_EQ(r.rc, 2);
  const std::string err = slurp((root_ / "io" / "err").string());
  EXPECT_TRUE(err.starts_with("dpc31 cosim: d/")) << err;  // the prefix: s31-serve, finding 8
  EXPECT_NE(err.find(": cannot write: "), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(r.out.find("\"divergent_seeds\": 0"), std::string::npos) << r.out;
  EXPECT_TRUE(listing().empty());
}

// docs/bad-input.md, "Output files": a signal in the middle of a cosim run removes the --dump
// directory it made and its parents that it made (empty: the dump comes after the seeds), and
// leaves the directory the user had.
TEST_F(BadInput, ASignalDuringACosimRemovesTheDirectoriesItMade) {
  fs::create_directory(path("have"));
  for (const int sig : {SIGINT, SIGTERM}) {
    const pid_t pid = spawn(
        {kCli, "cosim", "--seeds", "100000000", "--dump", "have/new/dump", "--quiet"}, path(""));
    ASSERT_GT(pid, 0);
    EXPECT_TRUE(eventually([&] { return fs::is_directory(path("have/new/dump")); })) << sig;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ASSERT_EQ(::kill(pid, sig), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << sig << " status " << status;
    EXPECT_EQ(listing(), std::vector<std::string>{"have"}) << sig;
    EXPECT_TRUE(fs::is_empty(path("have"))) << sig;
  }
}

// A standard output whose reader has gone (`| head -1`): SIGPIPE ended the process silently, the
// bridge leaving its pty symlink and the capture's temporary (audit a13, finding 2). dpc31 ignores
// the signal: the write fails with EPIPE and takes the path of every failed write. The pipe's read
// end is closed before the command starts, so its first write fails, whatever the timing.
TEST_F(BadInput, AClosedPipeIsAFailedWrite) {
  const std::string broken = ": Broken pipe";
  for (const auto& [args, want] : std::vector<std::pair<std::string, std::string>>{
           {"bridge --pty p --firmware DO4 --pacing free --pcap o.pcapng",
            "dpc31 bridge: cannot write the log to the standard output" + broken},
           {"serve --unix s", "dpc31 serve: cannot write the standard output" + broken},
           {"run " + kScn, "dpc31 run: cannot write the standard output" + broken},
           {"regs --profile dpc31", "dpc31 regs: cannot write the standard output" + broken},
           {"replay " + kTraces + "gc_clear_spc3.trace",
            "dpc31 replay: cannot write the standard output" + broken}}) {
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    ::close(fds[0]);
    std::vector<std::string> argv = {kCli};
    std::istringstream words(args);
    for (std::string w; words >> w;) argv.push_back(w);
    std::vector<char*> cargv;
    for (std::string& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    const std::string err = (root_ / "io" / "err").string();
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addchdir_np(&fa, path("").c_str());
    // The default action of SIGPIPE, as a shell gives a pipeline's command.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t pipe_signal;
    sigemptyset(&pipe_signal);
    sigaddset(&pipe_signal, SIGPIPE);
    posix_spawnattr_setsigdefault(&attr, &pipe_signal);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
    pid_t pid = -1;
    ASSERT_EQ(::posix_spawn(&pid, cargv[0], &fa, &attr, cargv.data(), environ), 0);
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << args << ": ended by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 2) << args;
    EXPECT_EQ(slurp(err), want + "\n") << args;
    // No pty symlink, no capture or its temporary, no socket.
    EXPECT_EQ(listing(), std::vector<std::string>{}) << args;
  }
}

// The running program is an input of every command: `bridge --pcap build/bin/dpc31` renamed its
// capture over the program (the audit of 2026-12-05, run 21). A copy of it here, run as ./dpc31:
// refused before anything runs by distinct() (OutFile::open() refuses it too, for a library's
// caller).
TEST_F(BadInput, TheRunningProgramIsNeverAnOutput) {
  const std::string exe = copy(kCli, "dpc31");
  const std::string bytes = slurp(exe);
  const std::string is_it = ": is the running program " + fs::canonical(exe).string();
  for (const auto& [args, want] : std::vector<std::pair<std::string, std::string>>{
           {"bridge --tcp 0 --slave 5:DO4 --pcap dpc31",
            "dpc31 bridge: --pcap dpc31" + is_it + ": an output must not replace an input"},
           {"bridge --pty p --slave 5:DO4 --log ./dpc31",
            "dpc31 bridge: --log ./dpc31" + is_it + ": an output must not replace an input"},
           {"run " + kScn + " --quiet --json " + exe,
            "dpc31 run: --json " + exe + is_it + ": an output must not replace an input"},
           {"soak --cycles 1000 --json dpc31",
            "dpc31 soak: --json dpc31" + is_it + ": an output must not replace an input"},
           {"bench --bench /bin/true --json dpc31",
            "dpc31 bench: --json dpc31" + is_it + ": an output must not replace an input"}}) {
    const testutil::CommandResult r = testutil::run_command(
        "cd " + path("") + " && timeout 60 ./dpc31 " + args + " 2>&1 >/dev/null");
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(r.out, want + "\n") << args;
  }
  EXPECT_EQ(slurp(exe), bytes);
  EXPECT_EQ(listing(), std::vector<std::string>{"dpc31"});
}

// An output that names an input, or another output, is refused before any work: the scenario,
// waveform B and the first output stay as they were (finding 6).
TEST_F(BadInput, AnOutputThatNamesAnInputOrAnotherOutputIsRefused) {
  const std::string scn = copy(kScn, "s.scn");
  const std::string text = slurp(scn);
  expect_bad(dpc31("run s.scn --json s.scn"),
             "dpc31 run: --json s.scn: is the scenario s.scn: an output must not replace an input",
             "json = scenario");
  expect_bad(dpc31("run s.scn --quiet --vcd ./s.scn"),
             "dpc31 run: --vcd ./s.scn: is the scenario s.scn: an output must not replace an "
             "input",
             "another spelling");
  fs::create_hard_link(scn, path("hard.scn"));
  expect_bad_prefix(dpc31("run s.scn --quiet --record hard.scn"),
                    "dpc31 run: --record hard.scn: is the scenario s.scn", "hard link");
  EXPECT_EQ(slurp(scn), text);
  spit(path("x"), "old");
  expect_bad(dpc31("run s.scn --quiet --vcd x --fst x"),
             "dpc31 run: --vcd x and --fst x are the same file: each output needs its own",
             "two outputs, one file");
  expect_bad(dpc31("run s.scn --quiet --vcd new.vcd --pcap " + path("new.vcd")),
             "dpc31 run: --vcd new.vcd and --pcap " + path("new.vcd") +
                 " are the same file: each output needs its own",
             "two outputs, a file to be");
  EXPECT_EQ(slurp(path("x")), "old");
  // wavediff: --diff-vcd B would overwrite the file compared.
  copy(kTraces + "../tests/data/wavediff/emu.vcd", "a.vcd");
  copy(kTraces + "../tests/data/wavediff/rtl.vcd", "b.vcd");
  const std::string b_text = slurp(path("b.vcd"));
  expect_bad(dpc31("wavediff a.vcd b.vcd --diff-vcd b.vcd"),
             "dpc31 wavediff: --diff-vcd b.vcd: is B b.vcd: an output must not replace an input",
             "diff-vcd = B");
  expect_bad(dpc31("wavediff a.vcd b.vcd --json r.json --wavedrom r.json"),
             "dpc31 wavediff: --json r.json and --wavedrom r.json are the same file: each output "
             "needs its own",
             "json = wavedrom");
  EXPECT_EQ(slurp(path("b.vcd")), b_text);
  EXPECT_FALSE(fs::exists(path("new.vcd")));
  EXPECT_FALSE(fs::exists(path("r.json")));
}

// docs/security.md "Outputs never destroy what is there": no output replaces what a scenario
// reads, its `cpu` line's image and the SDCC map beside it included (`dpc31 run`, `cosim
// --session`), nor a plug-in through a link in `demo --out-dir` (s29-sec, finding 2: each was
// written over, exit 0). The image: LJMP 000Bh, its checksum F0h, and the end record.
TEST_F(BadInput, AnOutputNeverReplacesWhatTheScenarioReads) {
  const std::string image = ":0300000002000BF0\n:00000001FF\n";
  file("fw.ihx", image);
  file("fw.map", "the map\n");
  file("s.scn", "profile spc3\ncpu 80c32 firmware fw.ihx\nstartup\n");
  file("c.scn", "profile dpc31\ncpu c31 firmware fw.ihx code=0x1000\nstartup\n");
  const std::string is_image = ": is the `cpu 80c32` image " + path("fw.ihx") + refused_words();
  expect_bad(dpc31("run s.scn --quiet --json fw.ihx"), "dpc31 run: --json fw.ihx" + is_image,
             "json");
  expect_bad(dpc31("run s.scn --quiet --record ./fw.ihx"),
             "dpc31 run: --record ./fw.ihx" + is_image, "record");
  expect_bad(dpc31("run s.scn --quiet --vcd fw.map"),
             "dpc31 run: --vcd fw.map: is the SDCC map " + path("fw.map") + refused_words(), "map");
  expect_bad(dpc31("run c.scn --quiet --pcap fw.ihx"),
             "dpc31 run: --pcap fw.ihx: is the `cpu c31` image " + path("fw.ihx") + refused_words(),
             "c31");
  expect_bad(dpc31("cosim --session s.scn --junit fw.ihx"),
             "dpc31 cosim: --junit fw.ihx" + is_image, "cosim --session");
  EXPECT_EQ(slurp(path("fw.ihx")), image);
  EXPECT_EQ(slurp(path("fw.map")), "the map\n");
  // demo: its capture in --out-dir is a link to the plug-in; refused before it is loaded.
  const std::string plugin = copy(BAD_PLUGIN_MARK, "fw.so");
  const std::string bytes = slurp(plugin);
  fs::create_directory(path("out"));
  fs::create_symlink("../fw.so", path("out/dpc31-demo.pcapng"));
  expect_bad(dpc31("demo --firmware ./fw.so --out-dir out", "DPC31_PLUGIN_MARK=" + path("mark")),
             "dpc31 demo: --out-dir out/dpc31-demo.pcapng: is --firmware ./fw.so" + refused_words(),
             "demo");
  EXPECT_EQ(slurp(plugin), bytes);
  EXPECT_FALSE(fs::exists(path("mark"))) << "the plug-in was loaded";
}

// A long run (10^6 exchanges at 12 Mbaud, about 40 s of chip time): long enough to be signalled.
std::string long_scenario() {
  return "profile spc3\nbaud 12000000\nmaster address=1\n"
         "slave address=12 ident=0x8031 cfg=11,21 in=2 out=2\nuser inputs=C0,DE\n"
         "startup\nexchange 1000000 outputs=5A,A5\n";
}

bool any_ending(const fs::path& dir, const std::string& suffix) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (n.size() >= suffix.size() &&
        n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0)
      return true;
  }
  return false;
}

// Runs `argv` in `work`, waits until an output's temporary is there (each is, from the start of
// the run), sends `sig` 200 ms later, and expects the process to end by it.
void expect_ended_by_signal(const std::vector<std::string>& argv, const fs::path& work, int sig) {
  const pid_t pid = spawn(argv, work.string());
  ASSERT_GT(pid, 0);
  EXPECT_TRUE(eventually([&] { return any_ending(work, ".tmp"); })) << sig;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_EQ(::kill(pid, sig), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << sig << " status " << status;
}

// SIGINT, SIGTERM or SIGHUP in the middle of a run: the process still ends by the signal, and
// no temporary of its outputs is left (finding 7).
TEST_F(BadInput, ASignalDuringARunLeavesNoTemporary) {
  spit(path("long.scn"), long_scenario());
  spit(path("old.vcd"), "old");
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    expect_ended_by_signal(
        {kCli, "run", "long.scn", "--quiet", "--json", "r.json", "--vcd", "old.vcd", "--fst",
         "r.fst", "--pcap", "r.pcapng", "--record", "r.trace"},
        root_ / "work", sig);
    EXPECT_EQ(listing(), (std::vector<std::string>{"long.scn", "old.vcd"})) << sig;
    EXPECT_EQ(slurp(path("old.vcd")), "old");
  }
}

// The same for a soak (docs/soak.md): the JSON report's temporary goes, an old report stays as it
// was, and nothing of the report was printed (it is printed at the end only).
TEST_F(BadInput, ASignalDuringASoakLeavesNoReport) {
  spit(path("old.json"), "old");
  for (const int sig : {SIGINT, SIGTERM}) {
    expect_ended_by_signal(
        {"/bin/sh", "-c", "exec " + kCli + " soak --cycles 1e12 --json old.json >out"},
        root_ / "work", sig);
    EXPECT_EQ(listing(), (std::vector<std::string>{"old.json", "out"})) << sig;
    EXPECT_EQ(slurp(path("old.json")), "old");
    EXPECT_EQ(slurp(path("out")), "") << sig;
  }
}

// --- demo (finding 4) ------------------------------------------------------------------------

// A TMPDIR/dpc31-demo made beforehand by someone else (a directory, or a link to one) is not
// used: the demo writes into a new directory of its own, mode 0700.
TEST_F(BadInput, DemoUsesAFreshPrivateDirectory) {
  const std::string tmp = path("tmp");
  fs::create_directory(tmp);
  fs::create_directory(path("elsewhere"));
  fs::create_directory_symlink(path("elsewhere"), tmp + "/dpc31-demo");
  ASSERT_EQ(::chown(path("elsewhere").c_str(), 65534, 65534), ::geteuid() == 0 ? 0 : -1);
  const testutil::CommandResult r =
      testutil::run_command("TMPDIR=" + tmp + " " + kCli + " demo 2>/dev/null");
  ASSERT_EQ(r.rc, 0);
  const std::string key = "waveform (VCD): ";
  const auto at = r.out.find(key);
  ASSERT_NE(at, std::string::npos);
  const fs::path vcd = r.out.substr(at + key.size(), r.out.find('\n', at) - at - key.size());
  const fs::path dir = vcd.parent_path();
  EXPECT_EQ(dir.parent_path(), fs::path(tmp));
  EXPECT_EQ(dir.filename().string().rfind("dpc31-demo-", 0), 0u) << dir;
  EXPECT_EQ(dir.filename().string().size(), std::string("dpc31-demo-XXXXXX").size()) << dir;
  EXPECT_TRUE(fs::is_regular_file(vcd));
  EXPECT_TRUE(fs::is_regular_file(dir / "dpc31-demo.pcapng"));
  struct stat st {};
  ASSERT_EQ(::lstat(dir.c_str(), &st), 0);
  EXPECT_TRUE(S_ISDIR(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  EXPECT_TRUE(fs::is_empty(path("elsewhere")));
  // A second run: another new directory.
  const testutil::CommandResult again =
      testutil::run_command("TMPDIR=" + tmp + " " + kCli + " demo 2>/dev/null");
  EXPECT_EQ(again.rc, 0);
  EXPECT_EQ(again.out.find(vcd.string()), std::string::npos);
}

// --- numbers (finding 9) ---------------------------------------------------------------------

// Every numeric option refuses NaN, the infinities, values that overflow its type and values
// outside its range: one line, exit 2, nothing run.
TEST_F(BadInput, NumbersAreFiniteAndInRangeEverywhere) {
  const std::string scn = copy(kScn, "s.scn");
  const std::vector<std::string> cases = {
      // dpc31 soak: NaN ran forever (--cycles) or was undefined behaviour (--fault-period).
      "soak --cycles nan", "soak --cycles inf", "soak --cycles -inf", "soak --cycles 1e400",
      "soak --fault-period nan", "soak --fault-period 0x10", "soak --seed 18446744073709551616",
      "soak --seed 99999999999999999999999", "soak --seed -1", "soak --seed 1.5",
      // dpc31 run
      "run s.scn --from nan", "run s.scn --to 18446744073709551616", "run s.scn --from -1",
      "run s.scn --to 1e3",
      // dpc31 cosim
      "cosim --seeds nan", "cosim --seeds 0", "cosim --seeds 100000001",
      "cosim --seed-base 18446744073709551616", "cosim --cycles inf", "cosim --window -5",
      // dpc31 wavediff
      "wavediff a b --tolerance-cycles nan", "wavediff a b --wavedrom-window 0",
      "wavediff a b --max-signals 4294967296",
      // dpc31 bench
      "bench --min-time nan", "bench --min-time inf", "bench --repetitions 1e2",
      "bench --wavediff-mb 18446744073709551616",
      // dpc31 serve
      "serve --idle-timeout nan", "serve --idle-timeout inf", "serve --max-clients 1e5"};
  const auto before = listing();
  for (const std::string& args : cases) {
    const Outcome r = dpc31(args);
    expect_bad_prefix(r, "dpc31 " + args.substr(0, args.find(' ')) + ": ", args);
    EXPECT_EQ(r.out, "") << args;
  }
  EXPECT_EQ(listing(), before);
}

// A stimulus trace of a few bytes that claims a huge run: refused with FILE:LINE, not a
// multi-gigabyte allocation or std::bad_alloc (the bound of --cycles and of the cycle lines).
TEST_F(BadInput, CosimReplayRefusesARunLongerThanTheBound) {
  file("huge.trace", "end 99999999999999\n");
  expect_bad(dpc31("cosim --replay " + path("huge.trace") + " --quiet"),
             path("huge.trace") + ":1: 'end' beyond 100000000 cycles", "end");
  file("far.trace", "100000001 rst\nend 100000002\n");
  expect_bad(dpc31("cosim --replay " + path("far.trace") + " --quiet"),
             path("far.trace") + ":1: cycle beyond 100000000", "cycle");
}

// Reading a text input allocates what the file holds, not the size cap (256 MB for /dev/null
// before): with 200 MB of address space the empty scenario is still just empty.
TEST_F(BadInput, TextInputsDoNotPreallocateTheirCap) {
#if defined(__SANITIZE_ADDRESS__)
  // ASan reserves terabytes of shadow address space at start-up: no ulimit -v build can run.
  GTEST_SKIP() << "an address-space limit cannot hold an AddressSanitizer binary";
#endif
  const testutil::CommandResult r =
      testutil::run_command("(ulimit -v 200000; " + kCli + " run /dev/null) 2>&1");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, "/dev/null: no commands: nothing to run\n");
}

// Each waveform is opened once: a pipe (bash's <(cat ...)) is read like the file (finding 9).
TEST_F(BadInput, WavediffReadsAPipeLikeTheFile) {
  const std::string a = kTraces + "../tests/data/wavediff/emu.vcd";
  for (const std::string& cmd :
       std::vector<std::string>{kCli + " wavediff " + a + " <(cat " + a + ")",
                                kCli + " wavediff <(cat " + a + ") " + a}) {
    const testutil::CommandResult r = testutil::run_command("bash -c '" + cmd + "' 2>&1");
    EXPECT_EQ(r.rc, 0) << cmd << "\n" << r.out;
  }
  // An FST through a pipe too (fstapi seeks: it is buffered in memory first).
  ASSERT_EQ(dpc31("run " + kScn + " --quiet --fst w.fst").rc, 0);
  const std::string fst = path("w.fst");
  const testutil::CommandResult r =
      testutil::run_command("bash -c '" + kCli + " wavediff " + fst + " <(cat " + fst + ")' 2>&1");
  EXPECT_EQ(r.rc, 0) << r.out;
}

// `dpc31 run` reads its scenario once (docs/scenario-format.md): a pipe, /dev/stdin and a FIFO
// play as the file does, a segment's scenario too, and --record heads its trace with the piped
// text's comments. It opened the file again to parse it: "/dev/fd/63: no commands: nothing to
// run", exit 2, and a FIFO waited for a second writer.
TEST_F(BadInput, RunReadsAPipeOrAFifoLikeTheFile) {
  ASSERT_EQ(dpc31("run " + kScn + " --quiet --record file.trace").rc, 0);
  const std::string segment = kTraces + "segment/three_slaves.scn";
  for (const std::string& cmd : std::vector<std::string>{
           "bash -c '" + kCli + " run <(cat " + kScn + ") --quiet --record pipe.trace'",
           "cat " + kScn + " | " + kCli + " run /dev/stdin --quiet",
           "bash -c '" + kCli + " run <(cat " + segment + ") --quiet'",
           "mkfifo fifo && { cat " + kScn + " > fifo & timeout 10 " + kCli +
               " run fifo --quiet; rc=$?; wait; exit $rc; }"}) {
    const testutil::CommandResult r =
        testutil::run_command("cd " + (root_ / "work").string() + " && " + cmd + " 2>&1");
    EXPECT_EQ(r.rc, 0) << cmd << "\n" << r.out;
  }
  // The piped file's trace is the file's, but for the name in its "recorded ... from" line.
  const std::string file = slurp(path("file.trace"));
  const std::string pipe = slurp(path("pipe.trace"));
  const std::size_t f = file.find("# recorded by");
  const std::size_t p = pipe.find("# recorded by");
  ASSERT_NE(f, std::string::npos);
  ASSERT_NE(p, std::string::npos);
  EXPECT_EQ(pipe.substr(0, p), file.substr(0, f));
  EXPECT_EQ(pipe.substr(pipe.find('\n', p)), file.substr(file.find('\n', f)));
}

}  // namespace
