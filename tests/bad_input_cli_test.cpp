// Findings of an outside audit of the `dpc31` command line as a whole (s34): a user's symlink
// that the bridge replaced, outputs that named one another or the standard output's file and were
// found only after the work (or never), options that acted on nothing, names printed raw.
#include <gtest/gtest.h>

#include <string>

#include "bad_input.hpp"

using namespace badinput;

// docs/bridge.md, "The symlink": only a pty's link is replaced. A user's own link at PATH (a
// dotfile kept as a link; the audit's was /dev/stdout) is refused before the bridge starts, and
// stays as it was.
TEST_F(BadInput, TheBridgeKeepsAUsersOwnSymlink) {
  file("real_config", "my config\n");
  fs::create_symlink("real_config", path("mylink"));
  // `timeout`: the old bridge ran on, and removed the link when the signal stopped it.
  expect_bad(dpc31("bridge --pty mylink --firmware DO4", "timeout 10"),
             "dpc31 bridge: mylink is a symlink to real_config, not to a pty in /dev/pts/: "
             "refusing to replace it",
             "a user's symlink");
  EXPECT_EQ(fs::read_symlink(path("mylink")).string(), "real_config");
  EXPECT_EQ(slurp(path("mylink")), "my config\n");
}

// docs/bad-input.md, "Output files": "an output that names an input or another output is refused
// before any work". cosim's --junit against the files its --dump, --vcd and --out write (their
// names known before the seeds: a shrunk trace's by its pattern), and against the directories.
TEST_F(BadInput, CosimJunitNeverNamesAnotherOutput) {
  fs::create_directory(path("d"));
  fs::create_directory(path("v"));
  fs::create_directory(path("o"));
  const std::string seeds = "cosim --seeds 1 --cycles 3000 --mutant NO_C_SWAP ";
  const std::string same = " are the same file: each output needs its own";
  Outcome r = dpc31(seeds + "--dump d --junit d/emu.vcd");
  expect_bad(r, "dpc31 cosim: --junit d/emu.vcd and --dump d/emu.vcd" + same, "--dump");
  EXPECT_EQ(r.out, "");
  expect_bad(dpc31(seeds + "--vcd v --junit v/rtl_internal.fst"),
             "dpc31 cosim: --junit v/rtl_internal.fst and --vcd v/rtl_internal.fst" + same,
             "--vcd");
  expect_bad(
      dpc31(seeds + "--out o --junit o/cosim-dpc31-seed1.trace"),
      "dpc31 cosim: --junit o/cosim-dpc31-seed1.trace and --out o/cosim-dpc31-seed1.trace" + same,
      "--out");
  // --out's default is the working directory.
  expect_bad(
      dpc31(seeds + "--junit cosim-dpc31-seed1.trace"),
      "dpc31 cosim: --junit cosim-dpc31-seed1.trace and --out ./cosim-dpc31-seed1.trace" + same,
      "--out .");
  // A directory not there yet: the old run wrote every seed, then failed at the rename.
  expect_bad(dpc31(seeds + "--dump n --junit n"), "dpc31 cosim: --dump n and --junit n" + same,
             "--dump = --junit");
  EXPECT_EQ(listing(), (std::vector<std::string>{"d", "o", "v"}));
  for (const char* dir : {"d", "o", "v"}) EXPECT_TRUE(fs::is_empty(path(dir))) << dir;
}

