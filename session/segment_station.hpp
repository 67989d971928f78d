// The segment's stations as its sources see them (session/segment.cpp, segment_answers.cpp):
// private to the segment.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "segment.hpp"

namespace dpc31 {

// What a sender hears of the line, in cycle order: an edge, or good characters whole, `count` of
// them back to back from `at` (the first one's start bit), their bytes from `first` in the
// station's `heard_bytes`. No entry lies inside such a run. A master's receiver takes the
// characters whole (Segment::take_line).
struct Heard {
  std::uint64_t at = 0;
  bool whole = false;  // characters; else an edge to `level`
  bool level = false;
  std::size_t count = 0;
  std::size_t first = 0;
};

// The answer a chip armed (Chip::on_answer): its characters from `start`, what the line relayed
// of it (before `next`) and what the chip's TxD was seen to drive of it (before `confirmed`).
// Its TxD edges are made only where something takes them one by one (make()): an answer relayed
// whole at its first start bit and driven as whole characters, the common case, needs none.
// Until made, `next` is 0 (nothing relayed), 1 (its first start bit handed to a round) or kWhole,
// and `confirmed` counts whole characters seen, `part` the edges seen of the next one; once made,
// `next` and `confirmed` index `edges`.
struct ArmedAnswer {
  static constexpr std::size_t kWhole = SIZE_MAX;
  std::vector<std::uint8_t> bytes;
  std::uint64_t start = 0;
  std::uint64_t end = 0;
  std::uint32_t t = 0;
  std::uint64_t last = 0;       // its last edge (the rise into the last stop bit)
  std::uint64_t last_fall = 0;  // its last falling edge
  std::size_t next = 0;
  std::size_t confirmed = 0;
  std::size_t part = 0;
  bool made = false;
  std::vector<std::pair<std::uint64_t, bool>> edges;
  // Not made: the edges of character `seen_of` (the one see() checks edge by edge, most of them
  // one or two at a time while a firmware steps its chip), made once for all of them.
  std::array<std::pair<std::uint64_t, bool>, kUartCharBits> seen{};
  std::size_t seen_n = 0;
  std::size_t seen_of = kWhole;

  void arm(const Telegram& tel, std::uint32_t bit_cycles);
  // Its edges one by one from here on.
  void make();
  [[nodiscard]] std::uint64_t frame() const { return std::uint64_t{kUartCharBits} * t; }
  [[nodiscard]] bool all_relayed() const { return made ? next == edges.size() : next == kWhole; }
  // Withdrawn before it began: nothing left to relay, nothing to see.
  void withdraw();
  // The next edge the line has not relayed (UINT64_MAX: none).
  [[nodiscard]] std::uint64_t next_edge() const;
  // Whether the line relayed an edge its TxD has not driven yet, and the first such edge.
  [[nodiscard]] bool behind() const;
  [[nodiscard]] std::uint64_t first_unconfirmed() const;
  // Whether it drives an edge anywhere in [from, to].
  [[nodiscard]] bool drives(std::uint64_t from, std::uint64_t to) const;
  // Checks TxD's next edge against it; false where it differs.
  bool see(std::pair<std::uint64_t, bool> edge);
  // Whole characters `data` from `at` on TxD: false where they are not its next ones.
  bool see(std::span<const std::uint8_t> data, std::uint64_t at, std::uint32_t bit_cycles);
};

struct Segment::Station {
  std::size_t index = 0;
  std::string name;
  std::unique_ptr<Chip> chip;  // null: a sender
  std::unique_ptr<Cpu> cpu;
  Edges txd;  // the reference line: the chip's TxD edges not yet relayed (Chip::on_txd)
  std::vector<Heard> heard;               // a sender's: the line as it hears it, not yet taken
  std::vector<std::uint8_t> heard_bytes;  // the bytes of its runs of characters
  std::uint64_t colliding_until = 0;      // a collision of this station is reported once per burst
  // Telegram level (docs/segment.md): the chip's next event and whether its firmware runs, as the
  // rounds last looked; whether the answer it armed (Chip::on_answer: `out`)
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
  // Its last armed answer (both line modes): what a firmware running past a round's end must not
  // cross; at telegram level also what the line relays and what its TxD is checked against.
  ArmedAnswer out;
  std::string broken;  // its TxD left the armed answer (cut short): thrown by look_at
};

}  // namespace dpc31
