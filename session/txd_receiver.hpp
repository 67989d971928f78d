// A receiver on TxD that takes runs of whole characters as blocks (docs/engine.md, "The answer
// kept as characters"): the built-in master's and the bridge's, and a segment's line decoder.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "dpc31/uart.hpp"

namespace dpc31 {

// A master's receiver on TxD (Chip::on_txd_chars), the UART receiver's rules kept: a run of whole
// characters that finds the receiver with nothing of its own (UartRx::idle_for, once the samples
// before its first start bit are taken) is kept as it comes, and advance() hands its characters
// over whole once their stop samples are due, with no queue of UartChar and no step per
// character. Anything after a kept run (edges: a character only partly on the line, an answer
// cut by MAC_Stop (DPC31) or a reset, an answer made of edges for a waveform; a run after a gap)
// turns the run into UartChar (all its stop samples are past) and goes through the receiver
// (UartRx::take).
// A run handed ahead of time (a segment's line: a telegram whole at its first start bit) keeps
// the characters advance() has not reached; what comes after them then gives those to the
// receiver as they are (UartRx::take), as if advance() had. Everything taken lies at or before
// the `now` of the next advance(), but a run's characters. Used by DpMaster, the bridge
// (lib/bridge) and a segment's line decoder (Segment::close_telegrams).
class TxdReceiver {
 public:
  TxdReceiver(std::uint32_t bit_cycles, std::uint64_t now) : rx_(bit_cycles, now) {}
  void take(const TxdRun& r);
  // One edge (UartRx::edge).
  void edge(std::uint64_t cycle, bool level);
  // Every character whose stop sample is at or before `now`, in order: those the receiver decoded
  // appended to `out`, then due()'s whole ones.
  void advance(std::uint64_t now, std::vector<UartChar>& out);
  // The good characters of the last advance() after `out`'s, back to back from due_start().
  [[nodiscard]] std::span<const std::uint8_t> due() const { return due_; }
  [[nodiscard]] std::uint64_t due_start() const { return due_start_; }
  // due() as the UartChar the receiver would have reported, appended to `out`.
  void due_chars(std::vector<UartChar>& out) const;
  // Valid after advance(): a kept run is then the characters it has not reached.
  [[nodiscard]] bool receiving() const { return rx_.receiving() || !run_.empty(); }
  // UartRx::next_deadline, the characters kept counted.
  [[nodiscard]] std::uint64_t next_deadline() const {
    if (!early_.empty()) return stop_sample(early_.front().start);
    return run_.empty() ? rx_.next_deadline() : stop_sample(run_start_);
  }
  // UartRx::busy_from, the characters kept counted (rx_ is idle under a kept run).
  [[nodiscard]] std::uint64_t busy_from() const {
    if (!early_.empty()) return early_.front().start;
    return run_.empty() ? rx_.busy_from() : run_start_;
  }

 private:
  [[nodiscard]] std::uint64_t frame_cycles() const {
    return std::uint64_t{kUartCharBits} * rx_.bit_time();
  }
  // The stop sample of a character from `start`.
  [[nodiscard]] std::uint64_t stop_sample(std::uint64_t start) const {
    return start + (kUartCharBits - 1) * std::uint64_t{rx_.bit_time()} + rx_.bit_time() / 2;
  }

  // The kept run's characters as UartChar, now that something after them came (the receiver is
  // set as they leave it), and those the receiver ended before a run: reported first.
  void settle();

  UartRx rx_;
  std::vector<UartChar> early_;  // ended before what was taken since: due at the next advance()
  // Whole characters not yet given to rx_, which is as it was at run_start_.
  std::vector<std::uint8_t> run_;
  std::uint64_t run_start_ = 0;
  bool rest_ = false;  // run_ is what advance() left of a run: its stop samples are not past
  std::vector<std::uint8_t> due_;
  std::uint64_t due_start_ = 0;
  std::uint64_t due_idle_bits_ = 0;  // UartChar::idle_bits of due_'s first character
};

}  // namespace dpc31
