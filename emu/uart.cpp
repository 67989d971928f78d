// PROFIBUS UART: bit times, the edge-driven receiver and the encoder used by tests and the
// master side of the bench. Sampling rules: docs/timing.md, "Serial line (UART)".
#include "dpc31/uart.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <limits>

#include "snapshot.hpp"

namespace dpc31 {

namespace {

constexpr std::uint32_t kStopBit = 10;

// Parity of the low 9 bits by folding (std::popcount is a library call without -mpopcnt).
constexpr unsigned parity9(unsigned v) {
  v ^= v >> 8;
  v ^= v >> 4;
  return (0x6996u >> (v & 0xFu)) & 1u;
}
static_assert(parity9(0x1FF) == 1 && parity9(0x101) == 0 && parity9(0x100) == 1);

// The character both receivers report: `bits` holds sampled bit k at position k.
UartChar make_char(std::uint16_t bits, std::uint64_t start, std::uint32_t t,
                   std::uint64_t idle_bits) {
  UartChar c;
  c.data = static_cast<std::uint8_t>(bits >> 1);
  c.start_ok = (bits & 1) == 0;
  c.parity_ok = parity9((bits >> 1) & 0x1FF) == 0;
  c.stop_ok = ((bits >> kStopBit) & 1) != 0;
  c.start = start;
  c.end = start + std::uint64_t{kUartCharBits} * t;
  c.idle_bits = idle_bits;
  return c;
}

// The bit boundary of a good frame's last rise: after its last 0 bit (the stop bit is 1).
std::uint32_t last_rise_bit(std::uint16_t frame) {
  return static_cast<std::uint32_t>(
      std::bit_width(static_cast<unsigned>(~frame & ((1u << kStopBit) - 1))));
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

std::uint8_t even_parity(std::uint8_t data) { return static_cast<std::uint8_t>(parity9(data)); }

bool uart_bit(std::uint8_t data, std::uint32_t k) { return (uart_frame(data) >> k & 1u) != 0; }

std::uint16_t uart_frame(std::uint8_t data) {
  return static_cast<std::uint16_t>(std::uint32_t{data} << 1 |
                                    std::uint32_t{even_parity(data)} << 9 | 1u << kStopBit);
}

// The bits where the line changes (bit k against bit k - 1, bit 0 against `line`), each set bit
// one edge: a character sent with a fault (uart_encode), or one after a stop bit sent low.
namespace {
template <typename Put>
void frame_changes(std::uint16_t frame, std::uint64_t start, std::uint32_t bit_cycles, bool& line,
                   Put put) {
  constexpr std::uint32_t kMask = (1u << kUartCharBits) - 1;
  const std::uint32_t bits = frame & kMask;
  for (std::uint32_t c = (bits ^ (bits << 1 | (line ? 1u : 0u))) & kMask; c != 0; c &= c - 1) {
    const auto k = static_cast<std::uint32_t>(std::countr_zero(c));
    put(start + std::uint64_t{k} * bit_cycles, (bits >> k & 1u) != 0);
  }
  line = (bits >> kStopBit & 1u) != 0;
}

// The edges of a good character after a high line (a stop bit or the idle line), per data
// byte: how many, and the bit boundary of each. The first is the start bit's fall and they
// alternate, so the last is the rise into the stop bit and the line ends high.
struct CharEdges {
  std::uint8_t n = 0;
  std::array<std::uint8_t, kUartCharBits> bit{};
};
constexpr std::array<CharEdges, 256> kCharEdges = [] {
  std::array<CharEdges, 256> table{};
  constexpr std::uint32_t kMask = (1u << kUartCharBits) - 1;
  for (std::uint32_t d = 0; d < 256; ++d) {
    const std::uint32_t bits = d << 1 | parity9(d) << 9 | 1u << kStopBit;
    for (std::uint32_t c = (bits ^ (bits << 1 | 1u)) & kMask; c != 0; c &= c - 1) {
      table[d].bit[table[d].n++] = static_cast<std::uint8_t>(std::countr_zero(c));
    }
  }
  return table;
}();
static_assert(kCharEdges[0xFF].n == 4 && kCharEdges[0xFF].bit[2] == 9);  // parity 0, stop 1
static_assert(kCharEdges[0x00].n == 2 && kCharEdges[0x00].bit[1] == 10);

template <typename Put>
void char_changes(std::uint8_t data, std::uint64_t start, std::uint32_t bit_cycles, Put put) {
  const CharEdges& e = kCharEdges[data];
  for (std::uint32_t j = 0; j < e.n; ++j) {
    put(start + std::uint64_t{e.bit[j]} * bit_cycles, (j & 1) != 0);
  }
}

}  // namespace

std::size_t uart_char_edges(std::uint8_t data, std::uint64_t start, std::uint32_t bit_cycles,
                            std::pair<std::uint64_t, bool>* out) {
  std::size_t n = 0;
  char_changes(data, start, bit_cycles, [&](std::uint64_t at, bool level) {
    out[n++] = {at, level};
  });
  return n;
}

std::size_t uart_char_edge_count(std::uint8_t data) { return kCharEdges[data].n; }

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
  // The line has held level_ since the last edge, so every sample up to `last` reads it: all of
  // them at once (a character ends at its stop sample, so one frame at most).
  if (!receiving() || sample_at(k_) > last) return;
  const auto m = static_cast<std::uint32_t>(
      std::min<std::uint64_t>(kUartCharBits - k_, (last - sample_at(k_)) / t_ + 1));
  if (level_) bits_ = static_cast<std::uint16_t>(bits_ | ((1u << m) - 1) << k_);
  k_ += m;
  if (k_ == kUartCharBits) finish();
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
  idle_bits_ = std::min((cycle - high_since) / t_, kUartMaxIdleBits);
}

bool UartRx::whole_char(std::uint64_t start, std::uint8_t data, std::uint32_t bit_cycles) {
  // Sampling reads a bit's level in its middle: with T >= 2 every sample of the frame lies before
  // the next bit's edge, as below.
  if (bit_cycles != t_ || t_ < 2 || !level_) return false;
  if (start > 0) sample_through(start - 1);  // what the start bit's falling edge does first
  if (receiving() || start < not_before_) return false;
  // The falling edge at `start` begins the character (edge() above).
  idle_bits_ = idle_bits_at(start);
  begin_whole(start, data);
  return true;
}

void UartRx::begin_whole(std::uint64_t start, std::uint8_t data) {
  // The frame's last edge is the rise that ends its last 0 bit (the stop bit is 1), at bit
  // boundary b; that edge took the samples of bits 0 .. b-1 and left the line high. Samples b ..
  // 10 and finish() come later, from advance() or the next edge, as they would.
  const std::uint16_t frame = uart_frame(data);
  const std::uint32_t b = last_rise_bit(frame);
  s_ = start;
  k_ = b;
  bits_ = static_cast<std::uint16_t>(frame & ((1u << b) - 1));
  last_rise_ = start + std::uint64_t{b} * t_;
}

std::uint64_t UartRx::idle_bits_at(std::uint64_t start) const {
  return std::min((start - std::max(not_before_, last_rise_)) / t_, kUartMaxIdleBits);
}

void UartRx::after_chars(std::uint64_t start, std::uint8_t data, std::uint64_t idle_bits) {
  // whole_char's state with the samples from the last rise on taken (all high: bits b .. 10 of
  // the frame are ones) and the character reported: idle, the next start from its end on.
  const std::uint16_t frame = uart_frame(data);
  s_ = start;
  idle_bits_ = idle_bits;
  bits_ = frame;
  k_ = kUartCharBits;
  level_ = true;
  last_rise_ = start + std::uint64_t{last_rise_bit(frame)} * t_;
  not_before_ = start + std::uint64_t{kUartCharBits} * t_;
}

std::size_t UartRx::whole_run(std::span<const std::pair<std::uint64_t, bool>> e) {
  // A good character's edges fall on its bit boundaries s + kT, alternating from the start bit's
  // fall. The edges that read as one are taken whole: whole_char leaves the state those edges
  // leave, so an edge still to come inside the frame (a later batch) reads as it would.
  if (e.empty() || e[0].second || t_ < 2) return 0;
  const std::uint64_t s = e[0].first;
  // The next edge's cycle is kept at hand (none: the largest cycle): the loop runs per bit, and
  // this is the hottest loop of a master receiving long answers (docs/performance.md, row k).
  constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
  std::uint32_t frame = 0;
  std::uint32_t line = 0;
  std::size_t n = 1;
  std::uint64_t next = e.size() > 1 ? e[1].first : kNone;
  std::uint64_t at = s;
  for (std::uint32_t k = 1; k < kUartCharBits; ++k) {
    at += t_;
    if (next < at) return 0;  // off a bit boundary: not a character's edge
    if (next == at) {
      if (e[n].second == (line != 0)) return 0;
      line ^= 1u;
      next = ++n < e.size() ? e[n].first : kNone;
    }
    frame |= line << k;
  }
  const auto data = static_cast<std::uint8_t>(frame >> 1);
  if (frame != uart_frame(data) || !whole_char(s, data, t_)) return 0;
  return n;
}

std::size_t UartRx::edges(std::span<const std::pair<std::uint64_t, bool>> e) {
  std::size_t whole = 0;
  std::size_t i = 0;
  while (i < e.size()) {
    const std::size_t n = whole_run(e.subspan(i));
    if (n == 0) {
      edge(e[i].first, e[i].second);
      ++i;
    } else {
      i += n;
      ++whole;
    }
  }
  return whole;
}

void UartRx::take(const TxdRun& run) {
  if (!run.edges.empty()) {
    edges(run.edges);
    return;
  }
  const std::uint64_t frame_cycles = std::uint64_t{kUartCharBits} * run.bit_cycles;
  bool whole = false;  // the character before was taken whole
  for (std::size_t i = 0; i < run.bytes.size(); ++i) {
    const std::uint64_t at = run.start + i * frame_cycles;
    if (whole) {
      // What whole_char does at the next start bit right after a character it took: the samples
      // left of that one read the high line (a good frame's bits from its last rise on are
      // ones), so it is finished as the good character it is, and this one begins with no idle
      // bit before it.
      done_.emplace_back(UartChar{run.bytes[i - 1], true, true, true, s_, at, idle_bits_});
      not_before_ = at;
      idle_bits_ = 0;
      begin_whole(at, run.bytes[i]);
      continue;
    }
    whole = whole_char(at, run.bytes[i], run.bit_cycles);
    if (whole) continue;
    // The line is high before a good character (the stop bit of the one before).
    std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
    const std::size_t n = uart_char_edges(run.bytes[i], at, run.bit_cycles, e.data());
    for (std::size_t k = 0; k < n; ++k) edge(e[k].first, e[k].second);
  }
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
  idle_bits_ = std::min(high_for_ / t_, kUartMaxIdleBits);
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
  const std::uint64_t frame_cycles = std::uint64_t{kUartCharBits} * bit_cycles;
  edges.reserve(edges.size() + bytes.size() * kUartCharBits + 1);
  const auto put = [&](std::uint64_t at, bool level) { edges.emplace_back(at, level); };
  bool line = true;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const bool faulty = fault.char_index >= 0 && static_cast<std::size_t>(fault.char_index) == i;
    if (line && !faulty) {  // a good character after a high line: its edges from the table
      char_changes(bytes[i], start + i * frame_cycles, bit_cycles, put);
      continue;
    }
    std::uint16_t frame = uart_frame(bytes[i]);
    if (faulty) {
      // The faulty bit is sent inverted: the start bit (0 -> 1), parity, or the stop bit (1 -> 0).
      using K = UartFault::Kind;
      const std::uint32_t k = fault.kind == K::start    ? 0
                              : fault.kind == K::parity ? 9
                              : fault.kind == K::stop   ? kStopBit
                                                        : kUartCharBits;
      if (k < kUartCharBits) frame = static_cast<std::uint16_t>(frame ^ 1u << k);
    }
    frame_changes(frame, start + i * frame_cycles, bit_cycles, line, put);
  }
  if (!line) put(start + bytes.size() * frame_cycles, true);
}

}  // namespace dpc31
