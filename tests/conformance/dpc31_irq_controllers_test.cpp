// The DPC31's two interrupt controllers (DPC31 HW Description, as issue 16 quotes it: "The
// interrupt controller exists twice, for the external processor and for the internal C31 core,
// at the same addresses"). The user says which one the bus reaches (ChipOptions::irq_controller,
// docs/dpc31.md "Two interrupt controllers"); the other is never written, so its mask keeps its
// reset value FFFFh and its output stays inactive. The external processor's drives X/INT.
// Timing from docs/timing.md: an access takes 4 clocks and acts when it completes; X/INT follows
// in the same cycle; the EOI inactive time is 1 us = 48 clocks at 48 MHz. Addresses as in
// irq_test.cpp: Int_Req_Reg 00h/01h, Int_Ack_Reg 02h/03h, Int_Mask_Reg 04h/05h, Mode_Reg0
// 06h/07h, Mode_Reg1_S 08h (Intel: low byte first).
#include <stdexcept>
#include <utility>
#include <vector>

#include "conformance.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

struct Observed {
  Edges interrupt;          // on_irq_change: the served controller's output
  std::vector<bool> x_int;  // the X/INT pin level at each of those changes
};

void w16(Chip& c, std::uint32_t a, std::uint16_t v) {
  testutil::bus_write16(c, static_cast<int>(a), 16, v);
}

// The sequence of irq_test.cpp's EoiInactiveTime test with one read more: unmask DX_Out and
// Diag_Buffer_Changed (writes complete at 4, 8), raise both (12, 16: the interrupt active at 16),
// read IRR's high byte (20), acknowledge DX_Out (24, 28), EOI at 32: inactive at 32, active again
// at 32 + 48 = 80. With int_pol the X/INT pin is high-active (Mode_Reg0 bit 4 written first, at
// 4 and 8, so everything is 8 clocks later).
Observed run(IrqController served, bool int_pol) {
  Chip c(ChipOptions{Profile::dpc31, BusMode::intel, 0, Engine::event, std::nullopt, served});
  c.set_log_sink(nullptr);
  Observed r;
  c.on_irq_change([&](std::uint64_t at, bool active) {
    r.interrupt.emplace_back(at, active);
    r.x_int.push_back(c.x_int_pin());
  });
  if (int_pol) w16(c, 0x06, 0x0010);
  w16(c, 0x04, static_cast<std::uint16_t>(~(irq::DX_Out | irq::Diag_Buffer_Changed)));
  w16(c, 0x00, irq::DX_Out | irq::Diag_Buffer_Changed);
  EXPECT_EQ(c.read(0x01), (irq::DX_Out | irq::Diag_Buffer_Changed) >> 8);  // IRR's high byte
  w16(c, 0x02, irq::DX_Out);
  c.write(0x08, 0x02);  // EOI
  c.step(100);
  return r;
}

// run() with each controller served: the user's interrupt has the edges `expect` both times;
// X/INT at each edge is `ext_x_int` with the external one served, `c31_x_int` with the C31's.
void expect_both(const Edges& expect, bool int_pol, const std::vector<bool>& ext_x_int,
                 const std::vector<bool>& c31_x_int) {
  const Observed ext = run(IrqController::external, int_pol);
  EXPECT_EQ(ext.interrupt, expect);
  EXPECT_EQ(ext.x_int, ext_x_int);
  const Observed c31 = run(IrqController::c31, int_pol);
  EXPECT_EQ(c31.interrupt, expect);
  EXPECT_EQ(c31.x_int, c31_x_int);
}

}  // namespace

// The bus reaches the chosen controller at the same addresses, with the same behaviour: the
// interrupt of the user's processor goes active at 16, inactive at the EOI (28 + 4 for the IRR
// read between), active again 48 clocks later. Only the external processor's drives X/INT: low
// (active, INT_Pol = 0) while its interrupt is active.
TEST(Dpc31IrqControllers, TheBusReachesTheChosenControllerAtTheSameAddresses) {
  // With the C31's served, the external controller is never unmasked: X/INT stays high, inactive
  // at INT_Pol = 0.
  expect_both({{16, true}, {32, false}, {80, true}}, false, {false, true, false},
              {true, true, true});
}

// INT_Pol (Mode_Reg0 bit 4) sets X/INT's polarity: with the C31's controller served, X/INT is
// inactive at either polarity — low when high-active.
TEST(Dpc31IrqControllers, XIntStaysInactiveAtEitherPolarityWhenTheC31sIsServed) {
  expect_both({{24, true}, {40, false}, {88, true}}, true, {true, false, true},
              {false, false, false});
}

// SPC3 and VPC3+ have no C31 core, so no second controller.
TEST(Dpc31IrqControllers, OnlyTheDpc31HasTheC31sController) {
  for (const Profile p : {Profile::spc3, Profile::vpc3plus}) {
    EXPECT_THROW(
        Chip(ChipOptions{p, BusMode::intel, 0, Engine::event, std::nullopt, IrqController::c31}),
        std::invalid_argument)
        << testutil::pname(p);
    EXPECT_NO_THROW(Chip(
        ChipOptions{p, BusMode::intel, 0, Engine::event, std::nullopt, IrqController::external}));
  }
}

// A snapshot keeps the state, not the make: loaded into a chip served through the C31's
// controller, the state still drives the C31's interrupt and leaves X/INT inactive.
TEST(Dpc31IrqControllers, ASnapshotLoadsIntoTheChosenController) {
  Chip ext(ChipOptions{Profile::dpc31});
  ext.set_log_sink(nullptr);
  w16(ext, 0x04, static_cast<std::uint16_t>(~irq::DX_Out));
  w16(ext, 0x00, irq::DX_Out);
  ASSERT_TRUE(ext.irq_active());
  ASSERT_FALSE(ext.x_int_pin());
  Chip c31(ChipOptions{Profile::dpc31, BusMode::intel, 0, Engine::event, std::nullopt,
                       IrqController::c31});
  c31.set_log_sink(nullptr);
  c31.load_state(ext.save_state());
  EXPECT_EQ(c31.irq_controller(), IrqController::c31);
  EXPECT_TRUE(c31.irq_active());
  EXPECT_TRUE(c31.x_int_pin());
  EXPECT_EQ(c31.read(0x01), irq::DX_Out >> 8);
}
