// The one check of every numeric command-line option (docs/bad-input.md): a CLI11 validator,
// run on the text before CLI11 converts it. It refuses what is not a number written whole,
// NaN and the infinities, values outside the option's range, and values that do not fit its
// type (2^64 for a 64-bit count, "-1" for an unsigned one, which CLI11 would take as 2^64 - 1).
// whole() hands CLI11 the value in plain decimal, so give it with ->transform(), not ->check():
// CLI11 reads "010" as octal eight.
#pragma once

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
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
