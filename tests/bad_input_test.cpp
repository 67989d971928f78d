// Bad input everywhere (docs/bad-input.md): every subcommand of the real `dpc31` binary, given a
// missing, empty, truncated or garbage input file or a bad option value, prints exactly one line
// on stderr and exits 2, and leaves no output file and no temporary behind; an output file that
// was there before is left untouched.
#include "bad_input.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

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
      // A built-in firmware's hardware input out of its range (CNT2's MSG bits: 1..15) is bad
      // input, found before the run (audit s32 finding 6: it ran, and exited 1).
      {"hw value out of range",
       file("hw.scn", "profile dpc31\nfirmware CNT2\nstartup\nhw event1 16\n"),
       path("hw.scn") + ":4: event1 16 out of range (1..15)"},
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

// A shipped 80C32 scenario names its image beside it, but the build writes the image (and a copy of
// the scenario) to build/firmware/mcs51/ (docs/cpu.md): run from traces/, the message said only
// "no such file" (audit a-docs, finding 8); now it names the built image. A missing image the
// build did not make (none.ihx above) keeps the bare message.
TEST_F(BadInput, AShippedCpuScenarioRunFromTracesNamesTheBuiltImage) {
  const std::string built = (std::filesystem::path(kCli).parent_path().parent_path() / "firmware" /
                             "mcs51" / "cnt2_80c32.ihx")
                                .string();
  ASSERT_TRUE(std::filesystem::is_regular_file(built)) << built << " (the sdcc build, setup.sh)";
  const Outcome r = dpc31("run " + kTraces + "cnt2_80c32.scn");
  // Line 22 of traces/cnt2_80c32.scn is its `cpu 80c32 ... firmware cnt2_80c32.ihx` header.
  expect_bad(r,
             kTraces + "cnt2_80c32.scn:22: " + kTraces +
                 "cnt2_80c32.ihx: no such file (the build made " + built +
                 ": run the scenario's copy beside it, docs/cpu.md)",
             "a shipped cpu scenario");
  EXPECT_EQ(r.out, "");
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
      {"the C31 without its profile line",
       file("c1.scn", "baud 1500000\ncpu c31 firmware halt.ihx\nstartup\n"),
       path("c1.scn") +
           ":2: 'cpu c31' needs 'profile dpc31' before it: only the DPC31 has a C31 core"},
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
  // An empty unit is a bad unit as any other (it was taken for "not given": the default, silently).
  expect_bad(dpc31("run " + scn + " --vcd old.vcd --timescale ''"),
             "dpc31 run: --timescale '': use 1, 10 or 100 fs or ps, or 1 or 10 ns",
             "empty timescale");
  // A waveform's option without a waveform acts on nothing: refused whatever its value ("No
  // silent options"; a good --timescale, --signals, --from and --to were ignored), for one chip
  // and for a segment.
  const std::string any = ": a waveform option needs --vcd, --fst or --la-vcd";
  for (const std::string& s : {scn, kTraces + "segment/two_masters.scn"}) {
    for (const auto& [args, line] : std::vector<std::pair<std::string, std::string>>{
             {"--timescale ps", "--timescale ps" + any},
             {"--timescale 1ns", "--timescale 1ns" + any},
             {"--timescale ''", "--timescale ''" + any},
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
      {"--la-vcd new.vcd --pvs taken", "dpc31 run: taken: cannot write: is a directory"},
      // PulseView's session goes with a VCD in the logic-analyser form that holds RxD or TxD.
      {"--pvs new.pvs",
       "dpc31 run: --pvs new.pvs: a PulseView session needs --la-vcd (or --vcd with --flat)"},
      {"--vcd new.vcd --pvs new.pvs",
       "dpc31 run: --pvs new.pvs: a PulseView session needs --la-vcd (or --vcd with --flat)"},
      {"--la-vcd new.vcd --signals pins.x_int --pvs new.pvs",
       "dpc31 run: new.pvs: a PulseView session decodes pins.rxd or pins.txd (a segment's "
       "line.level), and --signals leaves them out of new.vcd"},
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

// A trace from a pipe (`| ... /dev/stdin`) replays as the file does (docs/trace-format.md): the
// replay reads a trace twice (its check, then the replay), so a pipe is copied to a scratch file
// in TMPDIR first, removed at once; a copy that cannot be written (here the file size limit) is
// named, exit 2, nothing run.
TEST_F(BadInput, ReplayReadsAPipeLikeTheFile) {
  const std::string text = slurp(copy(kTraces + "gc_clear_spc3.trace", "good.trace"));
  file("cut.trace", text.substr(0, text.size() - 3));
  fs::create_directory(path("tmp"));
  const std::string tmpdir = "TMPDIR=" + path("tmp");
  const Outcome f = dpc31("replay good.trace");
  ASSERT_EQ(f.rc, 0) << f.err;
  const Outcome p = dpc31("replay /dev/stdin", "cat good.trace | " + tmpdir);
  EXPECT_EQ(p.rc, 0) << p.err;
  EXPECT_EQ("/dev/stdin" + f.out.substr(f.out.find(':')), p.out);
  expect_bad(dpc31("replay /dev/stdin", "cat cut.trace | " + tmpdir),
             "/dev/stdin:" + std::to_string(std::count(text.begin(), text.end(), '\n')) +
                 ": truncated: the last line has no end of line",
             "cut");
  expect_bad(
      dpc31("replay /dev/stdin", "ulimit -f 1 && cat good.trace | " + tmpdir),
      "/dev/stdin: cannot copy the pipe to a scratch file in " + path("tmp") + ": File too large",
      "file size limit");
  EXPECT_TRUE(fs::is_empty(path("tmp")));
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
  r = dpc31("demo --out-dir fresh --timescale ''");
  expect_bad(r, "dpc31 demo: --timescale '': use 1, 10 or 100 fs or ps, or 1 or 10 ns",
             "demo empty timescale");
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
  for (const char* name : {"dpc31-demo.vcd", "dpc31-demo-la.vcd", "dpc31-demo.gtkw",
                           "dpc31-demo-la.pvs", "dpc31-demo.pcapng"}) {
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
  // The good case: the demo prints its story and writes its five files.
  const Outcome ok = dpc31("demo --out-dir good");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_NE(ok.out, "");
  EXPECT_EQ(std::distance(fs::directory_iterator(path("good")), fs::directory_iterator()), 5);
  // Without --out-dir, a TMPDIR that is no directory is named (the library gives no path then).
  const Outcome gone = dpc31("demo", "TMPDIR=" + path("none"));
  expect_bad(gone,
             "dpc31 demo: cannot create a directory in TMPDIR=" + path("none") +
                 ": No such file or directory",
             "TMPDIR");
  EXPECT_EQ(gone.out, "");
}

}  // namespace
