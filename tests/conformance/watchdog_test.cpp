// Seed 002 (SPC3 watchdog text, copied in ProSoft MVI56-PDPS p.66) and the watchdog items of
// manual-quotes.md "Confirmed", sentence by sentence. Cycles at 48 MHz (docs/timing.md): 1 ms =
// 48 000 clocks, 10 ms = 480 000; a request is acted on at the stop sample of its last
// character (end - T + T/2), which restarts the watchdog; a bus read completes 4 clocks after
// it starts and sees what happened up to and including that cycle.
#include "conformance.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

constexpr std::uint64_t k1ms = 48'000;
constexpr std::uint64_t k10ms = 480'000;

// Responder default WD_Baud_Control_Val = 10h = 16. SPC3 / DPC31: 16 x 10 ms = 160 ms; VPC3+S
// p.39: "multiplying twice WD_BAUD_CONTROL_Val ... by the time base (10 ms)": 2 x 16 x 10 ms.
std::uint64_t baud_control_time(Profile p) { return (p == Profile::vpc3plus ? 2 : 1) * 16 * k10ms; }

// Status_Reg low byte read so that the read completes exactly at `at` (Intel: bits 7..0 at the
// register's address).
std::uint8_t status_low_at(Chip& c, std::uint64_t at) {
  c.step(at - 4 - c.cycle());
  return c.read(rd(c, RegId::Status_Reg));
}

// Switches the VPC3+'s watchdog time base to 1 ms: Mode_Reg0.WD_Base (bit 2, chip-facts §4.1,
// [S-VPC3-CFG]) can only be written Offline, so Go_Offline, write, Start again.
void vpc3_wd_base_1ms(Chip& c) {
  testutil::user_go_offline(c);
  const std::uint16_t m0 = testutil::bus_read16(c, static_cast<int>(rd(c, RegId::Mode_Reg0)), 16);
  testutil::bus_write16(c, static_cast<int>(wr(c, RegId::Mode_Reg0)), 16,
                        static_cast<std::uint16_t>(m0 | 0x0004));
  testutil::user_start(c);
}

ResponderConfig wd(bool on, std::uint8_t f1 = 10, std::uint8_t f2 = 10, bool base_1ms = false) {
  ResponderConfig rc;
  rc.slave.wd_on = on;
  rc.slave.wd_fact1 = f1;
  rc.slave.wd_fact2 = f2;
  rc.slave.wd_base_1ms = base_1ms;
  return rc;
}

class Watchdog : public ::testing::TestWithParam<Profile> {};

std::string profile_name_of(const ::testing::TestParamInfo<Profile>& i) {
  return testutil::pname(i.param);
}

}  // namespace

// Seed 002: "The watchdog is reset for each error-free telegram to its own station address. The
// monitoring time results from multiplying ... 'WD_Baud_Control_Val' ... by the time base (10
// ms). If the monitoring time runs out, WD_SM again goes to 'Baud_Search'." WD_On = 0 keeps the
// watchdog in Baud_Control. Expiry at acted(last telegram) + 160 ms (VPC3+: 320 ms): a read
// completing one clock earlier sees WD_State 01, one completing at the expiry 00.
TEST_P(Watchdog, BaudControl_MonitoringTimeWdBaudControlValTimes10ms) {
  for (std::uint64_t late : {0u, 1u}) {
    Bench b(GetParam(), 12'000'000, wd(false));
    ASSERT_TRUE(b.master.startup());
    const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
    b.master.idle(2000);  // the ISR fetches the outputs
    const std::uint64_t expiry = b.acted(dx) + baud_control_time(GetParam());
    const std::uint8_t s = status_low_at(b.chip, expiry - 1 + late);
    EXPECT_EQ(wd_bits(s), late != 0 ? kBaudSearch : kBaudControl) << "late " << late;
  }
}

