// The DP services and the user's Prm/Cfg handshake as manual-quotes.md "Confirmed" and the
// sourced facts of chip-facts.md state them. The test is the user (Bare: no ISR runs): it reads
// the verdict command addresses itself (User_Prm_Data_Okay 0Eh, _Not_Okay 0Fh,
// User_Cfg_Data_Okay 10h, _Not_Okay 11h, chip-facts §1.1) and sees the answers on the wire.
// Short answers (SD1) by hand: 10 DA SA FC FCS 16 with FCS = DA + SA + FC; RS = FC 03h "no
// service activated", RR = FC 02h "no resource" (chip-facts §8).
#include "conformance.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

class Services : public ::testing::TestWithParam<Profile> {};

const Bytes kRS = {0x10, 0x02, 0x05, 0x03, 0x0A, 0x16};  // 02 + 05 + 03 = 0Ah
const Bytes kRR = {0x10, 0x02, 0x05, 0x02, 0x09, 0x16};  // 02 + 05 + 02 = 09h

}  // namespace

// manual-quotes.md Confirmed / chip-facts §5.4 [S-PRM][S-CFG]: "Prm/Cfg OK codes 00 finished, 01
// conflict, 11 not allowed". Nothing pending: 03h from 0Eh and 10h; one Set_Prm: 00h, Wait_Cfg,
// then 03h; two Chk_Cfg before the verdict: 01h (re-check the newer one), then 00h, then 03h.
TEST_P(Services, PrmCfgOkCodes_00Finished01Conflict11NotAllowed) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(b.chip.read(0x0E), 0x03);
  EXPECT_EQ(b.chip.read(0x10), 0x03);
  b.master.set_prm();
  EXPECT_EQ(b.chip.read(0x0E), 0x00);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitCfg);
  EXPECT_EQ(b.chip.read(0x0E), 0x03);
  b.master.chk_cfg();
  b.master.chk_cfg();
  EXPECT_EQ(b.chip.read(0x10), 0x01);
  EXPECT_EQ(b.chip.read(0x10), 0x00);
  EXPECT_EQ(b.chip.read(0x10), 0x03);
}

// The same for Set_Prm: two Set_Prm (same master, both answered SC) before the user's verdict:
// User_Prm_Data_Okay answers 01h (conflict), then 00h.
// Fixed (issue 13); before: the model answers 00h at once and 03h after it.
TEST_P(Services, PrmOkCode01_ConflictWhenASecondSetPrmArrived) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.master.set_prm().answer), Bytes{0xE5});
  EXPECT_EQ(wire(b.master.set_prm().answer), Bytes{0xE5});
  EXPECT_EQ(b.chip.read(0x0E), 0x01);
  EXPECT_EQ(b.chip.read(0x0E), 0x00);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitCfg);
}

// manual-quotes.md Confirmed / chip-facts §5.4: "Not OK → Wait_Prm." User_Prm_Data_Not_Okay
// (0Fh) answers 00h and leaves Wait_Prm; after a Prm OK, User_Cfg_Data_Not_Okay (11h) goes from
// Wait_Cfg back to Wait_Prm; the master sees Prm_Req (St2 bit 0) again.
TEST_P(Services, PrmOrCfgNotOk_GoesToWaitPrm) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_EQ(b.chip.read(0x0F), 0x00);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm);
  b.master.set_prm();
  EXPECT_EQ(b.chip.read(0x0E), 0x00);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitCfg);
  b.master.chk_cfg();
  EXPECT_EQ(b.chip.read(0x11), 0x00);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm);
  const Exchange d = b.master.slave_diag();
  ASSERT_TRUE(d.answer);
  EXPECT_EQ(d.answer->du.at(1) & 0x01, 0x01);
}

