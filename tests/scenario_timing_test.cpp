// Scenario runs at exact cycles (docs/scenario-format.md, "Exact cycles"; docs/timing.md): state
// changes, the DP watchdog against a request, X/INT, bus accesses, the slot time and MinTSDR.
#include <fmt/core.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "scenario_test.hpp"

using namespace scenario_test;

// `at CYCLE` / `after N` (docs/scenario-format.md, "Exact cycles"): User_Leave_Master acts at
// the completion cycle of its write, which begins with the step and takes 4 clocks
// (docs/timing.md, "Bus accesses", "Mode and state changes"). The step's first cycle comes from
// the observer; the walk must show the change exactly there.
TEST(ScenarioRun, StateEnteredAtAndAfterExactCycles) {
  struct Begin : dpc31::ScenarioObserver {
    std::vector<std::uint64_t> at;
    void step_begins(std::uint64_t c, const dpc31::ScenarioStep& st, std::string_view) override {
      if (st.kind == dpc31::StepKind::write) at.push_back(c);
    }
  } begin;
  const std::string text =
      "profile spc3\nbaud 12000000\nstartup\nexchange\n"
      "write Mode_Reg1_S 0x08\n"
      "expect dp_state Wait_Prm after 4\n"
      "expect dp_state Wait_Prm after 5   # wrong on purpose\n"
      "expect wd_state DP_Control after 0  # entered before the write: fails\n";
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  ASSERT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  dpc31::ScenarioHooks hooks;
  hooks.observer = &begin;
  Lines walk;
  Lines errors;
  const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, walk.sink(), errors.sink(), hooks);
  ASSERT_EQ(begin.at.size(), 1u);
  const std::uint64_t done = begin.at[0] + 4;
  EXPECT_TRUE(walk.has(fmt::format("[cycle {:>10}] dp_state Data_Exchange -> Wait_Prm", done)));
  ASSERT_EQ(errors.lines.size(), 2u);
  EXPECT_EQ(errors.lines[0], "t.scn:7: expected dp_state Wait_Prm after 5, got Wait_Prm after 4");
  EXPECT_TRUE(errors.lines[1].starts_with(
      "t.scn:8: expected wd_state DP_Control after 0, got DP_Control since cycle "))
      << errors.lines[1];
  EXPECT_EQ(o.passed, 1u);

  // The same change by its absolute cycle.
  const std::string at = text.substr(0, text.find("expect")) +
                         fmt::format("expect dp_state Wait_Prm at {}\n", done) +
                         fmt::format("expect dp_state Wait_Prm at {}\n", done - 1);
  ASSERT_TRUE(dpc31::parse_scenario(at, "t.scn", s, err)) << err.text();
  Lines errors2;
  const dpc31::ScenarioOutcome o2 = dpc31::run_scenario(s, {}, errors2.sink());
  EXPECT_EQ(o2.passed, 1u);
  ASSERT_EQ(errors2.lines.size(), 1u);
  EXPECT_EQ(errors2.lines[0], fmt::format("t.scn:7: expected dp_state Wait_Prm at {}, got "
                                          "Wait_Prm at {}",
                                          done - 1, done));
}

// The DP watchdog against a request (audit a17, findings 1 and 6). SPC3 at 12 Mbaud, wd=1,1
// with the 1 ms base: TWD = 1 x 1 x 1 ms = 48 000 clocks, "expiry at last restart + TWD:
// WD_DP_Control_Timeout, Baud_Control, Leave_Master, all in that cycle" (docs/timing.md, "DP
// watchdog"; docs/scenario-format.md, "Exact cycles"). A Data_Exchange of 4 + 4 bytes is 13
// characters; it restarts the watchdog when it is acted on, at its last stop sample:
// (13 x 11 - 1) x 4 + 2 = 570 clocks after it starts (4 clocks per bit). The last restart is
// read off the line (the request's start); the next request is then placed `into` clocks before
// the expiry (the silence before it set to match).
struct WdRace {
  static constexpr std::uint64_t kActedOn = (13 * 11 - 1) * 4 + 2;
  static constexpr std::uint64_t kTwd = 48'000;
  struct Line : dpc31::ScenarioObserver {
    std::vector<std::uint64_t> starts;  // requests on RxD
    std::uint64_t silence = 0;          // where the silence step begins
    void telegram_sent(std::uint64_t c, std::span<const std::uint8_t>, dpc31::UartFault) override {
      starts.push_back(c);
    }
    void step_begins(std::uint64_t c, const dpc31::ScenarioStep& st, std::string_view) override {
      if (st.kind == dpc31::StepKind::silence) silence = c;
    }
  };
  std::uint64_t silence_begins = 0;
  std::uint64_t expiry = 0;  // with no request after the silence

