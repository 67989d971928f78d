// The DP services and the DP state machine as the manuals state them (manual-quotes.md "Decisions
// the sources contradict"): DP_Control watches Master_Add, Global_Control only from Master_Add,
// the Set_Prm lock rules, Chk_Cfg in every DP state, FCB/FCV repetitions with new data, the
// SPC3's entry into Data_Exchange, DP_Mode = 0. Cycles per docs/timing.md: T = round(48 MHz /
// baud); a request is acted on at its last stop sample; the answer starts max(11, MinTSDR) bit
// times after the request's last stop bit.
#include "conformance.hpp"

using namespace dpc31;
using namespace conformance;  // the bench, the ISR that only acknowledges

namespace {

class DpServices : public ::testing::TestWithParam<Profile> {
 protected:
  // TWD = 10 ms x 2 x 5 = 100 ms = 4 800 000 clocks at 48 MHz (seed 002: TWD = base x F1 x F2).
  static ResponderConfig twd_100ms() {
    ResponderConfig rc;
    rc.slave.wd_fact1 = 2;
    rc.slave.wd_fact2 = 5;
    return rc;
  }
  static constexpr std::uint64_t kTwd = 4'800'000;
};

std::uint8_t read8(Chip& c, RegId id) { return c.read(addr(c, id)); }
std::uint16_t irr(Chip& c) {
  const std::uint8_t lo = c.read(addr(c, RegId::Int_Req_Reg));
  return static_cast<std::uint16_t>(lo | c.read(addr(c, RegId::Int_Req_Reg) + 1) << 8);
}

// Lets `other` talk to the slave (answered Slave_Diag, refused Data_Exchange, FDL_Status) every
// 10 ms until `until`.
void chatter(DpMaster& other, Chip& chip, std::uint64_t until) {
  while (chip.cycle() < until) {
    other.slave_diag();
    other.data_exchange({0x01, 0x02, 0x03, 0x04});
    other.fdl_status();
    other.idle(480'000);
  }
}

// SPC3 p.25: "The 'DP_Control' state serves response time monitoring of the DP master
// (Master_Add)." VPC3+S p.39 likewise (Diag_Master_Add). Another master's telegrams to our address
// — answered (Slave_Diag, FDL_Status) or refused (Data_Exchange: RS) — do not retrigger it: the
// watchdog expires TWD after the locking master's last request was acted on.
TEST_P(DpServices, DpControlMonitorsMasterAddNotOtherMasters) {
  Bench b(GetParam(), 1'500'000, twd_100ms());
  ASSERT_TRUE(b.master.startup());
  const std::uint64_t last = b.acted(b.master.history().back());
  std::vector<std::uint64_t> on;
  b.chip.on_irq_change([&on](std::uint64_t c, bool a) {
    if (a) on.push_back(c);
  });
  DpMaster other(b.chip, MasterConfig{7, 1'500'000, 100, 33}, twd_100ms().slave);
  other.set_firmware([&b](BusPort& c) { b.user.isr(c); });
  chatter(other, b.chip, last + kTwd + 480'000);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  ASSERT_FALSE(on.empty());
  EXPECT_EQ(on.front(), last + kTwd);  // WD_DP_Control_Timeout, Leave_Master
  ASSERT_FALSE(b.user.interrupts.empty());
  EXPECT_NE(b.user.interrupts.back().second & irq::WD_DP_Control_Timeout, 0);
}

// The locking master's own telegrams do keep it alive (control for the test above).
TEST_P(DpServices, DpControlIsRetriggeredByMasterAdd) {
  Bench b(GetParam(), 1'500'000, twd_100ms());
  ASSERT_TRUE(b.master.startup());
  for (int k = 0; k < 15; ++k) {
    b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
    b.master.idle(480'000);
  }
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
}

// DPC31 p.31: "The MAC accepts the Global_Control message only in the 'Data_Exchange' mode and
// only from 'Master_Add'." For each valid one the Control_Command byte is stored in GC_Command.
TEST_P(DpServices, GlobalControlOnlyInDataExchangeAndOnlyFromMasterAdd) {
  Bench b(GetParam());
  while (!b.master.fdl_status().answer) {  // the baud rate is found: Wait_Prm
  }
  const std::uint8_t preset = read8(b.chip, RegId::R_GC_Command);
  b.master.global_control(0x08);  // Freeze, before any Set_Prm
  EXPECT_EQ(read8(b.chip, RegId::R_GC_Command), preset);
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(0x08);
  EXPECT_EQ(read8(b.chip, RegId::R_GC_Command), 0x08);
  DpMaster other(b.chip, MasterConfig{7, 1'500'000, 100, 33}, SlaveConfig{});
  other.set_firmware([&b](BusPort& c) { b.user.isr(c); });
  const std::uint64_t refused = b.chip.fdl_counters().not_allowed;
  other.global_control(0x04);  // Unfreeze from a master that did not lock us
  EXPECT_EQ(read8(b.chip, RegId::R_GC_Command), 0x08);
  EXPECT_EQ(b.chip.fdl_counters().not_allowed, refused + 1);
}

// CP 5613/5614 DP Base manual p.198: Lock_Req = Unlock_Req = 0: "The min TSDR is overwritten when
// parameters are assigned. All other parameters remain unchanged." No Leave_Master, no
// New_Prm_Data; answers start min TSDR = 20 bit times after the request (timing.md).
TEST_P(DpServices, SetPrmWithoutLockOrUnlockTakesOnlyMinTsdr) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  const std::uint32_t prm_before = b.user.prm_accepted;
  const std::size_t irqs = b.user.interrupts.size();
  b.master.slave().min_tsdr = 20;
  b.master.slave().wd_on = false;  // would switch monitoring off if it were adopted
  const Exchange prm = b.master.set_prm_status(0x00);
  EXPECT_EQ(wire(prm.answer), Bytes{0xE5});
  // The new min TSDR already places the answer to this very telegram (modelled, as for a lock).
  EXPECT_EQ(prm.answer_start, prm.request_end + 20u * b.T());
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  EXPECT_EQ(b.user.prm_accepted, prm_before);
  for (std::size_t k = irqs; k < b.user.interrupts.size(); ++k)
    EXPECT_EQ(b.user.interrupts[k].second & (irq::New_Prm_Data | irq::Go_Leave_Data_Exchange), 0);
  const Exchange dx = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  ASSERT_TRUE(dx.answer);
  EXPECT_EQ(dx.answer_start, dx.request_end + 20u * b.T());
}

// "The Group_Ident is accepted only when the Lock_Req bit is set." (p.199): a Set_Prm without
// Lock_Req naming group 1 leaves Group_Ident 0, so a Global_Control to group 1 is not for us.
TEST_P(DpServices, GroupIdentOnlyWithLockReq) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  b.master.slave().group_ident = 0x01;
  b.master.set_prm_status(0x00);
  b.master.global_control(0x08, 0x01);
  EXPECT_NE(read8(b.chip, RegId::R_GC_Command), 0x08);
}

// A Set_Prm from another master while we are locked never re-parameterises, unlocks or changes
// min TSDR ("disabled for other masters").
TEST_P(DpServices, LockedSlaveIgnoresEverySetPrmOfAnotherMaster) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  SlaveConfig s = b.master.slave();
  s.min_tsdr = 30;
  DpMaster other(b.chip, MasterConfig{7, 1'500'000, 100, 33}, s);
  other.set_firmware([&b](BusPort& c) { b.user.isr(c); });
  other.fdl_status();
  for (const std::uint8_t status :
       {std::uint8_t{0x00}, kUnlock_Req, static_cast<std::uint8_t>(kLock_Req | kUnlock_Req),
        static_cast<std::uint8_t>(kLock_Req | kWD_On)}) {
    SCOPED_TRACE(static_cast<int>(status));
    EXPECT_EQ(wire(other.set_prm_status(status).answer), Bytes{0xE5});
    EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  }
  const Exchange diag = other.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[3], 2);  // Master_Add: still master 2
  const Exchange dx = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(dx.answer_start, dx.request_end + 11u * b.T());  // min TSDR untouched
}

