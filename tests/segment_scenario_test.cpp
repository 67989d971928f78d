// Segment scenarios (docs/scenario-format.md, "Segments"; split from segment_test.cpp at its
// second namespace): several `slave` blocks, masters and scripted stations from the scenario
// door, their `expect`s, bus checks and the walk, with the cycles docs/timing.md gives.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <typeinfo>
#include <vector>

#include "bus_check.hpp"
#include "dpc31/fdl.hpp"
#include "heap_in_use.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"
#include "test_files.hpp"
#include "vocabulary.hpp"

namespace dpc31 {
namespace {

// A segment scenario's text run: its exit code, the walk and the failed checks.
struct ScenarioRun {
  int code = 0;
  std::vector<std::string> walk;
  std::vector<std::string> errors;
  // The cycle of the walk's last line that contains `text` (0 when none does).
  [[nodiscard]] std::uint64_t cycle_of(std::string_view text) const {
    for (auto l = walk.rbegin(); l != walk.rend(); ++l) {
      if (l->find(text) != std::string::npos) return std::stoull(l->substr(l->find("cycle") + 5));
    }
    ADD_FAILURE() << "no walk line with " << text;
    return 0;
  }
};

ScenarioRun run_scenario_text(const std::string& text, const char* file = "s.scn") {
  SegmentScenario s;
  ScenarioError err;
  EXPECT_TRUE(parse_segment_scenario(text, file, s, err)) << err.text();
  ScenarioRun r;
  r.code = run_segment_scenario(
      s, [&r](const std::string& l) { r.walk.push_back(l); },
      [&r](const std::string& e) { r.errors.push_back(e); });
  return r;
}

// `expect visit` from the scenario door (docs/scenario-format.md, "Segments"): a master alone
// with ttr= claims the token at its first visit (TRR 0, TTH = TTR = 1000 bit times: both cycles,
// at 33 and 363 T, start before it) and passes it to itself; a wrong field fails with what the
// visit did.
TEST(SegmentScenario, ExpectVisitChecksTheMastersLastVisit) {
  const std::string head =
      "segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\n"
      "master 2 slaves=5,6 ttr=1000\nstartup\ncycle 1\n";
  const auto run = [](const std::string& text, std::vector<std::string>& errors) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_TRUE(parse_segment_scenario(text, "v.scn", s, err)) << err.text();
    return run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); });
  };
  // The start-up's last visit (docs/segment.md, "The start-up under TTR") is the Slave_Diag that
  // finds 6 ready: TSYN 33 + request 121 (11 characters) + TSDR 11 + answer 187 (17) + TSYN 33 +
  // the token 33 = 418 T, the next visit's TRR: TTH 582, cycles at 33 and 363 (T = 32 clocks).
  std::vector<std::string> errors;
  EXPECT_EQ(run(head + "expect visit 2 polled=5,6 rotation=418 hold=582 gap=none\n", errors), 0);
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_EQ(run(head + "expect visit 2 polled=5 rotation=0\n", errors), 1);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0],
            "v.scn:7: expected visit 2 polled=5 rotation=0, got polled 5,6, rotation 418 bit "
            "times, hold 582 bit times, gap none");
  // After the start-up alone the last visit polled no one (`none`, not an empty list: the audit
  // s28 aud2, finding 7): it carried the Slave_Diag to 6. The visit before it carried 6's Chk_Cfg
  // (13 characters), so its TRR is TSYN 33 + 143 + TSDR 11 + the SC 11 + TSYN 33 + the token 33 =
  // 264 bit times, TTH 736.
  errors.clear();
  EXPECT_EQ(run("segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\n"
                "master 2 slaves=5,6 ttr=1000\nstartup\nexpect visit 2 polled=5\n",
                errors),
            1);
  EXPECT_EQ(errors, std::vector<std::string>{
                        "v.scn:6: expected visit 2 polled=5, got polled none, start-up 6, rotation "
                        "264 bit times, hold 736 bit times, gap none"});
}

// A failed `expect tsdr` says the delays in bit times, as the check is written (docs/scenario-
// format.md: "expected X, got Y" in the check's own terms; the audit s28 aud2, finding 7). The
// start-up's five answers (FDL_Status, Slave_Diag, Set_Prm's SC, Chk_Cfg's SC, Slave_Diag) each
// start 11 T after their request's end (docs/timing.md: max(11, MinTSDR) with MinTSDR 11 after
// Start and no Set_Prm byte 3).
TEST(SegmentScenario, ExpectTsdrSaysTheDelaysInBitTimes) {
  const ScenarioRun r =
      run_scenario_text("segment\nstation 5 profile=spc3\nstartup\nexpect tsdr 12\n", "t.scn");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.errors, std::vector<std::string>{
                          "t.scn:4: expected tsdr 12, got 5 answers, delays 11..11 bit times"});
}

// A station's min_tsdr= and wd_base= (the single chip's `slave` options, docs/scenario-format.md
// "Segments"): the master's Set_Prm carries them. 12 Mbaud. MinTSDR 20 on station 6: its answers
// from the Set_Prm's SC on start 20 T after their request's end (docs/timing.md, "answer":
// max(11, MinTSDR) T; before it, FDL_Status and Slave_Diag at 11), so `expect tsdr 20` fails
// with the delays 11..20. The 1 ms base with wd=1,1 on station 5: TWD = 1 ms x 1 x 1, and left
// unpolled it expires 1 ms after its last restart (with the 10 ms base not within `run 2ms`).
TEST(SegmentScenario, AStationsMinTsdrAndWdBaseReachItsSetPrm) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3 wd=1,1 wd_base=1ms\n"
      "station 6 profile=dpc31 min_tsdr=20\nmaster 2 slaves=5,6\nstartup\ncycle 1 skip=5\n"
      "run 2ms\nexpect watchdog_expired 5 twd=1ms\nexpect tsdr 20\n",
      "t.scn");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.errors, std::vector<std::string>{
                          "t.scn:9: expected tsdr 20, got 11 answers, delays 11..20 bit times"});
}

// Two stations on one address and no `master` line: the default master polls every address once
// (one FCB state per slave). Both answer each of the start-up's five requests (docs/segment.md:
// FDL_Status, Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag) at the same MinTSDR: five collisions, the
// first driver keeping the line, so the master hears one answer and the start-up completes: both
// take every request and reach Data_Exchange, each checked by its name.
TEST(SegmentScenario, TwoStationsOnOneAddressArePolledOnceAndCollide) {
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario(
      "segment\nstation 5 name=first\nstation 5 name=twin profile=vpc3plus\nstartup\n"
      "expect collisions 5\nexpect state first Data_Exchange\n"
      "expect state twin Data_Exchange\n",
      "c.scn", s, err))
      << err.text();
  ASSERT_EQ(s.masters.size(), 1U);
  EXPECT_EQ(s.masters[0].slaves, (std::vector<std::uint8_t>{5}));
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); }),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
}

// The audit's twin2.scn (s34 aSeg, finding 7): two chips at station 5, checked by name (a
// station's name= in `expect state`, `expect watchdog_expired`, `expect port`). Both take every
// request to 5, but the SPC3 ('a') is not served its user watchdog (user_wd_value=1, docs/timing.md
// "user watchdog": it leaves Data_Exchange at its second Data_Exchange), so after five rotations
// 'b' is in Data_Exchange and 'a' in Wait_Prm; by address either check was the later line's
// station.
TEST(SegmentScenario, TwoStationsAtOneAddressAreCheckedByName) {
  const ScenarioRun r = run_scenario_text(
      "segment\nstation 5 name=b profile=dpc31 user_wd=1\n"
      "station 5 name=a profile=spc3 user_wd_value=1\nmaster 2 slaves=5\nstartup\ncycle 5\n"
      "expect state b Data_Exchange\nexpect state a Wait_Prm wd=DP_Control\n"
      "expect state a Data_Exchange\n",
      "twin2.scn");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.errors, std::vector<std::string>{"twin2.scn:9: expected state a Data_Exchange, got "
                                               "Wait_Prm / DP_Control"});
}

