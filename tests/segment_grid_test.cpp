// A firmware's bus accesses on a segment are those it has on the chip alone (docs/segment.md,
// "Time: who runs when"; issue 30): where a round of the line ends must not move them. The
// timing contract (docs/timing.md): a request is acted on at the stop sample of its last
// character, end - T + floor(T/2), X/INT goes active in that cycle (latency 0), the host CPU
// enters its ISR there, and every bus access takes 4 clocks, back to back. At 12 Mbaud (T = 4,
// floor(T/2) = 2) and 19.2 kbaud (T = 2500, floor(T/2) = 1250) that entry is off the line's
// 4-clock bit grid, where the master wakes up (the request's end); at every rate a round ends
// wherever the master (a user) looks at the line.
#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/fdl.hpp"
#include "firmware_host.hpp"
#include "responder.hpp"
#include "segment.hpp"

namespace dpc31 {
namespace {

struct Access {
  std::uint64_t cycle;
  BusAccess a;
  bool operator==(const Access& o) const {
    return cycle == o.cycle && a.write == o.a.write && a.addr == o.a.addr && a.data == o.a.data;
  }
};

std::ostream& operator<<(std::ostream& os, const Access& x) {
  return os << (x.a.write ? "write " : "read ") << x.a.addr << " @" << x.cycle;
}

struct Run {
  std::vector<Access> accesses;   // station 5's firmware, init included
  std::vector<Exchange> history;  // the master's
};

SlaveConfig do4_slave(std::uint8_t address) {
  SlaveConfig sc;
  sc.address = address;
  sc.wd_fact1 = 10;  // TWD = 10 ms x 10 x 10 = 48 000 000 clocks (docs/timing.md, "Timers"):
  sc.wd_fact2 = 10;  // longer than a start-up's gaps at 19.2 kbaud
  return with_gsd_defaults(find_firmware("DO4"), sc);
}

const std::vector<std::uint8_t> kOut = {0x0A, 0x01};  // DO1..4, OSPValid
// The master starts here in both runs (after the inits, over TSYN at 19.2 kbaud: 82 500 clocks).
constexpr std::uint64_t kMasterFrom = 200'000;
constexpr std::uint64_t kTwd = 48'000'000;

// After the start-up and three Data_Exchanges the master stops polling: the DP watchdog expires
// at the last request's acted-on cycle + TWD, and DO4's ISR serves WD_DP_Control_Timeout from
// there. The master looks at the line 2 clocks into that ISR's first access (a round of the line
// ends there), then waits on.
template <typename Now>
void traffic(DpMaster& m, std::uint64_t t, Now now) {
  for (int i = 0; i < 3; ++i) m.data_exchange(kOut);
  const std::uint64_t expiry = m.history().back().request_end - t + t / 2 + kTwd;
  m.idle(expiry + 2 - now());
  m.idle(expiry + 100'000 - now());
}

// DO4 on an SPC3 at address 5, alone with the built-in master: start-up, three Data_Exchanges.
Run alone(std::uint32_t baud) {
  Run r;
  Chip chip(ChipOptions{Profile::spc3});
  chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) { r.accesses.push_back({c, a}); });
  FirmwareHost fw(find_firmware("DO4"));
  DirectBus bus(chip);
  fw.init(bus, 5);
  DpMaster m(chip, MasterConfig{2, baud}, do4_slave(5));
  m.set_firmware(fw.program());
  m.idle(kMasterFrom - chip.cycle());
  EXPECT_TRUE(m.startup());
  traffic(m, chip.bit_cycles(), [&] { return chip.cycle(); });
  r.history = m.history();
  return r;
}

// The same station and master on a segment beside a DPC31 running its own DO4 at address 7,
// which hears every telegram and is never asked: the line's rounds end at its events too.
Run on_segment(std::uint32_t baud, bool reference) {
  Run r;
  Segment seg(baud);
  seg.use_reference_line(reference);
  const std::size_t a = seg.add_chip("spc3", ChipOptions{Profile::spc3});
  const std::size_t b = seg.add_chip("dpc31", ChipOptions{Profile::dpc31});
  seg.chip(a).on_bus_access([&](std::uint64_t c, const BusAccess& x) {
    r.accesses.push_back({c, x});
  });
  FirmwareHost fa(find_firmware("DO4"));
  FirmwareHost fb(find_firmware("DO4"));
  {
    DirectBus bus(seg.chip(a));
    fa.init(bus, 5);
  }
  {
    DirectBus bus(seg.chip(b));
    fb.init(bus, 7);
  }
  seg.set_firmware(a, fa.program());
  seg.set_firmware(b, fb.program());
  DpMaster m(seg, seg.add_sender("master 2"), MasterConfig{2, baud}, {do4_slave(5)});
  m.idle(kMasterFrom - seg.cycle());
  EXPECT_TRUE(m.startup_all());
  traffic(m, seg.bit_cycles(), [&] { return seg.cycle(); });
  r.history = m.history();
  return r;
}

// The first bus access at or after `cycle`.
const Access* first_from(const Run& r, std::uint64_t cycle) {
  for (const Access& x : r.accesses) {
    if (x.cycle >= cycle) return &x;
  }
  return nullptr;
}

void expect_as_alone(std::uint32_t baud) {
  const Run lone = alone(baud);
  const std::uint64_t t = dpc31::bit_cycles(Chip().clock_hz(), baud);
  for (const bool reference : {false, true}) {
    SCOPED_TRACE(reference ? "reference line" : "telegram level");
    const Run seg = on_segment(baud, reference);
    // The same master traffic, request by request: else the comparison below means nothing.
    ASSERT_EQ(seg.history.size(), lone.history.size());
    for (std::size_t i = 0; i < lone.history.size(); ++i) {
      ASSERT_EQ(seg.history[i].request_start, lone.history[i].request_start) << i;
      ASSERT_EQ(seg.history[i].answer_start, lone.history[i].answer_start) << i;
    }
    // By hand: the last Data_Exchange is acted on at end - T + floor(T/2); the ISR entered there
    // makes its first access (Int_Reg, read) in that very cycle, which the chip reports at its
    // completion, 4 clocks later (the chip alone gives the same, checked below).
    const Exchange& dx = lone.history.back();
    const std::uint64_t acted = dx.request_end - t + t / 2;
    const Access* first = first_from(seg, acted);
    ASSERT_NE(first, nullptr);
    EXPECT_EQ(first->cycle, acted + 4);
    EXPECT_FALSE(first->a.write);
    EXPECT_EQ(first->a.addr, 0x02);  // Int_Reg's low byte on the SPC3, dps_isr's first read
    // The watchdog restarted there expires TWD later, X/INT goes active (WD_DP_Control_Timeout)
    // and the ISR's first access completes 4 clocks after, whatever the master looked at.
    const Access* wd = first_from(seg, acted + kTwd);
    ASSERT_NE(wd, nullptr);
    EXPECT_EQ(wd->cycle, acted + kTwd + 4);
    EXPECT_FALSE(wd->a.write);
    EXPECT_EQ(wd->a.addr, 0x02);
    // Every access of the firmware, init, start-up and Data_Exchange, at the chip alone's cycle.
    ASSERT_EQ(seg.accesses.size(), lone.accesses.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < lone.accesses.size(); ++i) {
      if (!(seg.accesses[i] == lone.accesses[i])) {
        if (differ++ == 0)
          ADD_FAILURE() << "access " << i << ": " << seg.accesses[i] << " on the segment, "
                        << lone.accesses[i] << " alone";
      }
    }
    EXPECT_EQ(differ, 0U) << "of " << lone.accesses.size() << " accesses";
  }
}

TEST(SegmentGrid, At12MbaudAFirmwaresAccessesAreThoseOfTheChipAlone) {
  expect_as_alone(12'000'000);
}

TEST(SegmentGrid, At19k2AFirmwaresAccessesAreThoseOfTheChipAlone) { expect_as_alone(19'200); }

// On the grid (1.5 Mbaud: T = 32, floor(T/2) = 16) the requests' ISRs were exact before; the
// master's look inside the watchdog's ISR was not.
TEST(SegmentGrid, At1M5AFirmwaresAccessesAreThoseOfTheChipAlone) { expect_as_alone(1'500'000); }

// A firmware that polls in its main loop (tests/dpv1_plugin.c: the DPV1 side polls the SAP list)
// runs in every round, so a round may end where its CPU is inside an access on a telegram's first
// start bit. It must not run past that start (docs/segment.md, "A firmware across a round's end":
// a sender's first start bit is a hard end), else at 12 Mbaud (T = 4) the chip gets that start
// bit up to 3 clocks late, samples the characters shifted and counts a parity error on a clean
// line, the telegram lost (the audit s35 aMix, finding 1, whose plug3.scn this is): the plug-in
// on a VPC3+ at address 5 beside DO4 on an SPC3 (6) and the built-in user side on a DPC31 (7),
// all three polled, then MSAC_C1 (SAP 51) Write and Read of the plug-in's record with a poll 1 ms
// after each (the raw telegrams of the audit's seg_plugin_dpv1.scn, FCV 0). Against the same
// plug-in on the VPC3+ alone given the same RxD traffic (every telegram of the line but its own
// answers, each ahead of time, as the single chip's master gives a request).
const std::vector<std::uint8_t> kC1Write = {0x68, 0x0D, 0x0D, 0x68, 0x85, 0x82, 0x4D,
                                            0x33, 0x33, 0x5F, 0x00, 0x01, 0x04, 0xA1,
                                            0xA2, 0xA3, 0xA4, 0xA8, 0x16};
const std::vector<std::uint8_t> kC1Read = {0x68, 0x09, 0x09, 0x68, 0x85, 0x82, 0x4D, 0x33,
                                           0x33, 0x5E, 0x00, 0x01, 0x04, 0x1D, 0x16};
const std::vector<std::uint8_t> kC1Poll = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82,
                                           0x4D, 0x33, 0x33, 0xBA, 0x16};

struct PollingRun {
  std::vector<Access> accesses;  // station 5's firmware, init included
  std::vector<Exchange> history;
  std::vector<LineTelegram> others;  // the line's telegrams not station 5's
  FdlCounters counters;              // station 5's
  std::uint64_t end = 0;
};

SlaveConfig slave_at(std::uint8_t address, const char* firmware) {
  SlaveConfig sc;
  sc.address = address;
  return firmware != nullptr ? with_gsd_defaults(find_firmware(firmware), sc) : sc;
}

PollingRun polling_on_segment(bool reference) {
  PollingRun r;
  Segment seg(12'000'000);
  seg.use_reference_line(reference);
  const std::size_t a = seg.add_chip("plug", ChipOptions{Profile::vpc3plus});
  const std::size_t b = seg.add_chip("do4", ChipOptions{Profile::spc3});
  const std::size_t c = seg.add_chip("resp", ChipOptions{Profile::dpc31});
  seg.chip(a).on_bus_access([&](std::uint64_t cy, const BusAccess& x) {
    r.accesses.push_back({cy, x});
  });
  seg.on_telegram = [&](const LineTelegram& t) {
    if (t.from != a) r.others.push_back(t);
  };
  FirmwareHost fa(find_firmware(DPV1_PLUGIN));
  FirmwareHost fb(find_firmware("DO4"));
  ResponderConfig rc;
  rc.slave = slave_at(7, nullptr);
  Responder resp(rc);
  {
    DirectBus bus(seg.chip(a));
    fa.init(bus, 5);
  }
  {
    DirectBus bus(seg.chip(b));
    fb.init(bus, 6);
  }
  {
    DirectBus bus(seg.chip(c));
    resp.init(bus);
  }
  seg.set_firmware(a, fa.program());
  seg.set_firmware(b, fb.program());
  seg.set_firmware(c, [&resp](BusPort& bus) { resp.isr(bus); });
  DpMaster m(seg, seg.add_sender("master 2"), MasterConfig{2, 12'000'000},
             {slave_at(5, DPV1_PLUGIN), slave_at(6, "DO4"), rc.slave});
  m.idle(kMasterFrom - seg.cycle());
  EXPECT_TRUE(m.startup_all());
  for (int i = 0; i < 3; ++i) m.dp_cycle();
  m.select(0);
  for (const auto* req : {&kC1Write, &kC1Read}) {
    m.transact_raw(*req);
    m.idle(seg.chip(a).clock_hz() / 1000);
    m.transact_raw(kC1Poll);
  }
  m.idle(1000);
  seg.flush();
  r.history = m.history();
  r.counters = seg.chip(a).fdl_counters();
  r.end = seg.cycle();
  return r;
}

PollingRun polling_alone(const PollingRun& line) {
  PollingRun r;
  Chip chip(ChipOptions{Profile::vpc3plus});
  chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) { r.accesses.push_back({c, a}); });
  FirmwareHost fw(find_firmware(DPV1_PLUGIN));
  {
    DirectBus bus(chip);
    fw.init(bus, 5);
  }
  Cpu cpu(chip, fw.program());
  for (const LineTelegram& t : line.others) {
    // Its last access ends by the start bit: the telegram is on RxD ahead of time.
    cpu.run_until(t.start - Segment::kCpuSlack);
    chip.hear_telegram(t.bytes, t.start, chip.bit_cycles());
  }
  cpu.run_until(line.end);
  r.counters = chip.fdl_counters();
  return r;
}

