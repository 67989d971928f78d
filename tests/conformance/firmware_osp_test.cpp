// Seed 000: the "OSP" function model (B&R X20 System User's Manual 3.10, X20DO4331, §4.15.10.11.6,
// p.1136) as firmware DO4 implements it (docs/firmware.md), sentence by sentence, on every
// profile. DO4's outputs: byte 0 bits 3..0 DO1..DO4, byte 1 bit 0 OSPValid; its input byte: bit 0
// ModulOK, bits 7..4 the terminals. User parameters (Set_Prm bytes 8..10): OSPMode, replacement
// value, refresh monitor in ms (0 = off). Terminal changes are the module's port 0 with their
// cycle (kPortLatency = 24 clocks after the Data_Exchange is acted on, docs/firmware.md).
#include "do4/do4.h"
#include "firmware_host_bench.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

constexpr std::uint64_t k10ms = 480'000;

SlaveConfig do4_slave(std::uint8_t mode, std::uint8_t value, std::uint8_t refresh_ms = 0) {
  SlaveConfig s = gsd_slave(do4_firmware, 5);
  s.user_prm = {0x00, mode, value, refresh_ms};
  s.wd_fact1 = 2;
  s.wd_fact2 = 5;  // TWD = 10 ms x 2 x 5 = 100 ms = 4 800 000 clocks
  return s;
}
constexpr std::uint64_t kTwd = 2 * 5 * k10ms;

class Osp : public ::testing::TestWithParam<Profile> {};

// Normal operation with `value`, then the cable is pulled until the DP watchdog has expired;
// returns the expiry cycle.
std::uint64_t run_then_interrupt(FirmwareBench& b, std::uint8_t value) {
  EXPECT_TRUE(b.master.startup());
  const Exchange dx = b.master.data_exchange({value, 0x01});
  const std::uint64_t expiry = b.acted(dx) + kTwd;
  b.master.idle(expiry + 100'000 - b.chip.cycle());
  return expiry;
}

}  // namespace

// "This OSP value is output as soon as communication between the module and master is
// interrupted." Replace mode, value 9: the DP watchdog expires at acted + 100 ms; its
// Leave_Master clears the outputs in that cycle (DX_Out, U_Buffer_Cleared), the ISR starts there
// and drives 9h after 6 bus accesses: expiry + 24.
TEST_P(Osp, OspValueOutputAsSoonAsCommunicationInterrupted) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  const std::uint64_t expiry = run_then_interrupt(b, 0x5);
  EXPECT_EQ(b.values_at(DO4_PORT_OUTPUTS, expiry - 1), (Writes{{0x9, expiry + kPortLatency}}));
}

// "In the first case [Retain last valid value], the module retains the last value as validly
// recognized output state." The last value received with OSPValid = 1 was 6h; the master then
// requested OSP with 3h (OSPValid 0): the terminals stay 6h, also after the watchdog expiry;
// only ModulOK drops (port 1, at the acted + 24 of the OSPValid 0 exchange).
TEST_P(Osp, RetainLastValidValue_KeepsLastValidlyRecognisedOutputState) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_RETAIN_LAST, 0x0));
  ASSERT_TRUE(b.master.startup());
  const Exchange valid = b.master.data_exchange({0x6, 0x01});
  const Exchange osp = b.master.data_exchange({0x3, 0x00});
  b.master.idle(b.acted(osp) + kTwd + 100'000 - b.chip.cycle());
  EXPECT_EQ(b.values_at(DO4_PORT_OUTPUTS), (Writes{{0x6, b.acted(valid) + kPortLatency}}));
  EXPECT_EQ(b.values_at(DO4_PORT_MODUL_OK, b.acted(valid) + kPortLatency),
            (Writes{{0, b.acted(osp) + kPortLatency}}));
}

