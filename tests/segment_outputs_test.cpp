// The outputs of a segment's run (docs/segment.md, "Outputs"): the waveform with the line at the
// top and every station under its own scope (read back from the VCD, and from the FST through
// gtkwave's fst2vcd), the pcapng of the line through tshark and the shipped dissector, a trace per
// station that replays alone, and the bad input of a segment's run. Every expected cycle comes
// from docs/timing.md at 1.5 Mbaud: T = 48 MHz / 1.5 Mbaud = 32 clocks, a character 11 T = 352.
#include "segment_outputs.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "dpc31/fdl.hpp"
#include "run_command.hpp"
#include "segment.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;
using testutil::slurp;

constexpr std::uint64_t kT = 32;          // clocks per bit at 1.5 Mbaud
constexpr std::uint64_t kChar = 11 * kT;  // one character (start, 8 data, parity, stop)
constexpr std::uint64_t kTsdr = 11 * kT;  // an answer's first start bit after the request's end
constexpr std::uint32_t kNone = 0xFF;     // line.driver: nobody drives
constexpr std::uint32_t kRogue = 0xFE;    // line.driver: a sender without an address

const std::string kScenario = std::string(SOURCE_DIR) + "/traces/segment/two_masters.scn";

testutil::CommandResult sh(const std::string& cmd) { return testutil::run_command(cmd + " 2>&1"); }

std::string tmp(const std::string& name) {
  // One private directory per process (CTest runs each test in a process of its own, in
  // parallel), removed with the process's static objects at its exit.
  static const testutil::TempDir dir;
  return dir.file(name);
}

// A VCD read back: every variable by its full name, its changes as (cycle, value). Times are
// units of `ps` picoseconds at 48 MHz (1 ps the full form, 10 ns the logic-analyser form):
// unit = round(cycle x 10^12 / (ps x f)), so cycle = round(unit x ps x f / 10^12).
struct Vcd {
  std::map<std::string, int> width;
  std::map<std::string, std::vector<std::pair<std::uint64_t, std::uint32_t>>> changes;
  std::uint64_t ps = 1;

  [[nodiscard]] std::uint64_t cycle_of(std::uint64_t unit) const {
    return (unit * ps * 24 + 250'000) / 500'000;
  }

  explicit Vcd(const std::string& text, std::uint64_t unit_ps = 1) : ps(unit_ps) {
    std::istringstream in(text);
    std::vector<std::string> scopes;
    std::map<std::string, std::string> name_of;  // id code -> full name
    std::uint64_t cycle = 0;
    for (std::string w; in >> w;) {
      if (w == "$scope") {
        std::string kind, name;
        in >> kind >> name;
        scopes.push_back(name);
      } else if (w == "$upscope") {
        scopes.pop_back();
      } else if (w == "$var") {
        std::string kind, id, leaf;
        int n = 0;
        in >> kind >> n >> id >> leaf;
        std::string full;
        for (const std::string& s : scopes) full += s + ".";
        full += leaf;
        name_of[id] = full;
        width[full] = n;
      } else if (w[0] == '#') {
        cycle = cycle_of(std::stoull(w.substr(1)));
      } else if (w[0] == 'b') {
        std::string id;
        in >> id;
        add(name_of.at(id), cycle, static_cast<std::uint32_t>(std::stoul(w.substr(1), nullptr, 2)));
      } else if ((w[0] == '0' || w[0] == '1') && name_of.count(w.substr(1)) != 0) {
        add(name_of.at(w.substr(1)), cycle, w[0] == '1' ? 1u : 0u);
      }
    }
  }
  void add(const std::string& n, std::uint64_t c, std::uint32_t v) {
    auto& ch = changes[n];
    if (!ch.empty() && ch.back().first == c) {
      ch.back().second = v;  // $dumpvars, then a change in the same time
    } else if (ch.empty() || ch.back().second != v) {
      ch.emplace_back(c, v);
    }
  }
  [[nodiscard]] std::uint32_t at(const std::string& n, std::uint64_t c) const {
    std::uint32_t v = 0;
    for (const auto& [cc, vv] : changes.at(n)) {
      if (cc > c) break;
      v = vv;
    }
    return v;
  }
  // Changes in [from, to).
  [[nodiscard]] std::size_t changes_in(const std::string& n, std::uint64_t from,
                                       std::uint64_t to) const {
    std::size_t k = 0;
    for (const auto& [c, v] : changes.at(n)) k += c >= from && c < to ? 1 : 0;
    return k;
  }
};

// A telegram on the line as the waveform shows it: line.driver from its first start bit to the
// end of its last stop bit, the bytes read from line.level (8E1, sampled mid-bit).
struct OnLine {
  std::uint32_t driver = 0;
  std::uint64_t start = 0;
  std::uint64_t end = 0;
  std::vector<std::uint8_t> bytes;
};

std::vector<OnLine> line_runs(const Vcd& v) {
  std::vector<OnLine> runs;
  const auto& d = v.changes.at("segment.line.driver");
  for (std::size_t i = 0; i + 1 < d.size(); ++i) {
    if (d[i].second == kNone) continue;
    OnLine r{d[i].second, d[i].first, d[i + 1].first, {}};
    for (std::uint64_t c = r.start; c + kChar <= r.end; c += kChar) {
      std::uint8_t b = 0;
      for (unsigned k = 0; k < 8; ++k)
        b |= static_cast<std::uint8_t>(v.at("segment.line.level", c + (k + 1) * kT + kT / 2) << k);
      r.bytes.push_back(b);
    }
    runs.push_back(r);
  }
  return runs;
}

// One run of the shipped two-master scenario with every output, shared by the tests.
struct Outputs {
  std::string vcd = tmp("two.vcd");
  std::string fst = tmp("two.fst");
  std::string la = tmp("two-la.vcd");
  std::string pcap = tmp("two.pcapng");
  std::string gtkw = tmp("two.gtkw");
  std::string record = tmp("two.trace");
  std::string json = tmp("two.json");
  int rc = -1;
  std::string out;
  Outputs() {
    // From the source tree, as the golden traces were recorded: they name the scenario so.
    const auto r = sh(fmt::format(
        "cd {} && {} run --quiet traces/segment/two_masters.scn --vcd {} --fst {} --la-vcd {} "
        "--pcap {} --gtkw {} --record {} --json {}",
        SOURCE_DIR, DPC31_CLI, vcd, fst, la, pcap, gtkw, record, json));
    rc = r.rc;
    out = r.out;
  }
};

const Outputs& outputs() {
  static const Outputs o;
  return o;
}

}  // namespace

