// Scenario files (docs/scenario-format.md): parse errors name FILE:LINE, a failed expect exits 1
// with its line, nothing runs when a file does not parse, and every shipped scenario passes.
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

#include "heap_in_use.hpp"
// emu/ is not on the tests' include path.
#include "scenario.hpp"

namespace {

namespace fs = std::filesystem;

// SOURCE_DIR, not __FILE__: with ccache's base directory (our launcher) or with Ninja, __FILE__
// is relative to where the compiler ran, and CTest runs the tests from build/tests.
const fs::path kTraces = fs::path(SOURCE_DIR) / "traces";

struct Lines {
  std::vector<std::string> lines;
  dpc31::LineSink sink() {
    return [this](const std::string& l) { lines.push_back(l); };
  }
  [[nodiscard]] bool has(const std::string& s) const {
    for (const std::string& l : lines) {
      if (l.find(s) != std::string::npos) return true;
    }
    return false;
  }
};

// `text` as "t.scn" parsed (a parse error fails the test) and run, its failures into `errors`.
dpc31::ScenarioOutcome run_text(const std::string& text, Lines& errors) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  return dpc31::run_scenario(s, {}, errors.sink());
}

// The first parse error of `text` as "FILE:LINE: message"; "" if it parses.
std::string parse_error(const std::string& text) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  if (dpc31::parse_scenario(text, "t.scn", s, err)) return "";
  return err.text();
}

// A scenario file in a fresh temporary directory.
class TempFile {
 public:
  explicit TempFile(const std::string& text) {
    std::array<char, 32> dir{};
    std::snprintf(dir.data(), dir.size(), "/tmp/scn_test_XXXXXX");
    dir_ = mkdtemp(dir.data());
    path_ = dir_ / "s.scn";
    std::ofstream(path_) << text;
  }
  ~TempFile() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  [[nodiscard]] std::string path() const { return path_.string(); }
  [[nodiscard]] fs::path dir() const { return dir_; }

 private:
  fs::path dir_;
  fs::path path_;
};

std::vector<fs::path> shipped() {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(kTraces)) {
    if (e.path().extension() != ".scn") continue;
    // DO4 and CNT2 on the 80C32 and ECHO on the C31 run as the build's copies, beside the
    // images they name (firmware/).
    const std::string stem = e.path().stem().string();
    v.push_back(stem.ends_with("_80c32") || stem.ends_with("_c31")
                    ? fs::path(FW51_DIR) / e.path().filename()
                    : e.path());
  }
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

TEST(ScenarioParse, ErrorsNameFileAndLine) {
  EXPECT_EQ(parse_error("profile dpc31\n\n# comment\nfrobnicate 3\n"),
            "t.scn:4: unknown command 'frobnicate'");
  EXPECT_EQ(parse_error("startup\nexchange 3x\n"), "t.scn:2: bad number '3x' for exchange count");
  EXPECT_EQ(parse_error("startup\nexchange 0\n"),
            "t.scn:2: exchange count 0 out of range (1..1000000)");
  EXPECT_EQ(parse_error("Startup\n"), "t.scn:1: unknown command 'Startup'");
  EXPECT_EQ(parse_error("profile z80\n"), "t.scn:1: unknown profile 'z80' (spc3, vpc3plus, dpc31)");
  EXPECT_TRUE(
      parse_error("baud 1200\nstartup\n").starts_with("t.scn:1: baud 1200 is not a PROFIBUS r"))
      << parse_error("baud 1200\nstartup\n");
  EXPECT_EQ(parse_error("startup\nbaud 9600\n"),
            "t.scn:2: 'baud' is a header command: headers come before actions and expects");
  EXPECT_EQ(parse_error("slave adress=5\n"), "t.scn:1: unknown option 'adress' for slave");
  EXPECT_EQ(parse_error("slave address=0x80\n"),
            "t.scn:1: slave address 0x80 out of range (0x00..0x7D)");
  EXPECT_EQ(parse_error("startup\nexchange outputs=01,2G\n"),
            "t.scn:2: bad byte '2G' in outputs (hex bytes separated by commas)");
  EXPECT_EQ(parse_error("startup\nsilence 10min\n"),
            "t.scn:2: bad time unit 'min' in '10min' (us, ms, s, bits, or none for cycles)");
  // A fraction is no unit (audit s30 a-docs, finding 6: "bad time unit '.5ms' in '1.5ms'").
  EXPECT_EQ(parse_error("startup\nsilence 1.5ms\n"),
            "t.scn:2: time '1.5ms': a time is a whole number of its unit: write it in a smaller "
            "unit");
  EXPECT_EQ(parse_error("startup\nsilence 4000s\n"),
            "t.scn:2: time '4000s' too long (at most 3600 s)");
  EXPECT_TRUE(parse_error("startup\nexpect counter parityy 1\n")
                  .starts_with("t.scn:2: unknown counter 'parityy' (th"))
      << parse_error("startup\nexpect counter parityy 1\n");
  EXPECT_TRUE(parse_error("startup\nexpect irr_bit DX_In 1\n")
                  .starts_with("t.scn:2: 'DX_In' is not an interrupt of dpc"))
      << parse_error("startup\nexpect irr_bit DX_In 1\n");
  EXPECT_EQ(parse_error("startup\nexpect dp_state Data_exchange\n"),
            "t.scn:2: unknown state 'Data_exchange' (Wait_Prm, Wait_Cfg, Data_Exchange)");
  EXPECT_EQ(parse_error("startup\nexchange 1 outputs=01 outputs=02\n"),
            "t.scn:2: option 'outputs' given twice");
  EXPECT_EQ(parse_error("foreign_master address=2\n"),
            "t.scn:1: foreign_master address=2 is our own master's address");
}

// The header line `variant` makes the chip a VPC3+B, C or S (Status_Reg bits 15..12, read over
// the bus by the scenario's own chip); it needs profile vpc3plus.
TEST(ScenarioParse, VariantHeaderChoosesTheVpc3plusAsicType) {
  for (const auto& [name, nibble] :
       {std::pair{"b", 0xB}, std::pair{"c", 0xC}, std::pair{"s", 0xE}}) {
    dpc31::Scenario s;
    dpc31::ScenarioError err;
    ASSERT_TRUE(dpc31::parse_scenario(std::string("profile vpc3plus\nvariant ") + name +
                                          "\nstartup\nexpect dp_state Data_Exchange\n",
                                      "t.scn", s, err))
        << err.text();
    int seen = -1;
    dpc31::ScenarioHooks hooks;
    hooks.at_end = [&](dpc31::Chip& c) { seen = c.read(0x05) >> 4; };  // Status_Reg high byte
    Lines walk;
    const dpc31::ScenarioOutcome out = dpc31::run_scenario(s, walk.sink(), {}, hooks);
    EXPECT_TRUE(out.ok());
    EXPECT_EQ(seen, nibble) << name;
    EXPECT_TRUE(walk.has(std::string("profile vpc3plus, variant ") + name)) << name;
  }
  EXPECT_EQ(parse_error("profile spc3\nvariant s\n"),
            "t.scn:2: 'variant' needs 'profile vpc3plus' before it: only the VPC3+ has variants");
  EXPECT_EQ(parse_error("profile vpc3plus\nvariant d\n"), "t.scn:2: unknown variant 'd' (b, c, s)");
  EXPECT_EQ(parse_error("profile vpc3plus\nvariant s\nprofile dpc31\n"),
            "t.scn:3: a 'variant' was given: only profile vpc3plus has variants");
}

