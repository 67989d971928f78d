// The walk's state lines and `expect dp_state/wd_state ... at` with a firmware on an 80C32
// (docs/scenario-format.md, "expect ... at"): a state change is noted at the cycle the chip makes
// it, which for a firmware's verdict is the completion cycle of its bus access, whoever looks
// next; a `cpu` firmware starts the chip at its own Start_SPC3, not at cycle 0.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/dpc31_regs.h"
#include "scenario.hpp"
#include "test_files.hpp"
#include "trace.hpp"

// A namespace of its own: the file shares a unity source with scenario_test.cpp.
namespace scenario_walk {
namespace {

namespace fs = std::filesystem;

struct Walk {
  dpc31::ScenarioOutcome outcome;
  std::vector<std::string> lines;
  std::vector<std::string> errors;
  std::vector<std::pair<std::uint64_t, std::uint16_t>> reads;  // completion cycle, address
  // The completion cycle of the first read of `addr` after a read of `after` (`addr` itself:
  // its first read); 0: none.
  [[nodiscard]] std::uint64_t read_after(std::uint16_t after, std::uint16_t addr) const {
    bool seen = after == addr;
    for (const auto& [c, a] : reads) {
      if (seen && a == addr) return c;
      seen = seen || a == after;
    }
    return 0;
  }
  [[nodiscard]] bool has(const std::string& s) const {
    for (const std::string& l : lines) {
      if (l == s) return true;
    }
    return false;
  }
};

std::string file_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `text` parsed as the file `path` (its firmware beside it) and run on `engine`; the firmware's
// reads go to Walk::reads.
Walk run(const std::string& text, const fs::path& path, dpc31::Engine engine,
         dpc31::ScenarioObserver* observer = nullptr) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(text, path.string(), s, err)) << err.text();
  EXPECT_TRUE(dpc31::bind_plugin(s, err)) << err.text();  // a plug-in's `firmware` line
  s.chip.engine = engine;
  Walk w;
  dpc31::ScenarioHooks h;
  h.observer = observer;
  h.at_start = [&w](dpc31::Chip& chip) {
    chip.on_bus_access([&w](std::uint64_t c, const dpc31::BusAccess& a) {
      if (!a.write) w.reads.emplace_back(c, a.addr);
    });
  };
  w.outcome = dpc31::run_scenario(
      s, [&w](const std::string& l) { w.lines.push_back(l); },
      [&w](const std::string& l) { w.errors.push_back(l); }, h);
  return w;
}

// A directory of its own for the images a test writes (removed with it).
struct ImageDir {
  testutil::TempDir tmp;
  fs::path dir{tmp.path()};
  void put(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
  }
};

// The heading lines of a recorded trace (`# ...`) that say who set the chip up.
std::string user_side_heading(const std::string& trace) {
  std::istringstream in(trace);
  for (std::string l; std::getline(in, l);) {
    if (l.starts_with("# firmware init (") || l.starts_with("# user side: ")) return l;
  }
  return "";
}

const char* engine_name(dpc31::Engine e) {
  return e == dpc31::Engine::event ? "event" : "per_cycle";
}

// The completion cycle of the first `rd` of `addr` after a `rd` of `after` in a recorded trace
// (docs/trace-format.md: `rd CYCLE ADDR = DATA`, a read that completes at CYCLE); 0: none.
std::uint64_t trace_read_after(const std::string& trace, unsigned after, unsigned addr) {
  std::istringstream in(trace);
  bool seen = false;
  for (std::string l; std::getline(in, l);) {
    std::istringstream f(l);
    std::string kind;
    std::uint64_t cycle = 0;
    unsigned a = 0;
    if (!(f >> kind >> cycle >> std::hex >> a) || kind != "rd") continue;
    if (seen && a == addr) return cycle;
    seen = seen || a == after;
  }
  return 0;
}

