// Waveforms of chip runs: the exact VCD of a known bus write, the signal/window selection, and
// the real outside tools: sigrok-cli decodes our RxD/TxD as 8E1 UART into exactly the telegram
// bytes, gtkwave's vcd2fst and fst2vcd accept our VCD and FST. Bad windows, patterns and units
// are refused; times grow, one value per signal and time; wavediff finds two units of a run equal.
#include "waveform.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "pvs.hpp"
#include "responder.hpp"
#include "run_command.hpp"
#include "scenario.hpp"
#include "test_files.hpp"
#include "wavediff.hpp"

using namespace dpc31;

namespace {

using testutil::slurp;

using Cmd = testutil::CommandResult;

Cmd sh(const std::string& cmd) { return testutil::run_command(cmd + " 2>&1"); }

std::string tmp(const std::string& name) { return testutil::scratch() + name; }

struct Line {
  std::string rx;  // every byte the master put on RxD (answered or not)
  std::string tx;  // every byte the chip put on TxD
  // The end of the last stop bit of the request the chip answered first (a cycle): the first
  // error-free telegram, which fixes the rate (docs/timing.md, Baud_Search).
  std::uint64_t first_answered_end = 0;
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
  std::uint64_t request_end = 0;
  chip.on_telegram([&](const Telegram& t) {
    for (std::uint8_t b : t.bytes) line.tx += t.from_chip ? fmt::format("{:02X}\n", b) : "";
    if (!t.from_chip) request_end = t.end;
    if (t.from_chip && line.first_answered_end == 0) line.first_answered_end = request_end;
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

// The waveform of an SPC3 at CLOCK_HZ (0: 48 MHz) that writes IMR's low byte, which completes at
// cycle 4, with the signals `pattern` matches.
std::string vcd_of_a_bus_write(std::uint32_t clock_hz, const std::string& file,
                               const std::string& pattern) {
  Chip chip({Profile::spc3, BusMode::intel, clock_hz});
  chip.set_log_sink(nullptr);
  wave::Options o;
  o.path = tmp(file);
  o.signals = {pattern};
  wave::Recorder rec(o);
  std::string error;
  EXPECT_TRUE(rec.attach(chip, error)) << error;
  chip.write(0x04, 0xEF);
  EXPECT_TRUE(rec.finish(chip.cycle(), error)) << error;
  return slurp(o.path);
}

}  // namespace

TEST(Waveform, ExactVcdOfABusWrite) {
  // cycle 4 at 48 MHz = 83 333.3 ps -> 83333; the dump ends one cycle after the run (cycle 5,
  // 104 166.7 -> 104167), before the strobe falls.
  EXPECT_EQ(vcd_of_a_bus_write(0, "write.vcd", "bus.*"),
            "$date dpc31emu $end\n$version dpc31emu 48 MHz clock $end\n$timescale 1ps $end\n"
            "$scope module dpc31 $end\n$scope module bus $end\n"
            "$var wire 1 $ rd $end\n$var wire 1 % wr $end\n$var wire 13 & addr $end\n$var wire 8 ' "
            "data $end\n"
            "$upscope $end\n$upscope $end\n$enddefinitions "
            "$end\n#0\n$dumpvars\n0$\n0%\nb0000000000000 &\n"
            "b00000000 '\n$end\n#83333\nb0000000000100 &\nb11101111 '\n1%\n#104167\n");
}

// A clock of no whole MHz is named exactly in the header; the times are round(cycle x 10^12 /
// 14 745 600) ps (docs/waveforms.md, --timescale): cycle 4 is 271 267.4 -> #271267, cycle 5
// 339 084.2 -> #339084. A unit coarser than its cycle (67.8 ns) names the same clock.
TEST(Waveform, AClockOfNoWholeMHzIsNamedExactly) {
  EXPECT_EQ(vcd_of_a_bus_write(14'745'600, "clock147456.vcd", "bus.wr"),
            "$date dpc31emu $end\n$version dpc31emu 14.7456 MHz clock $end\n$timescale 1ps "
            "$end\n$scope module dpc31 $end\n$scope module bus $end\n$var wire 1 % wr $end\n"
            "$upscope $end\n$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n0%\n$end\n"
            "#271267\n1%\n#339084\n");
  Chip chip({Profile::spc3, BusMode::intel, 14'745'600});
  wave::Options o;
  o.path = tmp("coarse147456.vcd");
  std::string error;
  o.timescale_exp = -7;  // 100 ns
  wave::Recorder coarse(o);
  EXPECT_FALSE(coarse.attach(chip, error));
  EXPECT_EQ(error, o.path +
                       ": timescale 100ns is longer than a clock cycle (67.8 ns at 14.7456 MHz): "
                       "use 10ns or finer");
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

// The save file of a window opens GTKWave on the window (docs/waveforms.md, "GTKWave"):
// [timestart] is --from's time, round(100 000 x 10^12 / 48 MHz) = 2 083 333 333 ps, and the zoom
// -log2((END - START) / 2) from the window's length: END is --to's time, 2 500 000 000 ps, so
// -log2(416 666 667 / 2) = -27.634318; no marker (no state change in the window), 26 times -1.
TEST(Waveform, TheSaveFileOfAWindowOpensOnTheWindow) {
  wave::Options o;
  o.path = tmp("window_gtkw.vcd");
  o.from = 100'000;
  o.to = 120'000;
  o.gtkw = tmp("window.gtkw");
  record_startup(o);
  std::istringstream in(slurp(o.gtkw));
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l) && lines.size() < 5;) lines.push_back(l);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[2], "[timestart] 2083333333");
  std::string none;
  for (int i = 0; i < 26; ++i) none += " -1";
  EXPECT_EQ(lines[3], "*-27.634318 -1" + none);
}

// GTKWave 3.3 counts a file's times in the unit's prefix: a 10 ns file's #1 is 10 (its ns), and
// a save file's times are read in those (docs/waveforms.md, "GTKWave"). A window of 10 ns units
// that ends where the baud search finds 1.5 Mbaud: the first error-free telegram, acted on at
// the stop sample of its last character, end - T + floor(T/2) with T = 48 MHz / 1.5 Mbaud = 32
// cycles, takes the watchdog to Baud_Control (docs/timing.md, Baud_Search and "acted on"): the
// one marker. A cycle's time is round(cycle x 10^8 / 48 MHz) units of 10 ns (docs/waveforms.md,
// --timescale); START and END are --from's and --to's, the zoom -log2((END - START) / 2).
TEST(Waveform, TheSaveFilesTimesAreGtkwavesAtTenNanoseconds) {
  wave::Options o;
  o.path = tmp("window_10ns.vcd");
  o.timescale_exp = -8;
  const std::uint64_t acted = record_startup(o).first_answered_end - 32 + 16;
  ASSERT_GT(acted, 1000u);
  o.from = acted - 1000;
  o.to = acted + 1;
  o.gtkw = tmp("window_10ns.gtkw");
  record_startup(o);
  const auto ns = [](std::uint64_t cycle) {
    return (cycle * 100'000'000 + 24'000'000) / 48'000'000 * 10;
  };
  std::istringstream in(slurp(o.gtkw));
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l) && lines.size() < 5;) lines.push_back(l);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[2], fmt::format("[timestart] {}", ns(o.from)));
  std::string rest;
  for (int i = 0; i < 25; ++i) rest += " -1";
  EXPECT_EQ(lines[3], fmt::format("*{:.6f} -1 {}{}",
                                  -std::log2(static_cast<double>(ns(o.to) - ns(o.from)) / 2.0),
                                  ns(acted), rest));
  EXPECT_EQ(lines[4], "[markername] Awd_state=Baud_Control");
}