// Seed 002: "The watchdog is reset for each error-free telegram to its own station address."
// Telegrams to us every 100 ms keep Baud_Control (160 ms) alive for 500 ms; telegrams to
// station 9 every 50 ms afterwards do not: it runs out 160 ms after the last one to us (read at
// +161 ms, before the next foreign telegram at +200 ms could make a new Baud_Search find the
// rate again).
TEST_P(Watchdog, BaudControl_ResetOnlyByTelegramsToOwnStationAddress) {
  Bench b(GetParam(), 12'000'000, wd(false));
  ASSERT_TRUE(b.master.startup());
  Exchange own = b.master.fdl_status();
  for (int i = 0; i < 5; ++i) {
    b.master.idle(b.acted(own) + 100 * k1ms - b.chip.cycle());
    own = b.master.fdl_status();
    ASSERT_TRUE(own.answer);
    EXPECT_EQ(wd_bits(status(b.chip)), kBaudControl) << i;
  }
  const std::uint64_t last = b.acted(own);
  b.master.set_target(9);
  for (int i = 1; i <= 3; ++i) {
    b.master.idle(last + static_cast<std::uint64_t>(i) * 50 * k1ms - b.chip.cycle());
    b.master.fdl_status();  // to station 9: nobody answers
  }
  const std::uint64_t expiry = last + baud_control_time(GetParam());
  EXPECT_EQ(wd_bits(status_low_at(b.chip, expiry - 1)), kBaudControl);
  EXPECT_EQ(wd_bits(status_low_at(b.chip, expiry + k1ms)), kBaudSearch);
}

// Seed 002: "The watchdog timer remains in the baud rate monitoring state when there is a
// switched off 'WD_On = 0' master monitoring. The PROFIBUS DP state machine is also not reset
// when the timer runs out. That is, the slave remains in the DATA_Exchange state." Also
// manual-quotes.md Confirmed: "Baud_Control expiry does not reset the DP state machine."
TEST_P(Watchdog, WdOn0_BaudControlExpiryKeepsDataExchange) {
  Bench b(GetParam(), 12'000'000, wd(false));
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(wd_bits(status(b.chip)), kBaudControl);
  const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
  const std::uint64_t expiry = b.acted(dx) + baud_control_time(GetParam());
  const std::uint8_t s = status_low_at(b.chip, expiry);
  EXPECT_EQ(wd_bits(s), kBaudSearch);
  EXPECT_EQ(dp_bits(s), kDataEx);
  // Baud_Search starts again at 12 Mbaud (the rate in use): the next exchange is heard in the
  // first window and answered with the inputs, the outputs reach the user (after TSYN of idle:
  // the search reconfigured the receiver at the expiry).
  b.master.idle(100 * b.T());
  const Exchange again = b.master.data_exchange({5, 6, 7, 8});
  ASSERT_TRUE(again.answer);
  EXPECT_EQ(again.answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
  b.master.idle(2000);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{5, 6, 7, 8}));
  EXPECT_EQ(dp_bits(status(b.chip)), kDataEx);
}

// Seed 002: "If the user carries out the DP protocol (DP_Mode = 1 ...) with SPC3, the watchdog
// is used for the 'DP_Control' state, after a 'Set_Param telegram' was received with an enabled
// response time monitoring 'WD_On = 1'." Before the Set_Prm the rate is only monitored
// (Baud_Control, 01); after the start-up WD_State is 10.
TEST_P(Watchdog, DpControl_AfterSetPrmWithWdOn1) {
  Bench b(GetParam(), 12'000'000, wd(true));
  ASSERT_TRUE(b.master.fdl_status().answer);  // 12 Mbaud: heard in the first search window
  EXPECT_EQ(wd_bits(status(b.chip)), kBaudControl);
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(wd_bits(status(b.chip)), kDpControl);
}

