// FDL telegram coding (chip-facts §8). Expected bytes are worked out by hand: FCS = sum mod 256
// of DA..last DU byte as sent (extension bits and SAP bytes included).
#include "dpc31/fdl.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

using namespace dpc31::fdl;
using Bytes = std::vector<std::uint8_t>;

namespace {

Decoded dec(const Bytes& b) { return decode(std::span<const std::uint8_t>(b)); }

// Expects decode(bytes) to succeed with `frame` and encode(frame) to give `bytes` back.
void expect_both_ways(const Frame& frame, const Bytes& bytes) {
  EXPECT_EQ(encode(frame), bytes);
  Bytes into(300, 0xAA);  // what the buffer held is replaced
  EXPECT_TRUE(encode(frame, into));
  EXPECT_EQ(into, bytes);
  const Decoded d = dec(bytes);
  EXPECT_EQ(error_name(d.error), "none");
  EXPECT_EQ(d.frame, frame);
}

Bytes counting(std::size_t n, std::uint8_t first = 0) {
  Bytes v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(first + i);
  return v;
}

}  // namespace

TEST(FdlFc, RequestCodes) {
  EXPECT_EQ(make_request_fc(Function::FDL_Status, false, false), 0x49);
  EXPECT_EQ(make_request_fc(Function::SRD_high, true, false), 0x6D);
  EXPECT_EQ(make_request_fc(Function::SRD_high, false, true), 0x5D);
  EXPECT_EQ(make_request_fc(Function::SRD_high, true, true), 0x7D);
  EXPECT_EQ(make_request_fc(Function::SDN_high, false, false), 0x46);
  EXPECT_EQ(make_request_fc(Function::LSAP_Status, false, false), 0x4F);
  EXPECT_TRUE(is_request(0x6D));
  EXPECT_TRUE(fcb(0x6D));
  EXPECT_FALSE(fcv(0x6D));
  EXPECT_FALSE(fcb(0x5D));
  EXPECT_TRUE(fcv(0x5D));
  EXPECT_EQ(request_function(0x7D), Function::SRD_high);
  EXPECT_EQ(request_function(0x43), Function::SDA_low);
  EXPECT_EQ(request_function(0x4E), Function::Ident);
}

TEST(FdlFc, ResponseCodes) {
  EXPECT_EQ(make_response_fc(Response::OK), 0x00);
  EXPECT_EQ(make_response_fc(Response::DL), 0x08);
  EXPECT_EQ(make_response_fc(Response::RS), 0x03);
  EXPECT_EQ(make_response_fc(Response::RDH), 0x0D);
  EXPECT_EQ(make_response_fc(Response::OK, 3), 0x30);  // master in ring
  EXPECT_EQ(make_response_fc(Response::NR, 2), 0x29);
  EXPECT_FALSE(is_request(0x08));
  EXPECT_EQ(response_code(0x0A), Response::DH);
  EXPECT_EQ(station_type(0x29), 2);
  EXPECT_EQ(sap_number(0x40 | 60), 60);
  EXPECT_TRUE(sap_segment(0x40 | 60));
  EXPECT_FALSE(sap_segment(60));
}

// Known telegrams of the DP start-up, master 2 and slave 5.
TEST(FdlTelegram, FdlStatusRequestAndResponse) {
  expect_both_ways(make_frame(5, 2, 0x49), Bytes{0x10, 0x05, 0x02, 0x49, 0x50, 0x16});
  expect_both_ways(make_frame(2, 5, make_response_fc(Response::OK)),
                   Bytes{0x10, 0x02, 0x05, 0x00, 0x07, 0x16});
}

// Slave_Diag request: DSAP 60, SSAP 62, no DU beyond the SAPs. SD1 cannot carry SAP bytes,
// so this is SD2 with LE = 5: 85+82+6D+3C+3E = 1EE.
TEST(FdlTelegram, SlaveDiagRequest) {
  const Frame f = make_frame(5, 2, 0x6D, {}, 60, 62);
  EXPECT_EQ(f.sd, SD2);
  expect_both_ways(f, Bytes{0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x6D, 0x3C, 0x3E, 0xEE, 0x16});
}

