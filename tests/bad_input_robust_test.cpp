// Findings of an outside audit of replay, wavediff, cosim and cosim merge (docs/bad-input.md):
// outputs found unwritable only after the run, a replay that ran for hours before its first
// mismatch, warnings without bound, declarations and fields taken in a wrong form.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>

#include "bad_input.hpp"

using namespace badinput;

namespace {

std::size_t lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace

// --dump's and --vcd's files are checked before the seeds: a divergent mutant's seed would write
// its shrunk trace into --out first (the audit's run lost 3.4 s of seeds and its summary).
TEST_F(BadInput, CosimWindowFilesAreCheckedBeforeTheSeeds) {
  const std::string run = "cosim --seeds 1 --cycles 3000 --mutant NEXT_DOUT_KEEPS_N --quiet ";
  fs::create_directories(path("d/rtl.vcd"));
  Outcome r = dpc31(run + "--out o --junit j.xml --dump d");
  expect_bad(r, "dpc31 cosim: d/rtl.vcd: cannot write: is a directory", "--dump rtl.vcd");
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(path("o"))) << "a seed ran";
  EXPECT_FALSE(fs::exists(path("j.xml")));
  fs::create_directories(path("v/emu.vcd"));
  r = dpc31(run + "--out o --vcd v");
  expect_bad(r, "dpc31 cosim: v/emu.vcd: cannot write: is a directory", "--vcd emu.vcd");
  EXPECT_FALSE(fs::exists(path("o"))) << "a seed ran";
  // The RTL's internal FST was a note without --quiet and exit 0.
  fs::create_directories(path("f/rtl_internal.fst"));
  expect_bad(dpc31("cosim --seeds 1 --cycles 2000 --quiet --dump f"),
             "dpc31 cosim: f/rtl_internal.fst: cannot write: is a directory",
             "--dump rtl_internal.fst");
  EXPECT_EQ(fs::directory_iterator(path("f/rtl_internal.fst")), fs::directory_iterator());
  EXPECT_FALSE(fs::exists(path("f/emu.vcd")));
}

// A write that fails during the run (here the file-size limit: the dump of 20 000 cycles is far
// larger than 16 KiB) is exit 2 with its one line, after the summary and the JUnit of the seeds
// that ran.
TEST_F(BadInput, CosimFailedDumpKeepsTheSummaryAndJunit) {
  const Outcome r =
      dpc31("cosim --seeds 2 --cycles 20000 --quiet --dump d --junit j.xml", "ulimit -f 16;");
  expect_bad_prefix(r, "dpc31 cosim: d/", "dump past the limit");
  EXPECT_NE(r.err.find(": cannot write: File too large"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"divergent_seeds\": 0"), std::string::npos) << r.out;
  EXPECT_NE(slurp(path("j.xml")).find("tests=\"2\""), std::string::npos);
}

// The seed range base + seeds (one past the last seed, the summary's "to") is a 64-bit number:
// it wrapped to 0. The one seed 2^64 - 1 does not run past 2^64 - 1, its "to" does: the message
// says so (docs/decisions.md, s30-out).
TEST_F(BadInput, CosimSeedRangeStaysWithin64Bits) {
  expect_bad(dpc31("cosim --seed-base 18446744073709551615 --seeds 2 --quiet"),
             "dpc31 cosim: --seed-base 18446744073709551615 with --seeds 2: the summary's \"to\" "
             "(one past the last seed) would pass 18446744073709551615, the last 64-bit number: "
             "the last seed a run can have is 18446744073709551614",
             "wrap");
  expect_bad(dpc31("cosim --seed-base 18446744073709551615 --seeds 1 --quiet"),
             "dpc31 cosim: --seed-base 18446744073709551615 with --seeds 1: the summary's \"to\" "
             "(one past the last seed) would pass 18446744073709551615, the last 64-bit number: "
             "the last seed a run can have is 18446744073709551614",
             "the last seed alone");
  expect_bad_prefix(dpc31("cosim --seed-base 18446744073709551615 --seeds 1 --shard 1/2"),
                    "dpc31 cosim: --seed-base ", "wrap in a shard");
  const Outcome r = dpc31("cosim --seed-base 18446744073709551613 --seeds 2 --cycles 100 --quiet");
  ASSERT_EQ(r.rc, 0) << r.err;
  spit(path("top.json"), r.out);
  EXPECT_EQ(dpc31("cosim merge top.json").rc, 0);
}