// "When selecting the mode, 'Replace with static value' ... If an OSP event occurs, this value
// will be output instead of the value currently requested by the task." The task requests Ch;
// the replacement value 3h is output at the event (watchdog expiry + 24).
TEST_P(Osp, ReplaceWithStaticValue_OutputInsteadOfRequestedValue) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x3));
  const std::uint64_t expiry = run_then_interrupt(b, 0xC);
  ASSERT_TRUE(b.last(DO4_PORT_OUTPUTS));
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->value, 0x3u);
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->cycle, expiry + kPortLatency);
}

// Bit structure of OSPValid: "0 Request OSP operation (after initial start or module in
// Standby)", "1 Request normal operation". After the start-up, before any OSPValid 1: the module
// is in OSP (inputs: ModulOK 0, terminals 0 = power-on outputs off, retain mode); a request with
// OSPValid 0 does not drive the terminals.
TEST_P(Osp, OspValidBit0_RequestsOspAfterInitialStart) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_RETAIN_LAST, 0x0));
  ASSERT_TRUE(b.master.startup());
  const Exchange first = b.master.data_exchange({0x5, 0x00});
  ASSERT_TRUE(first.answer);
  EXPECT_EQ(first.answer->du, (Bytes{0x00}));  // ModulOK 0, terminals 0
  const Exchange second = b.master.data_exchange({0x5, 0x00});
  EXPECT_EQ(second.answer->du, (Bytes{0x00}));
  b.master.idle(2000);
  EXPECT_TRUE(b.writes(DO4_PORT_OUTPUTS).empty());
  EXPECT_TRUE(b.writes(DO4_PORT_MODUL_OK).empty());
}

// OSPValid: "0 Request OSP operation", "1 Request normal operation". 5h with OSPValid 1: the
// terminals 5h, ModulOK 1; 6h with OSPValid 0: the replacement value 9h, ModulOK 0; 7h with
// OSPValid 1: 7h, ModulOK 1 — each at acted + 24.
TEST_P(Osp, OspValidBit0_0RequestsOsp_1RequestsNormalOperation) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  ASSERT_TRUE(b.master.startup());
  b.master.idle(2000);
  const std::uint64_t before = b.chip.cycle();  // the Set_Prm drove 9h already (OSP at start)
  const Exchange a = b.master.data_exchange({0x5, 0x01});
  const Exchange o = b.master.data_exchange({0x6, 0x00});
  const Exchange n = b.master.data_exchange({0x7, 0x01});
  b.master.idle(2000);
  EXPECT_EQ(b.values_at(DO4_PORT_OUTPUTS, before), (Writes{{0x5, b.acted(a) + kPortLatency},
                                                           {0x9, b.acted(o) + kPortLatency},
                                                           {0x7, b.acted(n) + kPortLatency}}));
  const auto ok = b.writes(DO4_PORT_MODUL_OK, before);
  ASSERT_EQ(ok.size(), 3u);
  EXPECT_EQ(ok[0].value, 1u);
  EXPECT_EQ(ok[1].value, 0u);
  EXPECT_EQ(ok[2].value, 1u);
}

// "As long as the OSPValid bit remains set in the module, the module behaves the same as the
// 'Standard' function model." Every transfer with OSPValid 1 drives its value: 1, 2, 4, 8, Fh,
// each at acted + 24, ModulOK stays 1.
TEST_P(Osp, OspValidSet_BehavesAsStandardFunctionModel) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_RETAIN_LAST, 0x0));
  ASSERT_TRUE(b.master.startup());
  std::vector<std::uint64_t> acted;
  for (std::uint8_t v : {0x1, 0x2, 0x4, 0x8, 0xF}) {
    acted.push_back(b.acted(b.master.data_exchange({v, 0x01})));
  }
  b.master.idle(2000);
  const auto t = b.writes(DO4_PORT_OUTPUTS);
  ASSERT_EQ(t.size(), 5u);
  const std::uint32_t expect[] = {0x1, 0x2, 0x4, 0x8, 0xF};
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(t[i].value, expect[i]) << i;
    EXPECT_EQ(t[i].cycle, acted[i] + kPortLatency) << i;
  }
  ASSERT_EQ(b.writes(DO4_PORT_MODUL_OK).size(), 1u);  // 0 -> 1 once
  EXPECT_EQ(b.writes(DO4_PORT_MODUL_OK)[0].value, 1u);
}