// The header line `irq-controller c31` puts the user's bus on the DPC31's C31 interrupt
// controller (docs/dpc31.md): the built-in user side still answers every interrupt, and X/INT,
// the external processor's, stays inactive (high). Only profile dpc31 has it.
TEST(ScenarioParse, IrqControllerHeaderChoosesTheC31s) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  ASSERT_TRUE(dpc31::parse_scenario(
      "profile dpc31\nirq-controller c31\nstartup\nexpect dp_state Data_Exchange\n", "t.scn", s,
      err))
      << err.text();
  int x_int_low = 0;
  bool c31 = false;
  dpc31::ScenarioHooks hooks;
  hooks.at_start = [&](dpc31::Chip& c) {
    c31 = c.irq_controller() == dpc31::IrqController::c31;
    c.on_irq_change([&x_int_low, &c](std::uint64_t, bool) { x_int_low += c.x_int_pin() ? 0 : 1; });
  };
  Lines walk;
  EXPECT_TRUE(dpc31::run_scenario(s, walk.sink(), {}, hooks).ok());
  EXPECT_TRUE(c31);
  EXPECT_EQ(x_int_low, 0);
  EXPECT_TRUE(walk.has("profile dpc31, the C31's interrupt controller"));
  EXPECT_EQ(parse_error("profile spc3\nirq-controller c31\n"),
            "t.scn:2: 'irq-controller c31' needs 'profile dpc31' before it: only the DPC31 has a "
            "C31 core");
  EXPECT_EQ(parse_error("profile dpc31\nirq-controller cpu\n"),
            "t.scn:2: unknown irq-controller 'cpu' (external, c31)");
  EXPECT_EQ(parse_error("profile dpc31\nirq-controller c31\nprofile spc3\n"),
            "t.scn:3: 'irq-controller c31' was given: only profile dpc31 has a C31 core");
}

TEST(ScenarioParse, FaultsNeedARequestToDamage) {
  EXPECT_EQ(parse_error("startup\ncorrupt parity\n"), "t.scn:2: no request follows to damage");
  EXPECT_EQ(parse_error("startup\nbad_fcs\nexpect dp_state Wait_Prm\nsilence 1ms\n"),
            "t.scn:2: the next action ('silence', line 4) sends no request to damage");
  EXPECT_EQ(parse_error("startup\ncorrupt stop\nbad_fcs\nexchange\n"),
            "t.scn:3: a second fault before the request of line 2");
  EXPECT_EQ(parse_error("startup\ncorrupt parity char=3\nexpect dp_state Data_Exchange\ndiag\n"),
            "");
}

TEST(ScenarioParse, EmptyAndCommentOnlyFilesAreRefused) {
  EXPECT_EQ(parse_error(""), "t.scn: no commands: nothing to run");
  EXPECT_EQ(parse_error("# nothing\n\n   \n"), "t.scn: no commands: nothing to run");
  EXPECT_EQ(parse_error("profile spc3\nbaud 9600\n"),
            "t.scn: only header commands: nothing to run");
}

TEST(ScenarioParse, GarbageGivesOneLine) {
  const std::string e =
      parse_error(std::string("\x7f"
                              "ELF\x02\x01\x01\0\0\n\xff\xfe",
                              13));
  EXPECT_EQ(e, "t.scn:1: unknown command '\\x7FELF\\x02\\x01\\x01\\x00\\x00'");
  EXPECT_EQ(e.find('\n'), std::string::npos);
}

TEST(ScenarioParse, TimesAndNumbers) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  ASSERT_TRUE(dpc31::parse_scenario(
      "baud 1500000\nsilence 1ms\nsilence 2us\nsilence 3bits\nsilence 0x10\nsilence 1s\n"
      "gc sync,clear groups=0x81\nexchange 0x10 outputs=0x0A,b,FF\n",
      "t.scn", s, err))
      << err.text();
  ASSERT_EQ(s.steps.size(), 7u);
  EXPECT_EQ(s.steps[0].cycles, 48'000u);  // ceil(t x 48 MHz)
  EXPECT_EQ(s.steps[1].cycles, 96u);
  EXPECT_EQ(s.steps[2].cycles, 96u);  // 32 clocks per bit at 1.5 Mbaud
  EXPECT_EQ(s.steps[3].cycles, 16u);
  EXPECT_EQ(s.steps[4].cycles, 48'000'000u);
  EXPECT_EQ(s.steps[5].value, 0x22u);
  EXPECT_EQ(s.steps[5].value2, 0x81u);
  EXPECT_EQ(s.steps[6].count, 16u);
  EXPECT_EQ(s.steps[6].bytes, (std::vector<std::uint8_t>{0x0A, 0x0B, 0xFF}));
}

TEST(ScenarioRun, MissingFileExits2WithOneLine) {
  Lines walk;
  Lines errors;
  EXPECT_EQ(dpc31::run_scenario_file("/nonexistent/x.scn", walk.sink(), errors.sink()), 2);
  ASSERT_EQ(errors.lines.size(), 1u);
  EXPECT_EQ(errors.lines[0], "/nonexistent/x.scn: no such file");
  EXPECT_TRUE(walk.lines.empty());
}

// The whole file is parsed before anything runs: an error on the last line costs no run.
TEST(ScenarioRun, NothingRunsWhenTheFileDoesNotParse) {
  const TempFile f("startup\nexchange 5\nexpect dp_state Data_Exchange\nexchange 1 outputs=XYZ\n");
  Lines walk;
  Lines errors;
  EXPECT_EQ(dpc31::run_scenario_file(f.path(), walk.sink(), errors.sink()), 2);
  EXPECT_TRUE(walk.lines.empty());
  ASSERT_EQ(errors.lines.size(), 1u);
  EXPECT_EQ(errors.lines[0], f.path() +
                                 ":4: bad byte 'XYZ' in outputs (hex bytes separated by "
                                 "commas)");
}

TEST(ScenarioRun, FailedExpectExits1WithItsLine) {
  const TempFile f(
      "startup\n"
      "expect dp_state Data_Exchange\n"
      "expect dp_state Wait_Cfg   # wrong on purpose\n"
      "expect counter requests 5\n"
      "exchange 2 outputs=01,02,03,04\n"
      "expect outputs 01,02,03,05\n");
  Lines walk;
  Lines errors;
  dpc31::Scenario s;
  dpc31::ScenarioOutcome o;
  EXPECT_EQ(dpc31::run_scenario_file(f.path(), walk.sink(), errors.sink(), &s, &o), 1);
  ASSERT_EQ(errors.lines.size(), 2u);
  EXPECT_EQ(errors.lines[0], f.path() + ":3: expected dp_state Wait_Cfg, got Data_Exchange");
  EXPECT_EQ(errors.lines[1], f.path() + ":6: expected outputs 01 02 03 05, got 01 02 03 04");
  EXPECT_EQ(o.passed, 2u);
  EXPECT_EQ(o.failed, 2u);
  // The run goes on after a failed expect: the exchange happened.
  EXPECT_TRUE(walk.has("2 -> 5 Data_Exchange 01 02 03 04 => DL"));
  EXPECT_TRUE(walk.has("line 3: expect dp_state Wait_Cfg: FAILED, got Data_Exchange"));
}

