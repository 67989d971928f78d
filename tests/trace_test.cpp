// Golden traces (docs/trace-format.md): recording, the parser's refusals, the replay's first
// mismatch, the RxD line formats, the `dpc31 replay` command, and the session behind the golden
// trace traces/diag_ext_diag_dpc31.trace (extended diagnosis, which scenarios cannot express).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "run_command.hpp"
#include "test_files.hpp"

// emu/ is not on the tests' include path.
#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/uart.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "textfile.hpp"
#include "trace.hpp"

namespace {

using dpc31::parse_trace;
using dpc31::ReplayOutcome;
using dpc31::Trace;
using dpc31::TraceError;

constexpr const char* kScenario = R"(# a short session for the trace tests
profile spc3
bus motorola
baud 12000000
master address=1
slave address=12 ident=0x8031 cfg=11,21 in=2 out=2
user inputs=C0,DE

startup
exchange 2 outputs=5A,A5
expect outputs 5A,A5
gc clear
)";

std::string record(const std::string& scn, int* rc = nullptr) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(scn, "test.scn", s, err)) << err.text();
  dpc31::TraceRecorder rec(s.master.baud, {"test"});
  const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, {}, {}, rec.scenario_hooks());
  if (rc != nullptr) *rc = o.ok() ? 0 : 1;
  EXPECT_EQ(rec.error(), "");
  return rec.text();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& l : v) s += l + '\n';
  return s;
}

// Parses and replays; returns the exit code replay_trace_file would give, with the message.
int replay_text(const std::string& text, std::string& message) {
  Trace t;
  TraceError err;
  if (!parse_trace(text, "t.trace", t, err)) {
    message = err.text();
    return 2;
  }
  const ReplayOutcome o = dpc31::replay_trace(t);
  message = o.failure;
  return o.ok ? 0 : 1;
}

// Index (0-based) of the first line starting with `prefix`, and its 1-based line number.
std::size_t find_line(const std::vector<std::string>& v, const std::string& prefix,
                      std::size_t from = 0) {
  for (std::size_t i = from; i < v.size(); ++i) {
    if (v[i].starts_with(prefix)) return i;
  }
  ADD_FAILURE() << "no line starting with " << prefix;
  return 0;
}

// Records "PROFILE\nLINE\nstartup\n" into `v` (its lines): LINE stands right after the profile's
// line, the trace holds `mark`, and it replays. The profile line's index.
std::size_t recorded_after_profile(const std::string& profile, const std::string& line,
                                   const std::string& mark, std::vector<std::string>& v) {
  const std::string text = record(profile + "\n" + line + "\nstartup\n");
  v = lines_of(text);
  const std::size_t p = find_line(v, profile);
  EXPECT_EQ(p + 1 < v.size() ? v[p + 1] : "", line);
  EXPECT_NE(text.find(mark), std::string::npos);
  std::string msg;
  EXPECT_EQ(replay_text(text, msg), 0) << msg;
  return p;
}

const std::string& recorded() {
  static const std::string text = record(kScenario);
  return text;
}

TEST(TraceFile, RecordingIsDeterministicAndReplays) {
  int rc = -1;
  const std::string a = record(kScenario, &rc);
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(a, record(kScenario));
  const std::vector<std::string> v = lines_of(a);
  ASSERT_GT(v.size(), 20u);
  EXPECT_EQ(v[0], "dpc31-trace 1");
  EXPECT_EQ(v[1], "# test");
  EXPECT_NE(a.find("\nprofile spc3\nbus motorola\nclock 48000000\nbaud 12000000\n"),
            std::string::npos);
  EXPECT_TRUE(v.back().starts_with("end "));
  // Every kind of line is there: RxD telegrams, writes, reads, X/INT, answers, states, and the
  // scenario's lines as comments.
  for (const char* p : {"rx ", "wr ", "rd ", "xint ", "tx ", "state ", "# line 9: startup"}) {
    EXPECT_NE(a.find(std::string("\n") + p), std::string::npos) << p;
  }
  std::string msg;
  EXPECT_EQ(replay_text(a, msg), 0) << msg;
}

TEST(TraceFile, GlobalControlIsAnRxWithoutAnswer) {
  // gc clear: SD2, LE 7, DA 127 with the SAP bit, SA 1 with it, FC SDN high, DSAP 58, SSAP 62.
  EXPECT_NE(recorded().find(" 68 07 07 68 FF 81 46 3A 3E 02 00 "), std::string::npos);
}

// The replay reports the first wrong expectation with its line, for every kind of expectation.
struct Damage {
  const char* prefix;  // the first line of this kind after the start-up is changed
  const char* from;
  const char* to;
  const char* message;
};

class TraceMismatch : public ::testing::TestWithParam<Damage> {};

TEST_P(TraceMismatch, FirstMismatchWithItsLine) {
  std::vector<std::string> v = lines_of(recorded());
  const Damage& d = GetParam();
  const std::size_t begin = find_line(v, "# line 10: exchange");
  const std::size_t i = find_line(v, d.prefix, begin);
  if (std::string(d.prefix) == "rd ") {
    // The value read: any other one.
    std::string& val = v[i];
    val.replace(val.size() - 2, 2, val.ends_with("EE") ? "DD" : "EE");
  } else {
    const std::size_t k = v[i].rfind(d.from);
    ASSERT_NE(k, std::string::npos) << v[i];
    v[i].replace(k, std::string(d.from).size(), d.to);
  }
  std::string msg;
  EXPECT_EQ(replay_text(join(v), msg), 1);
  EXPECT_TRUE(msg.starts_with("t.trace:" + std::to_string(i + 1) + ": expected ")) << msg;
  EXPECT_NE(msg.find(d.message), std::string::npos) << msg;
}

INSTANTIATE_TEST_SUITE_P(TraceFile, TraceMismatch,
                         ::testing::Values(Damage{"rd ", "", "", ", got "},
                                           Damage{"xint ", " 1", " 0", "got xint 1 at cycle"},
                                           Damage{"tx ", " 16", " 17", "got tx "},
                                           Damage{"state ", "dp=Data_Exchange", "dp=Wait_Cfg",
                                                  "got dp=Data_Exchange"},
                                           Damage{"state ", "fdl=", "fdl=parity:9,", "got fdl="}));

TEST(TraceFile, AMissingExpectationIsReportedWhereItWasDue) {
  std::vector<std::string> v = lines_of(recorded());
  const std::size_t i = find_line(v, "xint ", find_line(v, "# line 10: exchange"));
  v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
  std::string msg;
  EXPECT_EQ(replay_text(join(v), msg), 1);
  // The next X/INT expectation is met by the edge whose line was removed.
  EXPECT_NE(msg.find("got xint 1 at cycle"), std::string::npos) << msg;
}

