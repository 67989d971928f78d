// Issue 29 (security, round three), each finding attacked and refused (docs/security.md, "Code a
// command runs" and "Outputs"): plug-ins a scenario names load only before the run and only when
// no other user could have changed them; outputs never replace an input nor follow another user's
// link in a sticky directory; the bridge's log. "Another user" is uid 65534 (nobody): the suite
// runs as root (CI and here), which may chown files to it; these tests skip as any other user.
#include <sys/stat.h>

#include "bad_input.hpp"

namespace {

using namespace badinput;

constexpr uid_t kNobody = 65534;

class CodeSecurity : public BadInput {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "files of another user need root (chown)";
    BadInput::SetUp();
    mark_ = (root_ / "io" / "mark").string();
  }
  // The command with DPC31_PLUGIN_MARK set: the MARK plug-in creates `mark_` when it is loaded.
  Outcome marked(const std::string& args) const {
    fs::remove(mark_);
    const std::string out = (root_ / "io" / "out").string();
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult r =
        testutil::run_command("cd " + (root_ / "work").string() + " && DPC31_PLUGIN_MARK=" + mark_ +
                              " " + kCli + " " + args + " >" + out + " 2>" + err);
    return {r.rc, slurp(out), slurp(err)};
  }
  [[nodiscard]] bool loaded() const { return fs::exists(mark_); }

  std::string mark_;
};

void chown_to(const std::string& p, uid_t uid) { ASSERT_EQ(::lchown(p.c_str(), uid, uid), 0) << p; }

// Finding 1: `firmware ./x.so` loaded the library while the file was parsed, before any check,
// even when a later line was a syntax error. Now: the whole file parses first, the command checks
// its outputs, and only then is the plug-in loaded.
TEST_F(CodeSecurity, AScenarioLoadsNoPluginWhileParsing) {
  copy(BAD_PLUGIN_MARK, "mark.so");
  const std::string mark_bytes = slurp(path("mark.so"));
  file("bad.scn", "firmware ./mark.so\nstartup\nno_such_command\n");
  expect_bad_prefix(marked("run bad.scn"), "bad.scn:3: ", "syntax error");
  EXPECT_FALSE(loaded()) << "run: parsed a broken file and loaded its plug-in";
  expect_bad_prefix(marked("cosim --session bad.scn"), "bad.scn:3: ", "cosim --session");
  EXPECT_FALSE(loaded()) << "cosim --session";
  file("ok.scn", "firmware ./mark.so\nstartup\n");
  // An output naming the plug-in is refused before it is loaded, and leaves it as it was.
  expect_bad(marked("run ok.scn --json mark.so"),
             "dpc31 run: --json mark.so: is the firmware plug-in " + path("mark.so") +
                 ": an output must not replace an input",
             "--json over the plug-in");
  EXPECT_FALSE(loaded());
  EXPECT_EQ(slurp(path("mark.so")), mark_bytes);
  // With nothing wrong it is loaded (the mark shows that the test can see a load).
  marked("run ok.scn --quiet");
  EXPECT_TRUE(loaded());
}

