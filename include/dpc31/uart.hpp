// PROFIBUS serial line (EN 50170 / IEC 61158-3-3 character: start 0, 8 data bits LSB first,
// even parity, stop 1; idle = 1). Time is chip clock cycles. The receiver is fed RxD edges and
// never stepped per cycle, so idle time costs nothing; the rules are in docs/timing.md,
// "Serial line (UART)".
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "dpc31/fifo.hpp"

// Snapshots of the chip's internal state (emu/snapshot.hpp) save and load these through:
namespace dpc31::snap {
class Writer;
class Reader;
}  // namespace dpc31::snap

namespace dpc31 {

// Index = the Status_Reg baud code: 0 = 12 Mbaud ... 9 = 9.6 kbaud.
inline constexpr std::uint32_t kBaudRates[10] = {12000000, 6000000, 3000000, 1500000, 500000,
                                                 187500,   93750,   45450,   19200,   9600};

// Bits per character on the wire (start + 8 data + parity + stop).
inline constexpr std::uint32_t kUartCharBits = 11;
// UartChar::idle_bits counts at most this many idle bit times (a line's log counts as a chip does).
inline constexpr std::uint64_t kUartMaxIdleBits = 0xFFFF'FFFF;
inline constexpr std::uint32_t kTsynBits = 33;  // idle before a request (synchronisation time)

// Clock cycles per bit: clock_hz / baud rounded to the nearest integer, halves up (48 MHz at
// 45.45 kbaud: 1056.1 -> 1056). 0 when baud is 0 or above 2 x clock_hz (the rate is unusable).
[[nodiscard]] std::uint32_t bit_cycles(std::uint32_t clock_hz, std::uint32_t baud);
// Status_Reg baud code of `baud`, -1 if it is not one of kBaudRates.
[[nodiscard]] int baud_code(std::uint32_t baud);
// The parity bit that makes the number of ones in data + parity even.
[[nodiscard]] std::uint8_t even_parity(std::uint8_t data);
// The line level of bit k (0 start, 1..8 data, 9 parity, 10 stop) of character `data`.
[[nodiscard]] bool uart_bit(std::uint8_t data, std::uint32_t k);
// All eleven levels of character `data`: bit k of the result is uart_bit(data, k).
[[nodiscard]] std::uint16_t uart_frame(std::uint8_t data);
// The level changes of the good character `data` (bit k on the line from start + k * bit_cycles)
// on a high line, which it leaves high, written to out[0..n) (n <= 11, returned).
std::size_t uart_char_edges(std::uint8_t data, std::uint64_t start, std::uint32_t bit_cycles,
                            std::pair<std::uint64_t, bool>* out);
// How many edges uart_char_edges gives for `data` (even: they alternate from the start bit's fall).
[[nodiscard]] std::size_t uart_char_edge_count(std::uint8_t data);

struct UartChar {
  std::uint8_t data = 0;
  bool start_ok = false;    // bit 0 sampled as 0
  bool parity_ok = false;   // even parity over data + parity bit
  bool stop_ok = false;     // bit 10 sampled as 1
  std::uint64_t start = 0;  // falling edge that began the start bit
  std::uint64_t end = 0;    // start + 11 T, also for a bad character
  // Whole bit times the line was high between the previous character's end (or configure())
  // and `start`; saturates at 0xFFFF'FFFF. TSYN / idle-time checks read this.
  std::uint64_t idle_bits = 0;
  [[nodiscard]] bool ok() const { return start_ok && parity_ok && stop_ok; }
  bool operator==(const UartChar&) const = default;
};

// A stretch of TxD as the chip's transmitter hands it over (Chip::on_txd_chars): whole good
// characters, `bytes` back to back from `start` at `bit_cycles` per bit (the edges uart_encode
// gives for them), or `edges` in order where only part of a character is on the line yet, where
// the line is cut (Go_Offline) or where the answer is kept as edges (someone watches them).
// Exactly one of `bytes` and `edges` is non-empty.
struct TxdRun {
  std::span<const std::uint8_t> bytes;
  std::uint64_t start = 0;
  std::uint32_t bit_cycles = 0;
  std::span<const std::pair<std::uint64_t, bool>> edges;
};

// Receiver fed with RxD level changes. A character starts at a falling edge (1 -> 0) seen while
// idle, at or after the end of the previous character; bit k (0 start, 1..8 data, 9 parity,
// 10 stop) is sampled at start + k*T + T/2 and reads the level set by the last edge at or before
// that cycle. Once started, the whole 11-bit frame is sampled whatever the line does: a glitch
// (low pulse ending at or before the first sample point) yields one character with
// start_ok = false, and falling edges inside the frame are not starts. No edge history is kept:
// samples are taken as edges arrive, so memory does not grow with idle time.
class UartRx {
 public:
  static constexpr std::uint64_t kIdle = std::numeric_limits<std::uint64_t>::max();

