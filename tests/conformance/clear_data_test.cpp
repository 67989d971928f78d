// Seed 003 (DPC31 HW Description V1.0 p.32-33): Clear_Data, the fail-safe Data_Exchange without
// outputs, Sync and Unsync. Cycles: a request is acted on at the stop sample of its last
// character (docs/timing.md "Telegrams"); X/INT follows an event with 0 cycles latency.
#include "conformance.hpp"

using namespace dpc31;
using namespace conformance;  // the bench, the ISR that only acknowledges

namespace {

constexpr std::uint8_t kN_Cl = 0x80;                 // dpc31 Dout_Buffer_SM bit 7
constexpr std::uint8_t kU_Buffer_Cleared = 0x08;     // Next_Dout_Buffer_Cmd bit 3
constexpr std::uint8_t kState_U_Buffer = 0x04;       // Next_Dout_Buffer_Cmd bit 2
const Bytes kSubstitute = {0x5A, 0x5B, 0x5C, 0x5D};  // the user's values in the C buffer
// A Global_Control has no answer: the master's call returns at its last stop bit, before the
// user's ISR has run. 100 us of bus idle let it run.
constexpr std::uint64_t kIsrTime = 4'800;

ResponderConfig with_substitute() {
  ResponderConfig rc;
  rc.substitute = kSubstitute;
  return rc;
}

// A dpc31 slave in Data_Exchange whose user side only acknowledges: the test fetches.
struct ClearBench {
  Bench b{Profile::dpc31, 1'500'000, with_substitute()};
  AckOnly user;
  std::vector<std::uint64_t> irq_on;  // cycles X/INT went active

