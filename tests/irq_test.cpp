// Interrupt controller with exact cycles from docs/timing.md: a bus access takes 4 clocks and
// acts when it completes; X/INT follows IR in the same cycle; after EOI it stays inactive for
// ceil(1 us * f) = 48 or ceil(1 ms * f) = 48000 clocks at 48 MHz.
#include <fmt/core.h>
#include <gtest/gtest.h>

#include <utility>

#include "dpc31/reg_ids.hpp"
#include "harness.hpp"
#include "test_util.hpp"

using namespace dpc31;
using testutil::bus_read16;
using testutil::bus_write16;

namespace {

constexpr std::uint64_t kAccess = 4;

struct Edges {
  std::vector<std::pair<std::uint64_t, bool>> v;
  void attach(Chip& c) {
    c.on_irq_change([this](std::uint64_t cyc, bool a) { v.emplace_back(cyc, a); });
  }
};

class Irq : public testutil::ChipTest {
 protected:
  Chip make(std::uint32_t clock_hz = 0) {
    Chip c = ChipTest::make(clock_hz);
    edges_.attach(c);
    return c;
  }
  Edges edges_;
};

// Offset (0 or 1) of the byte holding bit `b` of a 16-bit register at the manuals' byte order.
int offset_of_bit(BusMode m, int b) { return spec::byte_index_at(m, 0) == b / 8 ? 0 : 1; }

}  // namespace

TEST_P(Irq, EveryBitSetsMasksAcknowledges) {
  const std::uint16_t events =
      spec::mask_of(spec::row(GetParam().profile, "Int_Req_Reg").policy, "w");
  const std::uint16_t not_by_iar =
      spec::mask_of(spec::row(GetParam().profile, "Int_Ack_Reg").policy, "i");
  for (int b = 0; b < 16; ++b) {
    if (((events >> b) & 1) == 0) continue;
    SCOPED_TRACE(fmt::format("bit {}", b));
    edges_.v.clear();
    log_.clear();
    Chip c = make();
    const auto bit = static_cast<std::uint16_t>(1u << b);
    bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~bit));  // unmask only this bit
    ASSERT_EQ(c.cycle(), 2 * kAccess);
    EXPECT_FALSE(c.irq_active());
    EXPECT_TRUE(c.x_int_pin());  // low-active: inactive = high

    harness::asic_raise(c, bit);  // event at cycle 8: X/INT active in the same cycle
    EXPECT_TRUE(c.irq_active());
    EXPECT_FALSE(c.x_int_pin());
    EXPECT_EQ(bus_read16(c, 0x02, 16), bit);  // IR; two reads end at cycle 16
    EXPECT_EQ(bus_read16(c, 0x00, 16), bit);  // IRR; cycle 24

    // Mask it: the line drops when the write of the byte holding the bit completes.
    const int off = offset_of_bit(c.bus_mode(), b);
    c.write(static_cast<std::uint32_t>(0x04 + off), 0xFF);  // completes at 28
    EXPECT_FALSE(c.irq_active());
    EXPECT_EQ(bus_read16(c, 0x00, 16), bit);  // IRR keeps the event while masked; cycle 36
    EXPECT_EQ(bus_read16(c, 0x02, 16), 0);    // cycle 44
    c.write(static_cast<std::uint32_t>(0x04 + off),
            static_cast<std::uint8_t>(~(bit >> (8 * (b / 8)))));
    EXPECT_TRUE(c.irq_active());  // unmasked at 48

    // Acknowledge: W1C, except the bits only the OK/Not_OK reads clear.
    c.write(static_cast<std::uint32_t>(0x02 + off),
            static_cast<std::uint8_t>(bit >> (8 * (b / 8))));
    const bool ignored = (not_by_iar & bit) != 0;
    EXPECT_EQ(c.irq_active(), ignored);  // acknowledge completes at 52
    std::vector<std::pair<std::uint64_t, bool>> expect = {{8, true}, {28, false}, {48, true}};
    if (!ignored) expect.emplace_back(52, false);
    EXPECT_EQ(edges_.v, expect);
    EXPECT_EQ(log_.count_containing("not changed by this register"), ignored ? 1u : 0u);
  }
}