  // "expect WHAT at CYCLE" for each of `what`.
  static std::string expects_at(std::uint64_t cycle, std::initializer_list<std::string_view> what) {
    std::string out;
    for (const std::string_view w : what) out += fmt::format("expect {} at {}\n", w, cycle);
    return out;
  }
  // `next`: the request after the silence.
  static std::string text(std::uint64_t silence, const std::string& expects, bool next = true) {
    return fmt::format(
        "profile spc3\nbaud 12000000\nmaster address=2\n"
        "slave address=5 ident=0x0C31 cfg=13,23 in=4 out=4 wd=1,1 wd_on=1 wd_base=1ms\n"
        "user inputs=A1,A2,A3,A4\nstartup\nexchange outputs=01,02,03,04\nsilence {}\n{}{}",
        silence, next ? "exchange outputs=01,02,03,04\n" : "", expects);
  }
  WdRace() {
    dpc31::Scenario s;
    dpc31::ScenarioError err;
    EXPECT_TRUE(dpc31::parse_scenario(text(47'000, ""), "t.scn", s, err)) << err.text();
    Line probe;
    dpc31::ScenarioHooks hooks;
    hooks.observer = &probe;
    dpc31::run_scenario(s, {}, {}, hooks);
    std::uint64_t last = 0;  // the exchange step's request, the last before the silence
    for (std::uint64_t c : probe.starts)
      if (c < probe.silence) last = c;
    EXPECT_GT(last, 0u);
    silence_begins = probe.silence;
    expiry = last + kActedOn + kTwd;
  }
  // Runs `expects` after a request starting `into` clocks before the expiry on `engine`: the
  // walk into `walk`, the first cycle an on_state_change observer shows Data_Exchange left.
  struct Run {
    dpc31::ScenarioOutcome outcome;
    Lines walk;
    Lines errors;
    std::uint64_t request = 0;
    std::uint64_t left = 0;
  };
  // Every expect holds (`passed` of them) and the request starts where it was placed.
  [[nodiscard]] Run run(std::uint64_t into, dpc31::Engine engine, const std::string& expects,
                        unsigned passed) const {
    dpc31::Scenario s;
    dpc31::ScenarioError err;
    EXPECT_TRUE(
        dpc31::parse_scenario(text(expiry - into - silence_begins, expects), "t.scn", s, err))
        << err.text();
    s.chip.engine = engine;
    Run r;
    Line line;
    dpc31::ScenarioHooks h;
    h.observer = &line;
    h.at_start = [&r](dpc31::Chip& chip) {
      chip.on_state_change([&r, &chip, dx = false](std::uint64_t c) mutable {
        const bool now = chip.dp_state() == dpc31::DpState::Data_Exchange;
        if (dx && !now && r.left == 0) r.left = c;
        dx = now;
      });
    };
    r.outcome = dpc31::run_scenario(s, r.walk.sink(), r.errors.sink(), h);
    if (!line.starts.empty()) r.request = line.starts.back();
    EXPECT_EQ(r.request, expiry - into);
    EXPECT_EQ(r.outcome.failed, 0u) << (r.errors.lines.empty() ? "" : r.errors.lines[0]);
    EXPECT_EQ(r.outcome.passed, passed);
    return r;
  }
};

const char* engine_name(dpc31::Engine e) {
  return e == dpc31::Engine::event ? "event" : "per_cycle";
}

// Finding 1: the expiry falls 1 .. 569 clocks into the next request (on the line, acted on
// after it). The walk, `expect dp_state ... at` and an on_state_change observer all give the
// expiry's cycle, on both engines.
TEST(ScenarioRun, DpWatchdogExpiryDuringARequestAtItsCycle) {
  const WdRace race;
  const std::uint64_t e = race.expiry;
  const std::string expects = WdRace::expects_at(
      e, {"irq WD_DP_Control_Timeout", "wd_state Baud_Control", "dp_state Wait_Prm"});
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    for (const std::uint64_t into : {1u, 2u, 5u, 20u, 250u, 569u}) {
      SCOPED_TRACE(
          fmt::format("{} engine, expiry {} clocks into the request", engine_name(engine), into));
      const WdRace::Run r = race.run(into, engine, expects, 3);
      EXPECT_TRUE(r.walk.has(fmt::format("[cycle {:>10}] dp_state Data_Exchange -> Wait_Prm", e)));
      EXPECT_EQ(r.left, e);
    }
  }
}

// Finding 6 (docs/timing.md, "Order within one cycle"): a request acted on in the expiry's own
// cycle restarts the watchdog before the deadline is looked at, so the slave stays in
// Data_Exchange, answers with its inputs, and the next expiry is TWD after that request; one
// acted on a cycle later (DpWatchdogExpiryDuringARequestAtItsCycle, into = 569) is too late.
TEST(ScenarioRun, DpWatchdogExpiryAgainstARequestInOneCycle) {
  const WdRace race;
  const std::uint64_t next = race.expiry + WdRace::kTwd;  // restarted in the expiry's cycle
  const std::string expects =
      "expect dp_state Data_Exchange\nexpect wd_state DP_Control\nexpect inputs A1,A2,A3,A4\n" +
      fmt::format(
          "silence {}\nexpect dp_state Wait_Prm at {}\nexpect wd_state Baud_Control at {}\n",
          WdRace::kTwd, next, next);
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(fmt::format("{} engine", engine_name(engine)));
    const WdRace::Run r = race.run(WdRace::kActedOn, engine, expects, 5);
    const auto expired_at = [&r](std::uint64_t c) {
      return r.walk.has(fmt::format("[cycle {:>10}] chip: DP watchdog expired", c));
    };
    EXPECT_FALSE(expired_at(race.expiry));
    EXPECT_TRUE(expired_at(next));
    EXPECT_EQ(r.left, next);
  }
}

// The expiry with the line silent: "expiry at last restart + TWD: WD_DP_Control_Timeout,
// Baud_Control, Leave_Master, all in that cycle" (docs/timing.md, "DP watchdog"), and the
// Leave_Master from Data_Exchange is Go_Leave_Data_Exchange and the outputs cleared with DX_Out
// (docs/timing.md, User_Leave_Master; chip-facts §5.1). X/INT is looked at once after all of
// them (docs/timing.md, "Order within one cycle", steps 3 and 6), so `expect irq ... at` finds
// each of the three among the causes of the edge at the expiry, on both engines.
TEST(ScenarioRun, DpWatchdogExpiryShowsEveryEventAtItsEdge) {
  const WdRace race;
  const std::string expects =
      WdRace::expects_at(race.expiry, {"irq WD_DP_Control_Timeout", "irq Go_Leave_Data_Exchange",
                                       "irq DX_Out", "dp_state Wait_Prm"});
  for (const dpc31::Engine engine : {dpc31::Engine::event, dpc31::Engine::per_cycle}) {
    SCOPED_TRACE(fmt::format("{} engine", engine_name(engine)));
    dpc31::Scenario s;
    dpc31::ScenarioError err;
    // The silence reaches past the expiry: no request after the last restart.
    ASSERT_TRUE(
        dpc31::parse_scenario(WdRace::text(2 * WdRace::kTwd, expects, false), "t.scn", s, err))
        << err.text();
    s.chip.engine = engine;
    Lines errors;
    const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, {}, errors.sink());
    EXPECT_EQ(o.failed, 0u) << (errors.lines.empty() ? "" : errors.lines[0]);
    EXPECT_EQ(o.passed, 4u);
  }
}

