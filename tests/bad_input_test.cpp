// Bad input everywhere (docs/bad-input.md): every subcommand of the real `dpc31` binary, given a
// missing, empty, truncated or garbage input file or a bad option value, prints exactly one line
// on stderr and exits 2, and leaves no output file and no temporary behind; an output file that
// was there before is left untouched.
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
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "run_command.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;

const std::string kCli = DPC31_CLI;
const std::string kTraces = std::string(SOURCE_DIR) + "/traces/";

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void spit(const std::string& path, const std::string& text) {
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

  Outcome dpc31(const std::string& args) const {
    const std::string out = (root_ / "io" / "out").string();
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult r = testutil::run_command(
        "cd " + (root_ / "work").string() + " && " + kCli + " " + args + " >" + out + " 2>" + err);
    return {r.rc, slurp(out), slurp(err)};
  }

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

// Exit 2 and exactly this one line on stderr.
void expect_bad(const Outcome& r, const std::string& line, const std::string& what) {
  EXPECT_EQ(r.rc, 2) << what << "\n" << r.err;
  EXPECT_EQ(r.err, line + "\n") << what;
}

// Exit 2 and one line on stderr that starts with `prefix` (the rest is CLI11's or the system's
// wording, not ours).
void expect_bad_prefix(const Outcome& r, const std::string& prefix, const std::string& what) {
  EXPECT_EQ(r.rc, 2) << what << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << what << ": " << r.err;
}

std::string fmt_line(const std::string& file, std::ptrdiff_t line, const std::string& what) {
  return file + ":" + std::to_string(line) + ": " + what;
}

// A directory the command cannot create files in: read-only for a user; root writes anyway, so
// there /proc, where nobody can create files, stands in for it.
std::string unwritable_dir(const std::string& ro) {
  if (::geteuid() == 0) return "/proc";
  fs::create_directory(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  return ro;
}

// The FST block chain (fstapi.h): type byte, big-endian length counting itself, data.
struct FstBlock {
  std::size_t pos;
  unsigned type;
  std::size_t len;
};
std::vector<FstBlock> fst_blocks(const std::string& b) {
  std::vector<FstBlock> out;
  for (std::size_t pos = 0; pos + 9 <= b.size();) {
    std::size_t len = 0;
    for (std::size_t i = 1; i < 9; ++i) len = len << 8 | static_cast<unsigned char>(b[pos + i]);
    out.push_back({pos, static_cast<unsigned char>(b[pos]), len});
    pos += 1 + len;
  }
  return out;
}

// --- dpc31 run: the scenario file, its options and its outputs ------------------------------

struct FileCase {
  std::string name;
  std::string path;
  std::string line;  // the one line expected on stderr
};

TEST_F(BadInput, RunScenarioFile) {
  const std::string good = copy(kTraces + "gc_clear_spc3.scn", "good.scn");
  const std::vector<FileCase> cases = {
      {"missing", path("missing.scn"), path("missing.scn") + ": no such file"},
      {"directory", path("dir"), path("dir") + ": is a directory, not a scenario file"},
      {"empty", file("empty.scn", ""), path("empty.scn") + ": no commands: nothing to run"},
      {"only comments", file("comments.scn", "# nothing\n\n"),
       path("comments.scn") + ": no commands: nothing to run"},
      // Cut inside "exchange 1 outputs=...": "exchange " alone would parse (one exchange).
      {"truncated", truncated(good, "cut.scn", 400),
       path("cut.scn") + ":11: truncated: the last line has no end of line"},
      {"cut after the header",
       file("cut_header.scn", slurp(good).substr(0, slurp(good).find("startup"))),
       path("cut_header.scn") + ": only header commands: nothing to run"},
      {"garbage",
       file("garbage.scn",
            "\x7f"
            "ELF\x01\x02\x03\n\xff\xfe\n"),
       path("garbage.scn") + ":1: unknown command '\\x7FELF\\x01\\x02\\x03'"},
      {"binary", file("nul.scn", std::string("startup\n\0\0\0\n", 12)),
       path("nul.scn") + ":2: unknown command '\\x00\\x00\\x00'"},
  };
  fs::create_directory(path("dir"));
  spit(path("old.json"), "old");
  spit(path("old.vcd"), "old");
  const auto before = listing();
  for (const FileCase& c : cases) {
    const Outcome r = dpc31("run " + c.path +
                            " --json old.json --record new.trace --vcd old.vcd --fst new.fst "
                            "--pcap new.pcapng");
    expect_bad(r, c.line, c.name);
    EXPECT_EQ(r.out, "") << c.name;  // nothing ran
    EXPECT_EQ(slurp(path("old.json")), "old") << c.name;
    EXPECT_EQ(slurp(path("old.vcd")), "old") << c.name;
    EXPECT_EQ(listing(), before) << c.name;
  }
}

TEST_F(BadInput, RunOptionValues) {
  const std::string scn = kTraces + "gc_clear_spc3.scn";
  spit(path("old.vcd"), "old");
  const auto before = listing();
  // Ours: checked after the scenario parsed, before anything is written.
  expect_bad(dpc31("run " + scn + " --vcd old.vcd --timescale 3ns"),
             "dpc31 run: --timescale '3ns': use 1, 10 or 100 with s, ms, us, ns, ps or fs",
             "timescale");
  expect_bad(dpc31("run " + scn + " --quiet --vcd old.vcd --fst new.fst --signals nosuch"),
             "dpc31 run: no signal matches 'nosuch' (see docs/waveforms.md)", "signals");
  // CLI11's wording after our prefix.
  expect_bad(dpc31("run " + scn + " --vcd old.vcd --from 10 --to 10"),
             "dpc31 run: --to 10 is not after --from 10: an empty waveform window", "window");
  for (const char* args :
       {"--engine fast", "--from x", "--to -1", "--from -5", "--frobnicate", "a b"}) {
    expect_bad_prefix(dpc31(std::string("run ") + scn + " --vcd old.vcd " + args),
                      "dpc31 run: ", args);
  }
  expect_bad(dpc31("run"), "dpc31 run: scenario is required", "no scenario");
  EXPECT_EQ(slurp(path("old.vcd")), "old");
  EXPECT_EQ(listing(), before);
}

// Every output of `run` into a directory that is in the way, one that does not exist and one
// that cannot be written: one line naming the file, no temporary left, the others not written.
TEST_F(BadInput, RunOutputPaths) {
  const std::string scn = kTraces + "gc_clear_spc3.scn";
  fs::create_directory(path("taken"));
  const std::string ro = unwritable_dir(path("ro"));
  const auto before = listing();
  for (const char* opt : {"--json", "--record", "--vcd", "--fst", "--pcap"}) {
    const std::string o = opt;
    expect_bad(dpc31("run " + scn + " --quiet " + o + " taken"),
               "dpc31 run: taken: cannot write: is a directory", o + " directory");
    expect_bad_prefix(dpc31("run " + scn + " --quiet " + o + " no/such/x"),
                      "dpc31 run: no/such/x: cannot create the temporary file no/such/x.",
                      o + " missing directory");
    expect_bad_prefix(dpc31("run " + scn + " --quiet " + o + " " + ro + "/x"),
                      "dpc31 run: " + ro + "/x: cannot create the temporary file " + ro + "/x.",
                      o + " unwritable");
    EXPECT_TRUE(fs::is_empty(path("taken"))) << o;
    EXPECT_EQ(listing(), before) << o;
    // The same among good outputs: none of them is written either.
    std::string all;
    for (const char* other : {"--json", "--record", "--vcd", "--fst", "--pcap"}) {
      all += " " + std::string(other) + (other == o ? " taken" : " new" + std::string(other + 1));
    }
    expect_bad(dpc31("run " + scn + " --quiet" + all),
               "dpc31 run: taken: cannot write: is a directory", o + " among good outputs");
    EXPECT_EQ(listing(), before) << o;
  }
}

// The good case of the same rule, so that the tests above can fail: every output is written
// whole over what was there, and nothing else is left in the directory.
TEST_F(BadInput, RunOutputsAppearWholeAndAlone) {
  for (const char* f : {"r.json", "r.trace", "r.vcd", "r.fst", "r.pcapng"}) spit(path(f), "old");
  const Outcome r = dpc31("run " + kTraces +
                          "gc_clear_spc3.scn --quiet --json r.json --record "
                          "r.trace --vcd r.vcd --fst r.fst --pcap r.pcapng");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(listing(),
            (std::vector<std::string>{"r.fst", "r.json", "r.pcapng", "r.trace", "r.vcd"}));
  EXPECT_EQ(slurp(path("r.trace")).rfind("dpc31-trace 1\n", 0), 0u);
  EXPECT_EQ(slurp(path("r.vcd")).rfind("$date dpc31emu $end\n", 0), 0u);
  EXPECT_EQ(slurp(path("r.json")).rfind("{\n", 0), 0u);
  EXPECT_EQ(slurp(path("r.pcapng")).substr(0, 4), std::string("\x0A\x0D\x0D\x0A", 4));
  EXPECT_EQ(fst_blocks(slurp(path("r.fst"))).at(0).type, 0u);  // the FST header block
}

// Not every target is a file to replace: a device is written in place (renaming over /dev/null
// would put a plain file there), and a symlink stays a symlink to the file it names.
TEST_F(BadInput, OutputsToDevicesAndThroughSymlinks) {
  spit(path("real.json"), "old");
  fs::create_symlink("real.json", path("link.json"));
  const Outcome r = dpc31("run " + kTraces +
                          "gc_clear_spc3.scn --quiet --vcd /dev/null --pcap /dev/null --json "
                          "/dev/stdout");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\n", 0), 0u);  // the JSON on stdout
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  const Outcome l = dpc31("run " + kTraces + "gc_clear_spc3.scn --quiet --json link.json");
  ASSERT_EQ(l.rc, 0) << l.err;
  EXPECT_TRUE(fs::is_symlink(path("link.json")));
  EXPECT_EQ(slurp(path("real.json")).rfind("{\n", 0), 0u);
  EXPECT_EQ(listing(), (std::vector<std::string>{"link.json", "real.json"}));
}

// --- dpc31 replay: golden traces --------------------------------------------------------------

TEST_F(BadInput, ReplayTraceFile) {
  const std::string good = copy(kTraces + "gc_clear_spc3.trace", "good.trace");
  const std::string text = slurp(good);
  // Cut after the line ending at byte 3000 or so: every line is whole, the 'end' line missing.
  const std::size_t at_line = text.find('\n', 3000) + 1;
  const auto line_no = [&](std::size_t bytes) {
    return std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(bytes), '\n');
  };
  fs::create_directory(path("dir"));
  const std::vector<FileCase> cases = {
      {"missing", path("missing.trace"), path("missing.trace") + ": no such file"},
      {"directory", path("dir"), path("dir") + ": is a directory, not a trace file"},
      {"empty", file("empty.trace", ""), path("empty.trace") + ": empty file, not a trace"},
      {"truncated at a line", file("cut_line.trace", text.substr(0, at_line)),
       fmt_line(path("cut_line.trace"), line_no(at_line), "truncated trace: no 'end' line")},
      {"truncated mid-line", file("cut_mid.trace", text.substr(0, at_line + 5)),
       fmt_line(path("cut_mid.trace"), line_no(at_line) + 1,
                "truncated: the last line has no end of line")},
      // "end 9388" cut to "end 93": the end line is there, its number cut short.
      {"truncated end", file("cut_end.trace", text.substr(0, text.size() - 3)),
       fmt_line(path("cut_end.trace"), line_no(text.size()),
                "truncated: the last line has no end of line")},
      {"garbage",
       file("garbage.trace",
            "\x7f"
            "ELF\x01\x02\x03\n\xff\xfe\n"),
       path("garbage.trace") + ":1: not a dpc31 trace (the first line must be 'dpc31-trace 1')"},
  };
  for (const FileCase& c : cases) {
    const Outcome r = dpc31("replay " + c.path);
    expect_bad(r, c.line, c.name);
    EXPECT_EQ(r.out, "") << c.name;
  }
  expect_bad(dpc31("replay"), "dpc31 replay: trace is required", "no trace");
  expect_bad_prefix(dpc31("replay " + good + " --loud"), "dpc31 replay: ", "unknown option");
  EXPECT_EQ(dpc31("replay --quiet " + good).rc, 0);  // the good file itself replays
}

// --- dpc31 cosim: stimulus traces, session scenarios, its outputs ------------------------------

TEST_F(BadInput, CosimReplayAndSessionFiles) {
  const std::string stim =
      "# dpc31 cosim stimulus trace\n83 ev_irq(0080) ev_dout\n102 rd 000b\nend 103\n";
  const std::string good = file("good.stim", stim);
  spit(path("old.xml"), "old");
  fs::create_directory(path("dir"));
  const std::vector<FileCase> replay = {
      {"missing", path("missing.stim"), path("missing.stim") + ": no such file"},
      {"directory", path("dir"), path("dir") + ": is a directory, not a stimulus trace file"},
      {"empty", file("empty.stim", ""), path("empty.stim") + ": empty file, not a stimulus trace"},
      {"truncated", file("cut.stim", stim.substr(0, stim.size() - 2)),
       path("cut.stim") + ":4: truncated: the last line has no end of line"},
      {"no end line", file("noend.stim", stim.substr(0, stim.find("end"))),
       path("noend.stim") + ":3: missing 'end <cycles>' (truncated trace?)"},
      {"garbage",
       file("garbage.stim",
            "\x7f"
            "ELF\x01\x02\x03\n"),
       path("garbage.stim") + ":1: '\\x7FELF\\x01\\x02\\x03' is not a cycle number"},
  };
  const auto files = listing();
  for (const FileCase& c : replay) {
    const Outcome r = dpc31("cosim --replay " + c.path +
                            " --junit old.xml --out shrunk --vcd window --dump dump");
    expect_bad(r, c.line, "replay " + c.name);
    EXPECT_EQ(r.out, "") << c.name;
    EXPECT_EQ(slurp(path("old.xml")), "old") << c.name;
    EXPECT_EQ(listing(), files) << c.name;
  }
  const std::string scn = copy(kTraces + "gc_clear_spc3.scn", "good.scn");
  const std::vector<FileCase> session = {
      {"missing", path("missing.scn"), path("missing.scn") + ": no such file"},
      {"directory", path("dir"), path("dir") + ": is a directory, not a scenario file"},
      {"empty", file("empty.scn", ""), path("empty.scn") + ": no commands: nothing to run"},
      {"truncated", truncated(scn, "cut.scn", 400),
       path("cut.scn") + ":11: truncated: the last line has no end of line"},
      {"garbage", file("garbage.scn", "\x01\x02\n"),
       path("garbage.scn") + ":1: unknown command '\\x01\\x02'"},
  };
  const auto files2 = listing();
  for (const FileCase& c : session) {
    const Outcome r = dpc31("cosim --session " + c.path + " --quiet");
    expect_bad(r, c.line, "session " + c.name);
    EXPECT_EQ(r.out, "") << c.name;
    EXPECT_EQ(listing(), files2) << c.name;
  }
  EXPECT_EQ(dpc31("cosim --replay " + good + " --quiet").rc, 0);  // the good stimulus runs
}

TEST_F(BadInput, CosimOptionsAndOutputs) {
  fs::create_directory(path("taken"));
  spit(path("old.xml"), "old");
  const auto before = listing();
  expect_bad(dpc31("cosim --shard 3/2 --junit old.xml"),
             "dpc31 cosim: --shard must be K/N with 1 <= K <= N, not '3/2'", "shard");
  expect_bad(dpc31("cosim --mutant NOPE --junit old.xml"),
             "dpc31 cosim: no RTL model for profile dpc31 mutant 'NOPE' (built mutants use dpc31)",
             "mutant");
  for (const char* args : {"--seeds 0", "--cycles abc", "--profile z80", "--bus sideways"}) {
    expect_bad_prefix(dpc31(std::string("cosim --junit old.xml ") + args), "dpc31 cosim: ", args);
  }
  // The JUnit file is checked before any seed runs.
  const Outcome r = dpc31("cosim --seeds 1 --cycles 100 --junit taken");
  expect_bad(r, "taken: cannot write: is a directory", "junit directory");
  EXPECT_EQ(r.out, "");
  expect_bad_prefix(dpc31("cosim --seeds 1 --cycles 100 --junit no/such/j.xml"),
                    "no/such/j.xml: cannot create the temporary file ", "junit missing directory");
  // Directories for shrunk traces and waveforms that cannot be made: found before any seed
  // runs (a divergent mutant would write into them), not a crash in the middle.
  spit(path("plain"), "old");
  for (const char* opt : {"--out", "--vcd", "--dump"}) {
    const std::string o = opt;
    expect_bad(
        dpc31("cosim --seeds 1 --cycles 3000 --mutant NEXT_DOUT_KEEPS_N --quiet " + o + " plain"),
        "dpc31 cosim: " + o + " plain: not a directory", o);
    expect_bad(dpc31("cosim --seeds 1 --cycles 3000 --mutant NEXT_DOUT_KEEPS_N --quiet " + o +
                     " plain/sub"),
               "dpc31 cosim: " + o + " plain/sub: plain is not a directory", o + " below a file");
  }
  EXPECT_EQ(slurp(path("plain")), "old");
  fs::remove(path("plain"));
  EXPECT_EQ(slurp(path("old.xml")), "old");
  EXPECT_TRUE(fs::is_empty(path("taken")));
  EXPECT_EQ(listing(), before);
}

// --- dpc31 wavediff: VCD, FST, the map file, its outputs ----------------------------------------

class BadWaves : public BadInput {
 protected:
  void SetUp() override {
    BadInput::SetUp();
    // A real run's waveforms, both formats, as the good side and the material to break.
    const Outcome r =
        dpc31("run " + kTraces + "gc_clear_spc3.scn --quiet --vcd good.vcd --fst good.fst");
    ASSERT_EQ(r.rc, 0) << r.err;
    vcd_ = slurp(path("good.vcd"));
    fst_ = slurp(path("good.fst"));
  }
  // Runs wavediff of the good VCD against `b` with every output; none may appear, the old JSON
  // report stays, and nothing else is left.
  void expect_refused(const std::string& b, const std::string& line, const std::string& what) {
    spit(path("old.json"), "old");
    const auto before = listing();
    for (const std::string& args : {"good.vcd " + b, b + " good.vcd", "good.fst " + b}) {
      const Outcome r =
          dpc31("wavediff " + args + " --json old.json --diff-vcd d.vcd --wavedrom w.json");
      expect_bad(r, line, what + ": " + args);
      EXPECT_EQ(r.out, "") << what;
      EXPECT_EQ(slurp(path("old.json")), "old") << what;
      EXPECT_EQ(listing(), before) << what;
    }
  }
  std::string vcd_;
  std::string fst_;
};

TEST_F(BadWaves, VcdFiles) {
  fs::create_directory(path("dir"));
  expect_refused("missing.vcd", "missing.vcd:0: cannot open: No such file or directory", "missing");
  expect_refused("dir", "dir:0: cannot open: is a directory", "directory");
  file("empty.vcd", "");
  expect_refused("empty.vcd", "empty.vcd:1: empty file", "empty");
  file("header.vcd", vcd_.substr(0, 200));
  expect_refused("header.vcd", "header.vcd:9: truncated: end of file inside $ups (from line 9)",
                 "cut in the header");
  file("tail.vcd", vcd_.substr(0, vcd_.size() - 1));
  expect_refused("tail.vcd",
                 "tail.vcd:" + std::to_string(std::count(vcd_.begin(), vcd_.end(), '\n')) +
                     ": truncated: the last line has no end of line",
                 "cut in the last line");
  file("garbage.vcd",
       "\x7f"
       "ELF\x01\x02\x03\n");
  // The reader splits words at control characters; the one quoted is shown escaped.
  expect_refused("garbage.vcd", "garbage.vcd:1: unexpected '\\x7FELF' in the header", "garbage");
}

TEST_F(BadWaves, FstFiles) {
  const std::vector<FstBlock> blocks = fst_blocks(fst_);
  ASSERT_GE(blocks.size(), 3u);
  ASSERT_EQ(blocks.back().pos + 1 + blocks.back().len, fst_.size());  // the chain as we read it
  const auto block_of = [&](std::initializer_list<unsigned> types) {
    for (const FstBlock& b : blocks) {
      if (std::find(types.begin(), types.end(), b.type) != types.end()) return b;
    }
    ADD_FAILURE() << "no such block";
    return blocks[0];
  };
  // Cut: inside the value changes, and just short of the end (fstapi reads both as shorter
  // waveforms).
  const FstBlock vc = block_of({1, 5, 8});
  file("cut.fst", fst_.substr(0, vc.pos + vc.len / 2));
  expect_refused("cut.fst",
                 "cut.fst:0: not a readable FST file (truncated: the block at byte " +
                     std::to_string(vc.pos) + " ends past the end of the file)",
                 "cut in the value changes");
  file("short.fst", fst_.substr(0, fst_.size() - 10));
  expect_refused("short.fst",
                 "short.fst:0: not a readable FST file (truncated: the block at byte " +
                     std::to_string(blocks.back().pos) + " ends past the end of the file)",
                 "cut at the end");
  // Garbage that starts like an FST (a 0 byte).
  file("garbage.fst", std::string("\0garbage garbage garbage", 24));
  expect_refused("garbage.fst", "garbage.fst:0: not a readable FST file", "garbage");
  // A good header block, then garbage.
  file("tail.fst", fst_.substr(0, blocks[1].pos) + "wxyz garbage after the header");
  expect_refused("tail.fst",
                 "tail.fst:0: not a readable FST file (corrupt: unknown block type 119 at byte " +
                     std::to_string(blocks[1].pos) + ")",
                 "garbage after the header");
  // Value changes scrambled, the chain intact: fstapi prints and exit()s in its decompressor;
  // the child process that reads the file first takes that.
  std::string scrambled = fst_;
  // (Not every scrambling is caught: FST has no checksums, and some corrupt value data
  // decompresses to other values; those compare as differences, docs/bad-input.md.)
  ASSERT_GT(vc.len, 1600u);
  for (std::size_t i = vc.pos + 70; i < vc.pos + 1570; ++i) {
    scrambled[i] = static_cast<char>(static_cast<unsigned char>(scrambled[i]) * 7 + 13);
  }
  file("scrambled.fst", scrambled);
  expect_refused("scrambled.fst",
                 "scrambled.fst:0: not a readable FST file (corrupt or truncated: its reader "
                 "exited with 255)",
                 "scrambled value changes");
  // The hierarchy overwritten: fstapi reads no variables at all, silently.
  const FstBlock hier = block_of({4, 6, 7});
  std::string no_hier = fst_;
  for (std::size_t i = hier.pos + 9; i < hier.pos + 1 + hier.len; ++i) no_hier[i] = '\xff';
  file("nohier.fst", no_hier);
  expect_refused("nohier.fst",
                 "nohier.fst:0: not a readable FST file (corrupt: the hierarchy has 0 of the 14 "
                 "variables of the header)",
                 "hierarchy overwritten");
  // The good pair is the same waveform: the checks do not refuse a good file.
  EXPECT_EQ(dpc31("wavediff good.vcd good.fst").rc, 0);
}

TEST_F(BadWaves, MapFileOptionsAndOutputs) {
  fs::create_directory(path("dir"));
  file("bad.map", "# renames\ndpc31.pins.rxd =\n");
  expect_refused("good.vcd --map bad.map",
                 "bad.map:2: expected 'nameA = nameB' (one name on each side)", "map garbage");
  expect_refused("good.vcd --map missing.map",
                 "missing.map:0: cannot open: No such file or directory", "map missing");
  expect_refused("good.vcd --map dir", "dir:0: cannot open: is a directory", "map directory");
  expect_refused("good.vcd --start 5",
                 "dpc31 wavediff: --start: '5' is not a time (a number and s, ms, us, ns, ps or "
                 "fs; e.g. 100ns)",
                 "start");
  // Outputs in the way: found before the comparison, nothing else written.
  fs::create_directory(path("taken"));
  const auto before = listing();
  for (const char* opt : {"--json", "--diff-vcd", "--wavedrom"}) {
    const std::string o = opt;
    expect_bad(dpc31("wavediff good.vcd good.fst " + o + " taken"),
               "taken: cannot write: is a directory", o);
    expect_bad_prefix(dpc31("wavediff good.vcd good.fst " + o + " no/such/x"),
                      "no/such/x: cannot create the temporary file no/such/x.", o);
    EXPECT_EQ(listing(), before) << o;
    // Among good outputs: none of them is written.
    std::string all;
    for (const char* other : {"--json", "--diff-vcd", "--wavedrom"}) {
      all += " " + std::string(other) + (other == o ? " taken" : " new" + std::string(other + 1));
    }
    expect_bad(dpc31("wavediff good.vcd good.fst" + all), "taken: cannot write: is a directory",
               o + " among good outputs");
    EXPECT_EQ(listing(), before) << o;
  }
  for (const char* args : {"good.vcd", "good.vcd good.vcd --xz maybe", "a b c"}) {
    expect_bad_prefix(dpc31(std::string("wavediff ") + args), "dpc31 wavediff: ", args);
  }
}

// --- regs, demo ---------------------------------------------------------------------------------

TEST_F(BadInput, RegsAndDemoOptions) {
  expect_bad(dpc31("regs --profile all --format text"),
             "dpc31 regs: --format text needs one profile, not all", "all text");
  for (const char* args :
       {"regs --profile z80", "regs --format yaml", "regs extra", "demo --profile z80",
        "demo --bus sideways", "demo extra", "nosuch", ""}) {
    const Outcome r = dpc31(args);
    expect_bad_prefix(r, "dpc31", args);
    EXPECT_EQ(r.out, "") << args;
  }
  // The output directory is a file, or cannot be made: one line before anything is printed.
  spit(path("plain"), "old");
  const auto before = listing();
  Outcome r = dpc31("demo --out-dir plain");
  expect_bad(r, "dpc31 demo: plain: cannot create the output directory: Not a directory",
             "out-dir is a file");
  EXPECT_EQ(r.out, "");
  r = dpc31("demo --out-dir plain/sub");
  expect_bad_prefix(
      r, "dpc31 demo: plain/sub: cannot create the output directory: ", "out-dir below a file");
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(slurp(path("plain")), "old");
  EXPECT_EQ(listing(), before);
}

// --- serve, bridge, bench
// -------------------------------------------------------------------------

// --variant b|c|s on every subcommand that takes --profile: only with --profile vpc3plus, and only
// those three names. One line, exit 2, nothing on stdout (serve binds nothing, soak runs nothing).
TEST_F(BadInput, VariantOptions) {
  for (const std::string sub : {"demo", "cosim --seeds 1 --cycles 10", "soak --cycles 1000",
                                "serve --tcp 0", "bridge --pty dp0 --firmware DO4"}) {
    const std::string name = sub.substr(0, sub.find(' '));
    const Outcome r = dpc31(sub + " --profile dpc31 --variant s");
    expect_bad(
        r, "dpc31 " + name + ": --variant is for --profile vpc3plus: only the VPC3+ has variants",
        sub);
    EXPECT_EQ(r.out, "") << sub;
    const Outcome x = dpc31(sub + " --profile vpc3plus --variant x");
    expect_bad_prefix(x, "dpc31 " + name + ": --variant", sub + " x");
    EXPECT_EQ(x.out, "") << sub;
  }
  EXPECT_EQ(listing(), std::vector<std::string>{}) << "nothing left behind";
}

TEST_F(BadInput, ServeOptions) {
  spit(path("plain"), "old");
  expect_bad(dpc31("serve --tcp abc"), "dpc31 serve: --tcp 'abc': expected PORT or ADDR:PORT",
             "tcp");
  expect_bad(dpc31("serve --unix no/such/s"),
             "dpc31 serve: cannot listen on unix no/such/s: No such file or directory",
             "unix missing directory");
  expect_bad(dpc31("serve --tcp 0 --state-dir no/such"),
             "dpc31 serve: --state-dir no/such: No such file or directory", "state-dir missing");
  expect_bad(dpc31("serve --tcp 0 --state-dir plain"),
             "dpc31 serve: --state-dir plain: Not a directory", "state-dir a file");
  expect_bad(dpc31("serve --tcp 0 --secret-file no/such"),
             "dpc31 serve: --secret-file no/such: No such file or directory", "secret missing");
  for (const char* args :
       {"serve", "serve --tcp 0 --max-clients 0", "serve --tcp 0 --idle-timeout soon",
        "serve --tcp 0 --profile z80", "serve --unix plain", "serve --tcp 0 --secret-file plain"}) {
    expect_bad_prefix(dpc31(args), "dpc31 serve: ", args);
  }
  EXPECT_EQ(slurp(path("plain")), "old");  // a file that is not a socket is not replaced
  EXPECT_EQ(listing(), std::vector<std::string>{"plain"});
}

TEST_F(BadInput, BridgeOptions) {
  spit(path("plain"), "old");
  expect_bad(dpc31("bridge --pty p --firmware XX"),
             "dpc31 bridge: unknown firmware 'XX' (DO4, CNT2)", "firmware");
  expect_bad(dpc31("bridge --pty plain --firmware DO4"),
             "dpc31 bridge: plain exists and is not a symlink: refusing to replace it", "pty");
  // The log is opened last: the symlink made before it is removed again.
  expect_bad(dpc31("bridge --pty p --firmware DO4 --log no/such/log"),
             "dpc31 bridge: cannot write the log no/such/log: No such file or directory", "log");
  for (const char* args : {"bridge --pty p --firmware DO4 --baud 12", "bridge --firmware DO4",
                           "bridge --pty p --firmware DO4 --address 200",
                           "bridge --pty p --firmware DO4 --pacing warp"}) {
    expect_bad_prefix(dpc31(args), "dpc31 bridge: ", args);
  }
  EXPECT_EQ(slurp(path("plain")), "old");
  EXPECT_EQ(listing(), std::vector<std::string>{"plain"});
}

TEST_F(BadInput, BenchOptionsAndJson) {
  fs::create_directory(path("taken"));
  spit(path("old.json"), "old");
  const auto before = listing();
  // The JSON path is checked before anything is measured (/bin/true stands in for the
  // benchmark binary: it is never run).
  expect_bad(dpc31("bench --bench /bin/true --json taken"),
             "dpc31 bench: taken: cannot write: is a directory", "json directory");
  expect_bad_prefix(dpc31("bench --bench /bin/true --json no/such/b.json"),
                    "dpc31 bench: no/such/b.json: cannot create the temporary file ", "json dir");
  expect_bad_prefix(dpc31("bench --bench /nonexistent/dpc31_bench --json old.json"),
                    "dpc31 bench: --bench: ", "bench binary");
  for (const char* args : {"bench --min-time 0", "bench --quick --wavediff-mb 5", "bench extra"}) {
    expect_bad_prefix(dpc31(args), "dpc31 bench: ", args);
  }
  EXPECT_EQ(slurp(path("old.json")), "old");
  EXPECT_EQ(listing(), before);
}

TEST_F(BadInput, SoakOptionsAndJson) {
  fs::create_directory(path("taken"));
  spit(path("old.json"), "old");
  const auto before = listing();
  // The JSON path is checked before the run (the cycle count would otherwise run first).
  expect_bad(dpc31("soak --cycles 1e9 --json taken"),
             "dpc31 soak: taken: cannot write: is a directory", "json directory");
  expect_bad_prefix(dpc31("soak --cycles 1e9 --json no/such/s.json"),
                    "dpc31 soak: no/such/s.json: cannot create the temporary file ", "json dir");
  for (const char* args : {"soak --cycles 0", "soak --cycles many", "soak --profile spc4",
                           "soak --baud 1234", "soak --seed -1", "soak extra"}) {
    expect_bad_prefix(dpc31(args), "dpc31 soak: ", args);
  }
  EXPECT_EQ(slurp(path("old.json")), "old");
  EXPECT_EQ(listing(), before);
}

// --- Outputs that must not destroy or half-write (docs/security.md, findings 2, 6, 7) -----------

const std::string kScn = kTraces + "gc_clear_spc3.scn";

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

// A full file system: fstapi does not check its writes, so only the walk of what it wrote
// shows it. Exit 2, one line, the old file kept, no temporary left (finding 6). A small tmpfs
// mounted for the test (root; the suite runs as root in CI and here).
TEST_F(BadInput, FullFileSystemIsExit2AndKeepsTheOldFile) {
  if (::geteuid() != 0) GTEST_SKIP() << "mounting a tmpfs needs root";
  const std::string full = path("full");
  fs::create_directory(full);
  ASSERT_EQ(::mount("tmpfs", full.c_str(), "tmpfs", 0, "size=64k"), 0) << std::strerror(errno);
  struct Unmount {
    std::string dir;
    ~Unmount() { ::umount2(dir.c_str(), MNT_DETACH); }
  } unmount{full};
  spit(full + "/old.fst", "old fst");
  spit(full + "/old.vcd", "old vcd");
  spit(full + "/old.json", "old json");
  // Fill it up: what is left cannot hold a waveform of the whole run.
  {
    std::ofstream fill(full + "/fill", std::ios::binary);
    const std::string block(4096, 'x');
    while (fill.write(block.data(), static_cast<std::streamsize>(block.size()))) {
    }
  }
  for (const auto& [opt, name] : {std::pair{"--fst", "old.fst"}, std::pair{"--vcd", "old.vcd"},
                                  std::pair{"--json", "old.json"}}) {
    const Outcome r = dpc31("run " + kScn + " --quiet " + opt + " full/" + name);
    expect_bad_prefix(r, std::string("dpc31 run: full/") + name + ": cannot write", name);
  }
  EXPECT_EQ(slurp(full + "/old.fst"), "old fst");
  EXPECT_EQ(slurp(full + "/old.vcd"), "old vcd");
  EXPECT_EQ(slurp(full + "/old.json"), "old json");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(full)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"fill", "old.fst", "old.json", "old.vcd"}));
}