TEST(TraceFile, AnUnexpectedEdgeIsReportedAtTheNextLine) {
  std::vector<std::string> v = lines_of(recorded());
  std::size_t last = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i].starts_with("xint ")) last = i;
  }
  v.erase(v.begin() + static_cast<std::ptrdiff_t>(last));
  std::string msg;
  EXPECT_EQ(replay_text(join(v), msg), 1);
  EXPECT_TRUE(msg.starts_with("t.trace:" + std::to_string(last + 1) +
                              ": expected no other X/INT edge up to cycle "))
      << msg;
}

TEST(TraceFile, ADelayedTelegramIsAMismatch) {
  std::vector<std::string> v = lines_of(recorded());
  const std::size_t i = find_line(v, "rx ", find_line(v, "# line 10: exchange"));
  // Two bit times later: the chip answers two bit times later than the trace says.
  std::istringstream in(v[i]);
  std::string kw;
  std::uint64_t start = 0;
  in >> kw >> start;
  std::string rest;
  std::getline(in, rest);
  v[i] = "rx " + std::to_string(start + 8) + rest;
  std::string msg;
  EXPECT_EQ(replay_text(join(v), msg), 1);
  EXPECT_NE(msg.find("expected "), std::string::npos) << msg;
}

// Bad input: one "FILE:LINE: message" line, nothing run.
struct BadInput {
  std::string text;
  int line;
  const char* message;
};

class TraceBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(TraceBadInput, OneLineWithFileAndLine) {
  const BadInput& b = GetParam();
  std::string msg;
  EXPECT_EQ(replay_text(b.text, msg), 2);
  const std::string want = b.line > 0 ? "t.trace:" + std::to_string(b.line) + ": " : "t.trace: ";
  EXPECT_TRUE(msg.starts_with(want)) << msg;
  EXPECT_NE(msg.find(b.message), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos);
}

const std::string kHead = "dpc31-trace 1\nprofile dpc31\nbus intel\nclock 48000000\nbaud 1500000\n";
// The DPC31 starts by request (DPC31 p.22, Table 5.1-3; docs/dpc31.md): InstQ_Base F8h (1F00h),
// InstQ_Len 4, the entry MAC_Start 10h (its parameter: RAM's 00h), then InstQ_Wr 1, whose
// completion at 24 is the start.
const std::string kMacStart = "wr 12 086A F8\nwr 16 086B 04\nwr 20 1F00 10\nwr 24 086C 01\n";

INSTANTIATE_TEST_SUITE_P(
    TraceFile, TraceBadInput,
    ::testing::Values(
        BadInput{"", 0, "empty file"}, BadInput{"hello\n", 1, "not a dpc31 trace"},
        BadInput{"dpc31-trace 2\n", 1, "version"},
        BadInput{kHead + "wr 4 0000 00\n", 6, "truncated trace: no 'end' line"},
        BadInput{kHead + "wr 4 0000 00\nfoo bar\nend 8\n", 7, "unknown line 'foo'"},
        BadInput{kHead + "wr 4 0000 00\n\x01\x02garbage\nend 8\n", 7, "unknown line"},
        BadInput{kHead + "wr 8 0000 00\nwr 4 0001 00\nend 8\n", 7, "cycle order"},
        BadInput{kHead + "wr 8 0000 00\nwr 10 0001 00\nend 10\n", 7, "before cycle 8"},
        BadInput{kHead + "wr 4 0000 0x1\nend 4\n", 6, "bad data"},
        BadInput{kHead + "wr 4 0000 00\nprofile spc3\nend 4\n", 7, "given twice"},
        BadInput{kHead + "rd 4 0000 04\nend 4\n", 6, "rd CYCLE ADDR = DATA"},
        BadInput{kHead + "state 4 dp=Nowhere\nend 4\n", 6, "unknown dp state"},
        BadInput{kHead + "state 4 foo=1\nend 4\n", 6, "unknown state key"},
        BadInput{kHead + "state 4 fdl=parity:1,parity:2\nend 4\n", 6, "each counter once"},
        BadInput{kHead + "rx 100 10 05 02 49 50 16 fed=200\nend 300\n", 6, "fed= after"},
        BadInput{kHead + "rx 100 10 05 fault=parity:7\nend 300\n", 6, "fault in character 7"},
        // Bounded before it becomes an int: 2^32 was character 0, 2^31 character -2147483648.
        BadInput{kHead + "rx 100 10 05 fault=parity:4294967296\nend 300\n", 6,
                 "fault in character 4294967296: a telegram has at most"},
        BadInput{kHead + "rx 100 10 05 fault=parity:2147483648\nend 300\n", 6,
                 "fault in character 2147483648: a telegram has at most"},
        BadInput{kHead + "xint 100 1\nend 50\n", 7, "cycle order"},
        BadInput{kHead + "end 8\nwr 12 0000 00\n", 7, "after the 'end' line"},
        BadInput{"dpc31-trace 1\nprofile dpc31\nwr 4 0000 00\nend 4\n", 3, "no 'bus' line"},
        BadInput{kHead + "wr 99999999999999999999 0000 00\nend 4\n", 6,
                 "cycle '99999999999999999999' out of range"},
        BadInput{kHead + "end 18446744073709551615\n", 6,
                 "cycle '18446744073709551615' out of range"},
        BadInput{kHead + "wr 4x 0000 00\nend 4\n", 6, "bad cycle '4x' (a decimal number)"},
        // Beyond the DPC31's 13-bit bus (docs/registers.md): refused as the scenario's `write
        // 0xE007` is, not folded to 0007h by the chip (s29-sec, finding 5).
        BadInput{kHead + "wr 4 E007 21\nend 4\n", 6,
                 "address 0xE007 out of range (0x0000..0x1FFF)"},
        BadInput{kHead + "rd 4 2000 = 00\nend 4\n", 6,
                 "address 0x2000 out of range (0x0000..0x1FFF)"},
        // PB3 is the DPC31's; a `pb3` line is checked only with the header's `check pb3`, which
        // also checks that no other edge comes (docs/trace-format.md).
        BadInput{"dpc31-trace 1\nprofile spc3\ncheck pb3\nbus intel\n", 3,
                 "'check pb3' follows 'profile dpc31': only the DPC31 has the DX_Out port PB3"},
        BadInput{"dpc31-trace 1\nprofile dpc31\ncheck xint\n", 3, "unknown check 'xint' (pb3)"},
        BadInput{kHead + "pb3 4 1\nend 8\n", 6, "a 'pb3' line needs the header line 'check pb3'"},
        BadInput{kHead + "wr 4 0000 00\ncheck pb3\nend 8\n", 7,
                 "header line 'check' after the first event"}));

TEST(TraceFile, CommentsAndBlankLinesAnywhere) {
  const std::string text =
      "dpc31-trace 1   # version\n\n# a comment\n" + kHead.substr(14) +
      "wr 4 0016 00   # R_TS_Adr\n\n  rd 8 0016 = 00\nstate 8 dp=Wait_Prm wd=Baud_Search "
      "status=0000 irr=0000 imr=3f3f station=0 fdl=-\nend 100\n";  // reset FFFFh, the dpc31's bits
  std::string msg;
  EXPECT_EQ(replay_text(text, msg), 0) << msg;
}