// The PulseView session beside a logic-analyser VCD (docs/waveforms.md, "PulseView"): the keys
// PulseView 0.4.2 restores (DecodeSignal::restore_settings), the UART decoder's options as
// GlobalSettings::store_gvariant writes them (type string, serialised GVariant as a QByteArray in
// QSettings' INI escapes). 1 500 000 = 16E360h: int64 little-endian 60 E3 16 00 00 00 00 00 ->
// '`' (60h, printable), \xe3 (from 7Fh), \x16 (a control byte), five \0; "even" and its NUL.
// Channel 0 is the uart decoder's rx, 1 its tx; initial pin state 2 is
// SRD_INITIAL_PIN_SAME_AS_SAMPLE0. Tests/pulseview_check.py loads this in PulseView itself.
TEST(Waveform, APulseViewSessionStacksTheDecodersOnRxdAndTxd) {
  wave::Options o;
  o.path = tmp("session.vcd");
  o.flat = true;
  o.timescale_exp = -8;
  o.pvs = tmp("session.pvs");
  o.baud = 1'500'000;
  record_startup(o);
  const std::string head =
      "; dpc31emu: the UART decoder (8E1) and PROFIBUS DP stacked on it (docs/waveforms.md)\n"
      "[General]\ndecode_signals=1\n\n[decode_signal0]\nname=PROFIBUS DP\nenabled=true\n"
      "decoders=2\ndecoder0\\id=uart\ndecoder0\\visible=true\ndecoder0\\options=2\n"
      "decoder0\\option0\\name=baudrate\ndecoder0\\option0\\type=x\n"
      "decoder0\\option0\\value=@ByteArray(`\\xe3\\x16\\0\\0\\0\\0\\0)\n"
      "decoder0\\option1\\name=parity\ndecoder0\\option1\\type=s\n"
      "decoder0\\option1\\value=@ByteArray(even\\0)\n"
      "decoder1\\id=profibus_dp\ndecoder1\\visible=true\ndecoder1\\options=0\nchannels=2\n";
  EXPECT_EQ(slurp(o.pvs),
            head +
                "channel0\\assigned_signal_name=rxd\nchannel0\\initial_pin_state=2\n"
                "channel1\\assigned_signal_name=txd\nchannel1\\initial_pin_state=2\n");
  // Only TxD in the file: rx stays unassigned.
  o.signals = {"pins.txd", "pins.x_int"};
  record_startup(o);
  EXPECT_EQ(slurp(o.pvs),
            head +
                "channel0\\initial_pin_state=2\n"
                "channel1\\assigned_signal_name=txd\nchannel1\\initial_pin_state=2\n");
  // Neither: refused before the run, nothing written.
  o.signals = {"pins.x_int"};
  o.path = tmp("session_none.vcd");
  o.pvs = tmp("session_none.pvs");
  std::string error;
  EXPECT_FALSE(wave::Recorder(o).check_signals(error));
  EXPECT_EQ(error, o.pvs +
                       ": a PulseView session decodes pins.rxd or pins.txd (a segment's "
                       "line.level), and --signals leaves them out of " +
                       o.path);
  // PulseView reads a VCD in the logic-analyser form only, and the decoder needs the rate.
  o.signals.clear();
  o.flat = false;
  EXPECT_FALSE(wave::Recorder(o).open(error));
  EXPECT_EQ(error, o.pvs + ": a PulseView session is for a VCD in the logic-analyser form (flat)");
  o.flat = true;
  o.baud = 0;
  EXPECT_FALSE(wave::Recorder(o).open(error));
  EXPECT_EQ(error, o.pvs + ": a PulseView session needs the bus's baud rate");
  EXPECT_FALSE(std::ifstream(o.pvs).good());
  EXPECT_FALSE(std::ifstream(o.path).good());
}