TEST(SegmentGrid, At12MbaudAPollingFirmwareTakesEveryTelegramAsTheChipAlone) {
  const auto answer = [](const Exchange& ex) {
    return ex.answer ? fdl::encode(*ex.answer) : std::vector<std::uint8_t>{};
  };
  for (const bool reference : {false, true}) {
    SCOPED_TRACE(reference ? "reference line" : "telegram level");
    const PollingRun seg = polling_on_segment(reference);
    // Every request answered: 3 DP cycles of 3 after the start-up, 4 MSAC_C1 telegrams to 5.
    ASSERT_GE(seg.history.size(), 13U);
    for (const Exchange& ex : seg.history) EXPECT_TRUE(ex.answer) << ex.request_start;
    // The poll after the Write gets the Write's response (its header, no data), the one after the
    // Read the record as written: DA 2, SA 5, FC 08 (DL), SAPs 51 (docs/dpv1.md).
    const std::size_t n = seg.history.size();
    EXPECT_EQ(answer(seg.history[n - 3]),
              (std::vector<std::uint8_t>{0x68, 0x09, 0x09, 0x68, 0x82, 0x85, 0x08, 0x33, 0x33, 0x5F,
                                         0x00, 0x01, 0x04, 0xD9, 0x16}));
    EXPECT_EQ(answer(seg.history[n - 1]),
              (std::vector<std::uint8_t>{0x68, 0x0D, 0x0D, 0x68, 0x82, 0x85, 0x08, 0x33, 0x33, 0x5E,
                                         0x00, 0x01, 0x04, 0xA1, 0xA2, 0xA3, 0xA4, 0x62, 0x16}));
    // Every telegram taken as alone: the same FDL counters, no parity error.
    const PollingRun lone = polling_alone(seg);
    EXPECT_EQ(seg.counters.parity, 0U);
    EXPECT_EQ(seg.counters, lone.counters);
    // Every access of the firmware at the chip alone's cycle.
    ASSERT_EQ(seg.accesses.size(), lone.accesses.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < lone.accesses.size(); ++i) {
      if (!(seg.accesses[i] == lone.accesses[i]) && differ++ == 0) {
        ADD_FAILURE() << "access " << i << ": " << seg.accesses[i] << " on the segment, "
                      << lone.accesses[i] << " alone";
      }
    }
    EXPECT_EQ(differ, 0U) << "of " << lone.accesses.size() << " accesses";
  }
}

}  // namespace
}  // namespace dpc31