TEST(ScenarioRun, WalkIsDeterministic) {
  const fs::path p = kTraces / "faults.scn";
  Lines a;
  Lines b;
  ASSERT_EQ(dpc31::run_scenario_file(p.string(), a.sink(), {}), 0);
  ASSERT_EQ(dpc31::run_scenario_file(p.string(), b.sink(), {}), 0);
  EXPECT_EQ(a.lines, b.lines);
}

TEST(ScenarioRun, ShippedStartupWalksToDataExchange) {
  bool found = false;
  for (const fs::path& p : shipped()) {
    if (p.filename().string().find("startup") == std::string::npos) continue;
    found = true;
    Lines walk;
    Lines errors;
    EXPECT_EQ(dpc31::run_scenario_file(p.string(), walk.sink(), errors.sink()), 0) << p;
    EXPECT_TRUE(walk.has("dp_state Wait_Prm -> Wait_Cfg")) << p;
    EXPECT_TRUE(walk.has("dp_state Wait_Cfg -> Data_Exchange")) << p;
    EXPECT_TRUE(walk.has("wd_state Baud_Search -> Baud_Control")) << p;
    EXPECT_TRUE(walk.lines.at(1).starts_with("[cycle ")) << p;
  }
  EXPECT_TRUE(found);
}

TEST(ScenarioRun, EveryShippedScenarioPasses) {
  const std::vector<fs::path> all = shipped();
  EXPECT_GE(all.size(), 7u);
  for (const fs::path& p : all) {
    Lines errors;
    dpc31::ScenarioOutcome o;
    EXPECT_EQ(dpc31::run_scenario_file(p.string(), {}, errors.sink(), nullptr, &o), 0) << p;
    EXPECT_TRUE(errors.lines.empty()) << p << ": " << errors.lines.front();
    EXPECT_GT(o.passed, 0u) << p;
  }
}

// The command line, when it has been built next to this test binary.
TEST(ScenarioRun, CliExitCodes) {
  std::error_code ec;
  const fs::path cli = fs::read_symlink("/proc/self/exe", ec).parent_path() / "dpc31";
  ASSERT_TRUE(!ec && fs::exists(cli)) << "dpc31 must be built next to the tests";
  const auto rc = [&](const std::string& args) {
    const int st = std::system((cli.string() + " " + args + " >/dev/null 2>&1").c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  const TempFile bad("startup\nnonsense\n");
  const TempFile failing("startup\nexpect dp_state Wait_Prm\n");
  const TempFile empty("");
  EXPECT_EQ(rc("run " + (kTraces / "startup_dpc31_1m5.scn").string()), 0);
  EXPECT_EQ(rc("run --quiet " + failing.path()), 1);
  EXPECT_EQ(rc("run " + bad.path()), 2);
  EXPECT_EQ(rc("run " + empty.path()), 2);
  EXPECT_EQ(rc("run /nonexistent.scn"), 2);
  EXPECT_EQ(rc("run"), 2);
  const std::string json = (failing.dir() / "out.json").string();
  EXPECT_EQ(rc("run --quiet --json " + json + " " + failing.path()), 1);
  std::ifstream j(json);
  const std::string text((std::istreambuf_iterator<char>(j)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"failed\": 1"), std::string::npos) << text;
  EXPECT_NE(text.find("\"dp_state\": \"Data_Exchange\""), std::string::npos) << text;
  for (const auto& e : fs::directory_iterator(failing.dir()))  // no .dpc31-PID.tmp left
    EXPECT_FALSE(e.path().filename().string().starts_with(".dpc31-")) << e.path();
}

// `user user_wd=1` on the dpc31 runs the DPS_User_Watchdog through the Instruction_Queue, as a
// firmware would (issue 31: the option did nothing there). DPC31 p.31: "started by a
// user-parameterized value ... decremented every 10 msec. If the timer reaches the value '0000h',
// DPS ... executes 'Leave_Master'"; docs/dpc31.md: Enable at cycle e starts the 10 ms time base
// (decrements at e + k x 480 000 at 48 MHz), Reset reloads the value without moving that phase,
// requests act in the completion cycle of the InstQ_Wr write. So after the last Reset at r, with
// value V = 5, Leave_Master falls on the 5th decrement after r: e + 480 000 x (k + 4), k the
// first decrement after r. e and r are read off the bus, as a logic analyser on it would.
TEST(ScenarioRun, Dpc31UserWatchdogExpiresAtItsCycle) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  ASSERT_TRUE(dpc31::load_scenario((kTraces / "user_wd_expiry_dpc31.scn").string(), s, err))
      << err.message;
  std::vector<std::uint64_t> instq_writes;  // completion cycles of the writes to InstQ_Wr
  std::uint64_t leave = 0;                  // Data_Exchange -> Wait_Prm
  dpc31::ScenarioHooks hooks;
  hooks.at_start = [&](dpc31::Chip& chip) {
    const auto* instq_wr = dpc31::find_reg(chip.profile(), "InstQ_Wr");
    chip.on_bus_access(
        [&, addr = instq_wr->write_addr](std::uint64_t c, const dpc31::BusAccess& a) {
          if (a.write && a.addr == addr) instq_writes.push_back(c);
        });
    chip.on_state_change([&, dx = false](std::uint64_t c) mutable {
      const bool now = chip.dp_state() == dpc31::DpState::Data_Exchange;
      if (dx && !now && leave == 0) leave = c;
      dx = now;
    });
  };
  Lines walk;
  const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, walk.sink(), {}, hooks);
  EXPECT_EQ(o.failed, 0u);
  ASSERT_GE(instq_writes.size(), 3u);       // MAC_Start + Enable, then a Reset per DX_Out
  constexpr std::uint64_t kTick = 480'000;  // 10 ms at 48 MHz
  const std::uint64_t e = instq_writes.front();
  std::uint64_t r = 0;  // the last Reset before the expiry
  for (std::uint64_t c : instq_writes)
    if (c < leave) r = c;
  ASSERT_GT(r, e);
  ASSERT_NE((r - e) % kTick, 0u);  // not on a decrement: no same-cycle order to decide
  const std::uint64_t k = (r - e) / kTick + 1;
  EXPECT_EQ(leave, e + kTick * (k + 4));
  EXPECT_TRUE(walk.has(fmt::format("[cycle {:>10}] dp_state Data_Exchange -> Wait_Prm", leave)));
}

