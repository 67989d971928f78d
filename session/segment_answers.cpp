// The armed answers on the line at telegram level (docs/segment.md): a chip's answer relayed
// whole from the answer it armed, its edges up to the line's time, and its TxD checked against it.
#include <fmt/format.h>

#include <algorithm>
#include <span>

#include "segment.hpp"
#include "segment_station.hpp"

namespace dpc31 {

bool Segment::relay_answer(std::size_t i, std::uint64_t cycle) {
  Station& a = *stations_[i];
  if (reference_ || !a.answer || a.out_start != cycle || a.chip->bit_cycles() != t_) return false;
  // Decoded once for every other chip (at once or through the log); with none on the line and
  // nothing in the log for it, nobody needs the frame: no entry, as hear_whole makes none.
  if (log_.chips() == 1 && a.taken == log_.end()) {
    log_.line_taken();
  } else {
    hear_whole(i, frames_.make(a.out_bytes), cycle);
  }
  a.answer = false;
  // Its edges from this one on (relay_armed took it; this one is its first start bit, so they
  // are the whole answer): the senders hear its characters and the line's decoder takes them
  // now, ahead of time as a sender's telegram; the line is the answer's up to a character time
  // after its last falling edge.
  const auto rest = std::span(a.drives_edges).subspan(a.out_next - 1);
  senders_hear(i, a.out_bytes, a.out_start);
  // A start bit a character time after the falling edge before it finds the line free again
  // (relay): a waiting master wakes there (wakes_), as on the reference line.
  wakes_.clear();
  wake_next_ = 0;
  wake_from_ = i;
  const std::uint64_t frame = std::uint64_t{kUartCharBits} * t_;
  for (const auto& [at, level] : rest) {
    if (level) continue;
    if (at >= owned_until_) wakes_.push_back(at);
    owned_until_ = std::max(owned_until_, at + frame);
  }
  decode_chars(i, a.out_bytes, cycle, rest);
  a.out_next = a.drives_edges.size();
  return true;
}

// What the chip drives must be the answer the line relayed: whole characters at their places in
// it, edges one by one. A Go_Offline or a reset cutting the answer short drives otherwise (or
// stops: look_at); the other chips heard it whole, so that is thrown, never papered over.
void Segment::check_txd(Station& s, const TxdRun& run) {
  if (!s.broken.empty()) return;
  const Edges& e = s.drives_edges;
  const auto index_at = [&](std::uint64_t c) {
    return static_cast<std::size_t>(
        std::partition_point(e.begin(), e.end(), [c](const auto& x) { return x.first < c; }) -
        e.begin());
  };
  if (!run.bytes.empty()) {
    const std::uint64_t frame = std::uint64_t{kUartCharBits} * run.bit_cycles;
    const std::uint64_t k = (run.start - s.out_start) / frame;
    if (run.start >= s.out_start && s.out_start + k * frame == run.start &&
        k + run.bytes.size() <= s.out_bytes.size() &&
        std::equal(run.bytes.begin(), run.bytes.end(),
                   s.out_bytes.begin() + static_cast<std::ptrdiff_t>(k)) &&
        index_at(run.start) == s.confirmed) {
      s.confirmed = index_at(run.start + run.bytes.size() * frame);
      return;
    }
    s.broken = fmt::format("drove characters from cycle {}", run.start);
    return;
  }
  for (const auto& edge : run.edges) {
    if (s.confirmed >= e.size() || e[s.confirmed] != edge) {
      s.broken = fmt::format("drove TxD {} at cycle {}", edge.second ? "high" : "low", edge.first);
      return;
    }
    ++s.confirmed;
  }
}

// The armed answers' edges up to now_ into round_. An answer whose first start bit finds its chip's
// TxD high was withdrawn before it began (Go_Offline, a reset): it never reaches the line.
void Segment::relay_armed(std::uint64_t before) {
  for (const std::size_t i : armed_) {
    Station& s = *stations_[i];
    const Edges& e = s.drives_edges;
    if (s.out_next == 0 && !e.empty() && e[0].first <= now_ && s.chip->cycle() >= e[0].first &&
        s.chip->cycle() < e[0].first + t_ && s.chip->txd_pin()) {
      s.out_next = s.confirmed = e.size();
      s.answer = false;
    }
    for (; s.out_next < e.size() && e[s.out_next].first <= now_; ++s.out_next)
      round_.push_back({e[s.out_next].first, i, e[s.out_next].second});
  }
  // Every later question (others_drive) is about cycles after `before`.
  std::erase_if(armed_, [this, before](std::size_t i) {
    const Station& s = *stations_[i];
    return s.out_next == s.drives_edges.size() &&
           (s.drives_edges.empty() || s.drives_edges.back().first <= before);
  });
}

}  // namespace dpc31
