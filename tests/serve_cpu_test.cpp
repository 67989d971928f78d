// `dpc31 serve --cpu` (docs/protocol.md, "A CPU on the bus"): the real binary with an Intel HEX
// image on an 80C32 beside the chip or on the DPC31's C31; the test plays the DP master through
// the line commands only. Expected cycles by hand: docs/timing.md (the line), docs/cpu.md (MOVX
// timing, INT0's sampling) and the firmware's own derivation (traces/do4_80c32.scn's comments,
// tests/mcs51/board/c31_ack.asm's machine cycles in brackets).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "dpc31/fdl.hpp"
#include "run_command.hpp"
#include "serve_client.hpp"
#include "test_files.hpp"

using namespace testutil;

namespace {

const std::string kCli = DPC31_CLI;
const std::string kDo4 = std::string(FW51_DIR) + "/do4_80c32.ihx";
const std::string kC31Ack = std::string(BOARD_DIR) + "/c31_ack.ihx";

constexpr std::uint64_t T = 4;  // 12 Mbaud at 48 MHz: the rate the chip hears first after Start

bool has(const std::vector<std::string>& lines, const std::string& line) {
  return std::find(lines.begin(), lines.end(), line) != lines.end();
}

// `dpc31 serve --cpu 80C32:24000000` on an SPC3 running an Intel HEX image (its text), with one
// client; shut down cleanly at the end. The part's name as the docs spell it: --cpu is
// case-insensitive, as --firmware (the s35 audit, finding 7).
class ImageServer {
  TempDir dir_;
  std::string sock_ = dir_.file("chip.sock");
  std::string image_ = dir_.file("fw.ihx");
  bool written_;

