// PROFIBUS UART: bit times, the edge-driven receiver and the encoder used by tests and the
// master side of the bench. Sampling rules: docs/timing.md, "Serial line (UART)".
#include "uart.hpp"

#include <algorithm>
#include <bit>

namespace dpc31 {

namespace {

constexpr std::uint32_t kStopBit = 10;
constexpr std::uint64_t kMaxIdleBits = 0xFFFF'FFFF;

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
  UartChar c;
  c.data = static_cast<std::uint8_t>(bits_ >> 1);
  c.start_ok = (bits_ & 1) == 0;
  c.parity_ok = (std::popcount(static_cast<unsigned>((bits_ >> 1) & 0x1FF)) & 1) == 0;
  c.stop_ok = ((bits_ >> kStopBit) & 1) != 0;
  c.start = s_;
  c.end = s_ + std::uint64_t{kUartCharBits} * t_;
  c.idle_bits = idle_bits_;
  done_.push_back(c);
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
static_assert(sizeof(UartRx) == 136, "a new member of UartRx: add it to UartRx::fields");
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

// ---- encoder ----

void uart_encode(std::span<const std::uint8_t> bytes, std::uint64_t start, std::uint32_t bit_cycles,
                 std::vector<std::pair<std::uint64_t, bool>>& edges, UartFault fault) {
  const std::uint64_t t = bit_cycles;
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
    drive(s, faulty(UartFault::Kind::start));
    for (std::uint32_t b = 0; b < 8; ++b) drive(s + (1 + b) * t, ((d >> b) & 1) != 0);
    drive(s + 9 * t, (even_parity(d) != 0) != faulty(UartFault::Kind::parity));
    drive(s + kStopBit * t, !faulty(UartFault::Kind::stop));
  }
  drive(start + bytes.size() * kUartCharBits * t, true);
}

}  // namespace dpc31