// docs/timing.md, "The master's wait": each telegram the master takes for a late answer is told
// once in the walk, at its end. 12 Mbaud (T = 4 clocks), MinTSDR 120 > TSL 100: from the Set_Prm
// on every answer is late. The Set_Prm (19 characters, 836 clocks) starts at P; its SC starts
// 120 T after its end (P + 1316) and ends 11 T later, P + 1360, the master's line; the request
// after it starts TSYN later, P + 1492, and is a Slave_Diag (FCB set: 7D), not a Chk_Cfg: the
// Set_Prm was not answered (docs/scenario-format.md `startup`), so the slave stays in Wait_Cfg.
// Of the 1000 tries the Set_Prm is one, then 999 Slave_Diags, each answered late: 1000 late
// answers, the bus check's `late_answer`s, and 999 lines, one for each but the last, which follows
// the start-up's last request (the master watches for one before its next request only).
TEST(SegmentScenario, ALateAnswerIsToldOnceInTheWalk) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000 slot=100\nstation 5 profile=spc3 min_tsdr=120\nmaster 2 slaves=5\n"
      "startup\nexpect state 5 Wait_Cfg\n",
      "late.scn");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  const std::uint64_t p = r.cycle_of("] master 2: 68 0D 0D 68 85 82 5D 3D 3E");
  const std::string told = fmt::format(
      "[cycle {:>10}] master 2: a late answer on the line (after the slot time): no answer",
      p + 1360);
  const auto at = std::find(r.walk.begin(), r.walk.end(), told);
  ASSERT_NE(at, r.walk.end()) << told;
  ASSERT_NE(at + 1, r.walk.end());
  EXPECT_EQ(*(at + 1),
            fmt::format("[cycle {:>10}] master 2: 68 05 05 68 85 82 7D 3C 3E FE 16", p + 1492));
  const auto count = [&r](std::string_view text) {
    return std::count_if(r.walk.begin(), r.walk.end(), [text](const std::string& l) {
      return l.find(text) != std::string::npos;
    });
  };
  EXPECT_EQ(count("] bus: late_answer: "), 1000);
  EXPECT_EQ(count("] master 2: a late answer"), 999);
}

// A long `cycle N` keeps the run's memory flat (docs/decisions.md): the masters' histories are
// not kept, nor the responders' output fetches. What the heap grew by over the `cycle` step
// (from its start to its end) with 2 000 DP cycles of two slaves is within 16 KiB of that with
// 200; without the trim every exchange's history stayed (about 0.5 MB more). ASan's allocator is
// not malloc's: there only the run.
TEST(SegmentScenario, ALongCycleStepKeepsTheMemoryFlat) {
  struct Heap : SegmentObserver {
    void step_begins(const SegmentStep& st, std::string_view) override {
      if (st.kind == SegmentStep::Kind::cycle) at_start = test::heap_in_use();
    }
    void step_ends(const SegmentStep& st) override {
      if (st.kind == SegmentStep::Kind::cycle) grown = test::heap_in_use() - at_start;
    }
    std::int64_t at_start = 0;
    std::int64_t grown = 0;
  };
  const auto grown = [](int cycles) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_TRUE(parse_segment_scenario(
        fmt::format("segment\nstation 5 profile=spc3 firmware=DO4 wd=1,1\n"
                    "station 6 profile=vpc3plus firmware=CNT2 wd=1,1\nmaster 2 slaves=5,6\n"
                    "startup\ncycle {}\nexpect state 5 Data_Exchange\n"
                    "expect state 6 Data_Exchange\n",
                    cycles),
        "long.scn", s, err))
        << err.text();
    Heap heap;
    std::vector<std::string> errors;
    EXPECT_EQ(run_segment_scenario(
                  s, {}, [&errors](const std::string& e) { errors.push_back(e); }, &heap),
              0);
    EXPECT_TRUE(errors.empty()) << errors.front();
    return heap.grown;
  };
  const std::int64_t short_run = grown(200);
  const std::int64_t long_run = grown(2000);
  if (test::kHeapCounted) {
    EXPECT_LE(long_run, short_run + 16 * 1024)
        << "grown by " << short_run << " bytes over 200 DP cycles, " << long_run << " over 2 000";
  }
}

// The user watchdog of a station with the built-in user side (docs/timing.md: it counts
// Data_Exchange telegrams; Res_User_WD, which the user side sets with Start_SPC3, loads
// R_User_WD_Value at the next Data_Exchange, each later one counts down, and the one that reaches
// 0 is not answered and makes Leave_Master). So with R_User_WD_Value = N and no service, the
// station answers Data_Exchanges 1..N and not N + 1. What each station did with every
// Data_Exchange request to it, in order: answered with its 4 input bytes, or not at all.
struct DataExchanges : SegmentObserver {
  enum class Answer : std::uint8_t { none, data, other };
  explicit DataExchanges(const SegmentScenario& s) {
    for (const SegmentStation& st : s.stations) address.push_back(st.slave.address);
  }
  void telegram(const LineTelegram& t) override {
    const fdl::Decoded d = fdl::decode(t.bytes);
    if (d.error != fdl::Error::none) return;
    if (t.from >= address.size()) {  // a master: the request a chip's next telegram answers
      asked.reset();
      if (d.frame.sd != fdl::SD4 && fdl::is_request(d.frame.fc) &&
          service_name(d.frame) == "Data_Exchange") {
        asked = d.frame.da;
        answers[d.frame.da].push_back(Answer::none);
      }
    } else if (asked && *asked == address[t.from]) {
      answers[*asked].back() = d.frame.du.size() == 4 ? Answer::data : Answer::other;
      asked.reset();
    }
  }
  std::vector<std::uint8_t> address;  // each chip station's, by its index on the segment
  std::optional<std::uint8_t> asked;
  std::map<std::uint8_t, std::vector<Answer>> answers;
};

DataExchanges run_exchanges(const std::string& text) {
  SegmentScenario s;
  ScenarioError err;
  EXPECT_TRUE(parse_segment_scenario(text, "uwd.scn", s, err)) << err.text();
  DataExchanges dx(s);
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(
                s, {}, [&errors](const std::string& e) { errors.push_back(e); }, &dx),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
  return dx;
}

// The default (R_User_WD_Value 0x1FF = 511, not served): Data_Exchanges 1..511 answered, the 512th
// not, and none answered with data after it (the station is in Wait_Prm; the master does not
// parameterise it again within `cycle`).
TEST(SegmentScenario, AStationWithoutUserWdLeavesDataExchangeAtIts512thDataExchange) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\nstartup\n"
      "cycle 511\nexpect state 5 Data_Exchange\nexpect state 6 Data_Exchange\ncycle 2\n"
      "expect state 5 Wait_Prm\nexpect state 6 Wait_Prm\n");
  for (const std::uint8_t a : {5, 6}) {
    const std::vector<A>& got = dx.answers.at(a);
    ASSERT_GE(got.size(), 513U) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin(), got.begin() + 511, A::data), 511) << "station " << int{a};
    EXPECT_EQ(got[511], A::none) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin() + 512, got.end(), A::data), 0) << "station " << int{a};
  }
}

// `user_wd=1`: the user side sets Res_User_WD on every DX_Out, so the count is loaded again at
// every next Data_Exchange and never reaches 0: 1 500 DP cycles, every Data_Exchange answered
// (the DPC31's DPS_User_Watchdog reset on every DX_Out as well).
TEST(SegmentScenario, AStationThatServesItsUserWatchdogStaysInDataExchange) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3 user_wd=1\n"
      "station 6 profile=vpc3plus user_wd=1\nstation 7 profile=dpc31 user_wd=1\nstartup\n"
      "cycle 1500\nexpect state 5 Data_Exchange\nexpect state 6 Data_Exchange\n"
      "expect state 7 Data_Exchange\n");
  for (const std::uint8_t a : {5, 6, 7}) {
    const std::vector<A>& got = dx.answers.at(a);
    EXPECT_EQ(got.size(), 1500U) << "station " << int{a};
    EXPECT_EQ(std::count(got.begin(), got.end(), A::data), 1500) << "station " << int{a};
  }
}

// `user_wd_value=3` without the service: Data_Exchanges 1..3 answered, the 4th not (the count
// loaded at the first, 2 and 1 at the next two, 0 at the fourth). The station beside it keeps
// the default.
TEST(SegmentScenario, UserWdValueSetsTheDataExchangeThatIsNotAnswered) {
  using A = DataExchanges::Answer;
  const DataExchanges dx = run_exchanges(
      "segment baud=12000000\nstation 5 profile=spc3 user_wd_value=3\nstation 6 profile=spc3\n"
      "startup\ncycle 3\nexpect state 5 Data_Exchange\ncycle 2\nexpect state 5 Wait_Prm\n"
      "expect state 6 Data_Exchange\n");
  const std::vector<A>& got = dx.answers.at(5);
  ASSERT_GE(got.size(), 5U);
  EXPECT_EQ(std::vector<A>(got.begin(), got.begin() + 4),
            (std::vector<A>{A::data, A::data, A::data, A::none}));
  EXPECT_EQ(std::count(got.begin() + 4, got.end(), A::data), 0);
  EXPECT_EQ(std::count(dx.answers.at(6).begin(), dx.answers.at(6).end(), A::data), 5);
}