TEST(TraceFile, AnUnexpectedEdgeBeforeTheEnd) {
  std::string msg;
  EXPECT_EQ(replay_text(kHead + "wr 4 0004 E0\nwr 8 0005 C0\n" + kMacStart + "end 100\n", msg), 1);
  EXPECT_EQ(msg, "t.trace:12: expected no more X/INT edges, got xint 1 at cycle 24");
}

// A run on a VPC3+S records `variant s` after the profile; the replay makes the same chip (its
// state lines carry Status_Reg with the ASIC type Eh). Without the line the replay runs on a
// VPC3+C and the first state line differs.
TEST(TraceFile, TheVariantIsRecordedAndReplayed) {
  std::vector<std::string> v;
  const std::size_t p = recorded_after_profile("profile vpc3plus", "variant s", " status=E", v);
  ASSERT_LT(p + 1, v.size());
  std::string msg;
  v.erase(v.begin() + static_cast<std::ptrdiff_t>(p + 1));
  EXPECT_EQ(replay_text(join(v), msg), 1);
  EXPECT_NE(msg.find("status"), std::string::npos) << msg;
  v.insert(v.begin() + static_cast<std::ptrdiff_t>(p), "variant s");  // before its profile
  EXPECT_EQ(replay_text(join(v), msg), 2);
  EXPECT_EQ(msg, "t.trace:" + std::to_string(p + 1) +
                     ": 'variant' follows 'profile vpc3plus': only the VPC3+ has variants");
}

// A run on the C31's interrupt controller records `irq-controller c31` after the profile (its
// xint lines are the C31's interrupt, docs/dpc31.md) and replays; the line belongs to the dpc31.
TEST(TraceFile, TheIrqControllerIsRecordedAndReplayed) {
  std::vector<std::string> v;
  const std::size_t p = recorded_after_profile("profile dpc31", "irq-controller c31", "xint ", v);
  ASSERT_LT(p + 1, v.size());
  std::string msg;
  v[p] = "profile spc3";
  EXPECT_EQ(replay_text(join(v), msg), 2);
  EXPECT_EQ(msg,
            "t.trace:" + std::to_string(p + 2) +
                ": 'irq-controller c31' follows 'profile dpc31': only the DPC31 has a C31 core");
  EXPECT_EQ(lines_of(record("profile dpc31\nstartup\n")).at(p + 1).rfind("irq-controller", 0),
            std::string::npos);  // the external one is the default and not written
  // external is no choice off the dpc31: a silent header line, refused (docs/decisions.md).
  v[p + 1] = "irq-controller external";
  EXPECT_EQ(replay_text(join(v), msg), 2);
  EXPECT_EQ(msg, "t.trace:" + std::to_string(p + 2) +
                     ": 'irq-controller external' follows 'profile dpc31': only the DPC31 has a "
                     "C31 core");
}

TEST(TraceFile, ReplayChecksAHandWrittenTrace) {
  // MAC_Start on the DPC31 at 24 (docs/timing.md): DX_Out from the power-on clear; unmasked,
  // X/INT goes active in the same cycle.
  const std::string text = kHead +
                           "wr 4 0004 C0\n"  // Int_Mask_Reg bits 7..0: all unmasked (7..6 reserved)
                           "wr 8 0005 C0\n"  // bits 15..8
                           + kMacStart +
                           "xint 24 1\n"
                           "rd 28 0003 = 20\n"  // Int_Reg bits 15..8: DX_Out
                           "state 28 dp=Wait_Prm wd=Baud_Search status=0001 irr=2000 "
                           "imr=0000 station=0 fdl=-\n"
                           "end 1000\n";
  std::string msg;
  EXPECT_EQ(replay_text(text, msg), 0) << msg;
}

