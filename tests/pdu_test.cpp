// The DP / DPV1 data units of include/dpc31/pdu.hpp: the bytes each one builds, written out by
// hand from its layout (EN 50170 Set_Prm and Slave_Diag; VPC3+C p.53 Figure 7-1; the DPV1 PDUs
// as the Profichip driver's dp_if.h lays them out: function number, slot, index, length; the
// 4-byte negative response; Initiate's 12-byte request head and 8-byte response head), and that
// parse gives the fields back and refuses what is not one.
#include "dpc31/pdu.hpp"

#include <gtest/gtest.h>

using namespace dpc31;
using namespace dpc31::pdu;

TEST(Pdu, SetPrmWithDpv1StatusBytes) {
  SetPrm p;
  p.station_status = SetPrm::Lock_Req | SetPrm::WD_On;
  p.wd_fact1 = 10;
  p.wd_fact2 = 20;
  p.min_tsdr = 11;
  p.ident = 0x0C31;
  p.group_ident = 0x01;
  p.user_prm = {0xC4, 0x20, 0x08, 0xAA};
  const Bytes b = p.build();
  EXPECT_EQ(b, (Bytes{0x88, 10, 20, 11, 0x0C, 0x31, 0x01, 0xC4, 0x20, 0x08, 0xAA}));
  const std::optional<SetPrm> q = SetPrm::parse(b);
  ASSERT_TRUE(q);
  EXPECT_EQ(*q, p);
  EXPECT_TRUE(q->dpv1());
  EXPECT_EQ(q->status(1), 0xC4);
  EXPECT_EQ(q->status(3), 0x08);
  EXPECT_EQ(Bytes(q->user_data().begin(), q->user_data().end()), Bytes{0xAA});
  EXPECT_FALSE(SetPrm::parse(Bytes{0x88, 10, 20, 11, 0x0C, 0x31}));  // 6 bytes
}

TEST(Pdu, SetPrmDpv0UserDataAfterSpecUserPrmByte) {
  const std::optional<SetPrm> p = SetPrm::parse(Bytes{0x80, 1, 1, 0, 0, 1, 0, 0x04, 0x55});
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->dpv1());
  EXPECT_EQ(Bytes(p->user_data().begin(), p->user_data().end()), Bytes{0x55});
}

TEST(Pdu, SlaveDiagWithAnAlarmBlockAndAnIdentifierBlock) {
  Dpv1DiagBlock alarm;
  alarm.type = 1;  // diagnosis alarm
  alarm.slot = 0;
  alarm.specifier = static_cast<std::uint8_t>(3 << 3 | 1);  // seq 3, appears
  alarm.data = {0x81};
  SlaveDiag d;
  d.station_status_1 = SlaveDiag::St1_Ext_Diag;
  d.station_status_2 = SlaveDiag::St2_Always_1 | SlaveDiag::St2_WD_On;
  d.master_add = 2;
  d.ident = 0x0C31;
  d.blocks = {alarm.build(), {SlaveDiag::Kind::identifier, {0x42, 0x01}}};
  const Bytes b = d.build();
  EXPECT_EQ(b,
            (Bytes{0x08, 0x0C, 0x00, 0x02, 0x0C, 0x31, 0x05, 0x01, 0x00, 0x19, 0x81, 0x42, 0x01}));
  const std::optional<SlaveDiag> q = SlaveDiag::parse(b);
  ASSERT_TRUE(q);
  EXPECT_EQ(*q, d);
  const std::optional<Dpv1DiagBlock> a = Dpv1DiagBlock::parse(q->blocks[0]);
  ASSERT_TRUE(a);
  EXPECT_EQ(*a, alarm);
  EXPECT_EQ(a->seq_nr(), 3);
  Bytes cut = b;
  cut.pop_back();  // the identifier block runs past the end
  EXPECT_FALSE(SlaveDiag::parse(cut));
}

