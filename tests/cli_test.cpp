// The dpc31 command line: help, the register map in every format, the demo.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dpc31/regdesc.hpp"
#include "run_command.hpp"
#include "test_files.hpp"

namespace {

using Result = testutil::CommandResult;

Result run(const std::string& args) {
  return testutil::run_command(std::string(DPC31_CLI) + " " + args + " 2>/dev/null");
}

using testutil::slurp;

}  // namespace

TEST(Cli, HelpListsSubcommands) {
  const Result r = run("--help");
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find("demo"), std::string::npos);
  EXPECT_NE(r.out.find("regs"), std::string::npos);
}

TEST(Cli, BadArgumentsExit2) {
  EXPECT_EQ(run("regs --profile pentium").rc, 2);
  EXPECT_EQ(run("regs --format yaml").rc, 2);
  EXPECT_EQ(run("nosuchcommand").rc, 2);
  EXPECT_EQ(run("").rc, 2);
}

TEST(Cli, RegsJsonIsValidAndComplete) {
  for (dpc31::Profile p : dpc31::kAllProfiles) {
    const auto& desc = dpc31::profile_desc(p);
    const Result r = run("regs --profile " + std::string(desc.name) + " --format json");
    ASSERT_EQ(r.rc, 0);
    const nlohmann::json j = nlohmann::json::parse(r.out);  // throws on invalid JSON
    ASSERT_TRUE(j.contains("registers"));
    ASSERT_EQ(j["registers"].size(), desc.regs.size());
    for (std::size_t i = 0; i < desc.regs.size(); ++i) {
      EXPECT_EQ(j["registers"][i]["name"].get<std::string>(), desc.regs[i].name);
    }
  }
}

// The compiled-in tables print exactly the checked-in generated files.
TEST(Cli, RegsReproducesTheCheckedInOutputs) {
  EXPECT_EQ(run("regs --profile all --format c").out,
            slurp(std::string(SOURCE_DIR) + "/include/dpc31/dpc31_regs.h"));
  EXPECT_EQ(run("regs --profile all --format verilog").out,
            slurp(std::string(SOURCE_DIR) + "/rtl/dpc31_regs.vh"));
  EXPECT_EQ(run("regs --profile all --format markdown").out,
            slurp(std::string(SOURCE_DIR) + "/docs/registers.md"));
}

// The Verilog include names each register's access policies as masks (s34 audit, finding 12),
// values from the register tables of docs/registers.md: the DPC31's Mode_Reg1_S has its requests
// IGN (5 Res_User_WD, 3 User_Leave_Master, 2 Go_Offline, 0 Start_SPC3: 2Dh), W1S 4 and 1 (12h),
// EOI a pulse (02h), 7:6 reserved (C0h); the SPC3's Int_Ack_Reg W1C 13, 12, 9, 8, 4..0 (331Fh),
// IGN New_Prm_Data / New_Cfg_Data (0C00h), reserved 15:14 and 7:5 (C0E0h); no RO mask (only
// the policies a register has).
TEST(Cli, RegsVerilogCarriesThePolicyMasks) {
  const std::string vh = run("regs --profile all --format verilog").out;
  const auto value = [&vh](const std::string& name) {
    const std::size_t at = vh.find("`define " + name + " ");
    if (at == std::string::npos) return std::string("(missing)");
    const std::string line = vh.substr(at, vh.find('\n', at) - at);
    return line.substr(line.find_last_of(' ') + 1);
  };
  const std::pair<const char*, const char*> want[] = {
      {"DPC31_Mode_Reg1_S_IGN", "8'h2D"},    {"DPC31_Mode_Reg1_S_W1S", "8'h12"},
      {"DPC31_Mode_Reg1_S_PULSE", "8'h02"},  {"DPC31_Mode_Reg1_S_RSVD", "8'hC0"},
      {"SPC3_Int_Ack_Reg_W1C", "16'h331F"},  {"SPC3_Int_Ack_Reg_IGN", "16'h0C00"},
      {"SPC3_Int_Ack_Reg_RSVD", "16'hC0E0"}, {"SPC3_Int_Ack_Reg_RO", "(missing)"}};
  for (const auto& [name, v] : want) EXPECT_EQ(value(name), v) << name;
}

