// Intel HEX (what SDCC's linker and Keil write): data records into a 64 KB image.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mcs51 {

struct HexImage {
  std::vector<std::uint8_t> bytes = std::vector<std::uint8_t>(0x10000, 0xFF);
  std::vector<bool> used = std::vector<bool>(0x10000, false);
  std::uint32_t size = 0;  // bytes given by data records (each address once)
};

// Record types 00 (data), 01 (end of file), 02/04 with a zero base, 03/05 (start address, not
// used: the 80C32 starts at 0000h). False with `error` = "line N: reason" for anything else: a
// bad character or checksum, a short record, data past 64 KB or at an address an earlier record
// gave, no data bytes, no end record.
bool parse_ihex(std::string_view text, HexImage& image, std::string& error);

}  // namespace mcs51