// The cycle of the walk's line `[cycle N] TEXT`; 0: no such line.
std::uint64_t walk_cycle(const Walk& w, const std::string& text) {
  for (const std::string& l : w.lines) {
    if (l.size() > 19 && l.starts_with("[cycle ") && l.substr(19) == text) {
      return std::stoull(l.substr(7, 10));
    }
  }
  return 0;
}

// s33 audit finding 9: after a refused Set_Prm (a wrong Ident_Number: Prm_Fault, Master_Add FFh)
// no master locks the slave; the Chk_Cfg that follows was logged "not the locking master", which
// sends the user to the master addresses. Its reason is now the missing lock (DPC31 p.28: a
// Check_Config not from Master_Add is ignored).
TEST(ScenarioWalk, AChkCfgAfterARefusedSetPrmNamesTheMissingLock) {
  const Walk w = run("profile spc3\nslave address=5\nstartup\nset_prm ident=0x1234\nchk_cfg\n",
                     "chk.scn", dpc31::Engine::event);
  std::size_t unlocked = 0;
  for (const std::string& l : w.lines) {
    EXPECT_EQ(l.find("not the locking master"), std::string::npos) << l;
    if (l.ends_with("] chip: Chk_Cfg from 2: no master has locked the slave (Master_Add FFh: not "
                    "parameterised): ignored"))
      ++unlocked;
  }
  EXPECT_EQ(unlocked, 1u);
}

// a19 finding 1: ECHO51 (tests/data/walk/echo51.c, an SPC3 firmware with only New_Prm_Data,
// New_Cfg_Data and DX_Out unmasked) accepts the Chk_Cfg and hands its first inputs over with
// New_Din_Buffer_Cmd; "the SPC3 waiting after Cfg OK enters Data_Exchange" at that read
// (docs/decisions.md, Cfg OK; docs/timing.md: an access acts at its completion cycle, the `rd`
// line's cycle of a recorded trace). The walk's line and `expect ... at` take that read's cycle,
// found in the run's own recorded trace (not X/INT, and not the next telegram's end).
TEST(ScenarioWalk, FirmwareMadeDataExchangeAtItsBusAccess) {
  const fs::path dir = fs::path(SOURCE_DIR) / "tests" / "data" / "walk";
  const std::string text =
      "profile spc3\nbaud 1500000\ncpu 80c32 clock=24000000 firmware echo51.ihx ports=out0\n"
      "slave address=9 ident=0x0E51 cfg=31 in=2 out=2 wd=2,5 user_prm=00\n"
      "startup\nexpect dp_state Data_Exchange\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    dpc31::TraceRecorder rec(1'500'000);
    const Walk w = run(text, dir / "t.scn", engine, &rec);
    const std::uint64_t read =
        trace_read_after(rec.text(), SPC3_User_Cfg_Data_Okay, SPC3_New_Din_Buffer_Cmd);
    ASSERT_NE(read, 0u);
    EXPECT_EQ(w.read_after(SPC3_User_Cfg_Data_Okay, SPC3_New_Din_Buffer_Cmd), read);
    EXPECT_EQ(walk_cycle(w, "dp_state Wait_Cfg -> Data_Exchange"), read);
    EXPECT_EQ(w.outcome.failed, 0u) << (w.errors.empty() ? "" : w.errors.front());
    EXPECT_EQ(w.outcome.passed, 1u);
    // `expect ... at` takes the same cycle.
    const Walk at = run(text + fmt::format("expect dp_state Data_Exchange at {}\n", read),
                        dir / "t.scn", engine);
    EXPECT_EQ(at.outcome.failed, 0u) << (at.errors.empty() ? "" : at.errors.front());
    EXPECT_EQ(at.outcome.passed, 2u);
  }
}