// A user that gives User_Prm_Data_Okay only after Baud_Control ran out (docs/decisions.md, "The
// twenty-ninth session: s29-chip"; seed 002: "the watchdog is used for the 'DP_Control' state,
// after a 'Set_Param telegram' was received with ... WD_On = 1"): the request that finds the rate
// again enters DP_Control and restarts it, so a pulled cable makes Wait_Prm exactly TWD (10 x 10 x
// 10 ms = 48 000 000 clocks) after that request is acted on (docs/timing.md, "DP watchdog"). First
// the same Okay followed by the user's Leave_Master before the rate is found: no master is left
// to monitor, so that rate found enters Baud_Control.
TEST_P(Watchdog, DpControl_AfterSetPrmWithWdOn1_AcceptedInBaudSearch) {
  ResponderConfig rc = wd(true);
  rc.wd_baud_control = 1;  // 10 ms (20 ms on the VPC3+)
  Bench b(GetParam(), 12'000'000, rc);
  const int mask = b.chip.addr_of(RegId::Int_Mask_Reg);
  const std::uint16_t user_mask = testutil::bus_read16(b.chip, mask, 16);
  // The master parameterises the slave while the user is busy (no interrupt served); Baud_Control
  // runs out before the user accepts.
  const auto okay_in_baud_search = [&] {
    testutil::bus_write16(b.chip, mask, 16, 0xFFFF);
    EXPECT_FALSE(b.master.startup(6));
    EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
    b.master.idle(20 * 48'000);
    ASSERT_EQ(b.chip.wd_state(), WdState::Baud_Search);
    testutil::bus_write16(b.chip, mask, 16, user_mask);  // Prm OK, Cfg OK now
    b.master.idle(48'000);
    ASSERT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
    ASSERT_EQ(b.chip.wd_state(), WdState::Baud_Search);
  };
  ASSERT_NO_FATAL_FAILURE(okay_in_baud_search());
  testutil::user_leave_master(b.chip);
  b.master.idle(48'000);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_TRUE(b.master.slave_diag().answer);  // finds the rate
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);

  ASSERT_NO_FATAL_FAILURE(okay_in_baud_search());
  const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  const std::uint64_t expiry = b.acted(dx) + 48'000'000;
  b.master.idle(expiry - 1 - b.chip.cycle());  // cable pulled
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  b.chip.step(1);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
  EXPECT_NE(b.chip.peek_reg(RegId::Int_Req_Reg) & irq::WD_DP_Control_Timeout, 0u);
}

// Seed 002: "TWD = (1 ms or 10 ms) * WD_Fact_1 * WD_Fact_2". 10 ms x 10 x 10 = 1 s = 48 000 000
// clocks after the last Data_Exchange was acted on, the WD_DP_Control_Timeout interrupt (X/INT
// goes active and the ISR starts in that cycle); nothing between.
namespace {

// One Data_Exchange, then silence: the WD_DP_Control_Timeout interrupt comes exactly `twd`
// clocks after the exchange was acted on, and no interrupt before it.
void expect_timeout_after(Bench& b, std::uint64_t twd) {
  ASSERT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
  b.master.idle(2000);
  const std::uint64_t expiry = b.acted(dx) + twd;
  b.master.idle(expiry + 2000 - b.chip.cycle());
  EXPECT_EQ(first_isr_after(b.user, b.acted(dx) + 2000), expiry);
  EXPECT_TRUE(isr_saw(b.user, expiry, irq::WD_DP_Control_Timeout));
}

}  // namespace

TEST_P(Watchdog, Twd_TimeBase10msTimesFact1TimesFact2) {
  Bench b(GetParam(), 12'000'000, wd(true, 10, 10));
  expect_timeout_after(b, 10 * 10 * k10ms);
}

// Seed 002: TWD with the 1 ms base. Set_Prm byte 7 bit 2 (WD_Base) on the SPC3 / DPC31
// (chip-facts §8, [S-PRM]); the VPC3+ takes the base from Mode_Reg0.WD_Base (chip-facts §4.1).
// 1 ms x 5 x 7 = 35 ms = 1 680 000 clocks.
TEST_P(Watchdog, Twd_TimeBase1msTimesFact1TimesFact2) {
  Bench b(GetParam(), 12'000'000, wd(true, 5, 7, GetParam() != Profile::vpc3plus));
  if (GetParam() == Profile::vpc3plus) vpc3_wd_base_1ms(b.chip);
  expect_timeout_after(b, 5 * 7 * k1ms);
}

// Seed 002: "The user can load the two watchdog factors ... via the 'Set_Param telegram' with
// any value between 1 and 255." 1 ms x 255 x 1 = 255 ms and 1 ms x 1 x 255 = 255 ms =
// 12 240 000 clocks; 1 ms x 3 x 255 = 765 ms = 36 720 000.
TEST_P(Watchdog, WdFactors_AnyValueBetween1And255) {
  for (auto [f1, f2] : {std::pair<std::uint8_t, std::uint8_t>{255, 1}, {1, 255}, {3, 255}}) {
    Bench b(GetParam(), 12'000'000, wd(true, f1, f2, GetParam() != Profile::vpc3plus));
    if (GetParam() == Profile::vpc3plus) vpc3_wd_base_1ms(b.chip);
    ASSERT_TRUE(b.master.startup());
    const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
    b.master.idle(2000);
    const std::uint64_t expiry = b.acted(dx) + std::uint64_t{f1} * f2 * k1ms;
    b.master.idle(expiry + 2000 - b.chip.cycle());
    EXPECT_EQ(first_isr_after(b.user, b.acted(dx) + 2000), expiry) << int(f1) << "x" << int(f2);
    EXPECT_TRUE(isr_saw(b.user, expiry, irq::WD_DP_Control_Timeout)) << int(f1) << "x" << int(f2);
  }
}

// Seed 002: "EXCEPTION: The WD_Fact_1=WD_Fact_2=1 setting is not permissible. The circuit does
// not check this setting." The Set_Prm is accepted (Data_Exchange, no Prm_Fault in the diag)
// and the watchdog runs with 10 ms x 1 x 1 = 480 000 clocks.
TEST_P(Watchdog, WdFact1EqualsWdFact2Equals1_NotCheckedByTheCircuit) {
  Bench b(GetParam(), 12'000'000, wd(true, 1, 1));
  ASSERT_TRUE(b.master.startup());
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[0] & 0x40, 0);  // St1 bit 6 Prm_Fault
  const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
  ASSERT_TRUE(dx.answer);
  b.master.idle(2000);
  const std::uint64_t expiry = b.acted(dx) + k10ms;
  b.master.idle(expiry + 2000 - b.chip.cycle());
  EXPECT_EQ(first_isr_after(b.user, b.acted(dx) + 2000), expiry);
  EXPECT_TRUE(isr_saw(b.user, expiry, irq::WD_DP_Control_Timeout));
}

// Seed 002: "Monitoring times between 2 ms and 650 s - independent of the baud rate - can be
// implemented". 2 ms = 1 ms x 1 x 2 = 96 000 clocks at 12 M and 1.5 Mbaud (at lower rates a
// start-up telegram sequence lasts longer than 2 ms); 650 s = 10 ms x 255 x 255 = 650.25 s =
// 31 212 000 000 clocks at 12 M and 9.6 kbaud.
class WatchdogRange : public ::testing::TestWithParam<std::tuple<Profile, std::uint32_t>> {};

TEST_P(WatchdogRange, MonitoringTime2msTo650sIndependentOfBaudRate) {
  const auto [profile, baud] = GetParam();
  struct Case {
    std::uint8_t f1, f2;
    bool base_1ms;
    std::uint64_t twd;
  };
  std::vector<Case> cases = {{255, 255, false, 255ull * 255 * k10ms}};
  if (baud >= 1'500'000) cases.push_back({1, 2, true, 2 * k1ms});
  for (const Case& k : cases) {
    Bench b(profile, baud, wd(true, k.f1, k.f2, k.base_1ms && profile != Profile::vpc3plus));
    if (k.base_1ms && profile == Profile::vpc3plus) vpc3_wd_base_1ms(b.chip);
    ASSERT_TRUE(b.master.startup());
    const Exchange dx = b.master.data_exchange({1, 2, 3, 4});
    ASSERT_TRUE(dx.answer);
    const std::uint64_t after = dx.answer_end + 2000;
    b.master.idle(after - b.chip.cycle());
    const std::uint64_t expiry = b.acted(dx) + k.twd;
    b.master.idle(expiry + 2000 - b.chip.cycle());
    EXPECT_EQ(first_isr_after(b.user, after), expiry) << k.twd;
    EXPECT_TRUE(isr_saw(b.user, expiry, irq::WD_DP_Control_Timeout)) << k.twd;
  }
}

INSTANTIATE_TEST_SUITE_P(ProfilesAndRates, WatchdogRange,
                         ::testing::Combine(::testing::ValuesIn(kAllProfiles),
                                            ::testing::Values(9600u, 1'500'000u, 12'000'000u)),
                         testutil::profile_rate_name);

// Seed 002: "If the monitoring time runs out, the SPC3 goes again to 'Baud_Control,' and the
// SPC3 generates the 'WD_DP_Control_Timeout-Interrupt'. In addition, the DP_State machine is
// reset, that is, generates the reset states of the buffer management." (manual-quotes.md
// Confirmed, SPC3 p.25.) At the expiry: WD_State 01, DP_State 00 (Wait_Prm), the interrupt
// with Go_Leave_Data_Exchange and DX_Out (the output buffer cleared and passed on); the user
// fetches 00 00 00 00 with U_Buffer_Cleared; the master then sees Prm_Req.
TEST_P(Watchdog, DpControlExpiry_BaudControlTimeoutInterruptDpStateMachineReset) {
  ResponderConfig rc = wd(true, 10, 10);
  rc.substitute = {0x5A, 0x5B, 0x5C, 0x5D};
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({6, 6, 6, 6});
  b.master.idle(2000);
  const std::uint64_t expiry = b.acted(dx) + 100 * k10ms;
  b.master.idle(expiry + 2000 - b.chip.cycle());
  EXPECT_TRUE(isr_saw(b.user, expiry,
                      irq::WD_DP_Control_Timeout | irq::Go_Leave_Data_Exchange | irq::DX_Out));
  const std::uint16_t s = status(b.chip);
  EXPECT_EQ(wd_bits(s), kBaudControl);
  EXPECT_EQ(dp_bits(s), kWaitPrm);
  ASSERT_FALSE(b.user.outputs.empty());
  EXPECT_TRUE(b.user.outputs.back().cleared);
  EXPECT_EQ(b.user.outputs.back().data, (Bytes{0, 0, 0, 0}));
  const Exchange diag = b.master.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[1] & 0x01, 0x01);  // St2 bit 0 Prm_Req
}