// Bad input in a segment scenario: one line, FILE:LINE, nothing run (docs/bad-input.md).
TEST(SegmentScenario, BadLinesAreOneErrorWithTheirLine) {
  const std::pair<std::string, std::string> cases[] = {
      {"segment\nstation 5\nbogus 3\n", "f.scn:3: unknown command 'bogus'"},
      {"station 5\n", "f.scn:1: a segment scenario begins with 'segment'"},
      {"segment\nstation 5 firmware=DO4\nstation 6 firmware=NOPE\n",
       "f.scn:3: unknown firmware 'NOPE' (DO4, CNT2, or a plug-in path such as ./libmine.so)"},
      // `expect port` (s33 audit finding 8): a station with a firmware, one of its ports.
      {"segment\nstation 5\nexpect port 5 outputs 1\n",
       "f.scn:3: 'expect port' needs a firmware: station 5 runs the built-in user side"},
      {"segment\nstation 5 firmware=DO4\nexpect port 5 led 1\n",
       "f.scn:3: unknown port 'led' of DO4 (outputs, modul_ok)"},
      {"segment\nstation 5 firmware=DO4\nexpect port 6 outputs 1\n", "f.scn:3: no station 6"},
      // The token's options (docs/scenario-format.md, "Segments").
      {"segment\nstation 5\nmaster 2 hsa=9\n",
       "f.scn:3: hsa= without gap=: the HSA bounds the GAP the master polls"},
      {"segment\nstation 5\nmaster 9 gap=1 hsa=8\n", "f.scn:3: hsa=8 below the master's address 9"},
      {"segment\nstation 5\nmaster 2 ttr=1000\nmaster 3 ttr=2000\n",
       "f.scn:4: ttr=2000 differs from master 2's ttr=1000: give the bus check's TTR on the "
       "segment "
       "line (segment ttr=BITS)"},
      {"segment\nstation 5\nmaster 2 gap=0\n", "f.scn:3: gap 0 out of range (1..100)"},
      {"segment\nstation 5\nmaster 2 ttr=1000\ncycle 1 skip=5\n",
       "f.scn:4: cycle skip=: master 2 obeys the token (ttr=, gap=) and polls all its slaves"},
      {"segment\nstation 5\nmaster 2\nexpect visit 2\n",
       "f.scn:4: master 2 does not obey the token: give it ttr= or gap="},
      {"segment\nstation 5\nmaster 2 gap=1\nexpect visit 3\n", "f.scn:4: no master 3"},
      {"segment\nstation 5\nmaster 2 gap=1\nexpect visit 2 gap_answered=maybe\n",
       "f.scn:4: gap_answered='maybe': yes or no"},
      {"segment\nstation 5\nexpect state 9 Data_Exchange\n", "f.scn:3: no station 9"},
      {"segment\nstation 5\nstartup\nstation 6\n", "f.scn:4: 'station' after the first action"},
      // The built-in user side's options, checked as the single chip's `user` step checks them.
      {"segment\nstation 5\nstation 6 profile=spc3 firmware=DO4 user_wd=1\n",
       "f.scn:3: 'user_wd' configures the built-in user side; a firmware configures itself"},
      {"segment\nstation 5 user_wd_value=9 firmware=CNT2 profile=vpc3plus\n",
       "f.scn:2: 'user_wd_value' configures the built-in user side; a firmware configures itself"},
      {"segment\nstation 5\nstation 6 profile=dpc31 user_wd_value=5\n",
       "f.scn:3: user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads "
       "R_User_WD_Value only through its requests"},
      {"segment\nstation 5 user_wd_value=5\n",
       "f.scn:2: user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads "
       "R_User_WD_Value only through its requests"},
      {"segment\nstation 5 profile=spc3 user_wd=yes\n",
       "f.scn:2: bad value 'yes' for user_wd: 0 or 1"},
      {"segment\nstation 5 profile=spc3 user_wd_value=65536\n",
       "f.scn:2: user_wd_value 65536 out of range (0..65535)"},
      // The single chip's `slave` min_tsdr= and wd_base=, with its checks and words.
      {"segment\nstation 5 profile=spc3 min_tsdr=256\n",
       "f.scn:2: min_tsdr 256 out of range (0..255)"},
      {"segment\nstation 5 profile=spc3 wd_base=2ms\n", "f.scn:2: wd_base '2ms': 1ms or 10ms"},
      {"segment\nstation 5 profile=vpc3plus wd_base=1ms\n",
       "f.scn:2: wd_base= on profile vpc3plus needs DPV1_Enable (user_prm byte 0 bit 7): without "
       "DPV1 the VPC3+ takes WD_Base from Mode_Reg0, not from Set_Prm"},
      // A master's slaves are stations of the segment, named before or after it.
      {"segment\nstation 5\nmaster 2 slaves=9\nstartup\n", "f.scn:3: slaves=9: no station 9"},
      {"segment\nmaster 2 slaves=5,9\nstation 5\nstartup\n", "f.scn:2: slaves=5,9: no station 9"},
      // One FCB state per slave (EN 50170): a slave listed twice would see its FCB repeated.
      {"segment\nstation 5\nstation 6\nmaster 2 slaves=5,6,5\nstartup\n",
       "f.scn:4: slaves=5,6,5: station 5 twice"},
      // One name a station, chips, senders and masters alike: it is the station's scope in the
      // waveforms and names it in the log and in `send from=`.
      {"segment\nstation 5 name=a\nstation 6 name=a\nstartup\n",
       "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=a\nsender a\nstartup\n", "f.scn:3: a second station named 'a'"},
      {"segment\nsender x\nstation 5\nsender x\nstartup\n", "f.scn:4: a second station named 'x'"},
      {"segment\nstation 5\nmaster 2 slaves=5\nmaster 2 slaves=5\nstartup\n",
       "f.scn:4: a second station named 'master 2'"},
      // s35 audit aMix finding 6: a single chip's command or check is refused as such, not as an
      // unknown word (a segment's DPV1 is the gap docs/segment.md names).
      {"segment\nstation 5 profile=vpc3plus\nstartup\ndpv1_read slot=0 index=1 length=2\n",
       "f.scn:4: 'dpv1_read' is a single chip's command: not on a segment"},
      {"segment\nstation 5\nc2_initiate\n",
       "f.scn:3: 'c2_initiate' is a single chip's command: not on a segment"},
      {"segment\nstation 5\nrecord slot=0 index=1 data=01\n",
       "f.scn:3: 'record' is a single chip's command: not on a segment"},
      {"segment\nstation 5\nexchange 2\n",
       "f.scn:3: 'exchange' is a single chip's command: not on a segment"},
      // The board's `reset` (s35-cpu) belongs to a `cpu` header, which a segment has not.
      {"segment\nstation 5\nreset\n",
       "f.scn:3: 'reset' is a single chip's command: not on a segment"},
      {"segment\nstation 5\nexpect dpv1 refused\n",
       "f.scn:3: 'expect dpv1' is a single chip's check: not on a segment"},
      {"segment\nstation 5\nexpect answer rs\n",
       "f.scn:3: 'expect answer' is a single chip's check: not on a segment"},
      {"segment\nstation 5\nexpect reg Param_Reg 0x02\n",
       "f.scn:3: 'expect reg' is a single chip's check: not on a segment"},
      {"segment\nstation 5\nexpect pb3 1\n",
       "f.scn:3: 'expect pb3' is a single chip's check: not on a segment"},
      {"segment\nstation 5\nfrobnicate\n", "f.scn:3: unknown command 'frobnicate'"},
      // s35 audit aMix finding 5: names apart whose scopes are one (station_scope makes '/' a
      // '_') would be one module in a VCD, one set of wires in an LA-VCD, one --record file.
      {"segment\nstation 5 name=a/b\nstation 5 name=a_b\nstartup\n",
       "f.scn:3: a second station named 'a_b' in the waveform scope of 'a/b' (station5_a_b)"},
      {"segment\nstation 6 name=x.y\nstation 6 name=x-y\n",
       "f.scn:3: a second station named 'x-y' in the waveform scope of 'x.y' (station6_x_y)"},
      {"segment\nstation 5\nmaster 2\nstartup\npass_token from=9 to=2\n",
       "f.scn:5: pass_token from=9: no master of that address"},
      {"segment\nstation 5\n", "f.scn: only header commands: nothing to run"},
      // A word no command takes (a mistyped option: its `=` missing) is refused, never ignored,
      // in the single chip's words.
      {"segment\nstation 5\nstartup\nexpect state 5 Data_Exchange after_request 999999\n",
       "f.scn:4: 'expect state' takes a station and a DP state; unexpected 'after_request'"},
      {"segment\nstation 5\nstartup\nexpect state 5 Data_Exchange wd DP_Control\n",
       "f.scn:4: 'expect state' takes a station and a DP state; unexpected 'wd'"},
      {"segment\nstation 5\nstartup\nexpect tsdr 11 foo\n",
       "f.scn:4: 'expect tsdr' takes the bit times; unexpected 'foo'"},
      {"segment\nstation 5\nstartup\nexpect bus_violation collision 0 extra\n",
       "f.scn:4: 'expect bus_violation' takes a violation kind and a count; unexpected 'extra'"},
      {"segment baud=12000000 extra\n",
       "f.scn:1: 'segment' takes no arguments; unexpected 'extra'"},
      {"segment\nstation 5 6\n", "f.scn:2: 'station' takes a station address; unexpected '6'"},
      {"segment\nstation 5\nstartup foo\n",
       "f.scn:3: 'startup' takes no arguments; unexpected 'foo'"},
      {"segment\nstation 5\ncycle 2 3\n",
       "f.scn:3: 'cycle' takes the number of rotations; unexpected '3'"},
      {"segment\nstation 5\nrun 1ms 2ms\n", "f.scn:3: 'run' takes a time; unexpected '2ms'"},
      // The walk's form of a telegram (spaces) copied back, as the single chip's `send` says it.
      {"segment\nsender a\nsend from=a 10 05 02 49 50 16\n",
       "f.scn:3: send: the bytes are separated by commas (10,05,...); unexpected '05'"},
      // Every station is one: a name, and a master's address, once.
      {"segment\nsender a\nsender a\n", "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=a\nsender a\n", "f.scn:3: a second station named 'a'"},
      {"segment\nstation 5 name=\n", "f.scn:2: empty name for station 5"},
      // s33 audit finding 11: a control character would redraw or forge the walk's lines.
      {"segment\nstation 5 name=a\x1b[2J\n",
       "f.scn:2: the name for station 5 has a control character, byte 1Bh at offset 1"},
      {"segment\nsender r\x7f\n",
       "f.scn:2: the name for a sender has a control character, byte 7Fh at offset 1"},
      // At most 64 bytes (vocabulary.hpp kMaxStationName): a name is a waveform scope, a --record
      // file's name, in every capture comment (the audit's 66 000 made a corrupt pcapng).
      {"segment\nstation 5 name=" + std::string(65, 's') + "\n",
       "f.scn:2: a name of 65 bytes for station 5: at most 64"},
      {"segment\nsender " + std::string(66000, 'r') + "\n",
       "f.scn:2: a name of 66000 bytes for a sender: at most 64"},
      {"segment\nstation 5\nmaster 2\nmaster 2\n", "f.scn:4: a second station named 'master 2'"},
      {"segment\nstation 5\nmaster 5\n", "f.scn:3: master 5 at the address of station 5"},
      {"segment\nmaster 5\nstation 5\n", "f.scn:3: station 5 at the address of master 5"},
      {"segment\nstation 5\nstation 2\nstartup\n",
       "f.scn:3: station 2 at the address of master 2, the default master: give a 'master' line"},
      // Two chips at one address (the duplicate-address fault): a check by that address would
      // pick one in silence (s34 audit aSeg, finding 7); each is named instead.
      {"segment\nstation 5 name=b\nstation 5 name=a profile=spc3\nmaster 2 slaves=5\nstartup\n"
       "expect state 5 Data_Exchange\n",
       "f.scn:6: station 5 names 2 stations ('b' at line 2, 'a' at line 3): give the name of the "
       "one to check"},
      {"segment\nstation 5\nstation 5 name=a\nstartup\nexpect watchdog_expired 5 twd=10ms\n",
       "f.scn:5: station 5 names 2 stations ('station 5' at line 2, 'a' at line 3): give the name "
       "of the one to check"},
      {"segment\nstation 5 name=b firmware=DO4\nstation 5 name=a firmware=DO4\nstartup\n"
       "expect port 5 outputs 0\n",
       "f.scn:5: station 5 names 2 stations ('b' at line 2, 'a' at line 3): give the name of the "
       "one to check"},
      {"segment\nstation 5 name=6\nstation 6\nstartup\nexpect state 6 Wait_Prm\n",
       "f.scn:5: '6' is the name of one station and the address of another"},
      {"segment\nstation 5 name=a\nstartup\nexpect state b Wait_Prm\n",
       "f.scn:4: no station named 'b'"},
      // token_hold needs a TTR and a token passed between masters: else it could only count 0.
      {"segment\nstation 5\nstation 6\nmaster 2 slaves=5\nmaster 3 slaves=6\nstartup\n"
       "expect bus_violation token_hold 0\n",
       "f.scn:7: token_hold is checked on a line with two or more masters and a TTR (segment "
       "ttr=BITS or master ... ttr=BITS): without them it would always count 0"},
      {"segment ttr=1000\nstation 5\nstartup\nexpect bus_violation token_hold 0\n",
       "f.scn:4: token_hold is checked on a line with two or more masters and a TTR (segment "
       "ttr=BITS or master ... ttr=BITS): without them it would always count 0"},
      // A second `segment` line would replace the first's settings (docs/scenario-format.md: a
      // repeated header command is a parse error naming the first's line; the audit s28 aud2,
      // finding 6: the run was silently at the second's rate).
      {"# the line\nsegment baud=1500000\nsegment slot=200\nstation 5\nstartup\n",
       "f.scn:3: 'segment' given twice: first at line 2"},
      {"segment\nsegment baud=1500000\nstation 5\nstartup\n",
       "f.scn:2: 'segment' given twice: first at line 1"},
      // One slot range at every door (vocabulary.hpp kSlotBits).
      {"segment slot=36\nstation 5\nstartup\n", "f.scn:1: slot 36 out of range (37..16383)"},
      // The only rates the chips' baud search finds, refused in the single chip's words.
      {"segment baud=12345\nstation 5\nstartup\n",
       "f.scn:1: baud 12345 is not a PROFIBUS rate (9600, 19200, 45450, 93750, 187500, 500000, "
       "1500000, 3000000, 6000000, 12000000)"},
  };
  for (const auto& [text, want] : cases) {
    SegmentScenario s;
    ScenarioError err;
    EXPECT_FALSE(parse_segment_scenario(text, "f.scn", s, err)) << text;
    EXPECT_EQ(err.text(), want);
  }
  // With the segment line silent, the bus check takes the TTR its masters obey.
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario(
      "segment\nstation 5\nmaster 2 ttr=1200\nmaster 3 ttr=1200 gap=2 hsa=9\nstartup\n", "f.scn", s,
      err))
      << err.text();
  EXPECT_EQ(s.ttr_bits, 1200U);
  EXPECT_EQ(s.masters[1].gap_factor, 2U);
  EXPECT_EQ(s.masters[1].hsa, 9U);
  EXPECT_TRUE(s.masters[1].obeys_token);
  EXPECT_TRUE(is_segment_scenario("# a comment\n\nsegment baud=12000000\n"));
  EXPECT_FALSE(is_segment_scenario("profile spc3\n"));
  // A UTF-8 BOM from an editor is skipped, as the single chip's parser skips it.
  EXPECT_TRUE(is_segment_scenario("\xEF\xBB\xBFsegment\nstation 5\nstartup\n"));
  ASSERT_TRUE(parse_segment_scenario("\xEF\xBB\xBFsegment\nstation 5\nstartup\n", "f.scn", s, err))
      << err.text();
  EXPECT_EQ(s.stations.size(), 1U);
}