// `expect irq` (docs/scenario-format.md): X/INT goes active in the cycle the event is latched
// (docs/timing.md, "Interrupt line": latency 0), here User_Leave_Master's Go_Leave_Data_Exchange
// at the completion of its write, 4 clocks after the step began; a wrong cycle or count fails
// and lists what X/INT did.
TEST(ScenarioRun, IrqActivationAtExactCycle) {
  const std::string text =
      "profile spc3\nbaud 12000000\nstartup\nexchange\n"
      "write Mode_Reg1_S 0x08\n"
      "expect irq Go_Leave_Data_Exchange after 4\n"
      "expect irq count 1\n"
      "expect irq Go_Leave_Data_Exchange after 5   # wrong on purpose\n"
      "expect irq count 2                          # wrong on purpose\n";
  Lines errors;
  const dpc31::ScenarioOutcome o = run_text(text, errors);
  EXPECT_EQ(o.passed, 2u);
  ASSERT_EQ(errors.lines.size(), 2u);
  EXPECT_TRUE(errors.lines[0].starts_with(
      "t.scn:8: expected irq Go_Leave_Data_Exchange after 5, got after 4 ("))
      << errors.lines[0];
  EXPECT_NE(errors.lines[0].find("Go_Leave_Data_Exchange"), std::string::npos);
  EXPECT_TRUE(errors.lines[1].starts_with("t.scn:9: expected irq count 2, got 1: after 4 ("))
      << errors.lines[1];
}