// README, "Command line": "Bad input found before the work (an option, a scenario, an output
// that cannot be created) writes no output file". A name of 256 bytes (NAME_MAX is 255): the
// temporary's short name was created, and the name itself failed only at the rename.
TEST_F(BadInput, AnOutputNameTooLongIsFoundBeforeTheWork) {
  const std::string name = std::string(256, 'n') + ".json";
  const std::string line = name + ": cannot write: File name too long";
  Outcome r = dpc31("run " + kTraces + "startup_dpc31_1m5.scn --record ok.trace --json " + name);
  expect_bad(r, "dpc31 run: " + line, "run");
  EXPECT_EQ(r.out, "");  // no walk
  r = dpc31("soak --cycles 1e6 --json " + name);
  expect_bad(r, "dpc31 soak: " + line, "soak");
  EXPECT_EQ(r.out, "");
  expect_bad(dpc31("cosim --seeds 1 --cycles 100 --junit " + name), "dpc31 cosim: " + line,
             "cosim");
  const std::string data = std::string(SOURCE_DIR) + "/tests/data/wavediff/";
  // wavediff's lines name the file first, as its inputs' do.
  expect_bad(dpc31("wavediff " + data + "emu.vcd " + data + "rtl.vcd --json " + name), line,
             "wavediff");
  EXPECT_TRUE(listing().empty());
}

// docs/decisions.md, "No silent options": cosim's options before `merge` acted on nothing (`cosim
// --junit F merge ...` wrote no F, exit 0).
TEST_F(BadInput, CosimMergeRefusesTheOptionsOfCosim) {
  const std::string why =
      " before merge: an option of cosim's seeds, which merge does not run; merge's own options "
      "go after it";
  expect_bad(dpc31("cosim --junit parent.xml merge a.json b.json"),
             "dpc31 cosim merge: --junit" + why, "--junit");
  expect_bad(dpc31("cosim --profile spc3 --quiet merge a.json b.json"),
             "dpc31 cosim merge: --profile" + why, "--profile");
  EXPECT_TRUE(listing().empty());
}

// docs/bad-input.md, "Output files": an output renamed over the file the shell redirected the
// standard output to took that file's place, and what was printed went with the old one (`run
// s.scn --json out.txt > out.txt`: the walk lost, exit 0). /dev/stdout still writes into it.
TEST_F(BadInput, AnOutputThatIsTheStandardOutputsFileIsRefused) {
  const std::string scn = kTraces + "startup_dpc31_1m5.scn";
  const std::string why =
      ": is the file the standard output goes to: what is printed there would "
      "be lost (name /dev/stdout to write into it)";
  Outcome r = dpc31("run " + scn + " --json ../io/out");
  expect_bad(r, "dpc31 run: --json ../io/out" + why, "run --json");
  EXPECT_EQ(r.out, "");
  expect_bad(dpc31("run " + scn + " --record ../io/out"), "dpc31 run: --record ../io/out" + why,
             "run --record");
  expect_bad(dpc31("soak --cycles 1e6 --json ../io/out"), "dpc31 soak: --json ../io/out" + why,
             "soak");
  expect_bad(dpc31("cosim --seeds 1 --cycles 100 --junit ../io/out"),
             "dpc31 cosim: --junit ../io/out" + why, "cosim");
  expect_bad(dpc31("bench --bench /bin/true --json ../io/out"),
             "dpc31 bench: --json ../io/out" + why, "bench");
  // A segment's station trace is named after FILE, and FILE cannot be /dev/stdout (a segment's
  // --record names a file): no advice. The standard output's file linked under the name.
  fs::create_hard_link(path("../io/out"), path("s.station5_spc3.trace"));
  expect_bad(dpc31("run " + kTraces + "segment/three_slaves.scn --record s"),
             "dpc31 run: --record s.station5_spc3.trace: is the file the standard output goes "
             "to: what is printed there would be lost",
             "segment --record");
  fs::remove(path("s.station5_spc3.trace"));
  r = dpc31("run " + scn + " --json /dev/stdout");
  EXPECT_EQ(r.rc, 0) << r.err;
  // The walk, then the JSON.
  EXPECT_LT(r.out.find("[cycle"), r.out.find("\"final_cycle\"")) << r.out.substr(0, 80);
  EXPECT_NE(r.out.find("\"final_cycle\""), std::string::npos);
  EXPECT_TRUE(listing().empty());
}