TEST(SegmentOutputs, RunWritesEveryOutput) {
  const Outputs& o = outputs();
  ASSERT_EQ(o.rc, 0) << o.out;
  EXPECT_EQ(o.out, "");
  for (const std::string& f : {o.vcd, o.fst, o.la, o.pcap, o.gtkw, o.json,
                               tmp("two.station5_spc3.trace"), tmp("two.station6_dpc31.trace")}) {
    EXPECT_TRUE(fs::is_regular_file(f)) << f;
  }
  // The summary: both stations in Data_Exchange, the collision, every expect passed.
  const std::string j = slurp(o.json);
  for (const std::string want :
       {"\"scope\": \"station5_spc3\"", "\"scope\": \"station6_dpc31\"", "\"collisions\": 1",
        "\"passed\": 9", "\"failed\": 0", "\"ok\": true"}) {
    EXPECT_NE(j.find(want), std::string::npos) << want << "\n" << j;
  }
  // The run's last cycle, where each station's trace ends too.
  const std::string trace = slurp(tmp("two.station5_spc3.trace"));
  const std::size_t end = trace.rfind("\nend ");
  ASSERT_NE(end, std::string::npos);
  const std::string last = trace.substr(end + 5, trace.find('\n', end + 1) - end - 5);
  EXPECT_NE(j.find("\"final_cycle\": " + last + ",\n"), std::string::npos) << last << "\n" << j;
  // The summary's objects: itself, the expects, and each station's with its counters.
  EXPECT_EQ(std::count(j.begin(), j.end(), '{'), 1 + 1 + 2 * 2) << j;
  std::size_t dx = 0;
  for (std::size_t at = j.find("\"dp_state\": \"Data_Exchange\""); at != std::string::npos;
       at = j.find("\"dp_state\": \"Data_Exchange\"", at + 1))
    ++dx;
  EXPECT_EQ(dx, 2u) << j;
}

// The line at the top, every station's signals (the single chip's list) under its scope.
TEST(SegmentOutputs, WaveformScopes) {
  const Vcd v(slurp(outputs().vcd));
  EXPECT_EQ(v.width.at("segment.line.level"), 1);
  EXPECT_EQ(v.width.at("segment.line.driver"), 8);
  for (const std::string st : {"station5_spc3", "station6_dpc31"}) {
    for (const auto& [sig, w] : std::vector<std::pair<std::string, int>>{{"pins.rxd", 1},
                                                                         {"pins.txd", 1},
                                                                         {"pins.x_int", 1},
                                                                         {"bus.rd", 1},
                                                                         {"bus.wr", 1},
                                                                         {"bus.addr", 13},
                                                                         {"bus.data", 8},
                                                                         {"state.dp_state", 2},
                                                                         {"state.wd_state", 2},
                                                                         {"state.baud_code", 4},
                                                                         {"state.service", 8},
                                                                         {"blocks.irr", 16},
                                                                         {"blocks.dout_sm", 8},
                                                                         {"blocks.din_sm", 8},
                                                                         {"blocks.diag_sm", 4}}) {
      EXPECT_EQ(v.width.at("segment." + st + "." + sig), w) << st << "." << sig;
    }
  }
  // PB3 is a DPC31 port.
  EXPECT_EQ(v.width.count("segment.station6_dpc31.pins.pb3"), 1u);
  EXPECT_EQ(v.width.count("segment.station5_spc3.pins.pb3"), 0u);
  // Both reach Data_Exchange (2) and DP_Control (2).
  EXPECT_EQ(v.changes.at("segment.station5_spc3.state.dp_state").back().second, 2u);
  EXPECT_EQ(v.changes.at("segment.station6_dpc31.state.dp_state").back().second, 2u);
}

// Every answer 11 T after its request (docs/timing.md, TSDR with MinTSDR 11), driven by the slave
// asked: line.driver is its address from that cycle, its TxD falls there, the other station hears
// it at the same cycle and it does not hear itself; every telegram is whole characters.
TEST(SegmentOutputs, WaveformLineAndAnswersAtTheirCycles) {
  const Vcd v(slurp(outputs().vcd));
  const std::vector<OnLine> runs = line_runs(v);
  ASSERT_GT(runs.size(), 40u);
  std::size_t answers = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const OnLine& r = runs[i];
    EXPECT_EQ((r.end - r.start) % kChar, 0u) << r.start;
    EXPECT_EQ(v.at("segment.line.level", r.start), 0u) << r.start;  // a start bit
    // An answer to a master's request (the collision's remains follow the rogue's).
    if ((r.driver != 5 && r.driver != 6) || i == 0 || runs[i - 1].driver > 3) continue;
    ++answers;
    const std::string me = r.driver == 5 ? "station5_spc3" : "station6_dpc31";
    const std::string other = r.driver == 5 ? "station6_dpc31" : "station5_spc3";
    const OnLine& req = runs[i - 1];
    EXPECT_EQ(req.driver, r.driver == 5 ? 2u : 3u) << r.start;  // each master's own slave
    EXPECT_EQ(r.start, req.end + kTsdr) << "answer of " << r.driver;
    // The request's DA is the answering station (SD1/SD2/SD3: byte 1 or 4).
    ASSERT_FALSE(req.bytes.empty());
    EXPECT_EQ(req.bytes[req.bytes[0] == 0x68 ? 4 : 1] & 0x7F, r.driver) << req.start;
    EXPECT_EQ(v.at("segment." + me + ".pins.txd", r.start), 0u);
    EXPECT_EQ(v.at("segment." + me + ".pins.txd", r.start - 1), 1u);
    EXPECT_EQ(v.at("segment." + other + ".pins.rxd", r.start), 0u);
    EXPECT_EQ(v.at("segment." + other + ".pins.rxd", r.start - 1), 1u);
    EXPECT_EQ(v.changes_in("segment." + me + ".pins.rxd", req.end, r.end), 0u);
  }
  // Each slave answers its start-up (FDL_Status once out of its baud search, Slave_Diag, Set_Prm,
  // Chk_Cfg, Slave_Diag) and the 5 Data_Exchange of `cycle 5`: 10 each.
  EXPECT_EQ(answers, 20u);
}

