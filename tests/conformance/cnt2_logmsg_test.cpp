// CNT2 (firmware/cnt2, seed 001): the MSG bits held by CNTx_LOGMSG are released only by the
// master writing LOGMSG 0, never by the ASIC clearing the outputs. The firmware runs on the host
// CPU over the C HAL; the built-in master drives the chip on the wire.
#include "../firmware_bench.hpp"
#include "cnt2/cnt2.h"
#include "conformance.hpp"

using namespace dpc31;

namespace {

enum class Cut { clear_data, failsafe, leave_master };

struct Case {
  Profile profile;
  Cut cut;
};

class Cnt2Hold : public ::testing::TestWithParam<Case> {};

std::uint8_t status1(const Exchange& ex) {
  EXPECT_TRUE(ex.answer && ex.answer->du.size() == 6);
  return ex.answer && ex.answer->du.size() == 6 ? ex.answer->du[2] : 0xEE;
}

// Seed 001 (Eaton XNE-2CNT-2PWM p.87, "Storage of messages (MSG)"): "With the change from 0 → 1
// in the control bits CNTx_LOGMSG ... all states of the MSG bits are held"; "If now the control
// bits CNTx_LOGMSG ... are reset through 1 → 0, the messages that were meanwhile recorded in the
// shadow register are copied to the MSG bits". Only the master resets the control bit: a
// Clear_Data (Global_Control), a fail-safe Data_Exchange (no output data) or a Leave_Master (DP
// watchdog expiry) clears the outputs in the ASIC (DX_Out with U_Buffer_Cleared) but is no
// 1 → 0 of CNT1_LOGMSG: the held MSG_REF stays held (status 82h = LOGMSG_ACK | MSG_REF) until
// the master transfers LOGMSG 0 in a normal Data_Exchange; then the shadow (MSG_SHORT, 04h) is
// the MSG.
TEST_P(Cnt2Hold, HeldMsgBitsStayHeldUntilTheMasterWritesLogmsg0) {
  SlaveConfig s = firmware_bench::gsd_slave(cnt2_firmware, 9);
  s.wd_fact1 = 2;  // TWD = 2 x 5 x 10 ms = 100 ms
  s.wd_fact2 = 5;
  firmware_bench::Bench b(GetParam().profile, cnt2_firmware, s, 1'500'000);
  DpMaster& m = b.master;
  ASSERT_TRUE(m.startup());
  ASSERT_EQ(cnt2_hw_input("event1", CNT2_MSG_REF), 0);
  m.data_exchange({0x01, 0x00});
  EXPECT_EQ(status1(m.data_exchange({0x81, 0x00})), CNT2_MSG_REF);  // inputs of before the hold
  EXPECT_EQ(status1(m.data_exchange({0x81, 0x00})), 0x80 | CNT2_MSG_REF);
  ASSERT_EQ(cnt2_hw_input("event1", CNT2_MSG_SHORT), 0);  // held: into the shadow
  const std::uint32_t cleared = dps_get_stats()->cleared;
  switch (GetParam().cut) {
    case Cut::clear_data:
      m.global_control(0x02);  // Control_Command bit 1 Clear_Data
      m.idle(48'000);
      break;
    case Cut::failsafe:
      m.data_exchange({});
      m.idle(48'000);
      break;
    case Cut::leave_master:
      m.idle(6'000'000);  // 125 ms of silence: the DP watchdog expires, Leave_Master
      EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
      ASSERT_TRUE(m.startup());
      break;
  }
  EXPECT_GT(dps_get_stats()->cleared, cleared) << "the ASIC cleared the outputs";
  EXPECT_EQ(cnt2_get_channel(0)->hold, 1);
  EXPECT_EQ(status1(m.data_exchange({0x81, 0x00})), 0x80 | CNT2_MSG_REF);
  EXPECT_EQ(status1(m.data_exchange({0x81, 0x00})), 0x80 | CNT2_MSG_REF);
  // The master releases: the shadow becomes the MSG bits.
  m.data_exchange({0x01, 0x00});
  EXPECT_EQ(status1(m.data_exchange({0x01, 0x00})), CNT2_MSG_SHORT);
}

std::vector<Case> cases() {
  std::vector<Case> v;
  for (Profile p : kAllProfiles) {
    for (Cut c : {Cut::clear_data, Cut::failsafe, Cut::leave_master}) v.push_back({p, c});
  }
  return v;
}

std::string case_name(const ::testing::TestParamInfo<Case>& i) {
  static const char* const kCut[] = {"ClearData", "Failsafe", "LeaveMaster"};
  return testutil::pname(i.param.profile) + "_" + kCut[static_cast<int>(i.param.cut)];
}

INSTANTIATE_TEST_SUITE_P(Cuts, Cnt2Hold, ::testing::ValuesIn(cases()), case_name);

}  // namespace