// The shipped DO4 scenario on the 80C32: its comment derives the User_Prm_Data_Okay read at
// M = 233 590, chip cycle 5 606 196, where the chip enters Wait_Cfg and the DP watchdog DP_Control
// (docs/timing.md, "DP watchdog": started at the completion cycle of that read). The EOI that
// used to be the walk's cycle comes 7 056 cycles later, at 5 613 252.
TEST(ScenarioWalk, Do4WatchdogDpControlAtTheUserPrmDataOkayRead) {
  const fs::path path = fs::path(FW51_DIR) / "do4_80c32.scn";
  std::string text = file_text(path);
  const std::string at = "\nexpect dp_state Data_Exchange at 5655516\n";
  const std::size_t i = text.find(at);
  ASSERT_NE(i, std::string::npos);
  text.insert(i + at.size(), "expect wd_state DP_Control at 5606196\n");
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, path, engine);
    EXPECT_EQ(w.read_after(SPC3_User_Prm_Data_Okay, SPC3_User_Prm_Data_Okay), 5'606'196u);
    EXPECT_TRUE(w.has("[cycle    5606196] dp_state Wait_Prm -> Wait_Cfg"));
    EXPECT_TRUE(w.has("[cycle    5606196] wd_state Baud_Control -> DP_Control"));
    EXPECT_EQ(w.outcome.failed, 0u) << (w.errors.empty() ? "" : w.errors.front());
  }
}

// a19 finding 2: the `cpu` firmware starts the chip itself. DO4's Start_SPC3 write completes at
// 531 084 (the shipped scenario's `expect irq DX_Out at 531084`: Start_SPC3 latches DX_Out at
// the completion cycle s of the write, where the WD state becomes Baud_Search: docs/timing.md,
// "Mode and state changes"); until then the chip is Offline and no built-in user side ran.
TEST(ScenarioWalk, CpuFirmwareStartsTheChipAtItsStartSpc3) {
  const fs::path path = fs::path(FW51_DIR) / "t.scn";
  const std::string text =
      "profile spc3\nbaud 187500\n"
      "cpu 80c32 clock=24000000 firmware do4_80c32.ihx ports=outputs,modul_ok\n"
      "slave address=7 ident=0x0D04 cfg=21,10 in=1 out=2 wd=2,5 user_prm=00,01,05,00\n"
      "silence 12ms\nexpect wd_state Baud_Search at 531084\n"
      "expect dp_state Wait_Prm at 531084\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    dpc31::TraceRecorder rec(187'500);
    const Walk w = run(text, path, engine, &rec);
    EXPECT_TRUE(
        w.has("[cycle          0] not started: dp_state Wait_Prm, wd_state Baud_Search, "
              "the chip Offline until the firmware's Start_SPC3"));
    EXPECT_TRUE(w.has("[cycle     531084] started: dp_state Wait_Prm, wd_state Baud_Search"));
    EXPECT_EQ(w.outcome.failed, 0u) << (w.errors.empty() ? "" : w.errors.front());
    EXPECT_EQ(w.outcome.passed, 2u);
    const std::string trace = rec.text();
    EXPECT_EQ(trace.find("built-in user side)"), std::string::npos);
    EXPECT_EQ(user_side_heading(trace),
              "# user side: the 80C32 firmware do4_80c32.ihx; not started: dp_state Wait_Prm, "
              "wd_state Baud_Search, the chip Offline until the firmware's Start_SPC3");
  }
}