// Bus actions and their checks (docs/scenario-format.md, "Bus accesses"): bad lines refused.
TEST(ScenarioParse, BusActionsRefuseWhatTheMapDoesNot) {
  const std::string h = "profile spc3\n";
  const std::pair<std::string, std::string> cases[] = {
      {h + "write No_Such_Reg 1\n",
       "t.scn:2: 'No_Such_Reg' is not a register of spc3 (names as in docs/registers.md)"},
      {h + "write Status_Reg 1\n", "t.scn:2: Status_Reg has no write side in spc3"},
      {h + "read Int_Mask_Reg\n", "t.scn:2: Int_Mask_Reg has no read side in spc3"},
      {h + "write R_TS_Adr 256\n", "t.scn:2: value 256 out of range (0..255)"},
      {h + "write 0x800 1\n", "t.scn:2: address 0x800 out of range (0x000..0x7FF)"},
      {h + "read 0x7FF count=2\n",
       "t.scn:2: 2 bytes from 0x7FF run past the end of the spc3 map (0x800 bytes)"},
      {h + "read R_TS_Adr count=2\n",
       "t.scn:2: a block access starts at an address, not at a register"},
      {h + "write 0x10 1 bytes=01\n",
       "t.scn:2: expected 'write REG VALUE', 'write ADDR VALUE' or 'write ADDR bytes=BYTES'"},
      {h + "expect read 1\n", "t.scn:2: 'expect read' needs a 'read' before it"},
      {h + "read 0x10 count=2\nexpect read 123\n",
       "t.scn:3: bad byte '123' in read (hex bytes separated by commas)"},
      {h + "expect reg Status_Reg 0x10000\n",
       "t.scn:2: register value 0x10000 out of range (0x0000..0xFFFF)"},
      {h + "expect baud 12000000 at 5\n",
       "t.scn:2: 'at' is for dp_state, wd_state, dpv1, irq and port: the cycle a state was "
       "entered, a response ended, X/INT went active or a port was written"},
      // `expect irq`: the cycle X/INT went active, or how often (docs/scenario-format.md).
      {h + "expect irq DX_Out after 12\nexpect irq count 0\nexpect irq MAC_Reset at 7\n", ""},
      {h + "expect irq DX_Out\n",
       "t.scn:2: 'expect irq DX_Out' needs 'at CYCLE' or 'after N': the cycle X/INT went active"},
      {h + "expect irq count 2 after 5\n", "t.scn:2: 'expect irq count N' takes no 'at' / 'after'"},
      {h + "expect irq count\n",
       "t.scn:2: expected 'expect irq NAME at CYCLE|after N' or 'expect irq count N'"},
      {h + "expect irq count x\n", "t.scn:2: bad number 'x' for count"},
      // A word too many names itself, the form its cycle (audit s30 a-docs, finding 7: a bare
      // usage line before).
      {h + "expect dp_state Data_Exchange extra\n",
       "t.scn:2: expected 'expect dp_state Wait_Prm|Wait_Cfg|Data_Exchange [at CYCLE|after N]'; "
       "unexpected 'extra'"},
      {h + "expect wd_state DP_Control after\n",
       "t.scn:2: expected 'expect wd_state Baud_Search|Baud_Control|DP_Control [at CYCLE|after "
       "N]'; "
       "unexpected 'after'"},
      {h + "expect dp_state\n",
       "t.scn:2: expected 'expect dp_state Wait_Prm|Wait_Cfg|Data_Exchange [at CYCLE|after N]'"},
      {h + "expect outputs 01 02\n", "t.scn:2: expected 'expect outputs BYTES'; unexpected '02'"},
      {h + "expect irq FDL_Ind at 5\n",
       "t.scn:2: 'FDL_Ind' is not an interrupt of spc3 (Int_Req_Reg: DX_Out, New_Prm_Data, "
       "WD_DP_Control_Timeout, ...)"},
      {h + "corrupt parity\nwrite 0x10 1\nstartup\n",
       "t.scn:2: the next action ('write', line 3) sends no request to damage"},
      {h + "read 0x10\nexpect read 0x12\nexpect dp_state Wait_Prm after 4\n", ""},
      {h + "read 0x10 count=\n", "t.scn:2: bad number '' for count"},
      {h + "expect answer e5\nexpect answer 68,0x09\n", ""},
      {h + "expect answer dx\n",
       "t.scn:2: bad byte 'dx' in answer (hex bytes separated by commas)"},
      {h + "expect answer sd\n",
       "t.scn:2: unknown answer kind 'sd' (none, sc, data, ok, ue, rr, rs, dl, nr, dh, or the "
       "answer's bytes)"},
      {"request MAC_Stop\n", ""},
      {h + "request MAC_Stop\n",
       "t.scn:2: 'request' is the DPC31's Instruction_Queue: needs profile dpc31"},
      {"request DPS_User_Wd on\n", "t.scn:1: DPS_User_Wd 'on': reset, enable or disable"},
      {"request MAC_New_TRDY\n",
       "t.scn:1: expected 'request MAC_New_TRDY N' (the ready time in bit times)"},
      {"set_prm bytes=88 wd=1,1\n",
       "t.scn:1: set_prm: bytes= is the whole data unit; no other parameter options with it"},
      {"gc sync data=20,00\n", "t.scn:1: 'gc' takes no arguments; unexpected 'sync'"},
      {"master address=2\nchk_cfg from=2\n", "t.scn:2: from=2 is our own master: leave from= out"},
      {"send from=7\n", "t.scn:1: send with fields needs from=SA and fc=N"},
      // The walk's form of a sent telegram (spaces) copied back (audit a16).
      {"send 10 05 02 49 50 16\n",
       "t.scn:1: send: the bytes are separated by commas (10,05,...); unexpected '05'"},
      {"send\n", "t.scn:1: expected 'send BYTES' or 'send from=SA fc=N ...'"},
  };
  for (const auto& [text, line] : cases) EXPECT_EQ(parse_error(text), line) << text;
}

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

