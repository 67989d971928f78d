// DP start-up as the manuals state it, on every profile.
#include "conformance.hpp"

using namespace dpc31;
using conformance::Bench;

namespace {

class Startup : public ::testing::TestWithParam<Profile> {};

// SPC3 p.31 / VPC3+C p.43 / DPC31 p.28: after a correct Set_Prm and Chk_Cfg from the master the
// slave reaches Data_Exchange and answers Data_Exchange with its inputs.
TEST_P(Startup, CorrectPrmAndCfgReachDataExchange) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.dp_state(), DpState::Data_Exchange);
  const Exchange dx = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(conformance::wire(dx.answer),
            (conformance::Bytes{0x68, 0x07, 0x07, 0x68, 0x02, 0x05, 0x08, 0xA1, 0xA2, 0xA3, 0xA4,
                                0x99, 0x16}));
}

INSTANTIATE_TEST_SUITE_P(Profiles, Startup, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

}  // namespace