// cosim merge checks the type of each field that names the run, not only that the shards agree.
TEST_F(BadInput, CosimMergeChecksTheRunFieldsTypes) {
  const Outcome r = dpc31("cosim --seeds 2 --cycles 100 --quiet");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto edited = [&](const std::string& from, const std::string& to) {
    std::string t = r.out;
    const std::size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) t.replace(at, from.size(), to);
    spit(path("s.json"), t);
    return dpc31("cosim merge s.json");
  };
  const std::string who = "dpc31 cosim merge: s.json: ";
  expect_bad(edited("\"cycles_per_seed\": 100", "\"cycles_per_seed\": \"x\""),
             who + "cycles_per_seed: \"x\" is not a number of cycles", "cycles_per_seed");
  expect_bad(edited("\"profile\": \"dpc31\"", "\"profile\": 5"), who + "profile: 5 is not a string",
             "profile");
  expect_bad(edited("\"keep_going\": false", "\"keep_going\": \"yes\""),
             who + "keep_going: \"yes\" is not true or false", "keep_going");
  expect_bad(edited("\"variant\": null", "\"variant\": -1"),
             who + "variant: -1 is not null or a variant number", "variant");
  EXPECT_EQ(edited("\"mutant\": \"\"", "\"mutant\": \"\"").rc, 0);
}

// A replay checks each event as the chip makes it: an end near 2^62 (2^62 - 1, the chip's last
// cycle) fails at the first unexpected event, one chip-second in, not after 19 hours of chip time.
TEST_F(BadInput, ReplayStopsAtTheFirstMismatch) {
  std::string text = slurp(kTraces + "gc_sync_dpc31.trace");
  const std::size_t end = text.rfind("\nend ") + 1;
  const std::size_t end_line = lines(text.substr(0, end)) + 1;
  text.replace(end, text.size() - end, "end 4611686018427387903\n");
  file("far.trace", text);
  const auto t0 = std::chrono::steady_clock::now();
  const Outcome r = dpc31("replay far.trace", "timeout 60");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(10));
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_EQ(
      r.err.rfind(
          "far.trace:" + std::to_string(end_line) + ": expected no more X/INT edges, got xint ", 0),
      0u)
      << r.err;
}

// A binary file without any newline is its own first line, not a cut one.
TEST_F(BadInput, BinaryFileWithoutNewlineIsItsFirstLine) {
  file("t",
       "\x7f"
       "ELF\x02\x01\x01garbage");
  expect_bad(dpc31("replay t"), "t:1: not a dpc31 trace (the first line must be 'dpc31-trace 1')",
             "replay");
  expect_bad(dpc31("run t"), "t:1: unknown command '\\x7FELF\\x02\\x01\\x01garbage'", "run");
}

// `$var TYPE SIZE ID NAME [RANGE] $end`: a missing $end or words inside were joined into a name.
TEST_F(BadInput, WavediffVarDeclarationsHaveOneForm) {
  const std::string head = "$timescale 1ns $end\n$scope module tb $end\n";
  const std::string tail = "$upscope $end\n$enddefinitions $end\n#0\n0!\n";
  file("ok.vcd", head + "$var wire 1 ! clk $end\n$var wire 8 # data [7:0] $end\n" + tail);
  EXPECT_EQ(dpc31("wavediff ok.vcd ok.vcd").rc, 0);
  file("noend.vcd", head + "$var wire 1 ! clk $end\n$var wire 8 # data [7:0]\n" +
                        "$var wire 1 $ x_int $end\n" + tail);
  expect_bad(dpc31("wavediff ok.vcd noend.vcd"),
             "noend.vcd:4: bad $var: unexpected '$var' before its $end (expected '$var type size "
             "id name [range] $end')",
             "no $end");
  file("extra.vcd", head + "$var wire 1 ! clk extra junk $end\n" + tail);
  expect_bad(dpc31("wavediff ok.vcd extra.vcd"),
             "extra.vcd:3: bad $var: unexpected 'extra' before its $end (expected '$var type size "
             "id name [range] $end')",
             "extra words");
}

