// Bad input of `dpc31 cosim` and `dpc31 wavediff` (docs/bad-input.md; split from
// bad_input_test.cpp at its sections): stimulus traces, session scenarios, RTL-model files, VCD
// and FST files, the map file and their outputs: one line on stderr, exit 2, nothing left.
#include <gtest/gtest.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "bad_input.hpp"

using namespace badinput;

namespace {

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
      // The other ".trace" of the project is named (s34 audit, finding 14: "'dpc31-trace' is not
      // a cycle number").
      {"golden trace", copy(kTraces + "gc_sync_dpc31.trace", "golden.trace"),
       path("golden.trace") +
           ":1: a golden trace of `dpc31 run --record` (replay it with `dpc31 replay`), not a "
           "stimulus trace of `dpc31 cosim`"},
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
  file("fw.ihx", ":0200000080FE80\n:00000001FF\n");  // SJMP $: the image of reset.scn below
  const std::vector<FileCase> session = {
      {"missing", path("missing.scn"), path("missing.scn") + ": no such file"},
      {"directory", path("dir"), path("dir") + ": is a directory, not a scenario file"},
      {"empty", file("empty.scn", ""), path("empty.scn") + ": no commands: nothing to run"},
      {"truncated", truncated(scn, "cut.scn", 400),
       path("cut.scn") + ":11: truncated: the last line has no end of line"},
      {"garbage", file("garbage.scn", "\x01\x02\n"),
       path("garbage.scn") + ":1: unknown command '\\x01\\x02'"},
      // A `cpu` board's RESET starts a second time line the block events cannot replay
      // (docs/golden-model.md): refused before anything runs (the image is read, not run).
      {"board reset", file("reset.scn", "cpu 80c32 firmware fw.ihx\nsilence 1ms\nreset\n"),
       path("reset.scn") +
           ":3: 'reset' (the CPU board's RESET) cannot be replayed in lockstep: the block events "
           "start at the one reset of the session"},
  };
  const auto files2 = listing();
  for (const FileCase& c : session) {
    const Outcome r = dpc31("cosim --session " + c.path + " --quiet");
    expect_bad(r, c.line, "session " + c.name);
    EXPECT_EQ(r.out, "") << c.name;
    EXPECT_EQ(listing(), files2) << c.name;
  }
  EXPECT_EQ(dpc31("cosim --replay " + good + " --quiet").rc, 0);  // the good stimulus runs
  // A UTF-8 BOM before the first line is skipped, as in a golden trace (docs/trace-format.md).
  EXPECT_EQ(dpc31("cosim --replay " + file("bom.stim", "\xEF\xBB\xBF" + stim) + " --quiet").rc, 0);
}

// An input the trace's profile has not (docs/golden-model.md, "Event inputs": ev_mac_start is
// the dpc31's MAC_Start request) is refused at its line, as other bad lines are: exit 2, one
// line, nothing written; the profile is the header's or --profile's.
TEST_F(BadInput, CosimReplayRefusesInputsOfAnotherProfile) {
  const std::string body = "100 ev_mac_start\n200 ev_sap_ind(0080,05) ev_sap_srd(0080)\nend 300\n";
  file("spc3.stim", "# profile spc3\n" + body);
  file("any.stim", body);
  spit(path("old.xml"), "old");
  const auto before = listing();
  const std::string args = " --junit old.xml --out shrunk --vcd window --dump dump";
  expect_bad(dpc31("cosim --replay spc3.stim" + args),
             "spc3.stim:2: 'ev_mac_start' is an input of profile dpc31 only, not of spc3", "spc3");
  expect_bad(dpc31("cosim --replay any.stim --profile vpc3plus" + args),
             "any.stim:1: 'ev_mac_start' is an input of profile dpc31 only, not of vpc3plus",
             "--profile vpc3plus");
  expect_bad(dpc31("cosim --replay any.stim" + args),  // the default profile, dpc31
             "any.stim:2: 'ev_sap_ind' is an input of profile vpc3plus only, not of dpc31",
             "dpc31");
  EXPECT_EQ(slurp(path("old.xml")), "old");
  EXPECT_EQ(listing(), before);
  // ev_mac_stop is every profile's: a RAM access violation emits it on the spc3 (docs/timing.md,
  // "RAM access violation"), so an spc3 trace with it replays.
  file("stop.stim", "# profile spc3\n100 wr 0008<-01\n200 ev_mac_stop\nend 300\n");
  EXPECT_EQ(dpc31("cosim --replay stop.stim --quiet").rc, 0);
}