// error(): "Empty, or why the recording is not a valid trace". A baud the `baud` line cannot hold
// and a recorder never attached gave an empty error() and a text() the parser refuses (the
// audit's rec.cpp); each now says why, in the parser's words.
TEST(TraceFile, TheRecorderSaysWhyItsRecordingIsNoTrace) {
  for (const std::uint32_t baud : {0U, 12'000'001U, 4'000'000'000U}) {
    dpc31::Chip c({dpc31::Profile::spc3, dpc31::BusMode::intel});
    dpc31::TraceRecorder r(baud);
    r.attach(c);
    c.step(10);
    r.finish();
    EXPECT_EQ(r.error(), "baud " + std::to_string(baud) + " out of range (1..12000000)");
    Trace t;
    TraceError e;
    EXPECT_FALSE(parse_trace(r.text(), "x.trace", t, e));
  }
  dpc31::ChipOptions slow{dpc31::Profile::spc3, dpc31::BusMode::intel};
  slow.clock_hz = 1000;  // T = 1000 / 1500000 rounds to no whole cycle
  dpc31::Chip c(slow);
  dpc31::TraceRecorder r(1'500'000);
  r.attach(c);
  r.finish();
  EXPECT_EQ(r.error(), "baud 1500000 is unusable at clock 1000");
  dpc31::TraceRecorder never(1'500'000);
  never.finish();
  EXPECT_EQ(never.error(), "never attached to a chip: attach() before the run");
  EXPECT_EQ(never.text(), "");
}

// --- the RxD line ---

std::vector<std::pair<std::uint64_t, bool>> encode(const std::vector<std::uint8_t>& b,
                                                   std::uint64_t start, std::uint32_t t,
                                                   dpc31::UartFault f = {}) {
  std::vector<std::pair<std::uint64_t, bool>> e;
  dpc31::uart_encode(b, start, t, e, f);
  return e;
}

TEST(TraceRxd, CleanTelegram) {
  const std::vector<std::uint8_t> b = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  const dpc31::RxdTelegram sent{100, b, {}};
  EXPECT_EQ(dpc31::format_rxd(100, encode(b, 100, 32), 32, &sent), "rx 100 10 05 02 49 50 16");
  const dpc31::RxdTelegram e5{100, {0xE5}, {}};
  EXPECT_EQ(dpc31::format_rxd(90, encode({0xE5}, 100, 4), 4, &e5), "rx 100 E5 fed=90");
  // Edges nobody said anything about, or not the ones said: the raw edges.
  EXPECT_TRUE(dpc31::format_rxd(100, encode(b, 100, 32), 32, nullptr).starts_with("rxd 100 "));
  EXPECT_TRUE(dpc31::format_rxd(100, encode(b, 100, 32), 16, &sent).starts_with("rxd 100 "));
}

TEST(TraceRxd, DamagedCharacters) {
  const std::vector<std::uint8_t> b = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  using K = dpc31::UartFault::Kind;
  for (K k : {K::parity, K::stop, K::start}) {
    for (int i = 0; i < 6; ++i) {
      if (k == K::start && i == 0) continue;
      const dpc31::RxdTelegram sent{7, b, {i, k}};
      const std::string s = dpc31::format_rxd(7, encode(b, 7, 8, {i, k}), 8, &sent);
      const std::string kind = k == K::parity ? "parity" : k == K::stop ? "stop" : "start";
      EXPECT_EQ(s, "rx 7 10 05 02 49 50 16 fault=" + kind + ":" + std::to_string(i));
    }
  }
  // No start bit in the first character: no start to count from; the raw edges.
  const auto e = encode(b, 7, 8, {0, K::start});
  const dpc31::RxdTelegram sent{7, b, {0, K::start}};
  const std::string raw = dpc31::format_rxd(7, e, 8, &sent);
  EXPECT_TRUE(raw.starts_with("rxd 7 ")) << raw;
  std::string msg;
  const std::string text =
      "dpc31-trace 1\nprofile dpc31\nbus intel\nclock 48000000\nbaud "
      "6000000\n" +
      raw + "\nend 1000\n";
  EXPECT_EQ(replay_text(text, msg), 0) << msg;
}

// --- the command line ---

using Cli = testutil::CommandResult;

Cli cli(const std::string& args) {
  return testutil::run_command(std::string(DPC31_CLI) + " " + args + " 2>&1");
}

std::string tmp(const std::string& name) {
  return testutil::scratch() + "dpc31_trace_test_" + name;
}

TEST(TraceCli, RecordThenReplay) {
  const std::string scn = tmp("a.scn");
  const std::string trace = tmp("a.trace");
  std::ofstream(scn) << kScenario;
  const Cli r = cli("run --quiet --record " + trace + " " + scn);
  EXPECT_EQ(r.rc, 0) << r.out;
  std::ifstream in(trace);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_TRUE(
      text.str().starts_with("dpc31-trace 1\n# a short session for the trace tests\n#\n# "
                             "recorded by `dpc31 run --record` from "))
      << text.str().substr(0, 200);
  const Cli p = cli("replay " + trace);
  EXPECT_EQ(p.rc, 0) << p.out;
  EXPECT_NE(p.out.find(": ok up to cycle "), std::string::npos) << p.out;
  EXPECT_EQ(cli("replay --quiet " + trace).out, "");
}

// docs/timing.md, "The master's wait": the answer to a run's last request that starts after the
// slot time (MinTSDR 120 > TSL 100 bit times) is heard out before one chip's run ends, and the
// run ends the idle time after it, TSYN = 33 bit times of 32 cycles at 1.5 Mbaud (48 MHz). The
// trace ended at the slot time's end + TSYN, inside that answer, and did not replay (`end at
// cycle 2959580 before an expected event at cycle 2967964`).
TEST(TraceCli, ARunWhoseLastAnswerIsLateReplays) {
  const std::string scn = tmp("late.scn");
  const std::string trace = tmp("late.trace");
  std::ofstream(scn) << "profile dpc31\nbaud 1500000\nmaster address=2 slot=100 retries=0\n"
                        "slave address=5 ident=0x0C31 cfg=13,1F in=16 out=4\n"
                        "user inputs=A0,A1,A2,A3,A4,A5,A6,A7,A8,A9,AA,AB,AC,AD,AE,AF\n"
                        "startup\nset_prm min_tsdr=120\nchk_cfg\nexchange 1 outputs=01,02,03,04\n";
  const Cli r = cli("run --record " + trace + " " + scn);
  ASSERT_EQ(r.rc, 0) << r.out;
  const std::vector<std::string> lines = lines_of(testutil::slurp(trace));
  ASSERT_GE(lines.size(), 3u);
  // The chip's last telegram, its late answer: `tx START END bytes`, then `end CYCLE`.
  std::string tx;
  for (const std::string& l : lines) {
    if (l.starts_with("tx ")) tx = l;
  }
  std::istringstream fields(tx.substr(3));
  std::uint64_t start = 0;
  std::uint64_t end = 0;
  ASSERT_TRUE(fields >> start >> end) << tx;
  EXPECT_NE(tx.find(" 68 13 13 68 02 05 08 A0 A1 A2 "), std::string::npos) << tx;
  const std::string last = std::to_string(end + 33 * 32);
  EXPECT_EQ(lines.back(), "end " + last);
  // The walk's cycles right-aligned in 10 columns.
  const auto at = [](const std::string& cycle) {
    return "[cycle " + std::string(10 - cycle.size(), ' ') + cycle + "] ";
  };
  EXPECT_NE(r.out.find(at(std::to_string(end)) +
                       "master: a late answer on the line (after the slot time): no answer\n" +
                       at(last) + "end: dp_state Data_Exchange"),
            std::string::npos)
      << r.out;
  const Cli p = cli("replay " + trace);
  EXPECT_EQ(p.rc, 0) << p.out;
  EXPECT_EQ(p.out.rfind(trace + ": ok up to cycle " + last + ": ", 0), 0u) << p.out;
  std::remove(scn.c_str());
  std::remove(trace.c_str());
}

// The scenario's file name is written into a comment: a newline in it put "end 5" on a body line
// of its own and the replay refused the trace (the audit's rnl.trace). It is one comment line,
// the newline as \x0A, and the trace replays.
TEST(TraceCli, AFileNameWithANewlineStaysInItsComment) {
  const std::string scn = tmp("rnl\nend 5\nx.scn");
  const std::string trace = tmp("rnl.trace");
  std::ofstream(scn) << kScenario;
  const Cli r = cli("run --quiet --record " + trace + " '" + scn + "'");
  ASSERT_EQ(r.rc, 0) << r.out;
  std::ifstream in(trace);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("\n# recorded by `dpc31 run --record` from " +
                            tmp("rnl\\x0Aend 5\\x0Ax.scn") + " (docs/trace-format.md)\n"),
            std::string::npos)
      << text.str().substr(0, 300);
  const Cli p = cli("replay --quiet " + trace);
  EXPECT_EQ(p.rc, 0) << p.out;
  std::remove(scn.c_str());
}

// docs/trace-format.md's "Example" as a user copies it: an SPC3 started by Mode_Reg1_S (the
// DPC31 ignores Start_SPC3 there: it starts through its Instruction_Queue) replays clean.
TEST(TraceCli, TheDocsExampleReplays) {
  std::ifstream doc(std::string(SOURCE_DIR) + "/docs/trace-format.md");
  std::stringstream all;
  all << doc.rdbuf();
  const std::string text = all.str();
  const std::size_t from = text.find("```\n", text.find("\n## Example\n")) + 4;
  const std::size_t to = text.find("```", from);
  ASSERT_NE(to, std::string::npos);
  const std::string trace = tmp("doc_example.trace");
  std::ofstream(trace) << text.substr(from, to - from);
  const Cli r = cli("replay " + trace);
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_EQ(r.out, trace +
                       ": ok up to cycle 1000: 0 telegrams in, 0 out, 3 writes, 1 reads, 1 "
                       "X/INT edges, 1 states\n");
}