// A request is acted on at the stop sample of its last character, end - T + T/2 (docs/timing.md):
// state.service shows its SAP there, at the station asked and at the other one, which hears it
// too (the Set_Prm of master 3 to station 6, once station 5 is out of its baud search).
TEST(SegmentOutputs, WaveformServiceAtTheStopSample) {
  const Vcd v(slurp(outputs().vcd));
  std::size_t seen = 0;
  for (const OnLine& r : line_runs(v)) {
    if (r.bytes.size() < 9 || r.bytes[0] != 0x68 || r.bytes[7] != 0x3D) continue;  // Set_Prm
    const std::uint64_t acted = r.end - kT + kT / 2;
    for (const std::string st : {"station5_spc3", "station6_dpc31"}) {
      const std::string n = "segment." + st + ".state.service";
      if (st == "station6_dpc31" && (r.bytes[4] & 0x7F) == 5) continue;  // 6 still searching
      EXPECT_EQ(v.at(n, acted), 0x3Du) << st << " " << r.start;
      EXPECT_NE(v.at(n, acted - 1), 0x3Du) << st << " " << r.start;
    }
    ++seen;
  }
  EXPECT_EQ(seen, 2u);
}

// The collision of two_masters.scn: the rogue's FDL_Status to 5 (10 05 02 49 50 16), then its
// second telegram, to 7, 2 T after the first's end (the step that sent the first ends there). The
// SPC3's answer is due 11 T after the first's end: its TxD falls there, while the line stays the
// rogue's (the first driver keeps it) and station 6 hears only the rogue.
TEST(SegmentOutputs, WaveformCollision) {
  const Vcd v(slurp(outputs().vcd));
  const std::vector<OnLine> runs = line_runs(v);
  const std::vector<std::uint8_t> to5 = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  const auto it = std::find_if(runs.begin(), runs.end(), [&](const OnLine& r) {
    return r.driver == kRogue && r.bytes == to5;
  });
  ASSERT_NE(it, runs.end());
  ASSERT_NE(it + 1, runs.end());
  const OnLine& first = *it;
  const OnLine& second = *(it + 1);
  EXPECT_EQ(first.end, first.start + 6 * kChar);
  EXPECT_EQ(second.driver, kRogue);
  EXPECT_EQ(second.start, first.end + 2 * kT);
  EXPECT_EQ(second.bytes, (std::vector<std::uint8_t>{0x10, 0x07, 0x02, 0x49, 0x52, 0x16}));
  const std::uint64_t due = first.end + kTsdr;
  EXPECT_EQ(v.at("segment.station5_spc3.pins.txd", due), 0u);
  EXPECT_EQ(v.at("segment.station5_spc3.pins.txd", due - 1), 1u);
  EXPECT_EQ(v.at("segment.line.driver", due), kRogue);
  // Station 6 hears the line, not the SPC3: its RxD is the rogue's second telegram throughout.
  for (std::uint64_t c = second.start; c < second.end; c += kT / 2)
    EXPECT_EQ(v.at("segment.station6_dpc31.pins.rxd", c), v.at("segment.line.level", c)) << c;
}

// The FST holds the same changes (read by gtkwave's fst2vcd), the logic-analyser form the line
// and each station's 1-bit pins in one scope, the save file a group per station.
TEST(SegmentOutputs, FstLaVcdAndSaveFile) {
  const Outputs& o = outputs();
  const auto conv = sh(fmt::format("fst2vcd -f {} -o {}", o.fst, tmp("from-fst.vcd")));
  ASSERT_EQ(conv.rc, 0) << conv.out;
  const Vcd a(slurp(o.vcd));
  const Vcd b(slurp(tmp("from-fst.vcd")));
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.changes, b.changes);
  const Vcd la(slurp(o.la), 10'000);
  EXPECT_EQ(la.width.count("segment.line"), 1u);
  EXPECT_EQ(la.width.count("segment.station5_spc3_txd"), 1u);
  EXPECT_EQ(la.width.count("segment.station6_dpc31_pb3"), 1u);
  EXPECT_EQ(la.width.count("segment.line.driver"), 0u);
  EXPECT_EQ(la.changes.at("segment.line"), a.changes.at("segment.line.level"));
  const std::string g = slurp(o.gtkw);
  EXPECT_NE(g.find("-station5_spc3\n"), std::string::npos) << g;
  EXPECT_NE(g.find("segment.station6_dpc31.state.dp_state[1:0]"), std::string::npos) << g;
  EXPECT_NE(g.find("dp_state.txt\nsegment.station5_spc3.state.dp_state[1:0]"), std::string::npos);
  EXPECT_NE(g.find("segment.line.driver[7:0]"), std::string::npos);
}