// "If an OSP event occurs (e.g. communication between the module and master CPU interrupted) then
// the OSPValid bit will be reset on the module. The module enters OSP mode and the output occurs
// ... according to the configuration." ModulOK drops at expiry + 24; when the master is back the
// module reports ModulOK 0 with the replacement value 9h on its terminals: input byte 90h.
TEST_P(Osp, OspEvent_ResetsOspValidAndEntersOspMode) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  const std::uint64_t expiry = run_then_interrupt(b, 0x5);
  EXPECT_EQ(b.values_at(DO4_PORT_MODUL_OK, expiry - 1), (Writes{{0, expiry + kPortLatency}}));
  ASSERT_TRUE(b.master.restart(200, 3));
  b.master.data_exchange({0x5, 0x00});
  EXPECT_EQ(b.master.data_exchange({0x5, 0x00}).answer->du, (Bytes{0x90}));
}

// "The OSP replacement value remains even after the communication channel has recovered. OSP
// mode is only exited when a set OSPValid bit is transferred." After the expiry the master is
// back and sends Ch with OSPValid 0 three times: the terminals stay 9h; Ch with OSPValid 1 leaves
// OSP at its acted + 24.
TEST_P(Osp, OspRemainsAfterRecovery_ExitedOnlyBySetOspValid) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  const std::uint64_t expiry = run_then_interrupt(b, 0x5);
  ASSERT_TRUE(b.master.restart(200, 3));
  for (int i = 0; i < 3; ++i) b.master.data_exchange({0xC, 0x00});
  b.master.idle(2000);
  auto t = b.writes(DO4_PORT_OUTPUTS, expiry - 1);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].value, 0x9u);
  const Exchange set = b.master.data_exchange({0xC, 0x01});
  b.master.idle(2000);
  t = b.writes(DO4_PORT_OUTPUTS, expiry - 1);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[1].value, 0xCu);
  EXPECT_EQ(t[1].cycle, b.acted(set) + kPortLatency);
  EXPECT_EQ(b.master.data_exchange({0xC, 0x01}).answer->du, (Bytes{0xC1}));  // ModulOK 1
}

// "When the master CPU is restarted, the OSPValid bit is re-initialized on the master CPU. It
// must once more be set by the application and transferred via the bus." A master restart
// (FDL_Status, Set_Prm, Chk_Cfg again) whose application sends OSPValid 0: the module is in OSP
// (replacement 9h, ModulOK 0) until OSPValid 1 is transferred again.
TEST_P(Osp, MasterRestart_OspValidMustBeSetAndTransferredAgain) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x5, 0x01});
  ASSERT_TRUE(b.master.restart(200, 3));
  const Exchange o = b.master.data_exchange({0x5, 0x00});
  b.master.idle(2000);
  ASSERT_TRUE(b.last(DO4_PORT_OUTPUTS));
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->value, 0x9u);
  EXPECT_LE(b.last(DO4_PORT_OUTPUTS)->cycle, b.acted(o) + kPortLatency);
  EXPECT_EQ(b.master.data_exchange({0x5, 0x00}).answer->du, (Bytes{0x90}));
  const Exchange n = b.master.data_exchange({0x5, 0x01});
  b.master.idle(2000);
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->value, 0x5u);
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->cycle, b.acted(n) + kPortLatency);
}

