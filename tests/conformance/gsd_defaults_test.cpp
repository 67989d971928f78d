// Every shipped firmware with a master configured from its GSD file's defaults, at the slowest
// and a fast rate the bridge offers: the module stays in normal operation, the master sees no
// storm of high-priority answers.
#include "../firmware_bench.hpp"
#include "conformance.hpp"

using namespace dpc31;

namespace {

struct Case {
  const dpc31_firmware* fw;
  std::uint32_t baud;
  Profile profile;
};

class GsdDefaults : public ::testing::TestWithParam<Case> {};

bool high_priority(const Exchange& ex) { return ex.answer && (ex.answer->fc & 0x0F) == 0x0A; }

// Seed 000 (B&R X20DO4331, "OSP" function model): "When temporary communication errors occur
// between the module and master CPU (e.g. due to EMC), a few bus cycles will pass without
// refreshing the cyclic registers. The OSPValid bit is reset internally". So the refresh monitor
// of DO4 (and any module parameter of the kind) must not trip while the master refreshes every
// cycle: a default shorter than one Data_Exchange cycle puts the module into OSP after every
// exchange, its diag changes (ModulOK) and every second answer is DH (chip-facts: FC A = DH).
// The master is set up as a configuration tool does it: Ident_Number, Module Cfg bytes,
// Ext_User_Prm_Data_Const with each Ext_User_Prm_Data_Ref at its default. Like a real master it
// fetches the diagnosis (Slave_Diag) after a DH answer. Rates: 9.6 k and 19.2 k (the slowest the
// bridge offers, docs/bridge.md) and 1.5 M.
TEST_P(GsdDefaults, MasterFromTheGsdSeesNoHighPriorityStormAtTheRate) {
  const Case& c = GetParam();
  const firmware_bench::Gsd g =
      firmware_bench::load_gsd(std::string(SOURCE_DIR) + "/firmware/" + c.fw->gsd);
  firmware_bench::Bench b(c.profile, *c.fw, firmware_bench::gsd_configured_slave(*c.fw, g, 5),
                          c.baud);
  ASSERT_TRUE(b.master.startup());
  const std::vector<std::uint8_t> outputs(c.fw->out_len, 0x01);  // DO4: DO1, OSPValid 1
  auto cycle = [&] {
    const Exchange ex = b.master.data_exchange(outputs);
    EXPECT_TRUE(ex.answer) << "no answer";
    if (high_priority(ex)) b.master.slave_diag();
    return high_priority(ex);
  };
  // Settling: the first normal transfer changes the module's state once (DO4: OSP -> normal).
  for (int i = 0; i < 4; ++i) cycle();
  int dh = 0;
  for (int i = 0; i < 30; ++i) dh += cycle() ? 1 : 0;
  EXPECT_EQ(dh, 0) << "high-priority answers in 30 Data_Exchange cycles";
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
}

std::vector<Case> cases() {
  std::vector<Case> v;
  for (const dpc31_firmware* const* f = dpc31_firmwares; *f != nullptr; ++f) {
    for (std::uint32_t baud : {9'600u, 19'200u, 1'500'000u}) {
      for (Profile p : kAllProfiles) v.push_back({*f, baud, p});
    }
  }
  return v;
}

INSTANTIATE_TEST_SUITE_P(ShippedFirmware, GsdDefaults, ::testing::ValuesIn(cases()),
                         [](const auto& i) {
                           return std::string(i.param.fw->name) + "_" +
                                  std::to_string(i.param.baud) + "_" +
                                  testutil::pname(i.param.profile);
                         });

}  // namespace