TEST(TraceCli, ExitCodes) {
  const std::string bad = tmp("bad.trace");
  std::ofstream(bad) << kHead << "wr 4 0000 00\n";
  Cli r = cli("replay " + bad);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, bad + ":6: truncated trace: no 'end' line\n");

  const std::string wrong = tmp("wrong.trace");
  std::ofstream(wrong) << kHead << "wr 4 0004 E0\nwr 8 0005 C0\n"
                       << kMacStart << "xint 25 1\nend 100\n";
  r = cli("replay " + wrong);
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(r.out, wrong + ":12: expected xint 1 at cycle 25, got xint 1 at cycle 24\n");

  // A bit time of round(clock / baud) = 0 clocks (docs/trace-format.md) is refused at the later
  // of the two header lines, whichever comes first, not at the first body line.
  const std::string fast = tmp("fast.trace");
  std::ofstream(fast)
      << "dpc31-trace 1\nbaud 1500000\nclock 1000\nprofile spc3\nbus intel\nend 10\n";
  r = cli("replay " + fast);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, fast + ":3: baud 1500000 is unusable at clock 1000\n");
  std::ofstream(fast) << "dpc31-trace 1\nprofile spc3\nbus intel\nclock 1000\nbaud 1500000\n\n"
                         "# a comment\nwr 4 0004 E0\nend 10\n";
  r = cli("replay " + fast);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, fast + ":5: baud 1500000 is unusable at clock 1000\n");

  r = cli("replay " + tmp("missing.trace"));
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, tmp("missing.trace") + ": no such file\n");
  EXPECT_EQ(cli("replay").rc, 2);

  r = cli("run --record /nonexistent-dir/x.trace " + std::string(SOURCE_DIR) +
          "/traces/gc_clear_spc3.scn --quiet");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(
      r.out.rfind("dpc31 run: /nonexistent-dir/x.trace: cannot create the temporary file ", 0), 0u)
      << r.out;
}

// --- a trace file read line by line (s35-replay) ---
//
// `dpc31 replay` read the file whole, at most 64 MiB; TraceFile reads it line by line, twice (a
// check of it all, then the replay), and must refuse what the whole file's reading refused with
// the same line: that reading is still cut_or_earlier_error (textfile.hpp) with parse_trace.

// The whole file's error ("" for a trace).
std::string whole_file_error(const std::string& name, const std::string& text) {
  TraceError err{name, 0, {}};
  err.line =
      dpc31::cut_or_earlier_error(text, err.message, [&](const std::string& whole, std::string& m) {
        Trace t;
        TraceError e;
        if (parse_trace(whole, name, t, e)) return 0;
        m = e.message;
        return e.line;
      });
  if (err.line != 0) return err.text();
  Trace t;
  return parse_trace(text, name, t, err) ? "" : err.text();
}

// TraceFile's error for a file holding `text` ("" for a trace, its lines in `out`).
std::string file_error(const std::string& path, const std::string& text, Trace* out = nullptr) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  Trace t;
  TraceError err;
  if (!dpc31::load_trace(path, t, err)) return err.text();
  if (out != nullptr) *out = std::move(t);
  return "";
}

// A line as one string of all its fields.
std::string fields(const dpc31::TraceLine& l) {
  std::string s =
      fmt::format("{} {} {} {} {} {} {} {} {} {}:{} |", l.line, static_cast<int>(l.kind), l.cycle,
                  l.start, l.end, l.addr, l.data, l.level, fmt::join(l.bytes, ","),
                  static_cast<int>(l.fault.kind), l.fault.char_index);
  for (const auto& [c, lv] : l.edges) s += fmt::format(" {}:{}", c, lv);
  for (const dpc31::TraceStateKey& k : l.state) s += fmt::format(" {}={}", k.key, k.value);
  return s;
}

std::vector<std::string> all_fields(const Trace& t) {
  std::vector<std::string> v;
  for (const dpc31::TraceLine& l : t.lines) v.push_back(fields(l));
  return v;
}

// Every cut of a short trace, the parser's refusals, binary files cut or whole, a BOM, CR LF: the
// file read line by line is refused as the file read whole, at the same line with the same words;
// what both take has the same lines.
TEST(TraceFileLines, RefusedAsTheWholeFileWas) {
  const std::string good = kHead + "# a comment\nwr 4 0004 E0\n\nwr 8 0005 C0 # IMR\n" + kMacStart +
                           "xint 25 1\nrx 100 10 05 02 49 50 16\nend 1000\n";
  std::vector<std::string> texts = {good,
                                    "\xEF\xBB\xBF" + good,
                                    "\xEF\xBB\xBF",
                                    "\n",
                                    "#\n",
                                    "dpc31-trace 1",
                                    "dpc31-trace 1\n",
                                    "dpc31-trace\v1",
                                    "dpc31-trace 1\r\n" + kHead.substr(14)};
  for (std::size_t n = 0; n < good.size(); ++n) texts.push_back(good.substr(0, n));
  // Binary: a control byte or a NUL before, in and after the first wrong line, cut or not.
  for (const std::string& bad : {std::string("\x01"), std::string(1, '\0'), std::string("\x7F")}) {
    for (const std::size_t at : {std::size_t{3}, kHead.size() + 2, good.size() - 4}) {
      std::string t = good;
      t.insert(at, bad);
      texts.push_back(t);
      texts.push_back(t.substr(0, t.size() - 2));
      texts.push_back(t + "x");
    }
  }
  for (const char* t : {"\x7f"
                        "ELF\x01\x02\x03\n\xff\xfe\n",
                        "\x7f"
                        "ELF\x01\x02\x03\n\xff\xfe\nx",
                        "\x7f"
                        "ELF\x02\x01\x01garbage",
                        "garbage\nmore\x01\nend"}) {
    texts.emplace_back(t);
  }
  // And edits of it, the same ones each run: bytes put in, taken out, the end cut.
  std::mt19937 rng(35);
  const std::string alphabet("\n\n\n\x01\0#  x0\r\xEF", 13);
  for (int i = 0; i < 800; ++i) {
    std::string t = good;
    for (int k = static_cast<int>(rng() % 3); k >= 0; --k) {
      const std::size_t at = rng() % (t.size() + 1);
      switch (rng() % 3) {
        case 0:
          t.insert(at, 1, alphabet[rng() % alphabet.size()]);
          break;
        case 1:
          t.erase(std::min(at, t.size() - 1), 1);
          break;
        default:
          t.resize(at);
          break;
      }
      if (t.empty()) break;
    }
    texts.push_back(t);
  }
  const std::string path = tmp("lines.trace");
  int refused = 0;
  for (const std::string& t : texts) {
    Trace whole;
    TraceError e;
    const std::string want = whole_file_error(path, t);
    Trace read;
    EXPECT_EQ(file_error(path, t, &read), want) << fmt::format("{:?}", t);
    if (want.empty() && parse_trace(t, path, whole, e)) {
      EXPECT_EQ(all_fields(read), all_fields(whole)) << fmt::format("{:?}", t);
    }
    refused += want.empty() ? 0 : 1;
  }
  // Most are refused, some are traces still (a comment or a blank line edited).
  EXPECT_GT(refused, 500);
  EXPECT_LT(refused, static_cast<int>(texts.size()) - 50);
}