// manual-quotes.md Confirmed / chip-facts §4.2, §5.4: "En_Change_Cfg_Buffer swaps Cfg and
// Read_Cfg on Cfg OK." Read_Cfg holds 13 23 (the driver's init); with Mode_Reg1 bit 4 set the
// master's Chk_Cfg 11 21 accepted by Cfg OK is what Get_Cfg answers afterwards. Without the bit
// Get_Cfg keeps 13 23.
TEST_P(Services, EnChangeCfgBuffer_CfgOkSwapsCfgAndReadCfg) {
  for (const bool swap : {true, false}) {
    Bare b(GetParam());
    if (swap) b.chip.write(wr(b.chip, RegId::Mode_Reg1_S), 0x10);
    ASSERT_TRUE(b.master.fdl_status().answer);
    b.master.set_prm();
    ASSERT_EQ(b.chip.read(0x0E), 0x00);
    b.master.slave().cfg = {0x11, 0x21};
    b.master.chk_cfg();
    ASSERT_EQ(b.chip.read(0x10), 0x00);
    const Exchange g = b.master.get_cfg();
    ASSERT_TRUE(g.answer) << swap;
    EXPECT_EQ(g.answer->du, swap ? (Bytes{0x11, 0x21}) : (Bytes{0x13, 0x23})) << swap;
  }
}

// manual-quotes.md Confirmed (DPC31 p.33): Rd_Inp / Rd_Outp "only in Data_Exchange"; otherwise
// "no service activated" (Wait_Prm, Wait_Cfg). In Wait_Prm and in Wait_Cfg both are answered RS.
TEST_P(Services, RdInpRdOutp_NoServiceActivatedInWaitPrmAndWaitCfg) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Inp, {}).answer), kRS);
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Outp, {}).answer), kRS);
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  ASSERT_EQ(dp_bits(status(b.chip)), kWaitCfg);
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Inp, {}).answer), kRS);
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Outp, {}).answer), kRS);
}

// manual-quotes.md Confirmed (DPC31 p.33): Rd_Inp / Rd_Outp in Data_Exchange "from any master",
// request length 0. Master 7 (not the one that locked us) reads the inputs A1..A4 (the driver's
// first Din buffer) and the outputs the user holds in U (01 02 03 04 fetched by the user).
TEST_P(Services, RdInpRdOutp_InDataExchangeFromAnyMaster) {
  Bare b(GetParam());
  start_by_hand(b, {0xA1, 0xA2, 0xA3, 0xA4});
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  ASSERT_EQ(b.chip.read(0x0B) & 0x04, 0x04);  // the user fetches the new outputs: N -> U
  const Exchange i = b.sap_request(dsap::Rd_Inp, {}, 7);
  ASSERT_TRUE(i.answer);
  EXPECT_EQ(i.answer->da, 7);
  EXPECT_EQ(i.answer->du, (Bytes{0xA1, 0xA2, 0xA3, 0xA4}));
  const Exchange o = b.sap_request(dsap::Rd_Outp, {}, 7);
  ASSERT_TRUE(o.answer);
  EXPECT_EQ(o.answer->du, (Bytes{0x01, 0x02, 0x03, 0x04}));
}

// manual-quotes.md Confirmed (DPC31 p.33): Rd_Inp / Rd_Outp with request data length != 0: "no
// resource" (RR), also in Data_Exchange.
// Fixed (issue 13); before: the model answers with the inputs / outputs as for length 0.
TEST_P(Services, RdInpRdOutp_RequestDataGivesNoResource) {
  Bare b(GetParam());
  start_by_hand(b, {0xA1, 0xA2, 0xA3, 0xA4});
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Inp, {0x00}).answer), kRR);
  EXPECT_EQ(wire(b.sap_request(dsap::Rd_Outp, {0x00}).answer), kRR);
}