// Slave_Diag response (DL): Station_Status_1..3 = 02 05 00, Master_Add FF, Ident 801D.
TEST(FdlTelegram, SlaveDiagResponse) {
  const Frame f = make_frame(2, 5, make_response_fc(Response::DL),
                             {0x02, 0x05, 0x00, 0xFF, 0x80, 0x1D}, 62, 60);
  expect_both_ways(f, Bytes{0x68, 0x0B, 0x0B, 0x68, 0x82, 0x85, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00,
                            0xFF, 0x80, 0x1D, 0x2C, 0x16});
}

// Set_Prm with the 7 standard bytes: Lock_Req|WD_On, WD_Fact 1/10, min_TSDR 11, Ident 801D,
// Group_Ident 0. LE = 3 + 2 + 7 = 12, FCS = 31A.
TEST(FdlTelegram, SetPrm) {
  const Frame f = make_frame(5, 2, 0x5D, {0x88, 0x01, 0x0A, 0x0B, 0x80, 0x1D, 0x00}, 61, 62);
  expect_both_ways(f, Bytes{0x68, 0x0C, 0x0C, 0x68, 0x85, 0x82, 0x5D, 0x3D, 0x3E, 0x88, 0x01, 0x0A,
                            0x0B, 0x80, 0x1D, 0x00, 0x1A, 0x16});
}

// Global_Control Freeze to all groups, SDN to the broadcast address: DA = 7F|80.
TEST(FdlTelegram, GlobalControlBroadcast) {
  const Frame f = make_frame(kBroadcast, 2, 0x46, {0x08, 0x00}, 58, 62);
  expect_both_ways(
      f, Bytes{0x68, 0x07, 0x07, 0x68, 0xFF, 0x82, 0x46, 0x3A, 0x3E, 0x08, 0x00, 0x47, 0x16});
}

// Data_Exchange with 8 output bytes in SD3 (default SAP, no extension): 84 + 24 = A8.
TEST(FdlTelegram, DataExchangeSd3) {
  const Frame f{SD3, 5, 2, 0x7D, std::nullopt, std::nullopt, counting(8, 1)};
  expect_both_ways(f, Bytes{0xA2, 0x05, 0x02, 0x7D, 1, 2, 3, 4, 5, 6, 7, 8, 0xA8, 0x16});
}

TEST(FdlTelegram, TokenAndShortAck) {
  expect_both_ways(token(5, 2), Bytes{0xDC, 0x05, 0x02});
  expect_both_ways(sc(), Bytes{0xE5});
}

TEST(FdlRoundTrip, Sd1) {
  for (const Frame& f :
       {make_frame(0, 0, 0x40), make_frame(126, 1, 0x4C), make_frame(127, 3, 0x44)}) {
    EXPECT_EQ(f.sd, SD1);
    const Bytes b = encode(f);
    EXPECT_EQ(b.size(), 6U);
    EXPECT_EQ(dec(b).frame, f);
  }
}

TEST(FdlRoundTrip, Sd2WithoutSaps) {
  for (std::size_t n : {1U, 2U, 8U, 100U, 246U}) {
    const Frame f = make_frame(5, 2, 0x7D, counting(n, 0xF0));
    EXPECT_EQ(f.sd, SD2);
    const Bytes b = encode(f);
    ASSERT_EQ(b.size(), n + 9);
    EXPECT_EQ(b[1], n + 3);
    EXPECT_EQ(b[4], 0x05);  // no extension bit
    const Decoded d = dec(b);
    EXPECT_EQ(d.error, Error::none);
    EXPECT_EQ(d.frame, f);
  }
}

TEST(FdlRoundTrip, Sd2WithSapsZeroAnd244DataBytes) {
  const Frame empty = make_frame(5, 2, 0x6D, {}, 60, 62);
  EXPECT_EQ(encode(empty).size(), 11U);
  EXPECT_EQ(dec(encode(empty)).frame, empty);

  // The longest frame: LE = 3 + 2 + 244 = 249 (F9), 255 bytes in all.
  const Frame full = make_frame(5, 2, 0x5D, counting(244), 61, 62);
  const Bytes b = encode(full);
  ASSERT_EQ(b.size(), 255U);
  EXPECT_EQ(b[1], 0xF9);
  EXPECT_EQ(b[2], 0xF9);
  EXPECT_EQ(b[4], 0x85);
  EXPECT_EQ(b[5], 0x82);
  EXPECT_EQ(b[7], 61);
  EXPECT_EQ(b[8], 62);
  EXPECT_EQ(b[9], 0);
  EXPECT_EQ(b[252], 243);
  const Decoded d = dec(b);
  EXPECT_EQ(d.error, Error::none);
  EXPECT_EQ(d.frame, full);
}