// The file is read in 64 KiB pieces: a line across two of them, at each place around the end of
// the first, is the line the parser reads in the whole text, and the trace replays as it does.
TEST(TraceFileLines, ALineAcrossTwoPiecesIsOneLine) {
  const std::string& text = recorded();
  const std::size_t second = text.find('\n') + 1;
  const std::string path = tmp("pieces.trace");
  for (std::size_t pad = 65536 - 120; pad < 65536 + 4; ++pad) {
    // A comment line that puts the next lines' bytes across offset 65536.
    const std::string t = text.substr(0, second) + "# " + std::string(pad - second - 3, 'x') +
                          "\n" + text.substr(second);
    Trace whole;
    TraceError e;
    ASSERT_TRUE(parse_trace(t, path, whole, e)) << e.text();
    Trace read;
    ASSERT_EQ(file_error(path, t, &read), "") << pad;
    ASSERT_EQ(all_fields(read), all_fields(whole)) << pad;
  }
  std::string message;
  ReplayOutcome o;
  EXPECT_EQ(dpc31::replay_trace_file(path, message, &o), 0) << message;
  Trace whole;
  TraceError e;
  ASSERT_TRUE(parse_trace(testutil::slurp(path), path, whole, e));
  const ReplayOutcome m = dpc31::replay_trace(whole);
  EXPECT_EQ(std::tie(o.final_cycle, o.telegrams_in, o.telegrams_out, o.writes, o.reads, o.irq_edges,
                     o.states),
            std::tie(m.final_cycle, m.telegrams_in, m.telegrams_out, m.writes, m.reads, m.irq_edges,
                     m.states));
}

// The bounds that remain are a line's (docs/security.md): its text before the comment at most
// 1 MiB (an `rxd` line with every edge of a telegram has less than 64 KiB), 64 MiB in all (a
// scenario's comment line, at most 16 MiB, heads the trace the recorder writes of it). The file
// has none: it was refused past 64 MiB.
TEST(TraceFileLines, BoundsALineNotTheFile) {
  const std::string head = kHead + "wr 4 0004 E0\n";
  const std::string path = tmp("long.trace");
  // 1 MiB of text: `rxd 4 4:1` and blanks.
  const std::string rxd = "rxd 4 4:1";
  EXPECT_EQ(file_error(path, head + rxd + std::string((1u << 20) - rxd.size(), ' ') + "\nend 8\n"),
            "");
  EXPECT_EQ(
      file_error(path, head + rxd + std::string((1u << 20) + 1 - rxd.size(), ' ') + "\nend 8\n"),
      path + ":7: more than 1048576 bytes before the comment: not a trace line");
  // A comment of 2 MiB replays; a line of 64 MiB is taken, one byte more is not.
  EXPECT_EQ(file_error(path, head + "# " + std::string(2u << 20, 'c') + "\nend 8\n"), "");
  std::string message;
  EXPECT_EQ(dpc31::replay_trace_file(path, message), 0) << message;
  EXPECT_EQ(file_error(path, head + "#" + std::string((64u << 20) - 1, 'c') + "\nend 8\n"), "");
  EXPECT_EQ(file_error(path, head + "#" + std::string(64u << 20, 'c') + "\nend 8\n"),
            path + ":7: a line of more than 67108864 bytes: not a trace line");
  std::filesystem::remove(path);
}

// The replay reads the file again after its check: a file changed in between (here cut before
// its `end` line) is bad input when the replay finds it, named so, not a mismatch or a crash.
TEST(TraceFileLines, AFileChangedAfterItsCheckIsNamed) {
  const std::string path = tmp("changed.trace");
  const std::string good = kHead + "wr 4 0004 E0\nwr 8 0005 C0\nend 100\n";
  std::ofstream(path) << good;
  dpc31::TraceFile file;
  TraceError err;
  ASSERT_TRUE(file.open(path, err)) << err.text();
  std::ofstream(path, std::ios::trunc) << good.substr(0, good.rfind("end"));
  try {
    (void)dpc31::replay_trace(file);
    ADD_FAILURE() << "no error";
  } catch (const TraceError& e) {
    EXPECT_EQ(e.text(), path + ":7: the file changed while it was replayed: no 'end' line");
  }
}

// --- traces/diag_ext_diag_dpc31.trace ---
//
// The built-in user side has no extended diagnosis, and scenarios cannot ask for it, so this
// golden trace comes from a session written here: the DPC31 at 1.5 Mbaud; after the start-up
// and one Data_Exchange the firmware, in its next DX_Out interrupt, puts a device-related
// diagnosis block (04 12 34 56) after the six standard bytes of its diag buffer, sets Ext_Diag
// in byte 0 and hands the buffer over (New_Diag_Buffer_Cmd). The following Data_Exchange is
// answered DH, the master fetches the diagnosis, and the exchange after it is DL again.
// DPC31_TRACE_OUT=FILE writes the recording to FILE (to refresh the golden trace, which must
// then be checked by hand again).

constexpr std::array<std::uint8_t, 4> kExtDiag = {0x04, 0x12, 0x34, 0x56};

struct ExtDiagSession {
  std::string text;
  std::vector<dpc31::Exchange> history;
};

