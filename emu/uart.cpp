// PROFIBUS UART: bit times, the edge-driven receiver and the encoder used by tests and the
// master side of the bench. Sampling rules: docs/timing.md, "Serial line (UART)".
#include "dpc31/uart.hpp"

#include <algorithm>
#include <bit>

#include "snapshot.hpp"

namespace dpc31 {

namespace {

constexpr std::uint32_t kStopBit = 10;
constexpr std::uint64_t kMaxIdleBits = 0xFFFF'FFFF;

// The character both receivers report: `bits` holds sampled bit k at position k.
UartChar make_char(std::uint16_t bits, std::uint64_t start, std::uint32_t t,
                   std::uint64_t idle_bits) {
  UartChar c;
  c.data = static_cast<std::uint8_t>(bits >> 1);
  c.start_ok = (bits & 1) == 0;
  c.parity_ok = (std::popcount(static_cast<unsigned>((bits >> 1) & 0x1FF)) & 1) == 0;
  c.stop_ok = ((bits >> kStopBit) & 1) != 0;
  c.start = start;
  c.end = start + std::uint64_t{kUartCharBits} * t;
  c.idle_bits = idle_bits;
  return c;
}

}  // namespace

std::uint32_t bit_cycles(std::uint32_t clock_hz, std::uint32_t baud) {
  if (baud == 0) return 0;
  // round(clock / baud), halves up, exactly in integers: floor((2 clock + baud) / (2 baud)).
  const std::uint64_t b = baud;
  return static_cast<std::uint32_t>((2 * std::uint64_t{clock_hz} + b) / (2 * b));
}

int baud_code(std::uint32_t baud) {
  for (int i = 0; i < 10; ++i) {
    if (kBaudRates[i] == baud) return i;
  }
  return -1;
}

std::uint8_t even_parity(std::uint8_t data) {
  return static_cast<std::uint8_t>(std::popcount(data) & 1);
}

bool uart_bit(std::uint8_t data, std::uint32_t k) {
  if (k == 0) return false;
  if (k <= 8) return ((data >> (k - 1)) & 1) != 0;
  return k == 9 ? even_parity(data) != 0 : true;
}

std::uint16_t uart_frame(std::uint8_t data) {
  return static_cast<std::uint16_t>(std::uint32_t{data} << 1 |
                                    std::uint32_t{even_parity(data)} << 9 | 1u << kStopBit);
}

// ---- receiver ----

void UartRx::configure(std::uint32_t bit_cycles, std::uint64_t now) {
  t_ = bit_cycles;
  level_ = true;
  not_before_ = now;
  last_rise_ = now;
  k_ = kUartCharBits;
  bits_ = 0;
  idle_bits_ = 0;
  done_.clear();
}

std::uint64_t UartRx::sample_at(std::uint32_t k) const {
  return s_ + std::uint64_t{k} * t_ + t_ / 2;
}

void UartRx::sample_through(std::uint64_t last) {
  // The line has held level_ since the last edge, so every sample up to `last` reads it.
  while (receiving() && sample_at(k_) <= last) {
    if (level_) bits_ = static_cast<std::uint16_t>(bits_ | (1u << k_));
    if (++k_ == kUartCharBits) finish();
  }
}

void UartRx::finish() {
  const UartChar& c = done_.emplace_back(make_char(bits_, s_, t_, idle_bits_));
  // A start is accepted only from the end of this frame on, and only on a real falling edge: a
  // line still low after a bad stop bit (break) must rise and fall again.
  not_before_ = c.end;
}

void UartRx::edge(std::uint64_t cycle, bool level) {
  if (level == level_) return;
  if (cycle > 0) sample_through(cycle - 1);  // samples at `cycle` itself read the new level
  level_ = level;
  if (level) {
    last_rise_ = cycle;
    return;
  }
  if (t_ == 0 || receiving() || cycle < not_before_) return;
  s_ = cycle;
  k_ = 0;
  bits_ = 0;
  // The last edge before a falling one is a rise, so the line was high since max(end, rise).
  const std::uint64_t high_since = std::max(not_before_, last_rise_);
  idle_bits_ = std::min((cycle - high_since) / t_, kMaxIdleBits);
}

bool UartRx::whole_char(std::uint64_t start, std::uint8_t data, std::uint32_t bit_cycles) {
  // Sampling reads a bit's level in its middle: with T >= 2 every sample of the frame lies before
  // the next bit's edge, as below.
  if (bit_cycles != t_ || t_ < 2 || !level_) return false;
  if (start > 0) sample_through(start - 1);  // what the start bit's falling edge does first
  if (receiving() || start < not_before_) return false;
  // The falling edge at `start` begins the character (edge() above).
  s_ = start;
  idle_bits_ = std::min((start - std::max(not_before_, last_rise_)) / t_, kMaxIdleBits);
  // The frame's last edge is the rise that ends its last 0 bit (the stop bit is 1), at bit
  // boundary b; that edge took the samples of bits 0 .. b-1 and left the line high. Samples b ..
  // 10 and finish() come later, from advance() or the next edge, as they would.
  const std::uint16_t frame = uart_frame(data);
  const auto b = static_cast<std::uint32_t>(
      std::bit_width(static_cast<unsigned>(~frame & ((1u << kStopBit) - 1))));
  k_ = b;
  bits_ = static_cast<std::uint16_t>(frame & ((1u << b) - 1));
  last_rise_ = start + std::uint64_t{b} * t_;
  return true;
}

void UartRx::advance(std::uint64_t now, std::vector<UartChar>& out) {
  sample_through(now);
  while (!done_.empty() && done_.front().start + kStopBit * std::uint64_t{t_} + t_ / 2 <= now) {
    out.push_back(done_.front());
    done_.pop_front();
  }
}

std::uint64_t UartRx::next_deadline() const {
  if (!done_.empty()) return done_.front().start + kStopBit * std::uint64_t{t_} + t_ / 2;
  return receiving() ? sample_at(kStopBit) : kIdle;
}

// ---- snapshot ----

// A guard for the one platform the sizes are known on: a new member changes the size (or lands in
// padding, which the snapshot tests' perturbation of a live session catches).
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(UartRx) == 88, "a new member of UartRx: add it to UartRx::fields");
#endif
static_assert(snap::member_count<UartChar>() == 7, "a new member of UartChar: add it below");