// Finding 1: plug-ins were loaded from files and directories other users can write. Refused: a
// plug-in of another user (0777 in a sticky directory, the case), one writable by others,
// one in a directory of another user or writable by its group; from every door that loads one
// (run's scenario header, cosim --session, bridge, soak, demo).
TEST_F(CodeSecurity, PluginsAnotherUserCouldChangeAreRefused) {
  fs::create_directory(path("sticky"));
  fs::permissions(path("sticky"), fs::perms::all | fs::perms::sticky_bit);
  const std::string theirs = copy(BAD_PLUGIN_MARK, "sticky/theirs.so");
  fs::permissions(theirs, fs::perms::all);
  chown_to(theirs, kNobody);
  const std::string open = copy(BAD_PLUGIN_MARK, "open.so");
  fs::permissions(open, fs::perms::all);  // 0777, ours
  fs::create_directory(path("their_dir"));
  chown_to(path("their_dir"), kNobody);
  copy(BAD_PLUGIN_MARK, "their_dir/fw.so");
  fs::create_directory(path("group_dir"));
  fs::permissions(path("group_dir"), fs::perms::group_write, fs::perm_options::add);
  copy(BAD_PLUGIN_MARK, "group_dir/fw.so");
  const std::string refused = "firmware plug-in refused: ";
  const std::string why = " (a plug-in runs as your code: another user could have changed it)";
  // The problem with each plug-in, as named by `name` (the command line's ./x, a scenario's
  // absolute path).
  const auto problem = [&](const std::string& rel, const std::string& name) {
    if (rel == "sticky/theirs.so")
      return name + " is owned by uid 65534, not by you (uid 0) or root";
    if (rel == "open.so") return name + " is writable by others (mode 0777)";
    if (rel == "their_dir/fw.so") {
      return name + ": the directory " + path("their_dir") +
             " is owned by uid 65534, not by you (uid 0) or root";
    }
    return name + ": the directory " + path("group_dir") + " is writable by its group (mode 0775)";
  };
  for (const std::string rel :
       {"sticky/theirs.so", "open.so", "their_dir/fw.so", "group_dir/fw.so"}) {
    const std::string line = refused + problem(rel, "./" + rel) + why;
    expect_bad(marked("bridge --pty p --firmware ./" + rel), "dpc31 bridge: " + line, rel);
    expect_bad(marked("soak --cycles 1000 --firmware ./" + rel), "dpc31 soak: " + line, rel);
    expect_bad_prefix(marked("demo --firmware ./" + rel), "dpc31 demo: ", rel);
    file("p.scn", "firmware ./" + rel + "\nstartup\n");
    const std::string in_scn = "p.scn:1: " + refused + problem(rel, path(rel)) + why;
    expect_bad(marked("run p.scn"), in_scn, rel);
    expect_bad(marked("cosim --session p.scn"), in_scn, rel);
    EXPECT_FALSE(loaded()) << rel;
  }
  // A scenario naming a plug-in is code too: one another user could have changed is refused
  // before the plug-in it names (ours, trusted) is loaded.
  copy(BAD_PLUGIN_MARK, "ours.so");
  const std::string theirs_scn = file("theirs.scn", "firmware ./ours.so\nstartup\n");
  chown_to(theirs_scn, kNobody);
  const std::string scn_why =
      "theirs.scn:1: firmware plug-in refused: the scenario names it, and "
      "another user could have changed the scenario: ";
  expect_bad(marked("run theirs.scn"),
             scn_why + "theirs.scn is owned by uid 65534, not by you (uid 0) or root", "scn owner");
  expect_bad(marked("cosim --session theirs.scn"),
             scn_why + "theirs.scn is owned by uid 65534, not by you (uid 0) or root", "cosim");
  fs::create_directory(path("open_dir"));
  fs::permissions(path("open_dir"), fs::perms::all);
  file("open_dir/s.scn", "firmware ../ours.so\nstartup\n");
  expect_bad(marked("run open_dir/s.scn"),
             "open_dir/s.scn:1: firmware plug-in refused: the scenario names it, and another user "
             "could have changed the scenario: open_dir/s.scn: the directory " +
                 path("open_dir") + " is writable by others (mode 0777)",
             "scn directory");
  EXPECT_FALSE(loaded());
  // Ours (root's), not writable by others, in the sticky directory: others cannot rename or
  // remove it there, so it is taken, as the kernel's sticky rule would have it.
  copy(BAD_PLUGIN_MARK, "sticky/ours.so");
  file("p.scn", "firmware ./sticky/ours.so\nstartup\n");
  marked("run p.scn --quiet");
  EXPECT_TRUE(loaded());
}

// Issue 30: a segment station's plug-in (`station 5 firmware=./x.so`) takes the single chip's
// door: never loaded while parsing, refused when an output names it, when another user could have
// changed it or the scenario, relative to the scenario's real file; and with nothing wrong it runs
// beside a built-in firmware to Data_Exchange (`dpc31 run`).
TEST_F(CodeSecurity, ASegmentStationsPluginTakesTheSameChecks) {
  copy(BAD_PLUGIN_MARK, "mark.so");
  const std::string head = "segment\nstation 5 profile=spc3 firmware=./mark.so\n";
  file("bad.scn", head + "startup\nno_such_command\n");
  expect_bad(marked("run bad.scn"), "bad.scn:4: unknown command 'no_such_command'", "syntax");
  EXPECT_FALSE(loaded()) << "parsed a broken segment and loaded its plug-in";
  file("ok.scn", head + "run 1ms\n");
  expect_bad(marked("run ok.scn --pcap mark.so"),
             "dpc31 run: --pcap mark.so: is the firmware plug-in " + path("mark.so") +
                 ": an output must not replace an input",
             "--pcap over the plug-in");
  EXPECT_FALSE(loaded());
  const std::string open = copy(BAD_PLUGIN_MARK, "open.so");
  fs::permissions(open, fs::perms::all);
  file("open.scn", "segment\nstation 4\nstation 5 firmware=./open.so\nrun 1ms\n");
  expect_bad(marked("run open.scn"),
             "open.scn:3: firmware plug-in refused: " + path("open.so") +
                 " is writable by others (mode 0777) (a plug-in runs as your code: another user "
                 "could have changed it)",
             "0777 plug-in");
  const std::string theirs = file("theirs.scn", head + "run 1ms\n");
  chown_to(theirs, kNobody);
  expect_bad(
      marked("run theirs.scn"),
      "theirs.scn:2: firmware plug-in refused: the scenario names it, and another user could "
      "have changed the scenario: theirs.scn is owned by uid 65534, not by you (uid 0) or "
      "root",
      "their scenario");
  EXPECT_FALSE(loaded());
  marked("run ok.scn --quiet");
  EXPECT_TRUE(loaded());
  // DO4 as a plug-in on the SPC3 beside the built-in CNT2 on the VPC3+, through a link to the
  // scenario (the plug-in is the one beside the real file).
  fs::create_directory(path("real"));
  copy(PLUGIN_DO4, "real/do4.so");
  file("real/s.scn",
       "segment\nstation 5 profile=spc3 firmware=./do4.so\n"
       "station 6 profile=vpc3plus firmware=CNT2\nstartup\ncycle 2\n"
       "expect state 5 Data_Exchange wd=DP_Control\nexpect state 6 Data_Exchange wd=DP_Control\n"
       "expect tsdr 11\n");
  fs::create_symlink("real/s.scn", path("s.scn"));
  const Outcome r = marked("run s.scn");
  EXPECT_EQ(r.rc, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("3 expects passed, 0 failed"), std::string::npos) << r.out;
}

