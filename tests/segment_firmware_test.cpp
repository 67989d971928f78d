// Several firmwares on one segment (docs/segment.md, docs/firmware.md "Instances"): an SPC3 and a
// DPC31 each running DO4 and a VPC3+ running CNT2, every one an instance of its own, driven only
// through the line by the built-in master. Expected values come from docs/timing.md (an answer's
// first start bit at the request's end + max(11, MinTSDR) T, MinTSDR_Val = 11 written by the
// driver; the DP watchdog restarted at a request's acted-on cycle, end - T + floor(T/2), and
// expiring TWD = 10 ms x WD_Fact_1 x WD_Fact_2 x 48 MHz later) and from the modules' documented
// behaviour (firmware/do4/do4.h: inputs = terminals << 4 | ModulOK; OSP on a lost connection,
// OSPMode 0 of the GSD defaults: the last valid value retained; cnt2.h: the PWM duty driven).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/dpc31_firmware.h"
#include "firmware_host.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"

namespace dpc31 {
namespace {

constexpr std::uint32_t kBaud = 1'500'000;
constexpr std::uint64_t kTwd = 480'000;  // 10 ms x 1 x 1 x 48 MHz

// spc3 @5 and dpc31 @7 running the DO4 named `do4` (built-in or plug-in), vpc3plus @6 CNT2.
struct ThreeFirmwares {
  explicit ThreeFirmwares(const std::string& do4) : seg(kBaud) {
    const struct {
      const char* name;
      Profile profile;
      std::string firmware;
      std::uint8_t address;
    } defs[] = {{"spc3", Profile::spc3, do4, 5},
                {"vpc3plus", Profile::vpc3plus, "CNT2", 6},
                {"dpc31", Profile::dpc31, do4, 7}};
    std::vector<SlaveConfig> slaves;
    for (const auto& d : defs) {
      const dpc31_firmware& fw = find_firmware(d.firmware);
      SlaveConfig sc;
      sc.address = d.address;
      sc.wd_fact1 = 1;
      sc.wd_fact2 = 1;
      slaves.push_back(with_gsd_defaults(fw, sc));
      ChipOptions opt;
      opt.profile = d.profile;
      chips.push_back(seg.add_chip(d.name, opt));
      hosts.push_back(std::make_unique<FirmwareHost>(fw));
      DirectBus bus(seg.chip(chips.back()));
      hosts.back()->init(bus, d.address);
      seg.set_firmware(chips.back(), hosts.back()->program());
    }
    master =
        std::make_unique<DpMaster>(seg, seg.add_sender("master 2"), MasterConfig{2, kBaud}, slaves);
  }
  // DO4: DO1..4 and OSPValid; CNT2: counter 1 enabled, PWM 1 enabled at 50 %.
  static std::vector<std::vector<std::uint8_t>> outputs() {
    return {{0x0A, 0x01}, {0x01, 0x00, 0x01, 50, 0x00, 0x00}, {0x05, 0x01}};
  }
  Segment seg;
  std::vector<std::size_t> chips;
  std::vector<std::unique_ptr<FirmwareHost>> hosts;
  std::unique_ptr<DpMaster> master;
};

class SegmentFirmware : public ::testing::TestWithParam<std::string> {};

TEST_P(SegmentFirmware, TwoDo4AndACnt2EachKeepTheirOwnState) {
  ThreeFirmwares line(GetParam());
  const std::uint64_t t = line.seg.bit_cycles();
  // Each module accepted only its own GSD's Set_Prm and Chk_Cfg: one shared module would have
  // refused the other's (DO4 checks 3 module bytes, CNT2 none).
  ASSERT_TRUE(line.master->startup_all());
  line.master->dp_cycle(ThreeFirmwares::outputs());
  // The second cycle's answers carry the inputs each firmware handed over after the first.
  const std::vector<Exchange> cycle = line.master->dp_cycle(ThreeFirmwares::outputs());
  ASSERT_EQ(cycle.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(line.seg.chip(line.chips[i]).dp_state(), DpState::Data_Exchange) << i;
    ASSERT_TRUE(cycle[i].answer) << i;
    EXPECT_EQ(cycle[i].answer_start, cycle[i].request_end + 11 * t) << i;
  }
  EXPECT_EQ(cycle[0].answer->du.at(0), 0xA1);  // terminals 0xA, ModulOK 1
  EXPECT_EQ(cycle[2].answer->du.at(0), 0x51);  // terminals 0x5, ModulOK 1
  EXPECT_EQ(line.hosts[0]->port("outputs"), 0xA);
  EXPECT_EQ(line.hosts[2]->port("outputs"), 0x5);
  EXPECT_EQ(line.hosts[1]->port("pwm1"), 50);

  // The master stops polling station 7: its watchdog runs out from its last request's
  // acted-on cycle, its DO4 goes to OSP; the other DO4 and the CNT2 go on.
  const Exchange last = line.master->history().back();
  ASSERT_EQ(last.request.da, 7);
  const std::uint64_t expiry = last.request_end - t + t / 2 + kTwd;
  Chip& dpc31 = line.seg.chip(line.chips[2]);
  EXPECT_EQ(dpc31.watchdog_due(), expiry);
  const std::vector<std::vector<std::uint8_t>> out = ThreeFirmwares::outputs();
  while (line.seg.cycle() < expiry + 10 * t) {
    for (std::size_t i = 0; i < 2; ++i) {
      line.master->select(i);
      line.master->data_exchange(out[i]);
    }
  }
  EXPECT_EQ(dpc31.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(dpc31.wd_state(), WdState::Baud_Control);
  EXPECT_EQ(line.seg.chip(line.chips[0]).dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(line.seg.chip(line.chips[1]).dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(line.hosts[2]->port("modul_ok"), 0);   // OSP,
  EXPECT_EQ(line.hosts[2]->port("outputs"), 0x5);  // the last valid value retained
  const auto& w = line.hosts[2]->port_writes();
  ASSERT_FALSE(w.empty());
  EXPECT_GE(w.back().cycle, expiry);  // its ISR served WD_DP_Control_Timeout
  EXPECT_EQ(line.hosts[0]->port("modul_ok"), 1);
  EXPECT_EQ(line.hosts[0]->port("outputs"), 0xA);
  EXPECT_EQ(line.hosts[1]->port("pwm1"), 50);
}

// The built-in DO4 (two instances of it) and the DO4 plug-in named twice (two private copies of
// the library: the same descriptor is returned for the same file; a fresh copy for every host,
// FirmwareModule.EveryModuleStartsWithTheGlobalsOfTheFile).
INSTANTIATE_TEST_SUITE_P(Do4, SegmentFirmware, ::testing::Values("DO4", PLUGIN_DO4),
                         [](const auto& info) { return info.index == 0 ? "builtin" : "plugin"; });

TEST(SegmentFirmwarePlugin, TheSameFileIsOneDescriptorWithACopyPerHost) {
  const dpc31_firmware& a = find_firmware(PLUGIN_DO4);
  const dpc31_firmware& b = find_firmware(PLUGIN_DO4);
  EXPECT_EQ(&a, &b);
  const std::shared_ptr<const dpc31_firmware> one = plugin_copy(a);
  std::shared_ptr<const dpc31_firmware> two = plugin_copy(a);
  EXPECT_NE(one.get(), two.get());
  EXPECT_NE(one->init, two->init);  // another library: other code, other globals
  EXPECT_STREQ(one->name, two->name);
}

// The C host API (dpc31/dpc31_firmware.h): a station address beyond PROFIBUS's 0..125 makes no
// module (NULL), as an unknown profile does.
TEST(FirmwareCHost, AStationAddressBeyond125IsNoModule) {
  const dpc31_firmware& fw = find_firmware(PLUGIN_DO4);
  EXPECT_EQ(dpc31_module_create("vpc3plus", 0, &fw, 200), nullptr);
  EXPECT_EQ(dpc31_module_create("vpc3plus", 0, &fw, 126), nullptr);
  dpc31_module* m = dpc31_module_create("vpc3plus", 0, &fw, 125);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(dpc31_module_run(m, 1000), 0);
  dpc31_module_destroy(m);
}

TEST(SegmentFirmwareScenario, ShippedThreeSlavesScenarioPasses) {
  SegmentScenario s;
  Scenario single;
  ScenarioError err;
  ASSERT_EQ(load_segment_scenario(SOURCE_DIR "/traces/segment/three_slaves.scn", s, single, err),
            SegmentLoad::ok)
      << err.message;
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(s, {}, [&errors](const std::string& e) { errors.push_back(e); }),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
}

// A plug-in on a segment station from the scenario door (docs/scenario-format.md, "Segments"):
// parsing leaves it unloaded (the GSD defaults wait), run_segment_scenario binds it, and DO4 as a
// plug-in on the SPC3 reaches Data_Exchange beside the built-in DO4 on the DPC31, each answer
// MinTSDR = 11 T after its request (docs/timing.md; the driver writes MinTSDR_Val = 11).
TEST(SegmentFirmwareScenario, APluginStationBesideABuiltInOneReachesDataExchange) {
  const std::string text = std::string("segment\nstation 5 profile=spc3 firmware=") + PLUGIN_DO4 +
                           "\nstation 7 profile=dpc31 firmware=DO4\nstartup\ncycle 2\n"
                           "expect state 5 Data_Exchange wd=DP_Control\n"
                           "expect state 7 Data_Exchange wd=DP_Control\nexpect tsdr 11\n";
  SegmentScenario s;
  ScenarioError err;
  ASSERT_TRUE(parse_segment_scenario(text, "p.scn", s, err)) << err.text();
  EXPECT_EQ(segment_plugins(s), std::vector<std::string>{PLUGIN_DO4});
  EXPECT_EQ(s.stations[0].slave.ident, SlaveConfig{}.ident);  // not loaded: no GSD defaults yet
  EXPECT_EQ(s.stations[1].slave.ident, 0x0D04);
  std::vector<std::string> walk;
  std::vector<std::string> errors;
  EXPECT_EQ(run_segment_scenario(
                s, [&walk](const std::string& l) { walk.push_back(l); },
                [&errors](const std::string& e) { errors.push_back(e); }),
            0);
  EXPECT_TRUE(errors.empty()) << errors.front();
  ASSERT_FALSE(walk.empty());
  EXPECT_NE(walk.back().find("3 expects passed, 0 failed"), std::string::npos) << walk.back();
  ASSERT_TRUE(bind_segment_plugins(s, err)) << err.text();
  EXPECT_EQ(s.stations[0].slave.ident, 0x0D04);  // DO4's GSD (firmware/do4)
}

}  // namespace
}  // namespace dpc31