// docs/segment.md, "Outputs": a station's trace is FILE.stationN_NAME.trace, beside FILE. FILE a
// FIFO or a device (`--record /dev/null`) made new files in its directory, /dev: refused. So are
// a directory and a name ending in '/' (`d/` wrote hidden d/.station5_spc3.trace files), as one
// chip's --record refuses them (docs/bad-input.md, "Output files").
TEST_F(BadInput, ASegmentsRecordNamesARegularFile) {
  ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0600), 0);
  fs::create_directory(path("d"));
  const std::string run = "run " + kTraces + "segment/two_masters.scn --record ";
  const Outcome r = dpc31(run + "fifo");
  expect_bad(r,
             "dpc31 run: --record fifo: not a regular file: a segment writes a trace per station "
             "beside FILE (FILE.stationN.trace), so FILE names a file",
             "a FIFO");
  EXPECT_EQ(r.out, "");
  expect_bad(dpc31(run + "d"), "dpc31 run: --record d: cannot write: is a directory", "dir");
  expect_bad(dpc31(run + "d/"),
             "dpc31 run: --record d/: cannot write: a file name cannot end in '/'", "dir/");
  expect_bad(dpc31(run + "new/"),
             "dpc31 run: --record new/: cannot write: a file name cannot end in '/'", "new/");
  EXPECT_EQ(listing(), (std::vector<std::string>{"d", "fifo"}));
  EXPECT_TRUE(fs::is_empty(path("d")));
}

// docs/decisions.md, "No silent options": --window sizes the --vcd window; without --vcd it acted
// on nothing, as `run --from` without a waveform would.
TEST_F(BadInput, CosimWindowNeedsVcd) {
  expect_bad(dpc31("cosim --seeds 1 --cycles 3000 --mutant NO_C_SWAP --window 5"),
             "dpc31 cosim: --window 5: the divergence's window needs --vcd", "no --vcd");
  EXPECT_TRUE(listing().empty());
}

