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

// --- dpc31 run: the scenario file, its options and its outputs ------------------------------

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