TEST(Cli, DemoRunsOnEveryProfile) {
  for (const char* p : {"spc3", "vpc3plus", "dpc31"}) {
    const std::string dir = testutil::scratch() + "demo-" + p;
    const Result r = run(std::string("demo --profile ") + p + " --out-dir " + dir);
    EXPECT_EQ(r.rc, 0) << p;
    // DO4 through the pulled cable: OSP after the watchdog, normal again after recovery; the
    // table of output changes and where the files went.
    EXPECT_NE(r.out.find("What DO4's outputs did"), std::string::npos) << p;
    EXPECT_NE(r.out.find("modul_ok = 0"), std::string::npos) << p;
    EXPECT_NE(r.out.find("outputs = 1010"), std::string::npos) << p;
    EXPECT_NE(r.out.find("expects passed 5, failed 0"), std::string::npos) << p;
    EXPECT_NE(r.out.find("waveform (VCD): " + dir + "/dpc31-demo.vcd"), std::string::npos) << p;
    EXPECT_FALSE(slurp(dir + "/dpc31-demo.vcd").empty()) << p;
    // The second waveform, for logic-analyser tools (decoded by sigrok: Waveform.sigrok_demo).
    EXPECT_NE(slurp(dir + "/dpc31-demo-la.vcd").find("$timescale 10ns $end"), std::string::npos)
        << p;
    EXPECT_FALSE(slurp(dir + "/dpc31-demo.pcapng").empty()) << p;
    EXPECT_NE(r.out.find("X/INT -> low (active)"), std::string::npos) << p;
    // The register session really starts the chip (the start clears the outputs: DX_Out,
    // docs/timing.md) and runs its 1 ms user timer, whose masked tick IRR latches; the DPC31 is
    // started and stopped through its Instruction_Queue (MAC_Start, MAC_Stop; docs/dpc31.md),
    // since its Mode_Reg1 has no start bit.
    EXPECT_NE(r.out.find("IR = 2000h (DX_Out = bit 13)"), std::string::npos) << p;
    EXPECT_NE(r.out.find("IRR = 0010h, IR = 0000h"), std::string::npos) << p;
    EXPECT_EQ(r.out.find("chip: request MAC_Start") != std::string::npos, std::string(p) == "dpc31")
        << p;
    EXPECT_EQ(r.out.find("chip: request MAC_Stop") != std::string::npos, std::string(p) == "dpc31")
        << p;
    EXPECT_NE(r.out.find("User_Prm_Data_Okay = 00h"), std::string::npos) << p;
    EXPECT_NE(r.out.find("dp_state Wait_Cfg -> Data_Exchange"), std::string::npos) << p;
    EXPECT_NE(r.out.find("wd_state DP_Control -> Baud_Control"), std::string::npos) << p;
  }
}

// The DP session with another firmware, here DO4 loaded as a plug-in: configured from its GSD
// defaults, outputs 05 05, through the pulled cable (DP watchdog) and the master's restart, back in
// Data_Exchange; the table lists its port writes. A firmware that does not load: one line, exit
// 2, and no output directory made.
TEST(Cli, DemoRunsAFirmwarePlugin) {
  const std::string dir = testutil::scratch() + "demo-plugin";
  const Result r = run(std::string("demo --firmware ") + PLUGIN_DO4 + " --out-dir " + dir);
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find(std::string("the slave runs the firmware ") + PLUGIN_DO4),
            std::string::npos);
  EXPECT_NE(r.out.find("What the firmware's ports did"), std::string::npos);
  // 05 01 normal operation (OSPValid), then OSP (ModulOK 0, outputs retained) after the watchdog.
  EXPECT_NE(r.out.find("outputs = 0x05"), std::string::npos);
  EXPECT_NE(r.out.find("modul_ok = 0x01"), std::string::npos);
  EXPECT_NE(r.out.find("modul_ok = 0x00"), std::string::npos);
  EXPECT_NE(r.out.find("wd_state DP_Control -> Baud_Control"), std::string::npos);
  EXPECT_NE(r.out.find("expects passed 1, failed 0"), std::string::npos);
  EXPECT_FALSE(slurp(dir + "/dpc31-demo.vcd").empty());

  const std::string none = testutil::scratch() + "demo-none";
  const Result bad = testutil::run_command(
      std::string(DPC31_CLI) + " demo --firmware ./nosuch.so --out-dir " + none + " 2>&1");
  EXPECT_EQ(bad.rc, 2);
  EXPECT_EQ(bad.out.rfind("dpc31 demo: cannot load firmware plug-in: ./nosuch.so", 0), 0u)
      << bad.out;
  EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(none));
}

TEST(Cli, RunWritesWaveformsAndCapture) {
  const std::string dir = testutil::scratch();
  const std::string scn = std::string(SOURCE_DIR) + "/traces/startup_dpc31_1m5.scn";
  const Result r = run("run " + scn + " --quiet --vcd " + dir + "r.vcd --fst " + dir +
                       "r.fst --pcap " + dir + "r.pcapng --signals 'pins.*,state.dp_state'");
  ASSERT_EQ(r.rc, 0);
  const std::string vcd = slurp(dir + "r.vcd");
  EXPECT_NE(vcd.find("$var wire 1 ! rxd $end"), std::string::npos);
  EXPECT_NE(vcd.find("dp_state"), std::string::npos);
  EXPECT_EQ(vcd.find("irr"), std::string::npos);  // only what was asked for
  EXPECT_FALSE(slurp(dir + "r.fst").empty());
  const std::string pcap = slurp(dir + "r.pcapng");
  ASSERT_GE(pcap.size(), 28u);
  EXPECT_EQ(pcap.substr(0, 4), std::string("\x0A\x0D\x0D\x0A", 4));  // Section Header Block
  // Bad input: one line, exit 2, nothing written.
  EXPECT_EQ(run("run " + scn + " --vcd " + dir + "bad.vcd --signals nosuch").rc, 2);
  EXPECT_TRUE(slurp(dir + "bad.vcd").empty());
  EXPECT_EQ(run("run " + scn + " --vcd " + dir + "bad.vcd --timescale 3ns").rc, 2);
}

