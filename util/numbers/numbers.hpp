// The one check of every numeric command-line option (docs/bad-input.md): a CLI11 validator,
// run on the text before CLI11 converts it. It refuses what is not a number written whole,
// NaN and the infinities, values outside the option's range, and values that do not fit its
// type (2^64 for a 64-bit count, "-1" for an unsigned one, which CLI11 would take as 2^64 - 1).
// whole() hands CLI11 the value in plain decimal, so give it with ->transform(), not ->check():
// CLI11 reads "010" as octal eight.
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>

#include "whole_number.hpp"

namespace dpc31::numbers {

// A whole number lo..hi as parse_whole reads it ("12", "012", "0xC"; not "1e3", "+5" or "-1").
inline CLI::Validator whole(std::uint64_t lo,
                            std::uint64_t hi = std::numeric_limits<std::uint64_t>::max()) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        std::uint64_t v = 0;
        const std::errc ec = parse_whole(s, v);
        const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
        if (ec == std::errc::result_out_of_range) return "'" + s + "' is outside " + range;
        if (ec != std::errc{}) return "'" + s + "' is not a whole number (decimal or 0x hex)";
        if (v < lo || v > hi) return "'" + s + "' is outside " + range;
        s = std::to_string(v);
        return {};
      },
      "UINT in " + std::to_string(lo) + ".." + std::to_string(hi), "whole");
}

// A count lo..hi (hi at most 10^18) in decimal, whole or with an exponent ("2000000", "1e9",
// "2.5e6"), handed to CLI11 in plain decimal; a value with a fraction ("1000000.7", "1e-1") is
// refused, never cut to a whole one. Read digit by digit: a double rounds a fraction away
// beyond 2^53.
inline CLI::Validator count(std::uint64_t lo, std::uint64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
        std::string_view t = s;
        std::string digits;      // the mantissa's digits without the point
        std::int64_t point = 0;  // digits after the point
        bool seen_point = false;
        while (!t.empty() && ((t[0] >= '0' && t[0] <= '9') || (t[0] == '.' && !seen_point))) {
          if (t[0] == '.') {
            seen_point = true;
          } else {
            digits += t[0];
            point += seen_point ? 1 : 0;
          }
          t.remove_prefix(1);
        }
        std::int64_t exponent = 0;
        bool exponent_ok = true;
        if (!t.empty() && (t[0] == 'e' || t[0] == 'E')) {
          t.remove_prefix(1);
          const bool negative = !t.empty() && t[0] == '-';
          if (!t.empty() && (t[0] == '-' || t[0] == '+')) t.remove_prefix(1);
          exponent_ok = !t.empty();
          for (; !t.empty() && t[0] >= '0' && t[0] <= '9'; t.remove_prefix(1)) {
            // Past 1000 the count is 0 or beyond any hi either way.
            exponent = std::min<std::int64_t>(exponent * 10 + (t[0] - '0'), 1000);
          }
          if (negative) exponent = -exponent;
        }
        if (digits.empty() || !t.empty() || !exponent_ok) return "'" + s + "' is not a number";
        // The digits left of the point after the exponent shifted it; those right of it must be 0.
        const std::int64_t whole_digits =
            static_cast<std::int64_t>(digits.size()) - point + exponent;
        std::uint64_t v = 0;
        for (std::int64_t i = 0; i < static_cast<std::int64_t>(digits.size()); ++i) {
          const int d = digits[static_cast<std::size_t>(i)] - '0';
          if (i >= whole_digits) {
            if (d != 0) return "'" + s + "' is not a whole number";
          } else if (v != 0 || d != 0) {
            if (v > hi / 10 || v * 10 + static_cast<std::uint64_t>(d) > hi)
              return "'" + s + "' is outside " + range;
            v = v * 10 + static_cast<std::uint64_t>(d);
          }
        }
        for (std::int64_t i = static_cast<std::int64_t>(digits.size()); i < whole_digits && v != 0;
             ++i) {
          if (v > hi / 10) return "'" + s + "' is outside " + range;
          v *= 10;
        }
        if (v < lo) return "'" + s + "' is outside " + range;
        s = std::to_string(v);
        return {};
      },
      "COUNT in " + std::to_string(lo) + ".." + std::to_string(hi), "count");
}

// A finite real number lo..hi ("0.5", "1e9"; not "nan", "inf", "1e400" or "0.5s").
inline CLI::Validator real(double lo, double hi) {
  const auto shown = [](double d) {
    std::string t(32, '\0');
    t.resize(
        static_cast<std::size_t>(std::to_chars(t.data(), t.data() + t.size(), d).ptr - t.data()));
    return t;
  };
  return CLI::Validator(
      [lo, hi, shown](std::string& s) -> std::string {
        double v = 0;
        const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
        if (r.ec == std::errc::result_out_of_range) return "'" + s + "' is out of range";
        if (r.ec != std::errc{} || r.ptr != s.data() + s.size())
          return "'" + s + "' is not a number";
        if (!std::isfinite(v)) return "'" + s + "' is not a finite number";
        if (v < lo || v > hi) return "'" + s + "' is outside " + shown(lo) + ".." + shown(hi);
        return {};
      },
      "NUMBER in " + shown(lo) + ".." + shown(hi), "real");
}

}  // namespace dpc31::numbers
