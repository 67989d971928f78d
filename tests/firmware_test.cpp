// The example firmware (firmware/) on the host CPU against the built-in master: exact cycles
// of the module's outputs after the events that move them (docs/timing.md: 4 clocks per bus
// access, the ISR starts in the cycle X/INT goes active), and CNT2's message storage as a
// property over many random timings.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "cnt2/cnt2.h"
#include "do4/do4.h"
#include "dp_master.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/fdl_counters.hpp"
#include "firmware_bench.hpp"

namespace {

using namespace dpc31;
using firmware_bench::Bench;
using firmware_bench::Gsd;
using firmware_bench::gsd_configured_slave;
using firmware_bench::gsd_slave;
using firmware_bench::load_gsd;

class Do4 : public ::testing::TestWithParam<Profile> {};

// Data_Exchange acted on -> DX_Out, X/INT active, the ISR starts in that cycle: Int_Reg (2
// reads), Next_Dout_Buffer_Cmd, the U pointer cell, 2 output bytes: 6 accesses, so the
// terminals change 24 clocks after the request was acted on.
TEST_P(Do4, TerminalsFollowDxOutAfterSixBusAccesses) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.user_prm = {0x00, DO4_REPLACE, 0x09, 0x00};
  Bench b(GetParam(), do4_firmware, s, 1'500'000);
  ASSERT_TRUE(b.master.startup());
  const Exchange ex = b.master.data_exchange({0x05, 0x01});
  b.master.idle(2000);
  const auto w = b.last_write(DO4_PORT_OUTPUTS);
  ASSERT_TRUE(w);
  ASSERT_FALSE(b.activations.empty());
  EXPECT_NE(std::find(b.activations.begin(), b.activations.end(), b.acted(ex)),
            b.activations.end());
  EXPECT_EQ(w->value, 0x5u);
  EXPECT_EQ(w->cycle, b.acted(ex) + 6 * 4);
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 1);
}

// The watchdog expires at acted + TWD (TWD = 2 x 5 x 10 ms). In that cycle Leave_Master also
// clears the outputs (DX_Out with U_Buffer_Cleared); the ISR handles DX_Out first: Int_Reg (2),
// Next_Dout_Buffer_Cmd, the U pointer, 2 bytes, then the cleared outputs are an OSP event:
// the replacement value 24 clocks after the expiry.
TEST_P(Do4, OspReplacementValue24ClocksAfterWatchdogExpiry) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.wd_fact1 = 2;
  s.wd_fact2 = 5;
  s.user_prm = {0x00, DO4_REPLACE, 0x09, 0x00};
  Bench b(GetParam(), do4_firmware, s, 1'500'000);
  ASSERT_TRUE(b.master.startup());
  const Exchange ex = b.master.data_exchange({0x05, 0x01});
  b.master.idle(6'000'000);  // 125 ms
  const std::uint64_t expiry = b.acted(ex) + 2 * 5 * 480'000;
  const auto w = b.last_write(DO4_PORT_OUTPUTS);
  ASSERT_TRUE(w);
  ASSERT_FALSE(b.activations.empty());
  EXPECT_NE(std::find(b.activations.begin(), b.activations.end(), expiry), b.activations.end());
  EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(w->value, 0x9u);
  EXPECT_EQ(w->cycle, expiry + 6 * 4);
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 0);
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->osp_valid, 0);
}