// Seed 002: "If another master accepts SPC3, then there is either a switch to 'Baud_Control'
// (WD_On = 0), or there is a delay in 'DP_Control' (WD_On = 1)". Master 2 releases the slave
// (the user's User_Leave_Master, Mode_Reg1 bit 3); master 7 parameterises it: WD_On = 0 gives
// WD_State 01, WD_On = 1 gives 10.
TEST_P(Watchdog, AnotherMasterAccepts_WdOn0BaudControl_WdOn1DpControl) {
  for (const bool first_on : {true, false}) {
    Bench b(GetParam(), 12'000'000, wd(first_on));
    ASSERT_TRUE(b.master.startup());
    EXPECT_EQ(wd_bits(status(b.chip)), first_on ? kDpControl : kBaudControl);
    testutil::user_leave_master(b.chip);  // User_Leave_Master
    ASSERT_EQ(dp_bits(status(b.chip)), kWaitPrm);
    ResponderConfig other = wd(!first_on);
    DpMaster m7(b.chip, MasterConfig{7, 12'000'000, 100, 33}, other.slave);
    m7.set_firmware([&](BusPort& c) { b.user.isr(c); });
    ASSERT_TRUE(m7.startup()) << first_on;
    const std::uint16_t s = status(b.chip);
    EXPECT_EQ(dp_bits(s), kDataEx);
    EXPECT_EQ(wd_bits(s), first_on ? kBaudControl : kDpControl) << first_on;
  }
}