// `--record`'s heading names what set the chip up (docs/trace-format.md): the built-in user side,
// a host C firmware by its name, a CPU's image by its file. The heading said "the built-in user
// side" for a host firmware (DO4's init, which starts the chip itself). Started at the init, the
// states are Start_SPC3's (docs/timing.md, "Mode and state changes": Wait_Prm, Baud_Search).
TEST(ScenarioWalk, TraceHeadingNamesWhatSetTheChipUp) {
  const ImageDir d;
  d.put("halt.ihx", ":0200000080FE80\n:00000001FF\n");  // SJMP $
  const auto heading = [&](const std::string& text) {
    dpc31::TraceRecorder rec(1'500'000);
    const Walk w = run(text, d.dir / "t.scn", dpc31::Engine::event, &rec);
    EXPECT_TRUE(w.errors.empty()) << (w.errors.empty() ? "" : w.errors.front());
    return user_side_heading(rec.text());
  };
  const std::string started = "started: dp_state Wait_Prm, wd_state Baud_Search";
  EXPECT_EQ(heading("profile spc3\nbaud 1500000\nsilence 1ms\n"),
            "# firmware init (the built-in user side): registers, buffers, Start_SPC3; " + started);
  EXPECT_EQ(heading("profile spc3\nbaud 1500000\nfirmware DO4\nsilence 1ms\n"),
            "# firmware init (the host firmware DO4): registers, buffers, Start_SPC3; " + started);
  EXPECT_EQ(heading("profile dpc31\nbaud 1500000\nsilence 1ms\n"),
            "# firmware init (the built-in user side): registers, buffers, MAC_Start; " + started);
  EXPECT_EQ(heading("profile spc3\nbaud 1500000\ncpu 80c32 firmware halt.ihx\nsilence 1ms\n"),
            "# user side: the 80C32 firmware halt.ihx; not started: dp_state Wait_Prm, wd_state "
            "Baud_Search, the chip Offline until the firmware's Start_SPC3");
  EXPECT_EQ(heading("profile dpc31\nbaud 1500000\ncpu c31 firmware halt.ihx\nsilence 1ms\n"),
            "# user side: the C31 firmware halt.ihx; not started: dp_state Wait_Prm, wd_state "
            "Baud_Search, the chip Offline until the firmware's MAC_Start");
}

// A firmware's Go_Offline with no request in progress: "go Offline after the current request",
// with none at the write's completion cycle, both states back to Wait_Prm and Baud_Search
// (docs/timing.md, "Mode and state changes"); the walk's `offline:` line is at that cycle
// (docs/scenario-format.md, "The walk"). The image, hand-assembled (Intel's MCS-51 manual for the
// machine cycles; the chip's Mode_Reg1_S at 08h, its window at 8000h):
//   M0-1 MOV DPTR,#8008h   M2 MOV A,#01h   M3-4 MOVX @DPTR,A (Start_SPC3)
//   M5 MOV A,#04h          M6-7 MOVX @DPTR,A (Go_Offline)        M8- SJMP $
// A MOVX starting in machine cycle M completes at chip cycle 24 M + 36 at 24 MHz beside the
// 48 MHz chip (docs/cpu.md, "MOVX timing": 18 oscillator clocks, ceil(clock x 48/24)): Start_SPC3
// at 24 x 3 + 36 = 108, Go_Offline at 24 x 6 + 36 = 180. No master sends during `silence`.
TEST(ScenarioWalk, FirmwareGoOfflineIsTheWalksOfflineLineAtItsWrite) {
  const ImageDir d;
  d.put("off.ihx", ":0B0000009080087401F07404F080FE92\n:00000001FF\n");
  const std::string text =
      "profile spc3\nbaud 1500000\ncpu 80c32 clock=24000000 firmware off.ihx\nsilence 1ms\n"
      "expect dp_state Wait_Prm at 180\nexpect wd_state Baud_Search at 180\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, d.dir / "t.scn", engine);
    EXPECT_EQ(walk_cycle(w, "started: dp_state Wait_Prm, wd_state Baud_Search"), 108u);
    EXPECT_EQ(walk_cycle(w, "offline: dp_state Wait_Prm, wd_state Baud_Search"), 180u);
    EXPECT_EQ(w.outcome.failed, 0u) << (w.errors.empty() ? "" : w.errors.front());
    EXPECT_EQ(w.outcome.passed, 2u);
  }
}