// Unlock_Req (01, and 11): "released for other masters": the slave leaves its master (Wait_Prm,
// Master_Add FFh) and another master may lock and parameterise it.
TEST_P(DpServices, UnlockReleasesTheSlaveForOtherMasters) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(wire(b.master.set_prm_status(kUnlock_Req).answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);  // nobody to monitor
  DpMaster other(b.chip, MasterConfig{7, 1'500'000, 100, 33}, b.master.slave());
  other.set_firmware([&b](BusPort& c) { b.user.isr(c); });
  ASSERT_TRUE(other.startup());
  const Exchange diag = other.slave_diag();
  ASSERT_TRUE(diag.answer);
  EXPECT_EQ(diag.answer->du[3], 7);
}

// manual-quotes.md: the DP watchdog starts with the new TWD only once the parameters are accepted
// (User_Prm_Data_Okay), not when the Set_Prm arrives; then it expires TWD after the OK read
// completes if the master stays silent.
TEST_P(DpServices, DpWatchdogStartsAtUserPrmDataOkay) {
  Bench b(GetParam(), 1'500'000, twd_100ms());
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  while (!b.master.fdl_status().answer) {
  }
  b.master.slave_diag();
  b.master.set_prm();
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);  // the user has not said OK yet
  b.master.idle(48'000);
  EXPECT_EQ(b.chip.read(addr(b.chip, RegId::User_Prm_Data_Okay)), 0x00);
  const std::uint64_t ok = b.chip.cycle();  // the read completed here
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  b.chip.step(kTwd - 1);
  EXPECT_EQ(b.chip.wd_state(), WdState::DP_Control);
  b.chip.step(1);
  EXPECT_EQ(b.chip.cycle(), ok + kTwd);
  EXPECT_EQ(b.chip.wd_state(), WdState::Baud_Control);
}