// Warnings of a kind: the first 10, then one line with the count of the rest.
TEST_F(BadInput, WavediffWarningsAreBounded) {
  std::string vcd = "$timescale 1ns $end\n$scope module tb $end\n";
  for (int i = 0; i < 25; ++i) vcd += "$var wire 1 ! x $end\n";
  file("twice.vcd", vcd + "$upscope $end\n$enddefinitions $end\n#0\n0!\n");
  Outcome r = dpc31("wavediff twice.vcd twice.vcd");
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(lines(r.err), 22u) << r.err;
  EXPECT_NE(r.err.find("twice.vcd: warning: 14 more signals named twice, the second ignored\n"),
            std::string::npos)
      << r.err;
  std::string map;
  for (int i = 0; i < 30; ++i) {
    const std::string n = std::to_string(i);
    map.append("a").append(n).append(" = b").append(n).append("\n");
  }
  file("m.map", map);
  r = dpc31("wavediff twice.vcd twice.vcd --map m.map");
  EXPECT_EQ(lines(r.err), 44u) << r.err;
  EXPECT_NE(r.err.find("m.map: warning: 20 more names of the map not in A\n"), std::string::npos);
  EXPECT_NE(r.err.find("m.map: warning: 20 more names of the map not in B\n"), std::string::npos);
}

// No valid VCD token is longer than a value of the widest $var (2^24 bits): that one is read, a
// longer one refused before it costs a gigabyte.
TEST_F(BadInput, VcdTokensAreBoundedByTheWidestValue) {
  const std::string wide =
      "$timescale 1ns $end\n$scope module tb $end\n$var wire 16777216 ! w "
      "$end\n$upscope $end\n$enddefinitions $end\n#0\nb" +
      std::string(std::size_t{1} << 24, '1') + " !\n";
  file("wide.vcd", wide);
  EXPECT_EQ(dpc31("wavediff wide.vcd wide.vcd").rc, 0);
  file("long.vcd", std::string(std::size_t{33} << 20, 'q') + "\n");
  expect_bad(dpc31("wavediff wide.vcd long.vcd"),
             "long.vcd:1: a token longer than 32 MiB (the widest value, 2^24 bits, has 16 Mi "
             "characters)",
             "long token");
}

// A session's JUnit case is named by its scenario's file name, which may hold the markup
// characters and a newline: the file stays XML a CI can read (python3's parser), and the name
// reads back as it is (docs/golden-model.md, "Session mode": PROFILE.session.NAME).
TEST_F(BadInput, CosimSessionJunitEscapesTheScenarioName) {
  const std::string name = "we&ird<\"x'>\n.scn";
  copy(std::string(SOURCE_DIR) + "/traces/gc_sync_dpc31.scn", name);
  const Outcome r = dpc31(
      "cosim --session 'we&ird<\"x'\\''>\n.scn' --mutant EOI_SHORT --junit weird.xml "
      "--out weird --quiet");
  ASSERT_EQ(r.rc, 1) << r.err;  // the mutant's divergence
  const testutil::CommandResult parsed = testutil::run_command(
      "python3 -c \"import sys, xml.etree.ElementTree as t; c = t.parse(sys.argv[1]).find("
      "'testcase'); print(repr(c.get('name')), c.find('failure') is not None)\" " +
      path("weird.xml") + " 2>&1");
  ASSERT_EQ(parsed.rc, 0) << slurp(path("weird.xml"));
  EXPECT_EQ(parsed.out, "'dpc31.session.we&ird<\"x\\'>\\n' True\n") << slurp(path("weird.xml"));
}

// `cosim merge` names its cases by the shards' `profile`, a string of the summary: escaped as the
// session's name (the review of the thirtieth session: `name="dpc31"<&.seed1"`, exit 0).
TEST_F(BadInput, CosimMergeJunitEscapesTheProfile) {
  const Outcome run = dpc31("cosim --seeds 1 --cycles 100 --shard 1/1 --quiet");
  ASSERT_EQ(run.rc, 0) << run.err;
  std::string summary = run.out;
  const std::string key = "\"profile\": \"dpc31\"";
  ASSERT_NE(summary.find(key), std::string::npos) << summary;
  summary.replace(summary.find(key), key.size(), "\"profile\": \"dpc31\\\"<&\"");
  file("s.json", summary);
  const Outcome m = dpc31("cosim merge s.json --junit m.xml");
  const testutil::CommandResult parsed = testutil::run_command(
      "python3 -c \"import sys, xml.etree.ElementTree as t; print(t.parse(sys.argv[1]).find("
      "'testcase').get('name'))\" " +
      path("m.xml") + " 2>&1");
  ASSERT_EQ(parsed.rc, 0) << m.err << slurp(path("m.xml"));
  EXPECT_EQ(parsed.out, "dpc31\"<&.seed1\n");
}
