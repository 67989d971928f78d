// Seed 001: storage of messages (MSG) with CNTx_LOGMSG / PWMx_LOGMSG and the shadow register
// (Eaton XI/ON XNE-2CNT-2PWM user manual 04/2011, §8.1.2, p.87) as firmware CNT2 implements it
// (docs/firmware.md), on every profile and for both pairs of channels: the counters and the PWM
// outputs. CNT2's outputs (6 bytes): byte 0/1 bit 7 CNT1/2_LOGMSG, byte 2/4 bit 7 PWM1/2_LOGMSG;
// its inputs (8 bytes): the counters' status in bytes 2 and 5, the PWM outputs' in bytes 6 and
// 7, each bits 3..0 MSG, bit 7 LOGMSG_ACK. The module builds its inputs in the DX_Out ISR after
// taking the outputs, so an answer shows the state after the previous exchange. Hardware events
// are the module's hardware inputs "event1/2" (counters) and "pwm_event1/2" (PWM); the hold
// lines are its ports hold1/2 and pwm_hold1/2 (kCnt2PortLatency = 40 clocks after the exchange
// is acted on). The MSG bits below are named by position (kMsg0 = bit 0 ...): the seed's rules
// are the same for every bit and both kinds of channel.
#include <memory>
#include <string>
#include <tuple>
#include <utility>

#include "cnt2/cnt2.h"
#include "firmware_host_bench.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

enum class LogmsgHalf { counter, pwm };
constexpr std::uint8_t kMsg0 = 0x01, kMsg1 = 0x02, kMsg2 = 0x04, kMsg3 = 0x08;

class Logmsg : public ::testing::TestWithParam<std::tuple<Profile, LogmsgHalf>> {
 protected:
  void SetUp() override {
    b_ = std::make_unique<FirmwareBench>(std::get<0>(GetParam()), cnt2_firmware,
                                         gsd_slave(cnt2_firmware, 9));
    ASSERT_TRUE(b_->master.startup());
  }
  [[nodiscard]] bool pwm() const { return std::get<1>(GetParam()) == LogmsgHalf::pwm; }
  // One exchange with LOGMSG of channel 1 / 2 (of the kind under test, the other kind's 0); the
  // status bytes of its answer.
  std::pair<std::uint8_t, std::uint8_t> dx(bool log1, bool log2 = false) {
    std::vector<std::uint8_t> out(6, 0);
    out[pwm() ? 2 : 0] = log1 ? 0x80 : 0;
    out[pwm() ? 4 : 1] = log2 ? 0x80 : 0;
    last_ = b_->master.data_exchange(out);
    EXPECT_TRUE(last_.answer && last_.answer->du.size() == 8);
    if (!last_.answer || last_.answer->du.size() != 8) return {0xEE, 0xEE};
    const auto& du = last_.answer->du;
    return pwm() ? std::pair{du[6], du[7]} : std::pair{du[2], du[5]};
  }
  void event(int channel, std::uint8_t bits) {
    const std::string name = (pwm() ? "pwm_event" : "event") + std::to_string(channel);
    ASSERT_EQ(b_->host.hw_input(name, bits), "");
  }
  [[nodiscard]] Writes hold_writes() const {
    return b_->values_at(pwm() ? CNT2_PORT_PWM_HOLD1 : CNT2_PORT_HOLD1);
  }
  std::unique_ptr<FirmwareBench> b_;
  Exchange last_;
};

}  // namespace

// Flow chart, "CNTx_LOGMSG = 0 resp. PWMx_LOGMSG = 0": "Continuous monitoring if messages have been
// activated." While LOGMSG is 0 every new message shows in MSG (ORed): 01h, then 01h | 08h = 09h.
TEST_P(Logmsg, Logmsg0_ContinuousMonitoringOfMessages) {
  event(1, kMsg0);
  dx(false);
  EXPECT_EQ(dx(false).first, 0x01);
  event(1, kMsg3);
  dx(false);
  EXPECT_EQ(dx(false).first, 0x09);
}

// "With the change from 0 -> 1 in the control bits CNTx_LOGMSG or respectively PWMx_LOGMSG
// ... all states of the MSG bits are held." MSG 02h; LOGMSG 1 (its hold line rises at acted + 40);
// a new message 04h comes: the inputs keep 02h (with LOGMSG_ACK: 82h).
TEST_P(Logmsg, LogmsgRising_AllMsgStatesHeld) {
  event(1, kMsg1);
  dx(false);
  EXPECT_EQ(dx(true).first, 0x02);
  const std::uint64_t hold = b_->acted(last_);
  event(1, kMsg2);
  EXPECT_EQ(dx(true).first, 0x82);
  EXPECT_EQ(dx(true).first, 0x82);
  EXPECT_EQ(dx(true).first, 0x82);
  EXPECT_EQ(hold_writes(), (Writes{{1, hold + kCnt2PortLatency}}));
}