namespace {

// A scenario file's run: its exit code, error lines and walk.
struct FileRun {
  int code = 0;
  std::vector<std::string> errors;
  std::vector<std::string> walk;
};
FileRun run_file(const std::string& path) {
  FileRun r;
  r.code = dpc31::run_scenario_file(
      path, [&](const std::string& l) { r.walk.push_back(l); },
      [&](const std::string& l) { r.errors.push_back(l); });
  return r;
}

// `cpu 80c32` (docs/cpu.md): the header is checked when parsing, the image is read only when the
// run starts, relative to the scenario file; a bad record is FILE:LINE, exit 2, nothing run.
TEST(ScenarioCpu51, HeaderIsCheckedAndTheImageReadWhenTheRunStarts) {
  EXPECT_EQ(parse_error("cpu 8051 firmware a.ihx\nstartup\n"),
            "t.scn:1: the form is 'cpu 80c32 firmware FILE'");
  EXPECT_EQ(parse_error("cpu 80c32 clock=50000000 firmware a.ihx\nstartup\n"),
            "t.scn:1: clock 50000000 out of range (1000000..40000000)");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx latch=0x8000 ports=x\nstartup\n"),
            "t.scn:1: the chip's window covers the output latch at 0x8000");
  // Without ports= the latch is DO4's two bytes (docs/cpu.md: the shipped firmware writes 4000h +
  // port), as `dpc31 bridge --board-address 0x4001` refuses it (BadInput.
  // EveryDoorTakesTheSameDefaultLatch).
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x4000 latch=0x4000\nstartup\n"),
            "t.scn:1: the chip's window covers the output latch at 0x4000");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x4000\nstartup\n"),
            "t.scn:1: the chip's window covers the output latch at 0x4000");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x3001\nstartup\n"),
            "t.scn:1: the chip's window covers the output latch at 0x4000");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x3000\nstartup\n"), "");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x4001\nstartup\n"),
            "t.scn:1: the chip's window covers the output latch at 0x4000");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x4002\nstartup\n"), "");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx base=0x4001 ports=a\nstartup\n"), "");
  // A port of the 80C32 board is a byte of its latch (docs/cpu.md, "DO4 on the 80C32").
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx ports=a\nstartup\nexpect port a 256\n"),
            "t.scn:3: port value 256 out of range (0..255)");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx ports=a\nstartup\nexpect port a 0xFFFF\n"),
            "t.scn:3: port value 0xFFFF out of range (0x00..0xFF)");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx ports=a\nstartup\nexpect port a 0xFF\n"), "");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx ports=x\nstartup\nexpect port y 1\n"),
            "t.scn:3: unknown port 'y' of the 80C32 board (x)");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx ports=outputs,outputs\nstartup\n"),
            "t.scn:1: ports=: port 'outputs' named twice");
  EXPECT_EQ(parse_error("cpu 80c32 firmware a.ihx\nstartup\n"), "");  // no file opened yet
  TempFile f("cpu 80c32 firmware bad.ihx\nstartup\n");
  std::ofstream(f.dir() / "bad.ihx") << ":0300000002000BF1\n:00000001FF\n";
  const FileRun r = run_file(f.path());
  EXPECT_EQ(r.code, 2);
  ASSERT_EQ(r.errors.size(), 1u);
  // The scenario's `cpu` line first, then the image's own line.
  EXPECT_TRUE(r.errors[0].starts_with(f.path() + ":1: " + (f.dir() / "bad.ihx").string() + ":1: "))
      << r.errors[0];
  EXPECT_TRUE(r.walk.empty());
}

// The master's line does not depend on the slave's CPU (docs/timing.md, "The master's wait" and
// "An 80C32 beside the chip"): at 1.5 Mbaud (T = 32) an unanswered FDL_Status starts at TSYN =
// 33 T = 1 056, its 6 characters take 66 T, the slot time 100 T, the retry follows TSYN later:
// 1 056 + 199 T = 7 424, with an 80C32 at 1 MHz or 24 MHz in a DIV loop (84h DIV AB, 80h FDh
// SJMP) that never starts the chip. `silence 1` lasts one chip cycle, `silence 100us` 4 800 (docs/
// scenario-format.md: "the bus stays idle for TIME"). The runs ended where the CPU's step did
// (7 872 at 1 MHz; a `silence 1` of up to 2 304 cycles).
TEST(ScenarioCpu51, TheMastersTimesDoNotDependOnTheCpu) {
  for (const char* const cpu : {"cpu 80c32 clock=1000000 firmware fw.ihx\n",
                                "cpu 80c32 clock=24000000 firmware fw.ihx\n"}) {
    TempFile f(std::string("profile spc3\n") + cpu +
               "slave address=7\nfdl_status\nsilence 1\nsilence 100us\nsilence 1\n");
    std::ofstream(f.dir() / "fw.ihx") << ":030000008480FDFC\n:00000001FF\n";
    const FileRun r = run_file(f.path());
    EXPECT_EQ(r.code, 0) << cpu;
    const auto has = [&](const std::string& line) {
      return std::find(r.walk.begin(), r.walk.end(), line) != r.walk.end();
    };
    EXPECT_TRUE(has("[cycle       1056] 2 -> 7 FDL_Status => no answer (x2, last at cycle 7424)"))
        << cpu;
    // The lines after it start where the one before ends: S, S + 1, S + 4 801.
    std::uint64_t s = 0;
    for (const std::string& l : r.walk) {
      if (l.ends_with("line 5: silence 1")) s = std::stoull(l.substr(7, 10));
    }
    ASSERT_NE(s, 0u) << cpu;
    EXPECT_TRUE(has(fmt::format("[cycle {:>10}] line 6: silence 100us", s + 1))) << cpu;
    EXPECT_TRUE(has(fmt::format("[cycle {:>10}] line 7: silence 1", s + 4801))) << cpu;
  }
}

// What the firmware sends on its UART reaches the walk (docs/cpu.md, "Serial port"). MOV SBUF,#41h
// (75h 99h 41h) in machine cycles [0,2) writes SBUF at the end of cycle 1 in mode 0 (SCON = 00h
// after reset); the manual: one full machine cycle between "write to SBUF" and SEND, then the 8
// bits one per machine cycle, TI as the last one ends: cycles 2..10, TI at the end of cycle 10,
// clock 132, chip cycle 264 at 24 MHz (5.5 us). Before, the character was lost.
TEST(ScenarioCpu51, TheSerialPortsCharactersReachTheWalk) {
  TempFile f("cpu 80c32 clock=24000000 firmware fw.ihx\nsilence 1ms\n");
  std::ofstream(f.dir() / "fw.ihx") << ":0500000075994180FE2E\n:00000001FF\n";  // + SJMP $
  const FileRun r = run_file(f.path());
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(std::find(r.walk.begin(), r.walk.end(),
                      "[cycle        264] 80C32 serial port: sent 0x41 'A' at 5.500 us"),
            r.walk.end());
}

// The image's FILE.map gives the walk its code names (docs/cpu.md); a map beside it that names
// no code (not SDCC's, or cut short) is said on the walk's line of the board, and the run goes on.
TEST(ScenarioCpu51, AMapWithoutCodeSymbolsIsSaid) {
  TempFile f("cpu 80c32 firmware fw.ihx\nsilence 1ms\n");
  std::ofstream(f.dir() / "fw.ihx") << ":0300000002000BF0\n:00000001FF\n";  // LJMP 000Bh
  const auto board_line = [&] {
    std::string board;
    EXPECT_EQ(dpc31::run_scenario_file(
                  f.path(),
                  [&](const std::string& l) {
                    if (l.find("80C32 at 24000000 Hz") != std::string::npos) board = l;
                  },
                  [](const std::string&) {}),
              0);
    return board;
  };
  const std::string map = (f.dir() / "fw.map").string();
  std::ofstream(map) << "Area  Addr  Size\nC:   0000000B  _spin   fw\n";
  EXPECT_NE(board_line().find("(3 bytes, symbols from " + map + ")"), std::string::npos);
  std::ofstream(map) << "garbage\n\x01\x02 not a map\n";
  EXPECT_NE(board_line().find("(3 bytes, no code symbols in " + map +
                              " (no SDCC 'C:' line): code addresses unnamed)"),
            std::string::npos)
      << board_line();
}