ExtDiagSession ext_diag_session() {
  using namespace dpc31;
  ResponderConfig cfg;
  cfg.slave.address = 5;
  MasterConfig m;
  m.address = 2;
  m.baud = 1'500'000;
  TraceRecorder rec(m.baud,
                    {"generated by tests/trace_test.cpp (TraceGolden.DiagExtDiag): the DPC31 "
                     "at 1.5 Mbaud, extended diagnosis",
                     "from the firmware; see there for the session"});
  Chip chip({Profile::dpc31, BusMode::intel});
  rec.attach(chip);
  Responder user(cfg);
  user.set_inputs({0xA1, 0xA2, 0xA3, 0xA4});
  DirectBus bus(chip);
  user.init(bus);
  rec.heading("firmware init (the built-in user side): registers, buffers, Start_SPC3");
  rec.checkpoint();

  const ProfileDesc& p = chip.profile();
  const auto addr = [&](RegId id) {
    const RegDesc* r = find_reg(p, id);
    return static_cast<std::uint32_t>(r->read_addr >= 0 ? r->read_addr : r->write_addr);
  };
  bool publish = false;
  DpMaster master(chip, m, cfg.slave);
  master.on_send = [&rec](std::uint64_t start, std::span<const std::uint8_t> bytes,
                          UartFault fault) { rec.telegram_sent(start, bytes, fault); };
  master.set_firmware([&](BusPort& b) {
    if (publish) {
      publish = false;
      // The user's diag buffer: the one in state 01 (User).
      const std::uint8_t sm = b.read(addr(RegId::Diag_Buffer_SM));
      const int k = (sm & 3) == 1 ? 0 : 1;
      const RegId ptr = k == 0 ? RegId::R_Diag_Buf_Ptr1 : RegId::R_Diag_Buf_Ptr2;
      const RegId len = k == 0 ? RegId::R_Len_Diag_Buf1 : RegId::R_Len_Diag_Buf2;
      const std::uint32_t base = static_cast<std::uint32_t>(b.read(addr(ptr))) << p.segment_shift;
      b.write(base, 0x01);  // Ext_Diag; bytes 1..5 are the ASIC's
      for (std::uint32_t i = 0; i < kExtDiag.size(); ++i) b.write(base + 6 + i, kExtDiag[i]);
      b.write(addr(len), static_cast<std::uint8_t>(6 + kExtDiag.size()));
      b.read(addr(RegId::New_Diag_Buffer_Cmd));
    }
    user.isr(b);
  });
  // After each request the bus idles until the master could send the next one (TSYN after the
  // answer), as the scenario runner does: the checkpoint sees a settled slave.
  const auto settle = [&] {
    const Exchange& ex = master.history().back();
    const std::uint64_t next = ex.answer_end + std::uint64_t{33} * master.bit_cycles();
    if (next > chip.cycle()) master.idle(next - chip.cycle());
  };
  master.startup();
  settle();
  rec.heading(
      "the master's start-up: FDL_Status until answered, Slave_Diag, Set_Prm, Chk_Cfg, "
      "Slave_Diag");
  rec.checkpoint();
  master.data_exchange({0x01, 0x02, 0x03, 0x04});
  settle();
  rec.heading("Data_Exchange 01 02 03 04 (DL)");
  rec.checkpoint();
  publish = true;
  master.data_exchange({0x05, 0x06, 0x07, 0x08});
  settle();
  rec.heading(
      "Data_Exchange 05 06 07 08 (DL); in its DX_Out interrupt the firmware publishes "
      "the extended diagnosis 04 12 34 56 (Ext_Diag, R_Len_Diag_Buf 10, "
      "New_Diag_Buffer_Cmd)");
  rec.checkpoint();
  master.data_exchange({0x05, 0x06, 0x07, 0x08});
  settle();
  rec.heading("Data_Exchange 05 06 07 08: answered DH (Diag_Flag)");
  rec.checkpoint();
  master.slave_diag();
  settle();
  rec.heading("Slave_Diag: the six standard bytes (Ext_Diag set) and the block 04 12 34 56");
  rec.checkpoint();
  master.data_exchange({0x09, 0x0A, 0x0B, 0x0C});
  settle();
  rec.heading("Data_Exchange 09 0A 0B 0C: DL again");
  rec.finish();
  EXPECT_EQ(rec.error(), "");
  return {rec.text(), master.history()};
}

TEST(TraceGolden, DiagExtDiag) {
  const ExtDiagSession s = ext_diag_session();
  ASSERT_GE(s.history.size(), 4u);
  const std::size_t n = s.history.size();
  // DH, then the diagnosis with Ext_Diag and the block, then DL.
  const auto& dh = s.history[n - 3];
  const auto& diag = s.history[n - 2];
  const auto& dl = s.history[n - 1];
  ASSERT_TRUE(dh.answer && diag.answer && dl.answer);
  EXPECT_EQ(dpc31::fdl::response_code(dh.answer->fc), dpc31::fdl::Response::DH);
  EXPECT_EQ(dpc31::fdl::response_code(dl.answer->fc), dpc31::fdl::Response::DL);
  const std::vector<std::uint8_t> want = {0x08, 0x0C, 0x00, 0x02, 0x0C,
                                          0x31, 0x04, 0x12, 0x34, 0x56};
  EXPECT_EQ(diag.answer->du, want);
  std::string msg;
  EXPECT_EQ(replay_text(s.text, msg), 0) << msg;
  if (const char* out = std::getenv("DPC31_TRACE_OUT"); out != nullptr) {
    std::ofstream(out, std::ios::binary) << s.text;
  }
}

}  // namespace