// The logic-analyser form (docs/waveforms.md): 1-bit signals in one scope, 10 ns unless
// --timescale says otherwise, as a second file (--la-vcd) or as the --vcd itself (--flat).
TEST(Cli, RunWritesTheLogicAnalyserForm) {
  const std::string dir = testutil::scratch();
  const std::string scn = std::string(SOURCE_DIR) + "/traces/startup_dpc31_1m5.scn";
  ASSERT_EQ(run("run " + scn + " --quiet --vcd " + dir + "full.vcd --la-vcd " + dir + "la.vcd").rc,
            0);
  const std::string full = slurp(dir + "full.vcd");
  const std::string la = slurp(dir + "la.vcd");
  EXPECT_NE(full.find("$timescale 1ps $end"), std::string::npos);
  EXPECT_NE(full.find("$var wire 16 + irr $end"), std::string::npos);
  EXPECT_NE(la.find("$timescale 10ns $end\n$scope module dpc31 $end\n$var wire 1 ! rxd $end\n"
                    "$var wire 1 \" txd $end\n$var wire 1 # x_int $end\n$var wire 1 / pb3 $end\n"
                    "$var wire 1 $ rd $end\n$var wire 1 % wr $end\n$upscope $end\n"),
            std::string::npos)
      << la.substr(0, 400);
  ASSERT_EQ(run("run " + scn + " --quiet --vcd " + dir + "flat.vcd --flat").rc, 0);
  EXPECT_EQ(slurp(dir + "flat.vcd"), la);
  ASSERT_EQ(run("run " + scn + " --quiet --la-vcd " + dir + "la1.vcd --timescale 1ns").rc, 0);
  EXPECT_NE(slurp(dir + "la1.vcd").find("$timescale 1ns $end"), std::string::npos);
}

// The PulseView session (docs/waveforms.md, "PulseView") takes the scenario's rate: 12 000 000 =
// B71B00h, int64 little-endian 00 1B B7 00 00 00 00 00 in QSettings' escapes: \0, \x1b, \xb7,
// five \0. A flat --vcd gets the same session as --la-vcd. A segment's decodes its line as RX,
// without TX; one whose --signals leave the line out is refused, nothing written.
TEST(Cli, RunWritesAPulseViewSessionForTheRunsRate) {
  const std::string dir = testutil::scratch();
  // The session `run SCN ARGS --pvs NAME.pvs` writes ("" if the run failed).
  const auto session = [&dir](const std::string& scn, const std::string& args,
                              const std::string& name) {
    const Result r = run("run " + std::string(SOURCE_DIR) + "/traces/" + scn + " --quiet " + args +
                         " --pvs " + dir + name + ".pvs");
    return r.rc == 0 ? slurp(dir + name + ".pvs") : std::string();
  };
  const std::string pvs = session("startup_dpc31_12m.scn", "--la-vcd " + dir + "12m.vcd", "12m");
  EXPECT_NE(pvs.find("decoder0\\option0\\name=baudrate\ndecoder0\\option0\\type=x\n"
                     "decoder0\\option0\\value=@ByteArray(\\0\\x1b\\xb7\\0\\0\\0\\0\\0)\n"),
            std::string::npos)
      << pvs;
  EXPECT_NE(pvs.find("channel0\\assigned_signal_name=rxd\n"), std::string::npos) << pvs;
  EXPECT_NE(pvs.find("channel1\\assigned_signal_name=txd\n"), std::string::npos) << pvs;
  EXPECT_EQ(session("startup_dpc31_12m.scn", "--vcd " + dir + "12m_flat.vcd --flat", "flat"), pvs);
  const std::string seg =
      session("segment/two_masters.scn", "--la-vcd " + dir + "seg.vcd", "segment");
  EXPECT_NE(seg.find("channels=2\nchannel0\\assigned_signal_name=line\n"
                     "channel0\\initial_pin_state=2\nchannel1\\initial_pin_state=2\n"),
            std::string::npos)
      << seg;
  const Result none = testutil::run_command(
      std::string(DPC31_CLI) + " run " + SOURCE_DIR + "/traces/segment/two_masters.scn --quiet " +
      "--la-vcd " + dir + "none.vcd --signals 'pins.*' --pvs " + dir + "none.pvs 2>&1");
  EXPECT_EQ(none.rc, 2);
  EXPECT_EQ(none.out, "dpc31 run: " + dir +
                          "none.pvs: a PulseView session decodes pins.rxd or pins.txd (a "
                          "segment's line.level), and --signals leaves them out of " +
                          dir + "none.vcd\n")
      << none.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "none.pvs"));
  EXPECT_FALSE(std::filesystem::exists(dir + "none.vcd"));
}