// An exported but empty TMPDIR is unset, as mktemp(1) and Python's tempfile take it: the scratch
// directory of an FST written to a device goes to /tmp (removed after).
TEST_F(BadInput, AnEmptyTmpdirIsUnset) {
  const Outcome r =
      dpc31("run " + kTraces + "startup_dpc31_1m5.scn --quiet --fst /dev/null", "TMPDIR=");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

// docs/bad-input.md: "exactly one line on stderr". A name's control bytes are shown as \xHH, as
// a file's contents are: a newline made two lines, an ESC reached the terminal.
TEST_F(BadInput, NamesWithControlBytesAreOneEscapedLine) {
  expect_bad(dpc31("run \"$(printf 'a\\nb.scn')\""), "a\\x0Ab.scn: no such file", "newline");
  file("c\x1B[31mred.scn", "x\n");
  expect_bad(dpc31("run \"$(printf 'c\\033[31mred.scn')\""),
             "c\\x1B[31mred.scn:1: unknown command 'x'", "ESC");
  expect_bad_prefix(dpc31("run " + kTraces + "startup_dpc31_1m5.scn --quiet --json " +
                          "\"$(printf 'd\\ne/x.json')\""),
                    "dpc31 run: d\\x0Ae/x.json: cannot create the temporary file d\\x0Ae/", "json");
  // A segment's --record, the bridge's symlink refusal (the link's name and what it points to),
  // replay's and wavediff's inputs.
  ASSERT_EQ(::mkfifo(path("f\nifo").c_str(), 0600), 0);
  expect_bad(dpc31("run " + kTraces + "segment/two_masters.scn --record \"$(printf 'f\\nifo')\""),
             "dpc31 run: --record f\\x0Aifo: not a regular file: a segment writes a trace per "
             "station beside FILE (FILE.stationN.trace), so FILE names a file",
             "segment --record");
  fs::create_symlink("real\nconf", path("my\x1Blink"));
  expect_bad(dpc31("bridge --pty \"$(printf 'my\\033link')\" --firmware DO4", "timeout 10"),
             "dpc31 bridge: my\\x1Blink is a symlink to real\\x0Aconf, not to a pty in /dev/pts/: "
             "refusing to replace it",
             "bridge");
  expect_bad(dpc31("replay \"$(printf 'a\\nb.trace')\""), "a\\x0Ab.trace: no such file", "replay");
  expect_bad(dpc31("wavediff \"$(printf 'a\\nb.vcd')\" x.vcd"),
             "a\\x0Ab.vcd:0: cannot open: No such file or directory", "wavediff");
}

// The commands the demo prints can be pasted as they are: a path with a space is quoted.
TEST_F(BadInput, TheDemosCommandsQuoteAPathWithASpace) {
  const Outcome r = dpc31("demo --out-dir 'd\xC3\xA9 mo'");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("GTKWave save file (gtkwave 'd\xC3\xA9 mo/dpc31-demo.gtkw'): d\xC3\xA9 "
                       "mo/dpc31-demo.gtkw\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("(pulseview -I vcd -i 'd\xC3\xA9 mo/dpc31-demo-la.vcd' opens it"),
            std::string::npos)
      << r.out;
}

// docs/soak.md: --cycles and --fault-period are whole numbers of cycles, in decimal or with an
// exponent. A fraction was cut off (`1000000.7` ran a fault every 1000000 cycles); it is refused
// in the option's words, and a whole value with an exponent or a point is taken exactly.
TEST_F(BadInput, ACountOfCyclesWithAFractionIsRefused) {
  expect_bad(dpc31("soak --cycles 2e6 --fault-period 1000000.7"),
             "dpc31 soak: --fault-period: '1000000.7' is not a whole number", "fault period");
  expect_bad(dpc31("soak --cycles 2000000.5"),
             "dpc31 soak: --cycles: '2000000.5' is not a whole number", "cycles");
  expect_bad(dpc31("soak --cycles 2e6 --fault-period 1e-1"),
             "dpc31 soak: --fault-period: '1e-1' is not a whole number", "negative exponent");
  EXPECT_TRUE(listing().empty());
  const Outcome r = dpc31("soak --cycles 2.0e6 --fault-period 2.5e5 --json s.json");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.out.rfind("dpc31 soak: profile dpc31, 1500000 baud, TWD 20 ms, a fault every "
                        "250000 cycles, seed 1\n",
                        0),
            0u)
      << r.out;
  EXPECT_NE(slurp(path("s.json")).find("\"fault_period\": 250000,"), std::string::npos);
}

// docs/bad-input.md, "Output files": `-` is the standard output of a file option and the standard
// input of an input, as /dev/stdout and /dev/stdin are (it wrote a file named `-`, and read none);
// `./-` names a file called `-`; an option that names a directory refuses `-`.
TEST_F(BadInput, ADashIsTheStandardOutputOrInput) {
  const std::string scn = kTraces + "startup_dpc31_1m5.scn";
  ASSERT_EQ(dpc31("run " + scn + " --quiet --json r.json").rc, 0);
  const Outcome to_stdout = dpc31("run " + scn + " --quiet --json -");
  EXPECT_EQ(to_stdout.rc, 0) << to_stdout.err;
  EXPECT_EQ(to_stdout.out, slurp(path("r.json")));
  EXPECT_EQ(listing(), std::vector<std::string>{"r.json"});
  const Outcome from_stdin = dpc31("run - --quiet --json ./-", "cat " + scn + " |");
  EXPECT_EQ(from_stdin.rc, 0) << from_stdin.err;
  std::string json = slurp(path("r.json"));
  json.replace(json.find(scn), scn.size(), "/dev/stdin");  // the scenario's name as read
  EXPECT_EQ(slurp(path("-")), json);
  fs::remove(path("-"));
  fs::remove(path("r.json"));
  expect_bad(dpc31("cosim --seeds 1 --dump -"),
             "dpc31 cosim: --dump: '-' is the standard input or output, which this option cannot "
             "name: ./- names one called -",
             "a directory option");
  EXPECT_TRUE(listing().empty());
}