// `expect irq` after a long action: every activation counted, the one an expect names found
// however late, a failure listing the first 16 and how many more. SPC3 at 12 Mbaud, 4 + 4 bytes
// (docs/timing.md): a Data_Exchange is 13 characters each way, so the master's requests follow
// each other every 143 + TSDR 11 + 143 + TSYN 33 = 330 bit times = 1320 clocks; DX_Out goes active
// at each request's last stop sample, (13 x 11 - 1) x 4 + 2 = 570 clocks after its start, the
// first request starting as the action begins (the line idle since the start-up for longer than
// TSYN).
TEST(ScenarioRun, ALongActionCountsEveryIrqAndFindsTheOneAnExpectNames) {
  const std::string text =
      "profile spc3\nbaud 12000000\nslave address=5 cfg=13,23 in=4 out=4\nuser user_wd=1\n"
      "startup\nexchange 3000 outputs=01,02,03,04\n"
      "expect irq count 3000\n"
      "expect irq DX_Out after 3959250  # the 3000th: 570 + 2999 x 1320\n"
      "inputs 05,06,07,08               # no action: the expects after it judge the exchanges\n"
      "expect irq DX_Out after 1320570  # the 1001st: 570 + 1000 x 1320\n"
      "expect irq DX_Out after 3959251  # wrong on purpose\n";
  Lines errors;
  const dpc31::ScenarioOutcome o = run_text(text, errors);
  EXPECT_EQ(o.passed, 3u);
  ASSERT_EQ(errors.lines.size(), 1u);
  std::string listed;
  for (int k = 0; k < 16; ++k) listed += fmt::format(", after {} (DX_Out)", 570 + k * 1320);
  // The 1001st and the 3000th are kept too (expects name their cycles): 18 listed, 2982 more.
  listed += ", after 1320570 (DX_Out), after 3959250 (DX_Out), and 2982 more";
  EXPECT_EQ(errors.lines[0],
            "t.scn:11: expected irq DX_Out after 3959251, got " + listed.substr(2));
}

// A register read through the scenario is two bus accesses of 4 clocks each, in the bus mode's
// byte placement (docs/timing.md "Bus accesses"; Motorola: the lower address holds bits 15..8,
// docs/registers.md "hi,lo"), made when the step begins.
TEST(ScenarioRun, RegisterAccessesAreBusAccessesInByteOrder) {
  const std::string text =
      "profile spc3\nbus motorola\nread Status_Reg\nwrite Int_Mask_Reg 0x1234\n";
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  ASSERT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  struct Access {
    std::uint64_t cycle;
    bool write;
    std::uint32_t addr;
    std::uint8_t data;
  };
  std::vector<Access> all;
  struct Begin : dpc31::ScenarioObserver {
    std::uint64_t first = 0;
    void step_begins(std::uint64_t c, const dpc31::ScenarioStep& st, std::string_view) override {
      if (st.kind == dpc31::StepKind::read) first = c;
    }
  } begin;
  dpc31::ScenarioHooks hooks;
  hooks.observer = &begin;
  hooks.at_start = [&](dpc31::Chip& chip) {
    chip.on_bus_access([&](std::uint64_t c, const dpc31::BusAccess& a) {
      all.push_back({c, a.write, a.addr, a.write ? a.data : std::uint8_t{0}});
    });
  };
  const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, {}, {}, hooks);
  EXPECT_TRUE(o.ok());
  const std::uint64_t t = begin.first;
  std::vector<Access> mine;
  for (const Access& a : all)
    if (a.cycle > t) mine.push_back(a);
  ASSERT_EQ(mine.size(), 4u);
  EXPECT_EQ(mine[0].cycle, t + 4);
  EXPECT_FALSE(mine[0].write);
  EXPECT_EQ(mine[0].addr, 0x04u);
  EXPECT_EQ(mine[1].cycle, t + 8);
  EXPECT_EQ(mine[1].addr, 0x05u);
  EXPECT_EQ(mine[2].cycle, t + 12);
  EXPECT_TRUE(mine[2].write);
  EXPECT_EQ(mine[2].addr, 0x04u);
  EXPECT_EQ(mine[2].data, 0x12);
  EXPECT_EQ(mine[3].cycle, t + 16);
  EXPECT_EQ(mine[3].addr, 0x05u);
  EXPECT_EQ(mine[3].data, 0x34);
}