// The same for a run whose every check passes: exit 0, no failure.
ScenarioRun run_passing(const std::string& text) {
  ScenarioRun r = run_scenario_text(text);
  EXPECT_EQ(r.errors, std::vector<std::string>{});
  EXPECT_EQ(r.code, 0);
  return r;
}

// s33 audit finding 8: a station's firmware shows its port writes in the walk, named by station,
// and `expect port STATION NAME VALUE` checks them (docs/scenario-format.md, "Segments"). The
// GLOBALS plug-in (tests/bad_plugin.c) writes its run count to port "boots" in init, before any
// bus access: at cycle 0, and 1 on each station, as each runs an instance of its own with fresh
// globals (docs/firmware.md, "Instances").
TEST(SegmentScenario, AStationsFirmwarePortsAreInTheWalkAndChecked) {
  const std::string head = fmt::format(
      "segment\nstation 5 profile=spc3 firmware={0}\nstation 6 profile=vpc3plus firmware={0}\n"
      "run 1ms\n",
      BAD_PLUGIN_GLOBALS);
  const ScenarioRun r = run_scenario_text(head + "expect port 5 boots 1\nexpect port 6 boots 2\n");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.errors, std::vector<std::string>{"s.scn:6: expected port 6 boots 2, got 0x1 (0001)"});
  for (const char* station : {"station 5", "station 6"}) {
    const std::string line =
        fmt::format("[cycle          0] {}: BAD: boots = 0x1 (0001) at 0.000 us", station);
    EXPECT_NE(std::find(r.walk.begin(), r.walk.end(), line), r.walk.end()) << line;
  }
  // A name the firmware does not have: the single chip's words, at the check's line, before the
  // run (the plug-in's ports are known once it is loaded).
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario(head + "expect port 6 outputs 1\n", "s.scn", s, err));
  EXPECT_FALSE(bind_segment_plugins(s, err));
  EXPECT_EQ(err.text(), "s.scn:5: unknown port 'outputs' of BAD (boots)");
}

// docs/scenario-format.md: `expect tsdr` counts the answers the bus check pairs with their
// requests (docs/segment.md "Bus checks"): a scripted station's answer to an FDL_Status to 9
// 132 bit times after its end is the asked station's late answer (before TSL + TSYN = 133) and
// its delay counts; at 133 bit times the bus check calls it unsolicited and `expect tsdr 11`
// (the start-up's answers, each 11 bit times) holds. The audit's u133.scn.
TEST(SegmentScenario, ExpectTsdrCountsOnlyWhatTheBusCheckCallsAnAnswer) {
  for (const int after : {132, 133}) {
    const bool late = after == 132;
    const ScenarioRun r = run_scenario_text(fmt::format(
        "segment baud=1500000 slot=100\nstation 5 profile=spc3\nsender asker\nsender nine\n"
        "startup\nsend from=asker after=33bits 10,09,03,49,55,16\n"
        "send from=nine after={}bits 10,03,09,00,0C,16\nrun 1ms\n"
        "expect bus_violation late_answer {}\nexpect bus_violation unsolicited {}\n"
        "expect tsdr 11\n",
        after, late ? 1 : 0, late ? 0 : 1));
    ASSERT_EQ(r.errors.size(), late ? 1U : 0U) << after;
    if (late) {
      EXPECT_EQ(r.errors[0].substr(0, 27), "s.scn:11: expected tsdr 11,") << r.errors[0];
      EXPECT_NE(r.errors[0].find("delays 11..132 bit times"), std::string::npos) << r.errors[0];
    }
    EXPECT_EQ(r.code, late ? 1 : 0) << after;
  }
}