// DPC31 p.28: Chk_Cfg "is accepted by DPS in any DP mode" from the locking master; with
// New_Prm_Data and New_Cfg_Data both pending the user acknowledges Set_Param, then Check_Config,
// and the slave reaches Data_Exchange.
TEST_P(DpServices, ChkCfgAcceptedInWaitPrmFromTheLockingMaster) {
  Bench b(GetParam());
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  while (!b.master.fdl_status().answer) {
  }
  b.master.set_prm();
  ASSERT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(wire(b.master.chk_cfg().answer), Bytes{0xE5});
  EXPECT_EQ(irr(b.chip) & (irq::New_Prm_Data | irq::New_Cfg_Data),
            irq::New_Prm_Data | irq::New_Cfg_Data);
  EXPECT_EQ(read8(b.chip, RegId::User_Prm_Data_Okay), 0x00);
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Cfg);
  EXPECT_EQ(read8(b.chip, RegId::User_Cfg_Data_Okay), 0x00);
  read8(b.chip, RegId::New_Din_Buffer_Cmd);  // inputs handed over (the SPC3 waits for them)
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

// "If the Check_Config message does not come from 'Master_Add' ... DPS ignores this message."
TEST_P(DpServices, ChkCfgFromAnotherMasterIsIgnored) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  const std::size_t irqs = b.user.interrupts.size();
  DpMaster other(b.chip, MasterConfig{7, 1'500'000, 100, 33}, b.master.slave());
  other.set_firmware([&b](BusPort& c) { b.user.isr(c); });
  other.fdl_status();
  other.chk_cfg();
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  for (std::size_t k = irqs; k < b.user.interrupts.size(); ++k)
    EXPECT_EQ(b.user.interrupts[k].second & irq::New_Cfg_Data, 0);
}

// SPC3 p.36 §6.2.8 (VPC3+C p.51): "If there is a buffer change from 'N' to 'U' (through the
// Next_Dout_Buffer_Cmd) between the first call-up and the repetition, the new output data is
// sent during the repetition."
TEST_P(DpServices, RdOutpRepetitionSendsTheNewOutputs) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  read8(b.chip, RegId::Next_Dout_Buffer_Cmd);  // U = 01..04
  b.master.data_exchange({0x05, 0x06, 0x07, 0x08});
  const Exchange first = b.master.read_outputs();
  ASSERT_TRUE(first.answer);
  EXPECT_EQ(first.answer->du, (Bytes{0x01, 0x02, 0x03, 0x04}));
  read8(b.chip, RegId::Next_Dout_Buffer_Cmd);               // N -> U: 05..08
  const Exchange again = b.master.transact(first.request);  // same FCB: a repetition
  ASSERT_TRUE(again.answer);
  EXPECT_EQ(again.answer->du, (Bytes{0x05, 0x06, 0x07, 0x08}));
}