// The latch is the bytes `ports=` names from `latch` on (DO4's two, `outputs` and `modul_ok`,
// without it: docs/cpu.md, "The scenario header"); any other XDATA write outside the chip's window
// is the board's RAM, not a port, even next to the latch. The image, hand-assembled as above:
//   M0-1 MOV DPTR,#4002h   M2 MOV A,#07h   M3-4 MOVX @DPTR,A (past DO4's two bytes)
//   M5-6 MOV DPTR,#4000h   M7-8 MOVX @DPTR,A (outputs)             M9- SJMP $
// The second MOVX completes at chip cycle 24 x 7 + 36 = 204 (docs/cpu.md, "MOVX timing").
TEST(ScenarioWalk, OnlyTheNamedLatchBytesArePorts) {
  const ImageDir d;
  d.put("latch.ihx", ":0C0000009040027407F0904000F080FE79\n:00000001FF\n");
  const std::string text =
      "profile spc3\nbaud 1500000\ncpu 80c32 clock=24000000 firmware latch.ihx\nsilence 1ms\n"
      "expect port outputs 7\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, d.dir / "t.scn", engine);
    EXPECT_TRUE(w.errors.empty()) << (w.errors.empty() ? "" : w.errors.front());
    ASSERT_EQ(w.outcome.port_writes.size(), 1u);
    EXPECT_EQ(w.outcome.port_writes[0].port, "outputs");
    EXPECT_EQ(w.outcome.port_writes[0].cycle, 204u);
    EXPECT_EQ(w.outcome.port_writes[0].value, 7u);
    std::size_t port_lines = 0;
    for (const std::string& l : w.lines) {
      if (l.find("80C32 at ") != std::string::npos && l.find(" = ") != std::string::npos) {
        ++port_lines;
        EXPECT_NE(l.find(": outputs = "), std::string::npos) << l;
      }
    }
    EXPECT_EQ(port_lines, 1u);
    EXPECT_EQ(w.outcome.passed, 1u);
  }
}

// A slave locked by another master (Slave_Diag byte 3, Master_Add, neither FFh nor ours:
// chip-facts.md "Slave_Diag") is not parameterised; the walk says so (docs/scenario-format.md,
// `startup`), not "not ready after N tries" (the review s28 rev2 finding 3). The watchdog's 600 ms
// of silence (TWD 5 x 10 x 10 ms = 500 ms) returns the slave to Wait_Prm; master 3 takes it.
TEST(ScenarioWalk, AStartupOfASlaveLockedByAnotherMasterSaysSo) {
  const Walk w =
      run("profile dpc31\nbaud 1500000\nmaster address=2\nslave address=5 wd=5,10 wd_on=1 "
          "wd_base=10ms\nstartup\nsilence 600ms\nforeign_master address=3\nstartup\n"
          "expect dp_state Wait_Cfg\n",
          "lock.scn", dpc31::Engine::event);
  EXPECT_TRUE(w.errors.empty()) << w.errors.front();
  std::size_t at = 0;
  while (at < w.lines.size() && w.lines[at].find("] line 8: startup") == std::string::npos) ++at;
  ASSERT_LT(at, w.lines.size());
  int said = 0;
  for (std::size_t i = at; i < w.lines.size(); ++i) {
    EXPECT_EQ(w.lines[i].find("Set_Prm"), std::string::npos) << w.lines[i];
    said += w.lines[i].ends_with(
        "] startup: slave locked by master 3 (its Slave_Diag's Master_Add): not parameterised");
  }
  EXPECT_EQ(said, 1);
}