// A trace replays on the model its header names (docs/golden-model.md): its profile and mutant;
// --profile or --mutant that contradicts the header is refused, and so are the options of random
// seeds, which mean nothing to a replay. The summary names the trace, not a seed range.
TEST_F(BadInput, CosimReplayTakesTheTraceHeader) {
  const std::string body = "83 ev_irq(0080) ev_dout\n102 rd 000b\nend 103\n";
  file("spc3.stim", "# dpc31 cosim stimulus trace\n# profile spc3\n# mutant -\n" + body);
  file("z80.stim", "# profile z80\n" + body);
  file("seed.stim", "# profile spc3\n# seed x1\n" + body);
  const Outcome r = dpc31("cosim --replay spc3.stim --quiet");
  EXPECT_EQ(r.rc, 0) << r.err;
  for (const char* key : {"\"profile\": \"spc3\"", "\"replay\": \"spc3.stim\"",
                          "\"trace_cycles\": 103", "\"mutant\": \"\""})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " in " << r.out;
  for (const char* key : {"cycles_per_seed", "\"seeds\"", "\"shard\"", "keep_going"})
    EXPECT_EQ(r.out.find(key), std::string::npos) << key << " in " << r.out;
  EXPECT_EQ(dpc31("cosim --replay spc3.stim --profile spc3 --mutant '' --quiet").rc, 0);
  spit(path("old.xml"), "old");
  const auto before = listing();
  expect_bad(dpc31("cosim --replay spc3.stim --profile vpc3plus --junit old.xml"),
             "spc3.stim:2: recorded on profile spc3, not --profile vpc3plus", "other profile");
  expect_bad(dpc31("cosim --replay spc3.stim --mutant SAP_NO_RR --junit old.xml"),
             "spc3.stim:3: recorded with mutant -, not --mutant SAP_NO_RR", "other mutant");
  expect_bad(dpc31("cosim --replay z80.stim --junit old.xml"),
             "z80.stim:1: 'z80' is not a chip profile", "no profile");
  expect_bad(dpc31("cosim --replay seed.stim --junit old.xml"), "seed.stim:2: 'x1' is not a seed",
             "no seed");
  for (const char* opt : {"--seeds 3", "--seed-base 2", "--cycles 10", "--shard 1/2",
                          "--shard-base 0", "--keep-going"}) {
    const std::string name = std::string(opt).substr(0, std::string(opt).find(' '));
    // CLI11 names the option defined first first (--keep-going comes after --replay); alone,
    // --shard-base is refused first for the --shard it needs.
    expect_bad(dpc31("cosim --replay spc3.stim --junit old.xml " + std::string(opt)),
               name == "--keep-going"   ? "dpc31 cosim: --replay excludes --keep-going"
               : name == "--shard-base" ? "dpc31 cosim: --shard-base requires --shard"
                                        : "dpc31 cosim: " + name + " excludes --replay",
               opt);
  }
  EXPECT_EQ(slurp(path("old.xml")), "old");
  EXPECT_EQ(listing(), before);
  // The audit's case: a mutant's shrunk failure replays as a failure without its options.
  ASSERT_EQ(dpc31("cosim --profile vpc3plus --mutant SAP_NO_RR --seeds 20 --out vp --quiet").rc, 1);
  EXPECT_EQ(dpc31("cosim --replay vp/cosim-vpc3plus-seed1.trace --out vp --quiet").rc, 1);
  // A replay runs as the header's seed (the report, the JSON, the JUnit name); the trace it
  // replays stays as it is, and its own shrunk trace goes beside it under a name of its own.
  const std::string seed1 = slurp(path("vp/cosim-vpc3plus-seed1.trace"));
  // Its header names the variant that ran: the VPC3+C, the default (docs/golden-model.md).
  EXPECT_NE(seed1.find("# profile vpc3plus\n# bus intel\n# variant c\n"), std::string::npos)
      << seed1.substr(0, 200);
  fs::remove(path("vp/cosim-vpc3plus-seed1-replay.trace"));
  const Outcome rp = dpc31("cosim --replay vp/cosim-vpc3plus-seed1.trace --out vp --junit vp.xml");
  EXPECT_EQ(rp.rc, 1) << rp.err;
  EXPECT_NE(rp.out.find("\"seed\": 1,"), std::string::npos) << rp.out;
  // The header's seed is read as every door reads a whole number (docs/security.md): 0x hex too.
  std::string hex = seed1;
  const std::size_t at = hex.find("# seed 1\n");
  ASSERT_NE(at, std::string::npos) << hex;
  hex.replace(at, 9, "# seed 0x10\n");
  file("hex.trace", hex);
  const Outcome rh = dpc31("cosim --replay hex.trace --quiet");
  EXPECT_EQ(rh.rc, 1) << rh.err;
  EXPECT_NE(rh.out.find("\"seed\": 16,"), std::string::npos) << rh.out;
  EXPECT_TRUE(rp.err.starts_with("seed 1: divergence at cycle ")) << rp.err;
  EXPECT_NE(slurp(path("vp.xml")).find("name=\"vpc3plus.seed1\""), std::string::npos);
  EXPECT_EQ(slurp(path("vp/cosim-vpc3plus-seed1.trace")), seed1);
  EXPECT_NE(rp.err.find("vp/cosim-vpc3plus-seed1-replay.trace"), std::string::npos) << rp.err;
  EXPECT_TRUE(fs::exists(path("vp/cosim-vpc3plus-seed1-replay.trace")));
  // Replaying the replay's trace: the seed run's trace is not written over, nor the trace
  // replayed (the review's case: it wrote cosim-vpc3plus-seed1.trace).
  const std::string again = slurp(path("vp/cosim-vpc3plus-seed1-replay.trace"));
  const Outcome ra = dpc31("cosim --replay vp/cosim-vpc3plus-seed1-replay.trace --out vp");
  EXPECT_EQ(ra.rc, 1) << ra.err;
  EXPECT_NE(
      ra.err.find("not written over vp/cosim-vpc3plus-seed1-replay.trace, the trace replayed"),
      std::string::npos)
      << ra.err;
  EXPECT_EQ(ra.out.find("\"trace\""), std::string::npos) << ra.out;
  EXPECT_EQ(slurp(path("vp/cosim-vpc3plus-seed1.trace")), seed1);
  EXPECT_EQ(slurp(path("vp/cosim-vpc3plus-seed1-replay.trace")), again);
  // The bus and the variant are recorded too (the review's case): a motorola VPC3+C failure
  // replays on that model, a --variant beside a vpc3plus header is taken, a contradiction refused.
  ASSERT_EQ(
      dpc31("cosim --profile vpc3plus --variant c --bus motorola --mutant SAP_NO_RR --seeds 20 "
            "--out vc --quiet")
          .rc,
      1);
  const std::string shrunk = slurp(path("vc/cosim-vpc3plus-seed1.trace"));
  EXPECT_NE(shrunk.find("# profile vpc3plus\n# bus motorola\n# variant c\n"), std::string::npos)
      << shrunk.substr(0, 200);
  const Outcome v = dpc31("cosim --replay vc/cosim-vpc3plus-seed1.trace --out vc");
  EXPECT_EQ(v.rc, 1) << v.err;
  EXPECT_NE(v.out.find("\"bus\": \"motorola\""), std::string::npos) << v.out;
  EXPECT_NE(v.out.find("\"variant\": 12"), std::string::npos) << v.out;  // Vpc3Variant::c, 0xC
  EXPECT_EQ(dpc31("cosim --replay vc/cosim-vpc3plus-seed1.trace --variant c --out vc --quiet").rc,
            1);
  file("vp.stim", "# profile vpc3plus\n# mutant -\n" + body);
  EXPECT_EQ(dpc31("cosim --replay vp.stim --variant c --quiet").rc, 0);
  expect_bad(dpc31("cosim --replay vc/cosim-vpc3plus-seed1.trace --variant b --junit old.xml"),
             "vc/cosim-vpc3plus-seed1.trace:4: recorded with variant c, not --variant b",
             "other variant");
  expect_bad(dpc31("cosim --replay vc/cosim-vpc3plus-seed1.trace --bus intel --junit old.xml"),
             "vc/cosim-vpc3plus-seed1.trace:3: recorded on bus motorola, not --bus intel",
             "other bus");
}