// "If events which would cause messages would occur in the meantime, they would get lost. To
// avoid this, a 'shadow register' ... was created, in which, as long as the message bits are
// held, newly occurring messages (MSG) are stored." Two messages while held (04h, then 08h, at
// different exchanges) both appear after the release: 0Ch.
TEST_P(Logmsg, MessagesWhileHeld_StoredInShadowRegister) {
  event(1, kMsg1);
  dx(false);
  dx(true);
  event(1, kMsg2);
  EXPECT_EQ(dx(true).first, 0x82);
  event(1, kMsg3);
  EXPECT_EQ(dx(true).first, 0x82);
  EXPECT_EQ(dx(false).first, 0x82);  // the release is taken in this exchange's ISR
  EXPECT_EQ(dx(false).first, 0x0C);
}

// "The basic status of the shadow register is: 'all MSG = 0'." Hold with MSG 01h and release
// with no message in between: MSG becomes the shadow, 00h — nothing invented, on both channels.
TEST_P(Logmsg, ShadowRegisterBasicStatus_AllMsg0) {
  event(1, kMsg0);
  event(2, kMsg1);
  dx(false, false);
  EXPECT_EQ(dx(true, true), (std::pair<std::uint8_t, std::uint8_t>{0x01, 0x02}));
  EXPECT_EQ(dx(true, true), (std::pair<std::uint8_t, std::uint8_t>{0x81, 0x82}));
  EXPECT_EQ(dx(false, false), (std::pair<std::uint8_t, std::uint8_t>{0x81, 0x82}));
  EXPECT_EQ(dx(false, false), (std::pair<std::uint8_t, std::uint8_t>{0x00, 0x00}));
}

// "The states of the MSG bits, held in the process input data, can now be read out without newly
// incoming MSG going lost." Channel 2: MSG 01h held and read (81h) while 02h comes in; after
// the release 02h is there and 01h, read out, is gone.
TEST_P(Logmsg, HeldMsgReadOutWithoutLosingNewMessages) {
  event(2, kMsg0);
  dx(false);
  dx(false, true);
  event(2, kMsg1);
  EXPECT_EQ(dx(false, true).second, 0x81);
  EXPECT_EQ(dx(false, false).second, 0x81);
  EXPECT_EQ(dx(false, false).second, 0x02);
}

// "If now the control bits CNTx_LOGMSG or PWMx_LOGMSG ... are reset through 1 -> 0, the
// messages that were meanwhile recorded in the shadow register are copied to the MSG bits". The
// shadow (08h) replaces the held MSG (03h): 08h, not 0Bh; the hold line falls at the release's
// acted + 40.
TEST_P(Logmsg, LogmsgFalling_ShadowCopiedToMsgBits) {
  event(1, kMsg0 | kMsg1);
  dx(false);
  dx(true);
  event(1, kMsg3);
  EXPECT_EQ(dx(true).first, 0x83);
  EXPECT_EQ(dx(false).first, 0x83);
  const std::uint64_t release = b_->acted(last_);
  EXPECT_EQ(dx(false).first, 0x08);
  const Writes w = hold_writes();
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[1], (ValueAt{0, release + kCnt2PortLatency}));
}

// "By means of this procedure, MSG bits of the Process input ... can be read out or respectively
// set back without loosing messages." The flow chart run by the master on both channels for six
// rounds (MSG > 0 -> LOGMSG 1 -> evaluate the held MSG -> LOGMSG 0), messages arriving before,
// during and after each hold: every message is reported exactly once, in the round after it came.
TEST_P(Logmsg, ProcedureReadsOutAndSetsBackWithoutLosingMessages) {
  const std::uint8_t kBits[] = {0x01, 0x02, 0x04, 0x08, 0x03, 0x0C};
  std::vector<std::uint8_t> reported[2];
  std::vector<std::uint8_t> sent[2];
  std::uint8_t pending[2] = {0, 0};
  for (int round = 0; round < 6; ++round) {
    for (int c = 0; c < 2; ++c) {
      const auto bits = kBits[(round + 3 * c) % 6];
      event(c + 1, bits);
      pending[c] |= bits;
    }
    dx(false, false);  // the messages reach MSG
    dx(true, true);    // the answer shows MSG; the ISR holds
    const auto held = dx(true, true);
    // A message while held: it belongs to the next round.
    for (int c = 0; c < 2; ++c) {
      const auto bits = kBits[(round + 1 + 3 * c) % 6];
      event(c + 1, bits);
      sent[c].push_back(pending[c]);
      pending[c] = bits;
    }
    reported[0].push_back(held.first & 0x0F);
    reported[1].push_back(held.second & 0x0F);
    EXPECT_EQ(held.first & 0x80, 0x80);
    EXPECT_EQ(held.second & 0x80, 0x80);
    dx(false, false);  // release: the shadow becomes MSG
  }
  EXPECT_EQ(reported[0], sent[0]);
  EXPECT_EQ(reported[1], sent[1]);
}

INSTANTIATE_TEST_SUITE_P(Profiles, Logmsg,
                         ::testing::Combine(::testing::ValuesIn(kAllProfiles),
                                            ::testing::Values(LogmsgHalf::counter,
                                                              LogmsgHalf::pwm)),
                         [](const auto& i) {
                           return testutil::pname(std::get<0>(i.param)) +
                                  (std::get<1>(i.param) == LogmsgHalf::pwm ? "_pwm" : "_counter");
                         });