// `dpc31 bench --quick`: every row of the table is there and well-formed. The timings are not
// checked (speed is measured by the benchmarks, not asserted by tests).
TEST(CliBench, QuickPrintsEveryRowWellFormed) {
  const std::string json_path = testutil::scratch() + "dpc31_bench_quick.json";
  const Result r = run("bench --quick --json " + json_path);
  ASSERT_EQ(r.rc, 0) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  std::vector<std::vector<std::string>> rows;
  while (std::getline(lines, line)) {
    if (line == "|---|---|---|---|---|") continue;
    ASSERT_EQ(line.rfind("| ", 0), 0u) << "not a table line: " << line;
    std::vector<std::string> cells;
    std::size_t at = 1;
    for (std::size_t bar = line.find(" |", at); bar != std::string::npos;
         bar = line.find(" |", at)) {
      cells.push_back(line.substr(at + 1, bar - at - 1));
      at = bar + 2;
    }
    ASSERT_EQ(cells.size(), 5u) << line;
    rows.push_back(cells);
  }
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0], (std::vector<std::string>{"item", "what", "measured", "target", "result"}));
  rows.erase(rows.begin());
  // Rows per item: a (six accesses), b, b' (block copies, byte by byte), c, d, e (ratio,
  // lockstep), f (MB/s and RSS on a pair of the emulator's VCD files and on a generated pair), g
  // (pipelined over TCP, one in flight over the Unix socket and over TCP, each with the server's
  // own cost per command and the rest reported beside it; one round trip beside a flood), i
  // (tracing), j (the 80C32 core, docs/cpu.md), k (DPV1 Reads), l (a segment), m (DO4 on the
  // 80C32), h (the fresh build: not run without --build, last).
  std::vector<std::string> items = {"a", "a", "a", "a", "a", "a", "b", "b'", "c", "d",
                                    "e", "e", "f", "f", "f", "f", "g", "g",  "g", "g",
                                    "g", "g", "g", "g", "g", "i", "j", "k"};
  // l: one DP cycle over a segment of 1, 2, 4, 8, 16, 32 slaves at 1.5 and 12 Mbaud (issue 30);
  // only the 32-slave rows have targets.
  items.insert(items.end(), 12, "l");
  items.push_back("m");  // a whole DO4 session on the 80C32 (docs/cpu.md)
  items.push_back("h");
  ASSERT_EQ(rows.size(), items.size()) << r.out;
  int reported = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& c = rows[i];
    EXPECT_EQ(c[0], items[i]);
    EXPECT_FALSE(c[1].empty());
    EXPECT_TRUE(!c[2].empty() && c[2].find("error") == std::string::npos) << c[2];
    if (c[3] == "—") {  // a breakdown of the row above it, with no target of its own
      EXPECT_EQ(c[4], "reported");
      ++reported;
      continue;
    }
    EXPECT_TRUE(c[3].rfind("≤ ", 0) == 0 || c[3].rfind("≥ ", 0) == 0 || c[3].rfind("< ", 0) == 0)
        << c[3];
    if (items[i] == "h") {  // the build is timed only when asked for (--build SOURCE_DIR)
      EXPECT_EQ(c[2], "—");
      EXPECT_EQ(c[3], "≤ 5 min");
      EXPECT_EQ(c[4].rfind("not run: dpc31 bench --build SOURCE_DIR", 0), 0u) << c[4];
      continue;
    }
    EXPECT_TRUE(c[4].rfind("met", 0) == 0 || c[4].rfind("missed by ", 0) == 0) << c[4];
  }
  EXPECT_EQ(reported, 15);
  const auto j = nlohmann::json::parse(slurp(json_path));
  ASSERT_EQ(j["rows"].size(), items.size());
  for (const auto& row : j["rows"]) {
    if (row["item"] == "h") {
      EXPECT_FALSE(row["measured"].get<bool>()) << row.dump();
      EXPECT_TRUE(row["not_run"].is_string()) << row.dump();
      EXPECT_EQ(row["target"], 5) << row.dump();
      continue;
    }
    EXPECT_TRUE(row["measured"].get<bool>()) << row.dump();
    EXPECT_TRUE(row["value"].is_number()) << row.dump();
  }
  std::remove(json_path.c_str());
}

// `--items d,i`: only those rows are measured, every other one reads "not run: not in --items"
// (also in the JSON), and that is exit 0.
TEST(CliBench, ItemsRunsOnlyThose) {
  const std::string json_path = testutil::scratch() + "dpc31_bench_items.json";
  const Result r = run("bench --quick --items d,i --json " + json_path);
  ASSERT_EQ(r.rc, 0) << r.out;
  const auto j = nlohmann::json::parse(slurp(json_path));
  // Every row of docs/performance.md, rows j (the 80C32), k (DPV1), the twelve of row l (a
  // segment) and m (DO4 on the 80C32) included.
  ASSERT_EQ(j["rows"].size(), 42u);
  int measured = 0;
  for (const auto& row : j["rows"]) {
    if (row["item"] == "d" || row["item"] == "i") {
      EXPECT_TRUE(row["measured"].get<bool>()) << row.dump();
      ++measured;
    } else {
      EXPECT_EQ(row["not_run"], "not in --items") << row.dump();
    }
  }
  EXPECT_EQ(measured, 2);
  EXPECT_NE(r.out.find("| d | DP watchdog, TWD = 650 s, expiring (wall time) | "),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("| — | ≤ 3 ns | not run: not in --items |"), std::string::npos) << r.out;
  std::remove(json_path.c_str());
}