// Seed 002 "PROFIBUS Status Register ... Baud rate: Bits 0 to 3 The baud rates SPC3 found";
// chip-facts §3 coding: 0 12M, 1 6M, 2 3M, 3 1.5M, 4 500k, 5 187.5k, 6 93.75k, 7 45.45k,
// 8 19.2k, 9 9.6k (Status_Reg bits 11..8).
class BaudCode : public ::testing::TestWithParam<std::tuple<Profile, int>> {};

TEST_P(BaudCode, StatusBaudRateBits_TheRateFound) {
  const auto [profile, code] = GetParam();
  static constexpr std::uint32_t kRate[] = {12'000'000, 6'000'000, 3'000'000, 1'500'000, 500'000,
                                            187'500,    93'750,    45'450,    19'200,    9'600};
  Bench b(profile, kRate[code]);
  // Enough FDL_Status for the baud search from Start at every rate (docs/timing.md).
  for (int i = 0; i < dpc31::kStartupTries && !b.master.fdl_status().answer; ++i) {
  }
  const std::uint16_t s = status(b.chip);
  EXPECT_EQ((s >> 8) & 0x0F, code);
  EXPECT_EQ(wd_bits(s), kBaudControl);
}

INSTANTIATE_TEST_SUITE_P(ProfilesAndRates, BaudCode,
                         ::testing::Combine(::testing::ValuesIn(kAllProfiles),
                                            ::testing::Range(0, 10)),
                         [](const auto& i) {
                           return testutil::pname(std::get<0>(i.param)) + "_code" +
                                  std::to_string(std::get<1>(i.param));
                         });

// manual-quotes.md Confirmed: "Baud search from the highest rate; any error-free SD1/SD2/SD3
// telegram fixes the rate" (ProSoft copy of the SPC3 text), to any station. Right after
// Start_SPC3 the chip listens at 12 Mbaud (T = 4): an SD1 FDL_Status, an SD2 SRD and an SD3
// SRD, each to station 9, are acted on at end - 2: Baudrate_Detect (IRR bit 2) and WD_State 01
// there, not one clock earlier. Frames by hand: 10 09 02 49 54 16; 68 05 05 68 09 02 7D 01 02
// 8B 16; A2 09 02 7D 01..08 AC 16 (FCS = sum of DA..DU mod 256).
TEST_P(Watchdog, BaudSearch_AnyErrorFreeSd1Sd2Sd3TelegramFixesTheRate) {
  const std::vector<Bytes> frames = {
      {0x10, 0x09, 0x02, 0x49, 0x54, 0x16},
      {0x68, 0x05, 0x05, 0x68, 0x09, 0x02, 0x7D, 0x01, 0x02, 0x8B, 0x16},
      {0xA2, 0x09, 0x02, 0x7D, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0xAC, 0x16}};
  for (const Bytes& f : frames) {
    for (std::uint64_t late : {0u, 1u}) {
      Bare b(GetParam());
      const std::uint64_t end = send_on_rxd(b.chip, f, b.chip.cycle() + 33 * 4, 4);
      const std::uint64_t acted = end - 4 + 2;
      b.chip.step(acted - 1 + late - 4 - b.chip.cycle());
      const std::uint8_t ir = b.chip.read(rd(b.chip, RegId::Int_Req_Reg));  // bits 7..0
      EXPECT_EQ((ir & irq::Baudrate_Detect) != 0, late != 0) << int(f[0]) << " late " << late;
      if (late != 0) {
        const std::uint16_t s = status(b.chip);
        EXPECT_EQ(wd_bits(s), kBaudControl);
        EXPECT_EQ((s >> 8) & 0x0F, 0);  // 12 Mbaud
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, Watchdog, ::testing::ValuesIn(kAllProfiles), profile_name_of);