// A FILE.map that is there but cannot be read (a directory, a dangling link) is the run's one
// error, SCENARIO:LINE: FILE: reason, exit 2, as an unreadable image is (docs/cpu.md): it was
// skipped in silence, the code names gone without a word.
TEST(ScenarioCpu51, AMapThatCannotBeReadIsRefused) {
  TempFile f("cpu 80c32 firmware fw.ihx\nsilence 1ms\n");
  std::ofstream(f.dir() / "fw.ihx") << ":0300000002000BF0\n:00000001FF\n";  // LJMP 000Bh
  const auto refused = [&](const std::string& why) {
    const FileRun r = run_file(f.path());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.errors, std::vector<std::string>{f.path() + ":1: " + (f.dir() / "fw.map").string() +
                                                 ": " + why});
    EXPECT_TRUE(r.walk.empty());
  };
  std::filesystem::create_directory(f.dir() / "fw.map");
  refused("is a directory, not a SDCC map file");
  std::filesystem::remove(f.dir() / "fw.map");
  std::filesystem::create_symlink(f.dir() / "gone.map", f.dir() / "fw.map");
  refused("a symbolic link to a missing file");
  // A FIFO (opening it would wait for a writer) and a link to a device are refused unopened.
  std::filesystem::remove(f.dir() / "fw.map");
  ASSERT_EQ(::mkfifo((f.dir() / "fw.map").c_str(), 0600), 0);
  refused("not a regular file, not a SDCC map file");
  std::filesystem::remove(f.dir() / "fw.map");
  std::filesystem::create_symlink("/dev/zero", f.dir() / "fw.map");
  refused("not a regular file, not a SDCC map file");
}

// What the heap grew by from a run's start to its end (the hooks: the runner still holds what it
// kept) with `head`, then `steps` steps `step` (formatted with the step's number), then `tail`
// (formatted with the last one), whose expects must all pass.
std::int64_t heap_grown_over_steps(const std::string& head, const std::string& step, int steps,
                                   const std::string& tail) {
  std::string text = head;
  for (int i = 0; i < steps; ++i) text += fmt::format(fmt::runtime(step), i);
  text += fmt::format(fmt::runtime(tail), steps - 1);
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  std::int64_t at_start = 0;
  std::int64_t grown = 0;
  dpc31::ScenarioHooks hooks;
  hooks.at_start = [&](dpc31::Chip&) { at_start = dpc31::test::heap_in_use(); };
  hooks.at_end = [&](dpc31::Chip&) { grown = dpc31::test::heap_in_use() - at_start; };
  Lines errors;
  const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, {}, errors.sink(), hooks);
  EXPECT_TRUE(o.ok()) << (errors.lines.empty() ? "" : errors.lines.front());
  EXPECT_EQ(o.failed, 0u);
  EXPECT_GT(o.passed, 0u);
  return grown;
}

// The heap grows no more (within 16 KiB) over 200 steps of `step` than over 20 of them.
void expect_flat_over_exchanges(const std::string& head, const std::string& step,
                                const std::string& tail) {
  const std::int64_t short_run = heap_grown_over_steps(head, step, 20, tail);
  const std::int64_t long_run = heap_grown_over_steps(head, step, 200, tail);
  if (dpc31::test::kHeapCounted) {
    EXPECT_LE(long_run, short_run + 16 * 1024)
        << "grown by " << short_run << " bytes over 20 steps, " << long_run << " over 200";
  }
}

// Issue 30: the built-in responder kept every fetch of the outputs and every ISR entry for the
// whole run (about 100 bytes an exchange). The heap's growth over 200 steps of `exchange 100` is
// within 16 KiB of that over 20 of them; the leak made about 1.6 MB of these 18 000 more
// exchanges. The expects still read the last fetch and what the ISR saw. ASan's allocator is not
// malloc's: there only the run.
TEST(ScenarioRun, LongRunKeepsTheResponderFlat) {
  const std::string head =
      "profile spc3\nbaud 12000000\nslave address=5 cfg=13,23 in=4 out=4\n"
      "user user_wd=1\nstartup\n";  // Res_User_WD on every DX_Out: Data_Exchange stays
  const std::string step = "exchange 100 outputs={:02X},2,3,4\n";
  const std::string tail =
      "expect outputs {:02X},02,03,04\nexpect cleared 0\nexpect irr_bit DX_Out 1\n";
  expect_flat_over_exchanges(head, step, tail);
}

// The same with a firmware instead of the built-in user side: its host recorded every ISR entry
// (16 bytes each), which the runner folds into what `expect irr_bit` reads and then forgets.
TEST(ScenarioRun, LongRunKeepsTheFirmwareHostFlat) {
  const std::string head =
      "profile spc3\nbaud 12000000\nfirmware DO4\nslave address=5 user_prm=00,00,00,00\n"
      "startup\n";
  const std::string step = "exchange 100 outputs={:02X},01\n";  // DO4: outputs, OSPValid
  const std::string tail = "expect dp_state Data_Exchange\nexpect irr_bit DX_Out 1\n";
  expect_flat_over_exchanges(head, step, tail);
}

// One long action: the runner kept every X/INT activation of the action for `expect irq` (16
// bytes each); it keeps the first 16 and those its expects name, and counts the rest. The heap
// grows no more (within 16 KiB) over one `exchange 20000` than over one `exchange 2000`.
TEST(ScenarioRun, ALongActionKeepsItsIrqRecordsFlat) {
  const std::string head =
      "profile spc3\nbaud 12000000\nslave address=5 cfg=13,23 in=4 out=4\nuser user_wd=1\n"
      "startup\n";
  const std::int64_t short_run = heap_grown_over_steps(head, "exchange 2000 outputs=01,02,03,04\n",
                                                       1, "expect irq count 2000\n");
  const std::int64_t long_run = heap_grown_over_steps(head, "exchange 20000 outputs=01,02,03,04\n",
                                                      1, "expect irq count 20000\n");
  if (dpc31::test::kHeapCounted) {
    EXPECT_LE(long_run, short_run + 16 * 1024)
        << "grown by " << short_run << " bytes over 2 000 exchanges, " << long_run
        << " over 20 000";
  }
}

}  // namespace

