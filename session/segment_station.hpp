// The segment's stations as its sources see them (session/segment.cpp, segment_answers.cpp):
// private to the segment.
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "segment.hpp"

namespace dpc31 {

// What a sender hears of the line, in cycle order: an edge, or a good character whole (`at` its
// start bit). A master's receiver takes the characters whole (Segment::take_line).
struct Heard {
  std::uint64_t at = 0;
  bool whole = false;  // a character: `data`; else an edge to `level`
  bool level = false;
  std::uint8_t data = 0;
};

struct Segment::Station {
  std::size_t index = 0;
  std::string name;
  std::unique_ptr<Chip> chip;  // null: a sender
  std::unique_ptr<Cpu> cpu;
  Edges txd;  // the reference line: the chip's TxD edges not yet relayed (Chip::on_txd)
  std::vector<Heard> heard;           // a sender's: the line as it hears it, not yet taken
  std::uint64_t colliding_until = 0;  // a collision of this station is reported once per burst
  // Telegram level (docs/segment.md): the chip's next event and whether its firmware runs, as the
  // rounds last looked; whether the answer it armed (Chip::on_answer: out_bytes from out_start)
  // is still to be given to the other chips whole at its first start bit.
  bool busy = false;
  std::uint64_t looked = UINT64_MAX;  // the chip's cycle when the rounds last looked
  // Its cycle as Chip::on_cycle last told, and whether catch_up is to look at it (moved_).
  std::uint64_t known = 0;
  bool moved = false;
  // The telegram log: the next entry it takes; whether it hears every telegram at once (eager_),
  // and its station address as last looked (at_address_; -1: none yet).
  std::uint64_t taken = 0;
  std::deque<std::uint64_t> own;  // the entries of its own answers from `taken` on (not heard)
  bool eager = false;
  int address = -1;
  bool answer = false;
  // The TxD edges of its last armed answer (both line modes): what a firmware running past a
  // round's end must not cross; at telegram level also what the line relays (from out_next on:
  // not yet) and what its TxD is checked against (from confirmed on: not yet seen), its bytes and
  // end.
  Edges drives_edges;
  std::size_t out_next = 0;
  std::size_t confirmed = 0;
  std::vector<std::uint8_t> out_bytes;
  std::uint64_t out_start = 0;
  std::uint64_t out_end = 0;
  std::string broken;  // its TxD left the armed answer (cut short): thrown by look_at
  [[nodiscard]] bool drives(std::uint64_t from, std::uint64_t to) const {
    const auto e = std::lower_bound(
        drives_edges.begin(), drives_edges.end(), from,
        [](const std::pair<std::uint64_t, bool>& x, std::uint64_t c) { return x.first < c; });
    return e != drives_edges.end() && e->first <= to;
  }
};

}  // namespace dpc31
