// Bad input everywhere (docs/bad-input.md): every subcommand of the real `dpc31` binary, given a
// missing, empty, truncated or garbage input file or a bad option value, prints exactly one line
// on stderr and exits 2, and leaves no output file and no temporary behind; an output file that
// was there before is left untouched.
#include "bad_input.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "dpc31/dpc31_firmware.h"
#include "dpc31_rtl_model.h"

using namespace badinput;

namespace {

// " --json taken --vcd new-vcd ...": every output option, `taken` (a directory) for `bad`, a new
// file for the others. Appended piece by piece: the operator+ chain it replaces made GCC 12 at
// -O3 report a false -Wrestrict (issue 17).
std::string outputs_one_taken(std::initializer_list<const char*> options, const std::string& bad) {
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

// --- dpc31 run: the scenario file, its options and its outputs ------------------------------

struct FileCase {
  std::string name;
  std::string path;
  std::string line;  // the one line expected on stderr
};

TEST_F(BadInput, RunScenarioFile) {
  const std::string good = copy(kTraces + "gc_clear_spc3.scn", "good.scn");
  // The good scenario up to its first expect (its start-up and one exchange).
  const std::string head = slurp(good).substr(0, slurp(good).find("expect"));
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
      // A fault whose request is the cut line: the file is cut, not "no request follows" at the
      // fault's line (a check of the whole file names that line only because of the cut).
      {"cut after a fault", file("cut_fault.scn", head + "bad_fcs\nexchange 1 outputs=0F"),
       path("cut_fault.scn") + ":" +
           std::to_string(std::count(head.begin(), head.end(), '\n') + 2) +
           ": truncated: the last line has no end of line"},
      // A binary file seldom ends in a newline: its first line is what is wrong, not its end.
      {"garbage cut",
       file("garbage_cut.scn",
            "\x7f"
            "ELF\x01\x02\x03\n\xff\xfe"),
       path("garbage_cut.scn") + ":1: unknown command '\\x7FELF\\x01\\x02\\x03'"},
      // A segment scenario's bad lines (docs/scenario-format.md, "Segments"): the same rules.
      {"segment: a slave no station",
       file("seg_slave.scn", "segment\nstation 5\nmaster 2 slaves=5,9\nstartup\n"),
       path("seg_slave.scn") + ":3: slaves=5,9: no station 9"},
      {"segment: only headers", file("seg_header.scn", "segment\nstation 5\n"),
       path("seg_header.scn") + ": only header commands: nothing to run"},
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

// A scenario's 80C32 or C31 image (docs/cpu.md) is read before the walk starts: a bad one is
// the same one line and exit 2, with nothing printed and no output written.
TEST_F(BadInput, RunCpuImage) {
  // 03h + 02h + 0Bh = 10h: the checksum is F0h (two's complement, Intel's specification), not F1h.
  file("bad.ihx", ":0300000002000BF1\n:00000001FF\n");
  file("empty.ihx", "");
  file("high.ihx", ":02000000A5A5B4\n:00000001FF\n");
  fs::create_directory(path("dir.ihx"));
  file("eof.ihx", ":00000001FF\n");
  file("overlap.ihx", ":020000000000FE\n:0100010000FE\n:00000001FF\n");
  file("seg.ihx", ":020000020100FB\n:0200000080FE80\n:00000001FF\n");
  const std::vector<FileCase> cases = {
      {"bad checksum", file("sum.scn", "cpu 80c32 firmware bad.ihx\nstartup\n"),
       path("sum.scn") + ":1: " + path("bad.ihx") + ":1: checksum F1h, expected F0h"},
      {"missing", file("missing.scn", "cpu 80c32 firmware none.ihx\nstartup\n"),
       path("missing.scn") + ":1: " + path("none.ihx") + ": no such file"},
      {"directory", file("dir.scn", "cpu 80c32 firmware dir.ihx\nstartup\n"),
       path("dir.scn") + ":1: " + path("dir.ihx") + ": is a directory, not an Intel HEX file"},
      {"empty", file("empty.scn", "cpu 80c32 firmware empty.ihx\nstartup\n"),
       path("empty.scn") + ":1: " + path("empty.ihx") + ": empty file, not an Intel HEX image"},
      {"C31 past 1FFFh",
       file("c31.scn", "profile dpc31\ncpu c31 firmware high.ihx code=0x1FFF\nstartup\n"),
       path("c31.scn") + ":2: " + path("high.ihx") +
           ": the image does not fit the C31's code area (1FFFh..1FFFh)"},
      {"only the end record", file("eof.scn", "cpu 80c32 firmware eof.ihx\nstartup\n"),
       path("eof.scn") + ":1: " + path("eof.ihx") +
           ":1: no data bytes before the end-of-file record: an empty image"},
      {"overlapping records", file("overlap.scn", "cpu 80c32 firmware overlap.ihx\nstartup\n"),
       path("overlap.scn") + ":1: " + path("overlap.ihx") +
           ":2: data at 0001h overlaps an earlier record"},
      {"a segment base", file("seg.scn", "cpu 80c32 firmware seg.ihx\nstartup\n"),
       path("seg.scn") + ":1: " + path("seg.ihx") +
           ":1: a non-zero segment base 0100h (only 0000h is taken)"},
  };
  spit(path("old.json"), "old");
  const auto before = listing();
  for (const FileCase& c : cases) {
    const Outcome r = dpc31("run " + c.path + " --json old.json --record new.trace");
    expect_bad(r, c.line, c.name);
    EXPECT_EQ(r.out, "") << c.name;  // nothing ran
    EXPECT_EQ(slurp(path("old.json")), "old") << c.name;
    EXPECT_EQ(listing(), before) << c.name;
  }
}

// An image whose program is SJMP $ (80 FE), for the doors that need one that loads.
constexpr const char* kHalt = ":0200000080FE80\n:00000001FF\n";

// The board set-ups that cannot work are refused at every door, by one check (Cpu51Config::
// chip_problem): the 80C32 drives the chip's Intel mode and takes X/INT on INT0, which the C31's
// interrupt controller leaves inactive; the C31 serves that controller.
TEST_F(BadInput, CpuBoardSetUpsThatCannotWork) {
  file("halt.ihx", kHalt);
  const std::string motorola =
      "the 80C32 drives the chip in Intel mode (its multiplexed bus): not on the Motorola bus";
  const std::string c31_irq =
      "the 80C32 takes X/INT on INT0, which the C31's interrupt controller leaves inactive: its "
      "firmware would never be interrupted";
  const std::vector<FileCase> cases = {
      {"motorola after cpu", file("m1.scn", "cpu 80c32 firmware halt.ihx\nbus motorola\nstartup\n"),
       path("m1.scn") + ":1: " + motorola},
      {"motorola before cpu",
       file("m2.scn", "bus motorola\ncpu 80c32 firmware halt.ihx\nstartup\n"),
       path("m2.scn") + ":2: " + motorola},
      {"the C31's controller",
       file("i1.scn", "profile dpc31\nirq-controller c31\ncpu 80c32 firmware halt.ihx\nstartup\n"),
       path("i1.scn") + ":3: " + c31_irq},
      {"the C31 without its controller",
       file("i2.scn",
            "profile dpc31\ncpu c31 firmware halt.ihx\nirq-controller external\nstartup\n"),
       path("i2.scn") + ":2: the C31 serves its own interrupt controller: irq-controller external "
                        "contradicts it"},
  };
  for (const FileCase& c : cases) {
    const Outcome r = dpc31("run " + c.path);
    expect_bad(r, c.line, c.name);
    EXPECT_EQ(r.out, "") << c.name;
  }
  expect_bad(dpc31("bridge --tcp 0 --profile dpc31 --irq-controller c31 --cpu 80c32 --firmware "
                   "halt.ihx"),
             "dpc31 bridge: --cpu 80c32: " + c31_irq, "bridge");
  expect_bad(dpc31("serve --unix s --profile dpc31 --irq-controller c31 --cpu 80c32 --firmware "
                   "halt.ihx"),
             "dpc31 serve: --cpu 80c32: " + c31_irq, "serve, the C31's controller");
  expect_bad(dpc31("serve --unix s --bus motorola --cpu 80c32 --firmware halt.ihx"),
             "dpc31 serve: --cpu 80c32: " + motorola, "serve, motorola");
  EXPECT_FALSE(fs::exists(path("s")));
}

// A board whose ports nobody names has DO4's latch, N = 2 bytes (docs/cpu.md, "DO4 on the
// 80C32": the module's outputs go to 4000h + port, DO4's `outputs` and `modul_ok`; docs/bridge.md,
// `--ports`' default): a window from 4000h + N - 1 covers its last byte, one from 4000h + N does
// not. Every door gives the same verdict with the same words (Cpu51Config::latch_ports): the
// scenario accepted 4001h and the bridge and serve refused it. An accepted board goes on to read
// its image, here one with a bad checksum, so each door stops at the image instead.
TEST_F(BadInput, EveryDoorTakesTheSameDefaultLatch) {
  file("bad.ihx", ":0300000002000BF1\n:00000001FF\n");
  const std::string covered = "the chip's window covers the output latch at 0x4000";
  const auto scenario = [&](const std::string& base) {
    return dpc31("run " + file("b" + base + ".scn",
                               "cpu 80c32 firmware bad.ihx base=" + base + "\nstartup\n"));
  };
  const auto door = [&](const std::string& command, const std::string& base) {
    return dpc31(command + " --cpu 80c32 --firmware bad.ihx --board-address " + base);
  };
  expect_bad(scenario("0x4001"), path("b0x4001.scn") + ":1: " + covered, "scenario, 4001h");
  expect_bad(door("bridge --tcp 0", "0x4001"), "dpc31 bridge: --board-address 0x4001: " + covered,
             "bridge, 4001h");
  expect_bad(door("serve --unix s", "0x4001"), "dpc31 serve: --board-address 0x4001: " + covered,
             "serve, 4001h");
  expect_bad(scenario("0x4002"),
             path("b0x4002.scn") + ":1: " + path("bad.ihx") + ":1: checksum F1h, expected F0h",
             "scenario, 4002h");
  expect_bad(door("bridge --tcp 0", "0x4002"),
             "dpc31 bridge: bad.ihx:1: checksum F1h, expected F0h", "bridge, 4002h");
  expect_bad(door("serve --unix s", "0x4002"), "dpc31 serve: bad.ihx:1: checksum F1h, expected F0h",
             "serve, 4002h");
  EXPECT_FALSE(fs::exists(path("s")));
}

// Port names travel in protocol lines (`serve`'s `latch` replies, blank-separated) and in
// `expect port`: only words are names, at every door (Cpu51Config::ports_problem).
TEST_F(BadInput, CpuPortNamesAreWords) {
  file("halt.ihx", kHalt);
  const std::string word = "a port name is letters, digits and '_', not starting with a digit";
  expect_bad(dpc31("run " + file("p.scn", "cpu 80c32 firmware halt.ihx ports=a=b,c\nstartup\n")),
             path("p.scn") + ":1: ports=: port 'a=b': " + word, "scenario");
  expect_bad(dpc31("run " + file("d.scn", "cpu 80c32 firmware halt.ihx ports=out,2nd\nstartup\n")),
             path("d.scn") + ":1: ports=: port '2nd': " + word, "scenario, a digit first");
  expect_bad(dpc31("bridge --tcp 0 --cpu 80c32 --firmware halt.ihx --ports 'a b,c'"),
             "dpc31 bridge: --ports 'a b,c': port 'a b': " + word, "bridge");
  // A newline would forge a protocol line: shown, not written.
  expect_bad(
      dpc31("serve --unix s --cpu 80c32 --firmware halt.ihx --ports \"$(printf 'x\\nOK y')\""),
      "dpc31 serve: --ports 'x\\x0AOK y': port 'x\\x0AOK y': " + word, "serve");
  EXPECT_FALSE(fs::exists(path("s")));
}

// '' is not "not given" for an option that is not a file either (the same CLI11 check's wording).
TEST_F(BadInput, EmptyOptionValues) {
  const auto before = listing();
  for (const std::string sub : {"bridge", "serve"}) {
    for (const char* o : {"--cpu", "--ports", "--board-address", "--code", "--tcp"}) {
      expect_bad(dpc31(sub + " " + o + " ''"),
                 "dpc31 " + sub + ": " + o + ": an empty value: give one, or leave the option out",
                 sub + " " + o);
    }
  }
  EXPECT_EQ(listing(), before);
}

// A map only names places: one over 4 MiB is not read, and the run says so in its board line
// and goes on with addresses (it stopped every door).
TEST_F(BadInput, ATooLargeMapIsSkippedWithANote) {
  file("halt.ihx", kHalt);
  file("halt.map", "");
  fs::resize_file(path("halt.map"), (4u << 20) + 1);
  const Outcome r = dpc31("run " + file("m.scn", "cpu 80c32 firmware halt.ihx\nstartup\n"));
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("halt.ihx (2 bytes, " + path("halt.map") +
                       " not read (more than 4194304 bytes): code addresses unnamed)"),
            std::string::npos)
      << r.out;
}

// A firmware writing its latch in a loop: the walk's port-write lines are bounded as the chip's
// log is (1 000 in 48 000 000 cycles, then one line with the count left out); `expect port` and
// the outcome's port_writes still see every write.
TEST_F(BadInput, ALatchWrittenInALoopDoesNotFloodTheWalk) {
  // MOV DPTR,#4000h; loop: MOVX @DPTR,A; INC A; SJMP loop (5 machine cycles, 2.5 us at 24 MHz).
  file("flood.ihx", ":07000000904000F00480FCB9\n:00000001FF\n");
  const std::string scn = file("f.scn",
                               "cpu 80c32 clock=24000000 firmware flood.ihx ports=p0\n"
                               "slave address=7\nsilence 20ms\n");
  const Outcome r = dpc31("run " + scn);
  EXPECT_EQ(r.rc, 0) << r.err;
  std::istringstream walk(r.out);
  std::size_t shown = 0;
  std::uint64_t left = 0;
  const std::string said = "80C32 port writes: ";
  for (std::string l; std::getline(walk, l);) {
    shown += l.find(": p0 = ") != std::string::npos ? 1 : 0;
    if (const auto at = l.find(said); at != std::string::npos) {
      EXPECT_EQ(left, 0u) << "a second count: " << l;
      left = std::stoull(l.substr(at + said.size()));
      EXPECT_NE(l.find(" log lines left out (at most 1000 in 48000000 cycles)"), std::string::npos)
          << l;
    }
  }
  EXPECT_EQ(shown, 1000u);
  EXPECT_GT(shown + left, 7000u);  // 20 ms / 2.5 us, less the start-up
  EXPECT_LT(r.out.size(), 200'000u);
}

TEST_F(BadInput, RunOptionValues) {
  const std::string scn = kTraces + "gc_clear_spc3.scn";
  spit(path("old.vcd"), "old");
  const auto before = listing();
  // Ours: checked after the scenario parsed, before anything is written. The line names what is
  // accepted (docs/waveforms.md: 1fs .. 10ns at 48 MHz), not us, ms or 1s: each is longer than a
  // clock cycle and refused too.
  expect_bad(dpc31("run " + scn + " --vcd old.vcd --timescale 3ns"),
             "dpc31 run: --timescale '3ns': use 1, 10 or 100 fs or ps, or 1 or 10 ns", "timescale");
  // Above 1 s: refused all the same.
  expect_bad(dpc31("run " + scn + " --la-vcd old.vcd --timescale 10s"),
             "dpc31 run: --timescale '10s': use 1, 10 or 100 fs or ps, or 1 or 10 ns",
             "timescale above 1 s");
  // A waveform's option without a waveform acts on nothing: refused whatever its value ("No
  // silent options"; a good --timescale, --signals, --from and --to were ignored), for one chip
  // and for a segment.
  const std::string any = ": a waveform option needs --vcd, --fst or --la-vcd";
  for (const std::string& s : {scn, kTraces + "segment/two_masters.scn"}) {
    for (const auto& [args, line] : std::vector<std::pair<std::string, std::string>>{
             {"--timescale ps", "--timescale ps" + any},
             {"--timescale 1ns", "--timescale 1ns" + any},
             {"--signals nomatch", "--signals nomatch" + any},
             {"--signals 'pins.*,state.*'", "--signals pins.*,state.*" + any},
             {"--from 10 --to 20", "--from 10" + any},
             {"--to 20", "--to 20" + any},
             {"--from 0", "--from 0" + any},
             {"--flat", "--flat: a waveform option needs --vcd or --fst"},
             {"--flat --la-vcd new.vcd", "--flat: a waveform option needs --vcd or --fst"}}) {
      const Outcome r = dpc31("run " + s + " " + args);
      expect_bad(r, "dpc31 run: " + line, s + " " + args);
      EXPECT_EQ(r.out, "") << args;  // nothing ran
    }
  }
  // --la-vcd is a waveform: the options act on it.
  const Outcome la = dpc31("run " + scn +
                           " --quiet --la-vcd new.vcd --signals 'pins.*' --from 10 "
                           "--to 100000 --timescale 1ns");
  EXPECT_EQ(la.rc, 0) << la.err;
  EXPECT_TRUE(fs::remove(path("new.vcd")));
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
  // The engine's names only (README.md, docs/engine.md): not the enum's numbers.
  expect_bad(dpc31("run " + scn + " --engine 1"), "dpc31 run: --engine: 1 not in {event,per-cycle}",
             "engine number");
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
                      "dpc31 run: no/such/x: cannot create the temporary file no/such/.dpc31-",
                      o + " missing directory");
    expect_bad_prefix(
        dpc31("run " + scn + " --quiet " + o + " " + ro + "/x"),
        "dpc31 run: " + ro + "/x: cannot create the temporary file " + ro + "/.dpc31-",
        o + " unwritable");
    EXPECT_TRUE(fs::is_empty(path("taken"))) << o;
    EXPECT_EQ(listing(), before) << o;
    // The same among good outputs: none of them is written either.
    const std::string all =
        outputs_one_taken({"--json", "--record", "--vcd", "--fst", "--pcap"}, o);
    expect_bad(dpc31("run " + scn + " --quiet" + all),
               "dpc31 run: taken: cannot write: is a directory", o + " among good outputs");
    EXPECT_EQ(listing(), before) << o;
  }
}

// The waveforms' files and --signals are checked before the run like the other outputs: without
// --quiet, nothing of the state walk is printed before the one line (it printed the whole walk
// first: the recorder opened its file and matched its globs as the chip started).
TEST_F(BadInput, RunWaveformOutputsAreCheckedBeforeTheWalk) {
  const std::string scn = kTraces + "startup_dpc31_1m5.scn";
  fs::create_directory(path("taken"));
  const auto before = listing();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--vcd no/such/x.vcd", "dpc31 run: no/such/x.vcd: cannot create the temporary file "},
      {"--fst taken", "dpc31 run: taken: cannot write: is a directory"},
      {"--la-vcd taken", "dpc31 run: taken: cannot write: is a directory"},
      {"--vcd new.vcd --gtkw taken", "dpc31 run: taken: cannot write: is a directory"},
      {"--vcd new.vcd --signals 'nomatch*'",
       "dpc31 run: no signal matches 'nomatch*' (see docs/waveforms.md)"},
  };
  for (const auto& [args, line] : cases) {
    const Outcome r = dpc31("run " + scn + " --pcap new.pcapng " + args);
    expect_bad_prefix(r, line, args);
    EXPECT_EQ(r.out, "") << args;  // nothing ran
    EXPECT_TRUE(fs::is_empty(path("taken"))) << args;
    EXPECT_EQ(listing(), before) << args;
  }
  // The same run with good outputs prints its walk.
  const Outcome ok = dpc31("run " + scn + " --pcap new.pcapng --vcd new.vcd --signals 'pins.*'");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_NE(ok.out, "");
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
      {"garbage cut",
       file("garbage_cut.trace",
            "\x7f"
            "ELF\x01\x02\x03\n\xff\xfe\nx"),
       path("garbage_cut.trace") +
           ":1: not a dpc31 trace (the first line must be 'dpc31-trace 1')"},
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
    const std::string name = "h" + std::to_string(i++) + ".stim";
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
  // seed not its own, a count that is not its results'.
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
      "dpc31 cosim merge: cut_results.json: 1 results for its 2 seeds from 1 to 3" + incomplete,
      "results cut");
  expect_bad(dpc31(merge + "foreign_seed.json s2.json"),
             "dpc31 cosim merge: foreign_seed.json: result 1 is seed 999999, not 1: not its seeds "
             "from 1 to 3 in order" +
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

// --- regs, demo ---------------------------------------------------------------------------------

TEST_F(BadInput, RegsAndDemoOptions) {
  expect_bad(dpc31("regs --profile all --format text"),
             "dpc31 regs: --format text needs one profile, not all", "all text");
  // A first word that is no subcommand is named, with the ones there are.
  expect_bad(dpc31("frob --x"),
             "dpc31: unknown subcommand 'frob' (demo, regs, run, replay, cosim, wavediff, serve, "
             "bridge, bench, soak)",
             "unknown subcommand");
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
  // A bad --timescale: one line before the output directory is made or anything printed.
  r = dpc31("demo --out-dir fresh --timescale 1min");
  expect_bad(r, "dpc31 demo: --timescale '1min': use 1, 10 or 100 fs or ps, or 1 or 10 ns",
             "demo timescale");
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(path("fresh")));
  r = dpc31("demo --out-dir plain/sub");
  expect_bad_prefix(
      r, "dpc31 demo: plain/sub: cannot create the output directory: ", "out-dir below a file");
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(slurp(path("plain")), "old");
  EXPECT_EQ(listing(), before);
}