  // Default: unconfigured (T = 0): edges are tracked, no character is ever started.
  UartRx() = default;
  UartRx(std::uint32_t bit_cycles, std::uint64_t now) { configure(bit_cycles, now); }

  // (Re)start at `now` with the line assumed high (idle) since `now`: the character in progress
  // and characters not yet returned by advance() are dropped. bit_cycles = 0 disables reception.
  void configure(std::uint32_t bit_cycles, std::uint64_t now);
  // RxD becomes `level` at `cycle`. Cycles are non-decreasing, and an edge at c must be fed
  // before advance(c) (a sample already taken is not revised). An edge to the level the line
  // already has is ignored.
  void edge(std::uint64_t cycle, bool level);
  // One whole character on the line from `start` at `bit_cycles` per bit: the edges uart_encode
  // gives for `data` with no fault, taken in one step. The receiver is left exactly as those
  // edges, fed one by one, would leave it. False, and nothing received, when that cannot be done
  // so: another bit time (the baud search listens elsewhere), a line that is low, or a character
  // still in progress at `start`; the caller then feeds the edges (Mac::drive_rxd_char).
  bool whole_char(std::uint64_t start, std::uint8_t data, std::uint32_t bit_cycles);
  // Whether characters from `start` at `bit_cycles` per bit reach this receiver with nothing of
  // its own before them still to sample or report: the rate it listens at, the line high, no
  // character in progress or waiting for advance() (a telegram heard whole, Mac::hear_telegram).
  [[nodiscard]] bool idle_for(std::uint64_t start, std::uint32_t bit_cycles) const {
    return bit_cycles == t_ && t_ >= 2 && level_ && !receiving() && done_.empty() &&
           start >= not_before_;
  }
  // UartChar::idle_bits of a character whose start bit falls at `start` (>= the last edge).
  [[nodiscard]] std::uint64_t idle_bits_at(std::uint64_t start) const;
  // The state good back-to-back characters leave once advance() has reported them all, the last
  // one `data` from `start` with `idle_bits` before it: what whole_char and advance() would leave.
  void after_chars(std::uint64_t start, std::uint8_t data, std::uint64_t idle_bits);
  // Edges in order, after those given before (Chip::on_txd_edges): the same as edge() for each,
  // but a run that reads as one good character at this receiver's bit time is taken whole
  // (whole_char). Returns the number of characters taken whole.
  std::size_t edges(std::span<const std::pair<std::uint64_t, bool>> e);
  // A run of TxD (Chip::on_txd_chars): the same as edges() with the run's edges, its characters
  // taken whole where whole_char can, else edge by edge.
  void take(const TxdRun& run);
  // Appends, in order, every character whose stop sample is at or before `now`. Edges may have
  // been fed beyond `now`; such characters wait for a later advance().
  void advance(std::uint64_t now, std::vector<UartChar>& out);
  // Stop-sample cycle of the earliest character not yet returned by advance(), kIdle if none:
  // the engine may jump straight to it.
  [[nodiscard]] std::uint64_t next_deadline() const;

  [[nodiscard]] std::uint32_t bit_time() const { return t_; }  // T in clocks
  [[nodiscard]] bool level() const { return level_; }
  [[nodiscard]] bool receiving() const { return k_ < kUartCharBits; }
  // Start of the earliest character not yet returned by advance(), kIdle if none.
  [[nodiscard]] std::uint64_t busy_from() const {
    if (!done_.empty()) return done_.front().start;
    return receiving() ? s_ : kIdle;
  }

  // Snapshots (emu/snapshot.hpp): every member, so also the edges driven ahead of time (they are
  // already sampled into the character in progress and the finished characters in done_).
  void save_state(snap::Writer& w) const;
  void load_state(snap::Reader& r);