// QSettings' INI escapes of the rate's bytes (qsettings.cpp, iniEscapedString): 500 000 =
// 7A120h -> 20 A1 07 00 ..: a space, \xa1, 07h as its named escape \a (no hex digit follows a
// named one); 12 544 = 3100h -> 00 31 00 ..: '1' (31h) right after \0 is a hex digit, escaped
// (\x31) so that it is not read as part of the escape; 59 = 3Bh: ';' would start a comment, so
// the value goes in quotes.
TEST(Waveform, APulseViewSessionsRateInQSettingsEscapes) {
  const auto rate = [](std::uint32_t baud) {
    const std::string s = wave::pulseview_session_text(baud, "rxd", "");
    const std::string key = "decoder0\\option0\\value=";
    const std::size_t at = s.find(key) + key.size();
    return s.substr(at, s.find('\n', at) - at);
  };
  EXPECT_EQ(rate(500'000), "@ByteArray( \\xa1\\a\\0\\0\\0\\0\\0)");
  EXPECT_EQ(rate(12'544), "@ByteArray(\\0\\x31\\0\\0\\0\\0\\0\\0)");
  EXPECT_EQ(rate(59), "\"@ByteArray(;\\0\\0\\0\\0\\0\\0\\0)\"");
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

// sigrok numbers samples from the file's first time (docs/waveforms.md): 0 for a whole run,
// --from's time in a window (cycle 1000: round(1000 x 10^8 / 48 MHz) = 2083 units of 10 ns), or
// from 0 with `-I vcd:skip=0`. uart's rx-data span starts one bit time after the start bit's
// falling edge (at 1.5 Mbaud 66.7 samples, 67 as sigrok places it: the first data bit).
TEST(Waveform, SigrokSampleNumbersCountFromTheFilesFirstTime) {
  wave::Options o;
  o.path = tmp("samples.vcd");
  o.signals = {"pins.txd"};
  o.flat = true;
  o.timescale_exp = -8;
  record_startup(o);
  wave::Options w = o;
  w.path = tmp("samples_window.vcd");
  w.from = 1000;
  record_startup(w);
  const auto first_span = [](const std::string& path, const char* input) {
    const Cmd r = sh(fmt::format(
        "sigrok-cli -I {} -i {} -P uart:rx=txd:baudrate=1500000:parity=even -A uart=rx-data "
        "--protocol-decoder-samplenum 2>/dev/null | head -1",
        input, path));
    EXPECT_EQ(r.rc, 0) << r.out;
    return std::stoull(r.out.substr(0, r.out.find('-')));
  };
  // The first 1 -> 0 of TxD in the whole file: the start bit of the chip's first answer.
  const std::string v = slurp(o.path);
  std::istringstream in(v.substr(v.find("$end\n#") + 5));
  std::uint64_t t = 0;
  std::uint64_t fall = 0;
  for (std::string line; fall == 0 && std::getline(in, line);) {
    if (line.starts_with("#")) t = std::stoull(line.substr(1));
    if (t > 0 && line.starts_with("0")) fall = t;
  }
  ASSERT_GT(fall, 0u);
  const std::uint64_t whole = first_span(o.path, "vcd");
  EXPECT_EQ(whole, fall + 67);
  EXPECT_EQ(first_span(w.path, "vcd"), whole - 2083);
  EXPECT_EQ(first_span(w.path, "vcd:skip=0"), whole);
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

namespace {

// The first thing in a VCD that a viewer would show wrongly: a time that does not grow, or a
// variable given two values at one time (GTKWave shows the last only). "" if none.
std::string vcd_time_problem(const std::string& vcd) {
  std::istringstream in(vcd.substr(vcd.find("$enddefinitions")));
  std::string line;
  long long last = -1;
  std::set<std::string> ids;
  while (std::getline(in, line)) {
    if (line.starts_with("#")) {
      const long long t = std::stoll(line.substr(1));
      if (t <= last) return fmt::format("#{} after #{}", t, last);
      last = t;
      ids.clear();
    } else if (!line.empty() && line[0] != '$') {
      const std::string id = line.substr(line[0] == 'b' ? line.find(' ') + 1 : 1);
      if (!ids.insert(id).second) return fmt::format("'{}' twice at #{}", id, last);
    }
  }
  return "";
}

}  // namespace

// A window that opens after the run's end: the values in force then, at the window's start, and
// no time before it after that (the end of the run was written after the dump, going backwards).
TEST(Waveform, AWindowAfterTheRunsEnd) {
  for (const bool fst : {false, true}) {
    wave::Options o;
    o.path = tmp(fst ? "late.fst" : "late.vcd");
    o.fst = fst;
    o.from = 99'999'999;  // 2.083 s; the start-up ends before 0.1 s
    record_startup(o);
    const Cmd v = sh("fst2vcd " + o.path);
    const std::string vcd = fst ? v.out : slurp(o.path);
    EXPECT_EQ(vcd_time_problem(vcd), "") << fst;
    EXPECT_NE(vcd.find("#2083333312500\n$dumpvars"), std::string::npos) << fst;
  }
}

// A time that does not fit in the 64 bits of a VCD or FST time is refused, not wrapped.
TEST(Waveform, ATimePast64BitsIsRefused) {
  Chip chip({Profile::spc3, BusMode::intel, 0});
  wave::Options o;
  o.path = tmp("wrap.vcd");
  o.from = 18'446'744'073'709'551'000u;
  wave::Recorder rec(o);
  std::string error;
  EXPECT_FALSE(rec.attach(chip, error));
  EXPECT_EQ(error, o.path +
                       ": cycle 18446744073709551000 is past the last time a waveform in units "
                       "of 1ps can hold");
  o.from = 885'000'000'000'000u;  // 2^64 ps is cycle 885 443 715 538 058
  wave::Recorder fits(o);
  EXPECT_TRUE(fits.attach(chip, error)) << error;
  o.from = 885'443'715'538'059u;
  wave::Recorder past(o);
  EXPECT_FALSE(past.attach(chip, error));
}

// pins.pb3 is a DPC31 port: on an SPC3 the pattern matches nothing (it gave an empty VCD, and an
// FST "on a full file system"); a waveform left without a variable is refused too.
TEST(Waveform, APatternMatchesTheChipsOwnSignals) {
  for (const bool fst : {false, true}) {
    wave::Options o;
    o.path = tmp(fst ? "pb3.fst" : "pb3.vcd");
    o.fst = fst;
    o.signals = {"pins.pb3"};
    std::string error;
    Chip spc3({Profile::spc3, BusMode::intel, 0});
    wave::Recorder rec(o);
    EXPECT_TRUE(rec.check_signals(error)) << error;  // a DPC31's: no chip known yet
    EXPECT_FALSE(rec.attach(spc3, error));
    EXPECT_EQ(error, "no signal of the spc3 matches 'pins.pb3' (see docs/waveforms.md)");
    Chip dpc31({Profile::dpc31, BusMode::intel, 0});
    wave::Recorder ok(o);
    ASSERT_TRUE(ok.attach(dpc31, error)) << error;
    EXPECT_TRUE(ok.finish(dpc31.cycle(), error)) << error;
    o.signals = {"bus.addr"};
    o.flat = true;
    wave::Recorder flat(o);
    EXPECT_FALSE(flat.attach(dpc31, error));
    EXPECT_EQ(error, o.path +
                         ": no 1-bit signal matches --signals: the logic-analyser form has only "
                         "those");
  }
}

// With the C31's interrupt controller served, the interrupt the firmware gets is the C31's INT0
// (low-active), not X/INT, which stays inactive (docs/dpc31.md, "Two interrupt controllers"):
// pins.c31_int0 shows it, at each cycle the controller's activity changes (docs/timing.md: 0
// cycles of latency), in ps round(cycle x 10^12 / 48 MHz). It is no signal of the external one's.
TEST(Waveform, TheC31sInterruptIsItsInt0Pin) {
  wave::Options o;
  o.path = tmp("c31_int0.vcd");
  o.signals = {"pins.*"};
  Chip external({Profile::dpc31, BusMode::intel, 0});
  std::string error;
  wave::Recorder none(o);
  EXPECT_TRUE(none.attach(external, error)) << error;
  EXPECT_TRUE(none.finish(external.cycle(), error)) << error;
  EXPECT_EQ(slurp(o.path).find("c31_int0"), std::string::npos);
  o.signals = {"pins.c31_int0"};
  wave::Recorder only(o);
  EXPECT_FALSE(only.attach(external, error));
  EXPECT_EQ(error, "no signal of the dpc31 matches 'pins.c31_int0' (see docs/waveforms.md)");

  o.signals = {"pins.c31_int0"};
  Chip chip(ChipOptions{Profile::dpc31, BusMode::intel, 0, Engine::event, std::nullopt,
                        IrqController::c31});
  chip.set_log_sink(nullptr);
  ResponderConfig rc;
  Responder user(rc);
  DirectBus bus(chip);
  user.init(bus);
  wave::Recorder rec(o);
  ASSERT_TRUE(rec.attach(chip, error)) << error;
  // The expected body: each change of the C31's interrupt, INT0 low while it is active.
  bool active = chip.irq_active();  // the user's init has run: its events may be pending
  std::string want = fmt::format("\n{}\n", active ? 0 : 1);  // $dumpvars, before any time line
  chip.on_irq_change([&](std::uint64_t c, bool) {
    if (chip.irq_active() == active) return;
    active = chip.irq_active();
    want += fmt::format("#{}\n{}\n", (c * 125'000 + 3) / 6, active ? 0 : 1);  // 10^12 / 48e6
  });
  DpMaster master(chip, MasterConfig{2, 1'500'000, 100, 33}, rc.slave);
  master.set_firmware([&](BusPort& b) { user.isr(b); });
  ASSERT_TRUE(master.startup());
  ASSERT_TRUE(rec.finish(chip.cycle(), error)) << error;
  ASSERT_GT(std::count(want.begin(), want.end(), '#'), 0);  // the start-up has interrupts
  const std::string v = slurp(o.path);
  // Each signal's VCD identifier, from its $var line.
  const auto id = [&v](const std::string& name) {
    const std::size_t at = v.find(" " + name + " $end");
    const std::size_t from = v.rfind(' ', at - 1) + 1;
    return at == std::string::npos ? std::string("?") : v.substr(from, at - from);
  };
  const std::string int0 = id("c31_int0");
  std::string changes;
  std::istringstream is(v.substr(v.find("$dumpvars\n")));
  std::string at;
  for (std::string line; std::getline(is, line);) {
    if (line.starts_with('#')) at = line;
    if (line == "0" + int0 || line == "1" + int0) changes += at + "\n" + line.substr(0, 1) + "\n";
  }
  EXPECT_EQ(changes, want);
}

// A unit longer than a clock cycle (20.8 ns at 48 MHz) would give neighbouring cycles one time.
TEST(Waveform, ATimescaleCoarserThanACycleIsRefused) {
  Chip chip({Profile::spc3, BusMode::intel, 0});
  wave::Options o;
  o.path = tmp("coarse.vcd");
  o.timescale_exp = -7;  // 100 ns
  std::string error;
  for (const bool flat : {false, true}) {
    o.flat = flat;
    wave::Recorder rec(o);
    EXPECT_FALSE(rec.attach(chip, error));
    EXPECT_EQ(error, o.path +
                         ": timescale 100ns is longer than a clock cycle (20.8 ns at 48 MHz): use "
                         "10ns or finer");
  }
  o.timescale_exp = -8;
  wave::Recorder fine(o);
  EXPECT_TRUE(fine.attach(chip, error)) << error;
}

// irr changes twice in some cycles (an event's bit, then in the same cycle the next one's): one
// value per time, the last (bus_access_spc3 at 120 us, cycle 5760: 0002h then 2002h).
TEST(Waveform, OneValuePerSignalAndTime) {
  Scenario s;
  ScenarioError err;
  ASSERT_TRUE(load_scenario(std::string(SOURCE_DIR) + "/traces/bus_access_spc3.scn", s, err))
      << err.text();
  wave::Options o;
  o.path = tmp("irr.vcd");
  o.signals = {"blocks.irr"};
  wave::Recorder rec(o);
  std::string error;
  std::uint64_t end = 0;
  ScenarioHooks hooks;
  hooks.at_start = [&](Chip& chip) { EXPECT_TRUE(rec.attach(chip, error)) << error; };
  hooks.at_end = [&](Chip& chip) { end = chip.cycle(); };
  run_scenario(
      s, [](const std::string&) {}, [](const std::string&) {}, hooks);
  ASSERT_TRUE(rec.finish(end, error)) << error;
  const std::string v = slurp(o.path);
  EXPECT_EQ(vcd_time_problem(v), "");
  EXPECT_NE(v.find("#120000000\nb0010000000000010 +\n#"), std::string::npos) << v;
}

// Dumps of one run at two units compare equal (docs/wavediff.md): each file's times are brought
// to the coarser unit as the writer rounds them.
TEST(Waveform, OneRunAtTwoUnitsComparesEqual) {
  wave::Options ps;
  ps.path = tmp("run_ps.vcd");
  record_startup(ps);
  for (const int exp : {-9, -8, -10}) {
    wave::Options other = ps;
    other.path = tmp(fmt::format("run_{}.vcd", exp));
    other.timescale_exp = exp;
    record_startup(other);
    wavediff::Options w;
    w.file_a = other.path;
    w.file_b = ps.path;
    const wavediff::Report r = wavediff::compare(w);
    EXPECT_TRUE(r.same()) << exp << ": " << wavediff::text_report(r, 5);
    std::swap(w.file_a, w.file_b);
    EXPECT_TRUE(wavediff::compare(w).same()) << exp;
  }
}