// Two masters without a TTR still pass a token, so a lost one is found (docs/segment.md, "Bus
// checks": TTO = TSL x (6 + 2 x 2) = 1000 bit times needs no TTR): the token to nobody (DC 09 02,
// 3 characters: its end 33 T = 1056 clocks after its start at 1.5 Mbaud) leaves the line idle,
// counted once at that end + 1000 T (32 000 clocks).
TEST(SegmentScenario, TwoMastersWithoutTtrCheckTheToken) {
  const ScenarioRun r = run_scenario_text(
      "segment\nstation 5 profile=spc3\nstation 6 profile=dpc31\nmaster 2 slaves=5\n"
      "master 3 slaves=6\nstartup\ncycle 2\npass_token from=2 to=9\nrun 2ms\n"
      "expect bus_violation token_lost 1\nexpect bus_violation duplicate_token 0\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  const std::uint64_t token = r.cycle_of("master 2: DC 09 02");
  EXPECT_EQ(r.cycle_of("bus: token_lost"), token + 1056 + 32000);
}

// s33 audit finding 3: docs/segment.md "The log": every line but a visit's token line is in cycle
// order. A `run` that leaves the line idle finds the lost token only at the step's end (stamped
// TTO = 100 x (6 + 2 x 2) = 1000 bit times, 32 000 clocks at 1.5 Mbaud, after the last telegram),
// and it came after the station's watchdog expiry 48 M cycles later. Now the walk of the run
// step is in cycle order, the token loss first.
TEST(SegmentScenario, ALostTokenFoundAtAStepsEndIsToldInCycleOrder) {
  const ScenarioRun r = run_scenario_text(
      "segment\nstation 5 profile=spc3\nmaster 2 slaves=5\nstartup\ncycle 2\nrun 1100ms\n"
      "expect bus_violation token_lost 1\n");
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  const std::uint64_t last = r.cycle_of("line 6: run");  // the line is quiet from here
  EXPECT_EQ(r.cycle_of("bus: token_lost"), last + 32000);
  std::uint64_t before = 0;
  bool in_run = false;
  for (const std::string& l : r.walk) {
    in_run = in_run || l.find("line 6: run") != std::string::npos;
    if (!in_run) continue;
    const std::uint64_t c = std::stoull(l.substr(l.find("cycle") + 5));
    EXPECT_LE(before, c) << l;
    before = c;
  }
  EXPECT_LT(r.cycle_of("bus: token_lost"), r.cycle_of("station 5: Wait_Prm"));
}

// Only actions move the line's time (docs/scenario-format.md, "Segments"): a master's action ends
// on a quiet line, at the end of the last answer's stop bit; an expect moves no time; `run T`
// lasts T; `send` counts its `after=` (33 bit times) from the quiet line and lasts to its
// telegram's end. At 12 Mbaud, T = 4 clocks.
TEST(SegmentScenario, OnlyActionsMoveTheLinesTime) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "expect state 5 Data_Exchange\nexpect state 5 Data_Exchange\n"
      "send from=a 10,05,02,49,50,16\nrun 1000\nexpect state 5 Data_Exchange\n"
      "expect bus_violation short_tsyn 0\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  // The start-up's last telegram, the Slave_Diag answer: 17 characters of 11 T from its start.
  const std::uint64_t quiet = r.cycle_of("line 6: expect");
  EXPECT_EQ(r.cycle_of("] station 5: 68 0B 0B 68 82 85 08") + 17 * 11 * 4, quiet);
  EXPECT_EQ(r.cycle_of("line 7: expect"), quiet);
  EXPECT_EQ(r.cycle_of("line 8: send"), quiet);
  const std::uint64_t sent = r.cycle_of("] a: 10 05 02 49 50 16");
  EXPECT_EQ(sent, quiet + 33 * 4);
  EXPECT_EQ(r.cycle_of("line 9: run"), sent + 6 * 11 * 4);
  EXPECT_EQ(r.cycle_of("line 10: expect"), sent + 6 * 11 * 4 + 1000);
  EXPECT_EQ(r.cycle_of("line 11: expect"), sent + 6 * 11 * 4 + 1000);
}

// A run with no telegram on the line at all (the segment has relayed none whole: its whole_start
// is "never") ends after its `run`s: nothing to finish at the end.
TEST(SegmentScenario, ALineWithoutATelegramEndsAfterItsRuns) {
  const ScenarioRun r =
      run_scenario_text("segment\nstation 5 profile=spc3\nrun 1000\nexpect state 5 Wait_Prm\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.cycle_of("line 4: expect"), r.cycle_of("line 3: run") + 1000);
  EXPECT_EQ(r.cycle_of("1 expects passed"), r.cycle_of("line 3: run") + 1000);
}

// A short TSYN names the station that sent, not the SA its frame carries: sender `a` sends a
// request in master 2's name 32 bit times after the start-up's last answer.
TEST(SegmentScenario, AShortTsynNamesItsSender) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "send from=a after=32bits 10,05,02,49,50,16\nrun 1000\nexpect bus_violation short_tsyn 1\n");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  EXPECT_NE(r.cycle_of("bus: short_tsyn: a sent after 32 bit times of idle (TSYN 33)"), 0U);
}

// The built-in master keeps TSYN after every telegram on the line, not only its own
// (docs/timing.md: a telegram after fewer than 33 idle bit times is ignored and counted `no_sync`;
// docs/scenario- format.md `idle=`: after the end of the line's last telegram; the audit s28 aud2,
// finding 1: it counted from its own traffic and started on the last bit of another station's
// token). At 12 Mbaud T = 4 clocks. A sender's token (DC 02 02, 3 characters: 33 T) ends 132 clocks
// after its first start bit; master 2's Data_Exchange (4 output bytes: SD2 with 13 characters)
// starts TSYN = 132 clocks later, and station 5 answers it (13 characters) 11 T after its end.
TEST(SegmentScenario, TheMasterKeepsTsynAfterAnotherStationsTelegram) {
  const ScenarioRun r = run_passing(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender r\nstartup\n"
      "cycle 1\nsend from=r after=200bits DC,02,02\ncycle 1\nexpect bus_violation short_tsyn 0\n"
      "expect state 5 Data_Exchange\n");
  const std::uint64_t token = r.cycle_of("] r: DC 02 02");
  const std::uint64_t request = r.cycle_of("] master 2: 68 07 07 68 05 02");
  EXPECT_EQ(request, token + 33 * 4 + 33 * 4);
  EXPECT_EQ(r.cycle_of("] station 5: 68 07 07 68 02 05"), request + 13 * 11 * 4 + 11 * 4);
}

// The audit s35 aMix, finding 1 (seg_plugin_dpv1.scn): a scripted class-1 station writes the
// record of a polling firmware (tests/dpv1_plugin.c, MSAC_C1 on SAP 51) beside DO4 and the built-in
// user side at 12 Mbaud: Read, Write, Read, each with its poll 1 ms later. Each poll is taken at
// its exact edges (no parity error, docs/segment.md "A firmware across a round's end": a sender's
// start is a hard end) and answered TSDR 11 bit times (T = 4) after its 11 characters end: the
// Write's response (its header), then the record as written. Until the thirty-fifth session the
// first poll reached the plug-in's CPU 2 clocks late and was lost, the Write got RR and the record
// was never written.
TEST(SegmentScenario, APollingFirmwareTakesEveryMsacC1PollAt12Mbaud) {
  const std::string poll = "send from=tool 68,05,05,68,85,82,4D,33,33,BA,16\nrun 1ms\n";
  const std::string read = "send from=tool 68,09,09,68,85,82,4D,33,33,5E,00,01,04,1D,16\nrun 1ms\n";
  const ScenarioRun r = run_passing(
      std::string("segment baud=12000000\nstation 5 name=plug profile=vpc3plus firmware=") +
      DPV1_PLUGIN +
      "\nstation 6 name=do4 profile=spc3 firmware=DO4\nstation 7 name=resp profile=dpc31\n"
      "master 2 slaves=5,6,7\nsender tool\nstartup\ncycle 3\n" +
      read + poll +
      "send from=tool 68,0D,0D,68,85,82,4D,33,33,5F,00,01,04,A1,A2,A3,A4,A8,16\nrun 1ms\n" + poll +
      read + poll +
      "cycle 3\nexpect state 5 Data_Exchange\nexpect state 6 Data_Exchange\n"
      "expect state 7 Data_Exchange\n");
  // Each answer and the last poll before it in the walk (the `run` step's line between them).
  const auto cycle = [](const std::string& l) {
    return std::stoull(l.substr(l.find("cycle") + 5));
  };
  const auto answered_at = [&](std::string_view answer) -> std::pair<std::uint64_t, std::uint64_t> {
    std::uint64_t poll = 0;
    for (const std::string& l : r.walk) {
      if (l.find("] tool: 68 05 05 68 85 82 4D 33 33 BA 16") != std::string::npos) poll = cycle(l);
      if (l.find(answer) != std::string::npos) return {poll, cycle(l)};
    }
    ADD_FAILURE() << "no answer " << answer;
    return {0, 0};
  };
  const std::uint64_t tsdr = (11 * 11 + 11) * 4;  // the poll's 11 characters, then 11 T
  const auto [first_poll, first_answer] =
      answered_at("] plug: 68 0D 0D 68 82 85 08 33 33 5E 00 01 04 11 22 33 44 82 16");
  EXPECT_EQ(first_answer, first_poll + tsdr);
  const auto [write_poll, write_answer] =
      answered_at("] plug: 68 09 09 68 82 85 08 33 33 5F 00 01 04 D9 16");
  EXPECT_EQ(write_answer, write_poll + tsdr);
  const auto [read_poll, read_answer] =
      answered_at("] plug: 68 0D 0D 68 82 85 08 33 33 5E 00 01 04 A1 A2 A3 A4 62 16");
  EXPECT_EQ(read_answer, read_poll + tsdr);
  EXPECT_LT(first_poll, write_poll);
  EXPECT_LT(write_poll, read_poll);
}

