// CNT2 (firmware/cnt2, seed 001): the MSG bits held by CNTx_LOGMSG or PWMx_LOGMSG are released
// only by the master writing LOGMSG 0, never by the ASIC clearing the outputs. The firmware runs on
// the host CPU over the C HAL; the built-in master drives the chip on the wire.
#include <utility>
#include <vector>

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

// The status bytes of counter 1 (input byte 2) and PWM output 1 (byte 6).
std::pair<std::uint8_t, std::uint8_t> status1(const Exchange& ex) {
  EXPECT_TRUE(ex.answer && ex.answer->du.size() == 8);
  if (!ex.answer || ex.answer->du.size() != 8) return {0xEE, 0xEE};
  return {ex.answer->du[2], ex.answer->du[6]};
}
using St = std::pair<std::uint8_t, std::uint8_t>;
// Outputs: counter 1 CNT_EN (+ CNT1_LOGMSG), PWM 1 PWM_EN at 50 % (+ PWM1_LOGMSG).
const std::vector<std::uint8_t> kRun = {0x01, 0x00, 0x01, 50, 0x00, 0};
const std::vector<std::uint8_t> kHold = {0x81, 0x00, 0x81, 50, 0x00, 0};

// Seed 001 (Eaton XNE-2CNT-2PWM p.87, "Storage of messages (MSG)"): "With the change from 0 → 1
// in the control bits CNTx_LOGMSG or respectively PWMx_LOGMSG ... all states of the MSG bits are
// held"; "If now the control bits CNTx_LOGMSG or PWMx_LOGMSG ... are reset through 1 → 0, the
// messages that were meanwhile recorded in the shadow register are copied to the MSG bits".
// Only the master resets the control bit: a Clear_Data (Global_Control), a fail-safe
// Data_Exchange (no output data) or a Leave_Master (DP watchdog expiry) clears the outputs in the
// ASIC (DX_Out with U_Buffer_Cleared) but is no 1 → 0 of CNT1_LOGMSG or PWM1_LOGMSG: the held
// MSG_REF of counter 1 stays held (status 82h = LOGMSG_ACK | MSG_REF), and so does PWM 1's
// MSG_SUPPLY (84h), until the master transfers LOGMSG 0 in a normal Data_Exchange; then the
// shadows (counter MSG_SHORT 04h, PWM MSG_OPEN_LOAD 08h) are the MSG. The PWM output itself
// goes to its safe state, off (port pwm1 0), and runs again at 50 % with the next transfer.
TEST_P(Cnt2Hold, HeldMsgBitsStayHeldUntilTheMasterWritesLogmsg0) {
  SlaveConfig s = firmware_bench::gsd_slave(cnt2_firmware, 9);
  s.wd_fact1 = 2;  // TWD = 2 x 5 x 10 ms = 100 ms
  s.wd_fact2 = 5;
  firmware_bench::Bench b(GetParam().profile, cnt2_firmware, s, 1'500'000);
  DpMaster& m = b.master;
  ASSERT_TRUE(m.startup());
  ASSERT_EQ(cnt2_hw_input(firmware_bench::cnt2_of(b.host), "event1", CNT2_MSG_REF), 0);
  ASSERT_EQ(cnt2_hw_input(firmware_bench::cnt2_of(b.host), "pwm_event1", CNT2_PWM_MSG_SUPPLY), 0);
  m.data_exchange(kRun);
  EXPECT_EQ(cnt2_get_pwm(firmware_bench::cnt2_of(b.host), 0)->duty, 50);
  // The inputs of before the hold, then the held ones.
  EXPECT_EQ(status1(m.data_exchange(kHold)), (St{CNT2_MSG_REF, CNT2_PWM_MSG_SUPPLY}));
  EXPECT_EQ(status1(m.data_exchange(kHold)), (St{0x80 | CNT2_MSG_REF, 0x80 | CNT2_PWM_MSG_SUPPLY}));
  ASSERT_EQ(cnt2_hw_input(firmware_bench::cnt2_of(b.host), "event1", CNT2_MSG_SHORT),
            0);  // held: into the shadows
  ASSERT_EQ(cnt2_hw_input(firmware_bench::cnt2_of(b.host), "pwm_event1", CNT2_PWM_MSG_OPEN_LOAD),
            0);
  const std::uint32_t cleared = firmware_bench::stats_of(b.host)->cleared;
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
  EXPECT_GT(firmware_bench::stats_of(b.host)->cleared, cleared) << "the ASIC cleared the outputs";
  EXPECT_EQ(cnt2_get_channel(firmware_bench::cnt2_of(b.host), 0)->m.hold, 1);
  EXPECT_EQ(cnt2_get_pwm(firmware_bench::cnt2_of(b.host), 0)->m.hold, 1);
  ASSERT_TRUE(b.last_write(CNT2_PORT_PWM1).has_value());
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM1)->value, 0u) << "the PWM output in its safe state";
  EXPECT_EQ(status1(m.data_exchange(kHold)), (St{0x80 | CNT2_MSG_REF, 0x80 | CNT2_PWM_MSG_SUPPLY}));
  EXPECT_EQ(status1(m.data_exchange(kHold)), (St{0x80 | CNT2_MSG_REF, 0x80 | CNT2_PWM_MSG_SUPPLY}));
  EXPECT_EQ(cnt2_get_pwm(firmware_bench::cnt2_of(b.host), 0)->duty, 50);
  // The master releases: the shadows become the MSG bits.
  m.data_exchange(kRun);
  EXPECT_EQ(status1(m.data_exchange(kRun)), (St{CNT2_MSG_SHORT, CNT2_PWM_MSG_OPEN_LOAD}));
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