  ClearBench() {
    EXPECT_TRUE(b.master.startup());
    // Start-up hands the cleared D to the user (power-on, SPC3 p.23); the responder took it.
    b.master.set_firmware([this](BusPort& c) { user.isr(c); });
    b.chip.on_irq_change([this](std::uint64_t cyc, bool active) {
      if (active) irq_on.push_back(cyc);
    });
  }
  std::uint8_t dout_sm() { return b.chip.read(conformance::addr(b.chip, RegId::Dout_Buffer_SM)); }
  std::uint8_t next_dout() {
    return b.chip.read(conformance::addr(b.chip, RegId::Next_Dout_Buffer_Cmd));
  }
  Bytes u_data(std::uint8_t next_dout_result) {
    const std::uint32_t base =
        conformance::buffer_base(b.chip, conformance::dout_ptr(next_dout_result & 3u));
    return conformance::read_ram(b.chip, base, 4);
  }
  // The last ISR entry saw DX_Out.
  bool saw_dx_out_since(std::size_t n) const {
    for (std::size_t k = n; k < user.seen.size(); ++k)
      if ((user.seen[k].second & irq::DX_Out) != 0) return true;
    return false;
  }
};

// "Clear_Data: ... the mode 'N_Cl=1' is set in the Dout_Buffer_SM, and the user interrupt
// 'DX_OUT' is generated. If the user then fetches his new Dout data, the C and U buffers are
// exchanged and the user gets the message 'U_Buffer_Cleared'." (seed 003, p.32) — also when the
// Clear is the first output event after start-up (the user's U holds the power-on clear).
TEST(Dpc31ClearData, SetsNClRaisesDxOutAndHandsOverC_FirstEventAfterStartup) {
  ClearBench cb;
  const unsigned u = (cb.dout_sm() >> 4) & 3u;
  const std::size_t seen = cb.user.seen.size();
  const Exchange gc = cb.b.master.global_control(kGC_Clear_Data);
  ASSERT_FALSE(cb.irq_on.empty());
  EXPECT_EQ(cb.irq_on.back(), cb.b.acted(gc));  // DX_Out latched when the GC is acted on
  EXPECT_TRUE(cb.saw_dx_out_since(seen));
  EXPECT_EQ(cb.dout_sm() & kN_Cl, kN_Cl);
  const std::uint8_t r = cb.next_dout();
  EXPECT_EQ(r, kU_Buffer_Cleared | kState_U_Buffer | u);  // U keeps its number, C swapped in
  EXPECT_EQ(cb.u_data(r), kSubstitute);
  EXPECT_EQ(cb.dout_sm() & kN_Cl, 0);
}

// "To support the failsafe mode, the DPC31 also accepts Write_Read_Data messages without output
// data ... After the receipt of this message, the C buffer where the substitute values are
// stored, is then included in the buffer cycle." (seed 003, p.33)
TEST(Dpc31Failsafe, DataExchangeWithoutOutputsHandsOverC_FirstEventAfterStartup) {
  ClearBench cb;
  const unsigned u = (cb.dout_sm() >> 4) & 3u;
  const Exchange dx = cb.b.master.data_exchange({});
  EXPECT_EQ(conformance::wire(dx.answer),
            (Bytes{0x68, 0x07, 0x07, 0x68, 0x02, 0x05, 0x08, 0xA1, 0xA2, 0xA3, 0xA4, 0x99, 0x16}));
  ASSERT_FALSE(cb.irq_on.empty());
  EXPECT_EQ(cb.irq_on.back(), cb.b.acted(dx));
  EXPECT_EQ(cb.dout_sm() & kN_Cl, kN_Cl);
  const std::uint8_t r = cb.next_dout();
  EXPECT_EQ(r, kU_Buffer_Cleared | kState_U_Buffer | u);
  EXPECT_EQ(cb.u_data(r), kSubstitute);
}

// The same after a Leave_Master (User_Leave_Master, then the master starts over) and after a DP
// watchdog expiry (WD_DP_Control_Timeout, seed 002): the first Clear still delivers C.
TEST(Dpc31ClearData, HandsOverCAfterLeaveMasterAndAfterWatchdogExpiry) {
  for (const bool by_watchdog : {false, true}) {
    SCOPED_TRACE(by_watchdog ? "DP watchdog expiry" : "User_Leave_Master");
    Bench b(Profile::dpc31, 1'500'000, with_substitute());
    ASSERT_TRUE(b.master.startup());
    if (by_watchdog) {
      b.master.idle(48'000'000ull + 48'000);  // TWD = 10 ms x 10 x 10 = 1 s at 48 MHz, + 1 ms
      ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
    } else {
      testutil::user_leave_master(b.chip);  // User_Leave_Master
      ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
    }
    ASSERT_TRUE(b.master.restart(200, 3));
    ASSERT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
    const std::size_t n = b.user.outputs.size();
    b.master.global_control(kGC_Clear_Data);
    b.master.idle(kIsrTime);
    ASSERT_EQ(b.user.outputs.size(), n + 1);
    EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
    EXPECT_TRUE(b.user.outputs.back().cleared);
  }
}

// Clear while N still holds outputs the user has not fetched: the fetch hands over C, and the
// outputs from before the Clear never reach the user afterwards (modelled, docs/decisions.md).
TEST(Dpc31ClearData, WhileNHoldsUnfetchedOutputs) {
  ClearBench cb;
  cb.b.master.data_exchange({0x01, 0x02, 0x03, 0x04});  // into N, not fetched
  cb.b.master.global_control(kGC_Clear_Data);
  const std::uint8_t r = cb.next_dout();
  EXPECT_EQ(r & (kU_Buffer_Cleared | kState_U_Buffer), kU_Buffer_Cleared | kState_U_Buffer);
  EXPECT_EQ(cb.u_data(r), kSubstitute);
  const std::uint8_t again = cb.next_dout();
  EXPECT_EQ(again & kState_U_Buffer, 0);  // nothing new: the stale outputs are gone
  EXPECT_EQ(cb.u_data(again), kSubstitute);
}

// A Clear, then new outputs before the user fetches: the master has left Clear; the user gets
// the new outputs, not the substitute values (modelled: real outputs handed to N end N_Cl).
TEST(Dpc31ClearData, NewOutputsBeforeTheFetchWin) {
  ClearBench cb;
  cb.b.master.global_control(kGC_Clear_Data);
  cb.b.master.data_exchange({0x11, 0x12, 0x13, 0x14});
  EXPECT_EQ(cb.dout_sm() & kN_Cl, 0);
  const std::uint8_t r = cb.next_dout();
  EXPECT_EQ(r & (kU_Buffer_Cleared | kState_U_Buffer), kState_U_Buffer);
  EXPECT_EQ(cb.u_data(r), (Bytes{0x11, 0x12, 0x13, 0x14}));
}

// Sync and Clear_Data in one Control_Command: one DX_Out, the user gets C once.
TEST(Dpc31ClearData, SyncAndClearDataInOneCommand) {
  Bench b(Profile::dpc31, 1'500'000, with_substitute());
  ASSERT_TRUE(b.master.startup());
  const std::size_t n = b.user.outputs.size();
  const std::size_t irqs = b.user.interrupts.size();
  b.master.global_control(kGC_Sync | kGC_Clear_Data);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), n + 1);
  EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
  EXPECT_TRUE(b.user.outputs.back().cleared);
  std::size_t dx_outs = 0;
  for (std::size_t k = irqs; k < b.user.interrupts.size(); ++k)
    dx_outs += (b.user.interrupts[k].second & irq::DX_Out) != 0 ? 1 : 0;
  EXPECT_EQ(dx_outs, 1u);
}

