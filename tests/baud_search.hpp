// The Baud_Search windows as docs/timing.md ("Baud_Search") states them, at 48 MHz: 12 Mbaud
// first, then each lower rate, max(4096 bit times, 20 ms = 960 000 cycles) each, T = round(48 MHz
// / baud). Written from the document, not from the model's constants.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "dpc31/uart.hpp"

namespace testutil {

inline constexpr std::uint64_t bit_time_48mhz(std::uint32_t baud) {
  return (48'000'000u + baud / 2) / baud;
}
inline constexpr std::uint64_t baud_search_window(std::uint32_t baud) {
  return std::max<std::uint64_t>(4096 * bit_time_48mhz(baud), 960'000);
}
// From the opening of the 12 Mbaud window (Start) to the opening of the window of `baud`.
inline constexpr std::uint64_t baud_search_opens(std::uint32_t baud) {
  std::uint64_t at = 0;
  for (std::size_t j = 0; j < std::size(dpc31::kBaudRates) && dpc31::kBaudRates[j] != baud; ++j) {
    at += baud_search_window(dpc31::kBaudRates[j]);
  }
  return at;
}
// One round, 5 x 960 000 + 4096 x (256 + 512 + 1056 + 2500 + 5000) cycles (0.896 s).
inline constexpr std::uint64_t kBaudSearchRound = 42'991'104;
static_assert(baud_search_opens(9600) + baud_search_window(9600) == kBaudSearchRound);

}  // namespace testutil