// The slot time is the wait for an answer's first character (docs/timing.md, "The master's
// wait"): an answer later than it is no answer, and no later request takes it for its own. The
// slave answers MinTSDR 120 bit times after each request, the master waits 100 (the audit's
// case: without the rule the Get_Cfg took the late FDL_Status answer, the second FDL_Status the
// late Get_Cfg answer).
TEST(ScenarioRun, AnAnswerLaterThanTheSlotTimeIsNoLaterRequestsAnswer) {
  Lines walk;
  Lines errors;
  const TempFile f(
      "profile spc3\nbaud 12000000\nmaster slot=100 retries=0\nslave min_tsdr=120\n"
      "startup tries=3\nfdl_status\nexpect answer none\nget_cfg\nexpect answer none\n"
      "fdl_status\nexpect answer none\nexchange 2\nexpect answer none\n");
  EXPECT_EQ(dpc31::run_scenario_file(f.path(), walk.sink(), errors.sink()), 0);
  EXPECT_TRUE(errors.lines.empty()) << errors.lines.front();
  // From the Set_Prm on (MinTSDR 120) every answer is late: none is taken.
  const auto prm = std::find_if(walk.lines.begin(), walk.lines.end(), [](const std::string& l) {
    return l.find("Set_Prm") != std::string::npos;
  });
  ASSERT_NE(prm, walk.lines.end());
  int requests = 0;
  for (auto l = prm; l != walk.lines.end(); ++l) {
    if (l->find(" -> 5 ") == std::string::npos) continue;
    ++requests;
    EXPECT_NE(l->find("=> no answer"), std::string::npos) << *l;
  }
  EXPECT_GE(requests, 6);
}

// The answer delay is the MinTSDR set last: Set_Prm byte 3 when not 0 (0 keeps it), a
// MinTSDR_Val write, the DPC31's MAC_New_TRDY (docs/timing.md "answer"; the audit's tsdr1.scn). At
// 12 Mbaud T = 4 clocks; a Data_Exchange of 4 bytes and its DL answer are 13 characters, 572
// clocks each, so one exchange step is 572 + TSDR x 4 + 572 + 33 x 4 (TSYN): 1356 at TSDR 20,
// 1436 at TSDR 40 (docs/timing.md's answer and master's idle rows).
TEST(ScenarioRun, MinTsdrIsTheOneSetLast) {
  const auto run = [](const std::string& profile, const std::string& set_40) {
    Lines walk;
    Lines errors;
    const TempFile f("profile " + profile +
                     "\nbaud 12000000\nmaster address=2\n"
                     "slave address=5 ident=0x0C31 cfg=13,23 in=4 out=4 min_tsdr=20\n"
                     "user inputs=A1,A2,A3,A4\nstartup\n"
                     "exchange outputs=01,02,03,04\nexchange outputs=01,02,03,04\n" +
                     set_40 +
                     "\nexchange outputs=01,02,03,04\nexchange outputs=01,02,03,04\n"
                     "set_prm min_tsdr=0\nchk_cfg\n"
                     "exchange outputs=01,02,03,04\nexchange outputs=01,02,03,04\n"
                     "set_prm min_tsdr=20\nchk_cfg\n"
                     "exchange outputs=01,02,03,04\nexchange outputs=01,02,03,04\n");
    EXPECT_EQ(dpc31::run_scenario_file(f.path(), walk.sink(), errors.sink()), 0);
    std::vector<std::uint64_t> starts;
    for (const std::string& l : walk.lines) {
      if (l.find("2 -> 5 Data_Exchange") != std::string::npos)
        starts.push_back(std::stoull(l.substr(7)));
    }
    std::vector<std::uint64_t> steps;
    for (std::size_t i = 0; i + 1 < starts.size(); i += 2)
      steps.push_back(starts[i + 1] - starts[i]);
    return steps;
  };
  // Byte 3 = 20; the user's 40 wins over it; byte 3 = 0 keeps 40; byte 3 = 20 wins again.
  const std::vector<std::uint64_t> want = {1356, 1436, 1436, 1356};
  for (const char* p : {"spc3", "vpc3plus", "dpc31"}) {
    EXPECT_EQ(run(p, "write MinTSDR_Val 40"), want) << p;
  }
  EXPECT_EQ(run("dpc31", "request MAC_New_TRDY 40"), want);
}