// The audit s35 aMix, findings 2 and 7 from the scenario door (tsyn_after_send.scn): the SPC3
// answers a scripted FDL_Status (6 characters) TSDR 11 bit times after it (T = 32); the next
// `cycle`'s Data_Exchange starts TSYN (33 T) after that answer's end, no bus violation, no
// collision, no "late answer" of master 2 (it asked nothing unanswered), and the walk from the
// step on is in cycle order (docs/segment.md "The log"). Until the thirty-fifth session master 2
// drove into the answer (a collision) and told it as its late answer after its own request.
TEST(SegmentScenario, TheMasterWaitsForAnAnswerToAnotherStationsRequest) {
  const ScenarioRun r = run_passing(
      "segment baud=1500000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender tool\nstartup\n"
      "cycle 1\nsend from=tool 10,05,09,49,57,16\ncycle 1\nexpect bus_violation short_tsyn 0\n"
      "expect collisions 0\n");
  const std::uint64_t answer = r.cycle_of("] station 5: 10 09 05 00 0E 16");
  EXPECT_EQ(answer, r.cycle_of("] tool: 10 05 09 49 57 16") + (6 * 11 + 11) * 32);
  EXPECT_EQ(r.cycle_of("] master 2: 68 07 07 68 05 02"), answer + (6 * 11 + 33) * 32);
  std::uint64_t last = 0;
  for (std::size_t i = 0; i < r.walk.size(); ++i) {
    EXPECT_EQ(r.walk[i].find("late answer"), std::string::npos) << r.walk[i];
    if (r.walk[i].find("] line 8:") != std::string::npos) last = 1;
    if (last == 0) continue;
    const std::uint64_t at = std::stoull(r.walk[i].substr(r.walk[i].find("cycle") + 5));
    EXPECT_GE(at, last) << r.walk[i];
    last = at;
  }
  EXPECT_NE(last, 0U);
}

// A token claimed without an SD4 is held from TSYN before the claiming master's first request
// (docs/segment.md, "The token"): the master's own TTH counts from there as the bus check's does
// (the review s28 rev2 finding 1: it counted from the claim's step, 33 bit times earlier for the
// check, and the check charged it token_hold at TTR 331..340).
TEST(SegmentScenario, AClaimedTokensHoldIsTheBusChecks) {
  for (const int ttr : {331, 335, 340}) {
    run_passing(
        fmt::format("segment baud=12000000\nstation 5 name=spc3 profile=spc3\n"
                    "station 6 name=vpc3plus profile=vpc3plus\nstation 7 name=dpc31 profile=dpc31\n"
                    "master 2 slaves=5,6 ttr={0}\nmaster 3 slaves=7 ttr={0}\nstartup\ncycle 2\n"
                    "pass_token from=2 to=9\nrun 2ms\ncycle 3\nexpect bus_violation token_hold 0\n",
                    ttr));
  }
}

// The same after another master's token: master 3, given the token by master 2, passes it back
// TSYN after master 2's token ends (each DC xx yy: 33 T), not at once (the audit's f1b).
TEST(SegmentScenario, AMasterPassesTheTokenTsynAfterTheTokenItGot) {
  const ScenarioRun r = run_passing(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nmaster 3 slaves=5\n"
      "pass_token from=2 to=3\npass_token from=3 to=2\nexpect bus_violation short_tsyn 0\n");
  EXPECT_EQ(r.cycle_of("] master 3: DC 02 03"), r.cycle_of("] master 2: DC 03 02") + 66 * 4);
}

// s34 audit aSeg finding 2: after `pass_token from=2 to=3` master 3 holds the token, so the next
// rotation is its own (docs/scenario-format.md, `cycle`: token rotations): the step starts at
// the token's end (the line quiet), master 3 polls 6 TSYN (33 T, 32 clocks each) later, then
// passes the token to 2, which polls 5. It started with master 2, twice a duplicate_token.
TEST(SegmentScenario, ACycleAfterPassTokenStartsAtTheMasterThatHoldsIt) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 profile=spc3\nstation 6 profile=dpc31\nmaster 2 slaves=5\n"
      "master 3 slaves=6\nstartup\ncycle 1\npass_token from=2 to=3\ncycle 1\n"
      "expect bus_violation duplicate_token 0\n");
  // Master 3's poll, its token to 2, master 2's poll: in this order, the first TSYN after the step.
  const std::vector<std::uint64_t> rotation{r.cycle_of("] master 3: 68 07 07 68 06 03 5D"),
                                            r.cycle_of("] master 3: DC 02 03"),
                                            r.cycle_of("] master 2: 68 07 07 68 05 02 5D")};
  EXPECT_EQ(rotation.front(), r.cycle_of("line 9: cycle 1") + 33 * 32);
  EXPECT_TRUE(std::is_sorted(rotation.begin(), rotation.end()));
}

// s34 audit aSeg finding 1 from the scenario door: a token passed to an absent station (9) and,
// after a silent slot time, again, then to master 3 (EN 50170 token passing, docs/segment.md "The
// token"): master 2 holds the token until 3 takes it, so nothing is a duplicate_token, and the
// rotation after goes on from 3.
TEST(SegmentScenario, ATokenPassRetriedAfterTheSlotTimeIsNoDuplicateToken) {
  run_passing(
      "segment\nstation 5 profile=spc3\nstation 6 profile=dpc31\nmaster 2 slaves=5\n"
      "master 3 slaves=6\nstartup\ncycle 1\npass_token from=2 to=9\nrun 100bits\n"
      "pass_token from=2 to=9\nrun 100bits\npass_token from=2 to=3\ncycle 1\n"
      "expect bus_violation duplicate_token 0\nexpect bus_violation token_lost 0\n");
}

// Review s34 rev1 finding 1: a token passed to an absent address (9) leaves the passer holding it
// (docs/scenario-format.md, `pass_token`; docs/segment.md "The token": EN 50170, nobody took it),
// so master 2's next visit goes on with the token it held: the same arrival (the walk stamps the
// visit there), TRR and TTH as the visit before the pass, not a fresh claim (TRR 0, TTH = TTR),
// and the bus check, which keeps that arrival too, finds no token_hold. The master goes on once
// the slot time after its token has passed (`run 100bits`: before, 9 may still take it).
TEST(SegmentScenario, AMasterKeepsTheTokenNobodyTook) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 profile=spc3\nstation 6 profile=dpc31\nmaster 2 slaves=5,6 ttr=1000\n"
      "master 3 slaves=6 ttr=1000\nstartup\ncycle 2\npass_token from=2 to=9\nrun 100bits\ncycle 1\n"
      "expect bus_violation token_hold 0\nexpect bus_violation duplicate_token 0\n");
  // Before the pass: master 2's last visit's arrival, and master 3's token to it (DC 02 03, 3
  // characters: it arrives 33 T = 1056 clocks after its start, at 1.5 Mbaud).
  std::uint64_t before = 0;
  std::uint64_t arrival = 0;
  std::string kept;  // master 2's visit after the pass
  bool passed = false;
  for (const std::string& l : r.walk) {
    const std::uint64_t at = std::stoull(l.substr(l.find("cycle") + 5));
    const bool visit = l.find("master 2: the token: TRR") != std::string::npos;
    if (l.find("line 8: pass_token") != std::string::npos) {
      passed = true;
    } else if (!passed && l.find("] master 3: DC 02 03") != std::string::npos) {
      arrival = at + 1056;
    } else if (!passed && visit) {
      before = at;
    } else if (passed && visit && kept.empty()) {
      kept = l;
    }
  }
  ASSERT_NE(arrival, 0U);
  ASSERT_FALSE(kept.empty());
  const std::uint64_t trr = (arrival - before) / 32;
  EXPECT_EQ(std::stoull(kept.substr(kept.find("cycle") + 5)), arrival) << kept;
  EXPECT_NE(
      kept.find(fmt::format("master 2: the token: TRR {} bit times, TTH {}, ", trr, 1000 - trr)),
      std::string::npos)
      << kept;
}