// The pcapng of the line through tshark and lib/capture/profibus_dl.lua: every telegram of the
// waveform's line, at its first start bit (ns = round(cycle x 10^9 / 48 MHz)), its sender and,
// for a request, who answered it.
TEST(SegmentOutputs, PcapOfTheLineInTshark) {
  const Outputs& o = outputs();
  const auto r = testutil::run_command(fmt::format(
      "env HOME={0} XDG_CONFIG_HOME={0} tshark -n -X lua_script:{1}/lib/capture/profibus_dl.lua "
      "-r {2} -T fields -E 'separator=|' -e frame.time_epoch -e frame.comment -e profibus.sd "
      "-e profibus.sa -e profibus.da 2>/dev/null",
      ::testing::TempDir(), SOURCE_DIR, o.pcap));
  ASSERT_EQ(r.rc, 0) << r.out;
  const Vcd v(slurp(o.vcd));
  const std::vector<OnLine> runs = line_runs(v);
  std::vector<std::string> lines;
  std::istringstream in(r.out);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), runs.size()) << r.out;
  const std::map<std::uint32_t, std::string> names = {
      {2, "master 2"}, {3, "master 3"}, {5, "spc3"}, {6, "dpc31"}, {kRogue, "rogue"}};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const OnLine& run = runs[i];
    const std::uint64_t ns = (run.start * 1'000'000'000 + 24'000'000) / 48'000'000;
    std::string want = fmt::format("{}.{:09}|cycles {}-{}, {}", ns / 1'000'000'000,
                                   ns % 1'000'000'000, run.start, run.end, names.at(run.driver));
    // An answer: a slave's telegram right after a master's request (the collision's remains
    // after the rogue's are no frame and answer nothing).
    const auto answer = [&](std::size_t k) {
      return (runs[k].driver == 5 || runs[k].driver == 6) && k > 0 && runs[k - 1].driver <= 3;
    };
    if (answer(i)) want += fmt::format(", answer to master {}", runs[i - 1].driver);
    if (i + 1 < runs.size() && answer(i + 1))
      want += fmt::format(", answered by {}", names.at(runs[i + 1].driver));
    EXPECT_EQ(lines[i].substr(0, want.size()), want) << i;
    // The dissector's SD is the first byte on the line (F1, the collision's remains, is none).
    if (run.bytes.at(0) != 0xF1) {
      EXPECT_NE(lines[i].find(fmt::format("|0x{:02x}|", run.bytes.at(0))), std::string::npos)
          << lines[i];
    }
  }
}

// The pcapng pairs a request and its answer as the bus check does (docs/capture.md, docs/segment.md
// "Bus checks"): an answer within TSL (100 bit times, the header's default) after the request's
// end, or the asked station's late answer before TSL + TSYN (133), is "answered by"; at TSL + TSYN,
// or a late one from another station, it is unsolicited and stands alone. 1.5 Mbaud at 48 MHz: a
// bit 32 cycles, an SD1 telegram of 6 characters 66 bits = 2112 cycles, a sender's default gap
// TSYN 33 bits = 1056.
TEST(SegmentOutputs, ThePcapPairsAsTheBusCheckDoes) {
  const std::string file = tmp("pair.scn");
  const std::string req = "send from=a 10,09,01,49,53,16\n";  // 1 -> 9, SRD low: wants an answer
  const std::string ans = "10,01,09,00,0A,16\n";              // 9 -> 1: mirrors it
  {
    std::ofstream(file) << "segment baud=1500000\nstation 5 profile=spc3\nsender a\nsender b\n"
                        << req << "send from=b after=100bits " << ans << req
                        << "send from=b after=120bits " << ans << req
                        << "send from=b after=133bits " << ans << req
                        << "send from=b after=120bits 10,01,07,00,08,16\n"  // station 7: not asked
                        << "run 100bits\nexpect bus_violation late_answer 1\n"
                        << "expect bus_violation unsolicited 2\n";
  }
  const auto r =
      sh(fmt::format("{} run --quiet {} --pcap {}", DPC31_CLI, file, tmp("pair.pcapng")));
  ASSERT_EQ(r.rc, 0) << r.out;
  // The comments, in the file's order (pcapng keeps an option's text as it is, padded to 4 bytes
  // with zeros: the text ends at the first).
  const std::string pcap = slurp(tmp("pair.pcapng"));
  std::vector<std::string> got;
  for (std::size_t at = pcap.find("cycles "); at != std::string::npos;
       at = pcap.find("cycles ", at + 1)) {
    const std::size_t end = pcap.find('\0', at);
    got.push_back(pcap.substr(at, end - at));
  }
  ASSERT_EQ(got.size(), 8u);
  std::uint64_t t = std::stoull(got[0].substr(7));  // the first request's start
  const std::uint64_t bit = 32;
  const std::uint64_t tel = 66 * bit;
  std::vector<std::string> want;
  for (const auto& [gap, paired] :
       {std::pair{100, true}, {120, true}, {133, false}, {120, false}}) {
    want.push_back(fmt::format("cycles {}-{}, a{}", t, t + tel, paired ? ", answered by b" : ""));
    t += tel + gap * bit;
    want.push_back(fmt::format("cycles {}-{}, b{}", t, t + tel, paired ? ", answer to a" : ""));
    t += tel + 33 * bit;
  }
  EXPECT_EQ(got, want);
}