// No silent options (docs/decisions.md): an option the chosen profile has nothing for is refused
// at its line, whichever order the headers come in.
TEST(ScenarioParse, OptionsWithoutEffectOnTheProfileAreRefused) {
  const std::string dpc31_only = "startup\n";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"profile spc3\nirq-controller external\n" + dpc31_only,
       "t.scn:2: 'irq-controller' is for profile dpc31: only the DPC31 has a C31 core"},
      {"irq-controller external\nprofile vpc3plus\n" + dpc31_only,
       "t.scn:1: 'irq-controller' is for profile dpc31: only the DPC31 has a C31 core"},
      {"profile spc3\nuser substitute=01,02\n" + dpc31_only,
       "t.scn:2: user substitute= is for profile dpc31: only the DPC31 has the clear buffer C"},
      {"user dx_out_port=1\nprofile vpc3plus\n" + dpc31_only,
       "t.scn:1: user dx_out_port= is for profile dpc31: only the DPC31 has "
       "C31_Control.Enable_DX_Out_Port"},
      {"profile dpc31\nuser user_wd_value=5\n" + dpc31_only,
       "t.scn:2: user user_wd_value= needs user_wd=1 on profile dpc31: the DPS_User_Watchdog "
       "loads R_User_WD_Value only through its requests"},
      {"profile vpc3plus\nslave wd_base=1ms\n" + dpc31_only,
       "t.scn:2: wd_base= on profile vpc3plus needs DPV1_Enable (user_prm byte 0 bit 7): without "
       "DPV1 the VPC3+ takes WD_Base from Mode_Reg0, not from Set_Prm"},
      {"profile vpc3plus\nstartup\nset_prm wd_base=10ms\n",
       "t.scn:3: wd_base= on profile vpc3plus needs DPV1_Enable (user_prm byte 0 bit 7): without "
       "DPV1 the VPC3+ takes WD_Base from Mode_Reg0, not from Set_Prm"},
  };
  for (const auto& [text, line] : refused) EXPECT_EQ(parse_error(text), line) << text;
  // The same options where the profile acts on them.
  for (const std::string ok :
       {"profile dpc31\nirq-controller external\n", "profile dpc31\nuser substitute=01,02\n",
        "profile dpc31\nuser dx_out_port=1\n", "profile dpc31\nuser user_wd=1 user_wd_value=5\n",
        "profile spc3\nuser user_wd_value=5\n", "profile spc3\nslave wd_base=1ms\n",
        "profile vpc3plus\nslave wd_base=1ms user_prm=80,00,00\n"}) {
    EXPECT_EQ(parse_error(ok + dpc31_only), "") << ok;
  }
}

// wd_base=10ms and user_prm byte 0 bit 2 (WD_Base, the 1 ms base) both drive Set_Prm byte 7 bit
// 2 (SPC3 Spec_User_Prm_Byte; VPC3+C p.53 DPV1_Status_1): the master sent the bit, the 10 ms
// asked for was dropped silently (audit s28 aud1, finding 3). Refused at the line that makes the
// contradiction (No silent options), whichever of the two a set_prm takes from the slave.
TEST(ScenarioParse, WdBaseTenMsAndUserPrmWdBaseBitAreRefusedTogether) {
  const std::string why =
      "wd_base=10ms contradicts user_prm byte 0 bit 2 (WD_Base: the 1 ms base): both are Set_Prm "
      "byte 7 bit 2; give one of them";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"profile vpc3plus\nslave address=5 user_prm=C4,00,00 wd_base=10ms wd=2,5\nstartup\n",
       "t.scn:2: " + why},
      {"profile spc3\nslave user_prm=04 wd_base=10ms\nstartup\n", "t.scn:2: " + why},
      {"profile spc3\nslave wd_base=10ms\nstartup\nset_prm user_prm=04\n", "t.scn:4: " + why},
      {"profile spc3\nslave user_prm=04\nstartup\nset_prm wd_base=10ms\n", "t.scn:4: " + why},
  };
  for (const auto& [text, line] : refused) EXPECT_EQ(parse_error(text), line) << text;
  for (const std::string ok :
       {"profile spc3\nslave user_prm=04 wd_base=1ms\n", "profile spc3\nslave user_prm=04\n",
        "profile spc3\nslave user_prm=00 wd_base=10ms\n",
        "profile spc3\nslave wd_base=10ms\nstartup\nset_prm wd_base=1ms user_prm=04\n"}) {
    EXPECT_EQ(parse_error(ok + "startup\n"), "") << ok;
  }
}

// What a second line or another station would silently override is refused at its line: a
// header command given twice (its first line named), the master at the slave's address, inputs
// the chip would get cut or padded with stale bytes (both lengths named), a check of a pin the
// profile has not, a slot time outside the segment's range.
TEST(ScenarioParse, WhatWouldBeSilentlyOverriddenIsRefused) {
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"profile spc3\nprofile dpc31\nstartup\n", "t.scn:2: 'profile' given twice: first at line 1"},
      {"firmware DO4\n# again\nfirmware DO4\nstartup\n",
       "t.scn:3: 'firmware' given twice: first at line 1"},
      {"slave address=6\nslave address=7\nstartup\n",
       "t.scn:2: 'slave' given twice: first at line 1"},
      {"master address=5\nslave address=5\nstartup\n",
       "t.scn:2: the master and the slave both have address 5: each station needs its own"},
      {"slave address=9\nmaster address=9\nstartup\n",
       "t.scn:2: the master and the slave both have address 9: each station needs its own"},
      {"slave address=2\nstartup\n",
       "t.scn:1: the master and the slave both have address 2: each station needs its own"},
      {"user inputs=01,02,03,04,05,06\nstartup\n",
       "t.scn:1: user inputs=: 6 bytes for a slave with in=4: inputs are exactly in= bytes, or "
       "none"},
      {"user inputs=01,02,03,04,05,06\nslave in=2\nstartup\n",
       "t.scn:1: user inputs=: 6 bytes for a slave with in=2: inputs are exactly in= bytes, or "
       "none"},
      {"user inputs=A1,A2,A3,A4\nstartup\ninputs 01,02\n",
       "t.scn:3: inputs: 2 bytes for a slave with in=4: inputs are exactly in= bytes, or none"},
      {"profile spc3\nexpect pb3 0\n", "t.scn:2: 'expect pb3' needs profile dpc31"},
      {"profile vpc3plus\nstartup\nexpect pb3 1\n", "t.scn:3: 'expect pb3' needs profile dpc31"},
      {"master slot=36\nstartup\n", "t.scn:1: slot 36 out of range (37..16383)"},
      {"master slot=16384\nstartup\n", "t.scn:1: slot 16384 out of range (37..16383)"},
      // The master always sends Set_Prm byte 7: '-' would silently be a byte 00 (a9 audit).
      {"slave user_prm=-\nstartup\n",
       "t.scn:1: user_prm=-: the master always sends byte 7 (user_prm=00 is that byte as 00); a "
       "Set_Prm of 7 bytes is 'set_prm bytes=BYTES'"},
      {"startup\nset_prm user_prm=-\n",
       "t.scn:2: user_prm=-: the master always sends byte 7 (user_prm=00 is that byte as 00); a "
       "Set_Prm of 7 bytes is 'set_prm bytes=BYTES'"},
      // A DPV1 check on a chip without DPV1 is refused as the DPV1 actions are, not a run whose
      // check cannot pass.
      {"profile spc3\nstartup\nexpect dpv1 sc\n",
       "t.scn:3: 'expect dpv1' needs 'profile vpc3plus': DPV1 is modelled on the VPC3+ only (the "
       "DPC31's is not modelled; the SPC3 has none)"},
      {"profile dpc31\nstartup\nexpect dpv1 polls 1\n",
       "t.scn:3: 'expect dpv1' needs 'profile vpc3plus': DPV1 is modelled on the VPC3+ only (the "
       "DPC31's is not modelled; the SPC3 has none)"},
  };
  for (const auto& [text, line] : refused) EXPECT_EQ(parse_error(text), line) << text;
  for (const std::string ok :
       {"master address=5\nslave address=6\n", "slave in=2\nuser inputs=01,02\ninputs -\n",
        "user inputs=-\ninputs 01,02,03,04\n", "profile dpc31\nexpect pb3 0\n", "master slot=37\n",
        "master slot=16383\n", "slave user_prm=00\n", "profile vpc3plus\nexpect dpv1 sc\n",
        "profile vpc3plus\nslave user_prm=C0,00,00\nrecord slot=1 index=1 data=01\n"
        "record slot=1 index=2 data=02\n"}) {
    EXPECT_EQ(parse_error(ok + "startup\n"), "") << ok;
  }
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