// Only one side extended: that SAP is the first DU byte; a segment flag survives.
TEST(FdlRoundTrip, SingleSapAndSegmentFlag) {
  const Frame ssap_only = make_frame(5, 2, 0x48, {0xAA}, std::nullopt, 62);
  expect_both_ways(ssap_only,
                   Bytes{0x68, 0x05, 0x05, 0x68, 0x05, 0x82, 0x48, 0x3E, 0xAA, 0xB7, 0x16});
  const Frame dsap_only = make_frame(5, 2, 0x6D, {}, 0x40 | 60);
  expect_both_ways(dsap_only, Bytes{0x68, 0x04, 0x04, 0x68, 0x85, 0x02, 0x6D, 0x7C, 0x70, 0x16});
}

TEST(FdlRoundTrip, Sd3WithAndWithoutSaps) {
  const Frame plain{SD3, 9, 1, 0x7D, std::nullopt, std::nullopt, counting(8, 0x80)};
  EXPECT_EQ(dec(encode(plain)).frame, plain);
  // The 8 fixed bytes include the SAP bytes.
  const Frame saps{SD3, 9, 1, 0x5D, 61, 62, counting(6, 0x10)};
  const Bytes b = encode(saps);
  ASSERT_EQ(b.size(), 14U);
  EXPECT_EQ(b[1], 0x89);
  EXPECT_EQ(b[4], 61);
  EXPECT_EQ(dec(b).frame, saps);
}

TEST(FdlRoundTrip, Sd4AndSc) {
  EXPECT_EQ(dec(encode(token(127, 0))).frame, token(127, 0));
  EXPECT_EQ(dec(encode(token(0, 126))).frame, token(0, 126));
  // SC: only sd is meaningful, the addresses are not sent.
  Frame f = sc();
  f.da = 5;
  EXPECT_EQ(encode(f), Bytes{SC});
  EXPECT_EQ(dec(Bytes{SC}).frame, sc());
}

TEST(FdlEncode, RefusesWhatTheSdCannotCarry) {
  EXPECT_TRUE(encode(Frame{SD1, 5, 2, 0x49, std::nullopt, std::nullopt, {1}}).empty());
  EXPECT_TRUE(encode(Frame{SD1, 5, 2, 0x49, 60, std::nullopt, {}}).empty());
  EXPECT_TRUE(encode(Frame{SD2, 5, 2, 0x49, std::nullopt, std::nullopt, {}}).empty());  // LE 3
  EXPECT_TRUE(encode(make_frame(5, 2, 0x7D, counting(247))).empty());                   // LE 250
  EXPECT_TRUE(encode(make_frame(5, 2, 0x7D, counting(245), 61, 62)).empty());           // LE 250
  EXPECT_TRUE(encode(Frame{SD3, 5, 2, 0x7D, std::nullopt, std::nullopt, counting(7)}).empty());
  EXPECT_TRUE(encode(Frame{SD3, 5, 2, 0x7D, 61, 62, counting(8)}).empty());
  EXPECT_TRUE(encode(make_frame(128, 2, 0x49)).empty());
  EXPECT_TRUE(encode(token(5, 0x80)).empty());
  EXPECT_TRUE(encode(make_frame(5, 2, 0x6D, {}, 0x80 | 60, 62)).empty());
  EXPECT_TRUE(encode(Frame{0x11, 5, 2, 0x49, std::nullopt, std::nullopt, {}}).empty());
  EXPECT_TRUE(encode(Frame{SD4, 5, 2, 0, std::nullopt, 62, {}}).empty());
  EXPECT_TRUE(encode(Frame{SC, 0, 0, 0, std::nullopt, std::nullopt, {1}}).empty());
}