// A scenario read from a named FIFO is judged as a file is: another user's, or one others may
// write to, could feed any plug-in's name. An anonymous pipe (`cat s.scn | run /dev/stdin`, `run
// <(cat s.scn)`) has no path: it is the piping user's own.
TEST_F(CodeSecurity, AScenarioFromANamedFifoIsJudgedAsAFile) {
  copy(BAD_PLUGIN_MARK, "ours.so");
  file("ok.scn", "firmware " + path("ours.so") + "\nstartup\n");
  ASSERT_EQ(::mkfifo(path("s.fifo").c_str(), 0600), 0);
  // `dpc31 run` reads the FIFO while a writer (ended after 20 s if nobody reads) feeds it.
  const auto fed = [&](const std::string& feed, const std::string& scenario) {
    fs::remove(mark_);
    const std::string cmd = "cd " + (root_ / "work").string() + " && " + feed +
                            " DPC31_PLUGIN_MARK=" + mark_ + " " + kCli + " run " + scenario +
                            " --quiet >" + (root_ / "io" / "out").string() + " 2>" +
                            (root_ / "io" / "err").string();
    const int rc = testutil::run_command(cmd).rc;
    return Outcome{rc, slurp((root_ / "io" / "out").string()),
                   slurp((root_ / "io" / "err").string())};
  };
  const std::string writer = "(timeout 20 sh -c 'cat ok.scn > s.fifo' >/dev/null 2>&1 &) &&";
  const Outcome ours = fed(writer, "s.fifo");
  EXPECT_EQ(ours.rc, 0) << ours.err;
  EXPECT_TRUE(loaded()) << "a FIFO of ours, mode 0600";
  fs::permissions(path("s.fifo"), fs::perms::others_write, fs::perm_options::add);
  expect_bad(fed(writer, "s.fifo"),
             "s.fifo:1: firmware plug-in refused: the scenario names it, and another user could "
             "have changed the scenario: s.fifo is writable by others (mode 0602)",
             "a FIFO others may write to");
  EXPECT_FALSE(loaded());
  fs::permissions(path("s.fifo"), fs::perms::others_write, fs::perm_options::remove);
  chown_to(path("s.fifo"), kNobody);
  expect_bad(fed(writer, "s.fifo"),
             "s.fifo:1: firmware plug-in refused: the scenario names it, and another user could "
             "have changed the scenario: s.fifo is owned by uid 65534, not by you (uid 0) or root",
             "another user's FIFO");
  EXPECT_FALSE(loaded());
  const Outcome piped = fed("cat ok.scn |", "/dev/stdin");
  EXPECT_EQ(piped.rc, 0) << piped.err;
  EXPECT_TRUE(loaded()) << "an anonymous pipe";
}

// Finding 1: a scenario reached through a symlink loaded `./fw.so` from the link's directory (a
// directory the link's maker chose). A relative plug-in path is now relative to the scenario's
// real file.
TEST_F(CodeSecurity, AScenarioThroughALinkLoadsThePluginBesideTheRealFile) {
  fs::create_directory(path("real"));
  copy(PLUGIN_DO4, "real/fw.so");
  file("real/s.scn", "firmware ./fw.so\nstartup\n");
  fs::create_directory(path("elsewhere"));
  copy(BAD_PLUGIN_MARK, "elsewhere/fw.so");
  fs::create_symlink("../real/s.scn", path("elsewhere/s.scn"));
  const Outcome r = marked("run elsewhere/s.scn --quiet");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(loaded()) << "the plug-in beside the link was loaded";
}

