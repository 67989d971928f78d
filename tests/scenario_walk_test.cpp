// The walk's state lines and `expect dp_state/wd_state ... at` with a firmware on an 80C32
// (docs/scenario-format.md, "expect ... at"): a state change is noted at the cycle the chip makes
// it, which for a firmware's verdict is the completion cycle of its bus access, whoever looks
// next; a `cpu` firmware starts the chip at its own Start_SPC3, not at cycle 0.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/dpc31_regs.h"
#include "scenario.hpp"
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

const char* engine_name(dpc31::Engine e) {
  return e == dpc31::Engine::event ? "event" : "per_cycle";
}

// a19 finding 1: ECHO51 (tests/data/walk/echo51.c, an SPC3 firmware with only New_Prm_Data,
// New_Cfg_Data and DX_Out unmasked) accepts the Chk_Cfg and hands its first inputs over with
// New_Din_Buffer_Cmd; "the SPC3 waiting after Cfg OK enters Data_Exchange" at that read
// (docs/decisions.md, Cfg OK; docs/timing.md: an access acts at its completion cycle, the `rd`
// line's cycle of a recorded trace). That read is at 2 945 076 (the audit's --record:
// `rd 2945076 0009 = 02`; its VCD: state.dp_state -> 2 there). X/INT does not move there, and the
// next telegram ends 2 288 cycles later, where the walk used to see it.
TEST(ScenarioWalk, FirmwareMadeDataExchangeAtItsBusAccess) {
  const fs::path dir = fs::path(SOURCE_DIR) / "tests" / "data" / "walk";
  const std::string text =
      "profile spc3\nbaud 1500000\ncpu 80c32 clock=24000000 firmware echo51.ihx ports=out0\n"
      "slave address=9 ident=0x0E51 cfg=31 in=2 out=2 wd=2,5 user_prm=00\n"
      "startup\nexpect dp_state Data_Exchange at 2945076\n";
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, dir / "t.scn", engine);
    EXPECT_EQ(w.read_after(SPC3_User_Cfg_Data_Okay, SPC3_New_Din_Buffer_Cmd), 2'945'076u);
    EXPECT_TRUE(w.has("[cycle    2945076] dp_state Wait_Cfg -> Data_Exchange"));
    EXPECT_EQ(w.outcome.failed, 0u) << (w.errors.empty() ? "" : w.errors.front());
    EXPECT_EQ(w.outcome.passed, 1u);
  }
}

// The shipped DO4 scenario on the 80C32: its comment derives the User_Prm_Data_Okay read at
// M = 233 635, chip cycle 5 607 276, where the chip enters Wait_Cfg and the DP watchdog DP_Control
// (docs/timing.md, "DP watchdog": started at the completion cycle of that read). The EOI that
// used to be the walk's cycle comes 7 056 cycles later, at 5 614 332.
TEST(ScenarioWalk, Do4WatchdogDpControlAtTheUserPrmDataOkayRead) {
  const fs::path path = fs::path(FW51_DIR) / "do4_80c32.scn";
  std::string text = file_text(path);
  const std::string at = "\nexpect dp_state Data_Exchange at 5656596\n";
  const std::size_t i = text.find(at);
  ASSERT_NE(i, std::string::npos);
  text.insert(i + at.size(), "expect wd_state DP_Control at 5607276\n");
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(engine_name(engine));
    const Walk w = run(text, path, engine);
    EXPECT_EQ(w.read_after(SPC3_User_Prm_Data_Okay, SPC3_User_Prm_Data_Okay), 5'607'276u);
    EXPECT_TRUE(w.has("[cycle    5607276] dp_state Wait_Prm -> Wait_Cfg"));
    EXPECT_TRUE(w.has("[cycle    5607276] wd_state Baud_Control -> DP_Control"));
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
    EXPECT_NE(trace.find("# no built-in user side; not started: dp_state Wait_Prm, wd_state "
                         "Baud_Search, the chip Offline until the firmware's Start_SPC3\n"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace scenario_walk