// The buffer form (DpMaster encodes every request into one buffer): false and empty where the
// value form is empty, the buffer's storage kept from one telegram to the next.
TEST(FdlEncode, IntoABufferKeepsItsStorage) {
  Bytes into;
  ASSERT_TRUE(encode(make_frame(5, 2, 0x7D, counting(244)), into));
  EXPECT_EQ(into.size(), 253U);  // SD2 with LE 247: SD LE LEr SD, 247, FCS, ED
  const std::uint8_t* storage = into.data();
  EXPECT_TRUE(encode(make_frame(5, 2, 0x49), into));
  EXPECT_EQ(into, (Bytes{SD1, 5, 2, 0x49, 0x50, ED}));
  EXPECT_EQ(into.data(), storage);
  EXPECT_TRUE(encode(token(3, 2), into));
  EXPECT_EQ(into, (Bytes{SD4, 3, 2}));
  EXPECT_TRUE(encode(sc(), into));
  EXPECT_EQ(into, (Bytes{SC}));
  EXPECT_FALSE(encode(make_frame(5, 2, 0x7D, counting(247)), into));  // LE 250
  EXPECT_TRUE(into.empty());
  into = {1, 2, 3};
  EXPECT_FALSE(encode(Frame{SC, 0, 0, 0, std::nullopt, std::nullopt, {1}}, into));
  EXPECT_TRUE(into.empty());
  into = {1, 2, 3};
  EXPECT_FALSE(encode(token(5, 0x80), into));
  EXPECT_TRUE(into.empty());
}

TEST(FdlMakeFrame, ChoosesSd1OrSd2) {
  EXPECT_EQ(make_frame(5, 2, 0x49).sd, SD1);
  EXPECT_EQ(make_frame(5, 2, 0x7D, {1}).sd, SD2);
  EXPECT_EQ(make_frame(5, 2, 0x6D, {}, 60).sd, SD2);
  EXPECT_EQ(make_frame(5, 2, 0x6D, {}, std::nullopt, 62).sd, SD2);
  EXPECT_EQ(make_frame(5, 2, 0x7D, counting(8)).sd, SD2);  // never SD3
}

// Every error class from a minimal input.
TEST(FdlDecode, Errors) {
  struct Case {
    Bytes in;
    Error want;
  };
  const Case cases[] = {
      {{0x10, 0x05, 0x02, 0x49, 0x50, 0x16}, Error::none},
      {{0x00}, Error::bad_sd},
      {{0x16}, Error::bad_sd},
      {{0x68, 0x04, 0x04, 0x10}, Error::bad_sd},  // SD2 not repeated
      {{}, Error::truncated},
      {{0x10, 0x05}, Error::truncated},
      {{0x68, 0x04}, Error::truncated},
      {{0x68, 0x04, 0x04}, Error::truncated},
      {{0x68, 0x04, 0x04, 0x68, 0x05, 0x02, 0x7D, 0x00, 0x84}, Error::truncated},
      {{0xDC, 0x05}, Error::truncated},
      {{0x68, 0x04, 0x05}, Error::le_mismatch},
      {{0x68, 0x03, 0x03}, Error::bad_le},
      {{0x68, 0xFA, 0xFA}, Error::bad_le},
      // Both extension bits but only one DU byte: LE too short for the SAPs.
      {{0x68, 0x04, 0x04, 0x68, 0x85, 0x82, 0x6D, 0x3C, 0xB0, 0x16}, Error::bad_le},
      {{0x10, 0x05, 0x02, 0x49, 0x51, 0x16}, Error::bad_fcs},
      {{0x10, 0x05, 0x02, 0x49, 0x50, 0x17}, Error::wrong_ed},
      {{0xE5, 0xE5}, Error::oversize},
      {{0x10, 0x05, 0x02, 0x49, 0x50, 0x16, 0x16}, Error::oversize},
      {{0xDC, 0x05, 0x02, 0x00}, Error::oversize},
      // DSAP with further extension (BC = 80|3C): 85+82+6D+BC+3E = 26E.
      {{0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x6D, 0xBC, 0x3E, 0x6E, 0x16}, Error::bad_sap},
      {{0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x6D, 0x3C, 0xBE, 0x6E, 0x16}, Error::bad_sap},
      // SD1 has no DU to carry the SAP its DA announces: 85+02+49 = D0.
      {{0x10, 0x85, 0x02, 0x49, 0xD0, 0x16}, Error::bad_sap},
      {{0xDC, 0x85, 0x02}, Error::bad_sap},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(error_name(dec(c.in).error), error_name(c.want))
        << "input of " << c.in.size() << " bytes starting " << (c.in.empty() ? -1 : c.in[0]);
  }
}