// What the capture and the bus check do with the rest of a telegram that a collision cut
// (docs/capture.md, a segment's --pcap; docs/segment.md "Bus checks"): no answer to either. The
// capture pairs it with nothing; the bus check judged that telegram at its start, in the
// collision, and counts its rest no more (until the thirty-fourth session it took it as the
// request's answer: `bad_frame` and `early_answer`, s34 audit aSeg finding 4). two_masters.scn's
// collision: the rogue's request 10 07 02 49 52 16 to station 7 (6 characters, 6 x 352 = 2112
// cycles at 1.5 Mbaud, 48 MHz) from S to S + 2112, and the SPC3's remainder F1, one character (352
// cycles), 2 bit times (64 cycles) after it; the SPC3 began its answer to the request to 5 in
// that request's window (11 T after it), so the collision is all the check says.
TEST(SegmentOutputs, ACollisionsRemainsAnswerNothing) {
  const std::string pcap = tmp("remains.pcapng");
  const auto r = sh(fmt::format("cd {} && {} run traces/segment/two_masters.scn --pcap {}",
                                SOURCE_DIR, DPC31_CLI, pcap));
  ASSERT_EQ(r.rc, 0) << r.out;
  const std::string request = "] rogue: 10 07 02 49 52 16\n";
  const std::size_t at = r.out.find(request);
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::uint64_t s = std::stoull(r.out.substr(r.out.rfind("[cycle", at) + 6));
  const std::uint64_t f = s + 6 * kChar + 2 * kT;
  const std::string cycle = fmt::format("[cycle {:>10}] ", f);
  EXPECT_NE(r.out.find(request + fmt::format("[cycle {:>10}] line 35: run 1ms\n", s + 6 * kChar) +
                       cycle + "spc3: F1\n"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("bus: bad_frame"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("bus: early_answer"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("bus: unsolicited"), std::string::npos) << r.out;
  const auto t = testutil::run_command(fmt::format(
      "env HOME={0} XDG_CONFIG_HOME={0} tshark -n -X lua_script:{1}/lib/capture/profibus_dl.lua "
      "-r {2} -T fields -e frame.comment 2>/dev/null",
      ::testing::TempDir(), SOURCE_DIR, pcap));
  ASSERT_EQ(t.rc, 0) << t.out;
  EXPECT_NE(t.out.find(fmt::format("\ncycles {}-{}, rogue\ncycles {}-{}, spc3\n", s, s + 6 * kChar,
                                   f, f + kChar)),
            std::string::npos)
      << t.out;
}

// A `# from NAME` note follows the rx line of the telegram it names (docs/trace-format.md), also
// when the segment reports the telegram only after many steps that move no time (expects): the
// review's case of 70 expects after the rogue's telegram put its note after the next step's
// heading, where it named the sender of nothing.
TEST(SegmentOutputs, AFromNoteFollowsItsTelegramAfterManySteps) {
  std::string scn =
      "segment baud=1500000\nstation 5 name=spc3 profile=spc3\nmaster 2 slaves=5\n"
      "sender rogue\nstartup\nsend from=rogue after=33bits 10,07,02,49,52,16\n";
  for (int i = 0; i < 70; ++i) scn += "expect state 5 Data_Exchange\n";
  scn += "run 1ms\n";
  const std::string file = tmp("many.scn");
  { std::ofstream(file) << scn; }
  const auto r =
      sh(fmt::format("{} run --quiet {} --record {}", DPC31_CLI, file, tmp("many.trace")));
  ASSERT_EQ(r.rc, 0) << r.out;
  std::istringstream in(slurp(tmp("many.station5_spc3.trace")));
  std::string prev;
  int notes = 0;
  for (std::string l; std::getline(in, l); prev = l) {
    if (l != "# from rogue") continue;
    ++notes;
    EXPECT_TRUE(prev.starts_with("rx ") && prev.ends_with(" 10 07 02 49 52 16")) << prev;
  }
  EXPECT_EQ(notes, 1);
}

// A trace per station; each replays alone on a single chip, and is the shipped golden trace (its
// hand-check block aside).
TEST(SegmentOutputs, TracePerStationReplaysAndIsGolden) {
  ASSERT_EQ(outputs().rc, 0);
  for (const std::string st : {"station5_spc3", "station6_dpc31"}) {
    const std::string rec = tmp("two." + st + ".trace");
    const auto r = sh(fmt::format("{} replay --quiet {}", DPC31_CLI, rec));
    EXPECT_EQ(r.rc, 0) << r.out;
    const std::string golden =
        slurp(std::string(SOURCE_DIR) + "/traces/segment/two_masters." + st + ".trace");
    // The golden file: the recording with the block `# checked by hand ...` after line 1.
    std::string stripped;
    std::istringstream in(golden);
    bool in_block = false;
    int n = 0;
    for (std::string l; std::getline(in, l); ++n) {
      if (n == 1 && l.starts_with("# checked by hand")) in_block = true;
      if (in_block && l == "#") {
        in_block = false;
        continue;
      }
      if (!in_block) stripped += l + "\n";
    }
    EXPECT_EQ(slurp(rec), stripped) << st;
  }
}

TEST(SegmentOutputs, BadInputIsOneLineAndNoFile) {
  const std::string out = tmp("bad.vcd");
  auto r =
      sh(fmt::format("{} run --quiet {} --vcd {} --signals 'nosuch.*'", DPC31_CLI, kScenario, out));
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, "dpc31 run: no signal matches 'nosuch.*' (see docs/waveforms.md)\n");
  EXPECT_FALSE(fs::exists(out));
  r = sh(fmt::format("{} run --quiet {} --vcd {} --engine per-cycle", DPC31_CLI, kScenario, out));
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, fmt::format("dpc31 run: {}: --engine per-cycle: a segment runs on the event "
                               "engine\n",
                               kScenario));
  EXPECT_FALSE(fs::exists(out));
  r = sh(fmt::format("{} run --quiet {} --vcd {} --pcap {}", DPC31_CLI, kScenario, out, out));
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_FALSE(fs::exists(out));
  // The trace of station 5 would overwrite the scenario itself.
  const std::string scn = tmp("x.station5_spc3.trace");
  fs::copy_file(kScenario, scn, fs::copy_options::overwrite_existing);
  r = sh(fmt::format("{} run --quiet {} --record {}", DPC31_CLI, scn, tmp("x.trace")));
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_EQ(slurp(scn), slurp(kScenario));
}

// A station's name is at most 64 bytes (docs/scenario-format.md, vocabulary.hpp kMaxStationName).
// The longest is every output's: the VCD and FST scope `station5_NAME` compare the same in
// wavediff, tshark reads the capture whose comments carry it, --record writes
// FILE.station5_NAME.trace. One byte more is refused at its line, exit 2, nothing written (the
// audit: 17 000 bytes made a VCD wavediff refuses, 66 000 a pcapng tshark calls corrupt).
TEST(SegmentOutputs, AStationsNameIsAtMost64BytesAndEveryOutputTakesIt) {
  const std::string body = "\nstartup\n";  // the default master 2 brings station 5 up
  const std::string name(64, 'n');
  const std::string file = tmp("name64.scn");
  { std::ofstream(file) << "segment\nstation 5 profile=spc3 name=" << name << body; }
  const std::string vcd = tmp("n64.vcd"), fst = tmp("n64.fst"), pcap = tmp("n64.pcapng");
  auto r = sh(fmt::format("{} run --quiet {} --vcd {} --fst {} --pcap {} --record {}", DPC31_CLI,
                          file, vcd, fst, pcap, tmp("n64.trace")));
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(slurp(vcd).find("$scope module station5_" + name + " $end"), std::string::npos);
  EXPECT_TRUE(fs::exists(tmp("n64.station5_" + name + ".trace")));
  r = sh(fmt::format("{} wavediff {} {}", DPC31_CLI, vcd, fst));
  EXPECT_EQ(r.rc, 0) << r.out;
  // The master's requests and the station's answers, each named (docs/capture.md).
  r = testutil::run_command(fmt::format(
      "env HOME={0} XDG_CONFIG_HOME={0} tshark -n -X lua_script:{1}/lib/capture/profibus_dl.lua "
      "-r {2} -T fields -e frame.comment 2>&1",
      ::testing::TempDir(), SOURCE_DIR, pcap));
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find(", master 2, answered by " + name + "\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(", " + name + ", answer to master 2\n"), std::string::npos) << r.out;

  const std::string file65 = tmp("name65.scn");
  { std::ofstream(file65) << "segment\nstation 5 profile=spc3 name=" << name << "n" << body; }
  const std::string vcd65 = tmp("n65.vcd"), pcap65 = tmp("n65.pcapng");
  r = sh(fmt::format("{} run --quiet {} --vcd {} --pcap {}", DPC31_CLI, file65, vcd65, pcap65));
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.out, fmt::format("{}:2: a name of 65 bytes for station 5: at most 64\n", file65));
  EXPECT_FALSE(fs::exists(vcd65));
  EXPECT_FALSE(fs::exists(pcap65));
}

// The outputs finished and destroyed, the segment runs on (dpc31.Segment's close()): the
// observers they put on the line and its chips do nothing any more, and the file holds the line
// up to its time then.
// The outputs of a segment built by hand: one VCD at `path`.
dpc31::SegmentOutputOptions one_vcd(const std::string& path) {
  dpc31::wave::Options w;
  w.path = path;
  return {{w}, ""};
}

TEST(SegmentOutputs, TheSegmentRunsOnAfterItsOutputsAreGone) {
  using namespace dpc31;
  const std::string vcd = tmp("gone.vcd");
  Segment seg(1'500'000);
  auto out = std::make_unique<SegmentOutputs>(one_vcd(vcd));
  std::string e;
  ASSERT_TRUE(out->open(e)) << e;
  const std::size_t chip = seg.add_chip("station 5", ChipOptions{});
  ASSERT_TRUE(out->add_station(seg, chip, "station5", e)) << e;
  const std::size_t sender = seg.add_sender("x");
  ASSERT_TRUE(out->attach_line(seg, {5, wave::kDriverWithoutAddress}, e)) << e;
  const std::vector<std::uint8_t> req = fdl::encode(
      fdl::make_frame(5, 2, fdl::make_request_fc(fdl::Function::FDL_Status, false, false)));
  seg.send(sender, req, 1000);
  seg.flush();
  seg.align();
  out->end(seg);
  ASSERT_TRUE(out->write(e)) << e;
  out.reset();
  const std::string written = slurp(vcd);
  for (int i = 0; i < 20; ++i) {
    seg.send(sender, req, seg.cycle() + 100);
    seg.chip(chip).write(0x04, 0xFF);
  }
  seg.run_until(seg.cycle() + 100'000);
  seg.flush();
  EXPECT_EQ(slurp(vcd), written);
  EXPECT_FALSE(written.empty());
}

// Two chips whose scopes are one are refused at the second's add_station, in the scenario's
// words (docs/segment.md "Outputs"; s35 audit aMix finding 5: the VCD had one module
// station5_a_b holding both chips' signals twice). The first keeps its scope; another joins.
TEST(SegmentOutputs, ASecondStationInOneScopeIsRefused) {
  using namespace dpc31;
  const std::string vcd = tmp("scope.vcd");
  Segment seg(1'500'000);
  SegmentOutputs out(one_vcd(vcd));
  std::string e;
  ASSERT_TRUE(out.open(e)) << e;
  ASSERT_TRUE(out.add_station(seg, seg.add_chip("a/b", ChipOptions{}), station_scope(5, "a/b"), e))
      << e;
  EXPECT_FALSE(
      out.add_station(seg, seg.add_chip("a_b", ChipOptions{}), station_scope(5, "a_b"), e));
  EXPECT_EQ(e, "a second station named 'a_b' in the waveform scope of 'a/b' (station5_a_b)");
  seg.remove_last_chip();
  e.clear();
  ASSERT_TRUE(out.add_station(seg, seg.add_chip("c", ChipOptions{}), station_scope(6, "c"), e))
      << e;
  ASSERT_TRUE(out.attach_line(seg, {5, 6}, e)) << e;
  seg.run_until(1000);
  out.end(seg);
  ASSERT_TRUE(out.write(e)) << e;
  const std::string text = slurp(vcd);
  std::size_t modules = 0;
  for (std::size_t at = text.find("$scope module station5_a_b "); at != std::string::npos;
       at = text.find("$scope module station5_a_b ", at + 1))
    ++modules;
  EXPECT_EQ(modules, 1u);
  EXPECT_NE(text.find("$scope module station6_c "), std::string::npos);
}

// A station's user watchdog options refused at their line (docs/scenario-format.md, "Segments"):
// beside a firmware, and user_wd_value= on a dpc31 without user_wd=1. `dpc31 run` says the one
// line `FILE:LINE: …` and exits 2 (docs/bad-input.md), writing nothing.
TEST(SegmentOutputs, AStationsBadUserSideOptionIsExit2WithItsLine) {
  const testutil::TempDir dir;
  const std::string out = dir.file("uwd.json");
  const std::pair<const char*, const char*> cases[] = {
      {"segment\nstation 5 profile=spc3 user_wd=1 firmware=DO4\nstartup\n",
       "uwd1.scn:2: 'user_wd' configures the built-in user side; a firmware configures itself"},
      {"segment\nstation 5 profile=spc3\nstation 7 user_wd_value=100\nstartup\n",
       "uwd2.scn:3: user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog loads "
       "R_User_WD_Value only through its requests"},
  };
  int n = 0;
  for (const auto& [text, want] : cases) {
    const std::string scn = dir.write(fmt::format("uwd{}.scn", ++n), text);
    const auto r = sh(fmt::format("{} run --quiet {} --json {}", DPC31_CLI, scn, out));
    EXPECT_EQ(r.rc, 2) << r.out;
    EXPECT_EQ(r.out, fmt::format("{}/{}\n", dir.path(), want));
    EXPECT_FALSE(fs::exists(out));
  }
}

// The three-slave segment (a firmware, a VPC3+, a DPC31): every station's trace replays alone, the
// VPC3+'s last answer of the run whole in it (the run ends once the line is quiet).
TEST(SegmentOutputs, ThreeSlavesTracesReplay) {
  const std::string rec = tmp("three.trace");
  auto r = sh(fmt::format("{} run --quiet {}/traces/segment/three_slaves.scn --record {}",
                          DPC31_CLI, SOURCE_DIR, rec));
  ASSERT_EQ(r.rc, 0) << r.out;
  std::size_t traces = 0;
  for (const auto& e : fs::directory_iterator(fs::path(rec).parent_path())) {
    const std::string name = e.path().filename().string();
    if (!name.starts_with("three.station") || !name.ends_with(".trace")) continue;
    ++traces;
    r = sh(fmt::format("{} replay --quiet {}", DPC31_CLI, e.path().string()));
    EXPECT_EQ(r.rc, 0) << name << ": " << r.out;
  }
  EXPECT_EQ(traces, 3u);
  // Each heading names the station's firmware as a single chip's does (docs/trace-format.md: "#
  // firmware init (WHO): registers, buffers, Start_SPC3"; MAC_Start on the DPC31).
  for (const auto& [st, who, start] : {std::tuple{"station5_spc3", "DO4", "Start_SPC3"},
                                       {"station6_vpc3plus", "CNT2", "Start_SPC3"},
                                       {"station7_dpc31", "DO4", "MAC_Start"}}) {
    const std::string want =
        fmt::format("# firmware init (the host firmware {}): registers, buffers, {}", who, start);
    EXPECT_NE(slurp(tmp(fmt::format("three.{}.trace", st))).find("\n" + want + "\n"),
              std::string::npos)
        << st << ": no line " << want;
  }
}

// A station's heading names its firmware by the descriptor's name, as a single chip's trace does,
// whatever the scenario's word (a plug-in's path, another case), and says `user side: …` for one
// that never started its chip (docs/trace-format.md: "the chip not started yet: `# user side:
// WHO; …`"; bad_plugin.c GLOBALS, named BAD: an init that only writes a port).
TEST(SegmentOutputs, StationHeadingsNameTheFirmwareAndWhetherItStarted) {
  const std::string scn = tmp("heads.scn");
  {
    std::ofstream out(scn);
    out << "segment baud=1500000\n"
        << "station 5 name=a profile=spc3 firmware=" << PLUGIN_DO4 << "\n"
        << "station 6 name=b profile=spc3 firmware=do4\n"
        << "station 7 name=c profile=spc3 firmware=" << BAD_PLUGIN_GLOBALS << "\n"
        << "master 2 slaves=5,6\n\nstartup\n";
  }
  const auto r =
      sh(fmt::format("{} run --quiet {} --record {}", DPC31_CLI, scn, tmp("heads.trace")));
  ASSERT_EQ(r.rc, 0) << r.out;
  for (const auto& [st, want] :
       {std::pair{"station5_a",
                  "# firmware init (the host firmware DO4): registers, buffers, "
                  "Start_SPC3"},
        {"station6_b", "# firmware init (the host firmware DO4): registers, buffers, Start_SPC3"},
        {"station7_c", "# user side: the host firmware BAD"}}) {
    const std::string trace = slurp(tmp(fmt::format("heads.{}.trace", st)));
    EXPECT_NE(trace.find(fmt::format("\n{}\n", want)), std::string::npos)
        << st << ": no line " << want << "\n"
        << trace.substr(0, 600);
  }
}

// The log of a segment's run in cycle order (docs/segment.md, "The log"): a telegram of the line
// ("[cycle S] station: bytes", stamped at its first start bit S) is told once the line stayed idle
// past its end E = S + 11 T per character, before anything the chips did after E. Until the
// seventeenth session a chip's state change up to a round later could come first.
TEST(SegmentOutputs, ATelegramOfTheLineIsLoggedBeforeWhatComesAfterItsEnd) {
  for (const auto& [scn, t] : {std::pair<std::string, std::uint64_t>{"three_slaves", kT},
                               {"two_masters", kT},
                               {"three_slaves_12m", 4}}) {
    const auto r =
        sh(fmt::format("cd {} && {} run traces/segment/{}.scn", SOURCE_DIR, DPC31_CLI, scn));
    ASSERT_EQ(r.rc, 0) << r.out;
    std::istringstream in(r.out);
    std::uint64_t latest = 0;  // the latest stamp logged so far
    std::size_t telegrams = 0;
    for (std::string line; std::getline(in, line);) {
      std::uint64_t cycle = 0;
      char name[64] = {};
      int used = 0;
      if (std::sscanf(line.c_str(), "[cycle %" SCNu64 "] %63[^:]: %n", &cycle, name, &used) < 2)
        continue;
      const std::string rest = line.substr(static_cast<std::size_t>(used));
      const bool bytes = !rest.empty() && rest.size() % 3 == 2 &&
                         std::all_of(rest.begin(), rest.end(), [](char c) {
                           return c == ' ' || std::isxdigit(static_cast<unsigned char>(c));
                         });
      if (bytes) {
        ++telegrams;
        const std::uint64_t end = cycle + (rest.size() + 1) / 3 * 11 * t;
        EXPECT_LE(latest, end) << scn << ": '" << line << "' after a line stamped " << latest;
      }
      latest = std::max(latest, cycle);
    }
    EXPECT_GT(telegrams, 100u) << scn;
  }
}

// docs/segment.md "The log": a telegram's line (stamped at its first start bit) and its checks'
// lines come once the line stayed idle past its end, a step that ends there prints them before the
// next step's lines, and only a visit's `master N: the token: ...` line comes later: no line after
// a step's heading is stamped before it. The audit's case: two_masters.scn's line 34 sends the
// rogue's second FDL_Status 2 T after its first, into which the SPC3's answer to the first
// collides; the step ends at the rogue's telegram's end while the SPC3 still drives. Until the
// thirtieth session that telegram and its `bus: short_tsyn` line came after line 35's heading.
TEST(SegmentOutputs, NoLineButTheTokensComesAfterALaterStepsHeading) {
  const auto r =
      sh(fmt::format("cd {} && {} run traces/segment/two_masters.scn", SOURCE_DIR, DPC31_CLI));
  ASSERT_EQ(r.rc, 0) << r.out;
  std::istringstream in(r.out);
  std::uint64_t heading = 0;
  std::string heading_line;
  std::size_t headings = 0;
  for (std::string line; std::getline(in, line);) {
    std::uint64_t cycle = 0;
    int used = 0;
    if (std::sscanf(line.c_str(), "[cycle %" SCNu64 "] %n", &cycle, &used) < 1) continue;
    if (line.find(": the token: ") != std::string::npos) continue;
    EXPECT_LE(heading, cycle) << "'" << line << "' after '" << heading_line << "'";
    if (line.compare(static_cast<std::size_t>(used), 5, "line ") == 0) {
      ++headings;
      heading = cycle;
      heading_line = line;
    }
  }
  EXPECT_GT(headings, 10u);
  const std::size_t tel = r.out.find("] rogue: 10 07 02 49 52 16");
  const std::size_t tsyn = r.out.find("] bus: short_tsyn: rogue sent after 2 bit times");
  const std::size_t step = r.out.find("] line 35: run 1ms");
  ASSERT_NE(step, std::string::npos);
  EXPECT_LT(tsyn, tel);
  EXPECT_LT(tel, step);
}

// The case a user found (the twenty-third session): three_slaves.scn's `cycle 40 skip=7` ends at
// the end of its last answer's stop bit, the VPC3+'s (17 characters: E = its start + 17 x 11 T,
// docs/timing.md, T = 32 clocks at 1.5 Mbaud), and line 48's expect looks there
// (docs/scenario-format.md: `cycle` ends on a quiet line, a check moves no time). The answer's line
// comes right before line 48's; until then it came after line 57's `ok`. The same at `cycle 3`'s
// end: the DPC31's answer (10 characters) right before line 41. The answers are SD2 DL telegrams
// to master 2 (FC 08h) with each GSD's inputs, all 0: DO4's one byte (Cfg 10h), CNT2's eight (Cfg
// 17h), FCS = 02h + SA + 08h.
TEST(SegmentOutputs, AStepsLastAnswerComesBeforeItsExpects) {
  const auto r =
      sh(fmt::format("cd {} && {} run traces/segment/three_slaves.scn", SOURCE_DIR, DPC31_CLI));
  ASSERT_EQ(r.rc, 0) << r.out;
  std::vector<std::string> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (const auto& [expect, answer, chars] :
       {std::tuple<std::string, std::string, std::uint64_t>{
            "line 41: expect state 5", "dpc31: 68 04 04 68 02 07 08 00 11 16", 10},
        {"line 48: expect watchdog_expired",
         "vpc3plus: 68 0B 0B 68 02 06 08 00 00 00 00 00 00 00 00 10 16", 17}}) {
    // A copy: clang before 16 cannot capture a structured binding.
    const auto at = std::find_if(lines.begin(), lines.end(), [want = expect](const std::string& l) {
      return l.find(want) != std::string::npos;
    });
    ASSERT_NE(at, lines.end()) << expect;
    ASSERT_NE(at, lines.begin()) << expect;
    const std::string& before = *(at - 1);
    ASSERT_EQ(before.substr(19), answer) << expect;
    const std::uint64_t start = std::stoull(before.substr(7, 10));
    EXPECT_EQ(std::stoull(at->substr(7, 10)), start + chars * 11 * kT) << *at;
  }
}

// sigrok-cli's UART decoder (8E1) reads the logic-analyser form of a window (the SPC3's start-up
// answers and master 3's first exchange with the DPC31, cycles 2 885 000 to 2 936 000): `line`
// gives exactly the bytes of every telegram of the full waveform's line in it, and the DPC31's
// `station6_dpc31_txd` exactly its answer.
TEST(SegmentOutputs, SigrokDecodesTheLine) {
  constexpr std::uint64_t kFrom = 2'885'000;
  constexpr std::uint64_t kTo = 2'936'000;
  const std::string la = tmp("window-la.vcd");
  auto r = sh(fmt::format("{} run --quiet {} --la-vcd {} --from {} --to {}", DPC31_CLI, kScenario,
                          la, kFrom, kTo));
  ASSERT_EQ(r.rc, 0) << r.out;
  const Vcd v(slurp(outputs().vcd));
  std::string line;
  std::string dpc31;
  for (const OnLine& run : line_runs(v)) {
    if (run.start < kFrom || run.end > kTo) continue;
    for (const std::uint8_t b : run.bytes) {
      line += fmt::format("{:02X}\n", b);
      if (run.driver == 6) dpc31 += fmt::format("{:02X}\n", b);
    }
  }
  ASSERT_FALSE(dpc31.empty());
  const auto decode = [&](const char* pin) {
    return testutil::run_command(
        fmt::format("sigrok-cli -I vcd -i {} -P uart:rx={}:baudrate=1500000:parity=even:format=hex "
                    "-A uart=rx-data 2>/dev/null | sed 's/^.* //' | tr a-f A-F",
                    la, pin));
  };
  r = decode("line");
  ASSERT_EQ(r.rc, 0);
  EXPECT_EQ(r.out, line);
  EXPECT_EQ(decode("station6_dpc31_txd").out, dpc31);
}