TEST_P(Irq, EoiHoldsTheLineInactiveFor1us) {
  Chip c = make();
  bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~(irq::DX_Out | irq::User_Timer_Clock)));
  harness::asic_raise(c, irq::DX_Out | irq::User_Timer_Clock);  // cycle 8
  bus_write16(c, 0x02, 16, irq::DX_Out);  // acknowledge one: still active, cycle 16
  EXPECT_TRUE(c.irq_active());
  c.write(0x08, 0x02);  // EOI completes at 20
  EXPECT_EQ(c.cycle(), 20u);
  EXPECT_FALSE(c.irq_active());
  c.step(47);  // cycle 67: still inside the inactive time
  EXPECT_FALSE(c.irq_active());
  c.step(1);  // cycle 68 = 20 + 48
  EXPECT_TRUE(c.irq_active());
  const std::vector<std::pair<std::uint64_t, bool>> expect = {{8, true}, {20, false}, {68, true}};
  EXPECT_EQ(edges_.v, expect);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1) & 0x02, 0);  // EOI cleared by the chip
}

TEST_P(Irq, EoiTimeBase1msAndEventsInsideTheWindow) {
  Chip c = make();
  bus_write16(c, 0x06, 16, 0x0200);  // EOI_Time_Base = 1 ms; cycle 8
  bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::New_GC_Command));  // cycle 16
  c.write(0x08, 0x02);  // EOI with nothing pending, completes at 20
  c.step(10);           // cycle 30: an event inside the window waits for its end
  harness::asic_raise(c, irq::New_GC_Command);
  EXPECT_FALSE(c.irq_active());
  c.step(20 + 48000 - 30 - 1);  // cycle 48019
  EXPECT_FALSE(c.irq_active());
  c.step(1);  // cycle 48020 = 20 + 48000
  EXPECT_TRUE(c.irq_active());
  // After the window an event asserts at once.
  bus_write16(c, 0x02, 16, irq::New_GC_Command);  // cycle 48028
  EXPECT_FALSE(c.irq_active());
  harness::asic_raise(c, irq::New_GC_Command);
  EXPECT_TRUE(c.irq_active());
  const std::vector<std::pair<std::uint64_t, bool>> expect = {
      {48020, true}, {48024 + (c.bus_mode() == BusMode::intel ? 4u : 0u), false}, {48028, true}};
  EXPECT_EQ(edges_.v, expect);
}

TEST_P(Irq, InactiveTimeRoundsUpAtOtherClocks) {
  for (auto [hz, cycles] : {std::pair{12'000'000u, 12u}, {20'000'001u, 21u}, {48'000'000u, 48u}}) {
    Chip c = make(hz);
    harness::asic_raise(c, 0);  // nothing
    bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::DX_Out));
    harness::asic_raise(c, irq::DX_Out);
    c.write(0x08, 0x02);  // EOI at 12
    c.step(cycles - 1);
    EXPECT_FALSE(c.irq_active()) << hz;
    c.step(1);
    EXPECT_TRUE(c.irq_active()) << hz;
  }
}

TEST_P(Irq, EventAndAcknowledgeInTheSameCycleKeepsTheEvent) {
  for (std::uint64_t late : {0u, 1u}) {
    Chip c = make();
    bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::User_Timer_Clock));
    // Start_SPC3 completes at s = 12 (dpc31: MAC_Start, later): the user timer ticks at s + 48000
    const std::uint64_t s = testutil::user_start(c);
    if (GetParam().profile != Profile::dpc31) {
      ASSERT_EQ(s, 12u);
    }
    c.step(48000 - kAccess + late);
    const int off = offset_of_bit(c.bus_mode(), 4);
    c.write(static_cast<std::uint32_t>(0x02 + off), 0x10);  // ack completes at s + 48000 + late
    EXPECT_EQ(c.cycle(), s + 48000u + late);
    const bool kept = late == 0;
    EXPECT_EQ((c.peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock) != 0, kept) << late;
  }
}

TEST_P(Irq, WritingIrrRaisesAndClearsEvents) {
  Chip c = make();
  bus_write16(c, 0x04, 16, 0x0000);  // all unmasked
  bus_write16(c, 0x00, 16, irq::Diag_Buffer_Changed);
  EXPECT_TRUE(c.irq_active());
  bus_write16(c, 0x00, 16, 0x0000);
  EXPECT_FALSE(c.irq_active());
}