 public:
  explicit ImageServer(const std::string& image)
      : written_(static_cast<bool>(std::ofstream(image_) << image)),
        server(kCli, {"--unix", sock_, "--profile", "spc3", "--cpu", "80C32:24000000", "--firmware",
                      image_}),
        client(LineClient::unix_socket(sock_)) {
    EXPECT_TRUE(written_);
  }
  ImageServer(const ImageServer&) = delete;
  ImageServer& operator=(const ImageServer&) = delete;
  ~ImageServer() {
    EXPECT_EQ(client.command("shutdown"), "OK shutdown");
    EXPECT_EQ(server.wait_exit(5000), 0);
  }
  ServerProcess server;
  LineClient client;
};

// The client as DP master: requests with inject_fdl, time with step, answers from the
// `! telegram ... tx` lines.
class LineMaster {
 public:
  explicit LineMaster(LineClient& c) : c_(c) {}
  std::string ok(const std::string& line) {
    const std::string r = c_.command(line);
    EXPECT_TRUE(starts_with(r, "OK")) << line << " -> " << r;
    return r.size() > 3 ? r.substr(3) : std::string();
  }
  // One SRD request to station 7 from master 2 (FCV set, FCB alternating from 1); returns the
  // answer's hex ("" for none). Checks the answer's place on the line (docs/timing.md: request
  // END + MinTSDR = 11 bit times).
  std::string transact(std::optional<std::uint8_t> dsap, const std::string& du) {
    fcb_ = !fcb_;
    std::string line = fmt::format("inject_fdl 7 2 {:#04x}", fcb_ ? 0x7D : 0x5D);
    if (dsap) line += fmt::format(" dsap={} ssap=62", *dsap);
    if (!du.empty()) line += " data=" + du;
    SCOPED_TRACE(line);
    const std::vector<std::string> r = words(ok(line));
    EXPECT_EQ(r.size(), 2u);
    start = std::stoull(r.at(0));
    const std::uint64_t end = std::stoull(r.at(1));
    const std::size_t mark = c_.async.size();
    ok(fmt::format("step {}", end + 100 * T - std::stoull(ok("cycle"))));
    for (std::size_t i = mark; i < c_.async.size(); ++i) {
      const std::vector<std::string> w = words(c_.async[i]);
      if (w.size() == 6 && w[1] == "telegram" && w[4] == "tx") {
        EXPECT_EQ(std::stoull(w[2]), end + 11 * T);
        EXPECT_EQ(std::stoull(w[3]), std::stoull(w[2]) + w[5].size() / 2 * 11 * T);
        return w[5];
      }
    }
    return {};
  }
  void wait_ms(unsigned ms) { ok(fmt::format("step {}", ms * 48'000u)); }
  std::uint64_t start = 0;  // the last request's first start bit

 private:
  LineClient& c_;
  bool fcb_ = false;
};

// DO4 built by SDCC on the 80C32 (24 MHz, the SPC3 at XDATA 8000h, address switch 7) behind the
// socket: the client is the master only; the 80C32 is the firmware and the bus master.
TEST(ServeCpu, Do4OnThe80c32ReachesDataExchangeAndWritesItsOutputsOnTime) {
  TempDir dir;
  const std::string sock = dir.file("chip.sock");
  ServerProcess server(kCli, {"--unix", sock, "--profile", "spc3", "--cpu", "80c32:24000000",
                              "--firmware", kDo4, "--address", "7"});
  LineClient client = LineClient::unix_socket(sock);
  LineMaster m(client);
  EXPECT_EQ(client.command("info"),
            "OK protocol=2 profile=spc3 bus=intel clock_hz=48000000 bus_access_cycles=4 "
            "address_bits=11 cpu=80c32 cpu_hz=24000000 board_address=0x8000");
  // The client is no bus master now; the debugger's back door and the CPU's view stay.
  for (const char* refused :
       {"read 0x16", "write 0x16 1", "readblock 0 2", "writeblock 0 01", "load x"}) {
    EXPECT_TRUE(starts_with(client.command(refused), "ERR cpu ")) << refused;
  }
  EXPECT_EQ(client.command("cycle"), "OK 0");                          // nothing of that took time
  EXPECT_EQ(client.command("cpu_port 1"), "OK latch=0xff pins=0x07");  // the address switch
  EXPECT_TRUE(starts_with(client.command("cpu"), "OK core=80c32 hz=24000000 pc=0x0000 "));

  // DO4's set-up ends with Start_SPC3; it listens at 12 Mbaud for 20 ms from then.
  for (int ms = 0; ms < 50 && words(m.ok("status"))[1] != "started=1"; ++ms) m.wait_ms(1);
  ASSERT_EQ(words(m.ok("status"))[1], "started=1");

  // Set_Prm as traces/do4_80c32.scn's: Lock_Req + WD_On, watchdog 2 x 5 x 10 ms, MinTSDR 0,
  // ident 0D04, group 0, User_Prm 00 01 05 00 (OSP: replace with 0101b); Chk_Cfg 21 10 (2
  // output bytes, 1 input byte). The chip answers both with SC; DO4 checks them in its ISR
  // (1.35 ms for the Prm at 24 MHz, docs/cpu.md), so the master waits 5 ms after each.
  // Not parameterised yet: Station_Not_Ready, Prm_Req, no master (tests/bridge_test.py's
  // startup_do4, to station 7 here).
  EXPECT_EQ(m.transact(60, ""), "680B0B688287083E3C020500FF0D04A216");
  EXPECT_EQ(m.transact(61, "880205000D040000010500"), "E5");
  m.wait_ms(5);
  EXPECT_EQ(m.transact(62, "2110"), "E5");
  m.wait_ms(5);
  // Ready (status 1 00), WD_On (status 2 0C), locked by master 2, ident 0D04.
  EXPECT_EQ(m.transact(60, ""), "680B0B688287083E3C000C00020D04AA16");
  // The first Data_Exchange (outputs 00 00: OSPValid 0). DO4 has been in its OSP state since
  // the Prm: its terminals the replacement value 0101b (User_Prm byte 05), ModulOK 0, so the
  // input byte is 50h (terminals in bits 7..4, ModulOK in bit 0; tests/bridge_test.py's 51h for
  // 05 01). A DH answer (DO4's device diag changed) is fetched with a Slave_Diag, the block DO4
  // keeps (header 02, OSP 0).
  const std::string first = m.transact(std::nullopt, "0000");
  EXPECT_TRUE(first == "68040468020708506116" || first == "6804046802070A506316") << first;
  m.wait_ms(5);
  if (first == "6804046802070A506316") {
    EXPECT_EQ(m.transact(60, ""), "680D0D688287083E3C000C00020D040200AC16");
  }
  EXPECT_EQ(words(m.ok("status"))[2], "dp=Data_Exchange");

  // Outputs 0A 01 (traces/do4_80c32.scn's first exchange): 11 characters, DX_Out and X/INT
  // active at the last stop sample E = X + (11 x 11 - 1) T + T/2 (docs/timing.md). INT0 is
  // sampled at S5P2 of machine cycle m, chip cycle 24m + 20, the first m with 24m + 20 >= E;
  // the idle 80C32 polls it in m + 1, calls in m + 2 and m + 3, the vector starts in m + 4;
  // from it DO4's path to the latch MOVX of `outputs` is 1 034 machine cycles, modul_ok's 22
  // more, and a MOVX starting in M ends its WR strobe at chip cycle 24M + 36 (the scenario's
  // derivation, from SDCC's listing and the manual's opcode map).
  client.async.clear();
  const std::string dx = m.transact(std::nullopt, "0A01");
  EXPECT_TRUE(dx.size() == 20u && dx.starts_with("68040468020708")) << dx;
  m.wait_ms(5);
  const std::uint64_t e = m.start + (11 * 11 - 1) * T + T / 2;
  const std::uint64_t sampled = (e - 20 + 23) / 24;
  const std::uint64_t movx = sampled + 4 + 1034;
  EXPECT_TRUE(has(client.async, fmt::format("! irq {} 1", e)));
  EXPECT_TRUE(has(client.async, fmt::format("! port {} outputs 0x0a", 24 * movx + 36)));
  EXPECT_TRUE(has(client.async, fmt::format("! port {} modul_ok 0x01", 24 * (movx + 22) + 36)));
  EXPECT_EQ(m.ok("latch"), "outputs=0x0a modul_ok=0x01");
  // The 80C32 idles between interrupts (PCON.IDL), nothing in service.
  const std::string cpu = m.ok("cpu");
  EXPECT_NE(cpu.find(" in_service=0 idle=1 "), std::string::npos) << cpu;
  EXPECT_EQ(client.command("shutdown"), "OK shutdown");
  EXPECT_EQ(server.wait_exit(5000), 0);
}

// A firmware refreshing its outputs in a loop (MOV DPTR,#4000h [0,2); MOVX @DPTR,A [2 + 5k,
// 4 + 5k), INC A 1, SJMP 2) writes the latch every 5 machine cycles, 120 chip cycles at 24 MHz:
// the k-th write's WR ends at 24 x (2 + 5k) + 36 = 84 + 120k (docs/cpu.md, "MOVX timing"). One
// `step` of one second, 48 000 000 cycles, holds k = 0..399 999: the `! port` lines are bounded
// as the walk's and the bridge's (1 000 in 48 000 000 cycles, docs/decisions.md "Logs that never
// flood"), and one `! port_log` line says how many were left out. Unbounded, the 400 000 lines
// (some 10 MB) got the client dropped, replies and all, though it read all along.
TEST(ServeCpu, PortLinesAreBoundedAndTheClientKept) {
  ImageServer s(":07000000904000F00480FCB9\n:00000001FF\n");
  LineClient& client = s.client;
  EXPECT_EQ(client.command("step 48000000"), "OK 48000000");
  std::vector<std::string> ports;
  for (const std::string& l : client.async) {
    if (l.starts_with("! port")) ports.push_back(l);
  }
  ASSERT_EQ(ports.size(), 1001u);
  EXPECT_EQ(ports[0], "! port 84 outputs 0x00");
  EXPECT_EQ(ports[999], "! port 119964 outputs 0xe7");  // k = 999
  EXPECT_EQ(ports[1000],
            "! port_log 48000000 399000 log lines left out (at most 1000 in 48000000 cycles)");
  EXPECT_EQ(client.command("ping"), "OK pong");
}

// `reset` under --cpu is the board's RESET, CPU and chip together at the chip's cycle
// (docs/protocol.md, "A CPU on the bus"; Cpu51Board.TheBoardsResetStartsCpuAndChipAtItsInstant-
// AndEndsAPowerDown derives the image's cycles): MOV DPTR,#4000h; INC 30h; MOV A,30h; MOVX
// @DPTR,A writes `outputs` at 24 x 4 + 36 = 132, then ORL PCON,#02h powers down for good. After
// `step 48000` (machine cycle 2 000, a boundary) the reset starts the CPU there, RAM kept:
// `outputs` = 2 at 24 x 2 004 + 36 = 48 132. Before, `reset` was refused and the power-down never
// ended.
TEST(ServeCpu, ResetStartsTheBoardAgain) {
  ImageServer s(":0D0000009040000530E530F043870280FE9F\n:00000001FF\n");
  LineClient& client = s.client;
  EXPECT_EQ(client.command("step 48000"), "OK 48000");
  EXPECT_EQ(client.command("reset"), "OK 48000");
  EXPECT_TRUE(starts_with(client.command("cpu"), "OK core=80c32 hz=24000000 pc=0x0000 "));
  EXPECT_EQ(client.command("step 48000"), "OK 96000");
  EXPECT_EQ(client.async,
            (std::vector<std::string>{"! port 132 outputs 0x01", "! port 48132 outputs 0x02"}));
}

// The serial port's characters reach the client (docs/protocol.md, `! serial`): MOV SBUF,#41h
// in mode 0 sets TI at the end of machine cycle 10, chip cycle 264 at 24 MHz
// (ScenarioCpu51.TheSerialPortsCharactersReachTheWalk derives it from the manual).
TEST(ServeCpu, SerialCharactersReachTheClient) {
  ImageServer s(":0500000075994180FE2E\n:00000001FF\n");
  EXPECT_EQ(s.client.command("step 1000"), "OK 1000");
  EXPECT_TRUE(has(s.client.async, "! serial 264 0x41"));
}

// The DPC31's C31 running tests/mcs51/board/c31_ack.asm (24 MHz, code area 1000h): its MOVX
// strobes end at chip cycles 156, 324, 564, 732, 852 (clocks 78, 162, 282, 366, 426, docs/cpu.md);
// the C31's interrupt is raised at the second and acknowledged at the third, `! irq` lines of
// the controller the bus reaches (the C31's). A debugger's poke into the code area before it
// runs is its program: the operand of `mov a,#0xef` (code 0033h, chip 1034h) poked to E0h, and
// the C31 writes E0h to Int_Mask_Reg (User_Timer_Clock still unmasked). Its `cpu` registers:
// A = 77h from the rewritten instruction.
TEST(ServeCpu, C31RunsFromTheChipsRamBehindTheSocket) {
  TempDir dir;
  const std::string sock = dir.file("chip.sock");
  ServerProcess server(kCli, {"--unix", sock, "--profile", "dpc31", "--cpu", "c31", "--firmware",
                              kC31Ack, "--code", "0x1000"});
  LineClient client = LineClient::unix_socket(sock);
  EXPECT_EQ(client.command("info"),
            "OK protocol=2 profile=dpc31 irq_controller=c31 bus=intel clock_hz=48000000 "
            "bus_access_cycles=4 address_bits=13 cpu=c31 cpu_hz=24000000 code=0x1000");
  EXPECT_EQ(client.command("peek 0x1000"), "OK 0x02");  // LJMP start: the image in the area
  EXPECT_EQ(client.command("peek 0x1034"), "OK 0xef");
  EXPECT_EQ(client.command("poke 0x1034 0xe0"), "OK");
  EXPECT_TRUE(starts_with(client.command("latch"), "ERR no_cpu "));
  // The interrupt goes active with the MOVX's strobe at 324: the reply comes when that CPU step
  // has ended, at most its second machine cycle later (24 chip cycles); the edge is exact.
  const std::vector<std::string> irq = words(client.command("run_until_irq 1000"));
  ASSERT_EQ(irq.size(), 3u);
  EXPECT_EQ(irq[1], "irq");
  EXPECT_GE(std::stoull(irq[2]), 324u);
  EXPECT_LE(std::stoull(irq[2]), 336u);
  EXPECT_EQ(client.async, (std::vector<std::string>{"! irq 324 1"}));
  // The C31 is in `sjmp .` (2 machine cycles from 36 on): the step ends with the CPU's step in
  // progress, at most a couple of machine cycles (24 chip cycles each) beyond 1000.
  const std::vector<std::string> stepped = words(client.command("step 676"));
  ASSERT_EQ(stepped.size(), 2u);
  EXPECT_GE(std::stoull(stepped[1]), 1000u);
  EXPECT_LT(std::stoull(stepped[1]), 1000u + 2 * 24);
  EXPECT_EQ(client.async, (std::vector<std::string>{"! irq 324 1", "! irq 564 0"}));
  // Int_Mask_Reg on the dpc31: reset FFFFh, bits 15:14 and 7:6 reserved (regs/dpc31_regs.json,
  // docs/registers.md); E0h written to the low byte: 3F20h (EFh would give 3F2Fh).
  EXPECT_EQ(client.command("peek_reg Int_Mask_Reg"), "OK 0x3f20");
  EXPECT_EQ(client.command("peek 0x1047"), "OK 0x77");  // the C31's own rewrite of `patch`
  EXPECT_EQ(client.command("peek 0x08a0"), "OK 0x77");  // A, fetched from the rewrite
  const std::string cpu = client.command("cpu");
  EXPECT_TRUE(starts_with(cpu, "OK core=c31 hz=24000000 pc=0x")) << cpu;
  EXPECT_NE(cpu.find(" a=0x77 "), std::string::npos) << cpu;
  EXPECT_NE(cpu.find(" in_service=0 "), std::string::npos) << cpu;
}

// No CPU: its commands say so; the CPU's options without --cpu, and bad ones, exit 2 with one
// line (a broken image: FILE:LINE from the Intel HEX parser).
TEST(ServeCpu, BadCpuOptionsExit2WithOneLine) {
  TempDir dir;
  {
    ServerProcess plain(kCli, {"--unix", dir.file("s")});
    LineClient c = LineClient::unix_socket(dir.file("s"));
    for (const char* cmd : {"cpu", "cpu_port 1", "latch"}) {
      EXPECT_TRUE(starts_with(c.command(cmd), "ERR no_cpu ")) << cmd;
    }
  }
  const std::string broken = dir.file("broken.ihx");
  std::ofstream(broken) << ":0100000000FF\n:0300000002003\n";  // line 2: odd length
  const std::string sock = dir.file("t");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--cpu", "8051", "--firmware", kDo4}, "--cpu '8051' must be 80c32[:HZ] or c31[:HZ]"},
      {{"--cpu", "80c32:99000000", "--firmware", kDo4}, "--cpu '80c32:99000000' must be"},
      {{"--cpu", "80c32"}, "--cpu needs --firmware"},
      {{"--firmware", kDo4}, "--firmware needs --cpu"},
      {{"--cpu", "80c32", "--firmware", broken}, broken + ":2: "},
      {{"--cpu", "80c32", "--firmware", dir.file("none.ihx")}, dir.file("none.ihx")},
      {{"--cpu", "c31", "--firmware", kC31Ack, "--profile", "spc3"},
       "--cpu c31 is for --profile dpc31"},
      {{"--cpu", "c31", "--firmware", kC31Ack, "--irq-controller", "external"},
       "--irq-controller external contradicts it"},
      {{"--cpu", "c31", "--firmware", kC31Ack, "--code", "0x800"}, "--code '0x800' must be"},
      {{"--cpu", "80c32", "--firmware", kDo4, "--code", "0x1000"}, "--code is the C31's"},
      {{"--cpu", "80c32", "--firmware", kDo4, "--board-address", "0x3800"},
       "covers the output latch"},
      {{"--cpu", "80c32", "--firmware", kDo4, "--ports", "a,a"},
       "--ports 'a,a': port 'a' named twice"},
  };
  for (const auto& [args, want] : cases) {
    std::string line = kCli + " serve --unix " + sock;
    for (const std::string& a : args) line += " '" + a + "'";
    const CommandResult r = run_command(line + " 2>&1");
    EXPECT_EQ(r.rc, 2) << line;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_NE(r.out.find("dpc31 serve: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(want), std::string::npos) << r.out;
  }
}

}  // namespace