 private:
  template <typename Ar, typename Self>
  static void fields(Ar& ar, Self& s);
  [[nodiscard]] std::uint64_t sample_at(std::uint32_t k) const;
  // whole_char's state from the start bit of `data` at `start` on (idle_bits_ set before).
  void begin_whole(std::uint64_t start, std::uint8_t data);
  // Takes the samples of the character in progress that fall at or before `last`.
  void sample_through(std::uint64_t last);
  void finish();
  // edges(): how many edges at the front of `e` are one good character taken whole (0: none).
  std::size_t whole_run(std::span<const std::pair<std::uint64_t, bool>> e);

  std::uint32_t t_ = 0;           // clock cycles per bit
  bool level_ = true;             // current RxD level
  std::uint64_t not_before_ = 0;  // end of the previous character: earliest accepted start
  std::uint64_t last_rise_ = 0;   // the line is high from here (or from not_before_) when idle
  // Character in progress: k_ = next bit to sample, kUartCharBits when idle.
  std::uint32_t k_ = kUartCharBits;
  std::uint64_t s_ = 0;
  std::uint16_t bits_ = 0;       // sampled bit k at bit position k
  std::uint64_t idle_bits_ = 0;  // of the character in progress
  Fifo<UartChar> done_;          // complete, waiting for advance() to reach their stop sample
};

// The receiver of the per-cycle engine (docs/engine.md): the rules of UartRx, evaluated the way
// hardware does it. Every clock it looks at RxD; a change of the line towards a level the
// receiver does not hold is an edge; a falling edge while idle starts a bit counter, and each bit
// is sampled when the counter reaches it. Nothing here is computed ahead of time.
class UartSampler {
 public:
  // At the current clock: idle, the line assumed high from now on (as UartRx::configure).
  void configure(std::uint32_t bit_cycles);
  struct Clock {
    bool ready = false;    // `ch` holds a character: this clock was its stop sample
    bool ended = false;    // this clock ended a frame (the end of its stop bit)
    bool started = false;  // a start bit began at this clock
  };
  // One clock at cycle `now`; `line` is RxD after the edges of this clock.
  Clock clock(bool line, std::uint64_t now, UartChar& ch);
  // An edge driven for the clock already evaluated (Chip::drive_rxd at the current cycle).
  bool late_edge(bool line, std::uint64_t now);
  [[nodiscard]] bool busy() const { return busy_; }
  [[nodiscard]] std::uint32_t bit_time() const { return t_; }  // T in clocks

  void save_state(snap::Writer& w) const;
  void load_state(snap::Reader& r);

 private:
  template <typename Ar, typename Self>
  static void fields(Ar& ar, Self& s);
  bool detect(bool line, std::uint64_t now);

  std::uint32_t t_ = 0;
  bool line_prev_ = true;            // RxD at the previous clock: the edge detector
  bool level_ = true;                // the level the receiver holds (set high by configure)
  bool busy_ = false;                // from the start edge to the end of the stop bit
  std::uint32_t k_ = kUartCharBits;  // next bit to sample
  std::uint64_t pos_ = 0;            // clocks since the start edge
  std::uint64_t next_pos_ = 0;       // pos_ of the next sample
  std::uint16_t bits_ = 0;
  std::uint64_t start_ = 0;
  std::uint64_t high_for_ = 0;  // clocks the line has been high since the last rise / frame end
  std::uint64_t idle_bits_ = 0;
};

// Fault injection for uart_encode: char `char_index` gets its parity bit inverted, its start bit
// sent as 1 (no falling edge: the line stays high for bit 0), or its stop bit sent as 0.
struct UartFault {
  int char_index = -1;
  enum class Kind { none, parity, start, stop } kind = Kind::none;
};

// Appends the TxD level changes (cycle, level) for back-to-back characters: char i starts at
// start + 11*T*i. The line is 1 before `start` and returns to 1 after the last stop bit; only real
// changes are listed (the final rise is included when the line is low before it).
void uart_encode(std::span<const std::uint8_t> bytes, std::uint64_t start, std::uint32_t bit_cycles,
                 std::vector<std::pair<std::uint64_t, bool>>& edges, UartFault fault = {});

}  // namespace dpc31