// Each of the demo's files that cannot be written (here a directory in its place) is one line
// naming it, "dpc31 demo: ...", before anything is printed; nothing of the others is left.
TEST_F(BadInput, DemoOutputsAreCheckedBeforeAnythingIsPrinted) {
  for (const char* name :
       {"dpc31-demo.vcd", "dpc31-demo-la.vcd", "dpc31-demo.gtkw", "dpc31-demo.pcapng"}) {
    const std::string dir = std::string("out-") + name;
    fs::create_directories(path(dir + "/" + name));
    const Outcome r = dpc31("demo --out-dir " + dir);
    expect_bad(r, "dpc31 demo: " + dir + "/" + name + ": cannot write: is a directory", name);
    EXPECT_EQ(r.out, "") << name;
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(path(dir)))
      left.push_back(e.path().filename().string());
    EXPECT_EQ(left, std::vector<std::string>{name});
    EXPECT_TRUE(fs::is_empty(path(dir + "/" + name))) << name;
  }
  // The good case: the demo prints its story and writes its four files.
  const Outcome ok = dpc31("demo --out-dir good");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_NE(ok.out, "");
  EXPECT_EQ(std::distance(fs::directory_iterator(path("good")), fs::directory_iterator()), 4);
  // Without --out-dir, a TMPDIR that is no directory is named (the library gives no path then).
  const Outcome gone = dpc31("demo", "TMPDIR=" + path("none"));
  expect_bad(gone,
             "dpc31 demo: cannot create a directory in TMPDIR=" + path("none") +
                 ": No such file or directory",
             "TMPDIR");
  EXPECT_EQ(gone.out, "");
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