namespace {

// Every event of a run as the observer is told it: (cycle, text), in the walk's order.
struct EveryEvent : dpc31::ScenarioObserver {
  std::vector<std::pair<std::uint64_t, std::string>> events;
  void user_side_started(std::uint64_t cycle, std::string_view, std::string_view text) override {
    events.emplace_back(cycle, text);
  }
  void step_begins(std::uint64_t cycle, const dpc31::ScenarioStep&,
                   std::string_view text) override {
    events.emplace_back(cycle, text);
  }
  void expect_checked(std::uint64_t cycle, const dpc31::ScenarioStep&, bool,
                      std::string_view text) override {
    events.emplace_back(cycle, text);
  }
  void walk_note(std::uint64_t cycle, std::string_view text) override {
    events.emplace_back(cycle, text);
  }
};

// `text` run with its walk in `walk`; the walk's folds undone must give the observer's events,
// each fold line at the cycle of the first line it folds and naming the cycle of the last.
// Returns the number of fold lines.
std::size_t run_folded(const std::string& text, Lines& walk) {
  dpc31::Scenario s;
  dpc31::ScenarioError err;
  EXPECT_TRUE(dpc31::parse_scenario(text, "t.scn", s, err)) << err.text();
  EveryEvent all;
  dpc31::run_scenario(s, walk.sink(), {}, dpc31::ScenarioHooks{{}, {}, &all, {}});
  std::vector<std::pair<std::uint64_t, std::string>> unfolded;
  std::size_t folds = 0;
  // The first line is the header, the last the end (neither is told to an observer).
  for (std::size_t i = 1; i + 1 < walk.lines.size(); ++i) {
    const std::string& l = walk.lines[i];
    const std::uint64_t cycle = std::stoull(l.substr(7));
    const std::string body = l.substr(l.find("] ") + 2);
    std::size_t k = 0, repeats = 0;
    std::uint64_t last = 0;
    int used = 0;
    if (std::sscanf(body.c_str(), "the line above repeated (x%zu, last at cycle %" SCNu64 ")%n",
                    &repeats, &last, &used) == 2 &&
        static_cast<std::size_t>(used) == body.size()) {
      k = 1;
    } else if (std::sscanf(body.c_str(),
                           "the %zu lines above repeated (x%zu, last at cycle %" SCNu64 ")%n", &k,
                           &repeats, &last, &used) != 3 ||
               static_cast<std::size_t>(used) != body.size()) {
      unfolded.emplace_back(cycle, body);
      continue;
    }
    ++folds;
    const std::size_t from = unfolded.size();
    for (std::size_t r = 0; r < repeats * k; ++r) {
      if (from + r >= all.events.size() || from < k) break;
      EXPECT_EQ(all.events[from + r].second, unfolded[from - k + r % k].second) << l;
      unfolded.push_back(all.events[from + r]);
    }
    EXPECT_EQ(unfolded.at(from).first, cycle) << l;
    EXPECT_EQ(unfolded.back().first, last) << l;
  }
  EXPECT_EQ(unfolded, all.events);
  return folds;
}

}  // namespace

// A start-up that cannot succeed (a wrong Ident_Number) sends Set_Prm, Chk_Cfg and Slave_Diag
// up to `tries` (1000) times, with the chip's remarks on each; a restart against a wrong cfg
// polls Slave_Diag 1000 times. Each run is its first occurrence and one line with the count and
// the repeats' cycles: 35 and 33 lines where they were 4021 and 1031, the counts exact.
TEST(ScenarioWalk, RepeatedRunsAreFoldedWithExactCounts) {
  Lines prm;
  EXPECT_EQ(run_folded("profile spc3\nbaud 12000000\nslave address=5\nstartup\n"
                       "set_prm ident=0x1234\nstartup\n",
                       prm),
            2u);
  EXPECT_LE(prm.lines.size(), 40u);
  // 332 rounds while the chip's log still remarks (its 1000 lines), 668 after.
  EXPECT_TRUE(prm.has("] the 6 lines above repeated (x331, last at cycle "));
  EXPECT_TRUE(prm.has("] the 3 lines above repeated (x667, last at cycle "));
  Lines cfg;
  EXPECT_EQ(run_folded("profile spc3\nbaud 12000000\nslave address=5 in=4 out=4\nstartup\n"
                       "chk_cfg cfg=13,22\nrestart\n",
                       cfg),
            1u);
  EXPECT_LE(cfg.lines.size(), 40u);
  EXPECT_TRUE(cfg.has("2 -> 5 Slave_Diag => DL 06 0D 00 FF 0C 31"));
  EXPECT_TRUE(cfg.has("] the line above repeated (x999, last at cycle "));
  // A run that comes only twice is written as it is.
  Lines two;
  EXPECT_EQ(run_folded("profile spc3\nbaud 12000000\nstartup\nexchange 2\n", two), 0u);
}

// What the chip's log limiter still owes when the run ends (docs/decisions.md, "Logs that never
// flood": a repeat is counted and said when another line comes, or at the end) is in the walk,
// before its end line: three foreign Set_Prms in a row are one remark and its two repeats, at the
// second and third request's spacing. The flood's lines past the window's 1000 are said too.
TEST(ScenarioWalk, TheChipsOwedLogLinesComeBeforeTheEnd) {
  Lines walk;
  run_folded(
      "profile dpc31\nbaud 1500000\nmaster address=2\nslave address=5\nstartup\n"
      "foreign_master address=3\nforeign_master address=3\nforeign_master address=3\n",
      walk);
  const auto cycle_of = [&](const std::string& text) -> std::uint64_t {
    for (const std::string& l : walk.lines)
      if (l.find(text) != std::string::npos) return std::stoull(l.substr(7));
    ADD_FAILURE() << "no line with " << text;
    return 0;
  };
  const std::uint64_t remark = cycle_of("] chip: Set_Prm from master 3 while locked by 2: ignored");
  const std::uint64_t spacing = cycle_of("] line 7: ") - cycle_of("] line 6: ");
  ASSERT_GE(walk.lines.size(), 2u);
  const std::string& owed = walk.lines[walk.lines.size() - 2];
  EXPECT_EQ(owed.substr(owed.find("] ") + 2),
            fmt::format("chip: last line repeated 2 times, cycles {} to {}", remark + spacing,
                        remark + 2 * spacing));
  EXPECT_EQ(std::stoull(owed.substr(7)), std::stoull(walk.lines.back().substr(7)));
  EXPECT_NE(walk.lines.back().find("] end: "), std::string::npos);

  Lines prm;
  run_folded(
      "profile spc3\nbaud 12000000\nslave address=5\nstartup\nset_prm ident=0x1234\nstartup\n",
      prm);
  EXPECT_TRUE(prm.has(" log lines left out (at most 1000 in 48000000 cycles)"));
}