// OSPMode 2, a replacement value beyond 4 bits, a short Set_Prm: the firmware answers
// User_Prm_Data_Not_Okay. A longer one does not fit the Prm buffer sized from the GSD: the chip
// answers RR (no resource) and the firmware never sees it.
TEST_P(Do4, ParametersOutsideTheGsdRangesAreRefused) {
  const std::vector<std::vector<std::uint8_t>> refused_by_firmware = {
      {0x00, 0x02, 0x00, 0x0A}, {0x00, 0x00, 0x10, 0x0A}, {0x00, 0x00, 0x00}};
  for (const auto& bad : refused_by_firmware) {
    SlaveConfig s = gsd_slave(do4_firmware, 5);
    s.user_prm = bad;
    Bench b(GetParam(), do4_firmware, s, 12'000'000);
    EXPECT_FALSE(b.master.startup(20));
    EXPECT_EQ(b.chip.dp_state(), DpState::Wait_Prm);
    EXPECT_EQ(firmware_bench::stats_of(b.host)->prm_ok, 0u);
    EXPECT_GE(firmware_bench::stats_of(b.host)->prm_rejected, 1u);
  }
  // One byte more than the Aux buffers hold: RR. On the VPC3+ they hold the DPV1 Set_Prm, two
  // bytes longer than the DP one (docs/firmware.md, "DO4 with DPV1").
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.user_prm = {0x00, 0x00, 0x00, 0x0A, 0x00};
  if (GetParam() == Profile::vpc3plus) s.user_prm.insert(s.user_prm.end(), {0x00, 0x00});
  Bench b(GetParam(), do4_firmware, s, 12'000'000);
  EXPECT_FALSE(b.master.startup(20));
  EXPECT_GE(b.chip.fdl_counters().no_resource, 1u);
  EXPECT_EQ(
      firmware_bench::stats_of(b.host)->prm_ok + firmware_bench::stats_of(b.host)->prm_rejected,
      0u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, Do4,
                         ::testing::Values(Profile::spc3, Profile::vpc3plus, Profile::dpc31),
                         [](const auto& i) { return std::string(profile_name(i.param)); });

// --- CNT2: no message is lost across hold and release, at any timing ---

// CNT2's four message channels: counters 1, 2 and PWM outputs 1, 2. Channel c's hardware input,
// its LOGMSG output byte (bit 7), its status input byte, and its hold port (= c).
constexpr int kChannels = 4;
const char* const kEventName[kChannels] = {"event1", "event2", "pwm_event1", "pwm_event2"};
constexpr int kLogmsgByte[kChannels] = {0, 1, 2, 4};
constexpr int kStatusByte[kChannels] = {2, 5, 6, 7};

// Everything in the order it happened (the host CPU and the bus side take turns, so this is a
// total order): hardware events and the firmware's hold/release instants.
struct LogEntry {
  enum Kind { event, hold, release } kind;
  int channel;
  std::uint8_t bits;
};

struct MasterApp {
  enum State { idle, wait_ack, held, wait_release } state = idle;
  int delay = 0;
  std::vector<std::uint8_t> reports;  // MSG bits read while held, one per hold
};

void run_property(std::uint32_t seed) {
  std::mt19937 rng(seed);
  auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const Profile profile = static_cast<Profile>(pick(0, 2));
  const std::uint32_t baud = pick(0, 1) != 0 ? 12'000'000 : 1'500'000;
  Bench b(profile, cnt2_firmware, gsd_slave(cnt2_firmware, 9), baud);
  for (int c = 0; c < 2; ++c) {
    ASSERT_EQ(cnt2_get_channel(firmware_bench::cnt2_of(b.host), c)->m.shadow, 0) << "seed " << seed;
    ASSERT_EQ(cnt2_get_pwm(firmware_bench::cnt2_of(b.host), c)->m.shadow, 0) << "seed " << seed;
  }
  ASSERT_TRUE(b.master.startup()) << "seed " << seed;

  std::vector<LogEntry> log;
  bool injecting = true;
  bool draining = false;  // the master starts no hold of its own
  const std::uint64_t max_gap = 3ull * b.master.bit_cycles() * 11 * 12;  // ~3 telegrams
  std::uint64_t next_event =
      b.chip.cycle() + std::uniform_int_distribution<std::uint64_t>(0, max_gap)(rng);
  // Hardware events arrive at any access of either side, also inside the firmware's ISR.
  b.chip.on_state_change([&](std::uint64_t cycle) {
    while (injecting && cycle >= next_event) {
      const int ch = pick(0, kChannels - 1);
      const auto bits = static_cast<std::uint8_t>(pick(1, 15));
      ASSERT_EQ(cnt2_hw_input(firmware_bench::cnt2_of(b.host), kEventName[ch], bits), 0);
      log.push_back({LogEntry::event, ch, bits});
      next_event =
          cycle +
          (pick(0, 3) == 0 ? 0 : std::uniform_int_distribution<std::uint64_t>(1, max_gap)(rng));
    }
  });
  b.host.on_port = [&](std::uint64_t, unsigned port, std::uint32_t value) {
    ASSERT_LT(port, static_cast<unsigned>(kChannels)) << "seed " << seed << ": PWM never enabled";
    log.push_back({value != 0 ? LogEntry::hold : LogEntry::release, static_cast<int>(port), 0});
  };

  MasterApp app[kChannels];
  std::vector<std::uint8_t> out(6, 0x00);
  auto exchange = [&] {
    const Exchange ex = b.master.data_exchange(out);
    if (pick(0, 2) == 0)
      b.master.idle(std::uniform_int_distribution<std::uint64_t>(1, max_gap)(rng));
    ASSERT_TRUE(ex.answer && ex.answer->du.size() == 8) << "seed " << seed;
    for (int c = 0; c < kChannels; ++c) {
      const std::uint8_t status = ex.answer->du[kStatusByte[c]];
      std::uint8_t& ctl = out[kLogmsgByte[c]];
      const bool ack = (status & 0x80) != 0;
      MasterApp& a = app[c];
      switch (a.state) {
        case MasterApp::idle:
          // Evaluate when messages are shown, or (rarely) for no reason at all.
          if (!draining && (((status & 0x0F) != 0 && pick(0, 2) != 0) || pick(0, 15) == 0)) {
            ctl |= 0x80;
            a.state = MasterApp::wait_ack;
          }
          break;
        case MasterApp::wait_ack:
          if (ack) {
            a.reports.push_back(status & 0x0F);
            a.delay = pick(0, 3);
            a.state = MasterApp::held;
          }
          break;
        case MasterApp::held:
          ASSERT_TRUE(ack) << "seed " << seed;
          ASSERT_EQ(status & 0x0F, a.reports.back()) << "seed " << seed << ": held MSG changed";
          if (a.delay-- <= 0) {
            ctl &= 0x7F;
            a.state = MasterApp::wait_release;
          }
          break;
        case MasterApp::wait_release:
          if (!ack) a.state = MasterApp::idle;
          break;
      }
    }
  };
  const int n = pick(20, 80);
  for (int i = 0; i < n; ++i) exchange();
  // Drain: no new events; every channel completes one more hold and release.
  injecting = false;
  draining = true;
  for (int c = 0; c < kChannels; ++c) {
    while (app[c].state != MasterApp::idle) exchange();
    const std::size_t before = app[c].reports.size();
    out[kLogmsgByte[c]] |= 0x80;
    app[c].state = MasterApp::wait_ack;
    while (app[c].reports.size() == before || app[c].state != MasterApp::idle) exchange();
  }
  if (::testing::Test::HasFatalFailure()) return;

  // Each hold must show exactly the messages since the previous hold instant: nothing lost,
  // nothing invented (a shadow that did not start at 0 would add bits to a report).
  for (int c = 0; c < kChannels; ++c) {
    std::vector<std::uint8_t> expected;
    std::uint8_t pending = 0;
    for (const LogEntry& e : log) {
      if (e.channel != c) continue;
      if (e.kind == LogEntry::event) pending |= e.bits;
      if (e.kind == LogEntry::hold) {
        expected.push_back(pending);
        pending = 0;
      }
    }
    EXPECT_EQ(pending, 0) << "seed " << seed << " channel " << c << ": never reported";
    EXPECT_EQ(app[c].reports, expected) << "seed " << seed << " channel " << c;
  }
  b.chip.on_state_change({});
}

TEST(Cnt2, NoMessageIsLostAcrossHoldAndReleaseAtAnyTiming) {
  for (std::uint32_t seed = 1; seed <= 300; ++seed) {
    run_property(seed);
    if (HasFailure()) break;
  }
}

// With no message ever raised, hold and release show MSG = 0 on all four channels: the shadows
// (REG_CNTx_LOGMSG, REG_PWMx_LOGMSG) start as all 0. Inputs: counters 1, 2 (high, low, status),
// then the status of PWM 1 and 2; LOGMSG_ACK is bit 7 of each status.
TEST(Cnt2, ShadowStartsAsAllZero) {
  Bench b(Profile::spc3, cnt2_firmware, gsd_slave(cnt2_firmware, 9), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  const std::vector<std::uint8_t> hold = {0x80, 0x80, 0x80, 0, 0x80, 0};
  const std::vector<std::uint8_t> release(6, 0);
  EXPECT_EQ(b.master.data_exchange(hold).answer->du, std::vector<std::uint8_t>(8, 0));
  EXPECT_EQ(b.master.data_exchange(hold).answer->du,
            (std::vector<std::uint8_t>{0, 0, 0x80, 0, 0, 0x80, 0x80, 0x80}));
  b.master.data_exchange(release);
  EXPECT_EQ(b.master.data_exchange(release).answer->du, std::vector<std::uint8_t>(8, 0));
}

// PWM output 1 (outputs byte 2: bit 0 PWM_EN, bit 7 PWM1_LOGMSG; byte 3: duty cycle in %)
// drives its duty cycle on port pwm1 when the DX_Out ISR has read the 6 output bytes: Int_Reg
// (2 reads), Next_Dout_Buffer_Cmd, the U pointer cell, 6 bytes = 10 accesses of 4 clocks after
// the request was acted on. PWM_EN 0 drives 0. A duty above 100 % drives 100 % and raises
// MSG_DUTY (bit 0) once, when the value leaves the range. Inputs show the state after the
// previous exchange (the ISR builds them after taking the outputs): PWM 1's status is byte 6.
TEST(Cnt2, PwmDrivesItsDutyCycleAndReportsOneRangeMessage) {
  Bench b(Profile::vpc3plus, cnt2_firmware, gsd_slave(cnt2_firmware, 9), 1'500'000);
  ASSERT_TRUE(b.master.startup());
  const auto pwm1 = [&](std::uint8_t ctl, std::uint8_t duty) {
    return b.master.data_exchange({0, 0, ctl, duty, 0, 0});
  };
  const Exchange on = pwm1(0x01, 40);
  ASSERT_TRUE(b.last_write(CNT2_PORT_PWM1));
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM1)->value, 40u);
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM1)->cycle, b.acted(on) + 10 * 4);
  pwm1(0x00, 40);
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM1)->value, 0u);
  EXPECT_EQ(pwm1(0x01, 150).answer->du.at(6), 0x00);
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM1)->value, 100u);
  EXPECT_EQ(pwm1(0x01, 200).answer->du.at(6), CNT2_PWM_MSG_DUTY);        // still out: no new one
  EXPECT_EQ(pwm1(0x81, 200).answer->du.at(6), CNT2_PWM_MSG_DUTY);        // hold
  EXPECT_EQ(pwm1(0x01, 20).answer->du.at(6), 0x80 | CNT2_PWM_MSG_DUTY);  // release: shadow 0
  EXPECT_EQ(pwm1(0x01, 20).answer->du.at(6), 0x00);
  EXPECT_EQ(b.last_write(CNT2_PORT_PWM2), std::nullopt) << "PWM 2 was never enabled";
}