// A master that finds a slave locked by another (its Slave_Diag's Master_Add, byte 3, neither FFh
// nor its own address: chip-facts.md, "Slave_Diag"; Master_Lock is the master's own bit) does not
// parameterise it, and its walk says so (the audit s28 aud2, finding 4: master 3 took the slave
// for ready and sent it Data_Exchange silently). At 1.5 Mbaud T = 32 clocks: master 3's Slave_Diag
// answer `00 0C 00 02 0C 31` is 17 characters; the master stops at its last stop sample, end - T
// + T/2, where the walk says it.
TEST(SegmentScenario, AMasterLeavesASlaveLockedByAnotherMasterAlone) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 profile=spc3\nstation 6 profile=vpc3plus\nmaster 2 slaves=5,6\n"
      "master 3 slaves=5\nstartup\nexpect state 5 Data_Exchange\n");
  const std::uint64_t diag =
      r.cycle_of("] station 5: 68 0B 0B 68 83 85 08 3E 3C 00 0C 00 02 0C 31");
  EXPECT_EQ(r.cycle_of("master 3: station 5 is locked by master 2 (its Slave_Diag's Master_Add): "
                       "not parameterised, its start-up ends"),
            diag + 17 * 11 * 32 - 32 + 16);
  // No Set_Prm (DSAP 3D) nor Chk_Cfg (3E) from master 3.
  EXPECT_EQ(std::count_if(r.walk.begin(), r.walk.end(),
                          [](const std::string& l) {
                            return l.find("] master 3: 68") != std::string::npos &&
                                   (l.find(" 3D 3E ") != std::string::npos ||
                                    l.find(" 3E 3E ") != std::string::npos);
                          }),
            0);
}

// Two stations at one address answer each of the start-up's five requests and the three
// Data_Exchanges together: eight collisions, each its own line in the walk (docs/segment.md, "Bus
// checks": one log line a violation; a run of equal lines folds only where nothing comes between,
// and then its note comes right after it: the audit s28 aud2, finding 8: one line showed and the
// note came 40 lines later). The chips' state lines are in cycle order (docs/segment.md, "The
// log"; finding 9: the two twins' Data_Exchange lines came in station order).
TEST(SegmentScenario, EachCollisionIsALineAndStateLinesAreInCycleOrder) {
  const ScenarioRun r = run_passing(
      "segment\nstation 5 name=a profile=spc3\nstation 5 name=b profile=vpc3plus\n"
      "station 6 profile=dpc31\nstartup\ncycle 3\nexpect collisions 8\n");
  std::vector<std::uint64_t> states;
  std::size_t collisions = 0;
  for (const std::string& l : r.walk) {
    EXPECT_EQ(l.find("repeated"), std::string::npos) << l;
    if (l.find("] bus: collision: b drove the line while a had it") != std::string::npos)
      ++collisions;
    if (l.find(" / ") != std::string::npos) states.push_back(std::stoull(l.substr(7)));
  }
  EXPECT_EQ(collisions, 8U);
  EXPECT_TRUE(std::is_sorted(states.begin(), states.end()));
  EXPECT_GE(states.size(), 6U);  // each of the three through Wait_Cfg into Data_Exchange at least
}

// An unanswered request waits for its answer only up to its slot time (docs/timing.md, "The
// master's wait"; docs/segment.md, "Bus checks"): each telegram long after it stands on its own.
// At 12 Mbaud T = 4 clocks, a 6-character telegram lasts 66 T = 264 clocks, `send` starts 33 T
// after the quiet line and ends at its telegram's end, `run 1ms` lasts 48 000 clocks, and the
// line idle for TTO = 100 x (6 + 2 x 2) = 1000 T = 4000 clocks after a telegram's end is one
// token_lost (master 2 alone). The rogue asks station 9 (nobody) in master 2's name; after a lost
// token a babbler's answer is unsolicited (no late answer, no wrong responder), and a request
// with a corrupted FCS (49 + 09 + 02 = 54, sent as 55) is one bad frame.
TEST(SegmentScenario, AnUnansweredRequestWaitsNoLongerThanItsSlotTime) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender rogue\n"
      "sender babbler\nstartup\nexpect state 5 Data_Exchange\n"
      "send from=rogue after=33bits 10,09,02,49,54,16\nrun 1ms\n"
      "send from=babbler after=33bits 10,02,07,00,09,16\n"
      "send from=rogue after=33bits 10,09,02,49,54,16\nrun 1ms\n"
      "send from=rogue after=33bits 10,09,02,49,55,16\nrun 1000\n"
      "expect bus_violation unsolicited 1\nexpect bus_violation bad_frame 1\n"
      "expect bus_violation late_answer 0\nexpect bus_violation wrong_responder 0\n"
      "expect bus_violation token_lost 2\n");
  EXPECT_EQ(r.errors, std::vector<std::string>{});
  EXPECT_EQ(r.code, 0);
  const std::uint64_t quiet = r.cycle_of("line 7: expect");
  const std::uint64_t end1 = quiet + 132 + 264;         // the first request to 9
  const std::uint64_t babble = end1 + 48000 + 132;      // the babbler's answer
  const std::uint64_t end3 = babble + 264 + 132 + 264;  // the second request to 9
  const std::uint64_t broken = end3 + 48000 + 132;      // the corrupted request
  const auto at = [](std::uint64_t cycle, std::string_view text) {
    return fmt::format("[cycle {:>10}] bus: {}", cycle, text);
  };
  const std::vector<std::string> want = {
      at(end1 + 4000,
         fmt::format("token_lost: the line idle for TTO (1000 bit times) since cycle {}", end1)),
      at(babble, "unsolicited: an answer from station 7 nobody asked for"),
      at(end3 + 4000,
         fmt::format("token_lost: the line idle for TTO (1000 bit times) since cycle {}", end3)),
      at(broken, fmt::format("bad_frame: 6 bytes from cycle {} do not decode (bad_fcs)", broken))};
  std::vector<std::string> bus;
  std::copy_if(r.walk.begin(), r.walk.end(), std::back_inserter(bus),
               [](const std::string& l) { return l.find("] bus: ") != std::string::npos; });
  EXPECT_EQ(bus, want);
}

// A telegram that ends at a step's end (its last stop bit) is over there: the walk prints it, and
// the bus check counts it, before the next step's lines at that cycle (docs/decisions.md, the
// twenty-third session; a chip's event at an expect's cycle comes before the expect in the single
// chip's walk too). Until then the segment told of it one character time later, after them. At
// 12 Mbaud T = 4 clocks: `send` starts 32 T after the start-up's quiet end (line 6's cycle) and
// ends 6 characters of 11 T later, where line 8's expect looks (docs/scenario-format.md,
// "Segments": `send` ends at its telegram's end, a check moves no time); the short TSYN is
// stamped at the telegram's start, where the idle ended too soon (the bus check is told of each
// telegram just before the log prints it).
TEST(SegmentScenario, ATelegramEndingAtAStepsEndComesBeforeItsExpects) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nsender a\nstartup\n"
      "expect state 5 Data_Exchange\nsend from=a after=32bits 10,05,02,49,50,16\n"
      "expect bus_violation short_tsyn 1\n");
  EXPECT_EQ(r.errors, std::vector<std::string>{});  // the short TSYN counted: exit 0
  const std::uint64_t quiet = r.cycle_of("line 6: expect");
  const std::uint64_t sent = quiet + 32 * 4;
  const std::uint64_t end = sent + 6 * 11 * 4;
  const auto at = [](std::uint64_t cycle, std::string_view text) {
    return fmt::format("[cycle {:>10}] {}", cycle, text);
  };
  const std::vector<std::string> want = {
      at(quiet, "line 7: send from=a after=32bits 10,05,02,49,50,16"),
      at(sent, "bus: short_tsyn: a sent after 32 bit times of idle (TSYN 33)"),
      at(sent, "a: 10 05 02 49 50 16"), at(end, "line 8: expect bus_violation short_tsyn 1"),
      at(end, "ok")};
  const auto from = std::find(r.walk.begin(), r.walk.end(), want.front());
  ASSERT_NE(from, r.walk.end());
  EXPECT_EQ(std::vector<std::string>(
                from, from + std::min<std::ptrdiff_t>(r.walk.end() - from, want.size())),
            want);
  EXPECT_EQ(r.code, 0);
}

