// Waveforms of chip runs: the exact VCD of a known bus write, the signal/window selection, and
// the real outside tools: sigrok-cli decodes our RxD/TxD as 8E1 UART into exactly the telegram
// bytes, gtkwave's vcd2fst and fst2vcd accept our VCD and FST.
#include "waveform.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "responder.hpp"
#include "run_command.hpp"
#include "test_files.hpp"

using namespace dpc31;

namespace {

using testutil::slurp;

using Cmd = testutil::CommandResult;

Cmd sh(const std::string& cmd) { return testutil::run_command(cmd + " 2>&1"); }

std::string tmp(const std::string& name) { return testutil::scratch() + name; }

struct Line {
  std::string rx;  // every byte the master put on RxD (answered or not)
  std::string tx;  // every byte the chip put on TxD
};

// A start-up at 1.5 Mbaud with a recorder attached; returns the bytes on the line, one per line.
Line record_startup(const wave::Options& o) {
  Chip chip({Profile::dpc31, BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  ResponderConfig rc;
  Responder user(rc);
  user.set_inputs({0xA1, 0xA2, 0xA3, 0xA4});
  DirectBus bus(chip);
  user.init(bus);
  wave::Recorder rec(o);
  std::string error;
  EXPECT_TRUE(rec.attach(chip, error)) << error;
  Line line;
  chip.on_telegram([&](const Telegram& t) {
    for (std::uint8_t b : t.bytes) line.tx += t.from_chip ? fmt::format("{:02X}\n", b) : "";
  });
  DpMaster master(chip, MasterConfig{2, 1'500'000, 100, 33}, rc.slave);
  master.set_firmware([&](BusPort& b) { user.isr(b); });
  EXPECT_TRUE(master.startup());
  master.data_exchange({1, 2, 3, 4});
  EXPECT_TRUE(rec.finish(chip.cycle(), error)) << error;
  for (const Exchange& ex : master.history()) {
    for (std::uint8_t b : fdl::encode(ex.request)) line.rx += fmt::format("{:02X}\n", b);
  }
  return line;
}

}  // namespace

TEST(Waveform, ExactVcdOfABusWrite) {
  Chip chip({Profile::spc3, BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  wave::Options o;
  o.path = tmp("write.vcd");
  o.signals = {"bus.*"};
  wave::Recorder rec(o);
  std::string error;
  ASSERT_TRUE(rec.attach(chip, error)) << error;
  chip.write(0x04, 0xEF);  // IMR low byte: completes at cycle 4
  ASSERT_TRUE(rec.finish(chip.cycle(), error)) << error;
  // cycle 4 at 48 MHz = 83 333.3 ps -> 83333; the dump ends one cycle after the run (cycle 5,
  // 104 166.7 -> 104167), before the strobe falls.
  EXPECT_EQ(slurp(o.path),
            "$date dpc31emu $end\n$version dpc31emu 48 MHz clock $end\n$timescale 1ps $end\n"
            "$scope module dpc31 $end\n$scope module bus $end\n"
            "$var wire 1 $ rd $end\n$var wire 1 % wr $end\n$var wire 13 & addr $end\n$var wire 8 ' "
            "data $end\n"
            "$upscope $end\n$upscope $end\n$enddefinitions "
            "$end\n#0\n$dumpvars\n0$\n0%\nb0000000000000 &\n"
            "b00000000 '\n$end\n#83333\nb0000000000100 &\nb11101111 '\n1%\n#104167\n");
}

TEST(Waveform, OnlyTheSignalsAndWindowAskedFor) {
  wave::Options o;
  o.path = tmp("window.vcd");
  o.signals = {"state.dp_state", "pins.x_int"};
  o.from = 100'000;
  o.to = 120'000;
  record_startup(o);
  const std::string v = slurp(o.path);
  EXPECT_NE(v.find("dp_state"), std::string::npos);
  EXPECT_NE(v.find("x_int"), std::string::npos);
  EXPECT_EQ(v.find("rxd"), std::string::npos);
  EXPECT_EQ(v.find("irr"), std::string::npos);
  EXPECT_NE(v.find("#2083333333\n$dumpvars"), std::string::npos);  // cycle 100000: 2.083 ms
  std::string error;
  wave::Options bad = o;
  bad.signals = {"nosuch.*"};
  Chip chip;
  wave::Recorder rec(bad);
  EXPECT_FALSE(rec.attach(chip, error));
  EXPECT_EQ(error, "no signal matches 'nosuch.*' (see docs/waveforms.md)");
}

TEST(Waveform, SigrokDecodesTheTelegramBytes) {
  wave::Options o;
  o.path = tmp("uart.vcd");
  o.signals = {"pins.rxd", "pins.txd"};
  o.flat = true;
  o.timescale_exp = -8;  // 10 ns: a 1.5 Mbaud bit is 66.7 units
  const Line want = record_startup(o);
  ASSERT_GE(want.tx.size(), 60u);
  const auto decode = [&](const char* pin) {
    return sh(
        fmt::format("sigrok-cli -I vcd -i {} -P uart:rx={}:baudrate=1500000:parity=even:format=hex "
                    "-A uart=rx-data --protocol-decoder-samplenum 2>/dev/null | sed 's/^.* //'",
                    o.path, pin));
  };
  const Cmd rx = decode("rxd");
  ASSERT_EQ(rx.rc, 0) << rx.out;
  const Cmd tx = decode("txd");
  // sigrok prints one byte per line: the master's telegrams on RxD, the chip's on TxD.
  EXPECT_EQ(rx.out, want.rx);
  EXPECT_EQ(tx.out, want.tx);
}

TEST(Waveform, GtkwaveConvertersAcceptOurFiles) {
  wave::Options v;
  v.path = tmp("full.vcd");
  record_startup(v);
  wave::Options f = v;
  f.path = tmp("full.fst");
  f.fst = true;
  record_startup(f);
  const Cmd a = sh(fmt::format("vcd2fst {} {}", v.path, tmp("conv.fst")));
  EXPECT_EQ(a.rc, 0) << a.out;
  const Cmd b = sh(fmt::format("fst2vcd {}", f.path));
  ASSERT_EQ(b.rc, 0) << b.out;
  for (const char* name :
       {"rxd", "txd", "x_int", "dp_state", "wd_state", "baud_code", "irr", "dout_sm"}) {
    EXPECT_NE(b.out.find(name), std::string::npos) << name;
  }
  const Cmd c = sh(fmt::format("fst2vcd {}", tmp("conv.fst")));
  EXPECT_EQ(c.rc, 0) << c.out;
}