// --irq-controller external|c31 where --variant is, but not on cosim (docs/dpc31.md): c31 only
// with --profile dpc31, and only those two names. One line, exit 2, nothing on stdout.
TEST_F(BadInput, IrqControllerOptions) {
  for (const std::string sub :
       {"demo", "soak --cycles 1000", "serve --tcp 0", "bridge --pty dp0 --firmware DO4"}) {
    const std::string name = sub.substr(0, sub.find(' '));
    const Outcome r = dpc31(sub + " --profile spc3 --irq-controller c31");
    expect_bad(r,
               "dpc31 " + name +
                   ": --irq-controller c31 is for --profile dpc31: only the DPC31 has a C31 core",
               sub);
    EXPECT_EQ(r.out, "") << sub;
    // external too: no choice off the dpc31, so no silent option (docs/decisions.md).
    expect_bad(dpc31(sub + " --profile vpc3plus --irq-controller external"),
               "dpc31 " + name +
                   ": --irq-controller external is for --profile dpc31: only the DPC31 has a C31 "
                   "core",
               sub + " external");
    const Outcome x = dpc31(sub + " --profile dpc31 --irq-controller cpu");
    expect_bad_prefix(x, "dpc31 " + name + ": --irq-controller", sub + " cpu");
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

// A library that exports the entry name as the wrong kind of symbol (docs/bring-up.md, section 3:
// one line, exit 2, never a crash; s29-sec, finding 6): dpc31/dpc31_firmware.h declares the
// descriptor a pointer, dpc31_rtl_model.h dpc31_rtl_model_get a function. They crashed (SIGSEGV).
TEST_F(BadInput, PluginEntrySymbolsOfTheWrongKindAreRefused) {
  for (const auto& [lib, is] : std::vector<std::pair<std::string, std::string>>{
           {WRONG_SYMBOL_FW_INT, "data of 4 bytes"}, {WRONG_SYMBOL_FW_FUNC, "a function"}}) {
    const std::string line = "firmware plug-in " + lib + ": dpc31_firmware_descriptor is " + is +
                             ", not the pointer dpc31/dpc31_firmware.h declares";
    expect_bad(dpc31("soak --cycles 1000 --firmware " + lib), "dpc31 soak: " + line, lib);
    expect_bad(dpc31("bridge --pty p --firmware " + lib), "dpc31 bridge: " + line, lib);
    expect_bad(dpc31("demo --firmware " + lib), "dpc31 demo: " + line, lib);
    file("plugin.scn", "firmware " + lib + "\nstartup\n");
    expect_bad(dpc31("run plugin.scn"), "plugin.scn:1: " + line, lib);
  }
  const std::string rtl = WRONG_SYMBOL_RTL_INT;
  expect_bad(dpc31("cosim --rtl-model " + rtl + " --seeds 1 --cycles 100"),
             "dpc31 cosim: " + rtl +
                 ": dpc31_rtl_model_get is data of 4 bytes, not the function dpc31_rtl_model.h "
                 "declares",
             "rtl-model");
  EXPECT_EQ(listing(), std::vector<std::string>{"plugin.scn"});
}

// A --rtl-model's table (dpc31_rtl_model.h) is checked before any entry is used: one line that
// names what is wrong, exit 2, never a NULL called (rtl_model_table.c).
TEST_F(BadInput, RtlModelTablesAreCheckedBeforeUse) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {RTL_TABLE_GET_NULL, "dpc31_rtl_model_get() returned NULL, not a model"},
      {RTL_TABLE_OLD_ABI, "model interface version 3, this harness needs " +
                              std::to_string(DPC31_RTL_MODEL_ABI) +
                              " (rebuild it against this dpc31emu)"},
      {RTL_TABLE_OUTPUTS_30,
       "the model has 30 outputs, this harness compares 31 (DPC31_RTL_OUTPUTS)"},
      {RTL_TABLE_NULL_STEP, "the model's step is NULL"},
      {RTL_TABLE_NO_PROFILE, "the model's profile is NULL"},
      {RTL_TABLE_BAD_PROFILE, "the model's profile 'dpc32' is not spc3, vpc3plus or dpc31"},
      // Built with PROFILE spc3, run on the default dpc31: every seed would differ at cycle 0.
      {RTL_TABLE_SPC3,
       "the model is built for profile spc3, not dpc31: run it with --profile spc3 (a session: a "
       "scenario of that profile), or build it with PROFILE dpc31"},
      // The header: "NULL when out of memory".
      {RTL_TABLE_CREATE_NULL, "its create() returned NULL: no model to run (out of memory?)"}};
  for (const auto& [lib, why] : cases) {
    expect_bad(dpc31("cosim --rtl-model " + lib + " --seeds 1 --cycles 100 --out o"),
               "dpc31 cosim: " + lib + ": " + why, lib);
  }
  EXPECT_TRUE(listing().empty());
}