// On one chip too the master's idle time counts from the end of the last telegram on the line:
// after a wait without an answer, a late answer that comes before the next request moves it to
// TSYN after that answer's end (docs/timing.md, "The master's wait"; until the thirty-third
// session the request started as its step did, into the late answer). 1.5 Mbaud, T = 32:
// MinTSDR 60 bit times is past the slot time 37, so every answer is late: the start-up's Set_Prm
// is unanswered, so it sends no Chk_Cfg (docs/scenario-format.md `startup`), and `chk_cfg` brings
// the slave to Data_Exchange, where it answers with its inputs. The first `exchange`'s
// repeat ends at E; its wait at E + 37 T; the `silence 40bits` step starts TSYN later and ends at
// S = E + 110 T. The late answer (the FCB repeat's, SD2 with 4 input bytes: 13 characters, 143 T)
// runs from E + 60 T to E + 203 T, so the step's Data_Exchange starts at E + 236 T = S + 126 T.
// The walk tells that late answer once, at its end, S + 93 T (docs/timing.md: "told once in
// `dpc31 run`'s walk ... at the end of its last stop bit"; until the thirty-fourth session never).
TEST(ScenarioWalk, OnOneChipALateAnswerOnTheLineIsWaitedFor) {
  const Walk w =
      run("profile spc3\nbaud 1500000\nmaster address=2 slot=37\nslave address=5 min_tsdr=60\n"
          "startup\nchk_cfg\nexchange 1\nsilence 40bits\nexchange 1\n",
          "late.scn", dpc31::Engine::event);
  const auto cycle_of = [&w](std::string_view text, std::size_t from) {
    for (std::size_t i = from; i < w.lines.size(); ++i) {
      if (w.lines[i].find(text) != std::string::npos)
        return std::pair{
            std::uint64_t{std::stoull(w.lines[i].substr(w.lines[i].find("cycle") + 5))}, i};
    }
    ADD_FAILURE() << "no walk line with " << text;
    return std::pair{std::uint64_t{0}, w.lines.size()};
  };
  const auto [step, at] = cycle_of("] line 9: exchange 1", 0);
  EXPECT_EQ(cycle_of("] 2 -> 5 Data_Exchange", at).first, step + 126 * 32);
  const std::string told = fmt::format(
      "[cycle {:>10}] master: a late answer on the line (after the slot time): no answer",
      step + 93 * 32);
  EXPECT_EQ(std::count(w.lines.begin(), w.lines.end(), told), 1) << told;
}

// A host user side that never starts the chip (the GLOBALS plug-in of tests/bad_plugin.c: its
// init only writes its port): the chip stays Offline in its reset states, Wait_Prm and
// Baud_Search (docs/timing.md), and the walk says so at cycle 0, where the init made no bus access
// (docs/scenario-format.md, "The walk"), and never `started:`; the trace's heading names it.
TEST(ScenarioWalk, AHostUserSideThatNeverStartsTheChipIsSaid) {
  const std::string text =
      fmt::format("profile spc3\nbaud 1500000\nfirmware {}\nsilence 1ms\n", BAD_PLUGIN_GLOBALS);
  const std::string not_started =
      "not started: dp_state Wait_Prm, wd_state Baud_Search, the chip Offline (the user side gave "
      "no Start_SPC3)";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    dpc31::TraceRecorder rec(1'500'000);
    const Walk w = run(text, fs::path(SOURCE_DIR) / "t.scn", engine, &rec);
    EXPECT_TRUE(w.errors.empty()) << (w.errors.empty() ? "" : w.errors.front());
    EXPECT_TRUE(w.has("[cycle          0] " + not_started));
    for (const std::string& l : w.lines) {
      EXPECT_EQ(l.find("] started:"), std::string::npos) << l;
      EXPECT_EQ(l.find("] offline:"), std::string::npos) << l;
    }
    EXPECT_EQ(user_side_heading(rec.text()), "# user side: the host firmware BAD; " + not_started);
  }
}