// manual-quotes.md Confirmed (DPC31 p.33): Get_Cfg "accepted in all modes." Wait_Prm, Wait_Cfg,
// Data_Exchange: the Read_Cfg buffer 13 23 comes back each time.
TEST_P(Services, GetCfg_AcceptedInAllModes) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  const auto cfg = [&] {
    const Exchange g = b.sap_request(dsap::Get_Cfg, {});
    return g.answer ? g.answer->du : Bytes{0xEE};
  };
  EXPECT_EQ(cfg(), (Bytes{0x13, 0x23}));  // Wait_Prm
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  EXPECT_EQ(cfg(), (Bytes{0x13, 0x23}));  // Wait_Cfg
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);
  b.master.data_exchange({0, 0, 0, 0});
  EXPECT_EQ(cfg(), (Bytes{0x13, 0x23}));  // Data_Exchange
}

// The same sentence: "If the call message contains request data, the MAC acknowledges with 'no
// resource'." Get_Cfg with one request byte, in Wait_Prm and in Data_Exchange: RR.
// Fixed (issue 13); before: the model answers with the configuration.
TEST_P(Services, GetCfg_RequestDataGivesNoResource) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.sap_request(dsap::Get_Cfg, {0x00}).answer), kRR);
  start_by_hand(b, {0xA1, 0xA2, 0xA3, 0xA4});
  EXPECT_EQ(wire(b.sap_request(dsap::Get_Cfg, {0x00}).answer), kRR);
}

// manual-quotes.md Confirmed, SPC3 p.30: New_Prm_Data "in the case of a positive validation for
// more than seven data bytes". A Set_Prm with 8 data bytes (7 standard + Spec_User_Prm_Byte)
// from the SPC3's master: New_Prm_Data in Int_Req_Reg (bit 11) once it is acted on.
TEST(ServicesSpc3, NewPrmData_OnPositiveValidationOfMoreThanSevenBytes) {
  Bare b(Profile::spc3);
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(irr(b.chip) & irq::New_Prm_Data, 0);
  const Exchange p = b.master.set_prm();
  EXPECT_EQ(p.request.du.size(), 8u);
  EXPECT_NE(irr(b.chip) & irq::New_Prm_Data, 0);
}

// chip-facts §6 [S-PYPB-DP]: Slave_Diag's 6 mandatory bytes. Before the Set_Prm: St1 Station_Not_
// Ready (bit 1), St2 Prm_Req (bit 0) and bit 2 "always 1", St3 0, Master_Add FFh "not
// parameterised", Ident 0C31h: 02 05 00 FF 0C 31. After the start-up by master 2 with WD_On:
// 00, St2 bit 2 | WD_On (bit 3) = 0Ch, 00, 02, 0C 31.
TEST_P(Services, SlaveDiag_SixMandatoryBytes) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(b.master.slave_diag().answer->du, (Bytes{0x02, 0x05, 0x00, 0xFF, 0x0C, 0x31}));
  start_by_hand(b, {0xA1, 0xA2, 0xA3, 0xA4});
  EXPECT_EQ(b.master.slave_diag().answer->du, (Bytes{0x00, 0x0C, 0x00, 0x02, 0x0C, 0x31}));
}