// A station that never left DP_Control fails `expect watchdog_expired` saying so (not "left at
// cycle 0"), with the cycle expected: the last request's end - T + T/2 + TWD.
TEST(SegmentScenario, AWatchdogThatNeverExpiredSaysSo) {
  const ScenarioRun r = run_scenario_text(
      "segment baud=12000000\nstation 5 profile=spc3\nmaster 2 slaves=5\nstartup\n"
      "expect watchdog_expired 5 twd=100\n");
  EXPECT_EQ(r.code, 1);
  ASSERT_EQ(r.errors.size(), 1U);
  EXPECT_EQ(r.errors[0].substr(0, r.errors[0].find(" at cycle")),
            "s.scn:5: expected watchdog_expired 5 twd=100, got never left DP_Control, expected it");
}

// s35 audit aMix finding 3 (its seg_wd_c2.scn): DO4 on a VPC3+ parameterised by a raw Set_Prm
// from SA 2 (88h Lock_Req + WD_On, WD_Fact 01 0A on the 10 ms base: TWD 100 ms; DPV1_Status_1
// C0h DPV1_Enable + Fail_Safe); then a class-2 master (SA 3) runs MSAC_C2 (Initiate, polls, a
// Read) until 3787952.
// "The 'DP_Control' state serves response time monitoring of the DP master (Master_Add)" (SPC3
// p.25): only master 2's requests restart it. Its last, the Data_Exchange poll of `cycle 2` to
// station 5 (11 bytes from 3160560, T = 32: end 3160560 + 11 x 352 = 3164432), is acted on at
// end - T + T/2 = 3164416 (docs/timing.md); expiry + 100 ms (4 800 000 clocks) = 7964416, with
// 99 ms 7916416. The old check took c2's last poll (end 3787952) and expected 8587936.
TEST(SegmentScenario, WatchdogExpiryCountsFromTheLockingMastersLastRequest) {
  const std::string head =
      "segment baud=1500000\nstation 5 name=vpc profile=vpc3plus firmware=DO4\n"
      "station 6 name=spc profile=spc3\nmaster 2 slaves=5,6\nsender tool\nsender c2\n"
      "startup\ncycle 3\n"
      "send from=tool 68,12,12,68,85,82,4D,3D,3E,88,01,0A,00,0D,04,00,C0,20,00,01,09,00,5D,16\n"
      "run 1ms\nsend from=tool 68,07,07,68,85,82,4D,3E,3E,21,10,01,16\nrun 1ms\ncycle 2\n"
      "expect state 5 Data_Exchange\n"
      "send from=c2 68,19,19,68,85,83,4D,31,30,57,00,00,00,00,64,01,00,00,00,00,00,00,02,00,02,"
      "00,00,00,00,76,16\n"
      "run 3ms\nsend from=c2 68,05,05,68,85,83,4D,31,30,B6,16\n"
      "run 3ms\nsend from=c2 68,05,05,68,85,83,4D,28,30,AD,16\n"
      "run 3ms\nsend from=c2 68,09,09,68,85,83,4D,28,30,5E,00,01,02,0E,16\n"
      "run 3ms\nsend from=c2 68,05,05,68,85,83,4D,28,30,AD,16\nrun 120ms\n";
  const ScenarioRun r =
      run_scenario_text(head +
                            "expect watchdog_expired 5 twd=100ms\nexpect state 5 Wait_Prm\n"
                            "expect watchdog_expired vpc twd=99ms\n",
                        "wd.scn");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.errors, std::vector<std::string>{"wd.scn:27: expected watchdog_expired vpc twd=99ms, "
                                               "got left DP_Control at cycle 7964416, expected "
                                               "7916416"});
}

// s35 audit aMix finding 8: each station's chip log is in the walk as the single chip's `chip: …`,
// named by station, at the chip's cycle: the DPC31 refuses a Set_Prm with DPV1_Enable "with
// Prm_Fault and a log line" (docs/dpv1.md) at the request's acted-on cycle, end - T + T/2 (21
// characters of 11 T = 32: start + 7392 - 16); the unlocked chip then ignores each Chk_Cfg with a
// line (13 characters: start + 4576 - 16), the second and third folded by the chip's rule into
// one note at the run's end, just before its last line, naming the repeats' own cycles.
TEST(SegmentScenario, EachStationsChipLogIsInTheWalk) {
  const std::string cfg = "send from=tool 68,07,07,68,87,82,4D,3E,3E,13,23,08,16\nrun 1ms\n";
  const ScenarioRun r = run_scenario_text(
      "segment\nstation 7 name=d profile=dpc31\nmaster 2 slaves=7\nsender tool\nstartup\n"
      "send from=tool 68,0F,0F,68,87,82,4D,3D,3E,88,0A,C8,00,0C,31,00,C0,00,00,28,16\nrun 1ms\n" +
      cfg + cfg + cfg);
  EXPECT_EQ(r.code, 0);
  const auto at = [](std::uint64_t cycle, const std::string& text) {
    return fmt::format("[cycle {:>10}] d: chip: {}", cycle, text);
  };
  const auto has = [&r](const std::string& line) {
    return std::find(r.walk.begin(), r.walk.end(), line) != r.walk.end();
  };
  const std::uint64_t prm = r.cycle_of("tool: 68 0F 0F 68");
  EXPECT_TRUE(has(at(prm + 21 * 352 - 16,
                     "Set_Prm from 2: DPV1_Enable: the DPC31's DPV1 is not modelled: Prm_Fault")));
  std::vector<std::uint64_t> chk;
  for (const std::string& l : r.walk) {
    if (l.find("tool: 68 07 07 68") != std::string::npos)
      chk.push_back(std::stoull(l.substr(l.find("cycle") + 5)));
  }
  ASSERT_EQ(chk.size(), 3U);
  EXPECT_TRUE(has(at(chk[0] + 13 * 352 - 16,
                     "Chk_Cfg from 2: no master has locked the slave (Master_Add FFh: not "
                     "parameterised): ignored")));
  EXPECT_EQ(std::count_if(r.walk.begin(), r.walk.end(),
                          [](const std::string& l) { return l.find("Chk_Cfg from") != l.npos; }),
            1);
  ASSERT_GE(r.walk.size(), 2U);
  const std::string& end = r.walk.back();
  EXPECT_EQ(r.walk[r.walk.size() - 2],
            at(std::stoull(end.substr(end.find("cycle") + 5)),
               fmt::format("last line repeated 2 times, cycles {} to {}", chk[1] + 13 * 352 - 16,
                           chk[2] + 13 * 352 - 16)));
}

// The single chip's loader on a segment's file names the segment's loader, at the `segment` line.
TEST(SegmentScenario, TheSingleChipLoaderNamesTheSegmentLoader) {
  Scenario s;
  ScenarioError err;
  EXPECT_FALSE(
      parse_scenario("# two stations\n\nsegment baud=1500000\nstation 5\n", "f.scn", s, err));
  EXPECT_EQ(err.text(),
            "f.scn:3: 'segment' begins a segment scenario (docs/scenario-format.md, \"Segments\"): "
            "load it with SegmentScenario (load_segment_scenario; dpc31.SegmentScenario in Python) "
            "or run it with `dpc31 run`");
  // After another line `dpc31 run` took the file for a single chip's (its first line decides):
  // the misplaced line is named, not the command the user ran (the s35 audit, finding 2).
  EXPECT_FALSE(parse_scenario("baud 1500000\nsegment\nstation 5\n", "f.scn", s, err));
  EXPECT_EQ(err.text(),
            "f.scn:2: 'segment' must be the first line of a segment scenario "
            "(docs/scenario-format.md, \"Segments\"); 'baud' (line 1) is a single chip's, which a "
            "segment scenario has not");
}

// A segment's station cannot be an 80C32 board at any door (docs/segment.md): a `cpu` line is
// refused in those words, not as an unknown command, and so is an Intel HEX image as a station's
// plug-in; neither is sent to a door that refuses it (the s35 audit, finding 1).
TEST(SegmentScenario, An80c32ImageIsRefusedInWordsThatNameTheLimit) {
  const std::string limit =
      "a segment's station cannot run an 80C32 image (docs/segment.md); one chip runs it: `dpc31 "
      "run` with the header cpu 80c32 firmware FILE, or --cpu 80c32 at `dpc31 bridge` and `dpc31 "
      "serve`";
  SegmentScenario s;
  ScenarioError err;
  EXPECT_FALSE(parse_segment_scenario("segment\ncpu 80c32 firmware fw.ihx\nstation 5\nrun 1ms\n",
                                      "g.scn", s, err));
  EXPECT_EQ(err.text(), "g.scn:2: 'cpu' is a single chip's header: " + limit);
  const testutil::TempDir dir;
  std::ofstream(dir.file("fw.ihx")) << ":0200000080FE80\n:00000001FF\n";
  ASSERT_TRUE(parse_segment_scenario("segment\nstation 7 profile=spc3 firmware=./fw.ihx\nrun 1ms\n",
                                     dir.file("h.scn"), s, err))
      << err.text();
  EXPECT_FALSE(bind_segment_plugins(s, err));
  EXPECT_EQ(err.line, 2);
  EXPECT_TRUE(err.message.ends_with("; it is an Intel HEX image, a CPU's program: " + limit))
      << err.message;
}

}  // namespace
}  // namespace dpc31