// Finding 4: an output naming an input silently replaced it. Every output is now compared with
// every input by device and inode: the plug-in of soak and bridge, cosim merge's summaries,
// cosim's replayed trace.
TEST_F(CodeSecurity, OutputsNeverReplaceAnInput) {
  const std::string fw = copy(PLUGIN_DO4, "fw.so");
  const std::string fw_bytes = slurp(fw);
  expect_bad(dpc31("soak --cycles 1000 --firmware ./fw.so --json ./fw.so"),
             "dpc31 soak: --json ./fw.so: is --firmware ./fw.so: an output must not replace an "
             "input",
             "soak");
  // The bridge truncated the mapped plug-in and died of SIGBUS.
  expect_bad(dpc31("bridge --pty p --firmware ./fw.so --log fw.so"),
             "dpc31 bridge: --log fw.so: is --firmware ./fw.so: an output must not replace an "
             "input",
             "bridge");
  EXPECT_EQ(slurp(fw), fw_bytes);
  const std::string a = file("a.json", "{}\n");
  expect_bad(dpc31("cosim merge a.json --junit ./a.json"),
             "dpc31 cosim merge: --junit ./a.json: is the summary a.json: an output must not "
             "replace an input",
             "merge");
  EXPECT_EQ(slurp(a), "{}\n");
  const std::string t = file("t", "end 10\n");
  expect_bad(dpc31("cosim --replay t --junit t"),
             "dpc31 cosim: --junit t: is --replay t: an output must not replace an input",
             "replay");
  EXPECT_EQ(slurp(t), "end 10\n");
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.json", "fw.so", "t"}));
}

// Finding 4: an output path that is another user's symlink in a sticky directory was followed
// (a file only root may write was overwritten). The kernel's protected_symlinks rule is applied
// by the writer itself, whatever the machine's setting: such a link is not followed; our own link
// there still is.
TEST_F(CodeSecurity, AnotherUsersSymlinkInAStickyDirectoryIsNotFollowed) {
  fs::create_directory(path("sticky"));
  fs::permissions(path("sticky"), fs::perms::all | fs::perms::sticky_bit);
  const std::string victim = file("victim", "root only\n");
  fs::permissions(victim, fs::perms::owner_read | fs::perms::owner_write);
  fs::create_symlink(victim, path("sticky/out.json"));
  chown_to(path("sticky/out.json"), kNobody);
  const std::string line =
      "sticky/out.json: cannot write: ./sticky/out.json is a symbolic link of "
      "uid 65534 in the sticky directory ./sticky, which belongs to neither "
      "you nor that directory's owner (not followed: protected symlinks)";
  expect_bad(dpc31("run " + kTraces + "startup_dpc31_1m5.scn --quiet --json sticky/out.json"),
             "dpc31 run: " + line, "run --json");
  expect_bad(dpc31("bridge --pty p --firmware DO4 --log sticky/out.json"), "dpc31 bridge: " + line,
             "bridge --log");
  EXPECT_EQ(slurp(victim), "root only\n");
  fs::remove(path("sticky/out.json"));
  fs::create_symlink(victim, path("sticky/out.json"));  // ours: followed, as before
  const Outcome r =
      dpc31("run " + kTraces + "startup_dpc31_1m5.scn --quiet --json sticky/out.json");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(slurp(victim), "root only\n");
}

// Finding 3: `bridge --log` naming its own pty fed the log back into it (100 % CPU); on a full
// disk the log stopped at 8 KiB with exit 0. Both are exit 2 with one line now.
TEST_F(CodeSecurity, TheBridgeLogIsRefusedOrReportedLikeEveryOutput) {
  expect_bad(dpc31("bridge --pty p --firmware DO4 --log p"),
             "dpc31 bridge: --log p: is --pty p: an output must not replace an input", "same path");
  EXPECT_EQ(listing(), std::vector<std::string>{});
  const SmallTmpfs full(path("full"));
  ASSERT_EQ(full.error(), "");
  full.fill();
  expect_bad(dpc31("bridge --pty p --firmware DO4 --pacing free --log full/log"),
             "dpc31 bridge: cannot write the log full/log: No space left on device", "full disk");
  EXPECT_FALSE(fs::is_symlink(path("p"))) << "the pty link stays";
}

// Finding 6: `bench --build` runs SOURCE_DIR/setup.sh, which as root may apt-get install: its
// help says so.
TEST_F(CodeSecurity, BenchBuildSaysItRunsSetupSh) {
  const Outcome r = dpc31("bench --help");
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find("runs SOURCE_DIR/setup.sh"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("apt-get installs"), std::string::npos) << r.out;
}

}  // namespace