// The scenario's own bus door (write, read, request) and its telegrams as given (send, from=)
// are recorded as wr / rd / rx lines and replay on a fresh chip (docs/trace-format.md,
// "Recording").
// The shipped scenario traces/NAME.scn recorded (every expect holds) and its trace replayed
// clean on a fresh chip; the trace.
static std::string record_shipped(const std::string& name) {
  std::ifstream in(std::string(SOURCE_DIR) + "/traces/" + name + ".scn");
  const std::string scn((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  int rc = -1;
  const std::string t = record(scn, &rc);
  EXPECT_EQ(rc, 0) << name;
  std::string msg;
  EXPECT_EQ(replay_text(t, msg), 0) << name << ": " << msg;
  return t;
}

TEST(TraceRun, NewScenarioActionsRecordAndReplay) {
  for (const char* name : {"bus_access_spc3", "requests_dpc31"}) record_shipped(name);
  // The bad-FCS telegram of `send` is an rx line as it was sent.
  EXPECT_NE(record_shipped("telegrams_as_given_dpc31").find(" 10 05 02 49 51 16\n"),
            std::string::npos);
}

// DPV1 (docs/trace-format.md, "Recording"): the acyclic exchanges are telegrams and the user
// side's bus accesses like any other, so a recorded MSAC_C1 / MSAC_C2 run replays on a fresh
// chip: the Read request and every poll as rx lines, the SC and the response as tx lines, the
// user side's SAP-list and buffer accesses as wr / rd lines, FDL_Ind / Poll_End_Ind as xint.
TEST(TraceRun, Dpv1ExchangesRecordAndReplay) {
  record_shipped("dpv1_c2_vpc3plus");
  const std::string t = record_shipped("dpv1_c1_vpc3plus");
  // The Read request (SAP 51 -> 51: 5E 00 01 04) and its response (DL, 5E 00 01 04 11 22 33 44)
  // as they went over the wire.
  const std::size_t req = t.find(" 33 33 5E 00 01 04 ");  // DSAP, SSAP, the Read
  ASSERT_NE(req, std::string::npos);
  EXPECT_EQ(t.substr(t.rfind('\n', req) + 1, 3), "rx ");  // a line of the master's
  EXPECT_NE(t.find(" 82 85 08 33 33 5E 00 01 04 11 22 33 44 "), std::string::npos);
}

// --- PB3 (seed 003, DPC31 p.32; docs/timing.md "dpc31 PB3") ---

namespace {

// traces/gc_sync_pb3_dpc31.trace as `edit` leaves it, replayed; the exit code and message.
int replay_pb3_golden(const std::function<void(std::vector<std::string>&)>& edit,
                      std::string& msg) {
  std::vector<std::string> v =
      lines_of(testutil::slurp(std::string(SOURCE_DIR) + "/traces/gc_sync_pb3_dpc31.trace"));
  edit(v);
  return replay_text(join(v), msg);
}

// The 1-based line number of the line `text` in the golden PB3 trace.
int pb3_golden_line(const std::string& text) {
  const std::vector<std::string> v =
      lines_of(testutil::slurp(std::string(SOURCE_DIR) + "/traces/gc_sync_pb3_dpc31.trace"));
  return static_cast<int>(std::find(v.begin(), v.end(), text) - v.begin()) + 1;
}

// "t.trace:LINE: MESSAGE".
std::string line_msg(int line, const std::string& message) {
  return "t.trace:" + std::to_string(line) + ": " + message;
}

}  // namespace

// The recorder writes PB3's edges as `pb3` lines (no longer as `# PB3 ...` comments) under the
// header `check pb3`, at the cycles of docs/timing.md: the Sync of rx 2939504 (13 characters of
// 352 clocks at 1.5 Mbaud) ends at 2944080 and is acted on at its last stop sample, 2944080 - 32
// + 16 = 2944064, where DX_Out is latched; PB3 falls at the completion of the user's Int_Ack_Reg
// write (wr 2944112 0003 21). The second Sync: 2955696 + 4576 - 16 = 2960256, acknowledged at
// 2960324. Unsync and Sync with Unsync drive no edge.
TEST(TracePb3, SyncEdgesAreRecordedAsPb3Lines) {
  const std::string t = record_shipped("gc_sync_pb3_dpc31");
  const std::vector<std::string> v = lines_of(t);
  std::vector<std::string> pb3;
  for (const std::string& l : v) {
    if (l.starts_with("pb3 ")) pb3.push_back(l);
  }
  EXPECT_EQ(pb3, (std::vector<std::string>{"pb3 2944064 1", "pb3 2944112 0", "pb3 2960256 1",
                                           "pb3 2960324 0"}));
  EXPECT_NE(t.find("\nprofile dpc31\ncheck pb3\nbus intel\n"), std::string::npos);
  EXPECT_EQ(t.find("# PB3 "), std::string::npos);
  // The other profiles have no PB3: no `check pb3`.
  EXPECT_EQ(recorded().find("check pb3"), std::string::npos);
}

// A replay whose chip drives PB3 otherwise fails at the `pb3` line, naming both edges.
TEST(TracePb3, AChangedPb3FailsTheReplayWithAPairedLine) {
  std::string msg;
  // The port never enabled (the auditor's cut: no C31_Control write): PB3 never rises.
  EXPECT_EQ(
      replay_pb3_golden(
          [](std::vector<std::string>& v) { std::erase(v, std::string("wr 196 0017 01")); }, msg),
      1);
  EXPECT_EQ(msg, line_msg(pb3_golden_line("pb3 2944064 1") - 1,
                          "expected pb3 1 at cycle 2944064, got no PB3 edge by cycle 2944064"));
  // The edge expected one access earlier than the Sync's stop sample.
  EXPECT_EQ(replay_pb3_golden(
                [](std::vector<std::string>& v) {
                  *std::find(v.begin(), v.end(), "pb3 2944064 1") = "pb3 2944060 1";
                },
                msg),
            1);
  EXPECT_EQ(msg, line_msg(pb3_golden_line("pb3 2944064 1"),
                          "expected pb3 1 at cycle 2944060, got pb3 1 at cycle 2944064"));
  // An edge the trace does not expect (the second Sync's): the chip makes it inside the read
  // that completes at 2960260, so it is reported at the next line (docs/trace-format.md), the
  // read completing at 2960264, which expects none before its cycle.
  EXPECT_EQ(replay_pb3_golden(
                [](std::vector<std::string>& v) {
                  std::erase(v, std::string("pb3 2960256 1"));
                  std::erase(v, std::string("pb3 2960324 0"));
                },
                msg),
            1);
  EXPECT_EQ(msg, line_msg(pb3_golden_line("rd 2960264 0003 = 20") - 1,
                          "expected no other PB3 edge up to cycle 2960263, got pb3 1 at cycle "
                          "2960256"));
}

// A trace without `check pb3` (recorded before it existed) replays as before: PB3 is not looked
// at, whatever the chip drives there.
TEST(TracePb3, ATraceWithoutCheckPb3DoesNotLookAtPb3) {
  std::string msg;
  EXPECT_EQ(replay_pb3_golden(
                [](std::vector<std::string>& v) {
                  std::erase_if(v, [](const std::string& l) {
                    return l == "check pb3" || l.starts_with("pb3 ");
                  });
                },
                msg),
            0)
      << msg;
}

TEST(TracePb3, TheReplayCountsPb3EdgesWhereItChecksThem) {
  const Cli r = cli("replay " + std::string(SOURCE_DIR) + "/traces/gc_sync_pb3_dpc31.trace");
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find(": 464 telegrams in, 7 out, 104 writes, 72 reads, 20 X/INT edges, 4 PB3 "
                       "edges, 8 states\n"),
            std::string::npos)
      << r.out;
}

// A `cpu` scenario's `reset` (the board's RESET, docs/cpu.md "The board's reset") is a `reset
// CYCLE` line, and the replay resets its chip there (docs/trace-format.md). The image: MOV
// DPTR,#8008h [0,2); MOV A,#01h [2]; MOVX @DPTR,A [3,5): Start_SPC3 completes at 24 x 3 + 36 =
// 108 (24 MHz beside 48 MHz, docs/cpu.md "MOVX timing"); SJMP $. `silence 1ms` ends at 48 000,
// machine cycle 2 000, where the reset starts the CPU again: Start_SPC3 at 48 108. Without the
// line the replay's chip stays started through the reset's checkpoint: a mismatch there.
TEST(Trace, ABoardsResetIsALineTheReplayFollows) {
  const testutil::TempDir dir;
  const std::string image = dir.file("start.ihx");
  std::ofstream(image) << ":080000009080087401F080FEFD\n:00000001FF\n";
  const std::vector<std::string> v =
      lines_of(record("profile spc3\ncpu 80c32 clock=24000000 firmware " + image +
                      "\nsilence 1ms\nreset\n"
                      "silence 1ms\n"));
  const std::size_t first = find_line(v, "wr 108 0008 01");
  const std::size_t reset = find_line(v, "reset 48000", first);
  find_line(v, "wr 48108 0008 01", reset);
  std::string message;
  EXPECT_EQ(replay_text(join(v), message), 0) << message;
  std::vector<std::string> without = v;
  without.erase(without.begin() + static_cast<std::ptrdiff_t>(reset));
  EXPECT_EQ(replay_text(join(without), message), 1);
  EXPECT_TRUE(message.starts_with("t.trace:")) << message;
  // A reset past the chip's time (Chip::kLastCycle = 2^62 - 1) is the line's bad input, exit 2 at
  // its line before anything runs (docs/trace-format.md), not Chip::reset's exception mid-replay.
  std::vector<std::string> late = v;
  late[reset] = "reset 4611686018427387904";
  EXPECT_EQ(replay_text(join(late), message), 2) << message;
  EXPECT_EQ(message, fmt::format("t.trace:{}: reset cycle 4611686018427387904 is past the chip's "
                                 "last cycle 4611686018427387903",
                                 reset + 1))
      << message;
}
