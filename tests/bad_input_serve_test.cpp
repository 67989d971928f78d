// Bad input of `dpc31 serve`, `bridge`, `bench`, `soak` and of firmware plug-ins and RTL models
// at every door that loads them (docs/bad-input.md; split from bad_input_test.cpp at its
// sections): one line on stderr, exit 2, nothing left behind.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bad_input.hpp"
#include "dpc31/dpc31_firmware.h"
#include "dpc31_rtl_model.h"

using namespace badinput;

namespace {

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
  const std::string nl_name = BAD_PLUGIN_NL_NAME;
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
      // s33 audit finding 11: a name is shown in logs and walks, one entry a line.
      {nl_name, "firmware plug-in " + nl_name +
                    ": the descriptor's name has a control character, byte 0Ah at offset 3 (a "
                    "name is shown in logs and walks, one entry a line)"},
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
  // `dpc31 demo` and `dpc31 soak` have no --cpu: they say they cannot run it, and where to (the
  // s35 audit, finding 1: their hint sent the user to an option they refuse).
  for (const std::string command : {"demo", "soak"}) {
    const Outcome r = dpc31(command + " --firmware " + ihx);
    expect_bad_prefix(r, "dpc31 " + command + ": cannot load firmware plug-in: " + ihx + ": ",
                      command);
    EXPECT_TRUE(r.err.ends_with("; it is an Intel HEX image, a CPU's program: `dpc31 " + command +
                                "` cannot run an 80C32 image; `dpc31 run` (the header cpu 80c32 "
                                "firmware FILE), `dpc31 bridge` and `dpc31 serve` (--cpu 80c32) "
                                "can\n"))
        << r.err;
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

// s33 audit findings 1 and 5: a firmware that crashes (SIGSEGV in its init) ended `dpc31 run`
// with no line, its output temporaries left, and `dpc31 bridge` with its --pty symlink left; the
// hang guard's line never reached the bridge's --log. The fatal signal now gets the hang guard's
// kind of line, naming the firmware and the place (docs/bring-up.md, section 4), the temporaries
// and the symlink go, and the process still ends by the signal; both lines go to the --log too.
TEST_F(BadInput, AFirmwareThatCrashesIsNamedAndLeavesNothing) {
#if defined(__SANITIZE_ADDRESS__)
  // The sanitizers take the crash themselves (their report and exit; UBSan's null store check in
  // the plug-in first): our handler is not the one that runs (docs/sanitizers.md).
  GTEST_SKIP() << "the sanitizers catch the plug-in's crash before our handler";
#endif
  const std::string crash = BAD_PLUGIN_CRASH;
  const std::string err = (root_ / "io" / "err").string();
  const auto signalled = [&](const std::string& args) {
    std::vector<std::string> argv = {kCli};
    std::istringstream words(args);
    for (std::string w; words >> w;) argv.push_back(w);
    const pid_t pid = spawn(argv, path(""), err);
    int st = 0;
    EXPECT_EQ(::waitpid(pid, &st, 0), pid);
    return WIFSIGNALED(st) ? WTERMSIG(st) : -1;
  };
  const std::string crashed =
      "firmware BAD crashed: SIGSEGV (a bad pointer?) while its code ran; stopped\n";
  file("crash.scn", "# crashes in init\nfirmware " + crash + "\nstartup\n");
  file("old.json", "old");
  EXPECT_EQ(signalled("run crash.scn --json old.json --vcd new.vcd"), SIGSEGV);
  EXPECT_EQ(slurp(err), "dpc31 run: crash.scn:2: " + crashed);
  EXPECT_EQ(slurp(path("old.json")), "old");
  EXPECT_EQ(signalled("bridge --pty p --firmware " + crash + " --log crash.log"), SIGSEGV);
  EXPECT_EQ(slurp(err), "dpc31 bridge: " + crashed);
  EXPECT_EQ(slurp(path("crash.log")), "dpc31 bridge: " + crashed);
  const std::string hangs =
      "dpc31 bridge: firmware BAD hangs: it ran 2000 ms of host time without a bus access or a "
      "board hook call (a while(1) loop, e.g. its fatal-error handler?); stopped\n";
  const Outcome spin =
      dpc31("bridge --pty p --firmware " + std::string(BAD_PLUGIN_SPIN) + " --log spin.log");
  EXPECT_EQ(spin.rc, 2);
  EXPECT_EQ(spin.err, hangs);
  EXPECT_EQ(slurp(path("spin.log")), hangs);
  EXPECT_EQ(listing(),
            (std::vector<std::string>{"crash.log", "crash.scn", "old.json", "spin.log"}));
}

// s33 review finding 1: a crash after the walk has printed lines, with stdout to a file (CI, a
// pipe): the walk so far is kept, as at a hang (docs/bring-up.md, section 4). It was lost, the
// buffered stdout never written. The trace, whose lines went to its temporary as the run went
// (s34-record), is not left: neither the file nor the temporary.
TEST_F(BadInput, AFirmwareThatCrashesLaterKeepsTheWalkPrintedSoFar) {
#if defined(__SANITIZE_ADDRESS__)
  // The sanitizers take the crash themselves (their report and exit; UBSan's null store check in
  // the plug-in first): our handler is not the one that runs (docs/sanitizers.md).
  GTEST_SKIP() << "the sanitizers catch the plug-in's crash before our handler";
#endif
  file("later.scn", "# crashes in its hardware input\nfirmware " +
                        std::string(BAD_PLUGIN_CRASH_INPUT) + "\nstartup\nhw crash 1\n");
  const std::string err = (root_ / "io" / "err").string();
  const std::string out = (root_ / "io" / "out").string();
  const pid_t pid =
      spawn({kCli, "run", "later.scn", "--record", "later.trace"}, path(""), err, false, out);
  int st = 0;
  ASSERT_EQ(::waitpid(pid, &st, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(st));
  EXPECT_EQ(WTERMSIG(st), SIGSEGV);
  EXPECT_EQ(slurp(err),
            "dpc31 run: later.scn:4: hw: firmware BAD crashed: SIGSEGV (a bad pointer?) "
            "while its code ran; stopped\n");
  const std::string walk = slurp(out);
  EXPECT_NE(walk.find("] line 3: startup\n"), std::string::npos) << walk;
  EXPECT_NE(walk.find("] line 4: hw crash 1\n"), std::string::npos) << walk;
  EXPECT_EQ(listing(), std::vector<std::string>{"later.scn"});
}

// s33 audit finding 5: `dpc31 bridge --log F` that never gets past its start left F emptied with
// nothing in it. Now a fault in the firmware's init (a hang here; a HAL misuse or a crash the
// same) replaces the earlier session's log by its line, and an output that cannot be written (a
// --pcap in a directory that does not exist) is refused before the log is opened: F is kept
// (docs/bridge.md, "The log"; docs/decisions.md, s33-hal2).
TEST_F(BadInput, ABridgeThatNeverStartsLeavesTheLogWithItsFaultOrAsItWas) {
  const std::string before = "4 NOTE bridge waiting for a client\n";
  file("keep.log", before);
  const Outcome pcap =
      dpc31("bridge --pty p --firmware DO4 --profile spc3 --log keep.log --pcap no/x.pcapng");
  EXPECT_EQ(pcap.rc, 2);
  EXPECT_NE(pcap.err.find("no/x.pcapng"), std::string::npos) << pcap.err;
  EXPECT_EQ(slurp(path("keep.log")), before);
  file("spin.log", before);
  const Outcome spin =
      dpc31("bridge --pty p --firmware " + std::string(BAD_PLUGIN_SPIN) + " --log spin.log");
  EXPECT_EQ(spin.rc, 2);
  EXPECT_EQ(slurp(path("spin.log")), spin.err);
  EXPECT_NE(spin.err.find("firmware BAD hangs"), std::string::npos) << spin.err;
  EXPECT_EQ(listing(), (std::vector<std::string>{"keep.log", "spin.log"}));
}

// s31-serve, finding 6: `soak --firmware` with a firmware that hangs after its init wrote
// reserved bits of Int_Mask_Reg (on the DPC31, the default profile) printed the chip's two
// warnings ahead of the hang guard's line. docs/soak.md and docs/bad-input.md promise exactly
// one line: the chip's log is kept for after the report, which a run that ends in exit 2 has not.
TEST_F(BadInput, ASoakWhoseFirmwareHangsPrintsOneLine) {
  const std::string hangs =
      " hangs: it ran 2000 ms of host time without a bus access or a board hook call (a while(1) "
      "loop, e.g. its fatal-error handler?); stopped";
  expect_bad(
      dpc31("soak --cycles 2e7 --fault-period 5e5 --firmware " + std::string(BAD_PLUGIN_SPIN_ISR)),
      "dpc31 soak: firmware BAD" + hangs, "spin_isr soak");
  expect_bad(
      dpc31("soak --cycles 2e7 --fault-period 5e5 --firmware " + std::string(BAD_PLUGIN_HAL_ISR)),
      "dpc31 soak: firmware BAD: CopyFromVpc3: local buffer is NULL with length 2", "hal_isr soak");
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
      // s33 audit finding 1: the pointers swapped read host memory at 0x40 (SIGSEGV, exit 139).
      {BAD_PLUGIN_HAL_SWAP,
       "firmware BAD: CopyToVpc3: chip pointer 0x12345678 is not a chip address (0x0000..0xFFFF): "
       "the arguments swapped?",
       "fault.scn:2", "segfault.scn", ""},
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