// DPC31 p.33, Read_Inputs: "Between the initial call and the repetition if there is a buffer
// change from 'U' -> 'N' -> 'D' (through User_New_Din command), the new input data is sent at the
// repetition." (New_Din_Buffer_Cmd on the SPC3 interface.)
TEST_P(DpServices, RdInpRepetitionSendsTheNewInputs) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  AckOnly user;
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  const Exchange first = b.master.read_inputs();
  ASSERT_TRUE(first.answer);
  EXPECT_EQ(first.answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
  const unsigned u = (read8(b.chip, RegId::Din_Buffer_SM) >> 4) & 3u;
  static constexpr RegId kPtr[] = {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2,
                                   RegId::R_Din_Buf_Ptr3};
  const std::uint32_t base = conformance::buffer_base(b.chip, kPtr[u - 1]);
  for (std::uint32_t i = 0; i < 4; ++i) b.chip.write(base + i, static_cast<std::uint8_t>(0xB1 + i));
  read8(b.chip, RegId::New_Din_Buffer_Cmd);  // U -> N
  const Exchange again = b.master.transact(first.request);
  ASSERT_TRUE(again.answer);
  EXPECT_EQ(again.answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
}

// Mode_Reg0 (public SPC3 header): "DP_MODE: 0 = DP_Mode is disabled. 1 = DP_Mode is enabled.
// SPC3 sets up all DP_SAPs." With DP_Mode = 0 no DP SAP exists: FDL_Status is answered (an FDL
// station), every DP request gets RS (10 02 05 03 0A 16: FCS 02+05+03), the DP state machine
// never leaves Wait_Prm (modelled, docs/decisions.md).
TEST_P(DpServices, DpModeZeroSetsUpNoDpSaps) {
  Bench b(GetParam());
  Chip& c = b.chip;
  testutil::user_go_offline(c);  // Go_Offline
  const std::uint32_t m0 = addr(c, RegId::Mode_Reg0);
  c.write(m0, 0xC0);        // Sync_Supported, Freeze_Supported
  c.write(m0 + 1, 0x20);    // Spec_Clear_Mode; DP_Mode (bit 8) = 0
  testutil::user_start(c);  // Start_SPC3
  Exchange st;
  for (int k = 0; k < dpc31::kStartupTries && !st.answer; ++k) st = b.master.fdl_status();
  EXPECT_EQ(wire(st.answer), (Bytes{0x10, 0x02, 0x05, 0x00, 0x07, 0x16}));
  const Bytes kRs = {0x10, 0x02, 0x05, 0x03, 0x0A, 0x16};
  EXPECT_EQ(wire(b.master.slave_diag().answer), kRs);
  EXPECT_EQ(wire(b.master.set_prm().answer), kRs);
  EXPECT_EQ(wire(b.master.chk_cfg().answer), kRs);
  EXPECT_EQ(wire(b.master.data_exchange({1, 2, 3, 4}).answer), kRs);
  EXPECT_EQ(c.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(b.user.prm_accepted, 0u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, DpServices, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

namespace {

// FDL_Status until answered, then Set_Prm and Chk_Cfg, each accepted by hand (User_Prm_Data_Okay,
// User_Cfg_Data_Okay read at once) while `user` acknowledges every interrupt.
void prm_and_cfg_by_hand(Bench& b, AckOnly& user) {
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  while (!b.master.fdl_status().answer) {
  }
  b.master.set_prm();
  read8(b.chip, RegId::User_Prm_Data_Okay);
  b.master.chk_cfg();
  read8(b.chip, RegId::User_Cfg_Data_Okay);
}

}  // namespace

// SPC3 p.31: "For a correct configuration, the transition to 'DATA_EX' takes place immediately,
// if no Din_buffer is present (R_Len_Din_Puf = 00H) and trigger counters ... are at 0. Otherwise"
// — cut off; modelled: at the user's next New_Din_Buffer_Cmd (docs/decisions.md). VPC3+C p.43:
// "immediately" with Go/Leave_DATA-EXCH. DPC31: at once as well (modelled).
TEST(SpcCfgOk, Spc3WithDinBufferEntersDataExchangeAtNewDinBufferCmd) {
  for (const Profile p : kAllProfiles) {
    SCOPED_TRACE(testutil::pname(p));
    Bench b(p);
    AckOnly user;
    prm_and_cfg_by_hand(b, user);
    if (p == Profile::spc3) {
      EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Cfg);
      EXPECT_EQ(irr(b.chip) & irq::Go_Leave_Data_Exchange, 0);
      read8(b.chip, RegId::New_Din_Buffer_Cmd);
    }
    EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
    EXPECT_NE(irr(b.chip) & irq::Go_Leave_Data_Exchange, 0);
  }
}

TEST(SpcCfgOk, Spc3WithoutDinBufferEntersDataExchangeAtOnce) {
  ResponderConfig rc;
  rc.slave.cfg = {0x23};  // 4 output bytes, no inputs
  rc.slave.in_len = 0;
  Bench b(Profile::spc3, 1'500'000, rc);
  AckOnly user;
  prm_and_cfg_by_hand(b, user);
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

}  // namespace
