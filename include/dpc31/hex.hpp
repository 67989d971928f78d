// Bytes as upper-case hex, two digits each ("10 05 02"): the one formatter of the chip library,
// the session layer (walks, traces) and the tools (bridge log, serve replies).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>

namespace dpc31 {

// `sep` between two bytes; past `max` bytes, " ... (N bytes)" instead of the rest.
inline std::string hex_bytes(std::span<const std::uint8_t> bytes, std::string_view sep = " ",
                             std::size_t max = std::numeric_limits<std::size_t>::max()) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string s;
  s.reserve(bytes.size() * (2 + sep.size()));
  for (std::size_t i = 0; i < bytes.size() && i < max; ++i) {
    if (i != 0) s += sep;
    s += kDigits[bytes[i] >> 4];
    s += kDigits[bytes[i] & 0xF];
  }
  if (bytes.size() > max) s.append(" ... (").append(std::to_string(bytes.size())).append(" bytes)");
  return s;
}

}  // namespace dpc31