template <typename Ar, typename Self>
void UartRx::fields(Ar& ar, Self& s) {
  ar(s.t_);
  ar(s.level_);
  ar(s.not_before_);
  ar(s.last_rise_);
  ar.bounded(s.k_, kUartCharBits);
  ar(s.s_);
  ar(s.bits_);
  ar(s.idle_bits_);
  ar.sequence(s.done_, snap::kMaxFileSize, [](auto& a, auto& c) {
    a(c.data);
    a(c.start_ok);
    a(c.parity_ok);
    a(c.stop_ok);
    a(c.start);
    a(c.end);
    a(c.idle_bits);
  });
}

void UartRx::save_state(snap::Writer& w) const {
  w.section("UART");
  fields(w, *this);
}

void UartRx::load_state(snap::Reader& r) {
  r.section("UART");
  fields(r, *this);
}

// ---- per-clock receiver ----

void UartSampler::configure(std::uint32_t bit_cycles) {
  t_ = bit_cycles;
  level_ = true;
  busy_ = false;
  k_ = kUartCharBits;
  high_for_ = 0;
}

bool UartSampler::detect(bool line, std::uint64_t now) {
  if (line == line_prev_) return false;
  line_prev_ = line;
  if (line == level_) return false;  // a change back to what the receiver assumed (configure)
  level_ = line;
  if (line) {
    high_for_ = 0;
    return false;
  }
  if (busy_ || t_ == 0) return false;
  busy_ = true;
  start_ = now;
  pos_ = 0;
  k_ = 0;
  next_pos_ = t_ / 2;
  bits_ = 0;
  idle_bits_ = std::min(high_for_ / t_, kMaxIdleBits);
  return true;
}

UartSampler::Clock UartSampler::clock(bool line, std::uint64_t now, UartChar& ch) {
  Clock r;
  ++high_for_;
  if (busy_ && ++pos_ == std::uint64_t{kUartCharBits} * t_) {
    busy_ = false;
    high_for_ = 0;
    r.ended = true;
  }
  r.started = detect(line, now);
  // The sample reads the level after this clock's edge.
  if (busy_ && k_ < kUartCharBits && pos_ == next_pos_) {
    if (level_) bits_ = static_cast<std::uint16_t>(bits_ | (1u << k_));
    next_pos_ += t_;
    if (++k_ == kUartCharBits) {
      ch = make_char(bits_, start_, t_, idle_bits_);
      r.ready = true;
    }
  }
  return r;
}

bool UartSampler::late_edge(bool line, std::uint64_t now) { return detect(line, now); }

#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(UartSampler) == 64, "a new member of UartSampler: add it to fields");
#endif

template <typename Ar, typename Self>
void UartSampler::fields(Ar& ar, Self& s) {
  ar(s.t_);
  ar(s.line_prev_);
  ar(s.level_);
  ar(s.busy_);
  ar.bounded(s.k_, kUartCharBits);
  ar(s.pos_);
  ar(s.next_pos_);
  ar(s.bits_);
  ar(s.start_);
  ar(s.high_for_);
  ar(s.idle_bits_);
}

void UartSampler::save_state(snap::Writer& w) const {
  w.section("USMP");
  fields(w, *this);
}

void UartSampler::load_state(snap::Reader& r) {
  r.section("USMP");
  fields(r, *this);
}

// ---- encoder ----

void uart_encode(std::span<const std::uint8_t> bytes, std::uint64_t start, std::uint32_t bit_cycles,
                 std::vector<std::pair<std::uint64_t, bool>>& edges, UartFault fault) {
  const std::uint64_t t = bit_cycles;
  edges.reserve(edges.size() + bytes.size() * kUartCharBits + 1);
  bool line = true;
  auto drive = [&](std::uint64_t cycle, bool level) {
    if (level != line) edges.emplace_back(cycle, level);
    line = level;
  };
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const std::uint8_t d = bytes[i];
    const bool hit = fault.char_index >= 0 && static_cast<std::size_t>(fault.char_index) == i;
    auto faulty = [&](UartFault::Kind k) { return hit && fault.kind == k; };
    const std::uint64_t s = start + i * kUartCharBits * t;
    for (std::uint32_t b = 0; b < kUartCharBits; ++b) {
      using K = UartFault::Kind;
      const K kind = b == 0 ? K::start : b == 9 ? K::parity : b == kStopBit ? K::stop : K::none;
      drive(s + b * t, uart_bit(d, b) != (kind != K::none && faulty(kind)));
    }
  }
  drive(start + bytes.size() * kUartCharBits * t, true);
}

}  // namespace dpc31