// docs/scenario-format.md, "Exact cycles": its example runs as written (with the default
// header) and both its checks hold; it said 2915904 for a run that enters Data_Exchange at
// 2915900 (audit s30 a-docs, finding 1).
TEST(ScenarioWalk, TheExactCyclesExampleOfTheDocsRunsAsWritten) {
  const std::string doc = file_text(fs::path(SOURCE_DIR) / "docs" / "scenario-format.md");
  const std::size_t at = doc.find("```\nstartup\nexpect dp_state Data_Exchange at ");
  ASSERT_NE(at, std::string::npos);
  const std::size_t from = at + 4;
  const std::string text = doc.substr(from, doc.find("```", from) - from);
  const Walk w = run(text, fs::path(SOURCE_DIR) / "t.scn", dpc31::Engine::event);
  EXPECT_TRUE(w.errors.empty()) << (w.errors.empty() ? "" : w.errors.front());
  EXPECT_EQ(w.outcome.passed, 2u);
  EXPECT_TRUE(w.outcome.ok()) << (w.outcome.ok() ? "" : w.outcome.failures.front());
}

// docs/scenario-format.md, `request`: a queue the user side has not set up (InstQ_Len 0) is
// reported at run time (exit 1) and nothing is written; the walk's line says it (it was an empty
// line, audit s30 a-docs, finding 2).
TEST(ScenarioWalk, ARequestOnAQueueNotSetUpIsSaidInTheWalk) {
  const std::string text = "startup\nwrite InstQ_Len 0\nrequest MAC_Stop\n";
  const Walk w = run(text, fs::path(SOURCE_DIR) / "t.scn", dpc31::Engine::event);
  const std::string why = "request: the Instruction_Queue is not set up (InstQ_Len 0)";
  ASSERT_EQ(w.outcome.failures.size(), 1u);
  EXPECT_EQ(w.outcome.failures[0], (fs::path(SOURCE_DIR) / "t.scn").string() + ":3: " + why);
  EXPECT_NE(walk_cycle(w, why), 0u);
  for (const std::string& l : w.lines) EXPECT_GT(l.size(), 19u) << "an empty walk line";
}

// An SPC3 firmware that gives its Cfg verdict but never reads New_Din_Buffer_Cmd (here the
// built-in user side with New_Cfg_Data masked, C0F0h being its own mask, and the scenario's `read`
// as the verdict) keeps the chip in Wait_Cfg: SPC3 p.31, "the transition to 'DATA_EX' takes place
// immediately, if no Din_buffer is present (R_Len_Din_Puf = 00H) ... Otherwise" (modelled: at the
// next New_Din_Buffer_Cmd, docs/decisions.md). The walk (what `dpc31 run` prints) says why once,
// at the first Slave_Diag from Master_Add acted on 10 ms = 480 000 cycles or more after the
// verdict read's completion cycle V. At 12 Mbaud (T = 4 cycles) the second `startup` sends
// FDL_Status at V (6 characters, TSDR 11, its OK 6 characters, idle 33: 176 bit times), then
// Slave_Diag every 352 bit times = 1 408 cycles from V + 704 (the request 11 characters = 121 bit
// times, TSDR 11, the DL answer of 6 bytes 17 characters = 187, idle 33). Poll k is acted on at
// the stop sample of its last character (docs/timing.md): V + 704 + 1408k + 484 - 4 + 2 =
// V + 1186 + 1408k; the first at or past V + 480 000 is k = 341, at V + 481 314. A firmware that
// makes the read (the built-in user side as it is) is never told.
TEST(ScenarioWalk, AnSpc3FirmwareThatNeverReadsNewDinBufferCmdIsToldOnce) {
  const std::string warning =
      "chip: master 2 is refused (Slave_Diag with Station_Not_Ready): the SPC3 is still in "
      "Wait_Cfg at least 10 ms after User_Cfg_Data_Okay, because the firmware has not read "
      "New_Din_Buffer_Cmd since; with R_Len_Din_Buf = 4 it enters Data_Exchange only at that read "
      "(SPC3 p.31, modelled). Hand the inputs over once after User_Cfg_Data_Okay: write them into "
      "the U buffer, then read New_Din_Buffer_Cmd (docs/bring-up.md)";
  const std::string head =
      "profile spc3\nbaud 12000000\nmaster address=2\nslave address=5\nuser inputs=A1,A2,A3,A4\n";
  const std::string forgets = head +
                              "write Int_Mask_Reg 0xC4F0\nstartup tries=20\n"
                              "read User_Cfg_Data_Okay\nexpect read 0x00\nstartup tries=400\n"
                              "expect dp_state Wait_Cfg\n";
  const std::string reads = head + "startup\nexpect dp_state Data_Exchange\nexchange 400\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    Walk w = run(forgets, fs::path(SOURCE_DIR) / "t.scn", engine);
    EXPECT_TRUE(w.outcome.ok()) << (w.outcome.ok() ? "" : w.outcome.failures.front());
    const std::uint64_t verdict = walk_cycle(w, "read User_Cfg_Data_Okay = 0x00");
    ASSERT_NE(verdict, 0u);
    EXPECT_EQ(walk_cycle(w, warning), verdict + 481'314);
    EXPECT_EQ(std::count_if(w.lines.begin(), w.lines.end(),
                            [](const std::string& l) {
                              return l.find("] chip: master ") != std::string::npos;
                            }),
              1);
    w = run(reads, fs::path(SOURCE_DIR) / "t.scn", engine);
    EXPECT_TRUE(w.outcome.ok()) << (w.outcome.ok() ? "" : w.outcome.failures.front());
    for (const std::string& l : w.lines)
      EXPECT_EQ(l.find("New_Din_Buffer_Cmd"), std::string::npos) << l;
  }
}