// Row h with --build: the wall time of SOURCE_DIR/setup.sh, run with ccache off and
// DPC31_BUILD_DIR a fresh directory (removed after); a setup.sh that fails is the row's error with
// its last line, and exit 1 (bench.hpp). Stand-in setup.sh scripts, not a real 5-minute build.
TEST(CliBench, BuildRowTimesSetupShOrReportsItsLastLine) {
  namespace fs = std::filesystem;
  const fs::path src = fs::path(testutil::scratch()) / "bench-build-src";
  fs::remove_all(src);
  fs::create_directories(src);
  const auto script = [&](const std::string& body) {
    std::ofstream(src / "setup.sh") << "#!/bin/sh\n" << body;
    fs::permissions(src / "setup.sh", fs::perms::owner_all);
  };
  const std::string fast = "bench --min-time 0.01 --repetitions 1 --wavediff-mb 1 --build ";
  // Writes what it was given into the source tree, which outlives the run.
  script("echo \"$CCACHE_DISABLE $DPC31_BUILD_DIR\" > \"$(dirname \"$0\")/seen\"\n");
  Result r = run(fast + src.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  const std::size_t h = r.out.find("| h | ");
  ASSERT_NE(h, std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| ≤ 5 min | met", h), std::string::npos) << r.out.substr(h);
  const std::string seen = slurp((src / "seen").string());
  ASSERT_EQ(seen.rfind("1 ", 0), 0u) << seen;
  const fs::path build_dir = seen.substr(2, seen.size() - 3);
  EXPECT_NE(build_dir.string().find("dpc31-bench-build-"), std::string::npos) << build_dir;
  EXPECT_FALSE(fs::exists(build_dir.parent_path())) << "the temporary directory is left";
  script("echo building >&2\necho 'cc: fatal error: boom' >&2\nexit 3\n");
  r = run(fast + src.string());
  EXPECT_EQ(r.rc, 1) << r.out;
  EXPECT_NE(r.out.find("| h | fresh build: ./setup.sh with every package present, ccache off "
                       "(wall time) | error: setup.sh exited with 3: cc: fatal error: boom |"),
            std::string::npos)
      << r.out;
  fs::remove_all(src);
}

TEST(CliBench, BadArgumentsExit2WithOneLine) {
  // --build: a directory with a setup.sh (row h), and no smoke test of a 5-minute build.
  for (const char* args :
       {"bench --min-time 0", "bench --quick --wavediff-mb 5",
        "bench --bench /nonexistent/dpc31_bench", "bench extra", "bench --build /nonexistent",
        "bench --build /", "bench --quick --build " SOURCE_DIR, "bench --quick --items z",
        "bench --quick --items f,x"}) {
    const Result r = testutil::run_command(std::string(DPC31_CLI) + " " + args + " 2>&1");
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << args << ": " << r.out;
  }
}

// Issue 16: `dpc31 regs --profile dpc31` shows the parameter cells and both queues at their
// places, each with its origin (documented / modelled) and its source (the manual's page).
TEST(Cli, RegsShowsTheDpc31QueuesWithTheirOrigin) {
  const Result r = run("regs --profile dpc31");
  ASSERT_EQ(r.rc, 0) << r.out;
  for (const char* line : {"0x086A  0x086A  InstQ_Base", "0x086C  0x086C  InstQ_Wr",
                           "0x0870  0x0870  IndQ_Wr", "0x0871  0x0871  IndQ_Rd"}) {
    const std::size_t at = r.out.find(line);
    ASSERT_NE(at, std::string::npos) << line;
    const std::string row = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NE(row.find("modelled"), std::string::npos) << row;
    EXPECT_NE(row.find("DPC31 p.22"), std::string::npos) << row;
  }
  // p.12: the Param Register and the status register are parameter cells too (places modelled).
  for (const char* line : {"0x0872  0x0872  Param_Reg", "0x0874  -       Status_Reg"}) {
    const std::size_t at = r.out.find(line);
    ASSERT_NE(at, std::string::npos) << line;
    const std::string row = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NE(row.find("modelled"), std::string::npos) << row;
    EXPECT_NE(row.find("DPC31 p.12"), std::string::npos) << row;
  }
  EXPECT_EQ(r.out.find("0x0004  -       Status_Reg"), std::string::npos);
}

namespace {

// The lines of `out` from the demo section whose title starts with `title` to the next section.
std::string demo_section(const std::string& out, const std::string& title) {
  const std::size_t at = out.find("\n# " + title);
  if (at == std::string::npos) return {};
  const std::size_t end = out.find("\n\n#", at + 1);
  return out.substr(at + 1, end == std::string::npos ? std::string::npos : end - at);
}

// The demo prints every bus access it makes, back to back from cycle 0.
std::uint64_t accesses(const std::string& text) {
  std::uint64_t n = 0;
  for (std::size_t at = text.find("] "); at != std::string::npos; at = text.find("] ", at + 1)) {
    n += text.compare(at, 8, "] write ") == 0 || text.compare(at, 8, "] read  ") == 0;
  }
  return n;
}

// A demo line as the demo prints it: "[cycle      NNN] TEXT".
std::string at_cycle(std::uint64_t cycle, const std::string& text) {
  std::string c = std::to_string(cycle);
  return "[cycle " + std::string(c.size() < 8 ? 8 - c.size() : 0, ' ') + c + "] " + text + "\n";
}

// docs/timing.md, "Bus accesses": 4 clocks each, one after the other; "Timers": the first
// User_Timer_Clock at the start's cycle s + P, P = ceil(1 ms x 48 MHz).
constexpr std::uint64_t kAccess = 4;
constexpr std::uint64_t kUserTimerPeriod = 48'000;

}  // namespace

// a22 finding 2: the demo waits for the real first User_Timer_Clock (start + 1 ms, not 1 ms after
// cycle 0), shows X/INT going active at its cycle, reads IR in the ISR, acknowledges and EOIs.
// Register addresses, IR's bit 4 and the EOI write (02h to 08h): chip-facts.md; Motorola swaps
// the byte lanes (docs/timing.md "Bus accesses"); X/INT low-active with INT_Pol 0, active in the
// cycle the event latches, inactive when the acknowledge completes (docs/timing.md "Interrupt
// line").
TEST(CliDemo, WaitsForTheFirstUserTimerTickAndAcknowledgesIt) {
  struct Case {
    const char* args;
    const char* ir_low;  // the address of Int_Reg / Int_Ack_Reg bits 7..0, then 15..8
    const char* ir_high;
  };
  for (const Case& c : {Case{"--profile dpc31", "0x0002", "0x0003"},
                        Case{"--profile spc3 --bus motorola", "0x0003", "0x0002"}}) {
    const std::string dir = testutil::scratch() + "demo-utc";
    const Result r = run(std::string("demo ") + c.args + " --out-dir " + dir);
    ASSERT_EQ(r.rc, 0) << c.args;
    // The start is the last access of the first section; the ISR of DX_Out follows.
    const std::string init = demo_section(r.out, "Initialise as a driver does");
    const std::string isr = demo_section(r.out, "ISR: read IR, fetch the (cleared) outputs");
    ASSERT_FALSE(init.empty() || isr.empty()) << r.out;
    const std::uint64_t start = kAccess * accesses(init);
    const std::uint64_t waits = start + kAccess * accesses(isr);
    const std::uint64_t tick = start + kUserTimerPeriod;
    const std::string want =
        "# Wait for the 1 ms User_Timer_Clock (first tick at the start's cycle " +
        std::to_string(start) + " + 48000); ISR: read IR, acknowledge it, EOI\n" +
        at_cycle(waits, "step  " + std::to_string(tick - waits) +
                            " cycles: until the first user timer tick") +
        at_cycle(tick, "  X/INT -> low (active)") +
        at_cycle(tick + 4, std::string("read  ") + c.ir_low + " -> 10h  Int_Reg bits 7..0") +
        at_cycle(tick + 8, std::string("read  ") + c.ir_high + " -> 00h  Int_Reg bits 15..8") +
        "                   IR = 0010h (User_Timer_Clock = bit 4)\n" +
        at_cycle(tick + 12, "  X/INT -> high (inactive)") +
        at_cycle(tick + 12, std::string("write ") + c.ir_low + " <- 10h  Int_Ack_Reg bits 7..0") +
        at_cycle(tick + 16, std::string("write ") + c.ir_high + " <- 00h  Int_Ack_Reg bits 15..8") +
        at_cycle(tick + 20, "write 0x0008 <- 02h  Mode_Reg1_S");
    EXPECT_EQ(demo_section(r.out, "Wait for the 1 ms User_Timer_Clock"), want) << c.args;
  }
}

// a22 finding 4: with the C31's controller served, the demo's edges are the C31 interrupt's and
// X/INT stays inactive (docs/dpc31.md, "Two interrupt controllers"); the start's DX_Out at its
// completion cycle s, the user timer's tick at s + P (docs/timing.md).
TEST(CliDemo, TheC31ControllerIsNamedNotXInt) {
  const std::string dir = testutil::scratch() + "demo-c31";
  const Result r = run("demo --irq-controller c31 --out-dir " + dir);
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find("\nThe bus reaches the C31's interrupt controller (--irq-controller c31): "
                       "the lines below are the C31 interrupt; X/INT, the external "
                       "controller's, stays inactive\n"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("X/INT ->"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("X/INT goes active"), std::string::npos) << r.out;
  const std::uint64_t start = kAccess * accesses(demo_section(r.out, "Initialise as a driver"));
  EXPECT_NE(r.out.find(at_cycle(start, "  C31 interrupt -> active")), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(at_cycle(start + kUserTimerPeriod, "  C31 interrupt -> active")),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("# Unmask it again: the C31 interrupt goes active as soon as the mask "
                       "write completes\n"),
            std::string::npos)
      << r.out;
  // The DP session runs the chip the options made, its controller too.
  EXPECT_NE(r.out.find("\nscenario <demo>: profile dpc31, the C31's interrupt controller, bus "
                       "intel, master 2 -> slave 5 at 1500000 baud\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("expects passed 5, failed 0"), std::string::npos) << r.out;
}

// The VPC3+ variant too: VPC3+B reads Bh in Status_Reg bits 15..12 (docs/scenario-format.md,
// `variant`), in the register session and in the DP session's chip.
TEST(CliDemo, TheDpSessionRunsTheChosenVariant) {
  const std::string dir = testutil::scratch() + "demo-variant";
  const Result r = run("demo --profile vpc3plus --variant b --out-dir " + dir);
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find("Status_Reg = B000h"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\nscenario <demo>: profile vpc3plus, variant b, bus intel, master 2 -> "
                       "slave 5 at 1500000 baud\n"),
            std::string::npos)
      << r.out;
}

// a22 finding 7: a firmware that never starts the chip (BAD_PLUGIN_GLOBALS' init only writes its
// port) leaves the DP state at its reset value Wait_Prm (docs/timing.md "Mode and state
// changes"): the demo's last expect fails, exit 1, and its one line names the step and the walk's
// line where it shows, not the built-in script's pseudo-file.
TEST(CliDemo, AFailedDpSessionNamesItsStep) {
  const std::string dir = testutil::scratch() + "demo-fails";
  const std::string err = testutil::scratch() + "demo-fails.err";
  const Result r = testutil::run_command(std::string(DPC31_CLI) + " demo --firmware " +
                                         BAD_PLUGIN_GLOBALS + " --out-dir " + dir + " 2>" + err);
  EXPECT_EQ(r.rc, 1);
  const std::string failed = ": expect dp_state Data_Exchange: FAILED, got Wait_Prm\n";
  const std::size_t at = r.out.find(failed);
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::size_t line = r.out.rfind("line ", at);
  const std::string walk_line = r.out.substr(line + 5, at - line - 5);
  EXPECT_EQ(slurp(err),
            "dpc31 demo: the DP session's `expect dp_state Data_Exchange` (the walk's "
            "line " +
                walk_line + "): expected dp_state Data_Exchange, got Wait_Prm\n");
}

// A plug-in whose path a scenario line cannot hold (a space, a '#') runs the demo's DP session
// too: the session names the loaded plug-in, not its path.
TEST(CliDemo, APluginPathWithASpaceAndAHashRuns) {
  namespace fs = std::filesystem;
  const fs::path plugin = fs::path(testutil::scratch()) / "with space" / "lib#do4 =1.so";
  fs::create_directories(plugin.parent_path());
  fs::permissions(plugin.parent_path(), fs::perms::owner_all | fs::perms::group_read |
                                            fs::perms::group_exec | fs::perms::others_read |
                                            fs::perms::others_exec);
  fs::copy_file(PLUGIN_DO4, plugin, fs::copy_options::overwrite_existing);
  const std::string dir = testutil::scratch() + "demo-space";
  const Result r = run("demo --firmware '" + plugin.string() + "' --out-dir " + dir);
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find("the slave runs the firmware " + plugin.string()), std::string::npos);
  EXPECT_NE(r.out.find("expects passed 1, failed 0"), std::string::npos) << r.out;
}

// a22 finding 8: each claim of a --help text, and that it holds.
TEST(CliHelp, TheDemoIsARegisterAndADpSession) {
  const Result r = run("--help");
  EXPECT_NE(r.out.find("demo                        a register-level session (start, interrupts, "
                       "EOI), then a DP session: the built-in master and DO4 (or --firmware), the "
                       "cable pulled past the DP watchdog; waveforms and pcapng\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("bridge                      the RS-485 line of one slave (or of several, "
                       "--slave) as a pseudo-terminal or a loopback TCP port for a DP master "
                       "program\n"),
            std::string::npos)
      << r.out;
}

// The bridge's --firmware: required without --slave, refused beside it (docs/bridge.md), both
// before anything starts (exit 2, one line).
TEST(CliHelp, TheBridgesFirmwareIsRequiredOnlyWithoutSlave) {
  EXPECT_NE(run("bridge --help")
                .out.find("--firmware TEXT             firmware: DO4, CNT2, or a "
                          "plug-in ./libmine.so (required without --slave, "
                          "refused with it: each --slave names its station's)\n"),
            std::string::npos);
  const std::string pty = testutil::scratch() + "help-pty";
  for (const std::string& args : {"bridge --pty " + pty, "bridge --pty " + pty +
                                                             " --slave 5:DO4 --slave 6:DO4 "
                                                             "--firmware DO4"}) {
    const Result r = testutil::run_command(std::string(DPC31_CLI) + " " + args + " 2>&1");
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << args << ": " << r.out;
  }
}

// --timescale: the units the help names are accepted, 1fs and 10ns included, and the next one up,
// 100ns, is refused (docs/waveforms.md: longer than a 48 MHz clock cycle).
TEST(CliHelp, TheTimescaleRangeIsWhatIsAccepted) {
  const std::string range =
      "1, 10 or 100 fs or ps, or 1 or 10 ns (a unit longer than a 48 MHz clock cycle, 20.8 ns, is "
      "refused)";
  EXPECT_NE(run("run --help")
                .out.find("--timescale TEXT            waveform time unit: " + range +
                          "; default 1ps, 10ns with --flat and --la-vcd\n"),
            std::string::npos);
  EXPECT_NE(run("demo --help")
                .out.find("--timescale TEXT            time unit of both "
                          "waveforms: " +
                          range +
                          "; default 1ps for the full VCD, 10ns for the logic "
                          "analysers' VCD\n"),
            std::string::npos);
  const std::string scn = std::string(SOURCE_DIR) + "/traces/gc_unfreeze_dpc31.scn";
  const std::string vcd = testutil::scratch() + "help-unit.vcd";
  for (const char* unit : {"1fs", "10fs", "100fs", "1ps", "10ps", "100ps", "1ns", "10ns"}) {
    EXPECT_EQ(run("run " + scn + " --quiet --vcd " + vcd + " --timescale " + unit).rc, 0) << unit;
  }
  EXPECT_EQ(run("run " + scn + " --quiet --vcd " + vcd + " --timescale 100ns").rc, 2);
}

namespace {

// A VPC3+ whose user side never sees the MSAC_C1 request (FDL_Ind masked): `dpv1_read` polls
// until c1_timeout `ms` ends (docs/dpv1.md), one step of about 680 polls a millisecond.
std::string silent_read(unsigned ms) {
  return "profile vpc3plus\nbaud 12000000\nmaster address=2\nslave address=5 user_prm=C0,00,00\n"
         "dpv1 c1_timeout=" +
         std::to_string(ms) +
         "\nrecord slot=0 index=1 data=11,22,33,44\nstartup\n"
         "write Int_Mask_Reg 0x80F0\ndpv1_read slot=0 index=1 length=4\nexpect dpv1 timeout\n";
}

}  // namespace

// s34-record: `--record` held the whole trace (every telegram, about 70 bytes a poll's line and
// more in memory) until the run ended: a 1 000 ms DPV1 time-out peaked at 439 MB, a 655 s one ran
// out of memory. The recorder writes its lines as they are decided into the temporary: five times
// the polls (500 ms against 100 ms) grow the peak RSS of `dpc31 run --record` by no more than
// 8 MiB (it grew by about 175 MB), the trace is five times as long, and the short one replays.
TEST(CliRun, ALongDpv1TimeoutKeepsTheRecordFlat) {
  const std::string dir = testutil::scratch();
  long rss[2] = {0, 0};
  std::uintmax_t size[2] = {0, 0};
  for (const unsigned ms : {100U, 500U}) {
    const std::string scn = dir + "read" + std::to_string(ms) + ".scn";
    std::ofstream(scn) << silent_read(ms);
    const std::string trace = dir + "read" + std::to_string(ms) + ".trace";
    const int k = ms == 100 ? 0 : 1;
    ASSERT_EQ(testutil::spawn({DPC31_CLI, "run", "--quiet", "--record", trace, scn}, &rss[k]), 0)
        << ms;
    size[k] = std::filesystem::file_size(trace);
  }
  EXPECT_GT(size[1], 4 * size[0]);
  // wait4's peak RSS also counts what the forked test process had resident (the same for both);
  // under AddressSanitizer that is its shadow memory: no bound.
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LE(rss[1], rss[0] + 8 * 1024)
      << "peak RSS " << rss[0] << " KiB over 100 ms of polls, " << rss[1] << " KiB over 500 ms";
#endif
  EXPECT_EQ(run("replay " + dir + "read100.trace").rc, 0);
}

// s35-replay: `dpc31 replay` read the whole trace (at most 64 MiB, `too large for a trace`) and
// held every line of it: the 950 ms time-out's trace, past that bound (about 70 MB: the cheapest
// run we know of that is, DPV1 polls at 12 Mbaud being the densest lines), was refused, and the
// 100 ms one (7.1 MB) peaked at about 58 MB. The replay reads the file line by line (twice: a
// check, then the replay; docs/trace-format.md): both replay, and the long one's peak RSS is
// within 4 MiB of the short one's.
TEST(CliRun, ALongDpv1TimeoutReplaysFlat) {
  const std::string dir = testutil::scratch();
  long rss[2] = {0, 0};
  std::uintmax_t size[2] = {0, 0};
  for (const unsigned ms : {100U, 950U}) {
    const int k = ms == 100 ? 0 : 1;
    const std::string scn = dir + "replay" + std::to_string(ms) + ".scn";
    std::ofstream(scn) << silent_read(ms);
    const std::string trace = dir + "replay" + std::to_string(ms) + ".trace";
    ASSERT_EQ(testutil::spawn({DPC31_CLI, "run", "--quiet", "--record", trace, scn}), 0) << ms;
    size[k] = std::filesystem::file_size(trace);
    EXPECT_EQ(testutil::spawn({DPC31_CLI, "replay", "--quiet", trace}, &rss[k]), 0) << ms;
    std::filesystem::remove(trace);
  }
  EXPECT_GT(size[1], std::uintmax_t{64} << 20);  // past the old bound
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LE(rss[1], rss[0] + 4 * 1024) << "peak RSS " << rss[0] << " KiB for " << size[0]
                                       << " bytes, " << rss[1] << " KiB for " << size[1];
#endif
}

// A trace written as the run goes still comes after the walk where both go to one file: a target
// written in place (a descriptor, a device, a FIFO) gets it from a scratch file when the run ends
// (docs/bad-input.md, "Output files"), as it got the whole trace then before.
TEST(CliRun, ATraceToTheStandardOutputComesAfterTheWalk) {
  const std::string dir = testutil::scratch();
  std::ofstream(dir + "read.scn") << silent_read(100);
  ASSERT_EQ(testutil::run_command(std::string(DPC31_CLI) + " run " + dir + "read.scn --record " +
                                  "/dev/stdout > " + dir + "both.txt 2>&1")
                .rc,
            0);
  const std::string both = slurp(dir + "both.txt");
  EXPECT_EQ(both.rfind("scenario " + dir + "read.scn: profile vpc3plus", 0), 0u)
      << both.substr(0, 200);
  const std::size_t end = both.find("] end: dp_state Data_Exchange");
  const std::size_t trace = both.find("dpc31-trace 1\n");
  ASSERT_NE(end, std::string::npos);
  ASSERT_NE(trace, std::string::npos);
  EXPECT_EQ(trace, both.find('\n', end) + 1);
  std::ofstream(dir + "read.trace") << both.substr(trace);
  EXPECT_EQ(run("replay " + dir + "read.trace").rc, 0);
}

namespace {

// With stdout and stderr on one file (`2>&1`), a failed check's line goes out after the walk lines
// before it, never inside one (the s35 audit, finding 9: the buffered walk was flushed later, the
// failure landed mid-line). The image writes the latch every 5 machine cycles (MOV DPTR,#4000h;
// MOVX @DPTR,A; INC A; SJMP back: ServeCpu.PortLinesAreBoundedAndTheClientKept), 1 000 walk lines
// in 10 ms, far more than stdio's buffer; the check that follows fails.
TEST(Cli, AnErrorLineGoesOutAfterTheWalkLinesBeforeIt) {
  const testutil::TempDir dir;
  std::ofstream(dir.file("fw.ihx")) << ":07000000904000F00480FCB9\n:00000001FF\n";
  std::ofstream(dir.file("f.scn"))
      << "profile spc3\ncpu 80c32 firmware fw.ihx\nsilence 10ms\nexpect port outputs 0x55\n";
  const Result r =
      testutil::run_command(std::string(DPC31_CLI) + " run " + dir.file("f.scn") + " 2>&1");
  EXPECT_EQ(r.rc, 1);
  std::istringstream in(r.out);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_GT(lines.size(), 1000u);
  const std::string failure = dir.file("f.scn") + ":4: expected port outputs 0x55, got ";
  std::size_t at = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].starts_with(failure)) {
      at = i;
    } else {
      EXPECT_TRUE(lines[i].starts_with(i == 0 ? "scenario " : "[cycle ")) << i << ": " << lines[i];
    }
  }
  ASSERT_LT(at, lines.size());
  // Every port write of the silence (before cycle 480 000, where the check is) precedes it.
  for (std::size_t i = at + 1; i < lines.size(); ++i)
    EXPECT_EQ(lines[i].find(" 80C32 at "), std::string::npos) << i << ": " << lines[i];
}

}  // namespace