// A dpc31 slave in Sync mode whose D holds the outputs 21..24, not yet handed to the user.
struct SyncHeldBench {
  Bench b{Profile::dpc31, 1'500'000, with_substitute()};
  std::size_t n = 0;  // the user's fetches before 21..24

  SyncHeldBench() {
    EXPECT_TRUE(b.master.startup());
    b.master.global_control(kGC_Sync);
    b.master.idle(kIsrTime);
    n = b.user.outputs.size();
    b.master.data_exchange({0x21, 0x22, 0x23, 0x24});
    EXPECT_EQ(b.user.outputs.size(), n);
  }
  std::uint8_t dout_sm() { return b.chip.read(conformance::addr(b.chip, RegId::Dout_Buffer_SM)); }
  void mask_all(bool masked) {
    const std::uint32_t mask = conformance::addr(b.chip, RegId::Int_Mask_Reg);
    b.chip.write(mask, masked ? 0xFF : 0x00);
    b.chip.write(mask + 1, masked ? 0xFF : 0x00);
  }
};

// Outputs a Sync holds in D, then a clear (Clear_Data or a fail-safe exchange), then the next Sync
// or Unsync. Clear_Data "is not deleted and it is not changed" for D, but the user is to get the
// substitute values ("the C and U buffers are exchanged ... 'U_Buffer_Cleared'", seed 003 p.32),
// and the Sync/Unsync hand-over is of "the previously transferred output data" — transferred
// before the clear, so older than it: modelled, they never reach the user (docs/decisions.md,
// "stale outputs must not come back"; the SPC3 and VPC3+ clear D itself). The release raises
// DX_Out and hands nothing over: Next_Dout_Buffer_Cmd = U_Buffer_Cleared | the same U.
TEST(Dpc31ClearData, OutputsHeldBySyncBeforeAClearNeverReachTheUser) {
  for (const bool failsafe : {false, true}) {
    for (const std::uint8_t release : {kGC_Sync, kGC_Unsync}) {
      SCOPED_TRACE(failsafe ? "fail-safe exchange" : "Clear_Data");
      SCOPED_TRACE(release == kGC_Sync ? "Sync" : "Unsync");
      SyncHeldBench sb;
      Bench& b = sb.b;
      if (failsafe) {
        b.master.data_exchange({});
      } else {
        b.master.global_control(kGC_Clear_Data);
      }
      b.master.idle(kIsrTime);
      ASSERT_EQ(b.user.outputs.size(), sb.n + 1);
      EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
      EXPECT_TRUE(b.user.outputs.back().cleared);
      const std::size_t irqs = b.user.interrupts.size();
      b.master.global_control(release);
      b.master.idle(kIsrTime);
      ASSERT_GT(b.user.interrupts.size(), irqs);
      EXPECT_NE(b.user.interrupts[irqs].second & irq::DX_Out, 0);  // the Sync is still signalled
      EXPECT_EQ(b.user.outputs.size(), sb.n + 1);                  // but 21..24 stay unseen
      const unsigned u = (sb.dout_sm() >> 4) & 3u;
      EXPECT_EQ(b.chip.read(conformance::addr(b.chip, RegId::Next_Dout_Buffer_Cmd)),
                kU_Buffer_Cleared | u);
      // Outputs after the clear are handed over as ever: the master has left Clear.
      b.master.data_exchange({0x31, 0x32, 0x33, 0x34});
      if (release == kGC_Sync) b.master.global_control(kGC_Sync);
      b.master.idle(kIsrTime);
      ASSERT_EQ(b.user.outputs.size(), sb.n + 2);
      EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x31, 0x32, 0x33, 0x34}));
      EXPECT_FALSE(b.user.outputs.back().cleared);
    }
  }
}

