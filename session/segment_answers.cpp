// The armed answers on the line at telegram level (docs/segment.md): a chip's answer relayed
// whole from the answer it armed, its edges up to the line's time, and its TxD checked against it.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <span>

#include "segment.hpp"
#include "segment_station.hpp"

namespace dpc31 {

void ArmedAnswer::arm(const Telegram& tel, std::uint32_t bit_cycles) {
  bytes = tel.bytes;
  start = tel.start;
  end = tel.end;
  t = bit_cycles;
  next = 0;
  confirmed = 0;
  part = 0;
  made = false;
  seen_of = kWhole;
  edges.clear();
  last = 0;
  last_fall = 0;
  if (!bytes.empty()) {
    std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
    const std::size_t n =
        uart_char_edges(bytes.back(), start + (bytes.size() - 1) * frame(), t, e.data());
    last = e[n - 1].first;
    last_fall = e[n - 2].first;  // the edges alternate from the start bit's fall: n is even
  }
}

void ArmedAnswer::make() {
  if (made) return;
  uart_encode(bytes, start, t, edges);
  made = true;
  if (next == kWhole) next = edges.size();
  // The edges of the characters seen whole so far, and those seen of the next one.
  const std::uint64_t seen = start + confirmed * frame();
  confirmed = static_cast<std::size_t>(
                  std::partition_point(edges.begin(), edges.end(),
                                       [seen](const auto& x) { return x.first < seen; }) -
                  edges.begin()) +
              part;
  part = 0;
}

void ArmedAnswer::withdraw() {
  if (made) {
    next = confirmed = edges.size();
  } else {
    next = kWhole;
    confirmed = bytes.size();
    part = 0;
  }
}

std::uint64_t ArmedAnswer::next_edge() const {
  if (made) return next < edges.size() ? edges[next].first : UINT64_MAX;
  if (bytes.empty() || next == kWhole) return UINT64_MAX;  // nothing to relay, or all of it
  if (next == 0) return start;                             // its first start bit
  // Its first start bit alone (it found the line taken: a collision): the rest goes edge by
  // edge from the first character's second edge, a round's end like every edge of the line.
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
  uart_char_edges(bytes[0], start, t, e.data());
  return e[1].first;
}

bool ArmedAnswer::behind() const {
  if (made) return confirmed < next;
  return next == 1 ? confirmed == 0 && part == 0 : next == kWhole && confirmed < bytes.size();
}

std::uint64_t ArmedAnswer::first_unconfirmed() const {
  if (made) return edges[confirmed].first;
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
  uart_char_edges(bytes[confirmed], start + confirmed * frame(), t, e.data());
  return e[part].first;
}

bool ArmedAnswer::see(std::pair<std::uint64_t, bool> edge) {
  if (made) {
    if (confirmed >= edges.size() || edges[confirmed] != edge) return false;
    ++confirmed;
    return true;
  }
  if (confirmed >= bytes.size()) return false;
  if (seen_of != confirmed) {
    seen_n = uart_char_edges(bytes[confirmed], start + confirmed * frame(), t, seen.data());
    seen_of = confirmed;
  }
  if (seen[part] != edge) return false;
  if (++part == seen_n) {
    ++confirmed;
    part = 0;
  }
  return true;
}

bool ArmedAnswer::see(std::span<const std::uint8_t> data, std::uint64_t at,
                      std::uint32_t bit_cycles) {
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * bit_cycles;
  const std::uint64_t k = (at - start) / frame;
  if (at < start || start + k * frame != at || k + data.size() > bytes.size() ||
      !std::equal(data.begin(), data.end(), bytes.begin() + static_cast<std::ptrdiff_t>(k))) {
    return false;
  }
  if (!made) {
    // Right after the characters seen: none of the next one seen edge by edge.
    if (k != confirmed || part != 0) return false;
    confirmed = k + data.size();
    return true;
  }
  const auto index_at = [&](std::uint64_t c) {
    return static_cast<std::size_t>(
        std::partition_point(edges.begin(), edges.end(),
                             [c](const auto& x) { return x.first < c; }) -
        edges.begin());
  };
  if (index_at(at) != confirmed) return false;
  confirmed = index_at(at + data.size() * frame);
  return true;
}

bool ArmedAnswer::drives(std::uint64_t from, std::uint64_t to) const {
  if (made) {
    const auto e = std::partition_point(edges.begin(), edges.end(),
                                        [from](const auto& x) { return x.first < from; });
    return e != edges.end() && e->first <= to;
  }
  if (bytes.empty() || from > last || to < start) return false;
  if (from <= start) return true;
  // The first edge at or after `from`: in the character `from` falls in, or the next one's
  // start bit.
  const std::size_t k = (from - start) / frame();
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> e{};
  const std::size_t n = uart_char_edges(bytes[k], start + k * frame(), t, e.data());
  for (std::size_t j = 0; j < n; ++j) {
    if (e[j].first >= from) return e[j].first <= to;
  }
  return start + (k + 1) * frame() <= to;  // k + 1 exists: `from` is not past the last edge
}

bool Segment::relay_answer(std::size_t i, std::uint64_t cycle) {
  Station& a = *stations_[i];
  ArmedAnswer& o = a.out;
  if (reference_ || !a.answer || o.start != cycle || a.chip->bit_cycles() != t_) return false;
  // Decoded once for every other chip (at once or through the log); with none on the line and
  // nothing in the log for it, nobody needs the frame: no entry, as hear_whole makes none.
  if (log_.chips() == 1 && a.taken == log_.end()) {
    log_.line_taken();
  } else {
    hear_whole(i, frames_.make(o.bytes), cycle);
  }
  a.answer = false;
  // The whole answer (relay_armed took its first start bit, this one): the senders hear its
  // characters and the line's decoder takes them now, ahead of time as a sender's telegram; the
  // line is the answer's up to a character time after its last falling edge.
  senders_hear(i, o.bytes, o.start);
  // A start bit a character time after the falling edge before it finds the line free again
  // (relay): a waiting master wakes there (wakes_), as on the reference line. Within the answer
  // that is a character's start bit after one whose only fall is its own start bit.
  wakes_.clear();
  wake_next_ = 0;
  wake_from_ = i;
  for (std::size_t k = 1; k < o.bytes.size(); ++k) {
    // Two edges: the start bit's fall and one rise.
    if (uart_char_edge_count(o.bytes[k - 1]) == 2) wakes_.push_back(o.start + k * o.frame());
  }
  owned_until_ = std::max(owned_until_, o.last_fall + o.frame());
  // The waveform's observer takes its edges (made for it).
  if (on_line) o.make();
  using Span = std::span<const std::pair<std::uint64_t, bool>>;
  decode_chars(i, o.bytes, cycle, o.made ? Span(o.edges).subspan(o.next - 1) : Span{});
  o.next = o.made ? o.edges.size() : ArmedAnswer::kWhole;
  return true;
}
// What the chip drives must be the answer the line relayed: whole characters at their places in
// it, edges one by one. A MAC_Stop (DPC31) or a reset cutting the answer short drives otherwise (or
// stops: look_at); the other chips heard it whole, so that is thrown, never papered over.
void Segment::check_txd(Station& s, const TxdRun& run) {
  if (!s.broken.empty()) return;
  if (!run.bytes.empty()) {
    if (!s.out.see(run.bytes, run.start, run.bit_cycles))
      s.broken = fmt::format("drove characters from cycle {}", run.start);
    return;
  }
  for (const auto& edge : run.edges) {
    if (!s.out.see(edge)) {
      s.broken = fmt::format("drove TxD {} at cycle {}", edge.second ? "high" : "low", edge.first);
      return;
    }
  }
}

// The armed answers' edges up to now_ into round_. An answer whose first start bit finds its chip's
// TxD high was withdrawn before it began (MAC_Stop (DPC31), a reset): it never reaches the line.
void Segment::relay_armed(std::uint64_t before) {
  for (const std::size_t i : armed_) {
    Station& s = *stations_[i];
    ArmedAnswer& o = s.out;
    if (o.next == 0 && !o.bytes.empty() && o.start <= now_ && s.chip->cycle() >= o.start &&
        s.chip->cycle() < o.start + t_ && s.chip->txd_pin()) {
      o.withdraw();
      s.answer = false;
    }
    // Edge by edge where its first start bit was not relayed whole, or where the round reaches
    // past it (the second edge is a bit time later at the earliest).
    if (!o.made && (o.next == 1 || (o.next == 0 && now_ >= o.start + o.t))) o.make();
    if (o.made) {
      for (; o.next < o.edges.size() && o.edges[o.next].first <= now_; ++o.next)
        round_.push_back({o.edges[o.next].first, i, o.edges[o.next].second});
    } else if (o.next == 0 && !o.bytes.empty() && o.start <= now_) {
      round_.push_back({o.start, i, false});  // its first start bit
      o.next = 1;
    }
  }
  // Every later question (others_drive) is about cycles after `before`.
  std::erase_if(armed_, [this, before](std::size_t i) {
    const ArmedAnswer& o = stations_[i]->out;
    return o.all_relayed() && (o.bytes.empty() || o.last <= before);
  });
}

}  // namespace dpc31