TEST_P(Irq, PolarityFollowsIntPol) {
  Chip c = make();
  bus_write16(c, 0x06, 16, 0x0010);  // INT_Pol = 1: high-active
  EXPECT_FALSE(c.x_int_pin());
  bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::DX_Out));
  harness::asic_raise(c, irq::DX_Out);
  EXPECT_TRUE(c.x_int_pin());
}

// A hardware reset clears Int_Req_Reg: an active interrupt ends in the reset's cycle, cycle 0 of
// the new time line, and on_irq_change sees that edge, as the PB3 observer sees PB3's
// (docs/timing.md, "Interrupt line"; docs/decisions.md, "The thirty-first session: s31-reset").
TEST_P(Irq, AHardwareResetEndsAnActiveInterruptWithAnEdgeAtCycle0) {
  Chip c = make();
  bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::DX_Out));
  harness::asic_raise(c, irq::DX_Out);  // cycle 8
  c.step(100);
  c.reset();
  EXPECT_FALSE(c.irq_active());
  c.reset();  // inactive already: no edge
  const std::vector<std::pair<std::uint64_t, bool>> expect = {{8, true}, {0, false}};
  EXPECT_EQ(edges_.v, expect);
}

// A snapshot's load gives the chip the snapshot's X/INT from the loaded cycle on: on_irq_change
// sees an edge there where the line changes, none where it does not (docs/snapshots.md).
TEST_P(Irq, LoadingASnapshotShowsTheLoadedInterruptAtTheLoadedCycle) {
  Chip c = make();
  const std::vector<std::uint8_t> quiet = c.save_state();  // cycle 0, inactive
  bus_write16(c, 0x04, 16, static_cast<std::uint16_t>(~irq::DX_Out));
  harness::asic_raise(c, irq::DX_Out);  // cycle 8
  const std::vector<std::uint8_t> active = c.save_state();
  c.step(92);
  c.load_state(quiet);
  EXPECT_FALSE(c.irq_active());
  c.load_state(active);
  c.load_state(active);  // active already: no edge
  EXPECT_TRUE(c.irq_active());
  const std::vector<std::pair<std::uint64_t, bool>> expect = {{8, true}, {0, false}, {8, true}};
  EXPECT_EQ(edges_.v, expect);
}

INSTANTIATE_TEST_SUITE_P(Chips, Irq, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

// X/INT is looked at once after a cycle's events (docs/timing.md, "Order within one cycle",
// step 6), so an edge caused by several events in one cycle shows IRR with all of them. The
// DPC31's MAC_Stop (Table 5.1-3: "MAC enters Offline", confirmed by an entry in the
// Indication_Queue, p.22 §5.1.3) latches MAC_Reset and then, with its indication 11h/00h,
// Indication (bit 5), both at the completion of the InstQ_Wr write (docs/timing.md, "Mode and
// state changes"; docs/dpc31.md, "The queues"). Both engines.
TEST(IrqDpc31, AnEdgeOfSeveralEventsShowsThemAll) {
  for (const Engine engine : {Engine::event, Engine::per_cycle}) {
    SCOPED_TRACE(engine == Engine::event ? "event engine" : "per-cycle engine");
    Chip c({.profile = Profile::dpc31, .engine = engine});
    const auto cell = [&c](RegId id) { return static_cast<std::uint32_t>(c.addr_of(id)); };
    c.write(cell(RegId::IndQ_Base), 0xF9);  // the ring at 1F20h, beside the requests' at 1F00h
    c.write(cell(RegId::IndQ_Len), 4);
    bus_write16(c, c.addr_of(RegId::Int_Mask_Reg), 16, 0x0000);  // every event unmasked
    testutil::user_start(c);                                     // DX_Out: X/INT active
    bus_write16(c, c.addr_of(RegId::Int_Ack_Reg), 16, 0xFFFF);   // acknowledged: inactive
    ASSERT_FALSE(c.irq_active());
    std::vector<std::pair<std::uint64_t, std::uint16_t>> rises;  // cycle, IRR seen
    c.on_irq_change([&c, &rises](std::uint64_t cyc, bool active) {
      if (active) rises.emplace_back(cyc, c.peek_reg(RegId::Int_Req_Reg));
    });
    const std::uint64_t stop = testutil::user_go_offline(c);
    ASSERT_EQ(rises.size(), 1u);
    EXPECT_EQ(rises[0].first, stop);
    EXPECT_EQ(rises[0].second, irq::MAC_Reset | irq::Indication);
  }
}
