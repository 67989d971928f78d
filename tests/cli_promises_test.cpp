// Every command's promises against its --help and the docs (the twenty-sixth session's audit
// a26): one reading of a number at every door, no option that acts on nothing taken silently,
// and messages that say what happened (docs/security.md "Numbers on the command line",
// docs/decisions.md "No silent options", docs/bad-input.md).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "bad_input.hpp"

namespace badinput {
namespace {

const std::string kScn = kTraces + "gc_clear_spc3.scn";
const std::string kVcd = std::string(SOURCE_DIR) + "/tests/data/wavediff/emu.vcd";

// The line of `text` that starts with `key`, or "".
std::string line_with(const std::string& text, const std::string& key) {
  const std::size_t at = text.find(key);
  return at == std::string::npos ? "" : text.substr(at, text.find('\n', at) - at);
}

// A leading zero is decimal at every door (docs/security.md): CLI11 alone read "010" as octal
// eight, so these ran another seed, window or count than the one written.
TEST_F(BadInput, LeadingZerosAreDecimalAtEveryDoor) {
  // soak --seed: the first line names the seed run.
  const Outcome soak = dpc31("soak --cycles 1e6 --seed 010");
  EXPECT_EQ(soak.rc, 0) << soak.err;
  EXPECT_EQ(line_with(soak.out, "dpc31 soak:"),
            "dpc31 soak: profile dpc31, 1500000 baud, TWD 20 ms, a fault every 2000000 cycles, "
            "seed 10");
  // soak --baud: 012000000 is the rate 12000000 (it was refused as 2621440).
  EXPECT_EQ(line_with(dpc31("soak --cycles 1e6 --baud 012000000").out, "dpc31 soak:"),
            "dpc31 soak: profile dpc31, 12000000 baud, TWD 20 ms, a fault every 2000000 cycles, "
            "seed 1");
  // The same rule takes 0x hex: seed 0x0A is seed 10.
  EXPECT_EQ(line_with(dpc31("soak --cycles 1e6 --seed 0x0A").out, "dpc31 soak:"),
            line_with(soak.out, "dpc31 soak:"));
  // run --from/--to: the window of 010..020 is the window of 10..20, byte for byte.
  const std::string scn = copy(kScn, "s.scn");
  ASSERT_EQ(dpc31("run s.scn --quiet --vcd zero.vcd --from 010 --to 020").rc, 0);
  ASSERT_EQ(dpc31("run s.scn --quiet --vcd plain.vcd --from 10 --to 20").rc, 0);
  EXPECT_EQ(slurp(path("zero.vcd")), slurp(path("plain.vcd")));
  // 08 and 09 are numbers (CLI11: "Could not convert").
  EXPECT_EQ(dpc31("run s.scn --quiet --vcd nine.vcd --from 09 --to 010").rc, 0);
  // wavediff --max-signals 01: one signal named in the text report, as with 1.
  const std::string vcd_a = copy(kVcd, "a.vcd");
  const Outcome one = dpc31("wavediff a.vcd zero.vcd --max-signals 1");
  const Outcome zero_one = dpc31("wavediff a.vcd zero.vcd --max-signals 01");
  EXPECT_EQ(one.rc, 1);
  EXPECT_EQ(zero_one.out, one.out);
  const Outcome octal = dpc31("wavediff a.vcd zero.vcd --max-signals 010");
  EXPECT_EQ(octal.out, dpc31("wavediff a.vcd zero.vcd --max-signals 10").out);
  // A scenario reads the same: baud 09600 is 9600, 0x2580 too (docs/scenario-format.md).
  file("b1.scn", "baud 09600\nstartup\nexpect dp_state Data_Exchange\n");
  file("b2.scn", "baud 0x2580\nstartup\nexpect dp_state Data_Exchange\n");
  EXPECT_EQ(dpc31("run b1.scn --quiet").rc, 0);
  EXPECT_EQ(dpc31("run b2.scn --quiet").rc, 0);
  // A mistake is still one line: not a number at all, or beyond the option's range.
  expect_bad(dpc31("soak --seed 0x"),
             "dpc31 soak: --seed: '0x' is not a whole number (decimal or 0x hex)", "0x");
  expect_bad(dpc31("soak --seed 08.5"),
             "dpc31 soak: --seed: '08.5' is not a whole number (decimal or 0x hex)", "08.5");
  expect_bad(dpc31("serve --tcp 0 --max-clients 0100001"),
             "dpc31 serve: --max-clients: '0100001' is outside 1..100000", "0100001");
}

// The bridge's own numbers: a --slave's user_wd_value takes 0x hex as the segment's `station`
// line does (docs/bridge.md); it was "'0x01FF' must be 0..65535". The bridge runs, so it is
// ended by SIGTERM after its first line.
TEST_F(BadInput, BridgeSlaveFieldsReadNumbersAsEveryDoor) {
  const testutil::CommandResult r = testutil::run_command(
      "cd " + path("") + " && timeout -s TERM 2 " + kCli +
      " bridge --tcp 0 --pacing free --slave 0x05:responder:spc3:user_wd=1:user_wd_value=0x01FF "
      "--slave 06:responder:spc3 2>&1");
  const std::string first = line_with(r.out, "dpc31 bridge:");
  EXPECT_NE(first.find("2 slaves: slave5 (profile spc3, firmware responder), slave6 (profile "
                       "spc3, firmware responder)"),
            std::string::npos)
      << r.out;
  expect_bad(dpc31("bridge --tcp 0 --slave 5:responder:spc3:user_wd=1:user_wd_value=0x10000"),
             "dpc31 bridge: --slave '5:responder:spc3:user_wd=1:user_wd_value=0x10000': "
             "user_wd_value '0x10000' must be 0..65535",
             "0x10000");
}

// cosim --session writes a run's outputs (docs/golden-model.md, "Chip-session mode"): --out,
// --vcd, --window, --dump and --junit were dropped without a word (audit a23, finding 2).
TEST_F(BadInput, CosimSessionWritesItsOutputs) {
  // A clean session: the JUnit case is the scenario's, the dump both sides' whole run.
  copy(kScn, "clean.scn");
  const Outcome clean = dpc31("cosim --session clean.scn --dump d --junit j.xml --quiet");
  EXPECT_EQ(clean.rc, 0) << clean.err;
  EXPECT_EQ(slurp(path("j.xml")),
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"dpc31-cosim\" "
            "tests=\"1\" failures=\"0\">\n  <testcase classname=\"cosim\" "
            "name=\"spc3.session.clean\"/>\n</testsuite>\n");
  for (const char* f : {"d/emu.vcd", "d/rtl.vcd"}) EXPECT_TRUE(fs::is_regular_file(path(f))) << f;
  // The SPC3 has no variant (docs/golden-model.md).
  EXPECT_EQ(line_with(clean.out, "\"variant\":"), "\"variant\": null") << clean.out;
  // A divergence (the mutant the session suite catches): its shrunk trace names the scenario's
  // chip and replays to the same divergence; without the mutant (the fixed RTL) it is clean.
  copy(kTraces + "gc_command_dpc31.scn", "m.scn");
  const Outcome bad = dpc31(
      "cosim --session m.scn --mutant NO_C_SWAP --out o --vcd w --window 5 --junit m.xml --quiet");
  EXPECT_EQ(bad.rc, 1) << bad.err;
  const std::string cycle = line_with(bad.out, "\"cycle\":");
  ASSERT_NE(cycle, "") << bad.out;
  const std::string trace = slurp(path("o/cosim-dpc31-session-m.trace"));
  EXPECT_EQ(trace.substr(0, trace.find("# shrunk")),
            "# dpc31 cosim stimulus trace\n# profile dpc31\n# bus intel\n# variant -\n# session " +
                path("m.scn") + "\n# mutant NO_C_SWAP\n");
  for (const char* f : {"w/emu.vcd", "w/rtl.vcd"}) EXPECT_TRUE(fs::is_regular_file(path(f))) << f;
  EXPECT_NE(slurp(path("m.xml"))
                .find("name=\"dpc31.session.m\"><failure message=\"divergence at "
                      "cycle "),
            std::string::npos);
  const Outcome again = dpc31("cosim --replay o/cosim-dpc31-session-m.trace --out r --quiet");
  EXPECT_EQ(again.rc, 1) << again.err;
  EXPECT_EQ(line_with(again.out, "\"cycle\":"), cycle) << again.out;
  std::string fixed = trace;
  const std::string mutant = "# mutant NO_C_SWAP";
  fixed.replace(fixed.find(mutant), mutant.size(), "# mutant -");
  file("fixed.trace", fixed);
  EXPECT_EQ(dpc31("cosim --replay fixed.trace --quiet").rc, 0);
}

// A session whose chip did not do what its scenario expects says so as `dpc31 run` does (the
// expect's line on stderr) and exits 1 (docs/golden-model.md, "Session mode"): it exited 0 with
// only `"scenario_expects_passed": false` in the summary (audit s30, finding 12).
TEST_F(BadInput, CosimSessionNamesAFailedExpect) {
  // The scenario ends in Data_Exchange (its own last expect): Wait_Prm is not where it is.
  const std::string scn = slurp(kScn);
  file("x.scn", scn + "expect dp_state Wait_Prm\n");
  const auto line = std::count(scn.begin(), scn.end(), '\n') + 1;
  const std::string failed =
      "x.scn:" + std::to_string(line) + ": expected dp_state Wait_Prm, got Data_Exchange\n";
  const Outcome run = dpc31("run x.scn --quiet");
  EXPECT_EQ(run.rc, 1);
  EXPECT_EQ(run.err, failed);
  const Outcome r = dpc31("cosim --session x.scn --junit x.xml --quiet");
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_EQ(r.err, failed);
  // The JUnit case fails too: a CI reading it saw a pass (the review of the thirtieth session).
  EXPECT_NE(slurp(path("x.xml")).find("failures=\"1\""), std::string::npos) << slurp(path("x.xml"));
  EXPECT_NE(slurp(path("x.xml")).find("<failure message=\"an expect of the scenario failed\"/>"),
            std::string::npos)
      << slurp(path("x.xml"));
  EXPECT_EQ(line_with(r.out, "\"scenario_expects_passed\":"),
            "\"scenario_expects_passed\": false,");
  EXPECT_EQ(line_with(r.out, "\"diverged\":"), "\"diverged\": false,");
  // The scenario as shipped passes: exit 0, nothing said.
  copy(kScn, "ok.scn");
  const Outcome ok = dpc31("cosim --session ok.scn --quiet");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_EQ(ok.err, "");
  EXPECT_EQ(line_with(ok.out, "\"scenario_expects_passed\":"),
            "\"scenario_expects_passed\": true,");
}

// A shrunk stimulus may fail sooner than the run it came from (the shrinker keeps any stimulus
// that still diverges): the report names the cycle its replay diverges at (audit s30, finding 7).
TEST_F(BadInput, CosimShrunkTraceNamesItsOwnDivergence) {
  // EOI_SHORT's seed 1 shrinks to a stimulus that diverges before the run's cycle.
  const Outcome r = dpc31("cosim --mutant EOI_SHORT --seeds 2 --out o");
  EXPECT_EQ(r.rc, 1) << r.err;
  const std::string run_cycle = line_with(r.out, "\"cycle\":");
  const std::string shrunk = line_with(r.err, "  shrunk to ");
  const std::string mark = ", which diverge at cycle ";
  const std::size_t at = shrunk.find(mark);
  ASSERT_NE(at, std::string::npos) << r.err;
  const std::string own =
      shrunk.substr(at + mark.size(), shrunk.find(' ', at + mark.size()) - at - mark.size());
  EXPECT_EQ(shrunk.substr(shrunk.find(" (replay it there): ")),
            " (replay it there): o/cosim-dpc31-seed1.trace");
  EXPECT_NE("\"cycle\": " + own + ",", run_cycle);
  const Outcome again = dpc31("cosim --replay o/cosim-dpc31-seed1.trace --out r --quiet");
  EXPECT_EQ(again.rc, 1) << again.err;
  EXPECT_EQ(line_with(again.out, "\"cycle\":"), "\"cycle\": " + own + ",");
}

// A `cpu` image that cannot be read is refused at its line before the session runs, as `dpc31 run`
// refuses it (exit 2, docs/cpu.md): the session ran and "diverged" at cycle 0 (review, s27).
TEST_F(BadInput, CosimSessionRefusesABadCpuImage) {
  file("img.scn", "cpu 80c32 firmware nosuch.ihx\nstartup\n");
  const Outcome r = dpc31("cosim --session img.scn --quiet");
  expect_bad(r, "img.scn:1: " + path("nosuch.ihx") + ": no such file", "a missing cpu image");
  EXPECT_EQ(r.out, "");
}

// cosim --session runs the scenario's chip, once: the options of seeds, and a chip the scenario
// is not, were dropped without a word (exit 0 on another chip than asked for).
TEST_F(BadInput, CosimSessionRefusesWhatItWouldIgnore) {
  const std::string scn = copy(kTraces + "startup_vpc3plus_1m5.scn", "s.scn");
  for (const std::string opt : {"--seeds 50", "--seed-base 3", "--cycles 7", "--shard 2/3",
                                "--replay s.scn", "--keep-going"}) {
    const std::string name = opt.substr(0, opt.find(' '));
    // CLI11 names the option defined first first (--keep-going comes after --session).
    expect_bad(dpc31("cosim --session s.scn " + opt + " --quiet"),
               name == "--keep-going" ? "dpc31 cosim: --session excludes --keep-going"
                                      : "dpc31 cosim: " + name + " excludes --session",
               opt);
  }
  expect_bad(dpc31("cosim --session s.scn --profile dpc31 --quiet"),
             "dpc31 cosim: s.scn: the scenario runs profile vpc3plus, not --profile dpc31",
             "profile");
  expect_bad(dpc31("cosim --session s.scn --bus intel --quiet"),
             "dpc31 cosim: s.scn: the scenario runs bus motorola, not --bus intel", "bus");
  // The VPC3+ without a `variant` line is the VPC3+C (docs/scenario-format.md).
  expect_bad(dpc31("cosim --session s.scn --variant b --quiet"),
             "dpc31 cosim: s.scn: the scenario runs profile vpc3plus variant c, not --variant b",
             "variant");
  // What agrees with the scenario is taken, and the summary names the chip as run: the
  // scenario's `profile vpc3plus` and `bus motorola` lines, and the variant C its missing
  // `variant` line means, as its release code 0xC = 12 (chip-facts.md, Status_Reg high byte
  // bits 7:4 "0xC VPC3+C"; docs/golden-model.md): it was null.
  const Outcome ok = dpc31(
      "cosim --session s.scn --profile vpc3plus --bus motorola --variant c "
      "--quiet");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_EQ(line_with(ok.out, "\"profile\":"), "\"profile\": \"vpc3plus\",") << ok.out;
  EXPECT_EQ(line_with(ok.out, "\"bus\":"), "\"bus\": \"motorola\",") << ok.out;
  EXPECT_EQ(line_with(ok.out, "\"variant\":"), "\"variant\": 12") << ok.out;
  // The same without the options: the scenario alone names the C.
  const Outcome bare = dpc31("cosim --session s.scn --quiet");
  EXPECT_EQ(bare.rc, 0) << bare.err;
  EXPECT_EQ(line_with(bare.out, "\"variant\":"), "\"variant\": 12") << bare.out;
  // A mutant the session's profile has no model for is refused as in seed mode (the review of the
  // thirtieth session: "no RTL model for mutant", a 0-event trace and exit 1 before).
  const std::string spc3 = copy(kTraces + "buffers_spc3.scn", "b.scn");
  expect_bad(dpc31("cosim --session b.scn --mutant SAP_NO_RR --quiet"),
             "dpc31 cosim: mutant 'SAP_NO_RR' is built for profile vpc3plus, not spc3 (--profile "
             "vpc3plus)",
             "mutant of another profile");
  expect_bad(dpc31("cosim --session b.scn --mutant NO_SUCH --quiet"),
             "dpc31 cosim: no RTL model for profile spc3 mutant 'NO_SUCH' (no such mutant)",
             "no such mutant");
  // --shard-base alone blamed a --shard '1/1' nobody gave.
  expect_bad(dpc31("cosim --seeds 2 --cycles 10 --shard-base 0 --quiet"),
             "dpc31 cosim: --shard-base requires --shard", "shard-base");
}

// Options of a mode that does not run are refused, as --clock-b and --tolerance-cycles were.
TEST_F(BadInput, WavediffAndBenchRefuseOptionsOfAModeNotRun) {
  copy(kVcd, "a.vcd");
  copy(kVcd, "b.vcd");
  expect_bad(dpc31("wavediff a.vcd b.vcd --edge falling"),
             "dpc31 wavediff: --edge requires --clock", "edge");
  expect_bad(dpc31("wavediff a.vcd b.vcd --clock-b clk"),
             "dpc31 wavediff: --clock-b requires --clock", "clock-b");
  expect_bad(dpc31("wavediff a.vcd b.vcd --tolerance-cycles 2"),
             "dpc31 wavediff: --tolerance-cycles requires --clock", "tolerance-cycles");
  // An output that cannot be written: the file's own style, no prefix (docs/decisions.md).
  expect_bad_prefix(dpc31("wavediff a.vcd b.vcd --json no/such/dir/r.json"),
                    "no/such/dir/r.json: cannot create the temporary file ", "json");
  expect_bad(dpc31("wavediff a.vcd b.vcd --wavedrom-window 5"),
             "dpc31 wavediff: --wavedrom-window requires --wavedrom", "wavedrom-window");
  expect_bad(dpc31("bench --items a --wavediff-mb 5"),
             "dpc31 bench: --wavediff-mb is for item f, which --items leaves out", "mb");
  expect_bad(dpc31("bench --items a,g --wavediff-dir ."),
             "dpc31 bench: --wavediff-dir is for item f, which --items leaves out", "dir");
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.vcd", "b.vcd"}));
}

// An option of several values took the scenario (or A and B) after it, and the error then said
// the scenario was missing: each takes one value (a comma list, or the option again).
TEST_F(BadInput, AListOptionDoesNotTakeThePositionalAfterIt) {
  copy(kScn, "s.scn");
  const Outcome run = dpc31("run --quiet --signals 'pins.*' s.scn --vcd x.vcd");
  EXPECT_EQ(run.rc, 0) << run.err;
  EXPECT_TRUE(fs::is_regular_file(path("x.vcd")));
  copy(kVcd, "a.vcd");
  const Outcome wd = dpc31("wavediff --include '*dp_state*' a.vcd a.vcd --exclude x a.vcd");
  // A third positional is what it is: an extra argument, named.
  EXPECT_EQ(wd.rc, 2);
  EXPECT_EQ(wd.err, "dpc31 wavediff: The following argument was not expected: a.vcd\n");
  EXPECT_EQ(dpc31("wavediff --include '*dp_state*' a.vcd a.vcd").rc, 0);
}

// The report's first line and the JSON name an --unaccounted-fault (docs/soak.md): without it
// the failing run read as a real counting failure.
TEST_F(BadInput, SoakNamesTheUnaccountedFault) {
  const Outcome r =
      dpc31("soak --cycles 1e7 --fault-period 5e5 --unaccounted-fault glitch --json ug.json");
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(line_with(r.out, "dpc31 soak:"),
            "dpc31 soak: profile dpc31, 1500000 baud, TWD 20 ms, a fault every 500000 cycles, "
            "seed 1, one unaccounted glitch fault");
  EXPECT_NE(slurp(path("ug.json")).find("\"unaccounted_fault\": \"glitch\""), std::string::npos);
}

// The number after `"KEY": ` in a JSON text (the soak's --json), as written, or "".
std::string json_number(const std::string& json, const std::string& key) {
  const std::string at = "\"" + key + "\": ";
  const std::size_t from = json.find(at);
  if (from == std::string::npos) return "";
  const std::size_t begin = from + at.size();
  return json.substr(begin, json.find_first_of(",\n}", begin) - begin);
}

// The report's cycles, chip time and "x real time" are the whole run's, the start-up included
// (docs/soak.md, "Measured": the whole chip time over the wall time of the whole run). The old
// factor divided the chip time after the start-up by the wall time after it. At 9600 baud the
// start-up alone outlasts --cycles 1e6: the baud search listens max(4096 bit times, 20 ms) at
// each rate above 9600 first (docs/timing.md, "Baud_Search"; T = 96, 256, 512, 1056, 2500 clocks
// at 500 k, 187.5 k, 93.75 k, 45.45 k, 19.2 kbaud, 48 MHz): 5 x 960 000 + 4096 x (256 + 512 +
// 1056 + 2500) = 22 511 104 cycles, so after the start-up there is only the last exchange, and
// the old factor was that exchange's alone.
TEST_F(BadInput, SoakRealTimeIsTheWholeRunsChipTime) {
  const Outcome r = dpc31("soak --cycles 1e6 --baud 9600 --json s.json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::string text = line_with(r.out, "cycles ");
  unsigned long long cycles = 0;
  unsigned long long after = 0;
  char factor[32] = {};
  // No std::regex here: g++ 12's -O1 ASan build warns inside <regex> (maybe-uninitialized).
  ASSERT_EQ(std::sscanf(text.c_str(),
                        "cycles %llu (%*f s of chip time), %llu after the start-up; wall %*s s "
                        "(%31[0-9.]x real time)",
                        &cycles, &after, factor),
            3)
      << text;
  const double hz = 48e6;  // the chip's clock (docs/soak.md)
  EXPECT_GE(cycles, 1'000'000u) << text;
  EXPECT_GT(cycles - after, 22'511'104u) << text;
  // The JSON names the same run: its cycles, where the start-up ended, and the wall time unrounded.
  const std::string json = slurp(path("s.json"));
  EXPECT_EQ(json_number(json, "cycles"), std::to_string(cycles)) << json;
  EXPECT_EQ(json_number(json, "first_cycle"), std::to_string(cycles - after)) << json;
  const double wall_s = std::strtod(json_number(json, "wall_s").c_str(), nullptr);
  ASSERT_GT(wall_s, 0.0) << json;
  char chip[32];
  std::snprintf(chip, sizeof chip, "%.3f", static_cast<double>(cycles) / hz);
  EXPECT_EQ(text.substr(0, text.find("; wall")), "cycles " + std::to_string(cycles) + " (" + chip +
                                                     " s of chip time), " + std::to_string(after) +
                                                     " after the start-up")
      << text;
  char want[32];
  std::snprintf(want, sizeof want, "%.1f", static_cast<double>(cycles) / hz / wall_s);
  EXPECT_EQ(std::string(factor), want) << text << " (wall_s " << wall_s << ")";
}

// A firmware that never starts the chip (the GLOBALS plug-in: its init counts its runs only): the
// line says how far the start-up got (docs/soak.md). A chip never started answers nothing; after
// reset it is in Wait_Prm (chip-facts.md, Status_Reg DP_State: 00 Wait_Prm, the reset value).
TEST_F(BadInput, SoakSaysWhereTheStartUpStopped) {
  expect_bad(dpc31(std::string("soak --cycles 1e6 --firmware ") + BAD_PLUGIN_GLOBALS),
             "dpc31 soak: the first start-up did not reach Data_Exchange: after 1000 tries the "
             "slave is in Wait_Prm; no request was answered, not even FDL_Status",
             "never started");
}

// `dpc31 --version` prints the project's version, the one of CMakeLists.txt's project().
TEST_F(BadInput, VersionIsTheProjectVersion) {
  const std::string cmake = slurp(std::string(SOURCE_DIR) + "/CMakeLists.txt");
  const std::string key = "project(dpc31emu VERSION ";
  const std::size_t at = cmake.find(key);
  ASSERT_NE(at, std::string::npos);
  const std::size_t from = at + key.size();
  const std::string version =
      cmake.substr(from, cmake.find_first_not_of("0123456789.", from) - from);
  ASSERT_FALSE(version.empty());
  const Outcome r = dpc31("--version");
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.out, "dpc31 " + version + "\n");
  EXPECT_EQ(r.err, "");
}

}  // namespace
}  // namespace badinput