// A model that cannot trace leaves the divergence's exit code 1, with a note that says why there
// is no rtl_internal.fst (docs/golden-model.md, "On a divergence"); a mutant of rtl/dpc31_blocks.v
// by name is refused on a profile the built-in one is refused on.
TEST_F(BadInput, RtlModelWithoutTracingOrMutantOfAnotherProfile) {
  const std::string zero = RTL_TABLE_NO_TRACE;
  // Every output 0: the C++ blocks differ at cycle 0. The window (--vcd) and the whole run
  // (--dump) are written but for rtl_internal.fst, which is the note.
  for (const std::string dir : {"w", "d"}) {
    const Outcome r = dpc31("cosim --rtl-model " + zero + " --seeds 1 --cycles 100 --out o " +
                            (dir == "w" ? "--vcd " : "--dump ") + dir);
    EXPECT_EQ(r.rc, 1) << r.err;
    EXPECT_NE(r.err.find(dir + "/rtl_internal.fst: not written: the RTL model " + zero +
                         " did not trace (its trace_to returned 0)\n"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(fs::exists(path(dir + "/emu.vcd"))) << dir;
    EXPECT_FALSE(fs::exists(path(dir + "/rtl_internal.fst"))) << dir;
  }
  const std::string sel = RTL_TABLE_MUTANT_SEL;
  expect_bad(dpc31("cosim --rtl-model " + sel + " --mutant SAP_NO_RR --seeds 1 --cycles 100"),
             "dpc31 cosim: mutant 'SAP_NO_RR' is built for profile vpc3plus, not dpc31 (--profile "
             "vpc3plus)",
             "SAP_NO_RR on dpc31");
}

// Firmware plug-ins (dpc31/dpc31_firmware.h) are checked at load: the library loads with every
// symbol resolved, exports the descriptor, has this host's ABI version and the required fields.
// The same checks behind `bridge --firmware` and the scenario header `firmware`.
TEST_F(BadInput, FirmwarePlugins) {
  const std::string abi = BAD_PLUGIN_BAD_ABI;
  const std::string no_init = BAD_PLUGIN_NO_INIT;
  const std::string bad_port = BAD_PLUGIN_BAD_PORT;
  const std::string twice_input = BAD_PLUGIN_TWICE_INPUT;
  const std::string no_export = BAD_PLUGIN_NO_EXPORT;
  const std::string undefined = BAD_PLUGIN_UNDEFINED;
  const std::string version = std::to_string(DPC31_FIRMWARE_ABI_VERSION);
  const std::vector<std::pair<std::string, std::string>> exact = {
      {abi, "firmware plug-in " + abi + ": descriptor ABI version " +
                std::to_string(DPC31_FIRMWARE_ABI_VERSION + 1) + ", this host takes " + version +
                " (rebuild it against this dpc31emu)"},
      {no_init, "firmware plug-in " + no_init + ": the descriptor has no init"},
      // The names `expect port` and `hw` take, checked in the words of `cpu 80c32 ports=`.
      {bad_port, "firmware plug-in " + bad_port +
                     ": the descriptor's ports: port 'out puts': a port name is letters, digits "
                     "and '_', not starting with a digit"},
      {twice_input,
       "firmware plug-in " + twice_input + ": the descriptor's inputs: input 'kick' named twice"},
      {no_export, "firmware plug-in " + no_export +
                      " exports no dpc31_firmware_descriptor (DPC31_FIRMWARE_EXPORT, "
                      "dpc31/dpc31_firmware.h)"},
  };
  for (const auto& [lib, line] : exact) {
    expect_bad(dpc31("bridge --pty p --firmware " + lib), "dpc31 bridge: " + line, lib);
    file("plugin.scn", "firmware " + lib + "\nstartup\n");
    expect_bad(dpc31("run plugin.scn"), "plugin.scn:1: " + line, lib);
  }
  // dlopen's own wording after ours: an unresolved symbol, a missing file, not an ELF file.
  const std::string garbage = file("garbage.so", "not a library\n");
  for (const std::string& lib : {undefined, path("missing.so"), garbage}) {
    expect_bad_prefix(dpc31("bridge --pty p --firmware " + lib),
                      "dpc31 bridge: cannot load firmware plug-in: " + lib, lib);
  }
  expect_bad_prefix(dpc31("bridge --pty p --firmware " + undefined),
                    "dpc31 bridge: cannot load firmware plug-in: " + undefined +
                        ": undefined symbol: no_such_board_function",
                    "undefined symbol named");
  // An Intel HEX image where a plug-in is named (--cpu forgotten, `firmware` for `cpu`): a hint.
  const std::string ihx = file("fw.ihx",
                               ":1000000000000000000000000000000000000000F0\n"
                               ":1000100000000000000000000000000000000000E0\n:00000001FF\n");
  const std::string hint =
      "; it is an Intel HEX image, a CPU's program: add --cpu 80c32 (in a scenario: cpu 80c32 "
      "firmware FILE)\n";
  file("plugin.scn", "firmware ./fw.ihx\nstartup\n");
  for (const auto& [r, prefix] :
       {std::pair{dpc31("bridge --pty p --firmware " + ihx), std::string("dpc31 bridge: ")},
        std::pair{dpc31("run plugin.scn"), std::string("plugin.scn:1: ")}}) {
    expect_bad_prefix(r, prefix + "cannot load firmware plug-in: " + ihx + ": ", prefix);
    EXPECT_TRUE(r.err.ends_with(hint)) << r.err;
  }
  std::filesystem::remove(ihx);
  // A bare file name ending in .so is a file in the current directory, not a library-path name.
  expect_bad_prefix(dpc31("bridge --pty p --firmware libdpc31_fw_do4.so"),
                    "dpc31 bridge: cannot load firmware plug-in: ./libdpc31_fw_do4.so", "./");
  EXPECT_EQ(listing(), (std::vector<std::string>{"garbage.so", "plugin.scn"}));
  // A directory in its place is no library (not code another user could have changed).
  expect_bad(dpc31("bridge --pty p --firmware " + path("")),
             "dpc31 bridge: cannot load firmware plug-in: " + path("") + ": is a directory",
             "directory");
  // A firmware that spins without a bus access: the hang guard stops the process after 2 s of
  // host time, with one line, and takes the bridge's symlink away.
  const std::string spin = BAD_PLUGIN_SPIN;
  const std::string hangs =
      " hangs: it ran 2000 ms of host time without a bus access or a board hook call (a while(1) "
      "loop, e.g. its fatal-error handler?); stopped";
  expect_bad(dpc31("bridge --pty p --firmware " + spin), "dpc31 bridge: firmware BAD" + hangs,
             "spin");
  // A scenario's line names its file and the `firmware` line (docs/bring-up.md, section 4).
  file("spin.scn", "# spins\nfirmware " + spin + "\nstartup\n");
  expect_bad(dpc31("run spin.scn --json spin.json"), "dpc31 run: spin.scn:2: firmware BAD" + hangs,
             "spin in run");
  expect_bad(dpc31("cosim --session spin.scn"), "dpc31 cosim: spin.scn:2: firmware BAD" + hangs,
             "spin in cosim --session");
  // On a segment several stations may run one firmware: the line names the scenario, as the fault
  // line does, and the station that spins (docs/bring-up.md, section 4).
  const std::string stations = "segment\nstation 5 profile=spc3 firmware=DO4\n";
  file("segspin.scn", stations + "station 6 profile=spc3 firmware=" + spin + "\nstartup\n");
  expect_bad(dpc31("run segspin.scn"), "dpc31 run: segspin.scn: station 6: firmware BAD" + hangs,
             "spin on a segment");
  expect_bad(dpc31("bridge --pty p --slave 5:DO4 --slave 7:" + spin),
             "dpc31 bridge: station 7: firmware BAD" + hangs, "spin among --slaves");
  EXPECT_EQ(listing(),
            (std::vector<std::string>{"garbage.so", "plugin.scn", "segspin.scn", "spin.scn"}));
  // A relative path in a scenario is relative to the scenario file: this one runs from work/.
  fs::create_directory(path("sub"));
  copy(PLUGIN_DO4, "sub/libdo4.so");
  file("sub/do4.scn", "firmware ./libdo4.so\nstartup\n");
  const Outcome ok = dpc31("run sub/do4.scn --quiet");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_EQ(ok.err, "");
}

// A firmware that hangs in a step (its ISR spins in `startup`): the guard's line names the step,
// "FILE:LINE: KEYWORD" (docs/bring-up.md, section 4), and the walk printed before the hang is kept
// on stdout, a file here, up to the step's own line, printed as the step begins
// (docs/scenario-format.md, "The walk"). The expected walk is the documented one: master 2 and
// slave 5 by default, the plug-in's init (four writes, docs/timing.md: 4 clocks each) ends at
// cycle 16 without Start_SPC3, the expect and the step take no time before the firmware runs.
TEST_F(BadInput, AFirmwareThatHangsInAStepKeepsTheWalk) {
  const std::string spin = BAD_PLUGIN_SPIN_ISR;
  const std::string hangs =
      " hangs: it ran 2000 ms of host time without a bus access or a board hook call (a while(1) "
      "loop, e.g. its fatal-error handler?); stopped";
  file("isr.scn", "# its ISR spins\nprofile vpc3plus\nfirmware " + spin +
                      "\nexpect dp_state Wait_Prm\nstartup\n");
  const Outcome r = dpc31("run isr.scn --json isr.json");
  expect_bad(r, "dpc31 run: isr.scn:5: startup: firmware BAD" + hangs, "spin in a step");
  // A session names the step alike (docs/golden-model.md, "Session mode").
  expect_bad(dpc31("cosim --session isr.scn"),
             "dpc31 cosim: isr.scn:5: startup: firmware BAD" + hangs, "spin in a session's step");
  EXPECT_EQ(r.out,
            "scenario isr.scn: profile vpc3plus, bus intel, master 2 -> slave 5 at 1500000 baud\n"
            "[cycle         16] not started: dp_state Wait_Prm, wd_state Baud_Search, the chip "
            "Offline (the user side gave no Start_SPC3)\n"
            "[cycle         16] line 4: expect dp_state Wait_Prm: ok\n"
            "[cycle         16] line 5: startup\n");
  // A segment's station: the step before the station, and the segment's walk up to the step.
  file("segisr.scn",
       "segment\nstation 5 profile=spc3 firmware=DO4\nstation 6 profile=vpc3plus "
       "firmware=" +
           spin + "\nstartup\n");
  const Outcome seg = dpc31("run segisr.scn");
  expect_bad(seg, "dpc31 run: segisr.scn:4: startup: station 6: firmware BAD" + hangs,
             "spin in a segment's step");
  EXPECT_TRUE(seg.out.ends_with("] line 4: startup\n")) << seg.out;
  EXPECT_EQ(listing(), (std::vector<std::string>{"isr.scn", "segisr.scn"}));
}

// A firmware that hangs in its hardware input (a `hw` step): hw_input is firmware code as its ISR
// and init are, so the guard stops it with the same line, naming the step (docs/bring-up.md,
// section 4), exit 2. The plug-in's init makes no bus access: the walk's `not started:` line is
// at cycle 0, its end (docs/scenario-format.md, "The walk"); a `hw` step takes no time.
TEST_F(BadInput, AFirmwareThatHangsInAHardwareInputIsStopped) {
  const std::string spin = BAD_PLUGIN_SPIN_INPUT;
  file("in.scn", "profile vpc3plus\nfirmware " + spin + "\nhw spin 1\n");
  const Outcome r = dpc31("run in.scn");
  expect_bad(r,
             "dpc31 run: in.scn:3: hw: firmware BAD hangs: it ran 2000 ms of host time without a "
             "bus access or a board hook call (a while(1) loop, e.g. its fatal-error handler?); "
             "stopped",
             "spin in hw_input");
  EXPECT_EQ(r.out,
            "scenario in.scn: profile vpc3plus, bus intel, master 2 -> slave 5 at 1500000 baud\n"
            "[cycle          0] not started: dp_state Wait_Prm, wd_state Baud_Search, the chip "
            "Offline (the user side gave no Start_SPC3)\n"
            "[cycle          0] line 3: hw spin 1\n");
  // A board hook that needs the chip is the firmware's fault there, as a HAL access is.
  file("wait.scn", "profile vpc3plus\nfirmware " + spin + "\nhw wait 1\n");
  expect_bad(dpc31("run wait.scn --quiet"),
             "dpc31 run: wait.scn:3: hw: firmware BAD: dpc31_board_wait_1ms called with no chip "
             "selected (hw_input runs with no chip selected: it notes the input for the ISR or the "
             "main loop)",
             "a board wait in hw_input");
  // A release of the reset line does nothing (docs/firmware.md: a pulse before the start has
  // nothing to do), so it needs no chip: the run goes on.
  file("release.scn", "profile vpc3plus\nfirmware " + spin + "\nhw release 0\n");
  const Outcome released = dpc31("run release.scn --quiet");
  EXPECT_EQ(released.rc, 0) << released.err;
  EXPECT_EQ(released.err, "");
}

// A FIFO is neither a plug-in nor an Intel HEX image: opening one waits for a writer (run, soak,
// bridge, demo and serve hung there for ever). Refused unopened, in the words of the FILE.map
// beside an image (docs/decisions.md); each command under a timeout, so that a hang fails the
// test instead of stalling it.
TEST_F(BadInput, AFifoIsNoPluginAndNoImage) {
  ASSERT_EQ(::mkfifo(path("fw.so").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo(path("fw.ihx").c_str(), 0600), 0);
  file("plugin.scn", "firmware ./fw.so\nstartup\n");
  file("image.scn", "cpu 80c32 firmware fw.ihx\nstartup\n");
  const std::string plugin = "cannot load firmware plug-in: ./fw.so: not a regular file";
  const std::string image = "fw.ihx: not a regular file, not an Intel HEX file";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"run plugin.scn --quiet",
       "plugin.scn:1: cannot load firmware plug-in: " + path("fw.so") + ": not a regular file"},
      {"soak --firmware ./fw.so --cycles 1000", "dpc31 soak: " + plugin},
      {"bridge --tcp 0 --firmware ./fw.so", "dpc31 bridge: " + plugin},
      {"demo --firmware ./fw.so --out-dir d", "dpc31 demo: " + plugin},
      {"run image.scn --quiet",
       "image.scn:1: " + path("fw.ihx") + ": not a regular file, not an Intel HEX file"},
      {"serve --tcp 0 --cpu 80c32 --firmware fw.ihx", "dpc31 serve: " + image},
  };
  const auto before = listing();
  for (const auto& [args, line] : cases) {
    expect_bad(dpc31(args, "timeout 20"), line, args);  // 124: the timeout ended a hang
    EXPECT_EQ(listing(), before) << args;
  }
}

// A firmware that misuses the C HAL (a NULL buffer) is a firmware fault at every door, as a reset
// of the started chip is: the HAL's message in one line, exit 2, no output or temporary left, the
// bridge's symlink removed; in init (the caller's stack) and in the ISR (the host CPU's). The line
// names where the firmware runs (docs/bring-up.md, section 4): a scenario's file and `firmware`
// line in init, the step's line and keyword in a step (the ISR's first run: `startup`); on a
// segment, and among the bridge's --slave stations, the station. The walk up to the fault is kept
// on stdout, the step's line last.
TEST_F(BadInput, FirmwareFaults) {
  struct Plugin {
    std::string lib, line, run_at, seg_at, walk_end;
  };
  const std::string started =
      "[cycle         16] not started: dp_state Wait_Prm, wd_state Baud_Search, the chip Offline "
      "(the user side gave no Start_SPC3)\n";
  const std::vector<Plugin> plugins = {
      {BAD_PLUGIN_HAL_INIT, "firmware BAD: CopyToVpc3: local buffer is NULL with length 4",
       "fault.scn:2", "segfault.scn", ""},  // init: the walk's heading only
      {BAD_PLUGIN_HAL_ISR, "firmware BAD: CopyFromVpc3: local buffer is NULL with length 2",
       "fault.scn:3: startup", "segfault.scn:4: startup",
       started + "[cycle         16] line 3: startup\n"},
  };
  fs::create_directory(path("o"));
  for (const auto& [lib, line, run_at, seg_at, walk_end] : plugins) {
    file("fault.scn", "profile vpc3plus\nfirmware " + lib + "\nstartup\n");
    const Outcome run =
        dpc31("run fault.scn --json o/out.json --record o/out.trace --vcd o/out.vcd");
    expect_bad(run, "dpc31 run: " + run_at + ": " + line, lib + " run");
    // A session names the place as `dpc31 run` does (golden-model.md).
    expect_bad(dpc31("cosim --session fault.scn"), "dpc31 cosim: " + run_at + ": " + line,
               lib + " cosim --session");
    EXPECT_EQ(run.out,
              "scenario fault.scn: profile vpc3plus, bus intel, master 2 -> slave 5 at 1500000 "
              "baud\n" +
                  walk_end)
        << lib;
    file("segfault.scn",
         "segment\nstation 5 profile=spc3 firmware=DO4\nstation 6 "
         "profile=vpc3plus firmware=" +
             lib + "\nstartup\n");
    expect_bad(dpc31("run segfault.scn --json o/out.json"),
               "dpc31 run: " + seg_at + ": station 6: " + line, lib + " segment");
    expect_bad(
        dpc31("bridge --pty " + path("dpn") + " --slave 5:DO4 --slave 7:" + lib + ":vpc3plus"),
        "dpc31 bridge: station 7: " + line, lib + " --slave");
    expect_bad(dpc31("bridge --profile vpc3plus --pty " + path("dpn") + " --firmware " + lib),
               "dpc31 bridge: " + line, lib + " bridge");
    expect_bad(
        dpc31("soak --profile vpc3plus --cycles 5e6 --firmware " + lib + " --json o/soak.json"),
        "dpc31 soak: " + line, lib + " soak");
    // The demo has no scenario file to name; the directories it made for its files are gone
    // (an empty TMPDIR/dpc31-demo-XXXXXX, an --out-dir and its parents were left).
    expect_bad(dpc31("demo --profile vpc3plus --firmware " + lib + " --out-dir o"),
               "dpc31 demo: " + line, lib + " demo");
    expect_bad(dpc31("demo --profile vpc3plus --firmware " + lib + " --out-dir made/new"),
               "dpc31 demo: " + line, lib + " demo, a new --out-dir");
    expect_bad(dpc31("demo --profile vpc3plus --firmware " + lib, "TMPDIR=" + path("o")),
               "dpc31 demo: " + line, lib + " demo in TMPDIR");
    EXPECT_EQ(listing(), (std::vector<std::string>{"fault.scn", "o", "segfault.scn"}))
        << lib;  // no symlink
    EXPECT_TRUE(fs::is_empty(path("o"))) << lib;
  }
}

TEST_F(BadInput, BridgeOptions) {
  spit(path("plain"), "old");
  expect_bad(
      dpc31("bridge --pty p --firmware XX"),
      "dpc31 bridge: unknown firmware 'XX' (DO4, CNT2, or a plug-in path such as ./libmine.so)",
      "firmware");
  expect_bad(dpc31("bridge --pty plain --firmware DO4"),
             "dpc31 bridge: plain exists and is not a symlink: refusing to replace it", "pty");
  // The log is opened last: the symlink made before it is removed again.
  expect_bad(dpc31("bridge --pty p --firmware DO4 --log no/such/log"),
             "dpc31 bridge: cannot write the log no/such/log: No such file or directory", "log");
  expect_bad(dpc31("bridge --pty p --firmware DO4 --baud 12"),
             "dpc31 bridge: --baud '12' is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, "
             "500000, 1500000, 3000000, 6000000, 12000000)",
             "baud");
  for (const char* args : {"bridge --firmware DO4", "bridge --pty p --firmware DO4 --address 200",
                           "bridge --pty p --firmware DO4 --pacing warp"}) {
    expect_bad_prefix(dpc31(args), "dpc31 bridge: ", args);
  }
  EXPECT_EQ(slurp(path("plain")), "old");
  EXPECT_EQ(listing(), std::vector<std::string>{"plain"});
}

TEST_F(BadInput, BenchOptionsAndJson) {
  // The JSON path is checked before anything is measured (/bin/true stands in for the
  // benchmark binary: it is never run).
  expect_json_checked_first("bench", "--bench /bin/true",
                            {"bench --min-time 0", "bench --quick --wavediff-mb 5", "bench extra"});
  expect_bad_prefix(dpc31("bench --bench /nonexistent/dpc31_bench --json old.json"),
                    "dpc31 bench: --bench: ", "bench binary");
  EXPECT_EQ(slurp(path("old.json")), "old");
}

TEST_F(BadInput, SoakOptionsAndJson) {
  // The JSON path is checked before the run (the cycle count would otherwise run first).
  expect_json_checked_first("soak", "--cycles 1e9",
                            {"soak --cycles 0", "soak --cycles many", "soak --profile spc4",
                             "soak --baud 1234", "soak --seed -1", "soak extra"});
  const auto before = listing();
  // A rate as the bridge words it, the rates named; "" was taken as 0 and divided by (SIGFPE).
  const std::string rates =
      " is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, 500000, 1500000, 3000000, "
      "6000000, 12000000)";
  for (const char* baud : {"", "abc", "1.5e6", "1234", "-1"}) {
    expect_bad(dpc31(std::string("soak --baud '") + baud + "'"),
               std::string("dpc31 soak: --baud: '") + baud + "'" + rates, baud);
  }
  EXPECT_EQ(listing(), before);
}

// An empty path is not "not given" (it ran without the output, or with the default input,
// silently): every option that names a file or a directory refuses it alike (path_option.hpp),
// and a firmware option, a name or a path, as an unknown firmware. Each command has a second
// mistake found only after its options are parsed (a missing scenario, a bad address): without
// the check it fails there with another line instead of running (serve and bridge would listen).
TEST_F(BadInput, EmptyPathOptions) {
  const std::string vcd = std::string(SOURCE_DIR) + "/tests/data/wavediff/emu.vcd";
  const std::string wavediff = "wavediff " + vcd + " " + vcd + " --start 5 --end 1";
  struct Case {
    std::string sub;   // the subcommand as the error names it
    std::string args;  // everything but the empty option
    std::vector<std::string> written, read;
  };
  const std::vector<Case> cases = {
      {"run",
       "run missing.scn",
       {"--json", "--record", "--vcd", "--fst", "--la-vcd", "--gtkw", "--pcap"},
       {}},
      {"cosim",
       "cosim --replay missing.trace --mutant NO_SUCH",
       {"--junit", "--vcd", "--out", "--dump"},
       {"--rtl-model", "--session"}},
      {"cosim", "cosim --mutant NO_SUCH", {}, {"--replay", "--rtl"}},
      {"cosim merge", "cosim merge missing.json", {"--junit"}, {}},
      {"wavediff", wavediff, {"--json", "--diff-vcd", "--merge", "--wavedrom"}, {"--map"}},
      {"demo", "demo --timescale 7ps", {"--out-dir"}, {}},
      {"bench", "bench --bench /nonexistent", {"--json", "--wavediff-dir"}, {"--build"}},
      {"bench", "bench", {}, {"--bench"}},  // refused there before, in other words
      {"serve",
       "serve --tcp 0 --code 1",
       {"--unix", "--state-dir"},
       {"--secret-file", "--firmware"}},
      {"bridge", "bridge --firmware DO4 --address 200", {"--pty"}, {}},
      {"bridge",
       "bridge --tcp 0 --firmware DO4 --address 200",
       {"--pcap", "--log", "--trace-cpu"},
       {}},
      {"soak", "soak", {"--json"}, {}},  // refused before without the option's name
  };
  const auto before = listing();
  for (const Case& c : cases) {
    for (const auto& [options, why] : {std::pair{&c.written, "nothing can be written there"},
                                       std::pair{&c.read, "nothing can be read there"}}) {
      for (const std::string& o : *options) {
        expect_bad(dpc31(c.args + " " + o + " ''"),
                   "dpc31 " + c.sub + ": " + o + ": an empty file name: " + why, c.args + " " + o);
      }
    }
  }
  // A file argument given as '' names itself, as an option does (it said ": no such file").
  for (const auto& [args, line] : std::vector<std::pair<std::string, std::string>>{
           {"run ''", "dpc31 run: scenario"},
           {"replay ''", "dpc31 replay: trace"},
           {"wavediff '' " + vcd, "dpc31 wavediff: A"},
           {"wavediff " + vcd + " ''", "dpc31 wavediff: B"},
           {"cosim merge ''", "dpc31 cosim merge: summaries"}}) {
    expect_bad(dpc31(args), line + ": an empty file name: nothing can be read there", args);
  }
  const std::string unknown =
      ": unknown firmware '' (DO4, CNT2, or a plug-in path such as ./libmine.so)";
  for (const char* sub : {"demo", "bridge --tcp 0", "soak --cycles 2e6"}) {
    const std::string name = std::string(sub).substr(0, std::string(sub).find(' '));
    expect_bad(dpc31(std::string(sub) + " --firmware ''"), "dpc31 " + name + unknown, sub);
  }
  EXPECT_EQ(listing(), before);
}

}  // namespace