// The standard output is an output too: a write that fails is exit 2 with one line, whatever
// the command found (finding 6).
TEST_F(BadInput, AFailedWriteToTheStandardOutputIsExit2) {
  for (const std::string& args :
       std::vector<std::string>{"regs --profile dpc31", "regs --profile all --format c",
                                "run " + kScn, "replay " + kTraces + "gc_clear_spc3.trace"}) {
    const std::string err = (root_ / "io" / "err").string();
    const testutil::CommandResult r =
        testutil::run_command(kCli + " " + args + " >/dev/full 2>" + err);
    EXPECT_EQ(r.rc, 2) << args;
    const std::string line = slurp(err);
    EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << args << ": " << line;
    EXPECT_NE(line.find(": cannot write the standard output: No space left on device"),
              std::string::npos)
        << args << ": " << line;
  }
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
             "--diff-vcd b.vcd: is B b.vcd: an output must not replace an input", "diff-vcd = B");
  expect_bad(dpc31("wavediff a.vcd b.vcd --json r.json --wavedrom r.json"),
             "--json r.json and --wavedrom r.json are the same file: each output "
             "needs its own",
             "json = wavedrom");
  EXPECT_EQ(slurp(path("b.vcd")), b_text);
  EXPECT_FALSE(fs::exists(path("new.vcd")));
  EXPECT_FALSE(fs::exists(path("r.json")));
}