// The same mistake in a firmware plug-in (tests/input_only_plugin.c with FORGETS_DIN: the dps
// driver, its ISR preceded by one that reads User_Cfg_Data_Okay on New_Cfg_Data and nothing else)
// under the default `startup`: the walk says it once. Its verdict read completes at V (the run's
// own bus reads); the Slave_Diag polls start at S (the walk's first `Slave_Diag => DL 02 0C ...`
// line) and every 1 408 cycles after it, each acted on 482 cycles after its start (as above), so
// the line comes at the first S + 482 + 1408k at or past V + 480 000.
TEST(ScenarioWalk, APlugInThatNeverReadsNewDinBufferCmdIsToldOnce) {
  const std::string text = fmt::format(
      "profile spc3\nbaud 12000000\nfirmware {}\nslave address=5\nstartup\n"
      "expect dp_state Wait_Cfg\n",
      PLUGIN_FORGETS_DIN);
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, fs::path(SOURCE_DIR) / "t.scn", engine);
    EXPECT_TRUE(w.outcome.ok()) << (w.outcome.ok() ? "" : w.outcome.failures.front());
    const std::uint64_t verdict = w.read_after(SPC3_User_Cfg_Data_Okay, SPC3_User_Cfg_Data_Okay);
    const std::uint64_t polls = walk_cycle(w, "2 -> 5 Slave_Diag => DL 02 0C 00 02 0E 10");
    ASSERT_NE(verdict, 0u);
    ASSERT_GT(polls, verdict);
    const std::uint64_t k = (verdict + 480'000 - polls - 482 + 1407) / 1408;
    std::vector<std::string> said;
    for (const std::string& l : w.lines) {
      if (l.find("] chip: master 2 is refused") != std::string::npos) said.push_back(l);
    }
    ASSERT_EQ(said.size(), 1u);
    EXPECT_TRUE(
        said[0].starts_with(fmt::format("[cycle {:>10}] chip: master 2 is refused (Slave_Diag "
                                        "with Station_Not_Ready): the SPC3 is still in "
                                        "Wait_Cfg at least 10 ms after User_Cfg_Data_Okay",
                                        polls + 482 + 1408 * k)))
        << said[0];
  }
}

}  // namespace
}  // namespace scenario_walk
