// The chip's FDL MAC: the RxD receiver framing characters into telegrams (TSYN before a
// request, errors counted by class), baud-rate search, and the TxD transmitter that sends our
// answer MinTSDR bit times after the request's last stop bit.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "fdl.hpp"
#include "uart.hpp"
#include "watchdog.hpp"

namespace dpc31 {

inline constexpr std::uint32_t kTsynBits = 33;  // idle before a request (synchronisation time)
// Baud_Search listens this many bit times at each rate before trying the next lower one.
inline constexpr std::uint32_t kBaudSearchBits = 4096;
inline constexpr std::uint32_t kMinTsdrBits = 11;

struct Mac {
  UartRx rx;
  fdl::Assembler frame;
  std::vector<UartChar> chars;  // scratch for UartRx::advance
  bool in_frame = false;
  bool skipping = false;    // after a telegram, an error or an unsynchronised start: wait for TSYN
  bool discarding = false;  // the telegram in progress was already counted as broken
  std::uint64_t frame_timeout = kNever;
  std::uint8_t search_code = 0;
  std::uint64_t search_deadline = kNever;
  // Transmitter: TxD edges still to come, and the end of our answer's last stop bit.
  std::vector<std::pair<std::uint64_t, bool>> tx_edges;
  std::size_t tx_next = 0;
  std::uint64_t tx_end = kNever;
  bool txd = true;
  void reset() { *this = Mac{}; }
};

void save_state(snap::Writer& w, const Mac& s);
void load_state(snap::Reader& r, Mac& s);
}  // namespace dpc31
