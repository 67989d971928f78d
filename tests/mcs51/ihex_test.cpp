// Intel HEX records (Intel's "Hexadecimal Object File Format Specification", rev. A).
#include "mcs51/ihex.hpp"

#include <gtest/gtest.h>

#include <string>
#include <string_view>

namespace mcs51 {
namespace {

TEST(Mcs51Hex, DataRecordsLandAtTheirAddresses) {
  // What sdld wrote for MOV A,#12h; MOV B,#3; MUL AB; ... (checksums by the specification).
  HexImage img;
  std::string err;
  ASSERT_TRUE(parse_ihex(":0C000000741275F003A47830F6A380FEA3\r\n:00000001FF\n", img, err)) << err;
  EXPECT_EQ(img.size, 12u);
  EXPECT_EQ(img.bytes[0], 0x74);
  EXPECT_EQ(img.bytes[11], 0xFE);
  EXPECT_TRUE(img.used[11]);
  EXPECT_FALSE(img.used[12]);
  // Records that meet without overlapping: each byte counted once, a zero base taken.
  HexImage two;
  ASSERT_TRUE(
      parse_ihex(":020000020000FC\n:020000000000FE\n:0200020080FE7E\n:00000001FF\n", two, err))
      << err;
  EXPECT_EQ(two.size, 4u);
  EXPECT_EQ(two.bytes[3], 0xFE);
}

// A raw binary where an Intel HEX image is expected (objcopy -O binary's output: LJMP 000Bh with
// its NUL byte, SJMP $) says so and how to convert it; a text file that is no image keeps the plain
// words (the s35 audit, finding 6).
TEST(Mcs51Hex, ARawBinaryIsNamedAndTheConversionGiven) {
  HexImage img;
  std::string err;
  using namespace std::string_view_literals;
  EXPECT_FALSE(parse_ihex("\x02\x00\x0B\x80\xFE"sv, img, err));
  EXPECT_EQ(err,
            "line 1: a record starts with ':': binary bytes, not an Intel HEX image (convert a raw "
            "image with objcopy -I binary -O ihex FILE.bin FILE.ihx)");
  EXPECT_FALSE(parse_ihex("hello\n", img, err));
  EXPECT_EQ(err, "line 1: a record starts with ':'");
}

TEST(Mcs51Hex, BadRecordsNameTheirLine) {
  const std::pair<const char*, const char*> bad[] = {
      // The checksum is the two's complement of the other bytes' sum (the specification): A3h.
      {":0C000000741275F003A47830F6A380FEA4\n", "line 1: checksum A4h, expected A3h"},
      {"\n0C000000\n", "line 2: a record starts with ':'"},
      // A record is ':', the byte count (2 digits), the address (4), the type (2), 2 digits a
      // data byte and the checksum (2): 11 + 2 x count characters.
      {":0200000074\n",
       "line 1: short record: byte count 02h needs 15 characters, the record has 11"},
      {":02000000741\n",
       "line 1: short record: byte count 02h needs 15 characters, the record has 12"},
      {":0100000G0000\n", "line 1: not a hex digit"},
      {":0G00000000\n", "line 1: not a hex digit"},
      {":03000000741275\n",
       "line 1: short record: byte count 03h needs 17 characters, the record has 15"},
      // Longer than its byte count: a blank after the checksum is no short record.
      {":0100000000FF \n:00000001FF\n", "line 1: 1 character after the checksum (byte count 01h)"},
      {":0100000000FF00\n:00000001FF\n",
       "line 1: 2 characters after the checksum (byte count 01h)"},
      // The end-of-file record (type 01) has byte count 00 by the specification: no data byte.
      {":0100000000FF\n:0100000100FE\n",
       "line 2: an end-of-file record has byte count 00h, not 01h"},
      {":02FFFF00000000\n:00000001FF\n", "line 1: data past 64 KB"},
      {":020000040001F9\n", "line 1: address above 64 KB"},
      // A segment base is x 16: 0100h would be 1000h, inside 64 KB, but it is no address.
      {":020000020100FB\n:0200000080FE80\n:00000001FF\n",
       "line 1: a non-zero segment base 0100h (only 0000h is taken)"},
      {":03000002000000FB\n", "line 1: a type 02 record has byte count 02h, not 03h"},
      // Start-address records (03 CS:IP, 05 EIP) have 4 data bytes by the format, as 02 / 04
      // have 2.
      {":0100000300FC\n:0100000000FF\n:00000001FF\n",
       "line 1: a type 03 record has byte count 04h, not 01h"},
      {":00000005FB\n:0100000000FF\n:00000001FF\n",
       "line 1: a type 05 record has byte count 04h, not 00h"},
      // No data bytes: an image that runs nothing.
      {":00000001FF\n", "line 1: no data bytes before the end-of-file record: an empty image"},
      {":0000000000\n:00000001FF\n",
       "line 2: no data bytes before the end-of-file record: an empty image"},
      // Address 0001h given twice: which byte the linker meant is unknown.
      {":020000000000FE\n:0100010000FE\n:00000001FF\n",
       "line 2: data at 0001h overlaps an earlier record"},
      {":0000000AF6\n", "line 1: record type 0A"},
      {":0100000000FF\n", "line 1: no end-of-file record"},
      {":0100000000FF\n:00000001FF\n:0100010000FE\n",
       "line 3: record after the end-of-file record"},
      {"", "empty file, not an Intel HEX image"},  // no line 0 to name
  };
  for (auto [text, why] : bad) {
    HexImage img;
    std::string err;
    EXPECT_FALSE(parse_ihex(text, img, err)) << text;
    EXPECT_EQ(err, why) << text;
  }
}

}  // namespace
}  // namespace mcs51