// "With the change from 0 -> 1 in the control bits ... PWMx_LOGMSG ... all states of the MSG
// bits are held"; messages "newly occurring" meanwhile go to the shadow (seed 001, p.87). A
// transfer that sets PWM1_LOGMSG together with a duty of 150 %: the hold is taken first, so the
// range message of that same transfer is a new one and goes to REG_PWM1_LOGMSG: the held status
// is 80h, and after the release MSG_DUTY is there (01h) -- not lost, not shown as held.
TEST(Cnt2, RangeMessageOfTheHoldingTransferGoesToTheShadow) {
  Bench b(Profile::dpc31, cnt2_firmware, gsd_slave(cnt2_firmware, 9), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0, 0, 0x81, 150, 0, 0});
  EXPECT_EQ(cnt2_get_pwm(firmware_bench::cnt2_of(b.host), 0)->m.shadow, CNT2_PWM_MSG_DUTY);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0x81, 150, 0, 0}).answer->du.at(6), 0x80);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0x01, 150, 0, 0}).answer->du.at(6), 0x80);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0x01, 150, 0, 0}).answer->du.at(6), CNT2_PWM_MSG_DUTY);
}

}  // namespace

// --- the GSD files: what a master is configured with must be what the firmware accepts ---

namespace {

class GsdFile : public ::testing::TestWithParam<const dpc31_firmware*> {};

TEST_P(GsdFile, DescribesWhatTheFirmwareChecks) {
  const dpc31_firmware& fw = *GetParam();
  const Gsd g = load_gsd(std::string(SOURCE_DIR) + "/firmware/" + fw.gsd);
  EXPECT_EQ(std::stoul(g.keys.at("Ident_Number"), nullptr, 0), fw.ident);
  EXPECT_EQ(g.module_cfg, std::vector<std::uint8_t>(fw.cfg, fw.cfg + fw.cfg_len));
  EXPECT_EQ(g.prm_const, std::vector<std::uint8_t>(fw.user_prm, fw.user_prm + fw.user_prm_len));
  EXPECT_EQ(std::stoul(g.keys.at("Max_User_Prm_Data_Len")), fw.user_prm_len);
  for (const auto& [n, p] : g.params) EXPECT_EQ(g.prm_const.at(p.offset), p.def) << "param " << n;
  // No Sync/Freeze: the firmware leaves them off in Mode_Reg0.
  EXPECT_EQ(g.keys.at("Sync_Mode_supp"), "0");
  EXPECT_EQ(g.keys.at("Freeze_Mode_supp"), "0");
  EXPECT_EQ(g.keys.at("Set_Slave_Add_supp"), "1");
  EXPECT_EQ(g.keys.at("Fail_Safe"), "1");
}

// A master set up from the GSD reaches Data_Exchange at every rate it claims, on every chip,
// with every parameter at its minimum, default and maximum; one beyond the range is refused.
TEST_P(GsdFile, EveryMasterConfiguredFromItReachesDataExchange) {
  const dpc31_firmware& fw = *GetParam();
  const Gsd g = load_gsd(std::string(SOURCE_DIR) + "/firmware/" + fw.gsd);
  const auto slave_from_gsd = [&] { return gsd_configured_slave(fw, g, 5); };
  for (const auto& [key, baud] : firmware_bench::kGsdRates) {
    if (g.keys.at(key) != "1") continue;
    for (Profile p : {Profile::spc3, Profile::vpc3plus, Profile::dpc31}) {
      Bench b(p, fw, slave_from_gsd(), baud);
      EXPECT_TRUE(b.master.startup()) << key << " " << profile_name(p);
      EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange) << key << " " << profile_name(p);
    }
  }
  for (const auto& [n, param] : g.params) {
    for (int v : {param.min, param.def, param.max, param.max + 1}) {
      if (v > 255) continue;
      SlaveConfig s = slave_from_gsd();
      s.user_prm.at(param.offset) = static_cast<std::uint8_t>(v);
      Bench b(Profile::dpc31, fw, s, 12'000'000);
      EXPECT_EQ(b.master.startup(40), v <= param.max) << "param " << n << " = " << v;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Firmware, GsdFile, ::testing::Values(&do4_firmware, &cnt2_firmware),
                         [](const auto& i) { return std::string(i.param->name); });

}  // namespace

namespace {

// DO4 on the DPC31 (docs/dpc31.md): started by a MAC_Start request (Table 5.1-3: "MAC enters
// Pas_Idle"), never by Mode_Reg1's Start_SPC3; its outputs fetched with User_New_Dout_Cmd (Table
// 5.2-8); the DPS_User_Watchdog enabled through the Instruction_Queue when Data_Exchange begins
// and retriggered after each DX_Out (p.31); a fail-safe Data_Exchange without outputs hands the
// C buffer over through User_New_Dout_Cmd with U_Buffer_Cleared (p.33, seed 003): the user
// gets the substitute values the firmware keeps in C (all 00h), which DO4 takes as an OSP event:
// its replacement value 9.
TEST(Do4Dpc31, FetchesThroughUserNewDoutAndWatchesItselfThroughRequests) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.user_prm = {0x00, DO4_REPLACE, 0x09, 0x00};
  std::vector<BusAccess> accesses;
  const ProfileDesc& p = profile_desc(Profile::dpc31);
  const auto instq_wr = static_cast<std::uint16_t>(find_reg(p, "InstQ_Wr")->read_addr);
  const auto user_new_dout =
      static_cast<std::uint16_t>(find_reg(p, "User_New_Dout_Cmd")->read_addr);
  Bench b(Profile::dpc31, do4_firmware, s, 1'500'000);
  b.chip.on_bus_access([&](std::uint64_t, const BusAccess& a) { accesses.push_back(a); });
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  // The start: the entry MAC_Start 10h at the Instruction_Queue's first entry, then InstQ_Wr.
  const auto instq = static_cast<std::uint16_t>(
      b.chip.peek(static_cast<std::uint32_t>(find_reg(p, "InstQ_Base")->read_addr))
      << p.segment_shift);
  const std::vector<BusAccess>& init = b.init_accesses;
  const auto mac_start = std::find_if(init.begin(), init.end(), [&](const BusAccess& a) {
    return a.write && a.addr == instq && a.data == request::MAC_Start;
  });
  ASSERT_NE(mac_start, init.end());
  EXPECT_TRUE(std::any_of(mac_start, init.end(),
                          [&](const BusAccess& a) { return a.write && a.addr == instq_wr; }));
  const auto mode1_s = static_cast<std::uint16_t>(find_reg(p, "Mode_Reg1_S")->write_addr);
  EXPECT_FALSE(std::any_of(init.begin(), init.end(), [&](const BusAccess& a) {
    return a.write && a.addr == mode1_s && (a.data & 0x2D) != 0;  // Start_SPC3 & co.
  }));
  b.master.data_exchange({0x05, 0x01});
  b.master.idle(2000);
  EXPECT_EQ(b.last_write(DO4_PORT_OUTPUTS)->value, 0x5u);
  const Exchange failsafe = b.master.data_exchange({});
  ASSERT_TRUE(failsafe.answer);
  b.master.idle(2000);
  // The user's U buffer is the C buffer of before, with the substitute values; User_New_Dout_Cmd
  // says U_Buffer_Cleared (a peek: what the command would answer, nothing changed).
  const std::uint8_t cmd = b.chip.peek(user_new_dout);
  EXPECT_NE(cmd & 0x08, 0);  // U_Buffer_Cleared
  static constexpr const char* kPtr[] = {"R_Dout_Buf_Ptr1", "R_Dout_Buf_Ptr2", "R_Dout_Buf_Ptr3"};
  const std::uint32_t u_buf =
      static_cast<std::uint32_t>(
          b.chip.peek(static_cast<std::uint32_t>(find_reg(p, kPtr[(cmd & 3) - 1])->read_addr)))
      << p.segment_shift;
  for (std::uint32_t i = 0; i < s.out_len; ++i) EXPECT_EQ(b.chip.peek(u_buf + i), 0x00) << i;
  EXPECT_EQ(b.last_write(DO4_PORT_OUTPUTS)->value, 0x9u);
  EXPECT_EQ(do4_get_state(firmware_bench::do4_of(b.host))->modul_ok, 0);
  const auto count = [&](auto pred) {
    return std::count_if(accesses.begin(), accesses.end(), pred);
  };
  EXPECT_GT(count([&](const BusAccess& a) { return a.write && a.addr == instq_wr; }), 0);
  EXPECT_GE(count([&](const BusAccess& a) { return !a.write && a.addr == user_new_dout; }), 2);
  // Every request the firmware queued was executed: InstQ_Rd caught up with InstQ_Wr.
  EXPECT_EQ(b.chip.peek(static_cast<std::uint32_t>(find_reg(p, "InstQ_Rd")->read_addr)),
            b.chip.peek(instq_wr));
}

// The DO4 firmware on the C31's interrupt controller (docs/dpc31.md, "Two interrupt
// controllers"): the firmware's interrupt is the C31's, the same as the external processor's
// would be at the same addresses, so it reaches Data_Exchange and drives its outputs; X/INT, the
// external processor's, never goes active (low) on the way.
TEST(Do4Dpc31, RunsOnTheC31sInterruptControllerWithXIntInactive) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.user_prm = {0x00, DO4_REPLACE, 0x09, 0x00};
  Bench b(ChipOptions{Profile::dpc31, BusMode::intel, 0, Engine::event, std::nullopt,
                      IrqController::c31},
          do4_firmware, s, 1'500'000);
  int x_int_low = 0;
  b.chip.on_irq_change([&](std::uint64_t, bool) { x_int_low += b.chip.x_int_pin() ? 0 : 1; });
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  b.master.data_exchange({0x05, 0x01});
  b.master.idle(2000);
  EXPECT_EQ(b.last_write(DO4_PORT_OUTPUTS)->value, 0x5u);
  EXPECT_FALSE(b.activations.empty());  // the ISR ran on the C31's interrupt
  EXPECT_EQ(x_int_low, 0);
  EXPECT_TRUE(b.chip.x_int_pin());
}

}  // namespace