// The audit's cases: a header names its run's mutant and RTL where it is read (TRACE:LINE), and
// the RTL as --rtl: its files must be there and the options must not contradict it. A replay with
// its RTL is CosimRtl.replay_names_its_rtl.
TEST_F(BadInput, CosimReplayHeaderNamesItsModel) {
  const std::string body = "83 ev_irq(0080) ev_dout\n102 rd 000b\nend 103\n";
  file("nope.stim", "# profile dpc31\n# mutant NOPE\n" + body);
  const std::string a = file("a.v", "module blocks; endmodule\n");
  file("b.v", "module blocks; endmodule\n");
  file("gone.stim",
       "# profile dpc31\n# mutant -\n# rtl " + path("gone.v") + "\n# top blocks\n" + body);
  file("a.stim", "# profile dpc31\n# mutant -\n# rtl " + a + "\n# top blocks\n" + body);
  spit(path("old.xml"), "old");
  const auto before = listing();
  expect_bad(dpc31("cosim --replay nope.stim --junit old.xml"),
             "nope.stim:2: 'NOPE' is not a mutant", "mutant");
  expect_bad(dpc31("cosim --replay gone.stim --junit old.xml"),
             "gone.stim:3: recorded with --rtl " + path("gone.v") + ": no such file", "gone");
  expect_bad(dpc31("cosim --replay a.stim --rtl b.v --top blocks --junit old.xml"),
             "a.stim:3: recorded with --rtl " + a + ", not --rtl b.v", "other rtl");
  expect_bad(dpc31("cosim --replay a.stim --rtl-model b.v --junit old.xml"),
             "a.stim:3: recorded with --rtl " + a + ", not --rtl-model b.v", "a model");
  // The same file by another name is the same RTL: the --top beside it is what differs.
  expect_bad(dpc31("cosim --replay a.stim --rtl ./a.v --top other --junit old.xml"),
             "a.stim:4: recorded with --top blocks, not --top other", "other top");
  expect_bad(dpc31("cosim --replay a.stim --define X --junit old.xml"),
             "a.stim:3: recorded with no --define, not --define X", "a define");
  expect_bad(
      dpc31("cosim --replay a.stim --junit a.v"),
      "dpc31 cosim: --junit a.v: is the trace's rtl " + a + ": an output must not replace an input",
      "junit over the rtl");
  EXPECT_EQ(slurp(a), "module blocks; endmodule\n");
  EXPECT_EQ(slurp(path("old.xml")), "old");
  EXPECT_EQ(listing(), before);
  // `--vcd win/` names win/emu.vcd (win//emu.vcd before), in the JSON and on stderr.
  const Outcome r = dpc31("cosim --mutant NO_C_SWAP --seeds 20 --vcd win/ --out win/");
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_NE(r.out.find("\"win/emu.vcd\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("win/rtl_internal.fst"), std::string::npos) << r.err;
  EXPECT_EQ((r.out + r.err).find("win//"), std::string::npos) << r.out << r.err;
}

// The audit's cases (s25 a21, findings 5 and 6): every error of a trace's header is at the line
// to edit (docs/bad-input.md: `FILE:LINE: message`), and its advice works for a trace: not "give
// --profile vpc3plus", which the header's `# profile dpc31` refuses in turn. What only one profile
// has: a variant only the VPC3+ (VPC3+C manual, Status_Reg 15..12; docs/golden-model.md), the SAP
// mutants only the vpc3plus model (docs/golden-model.md, "Mutants"). A header line names one
// thing: two `# profile` lines name none; `# top` and `# define` belong to `# rtl` sources.
TEST_F(BadInput, CosimReplayHeaderLinesAgree) {
  const std::string body = "83 ev_irq(0080) ev_dout\n102 rd 000b\nend 103\n";
  const std::string a = file("a.v", "module blocks; endmodule\n");
  struct Case {
    const char* name;
    std::string header;
    const char* options;
    std::string line;
  };
  const std::vector<Case> cases = {
      {"mutant of another profile", "# profile dpc31\n# mutant SAP_NO_RR\n", "",
       "2: mutant SAP_NO_RR is for profile vpc3plus, not the profile dpc31 of line 1: edit one of "
       "the two lines"},
      {"mutant, the default profile", "# mutant SAP_NO_RR\n", "",
       "1: mutant SAP_NO_RR is for profile vpc3plus, not the default profile dpc31: give "
       "--profile vpc3plus or edit this line"},
      {"mutant, --profile", "# mutant SAP_NO_RR\n", "--profile spc3",
       "1: mutant SAP_NO_RR is for profile vpc3plus, not --profile spc3: give --profile vpc3plus "
       "or edit this line"},
      {"--mutant on the header's profile", "# profile dpc31\n", "--mutant SAP_NO_RR",
       "1: recorded on profile dpc31, and --mutant SAP_NO_RR is for profile vpc3plus: edit this "
       "line or drop --mutant"},
      {"a mutant_sel number without RTL", "# profile dpc31\n# mutant 3\n", "",
       "2: mutant 3 is a mutant_sel number, for a run on your RTL: give --rtl or --rtl-model, or "
       "edit this line"},
      {"variant of another profile", "# profile spc3\n# variant b\n", "",
       "2: variant b is for profile vpc3plus, not the profile spc3 of line 1: edit one of the two "
       "lines"},
      {"variant, the default profile", "# variant b\n", "",
       "1: variant b is for profile vpc3plus, not the default profile dpc31: give --profile "
       "vpc3plus or edit this line"},
      {"--variant on the header's profile", "# profile spc3\n", "--variant c",
       "1: recorded on profile spc3, and --variant c is for profile vpc3plus: edit this line or "
       "drop --variant"},
      {"no variant", "# profile vpc3plus\n# variant x\n", "",
       "2: 'x' is not a variant (b, c, s; - for none)"},
      {"two profiles", "# profile dpc31\n# profile spc3\n# top foo\n", "",
       "2: '# profile' given twice, first at line 1"},
      {"the same profile twice", "# profile spc3\n# mutant -\n# profile spc3\n", "",
       "3: '# profile' given twice, first at line 1"},
      {"two buses", "# bus intel\n# bus motorola\n", "", "2: '# bus' given twice, first at line 1"},
      {"two variants", "# profile vpc3plus\n# variant c\n# variant b\n", "",
       "3: '# variant' given twice, first at line 2"},
      {"two mutants", "# mutant -\n# mutant -\n", "", "2: '# mutant' given twice, first at line 1"},
      {"two seeds", "# seed 1\n# seed 2\n", "", "2: '# seed' given twice, first at line 1"},
      {"two tops", "# rtl " + a + "\n# top blocks\n# top other\n", "",
       "3: '# top' given twice, first at line 2"},
      {"two models", "# rtl-model " + a + "\n# rtl-model " + a + "\n", "",
       "2: '# rtl-model' given twice, first at line 1"},
      {"top without rtl", "# profile dpc31\n# top foo\n", "",
       "2: '# top' without '# rtl': it belongs to the RTL sources the trace was run on (add them, "
       "or delete this line)"},
      {"define without rtl", "# profile dpc31\n# define X=1\n", "--rtl a.v",
       "2: '# define' without '# rtl': it belongs to the RTL sources the trace was run on (add "
       "them, or delete this line)"},
      {"top beside a model", "# profile dpc31\n# rtl-model " + a + "\n# top blocks\n", "",
       "3: '# top' beside the '# rtl-model' of line 2: a built model takes no top or define "
       "(delete this line)"},
      {"rtl and a model", "# rtl " + a + "\n# rtl-model " + a + "\n", "",
       "2: '# rtl-model' beside the '# rtl' of line 1: one model at a time"},
      // A header key with several words names no one thing: refused, not a silent comment.
      {"a profile of two words", "# dpc31 cosim stimulus trace\n# profile dpc31 spc3\n", "",
       "2: '# profile' takes one value, not 'dpc31 spc3': a header line names one thing"},
      {"a seed of two words", "# seed 1 2\n", "",
       "1: '# seed' takes one value, not '1 2': a header line names one thing"},
  };
  spit(path("old.xml"), "old");
  int i = 0;
  for (const Case& c : cases) {
    const std::string name = std::string("h").append(std::to_string(i++)).append(".stim");
    file(name, c.header + body);
    const auto before = listing();
    const Outcome r = dpc31("cosim --replay " + name + " --junit old.xml --out o --dump d " +
                            std::string(c.options));
    expect_bad(r, name + ":" + c.line, c.name);
    EXPECT_EQ(r.out, "") << c.name;
    EXPECT_EQ(listing(), before) << c.name;
  }
  EXPECT_EQ(slurp(path("old.xml")), "old");
  // The advice works: a header without a profile takes the one the line asks for.
  file("mutant.stim", "# mutant SAP_NO_RR\n" + body);
  file("variant.stim", "# variant b\n" + body);
  EXPECT_EQ(dpc31("cosim --replay mutant.stim --profile vpc3plus --quiet").rc, 0);
  EXPECT_EQ(dpc31("cosim --replay variant.stim --profile vpc3plus --quiet").rc, 0);
  // A key with no value is a comment, the path keys' too (docs/decisions.md, s25-trace), and so
  // is a line whose first word is no key (the writer's own first line).
  file("bare.stim",
       "# dpc31 cosim stimulus trace\n# rtl\n# define\n# rtl-model \n# profile\n# note: profile "
       "dpc31 spc3\n" +
           body);
  EXPECT_EQ(dpc31("cosim --replay bare.stim --quiet").rc, 0);
}

TEST_F(BadInput, CosimOptionsAndOutputs) {
  fs::create_directory(path("taken"));
  spit(path("old.xml"), "old");
  const auto before = listing();
  expect_bad(dpc31("cosim --shard 3/2 --junit old.xml"),
             "dpc31 cosim: --shard must be K/N with 1 <= K <= N, not '3/2'", "shard");
  expect_bad(dpc31("cosim --mutant NOPE --junit old.xml"),
             "dpc31 cosim: no RTL model for profile dpc31 mutant 'NOPE' (no such mutant)",
             "mutant");
  expect_bad(dpc31("cosim --mutant SAP_NO_RR --junit old.xml"),
             "dpc31 cosim: mutant 'SAP_NO_RR' is built for profile vpc3plus, not dpc31 (--profile "
             "vpc3plus)",
             "mutant");
  for (const char* args : {"--seeds 0", "--cycles abc", "--profile z80", "--bus sideways"}) {
    expect_bad_prefix(dpc31(std::string("cosim --junit old.xml ") + args), "dpc31 cosim: ", args);
  }
  // The JUnit file is checked before any seed runs; its line has the subcommand's prefix as every
  // other output's (docs/bad-input.md; s31-serve, finding 8: it was the bare path).
  const Outcome r = dpc31("cosim --seeds 1 --cycles 100 --junit taken");
  expect_bad(r, "dpc31 cosim: taken: cannot write: is a directory", "junit directory");
  EXPECT_EQ(r.out, "");
  expect_bad_prefix(dpc31("cosim --seeds 1 --cycles 100 --junit no/such/j.xml"),
                    "dpc31 cosim: no/such/j.xml: cannot create the temporary file ",
                    "junit missing directory");
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

// dpc31 cosim merge (docs/regression.md): summaries that are not the complete set of one run.
TEST_F(BadInput, CosimMerge) {
  spit(path("old.xml"), "old");
  const auto summary = [this](const std::string& file, const std::string& args) {
    const Outcome r = dpc31("cosim --quiet " + args);
    ASSERT_EQ(r.rc, 0) << args;
    spit(path(file), r.out);
  };
  summary("s1.json", "--seeds 4 --cycles 100 --shard 1/2");
  summary("s2.json", "--seeds 4 --cycles 100 --shard 2/2");
  summary("other.json", "--seeds 4 --cycles 200 --shard 2/2");
  summary("session.json", "--session " + std::string(SOURCE_DIR) + "/traces/startup_dpc31_1m5.scn");
  const std::string text = slurp(path("s1.json"));
  spit(path("cut.json"), text.substr(0, text.size() / 2));
  const auto before = listing();
  const std::string merge = "cosim merge --junit old.xml ";
  expect_bad(dpc31(merge + "s1.json"), "dpc31 cosim merge: shard 2/2 missing", "missing");
  expect_bad(dpc31(merge + "s1.json s1.json s2.json"),
             "dpc31 cosim merge: s1.json: shard 1/2 given twice", "twice");
  expect_bad(dpc31(merge + "s1.json other.json"),
             "dpc31 cosim merge: other.json: cycles_per_seed is 200, in s1.json it is 100: not "
             "shards of one run",
             "other run");
  expect_bad(dpc31(merge + "s1.json cut.json"),
             "dpc31 cosim merge: cut.json: not the JSON summary of a `dpc31 cosim --shard` run "
             "(not JSON, or cut off)",
             "cut off");
  expect_bad(dpc31(merge + "session.json"),
             "dpc31 cosim merge: session.json: not the JSON summary of a `dpc31 cosim --shard` run",
             "session summary");
  expect_bad_prefix(dpc31(merge + "nosuch.json"), "dpc31 cosim merge: nosuch.json: ", "no file");
  // Its command line's own mistakes name the subcommand typed too (they said `dpc31 cosim:`).
  expect_bad(dpc31("cosim merge"), "dpc31 cosim merge: summaries is required", "no summaries");
  expect_bad(dpc31(merge + "s1.json --bogus"),
             "dpc31 cosim merge: The following argument was not expected: --bogus",
             "unknown option");
  expect_bad(dpc31("cosim --shard-base 0 --shard 2/2 --junit old.xml"),
             "dpc31 cosim: --shard must be K/N with 0 <= K <= N - 1, not '2/2'", "0-based");
  expect_bad(dpc31("cosim --shard -1/2 --junit old.xml"),
             "dpc31 cosim: --shard must be K/N with 1 <= K <= N, not '-1/2'", "negative");
  // A summary that does not add up (shard 1/2 of seeds 1..4 ran seeds 1 and 2): a result cut, a
  // seed not its own, a count that is not its results'. A range's end is one past its last seed,
  // and said so (s31-serve, finding 10: "its 2 seeds from 1 to 3").
  const std::string whole = slurp(path("s1.json"));
  const auto edited = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string t = whole;
    const std::size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) t.replace(at, from.size(), to);
    spit(path(name), t);
  };
  const std::size_t last = whole.rfind(",\n    {");
  const std::size_t last_end = whole.find("\n    }", last);
  ASSERT_NE(last_end, std::string::npos) << whole;
  edited("cut_results.json", whole.substr(last, last_end + 6 - last), "");
  edited("foreign_seed.json", "\"seed\": 1\n", "\"seed\": 999999\n");
  edited("false_count.json", "\"divergent_seeds\": 0", "\"divergent_seeds\": 7");
  const std::string incomplete = ": not the complete set of one run";
  expect_bad(
      dpc31(merge + "cut_results.json s2.json"),
      "dpc31 cosim merge: cut_results.json: 1 results for its 2 seeds from 1 up to 3 (exclusive)" +
          incomplete,
      "results cut");
  expect_bad(dpc31(merge + "foreign_seed.json s2.json"),
             "dpc31 cosim merge: foreign_seed.json: result 1 is seed 999999, not 1: not its seeds "
             "from 1 up to 3 (exclusive) in order" +
                 incomplete,
             "foreign seed");
  expect_bad(dpc31(merge + "false_count.json s2.json"),
             "dpc31 cosim merge: false_count.json: divergent_seeds 7 and seeds run 2, but 2 "
             "results of which 0 diverged" +
                 incomplete,
             "false count");
  EXPECT_EQ(slurp(path("old.xml")), "old");
  EXPECT_EQ(listing().size(), before.size() + 3);
  // And the good set merges, in any order.
  EXPECT_EQ(dpc31("cosim merge s2.json s1.json").rc, 0);
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
  // Cut inside the last time stamp: "#1234" cut to "#12" is a time going backwards, but the
  // error is the cut (an outside user was told "time goes backwards").
  const std::size_t last_time = vcd_.rfind("\n#") + 1;
  ASSERT_GT(vcd_.find('\n', last_time), last_time + 3);
  file("time.vcd", vcd_.substr(0, last_time + 3));
  expect_refused(
      "time.vcd",
      "time.vcd:" +
          std::to_string(std::count(vcd_.begin(),
                                    vcd_.begin() + static_cast<std::ptrdiff_t>(last_time), '\n') +
                         1) +
          ": truncated: the last line has no end of line",
      "cut in the last time stamp");
  file("garbage.vcd",
       "\x7f"
       "ELF\n");
  // A token quoted is shown escaped.
  expect_refused("garbage.vcd", "garbage.vcd:1: unexpected '\\x7FELF' in the header", "garbage");
  // Only white space separates tokens (IEEE 1364-2005 18.2, 3.2: blanks, tabs, newlines, form
  // feeds; and CR): a control byte is a damaged or binary file, not a blank (a NUL-damaged file
  // compared "same", a NUL inside a time gave "time goes backwards").
  file("binary.vcd",
       "\x7f"
       "ELF\x01\x02\x03\n");
  expect_refused("binary.vcd", "binary.vcd:1: a control byte \\x01: not a text file", "binary");
  const std::size_t body = vcd_.find("\n#", vcd_.find("$enddefinitions"));
  std::size_t time = body + 1;
  while (vcd_.find('\n', time) < time + 4) time = vcd_.find("\n#", time) + 1;  // 3 digits at least
  const std::size_t time_end = vcd_.find('\n', time);
  const std::string time_line = std::to_string(
      std::count(vcd_.begin(), vcd_.begin() + static_cast<std::ptrdiff_t>(time), '\n') + 1);
  file("nul_line.vcd", vcd_.substr(0, time_end) + std::string(4, '\0') + vcd_.substr(time_end));
  expect_refused("nul_line.vcd", "nul_line.vcd:" + time_line + ": a NUL byte: not a text file",
                 "NUL bytes after a time");
  file("nul_time.vcd", vcd_.substr(0, time + 2) + '\0' + vcd_.substr(time + 2));
  expect_refused("nul_time.vcd", "nul_time.vcd:" + time_line + ": a NUL byte: not a text file",
                 "a NUL inside a time");
  file("esc.vcd", vcd_.substr(0, time_end) + "\x1b" + vcd_.substr(time_end));
  expect_refused("esc.vcd", "esc.vcd:" + time_line + ": a control byte \\x1B: not a text file",
                 "ESC");
  file("vt.vcd", vcd_.substr(0, time_end) + "\v" + vcd_.substr(time_end));
  expect_refused("vt.vcd", "vt.vcd:" + time_line + ": a control byte \\x0B: not a text file",
                 "vertical tab");
  // A form feed and CR are white space: the same waveform.
  file("ff.vcd", vcd_.substr(0, time_end) + "\f\r" + vcd_.substr(time_end));
  EXPECT_EQ(dpc31("wavediff good.vcd ff.vcd").rc, 0);
  // A token is quoted as the other parsers quote one (util/textfile's shown()): its first 40
  // characters and "..." (a 20 MB token was a 20 MB line).
  const std::string huge(std::size_t{1} << 21, 'q');
  const std::string cut = std::string(40, 'q') + "...";
  const std::string next_line = std::to_string(std::count(vcd_.begin(), vcd_.end(), '\n') + 1);
  file("long_header.vcd", huge + "\n");
  expect_refused("long_header.vcd", "long_header.vcd:1: unexpected '" + cut + "' in the header",
                 "a long token in the header");
  file("long_value.vcd", vcd_ + huge + "\n");
  expect_refused("long_value.vcd", "long_value.vcd:" + next_line + ": unexpected '" + cut + "'",
                 "a long token for a value");
  file("long_id.vcd", vcd_ + "1" + huge + "\n");
  expect_refused("long_id.vcd",
                 "long_id.vcd:" + next_line + ": undeclared identifier '" + cut + "'",
                 "a long identifier");
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
  ASSERT_GT(vc.len, 1500u);  // 1532 bytes since one value per signal and time (s22-wave)
  for (std::size_t i = vc.pos + 70; i < vc.pos + 1470; ++i) {
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
                 "nohier.fst:0: not a readable FST file (corrupt: the hierarchy has 0 of the 15 "
                 "variables of the header)",
                 "hierarchy overwritten");
  // The good pair is the same waveform: the checks do not refuse a good file.
  EXPECT_EQ(dpc31("wavediff good.vcd good.fst").rc, 0);
}

// docs/wavediff.md, "Errors (exit 2)": one pipe named as A and B (`/dev/stdin` twice, or
// `/dev/stdin` and `/dev/fd/0`) is one stream, read once: B got what A's reader left, and the line
// was a header error in the middle of the file (`/dev/stdin:1: unexpected '…' in the header`). A
// standard input from a file opens anew for each side and compares.
TEST_F(BadWaves, OneStreamAsBothSidesIsRefused) {
  spit(path("old.json"), "old");
  const auto before = listing();
  for (const char* b : {"/dev/stdin", "/dev/fd/0"}) {
    const Outcome r =
        dpc31(std::string("wavediff /dev/stdin ") + b + " --json old.json", "cat good.vcd |");
    expect_bad(r,
               std::string(b) +
                   ":0: the same stream as A (/dev/stdin), which can be read only once: save it "
                   "to a file to compare it with itself",
               b);
    EXPECT_EQ(r.out, "") << b;
    EXPECT_EQ(slurp(path("old.json")), "old") << b;
    EXPECT_EQ(listing(), before) << b;
  }
  const Outcome from_file = dpc31("wavediff /dev/stdin /dev/stdin < good.vcd");
  EXPECT_EQ(from_file.rc, 0) << from_file.err;
  EXPECT_NE(from_file.out.find("\nresult: same\n"), std::string::npos) << from_file.out;
}

TEST_F(BadWaves, MapFileOptionsAndOutputs) {
  fs::create_directory(path("dir"));
  file("bad.map", "# renames\ndpc31.pins.rxd =\n");
  expect_refused("good.vcd --map bad.map",
                 "bad.map:2: expected 'nameA = nameB' (one name on each side)", "map garbage");
  expect_refused("good.vcd --map missing.map",
                 "missing.map:0: cannot open: No such file or directory", "map missing");
  expect_refused("good.vcd --map dir", "dir:0: cannot open: is a directory", "map directory");
  const std::string name(100, 'n');
  file("long.map", name + " = a\n" + name + " = b\n");
  expect_refused("good.vcd --map long.map",
                 "long.map:2: '" + std::string(40, 'n') + "...' is already mapped on line 1",
                 "map: a long name twice");
  // A line holds two names (a full name has at most 16 KiB): 64 KiB at most.
  file("edge.map", std::string(65536, '#') + "\n");
  EXPECT_EQ(dpc31("wavediff good.vcd good.vcd --map edge.map").rc, 0);
  file("longline.map", "# renames\n#" + std::string(65536, ' ') + "\n");
  expect_refused("good.vcd --map longline.map", "longline.map:2: line longer than 65536 bytes",
                 "map: a line over the bound");
  // A control byte in a line: no signal name holds one (a NUL cut the name where it was printed,
  // and a self-comparison said "different").
  file("nul.map", std::string("dpc31.pins.rxd\0junk = dpc31.pins.rxd\n", 37));
  expect_refused("good.vcd --map nul.map", "nul.map:1: a NUL byte: not a text file", "map NUL");
  file("esc.map", "# colours\nx = y\x1b[31m\n");
  expect_refused("good.vcd --map esc.map", "esc.map:2: a control byte \\x1B: not a text file",
                 "map ESC");
  // A name quoted in a warning is shown as in an error: other bytes as \xHH.
  file("high.map", "x\xff = y\xfe\n");
  const Outcome high = dpc31("wavediff good.vcd good.vcd --map high.map");
  EXPECT_EQ(high.err,
            "high.map:1: warning: no signal 'x\\xFF' in A\n"
            "high.map:1: warning: no signal 'y\\xFE' in B\n");
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
                      "no/such/x: cannot create the temporary file no/such/.dpc31-", o);
    EXPECT_EQ(listing(), before) << o;
    // Among good outputs: none of them is written.
    const std::string all = outputs_one_taken({"--json", "--diff-vcd", "--wavedrom"}, o);
    expect_bad(dpc31("wavediff good.vcd good.fst" + all), "taken: cannot write: is a directory",
               o + " among good outputs");
    EXPECT_EQ(listing(), before) << o;
  }
  for (const char* args : {"good.vcd", "good.vcd good.vcd --xz maybe", "a b c"}) {
    expect_bad_prefix(dpc31(std::string("wavediff ") + args), "dpc31 wavediff: ", args);
  }
}

}  // namespace