// chip-facts §5.4 [S-AUX][S-PRM][S-CFG]: received into the Aux buffer, "if error-free, the Aux
// buffer is exchanged with the target buffer ...; length cell written; interrupt New_Prm/Cfg_
// Data". After the Set_Prm: R_Len_Prm_Data = 8 and the Prm buffer holds the telegram's data (88
// 0A 0A 00 0C 31 00 00: Lock_Req | WD_On, factors 10, 10, min_TSDR 0, ident, group 0, byte 7);
// after the Chk_Cfg: R_Len_Cfg_Data = 2, the Cfg buffer 13 23.
TEST_P(Services, PrmAndCfgTelegrams_InTheirBuffersWithTheirLengths) {
  Bare b(GetParam());
  Chip& c = b.chip;
  const auto buffer = [&](RegId ptr, std::size_t n) {
    const std::uint32_t at = static_cast<std::uint32_t>(c.read(rd(c, ptr)))
                             << c.profile().segment_shift;
    Bytes v;
    for (std::uint32_t i = 0; i < n; ++i) v.push_back(c.read(at + i));
    return v;
  };
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  EXPECT_EQ(c.read(rd(c, RegId::R_Len_Prm_Data)), 8);
  EXPECT_EQ(buffer(RegId::R_Prm_Buf_Ptr, 8),
            (Bytes{0x88, 0x0A, 0x0A, 0x00, 0x0C, 0x31, 0x00, 0x00}));
  ASSERT_EQ(c.read(0x0E), 0x00);
  b.master.chk_cfg();
  EXPECT_EQ(c.read(rd(c, RegId::R_Len_Cfg_Data)), 2);
  EXPECT_EQ(buffer(RegId::R_Cfg_Buf_Ptr, 2), (Bytes{0x13, 0x23}));
}

// chip-facts §5.4 [S-AUX]: Set_Prm, Chk_Cfg are received into an Aux buffer; "Buffer too small →
// ASIC answers 'no resources' (RR)." The driver (Responder::init) sizes its Aux buffers for 8
// bytes (7 + the Spec_User_Prm_Byte); a Set_Prm with 7 + 4 = 11 data bytes is answered RR and
// raises no New_Prm_Data.
TEST_P(Services, SetPrmLongerThanTheAuxBuffer_AnsweredNoResource) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.slave().user_prm = {0x00, 0x01, 0x02, 0x03};
  const Exchange p = b.master.set_prm();
  EXPECT_EQ(wire(p.answer), kRR);
  EXPECT_EQ(irr(b.chip) & irq::New_Prm_Data, 0);
}

// chip-facts §8 [S-PRM]: Set_Prm byte 3 min_TSDR (0 = no change); docs/timing.md: the answer's
// first start bit at the request's end + max(11, MinTSDR) bit times. min_TSDR = 40: the
// Slave_Diag after the start-up is answered 40 T = 160 clocks after its end at 12 Mbaud (11 T =
// 44 before).
TEST_P(Services, SetPrmMinTsdr_DelaysTheAnswers) {
  ResponderConfig rc;
  rc.slave.min_tsdr = 40;
  Bare b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.fdl_status().answer);
  const Exchange before = b.master.slave_diag();
  EXPECT_EQ(before.answer_start, before.request_end + 11 * 4);
  start_by_hand(b, {0xA1, 0xA2, 0xA3, 0xA4});
  const Exchange after = b.master.slave_diag();
  ASSERT_TRUE(after.answer);
  EXPECT_EQ(after.answer_start, after.request_end + 40 * 4);
}

// MinTSDR_Val "in bit times, 11..255" (chip-facts §1.3) written by the user after a Set_Prm whose
// byte 3 was 20 is the newer value and wins (docs/timing.md, answer: the MinTSDR set last); a
// Set_Prm with byte 3 = 0 keeps it ("0 = no change", chip-facts §8), at 1.5 Mbaud T = 32 clocks.
TEST_P(Services, MinTsdrValWrittenAfterSetPrmWins) {
  ResponderConfig rc;
  rc.slave.min_tsdr = 20;
  Bench b(GetParam(), 1'500'000, rc);
  ASSERT_TRUE(b.master.startup());
  const Exchange prm = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(prm.answer_start, prm.request_end + 20 * 32);
  b.chip.write(addr(b.chip, RegId::MinTSDR_Val), 40);
  const Exchange user = b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  ASSERT_TRUE(user.answer);
  EXPECT_EQ(user.answer_start, user.request_end + 40 * 32);
  b.master.slave().min_tsdr = 0;
  const Exchange keep = b.master.set_prm();
  EXPECT_EQ(keep.answer_start, keep.request_end + 40 * 32);
}

INSTANTIATE_TEST_SUITE_P(Profiles, Services, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });
