// The chip's FDL MAC: the RxD receiver framing characters into telegrams (TSYN before a
// request, errors counted by class), baud-rate search, and the TxD transmitter that sends our
// answer MinTSDR bit times after the request's last stop bit.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "dpc31/fdl.hpp"
#include "dpc31/uart.hpp"
#include "watchdog.hpp"

namespace dpc31 {

inline constexpr std::uint32_t kTsynBits = 33;  // idle before a request (synchronisation time)
// Baud_Search listens this many bit times at each rate before trying the next lower one.
inline constexpr std::uint32_t kBaudSearchBits = 4096;
inline constexpr std::uint32_t kMinTsdrBits = 11;

// Per-cycle engine: counts whole bit times of `t` clocks, one tick per clock.
struct BitTimer {
  bool on = false;
  std::uint32_t sub = 0;   // clocks into the current bit time
  std::uint32_t bits = 0;  // whole bit times counted
  std::uint32_t target = 0;
  void start(std::uint32_t n) { *this = BitTimer{true, 0, 0, n}; }
  // One clock; true on the clock that completes `target` bit times (the timer then stops).
  bool tick(std::uint32_t t) {
    if (!on || ++sub < t) return false;
    sub = 0;
    if (++bits < target) return false;
    on = false;
    return true;
  }
};

// Per-cycle engine: the transmitter shifting our answer out bit by bit.
struct TxShifter {
  // wait_end: the rest of the request's stop bit; tsdr: MinTSDR bit times; shifting: on the line.
  enum class Phase : std::uint8_t { idle, wait_end, tsdr, shifting };
  Phase phase = Phase::idle;
  std::vector<std::uint8_t> bytes;
  std::uint32_t tsdr_bits = 0;
  BitTimer timer;
  std::size_t index = 0;  // character on the line
  std::uint32_t bit = 0;  // bit of that character
  std::uint32_t sub = 0;  // clocks into that bit
};

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
  // Per-cycle engine (docs/engine.md): its own receiver and counters; never the deadlines above.
  UartSampler sampler;
  BitTimer gap;     // idle inside a telegram, from the end of a character (TSYN ends it)
  BitTimer search;  // the Baud_Search window at the current rate
  TxShifter shifter;
  void reset() { *this = Mac{}; }
};

void save_state(snap::Writer& w, const Mac& s);
void load_state(snap::Reader& r, Mac& s);
}  // namespace dpc31