// "When temporary communication errors occur ... a few bus cycles will pass without refreshing
// the cyclic registers. The OSPValid bit is reset internally in the module - the bit in the CPU
// however remains set. Upon the next successful transfer, the OSPValid bit in the module is set
// again and the module returns to normal operation." DO4's refresh monitor (10 ms, counted in
// User_Timer_Clock ticks of 1 ms, docs/firmware.md): 15 ms without a Data_Exchange while the DP
// watchdog (100 ms) still runs: OSP in the ISR of the 10th tick after the last refresh, the DP
// state stays Data_Exchange; the next transfer (OSPValid still 1) is normal operation again.
TEST_P(Osp, TemporaryCommunicationError_OspValidResetUntilNextSuccessfulTransfer) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9, 10));
  ASSERT_TRUE(b.master.startup());
  const Exchange last = b.master.data_exchange({0x5, 0x01});
  b.master.idle(b.acted(last) + 15 * 48'000 - b.chip.cycle());
  // The ticks seen by the ISR (Int_Reg at its entry) after the refresh.
  std::vector<std::uint64_t> ticks;
  for (const auto& [at, ir] : b.host.interrupts) {
    if (at > b.acted(last) + kPortLatency && (ir & irq::User_Timer_Clock) != 0) ticks.push_back(at);
  }
  ASSERT_GE(ticks.size(), 10u);
  const auto osp = b.writes(DO4_PORT_OUTPUTS, b.acted(last) + kPortLatency);
  ASSERT_EQ(osp.size(), 1u);
  EXPECT_EQ(osp[0].value, 0x9u);
  EXPECT_GT(osp[0].cycle, ticks[9]);  // in the ISR of the 10th tick ...
  if (ticks.size() > 10) {
    EXPECT_LT(osp[0].cycle, ticks[10]);  // ... not later
  }
  EXPECT_GT(ticks[9], b.acted(last) + 9 * 48'000);  // 10 ticks of 1 ms after the refresh
  EXPECT_LE(ticks[9], b.acted(last) + 10 * 48'000 + kPortLatency);
  EXPECT_EQ(dp_bits(status(b.chip)), kDataEx);
  const Exchange back = b.master.data_exchange({0x5, 0x01});
  b.master.idle(2000);
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->value, 0x5u);
  EXPECT_EQ(b.last(DO4_PORT_OUTPUTS)->cycle, b.acted(back) + kPortLatency);
  EXPECT_EQ(b.last(DO4_PORT_MODUL_OK)->value, 1u);
}

// "The ModulOK bit can be evaluated if the task in the master CPU needs to know which output mode
// the module is currently in." The input byte (bit 0 ModulOK, bits 7..4 terminals), handed over
// in the DX_Out ISR and so seen one exchange later: 51h in normal operation with 5h, 90h in OSP
// with the replacement value 9h.
TEST_P(Osp, ModulOkBit_TellsTheMasterTheOutputMode) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0x5, 0x01});
  EXPECT_EQ(b.master.data_exchange({0x5, 0x00}).answer->du, (Bytes{0x51}));
  EXPECT_EQ(b.master.data_exchange({0x5, 0x00}).answer->du, (Bytes{0x90}));
}

// "If the OSPValid bit is reset to '0' on the module, then the output state no longer depends on
// the responsible task in the master CPU. However, output still occurs according to the
// configuration of the OSP replacement value." In OSP the task sends 1h, 2h, 4h with OSPValid
// 0: no terminal change after the replacement value.
TEST_P(Osp, OspMode_OutputNoLongerDependsOnTheTask) {
  FirmwareBench b(GetParam(), do4_firmware, do4_slave(DO4_REPLACE, 0x9));
  const std::uint64_t expiry = run_then_interrupt(b, 0x5);
  ASSERT_TRUE(b.master.restart(200, 3));
  for (std::uint8_t v : {0x1, 0x2, 0x4}) b.master.data_exchange({v, 0x00});
  b.master.idle(2000);
  const auto t = b.writes(DO4_PORT_OUTPUTS, expiry - 1);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].value, 0x9u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, Osp, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });
