// The host CPU (session/cpu.hpp): the firmware's ISR interleaves with the bus side one bus access
// at a time (4 clocks each, docs/timing.md), resumes where it stopped, and keeps its own HAL
// selection; an exception it throws reaches the bus side; destroying the CPU unwinds an ISR in
// progress.
#include "cpu.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "dpc31/dpc31_hal.h"
#include "dpc31/hal.hpp"
#include "harness.hpp"

namespace {

using namespace dpc31;

constexpr std::uint64_t kAccess = 4;
constexpr std::uint32_t kRam = 0x0900;  // user RAM in every profile

// A chip whose X/INT goes active at cycle 8 (DX_Out unmasked by two writes, then raised).
Chip chip_with_pending_irq() {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  c.write(0x04, static_cast<std::uint8_t>(~irq::DX_Out & 0xFF));
  c.write(0x05, static_cast<std::uint8_t>(~irq::DX_Out >> 8));
  harness::asic_raise(c, irq::DX_Out);
  return c;
}

// Acknowledges DX_Out (Int_Ack_Reg high byte at 0x03 in Intel order): X/INT goes inactive.
void acknowledge(BusPort& b) { b.write(0x03, static_cast<std::uint8_t>(irq::DX_Out >> 8)); }

TEST(HostCpu, IsrInterleavesPerAccessAndResumesWhereItStopped) {
  Chip c = chip_with_pending_irq();
  ASSERT_EQ(c.cycle(), 2 * kAccess);
  ASSERT_TRUE(c.irq_active());
  std::vector<std::uint64_t> ends;
  Cpu cpu(c, [&](BusPort& b) {
    for (int i = 0; i < 5; ++i) {
      b.read(kRam);
      ends.push_back(b.cycle());
    }
    acknowledge(b);
  });
  cpu.run_until(16);  // two accesses fit: 8..12, 12..16
  EXPECT_EQ(ends, (std::vector<std::uint64_t>{12, 16}));
  EXPECT_EQ(c.cycle(), 16u);
  cpu.run_until(100);  // three more reads and the acknowledge (ends at 32), then idle to 100
  EXPECT_EQ(ends, (std::vector<std::uint64_t>{12, 16, 20, 24, 28}));
  EXPECT_FALSE(c.irq_active());
  EXPECT_EQ(c.cycle(), 100u);
}

TEST(HostCpu, AnExceptionInTheIsrReachesTheBusSide) {
  Chip c = chip_with_pending_irq();
  int entries = 0;
  Cpu cpu(c, [&](BusPort& b) {
    ++entries;
    b.read(kRam);
    if (entries == 1) throw std::runtime_error("firmware failed");
    acknowledge(b);
  });
  try {
    cpu.run_until(100);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "firmware failed");
  }
  EXPECT_EQ(c.cycle(), 12u);  // the one read
  cpu.run_until(100);         // X/INT is still active: the ISR is entered again, and finishes
  EXPECT_EQ(entries, 2);
  EXPECT_FALSE(c.irq_active());
}

// The C HAL's selection is per side: while an ISR waits between two of its accesses, the bus
// side's Vpc3Read still reaches the chip the bus side selected, and the ISR's own next access
// reaches the chip it runs against.
TEST(HostCpu, HalSelectionStaysWithItsSide) {
  Chip fw_chip = chip_with_pending_irq();
  Chip host_chip({Profile::spc3, BusMode::intel, 0});
  host_chip.set_log_sink(nullptr);
  DirectBus host_bus(host_chip);
  const hal::Scope host_scope(host_bus, nullptr);

  Cpu cpu(fw_chip, [&](BusPort& b) {
    const hal::Scope scope(b, nullptr);
    Vpc3Write(kRam, 0xA5);
    Vpc3Write(kRam + 1, 0x5A);
    acknowledge(b);
  });
  cpu.run_until(12);  // the first write (8..12); the ISR waits before its second
  EXPECT_EQ(fw_chip.peek(kRam), 0xA5);
  EXPECT_EQ(host_chip.cycle(), 0u);
  Vpc3Write(kRam, 0x3C);  // the bus side's selection: the SPC3
  EXPECT_EQ(host_chip.cycle(), kAccess);
  EXPECT_EQ(host_chip.peek(kRam), 0x3C);
  EXPECT_EQ(fw_chip.cycle(), 12u);
  cpu.run_until(100);
  EXPECT_EQ(fw_chip.peek(kRam + 1), 0x5A);
  EXPECT_EQ(fw_chip.peek(kRam), 0xA5);
  EXPECT_EQ(host_chip.cycle(), kAccess);  // nothing of the ISR reached the SPC3
}

TEST(HostCpu, DestroyingTheCpuUnwindsAnIsrInProgress) {
  Chip c = chip_with_pending_irq();
  struct Flag {
    bool* set;
    ~Flag() { *set = true; }
  };
  bool unwound = false;
  {
    Cpu cpu(c, [&](BusPort& b) {
      const Flag f{&unwound};
      for (;;) b.read(kRam);  // never finishes on its own
    });
    cpu.run_until(40);
    EXPECT_EQ(c.cycle(), 40u);
    EXPECT_FALSE(unwound);
  }
  EXPECT_TRUE(unwound);
}

}  // namespace