// The buffer form (a segment's HeardFramePool decodes every telegram into the frame it refills):
// each result as the value form's, nothing left of the telegram before, the DU's storage kept.
TEST(FdlDecode, IntoADecodedKeepsOnlyItsStorage) {
  const Bytes big = encode(make_frame(5, 2, 0x7D, counting(244), 60, 62));
  const Bytes inputs[] = {
      big,
      encode(make_frame(3, 2, 0x6D, {1, 2}, 61)),
      encode(make_frame(5, 2, 0x49)),
      {0x10, 0x85, 0x02, 0x49, 0xD0, 0x16},  // bad_sap after DA/SA/FC are parsed
      encode(token(3, 2)),
      {0xE5, 0xE5},
      {},
      encode(make_frame(7, 2, 0x5D, {9}, std::nullopt, 62)),
  };
  Decoded into;
  for (const Bytes& in : inputs) {
    decode(in, into);
    const Decoded want = dec(in);
    EXPECT_EQ(error_name(into.error), error_name(want.error)) << in.size() << " bytes";
    EXPECT_EQ(into.frame, want.frame) << in.size() << " bytes";
  }
  decode(big, into);
  const std::uint8_t* storage = into.frame.du.data();
  decode(inputs[1], into);
  EXPECT_EQ(into.frame.du.data(), storage);
}

TEST(FdlDecode, ErrorNames) {
  EXPECT_EQ(error_name(Error::none), "none");
  EXPECT_EQ(error_name(Error::le_mismatch), "le_mismatch");
  EXPECT_EQ(error_name(Error::bad_sap), "bad_sap");
}

// A broken frame's contents are not interpreted: a bad FCS wins over a bad SAP.
TEST(FdlDecode, FcsBeforeSap) {
  EXPECT_EQ(dec(Bytes{0x10, 0x85, 0x02, 0x49, 0x00, 0x16}).error, Error::bad_fcs);
  EXPECT_EQ(dec(Bytes{0x10, 0x05, 0x02, 0x49, 0x50}).error, Error::truncated);
}

namespace {

// Pushes all bytes, returns the status after the last.
Assembler::Status feed(Assembler& a, const Bytes& b) {
  Assembler::Status s = a.status();
  for (std::uint8_t x : b) s = a.push(x);
  return s;
}

}  // namespace

TEST(FdlAssembler, KnowsTheLengthFromSdAndLe) {
  using S = Assembler::Status;
  Assembler a;
  EXPECT_EQ(a.expected_length(), 0U);
  EXPECT_EQ(a.push(SC), S::complete);
  EXPECT_EQ(a.expected_length(), 1U);

  a.reset();
  EXPECT_EQ(a.push(SD4), S::need_more);
  EXPECT_EQ(a.expected_length(), 3U);
  a.reset();
  a.push(SD1);
  EXPECT_EQ(a.expected_length(), 6U);
  a.reset();
  a.push(SD3);
  EXPECT_EQ(a.expected_length(), 14U);

  a.reset();
  EXPECT_EQ(a.push(SD2), S::need_more);
  EXPECT_EQ(a.push(0x05), S::need_more);
  EXPECT_EQ(a.expected_length(), 0U);  // not before LEr
  EXPECT_EQ(a.push(0x05), S::need_more);
  EXPECT_EQ(a.expected_length(), 11U);
}

TEST(FdlAssembler, CompletesExactlyAtTheLastByte) {
  for (const Bytes& b : {encode(make_frame(5, 2, 0x49)), encode(make_frame(5, 2, 0x6D, {}, 60, 62)),
                         encode(make_frame(5, 2, 0x5D, counting(244), 61, 62)),
                         encode(Frame{SD3, 5, 2, 0x7D, std::nullopt, std::nullopt, counting(8)}),
                         encode(token(2, 5)), encode(sc())}) {
    Assembler a;
    for (std::size_t i = 0; i < b.size(); ++i) {
      const auto s = a.push(b[i]);
      ASSERT_EQ(s, i + 1 == b.size() ? Assembler::Status::complete : Assembler::Status::need_more)
          << "byte " << i << " of " << b.size();
    }
    EXPECT_EQ(a.expected_length(), b.size());
    EXPECT_TRUE(std::ranges::equal(a.bytes(), b));
    EXPECT_EQ(decode(a.bytes()).error, Error::none);
  }
}

