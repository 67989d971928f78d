#include "mcs51/ihex.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace mcs51 {

namespace {
int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}
}  // namespace

namespace {
// Bytes no text file holds (NUL, other control characters than tab, CR, LF; DEL): a raw image.
bool binary(std::string_view text) {
  return std::any_of(text.begin(), text.end(), [](char c) {
    const auto b = static_cast<unsigned char>(c);
    return (b < 0x20 && c != '\t' && c != '\r' && c != '\n') || b == 0x7F;
  });
}
}  // namespace

bool parse_ihex(std::string_view text, HexImage& image, std::string& error) {
  const std::string_view whole = text;
  int line_no = 0;
  bool ended = false;
  while (!text.empty()) {
    std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) continue;
    auto fail = [&](std::string_view why) {
      error = fmt::format("line {}: {}", line_no, why);
      return false;
    };
    if (ended) return fail("record after the end-of-file record");
    if (line[0] != ':') {
      // A raw binary (objcopy -O binary, a Keil .bin) given for an Intel HEX image.
      if (binary(whole)) {
        return fail(
            "a record starts with ':': binary bytes, not an Intel HEX image (convert a raw image "
            "with objcopy -I binary -O ihex FILE.bin FILE.ihx)");
      }
      return fail("a record starts with ':'");
    }
    // ':', the byte count, the address (4), the type (2), 2 a data byte, the checksum (2).
    if (line.size() < 11) return fail("short record");
    const int count_hi = hex_digit(line[1]), count_lo = hex_digit(line[2]);
    if (count_hi < 0 || count_lo < 0) return fail("not a hex digit");
    const std::size_t count = static_cast<std::size_t>(count_hi << 4 | count_lo);
    const std::size_t length = 11 + 2 * count;
    if (line.size() < length) {
      return fail(
          fmt::format("short record: byte count {:02X}h needs {} characters, the record has {}",
                      count, length, line.size()));
    }
    if (line.size() > length) {
      const std::size_t extra = line.size() - length;
      return fail(fmt::format("{} character{} after the checksum (byte count {:02X}h)", extra,
                              extra == 1 ? "" : "s", count));
    }
    std::vector<std::uint8_t> rec;
    for (std::size_t i = 1; i < line.size(); i += 2) {
      int hi = hex_digit(line[i]), lo = hex_digit(line[i + 1]);
      if (hi < 0 || lo < 0) return fail("not a hex digit");
      rec.push_back(static_cast<std::uint8_t>(hi << 4 | lo));
    }
    // The checksum is the two's complement of the sum of the record's other bytes.
    std::uint8_t sum = 0;
    for (std::size_t i = 0; i + 1 < rec.size(); ++i) sum = static_cast<std::uint8_t>(sum + rec[i]);
    const auto expected = static_cast<std::uint8_t>(-sum);
    if (rec.back() != expected) {
      return fail(fmt::format("checksum {:02X}h, expected {:02X}h", rec.back(), expected));
    }
    const unsigned addr = rec[1] << 8 | rec[2];
    switch (rec[3]) {
      case 0x00:
        if (addr + rec[0] > 0x10000) return fail("data past 64 KB");
        for (unsigned i = 0; i < rec[0]; ++i) {
          // Two values for one address: which one the linker meant is unknown.
          if (image.used[addr + i]) {
            return fail(fmt::format("data at {:04X}h overlaps an earlier record", addr + i));
          }
          image.bytes[addr + i] = rec[4 + i];
          image.used[addr + i] = true;
        }
        image.size += rec[0];
        break;
      case 0x01:
        if (rec[0] != 0) {
          return fail(fmt::format("an end-of-file record has byte count 00h, not {:02X}h", rec[0]));
        }
        // An image that gives no byte runs nothing but the FFh of empty program memory.
        if (image.size == 0)
          return fail("no data bytes before the end-of-file record: an empty image");
        ended = true;
        break;
      case 0x02:
      case 0x04:
        if (rec[0] != 2) {
          return fail(
              fmt::format("a type {:02X} record has byte count 02h, not {:02X}h", rec[3], rec[0]));
        }
        if (rec[4] != 0 || rec[5] != 0) {
          // A segment base (x 16) may still be inside 64 KB: refused as what it is.
          return fail(
              rec[3] == 0x02
                  ? fmt::format("a non-zero segment base {:02X}{:02X}h (only 0000h is taken)",
                                rec[4], rec[5])
                  : "address above 64 KB");
        }
        break;
      case 0x03:
      case 0x05:  // a start address (CS:IP, EIP): 4 bytes, of no use to a reset that starts at 0
        if (rec[0] != 4) {
          return fail(
              fmt::format("a type {:02X} record has byte count 04h, not {:02X}h", rec[3], rec[0]));
        }
        break;
      default:
        return fail(fmt::format("record type {:02X}", rec[3]));
    }
  }
  if (!ended) {
    // An empty file has no line to name.
    error = line_no == 0 ? "empty file, not an Intel HEX image"
                         : fmt::format("line {}: no end-of-file record", line_no);
    return false;
  }
  return true;
}

}  // namespace mcs51