TEST(Pdu, CfgGeneralAndSpecialFormat) {
  // 13h: 4 input bytes; 23h: 4 output bytes (general format). Special format (chip-facts.md
  // section 8: bits 7..6 01 an input length byte follows, 10 an output one, 11 output then
  // input; bits 3..0 manufacturer bytes): 40h one input length byte, 41h: 2 words = 4 bytes;
  // 81h one output length byte and one manufacturer byte, 02h: 3 bytes, then AAh.
  const std::optional<Cfg> c = Cfg::parse(Bytes{0x13, 0x23, 0x40, 0x41, 0x81, 0x02, 0xAA});
  ASSERT_TRUE(c);
  ASSERT_EQ(c->modules.size(), 4u);
  EXPECT_EQ(c->input_bytes(), 4 + 4);
  EXPECT_EQ(c->output_bytes(), 4 + 3);
  EXPECT_EQ(c->build(), (Bytes{0x13, 0x23, 0x40, 0x41, 0x81, 0x02, 0xAA}));
  // C0h: an output length byte (00h: 1 byte), then an input one (45h: 6 words = 12 bytes).
  const std::optional<Cfg> both = Cfg::parse(Bytes{0xC0, 0x00, 0x45});
  ASSERT_TRUE(both);
  EXPECT_EQ(both->output_bytes(), 1);
  EXPECT_EQ(both->input_bytes(), 12);
  EXPECT_FALSE(Cfg::parse(Bytes{0xC0, 0x81}));  // special format: two length bytes, one sent
}

TEST(Pdu, Dpv1ReadWriteAndTheirResponses) {
  EXPECT_EQ(read_request(1, 2, 8).build(), (Bytes{0x5E, 0x01, 0x02, 0x08}));
  EXPECT_EQ(write_request(0, 3, {0xAB, 0xCD}).build(), (Bytes{0x5F, 0x00, 0x03, 0x02, 0xAB, 0xCD}));
  const std::optional<Record> r =
      Record::parse(Bytes{0x5E, 0x01, 0x02, 0x02, 0x11, 0x22}, Function::Read, true);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data, (Bytes{0x11, 0x22}));
  EXPECT_FALSE(Record::parse(Bytes{0x5E, 0x01, 0x02, 0x03, 0x11}, Function::Read, true));
  EXPECT_FALSE(Record::parse(Bytes{0x5F, 0x01, 0x02, 0x03}, Function::Read, false));
  EXPECT_TRUE(Record::parse(Bytes{0x5F, 0x01, 0x02, 0x03}, Function::Write, false));
}

TEST(Pdu, NegativeResponseIsFourBytes) {
  const ErrorResponse e{Function::Read, Error_Decode_DPV1, error::Invalid_Index, 0x00};
  EXPECT_EQ(e.build(), (Bytes{0xDE, 0x80, 0xB0, 0x00}));
  EXPECT_EQ(ErrorResponse::parse(Bytes{0xDE, 0x80, 0xB0, 0x00}), e);
  EXPECT_TRUE(is_negative(Bytes{0xDE}));
  EXPECT_EQ(function_of(Bytes{0xDF}), Function::Write);
  EXPECT_FALSE(ErrorResponse::parse(Bytes{0x5E, 0x80, 0xB0, 0x00}));  // not negative
  EXPECT_FALSE(function_of(Bytes{0x12}));
}

TEST(Pdu, AlarmAckAbortIdleResourceManager) {
  EXPECT_EQ((AlarmAck{0, 1, 0x19}.build()), (Bytes{0x5C, 0x00, 0x01, 0x19}));
  EXPECT_EQ((Abort{0, 1, 3, 0}.build()), (Bytes{0x58, 0x00, 0x13, 0x00}));
  EXPECT_EQ(Abort::parse(Bytes{0x58, 0x00, 0x13, 0x00}), (Abort{0, 1, 3, 0}));
  EXPECT_EQ(Idle{}.build(), (Bytes{0x48, 0x00}));
  EXPECT_EQ((ResourceManager{48, 100}.build()), (Bytes{0x56, 0x30, 0x00, 0x64}));
  EXPECT_FALSE(AlarmAck::parse(Bytes{0x5C, 0x00, 0x01}));
}

TEST(Pdu, InitiateRequestAndResponse) {
  Initiate req;
  req.send_timeout = 100;
  req.features_supported = 0x0100;
  req.profile_ident_number = 0x9700;
  req.s_type = 0;
  req.d_type = 0;
  req.s_addr = {0x02, 0x00};
  req.d_addr = {0x05, 0x00};
  const Bytes b = req.build();
  EXPECT_EQ(b, (Bytes{0x57, 0,    0,    0,    0x00, 0x64, 0x01, 0x00, 0x00, 0x00,
                      0x97, 0x00, 0x00, 0x02, 0x00, 0x02, 0x02, 0x00, 0x05, 0x00}));
  EXPECT_EQ(Initiate::parse(b, false), req);
  Initiate res = req;
  res.response = true;
  res.send_timeout = 0;
  res.max_len_data_unit = 240;
  const Bytes r = res.build();
  EXPECT_EQ(r.size(), 16u);
  EXPECT_EQ(r[1], 240);
  EXPECT_EQ(Initiate::parse(r, true), res);
  EXPECT_FALSE(Initiate::parse(Bytes(b.begin(), b.end() - 1), false));
}