TEST(FdlAssembler, FramingErrorsAtTheOffendingByte) {
  using S = Assembler::Status;
  Assembler a;
  EXPECT_EQ(a.push(0x00), S::error);
  EXPECT_EQ(a.error(), Error::bad_sd);
  EXPECT_EQ(a.bytes().size(), 1U);

  a.reset();
  EXPECT_EQ(feed(a, {0x68, 0x04, 0x04, 0x10}), S::error);
  EXPECT_EQ(a.error(), Error::bad_sd);

  a.reset();
  EXPECT_EQ(feed(a, {0x68, 0x04}), S::need_more);
  EXPECT_EQ(a.push(0x05), S::error);
  EXPECT_EQ(a.error(), Error::le_mismatch);

  a.reset();
  EXPECT_EQ(feed(a, {0x68, 0x03, 0x03}), S::error);
  EXPECT_EQ(a.error(), Error::bad_le);
  a.reset();
  EXPECT_EQ(feed(a, {0x68, 0xFA, 0xFA}), S::error);
  EXPECT_EQ(a.error(), Error::bad_le);

  // One byte more than the SD says.
  a.reset();
  EXPECT_EQ(a.push(SC), S::complete);
  EXPECT_EQ(a.push(SC), S::error);
  EXPECT_EQ(a.error(), Error::oversize);
  EXPECT_EQ(a.bytes().size(), 1U);

  // The error state holds until reset and stores nothing more.
  EXPECT_EQ(a.push(SD1), S::error);
  EXPECT_EQ(a.bytes().size(), 1U);
  a.reset();
  EXPECT_EQ(a.status(), S::need_more);
  EXPECT_EQ(a.error(), Error::none);
  EXPECT_TRUE(a.bytes().empty());
}

// The remaining classes come from decode(bytes()): interrupted (truncated), or complete.
TEST(FdlAssembler, ContentErrorsViaDecode) {
  Assembler a;
  EXPECT_EQ(feed(a, {0x10, 0x05}), Assembler::Status::need_more);
  EXPECT_EQ(decode(a.bytes()).error, Error::truncated);
  for (const auto& [in, want] : std::vector<std::pair<Bytes, Error>>{
           {{0x10, 0x05, 0x02, 0x49, 0x51, 0x16}, Error::bad_fcs},
           {{0x10, 0x05, 0x02, 0x49, 0x50, 0x17}, Error::wrong_ed},
           {{0x10, 0x85, 0x02, 0x49, 0xD0, 0x16}, Error::bad_sap},
           {{0x68, 0x04, 0x04, 0x68, 0x85, 0x82, 0x6D, 0x3C, 0xB0, 0x16}, Error::bad_le}}) {
    a.reset();
    EXPECT_EQ(feed(a, in), Assembler::Status::complete);
    EXPECT_EQ(error_name(decode(a.bytes()).error), error_name(want));
  }
}

// Random input, biased towards delimiters and repeated bytes so that SD2 headers with LE = LEr
// occur. Invariants: never more than 255 bytes; the Assembler and decode agree.
TEST(FdlAssembler, RandomBytesWithReset) {
  std::mt19937 rng(0xDC31);
  std::uniform_int_distribution<unsigned> any(0, 255);
  std::uniform_int_distribution<unsigned> pick(0, 7);
  constexpr std::uint8_t kSpecial[] = {SD1, SD2, SD3, SD4, SC, ED};
  Assembler a;
  std::uint8_t prev = 0;
  std::size_t completes = 0, good = 0, errors = 0;
  for (int i = 0; i < 100000; ++i) {
    const unsigned p = pick(rng);
    const std::uint8_t x = p == 0   ? kSpecial[any(rng) % 6]
                           : p == 1 ? prev
                                    : static_cast<std::uint8_t>(any(rng));
    prev = x;
    const auto s = a.push(x);
    ASSERT_LE(a.bytes().size(), kMaxFrameLength);
    ASSERT_LE(a.expected_length(), kMaxFrameLength);
    const Decoded d = decode(a.bytes());
    if (s == Assembler::Status::need_more) {
      ASSERT_EQ(d.error, Error::truncated);
      continue;
    }
    if (s == Assembler::Status::complete) {
      ++completes;
      ASSERT_EQ(a.bytes().size(), a.expected_length());
      ASSERT_TRUE(d.error == Error::none || d.error == Error::bad_fcs ||
                  d.error == Error::wrong_ed || d.error == Error::bad_sap ||
                  d.error == Error::bad_le)
          << error_name(d.error);
      if (d.error == Error::none) {
        ++good;
        ASSERT_TRUE(std::ranges::equal(encode(d.frame), a.bytes()));
      }
    } else {
      ++errors;
      ASSERT_NE(a.error(), Error::oversize);
      ASSERT_EQ(d.error, a.error());
    }
    a.reset();
  }
  EXPECT_GT(completes, 0U);
  EXPECT_GT(good, 0U);
  EXPECT_GT(errors, 0U);
}

