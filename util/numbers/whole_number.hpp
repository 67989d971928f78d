// The one reading of a whole number at every door (docs/security.md, "Numbers"): the CLI's
// options, a bridge's --slave fields, a PROFIBUS rate. Decimal digits, or hex digits after 0x
// or 0X; a leading zero is decimal ("010" is ten, never octal as strtoull reads it); no sign,
// no exponent, no other base. Scenarios and the serve protocol read numbers the same way.
#pragma once

#include <charconv>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace dpc31::numbers {

// std::errc{} and v, result_out_of_range beyond 64 bits, invalid_argument for other text.
inline std::errc parse_whole(std::string_view s, std::uint64_t& v) {
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;
    s.remove_prefix(2);
  }
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (ec == std::errc::result_out_of_range) return ec;
  return s.empty() || ec != std::errc{} || p != s.data() + s.size() ? std::errc::invalid_argument
                                                                    : std::errc{};
}

}  // namespace dpc31::numbers