// The same with a slow user: every interrupt masked over the clear and the next Sync. The Sync
// hands no buffer over, so Dout_Buffer_SM is the ring as before with N_Cl (bit 7) added when the
// user looks, and its one fetch gets the substitute values flagged U_Buffer_Cleared: the user
// learns the master went to Clear.
TEST(Dpc31ClearData, AUserWithInterruptsMaskedOverClearAndSyncStillGetsTheClear) {
  SyncHeldBench sb;
  Bench& b = sb.b;
  const std::uint8_t ring = sb.dout_sm();
  ASSERT_EQ(ring & kN_Cl, 0);
  sb.mask_all(true);
  b.master.global_control(kGC_Clear_Data);
  b.master.global_control(kGC_Sync);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), sb.n);  // the user has not looked yet
  EXPECT_EQ(sb.dout_sm(), ring | kN_Cl);
  sb.mask_all(false);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), sb.n + 1);
  EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
  EXPECT_TRUE(b.user.outputs.back().cleared);
}

// Once per clear, in every order: repeated Clear_Data and fail-safe exchanges while the master
// stays in Clear hand the substitute values over once; real outputs end the clear; the next
// Clear hands them over again (the firmware refilled the new C after the first fetch).
TEST(Dpc31ClearData, OncePerClearInEveryOrder) {
  Bench b(Profile::dpc31, 1'500'000, with_substitute());
  ASSERT_TRUE(b.master.startup());
  const std::size_t n = b.user.outputs.size();
  b.master.data_exchange({});
  b.master.global_control(kGC_Clear_Data);
  b.master.data_exchange({});
  b.master.global_control(kGC_Clear_Data);
  b.master.data_exchange({});
  ASSERT_EQ(b.user.outputs.size(), n + 1);
  EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
  b.master.data_exchange({0x21, 0x22, 0x23, 0x24});
  ASSERT_EQ(b.user.outputs.size(), n + 2);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x21, 0x22, 0x23, 0x24}));
  EXPECT_FALSE(b.user.outputs.back().cleared);
  b.master.global_control(kGC_Clear_Data);
  b.master.data_exchange({});
  ASSERT_EQ(b.user.outputs.size(), n + 3);
  EXPECT_EQ(b.user.outputs.back().data, kSubstitute);
  EXPECT_TRUE(b.user.outputs.back().cleared);
}

class SpcClear : public ::testing::TestWithParam<Profile> {};

// SPC3 / VPC3+ (chip-facts §5.1, VPC3+S p.53): Clear_Data clears D and passes it to N with
// DX_Out; the user reads R_Len_Dout_Buf zero bytes flagged U_Buffer_Cleared.
TEST_P(SpcClear, ClearDataDeliversZeroedOutputsFlaggedCleared) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x31, 0x32, 0x33, 0x34});
  const std::size_t n = b.user.outputs.size();
  b.master.global_control(kGC_Clear_Data);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), n + 1);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0, 0, 0, 0}));
  EXPECT_TRUE(b.user.outputs.back().cleared);
}