TEST(FdlAssembler, RandomBytesWithoutReset) {
  std::mt19937 rng(31);
  std::uniform_int_distribution<unsigned> any(0, 255);
  for (std::uint8_t first : {SD2, SD1, SC, std::uint8_t{0}}) {
    Assembler a;
    a.push(first);
    a.push(0xF9);
    a.push(0xF9);
    a.push(SD2);
    for (int i = 0; i < 100000; ++i) {
      a.push(static_cast<std::uint8_t>(any(rng)));
      ASSERT_LE(a.bytes().size(), kMaxFrameLength);
    }
    EXPECT_EQ(a.status(), Assembler::Status::error);
  }
}

// push_block is push() byte by byte up to the verdict: the same status, length, bytes and error,
// and it stops after the byte that gave the verdict. Good frames of every SD (SD2 at every LE),
// and the same with bytes damaged at random, pushed in blocks split at random.
TEST(FdlAssembler, PushBlockIsPushByteByByte) {
  std::mt19937 rng(7);
  std::vector<Bytes> frames = {{SC},
                               {SD4, 5, 2},
                               encode(make_frame(5, 2, 0x49)),
                               encode(make_frame(5, 2, 0x5D, counting(6), 60, 62))};
  frames.back()[0] = SD3;  // SD3: 8 data bytes with the SAPs
  frames.back().erase(frames.back().begin() + 1, frames.back().begin() + 4);
  for (std::size_t n = 1; n <= 246; ++n)
    frames.push_back(encode(make_frame(5, 2, 0x7D, counting(n))));
  std::size_t damaged = 0;
  for (int round = 0; round < 3; ++round) {
    for (Bytes f : frames) {
      if (round > 0) {  // a byte damaged, and bytes after the frame
        f[rng() % std::min<std::size_t>(f.size(), 6)] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        f.push_back(static_cast<std::uint8_t>(rng()));
        ++damaged;
      }
      Assembler a;
      std::size_t taken = 0;
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (a.push(f[i]) != Assembler::Status::need_more) {
          taken = i + 1;
          break;
        }
        taken = i + 1;
      }
      Assembler b;
      std::size_t got = 0;
      for (std::span<const std::uint8_t> rest(f); !rest.empty() && got < f.size();) {
        const std::size_t cut = 1 + rng() % rest.size();
        const std::size_t k = b.push_block(rest.first(cut));
        got += k;
        if (k < cut) break;
        rest = rest.subspan(cut);
      }
      ASSERT_EQ(got, taken) << f.size();
      ASSERT_EQ(b.status(), a.status());
      ASSERT_EQ(b.error(), a.error());
      ASSERT_EQ(b.expected_length(), a.expected_length());
      ASSERT_TRUE(std::ranges::equal(b.bytes(), a.bytes()));
    }
  }
  EXPECT_GT(damaged, 400U);
}

// The FCS is the sum mod 256 of the bytes, whatever their number (fcs sums eight at a time).
TEST(FdlFcs, IsTheSumOfTheBytesMod256) {
  std::mt19937 rng(3);
  for (std::size_t n = 0; n < 2100; n += 1 + n / 16) {
    Bytes b(n);
    for (auto& x : b) x = static_cast<std::uint8_t>(rng() | 0xF0);
    unsigned sum = 0;
    for (std::uint8_t x : b) sum += x;
    ASSERT_EQ(fcs(b), static_cast<std::uint8_t>(sum)) << n;
  }
}