// A long run (10^6 exchanges at 12 Mbaud, about 40 s of chip time): long enough to be signalled.
std::string long_scenario() {
  return "profile spc3\nbaud 12000000\nmaster address=1\n"
         "slave address=12 ident=0x8031 cfg=11,21 in=2 out=2\nuser inputs=C0,DE\n"
         "startup\nexchange 1000000 outputs=5A,A5\n";
}

pid_t spawn(const std::vector<std::string>& argv, const std::string& dir) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

// Waits up to 60 s for `done`.
template <typename F>
bool eventually(F done) {
  for (int i = 0; i < 6000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
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

// SIGINT, SIGTERM or SIGHUP in the middle of a run: the process still ends by the signal, and
// no temporary of its outputs is left (finding 7).
TEST_F(BadInput, ASignalDuringARunLeavesNoTemporary) {
  spit(path("long.scn"), long_scenario());
  spit(path("old.vcd"), "old");
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const pid_t pid =
        spawn({kCli, "run", "long.scn", "--quiet", "--json", "r.json", "--vcd", "old.vcd", "--fst",
               "r.fst", "--pcap", "r.pcapng", "--record", "r.trace"},
              (root_ / "work").string());
    ASSERT_GT(pid, 0);
    // Every output's temporary is there from the start of the run.
    EXPECT_TRUE(eventually([&] { return any_ending(root_ / "work", ".tmp"); })) << sig;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ASSERT_EQ(::kill(pid, sig), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << sig << " status " << status;
    EXPECT_EQ(listing(), (std::vector<std::string>{"long.scn", "old.vcd"})) << sig;
    EXPECT_EQ(slurp(path("old.vcd")), "old");
  }
}

// dpc31 bench runs dpc31_bench as a child: a signal to dpc31 ends the child too, and the files
// of both go (finding 7).
TEST_F(BadInput, ASignalToBenchEndsItsChildAndRemovesTheFiles) {
  const std::string work = (root_ / "work").string();
  ::setenv("TMPDIR", work.c_str(), 1);
  const pid_t pid = spawn({kCli, "bench", "--quick"}, work);
  ::unsetenv("TMPDIR");
  ASSERT_GT(pid, 0);
  // The child: a process whose parent is `pid`.
  pid_t child = -1;
  EXPECT_TRUE(eventually([&] {
    for (const auto& e : fs::directory_iterator("/proc")) {
      std::ifstream stat(e.path() / "stat");
      std::string text;
      std::getline(stat, text);
      const auto close = text.rfind(')');
      if (close == std::string::npos) continue;
      std::istringstream rest(text.substr(close + 2));
      char state = 0;
      pid_t ppid = 0;
      rest >> state >> ppid;
      if (ppid == pid && text.find("(dpc31_bench)") != std::string::npos) {
        child = std::stoi(e.path().filename().string());
        return true;
      }
    }
    return false;
  }));
  ASSERT_GT(child, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  // Gone (reaped by init once it was killed), and with it everything both made in TMPDIR.
  EXPECT_TRUE(eventually([&] { return ::kill(child, 0) != 0 && listing().empty(); }))
      << "left: " << ::testing::PrintToString(listing());
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

}  // namespace