INSTANTIATE_TEST_SUITE_P(Profiles, SpcClear, ::testing::Values(Profile::spc3, Profile::vpc3plus),
                         [](const auto& i) { return testutil::pname(i.param); });

class Sync : public ::testing::TestWithParam<Profile> {};

// "Bit 5: Sync — The output data transferred with a Write_Read_Data message is changed from 'D'
// to 'N' (DX_OUT interrupt is generated). The subsequently transferred output data is kept in 'D'
// until the next 'Sync' command is made." "Bit 4: Unsync — cancels the 'Sync' command. In
// addition, as in the case of 'Sync', the previously transferred output data is changed from 'D'
// to 'N'." (seed 003, p.32)
TEST_P(Sync, SyncHoldsOutputsInDUntilTheNextSyncUnsyncReleases) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(kGC_Sync);
  const std::size_t n = b.user.outputs.size();
  b.master.data_exchange({0x41, 0x42, 0x43, 0x44});
  EXPECT_EQ(b.user.outputs.size(), n);  // kept in D
  const Exchange sync = b.master.global_control(kGC_Sync);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), n + 1);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x41, 0x42, 0x43, 0x44}));
  EXPECT_GE(b.user.outputs.back().cycle, b.acted(sync));
  b.master.data_exchange({0x51, 0x52, 0x53, 0x54});
  EXPECT_EQ(b.user.outputs.size(), n + 1);
  b.master.global_control(kGC_Unsync);
  b.master.idle(kIsrTime);
  ASSERT_EQ(b.user.outputs.size(), n + 2);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x51, 0x52, 0x53, 0x54}));
  b.master.data_exchange({0x61, 0x62, 0x63, 0x64});  // Sync cancelled: straight to the user
  ASSERT_EQ(b.user.outputs.size(), n + 3);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x61, 0x62, 0x63, 0x64}));
}

// Sync (and Unsync) with nothing new in D: the manual's wording is unconditional ("DX_OUT
// interrupt is generated"); no buffer changes hands, so Next_Dout_Buffer_Cmd reports no new U
// ("the buffer exchange is omitted", VPC3+S p.53). Modelled: docs/decisions.md.
TEST_P(Sync, SyncWithNothingNewInDStillRaisesDxOutButHandsNothingOver) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  std::vector<std::uint64_t> on;
  b.chip.on_irq_change([&on](std::uint64_t c, bool a) {
    if (a) on.push_back(c);
  });
  for (const std::uint8_t cmd : {kGC_Sync, kGC_Unsync}) {
    SCOPED_TRACE(cmd);
    const std::size_t seen = user.seen.size();
    const Exchange gc = b.master.global_control(cmd);
    ASSERT_FALSE(on.empty());
    EXPECT_EQ(on.back(), b.acted(gc));
    ASSERT_GT(user.seen.size(), seen);
    EXPECT_NE(user.seen[seen].second & irq::DX_Out, 0);
    const std::uint8_t r = b.chip.read(conformance::addr(b.chip, RegId::Next_Dout_Buffer_Cmd));
    EXPECT_EQ(r & kState_U_Buffer, 0);
  }
}

// manual-quotes.md Confirmed (ProSoft PTQ-PDPMV1): Sync and Unsync in one Control_Command:
// "Function will be inactive" — the chip does not enter Sync mode (Unsync wins, docs/decisions.md):
// the next Data_Exchange's outputs reach the user at once, not held in D.
TEST_P(Sync, SyncAndUnsyncTogetherLeaveSyncInactive) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(kGC_Sync | kGC_Unsync);
  b.master.idle(kIsrTime);
  const std::size_t n = b.user.outputs.size();
  b.master.data_exchange({0x71, 0x72, 0x73, 0x74});
  ASSERT_EQ(b.user.outputs.size(), n + 1);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0x71, 0x72, 0x73, 0x74}));
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[1] & 0x20, 0);  // St2 bit 5 Sync_Mode: off
}

INSTANTIATE_TEST_SUITE_P(Profiles, Sync, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

}  // namespace
