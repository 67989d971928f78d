// A segment's telegram log (docs/segment.md, "The telegram log"): the telegrams every chip hears
// whole, kept in line order for the chips that take them later, at their next step.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "dpc31/chip.hpp"

namespace dpc31 {

class TelegramLog {
 public:
  // Whom a telegram concerns beside the chips that cannot wait (Chip::may_hear_later false):
  // nobody (its verdict shows nothing in a chip that may hear later), every chip, or the chips
  // at one station address.
  static constexpr int kNobody = -1;
  static constexpr int kEveryone = -2;
  struct Entry {
    std::shared_ptr<const HeardFrame> frame;
    std::uint64_t start = 0;
    std::size_t from = 0;  // the sender (a chip does not hear its own answer)
    // What it does in a chip that heard the entry before it whole (append; the fold,
    // docs/segment.md): the idle bit times before it on the line, whether it counts a no_sync
    // and whether the MAC skips after it.
    std::uint64_t idle = 0;
    bool no_sync = false;
    bool skipping = false;
    // The last entry up to this one that cannot be folded (not linked, or a telegram that concerns
    // every chip), and the last one after TSYN (or kNone); both numbers from first() on.
    std::uint64_t unfolded = 0;
    std::uint64_t synced = 0;
    // The FDL counters from the log's first entry ever up to this one: a started chip, one
    // offline (modulo 2^32: a run's counts are differences).
    FdlCounters started;
    FdlCounters offline;
  };
  static constexpr std::uint64_t kNone = UINT64_MAX;
  // The concern of a telegram heard whole, read as Mac::heard_quiet reads it: a frame whose
  // verdict is not at its last character (the rest as characters), a broadcast and a request
  // with data concern more than the chips that cannot wait.
  [[nodiscard]] static int concerns(const HeardFrame& f);

  // The chips that hear a telegram at once: those that cannot wait (in station order) and those
  // at a request's destination address, kept as the segment looks at its chips.
  void add_chip(std::size_t i) { chips_.push_back(i); }
  // Chip i, the last one added, leaves the segment (Segment::remove_last_chip).
  void remove_chip(std::size_t i, int address) {
    std::erase(chips_, i);
    set_eager(i, false);
    set_address(i, address, -1);
  }
  [[nodiscard]] std::size_t chips() const { return chips_.size(); }
  void set_eager(std::size_t i, bool on) { keep(eager_, i, on); }
  void set_address(std::size_t i, int from, int to);
  // The chips `f` concerns at once, in station order: a copy, valid until the next call.
  [[nodiscard]] const std::vector<std::size_t>& hear_now(const HeardFrame& f);

  // Entries are numbered from 0 on, for good; those before first() are gone.
  [[nodiscard]] std::uint64_t first() const { return first_; }
  [[nodiscard]] std::uint64_t end() const { return first_ + entries_.size(); }
  [[nodiscard]] const Entry& at(std::uint64_t n) const {
    return entries_[static_cast<std::size_t>(n - first_)];
  }
  // A telegram heard whole from `start` (>= the end of the one before) at `t` clocks per bit.
  void append(std::shared_ptr<const HeardFrame> frame, std::uint64_t start, std::size_t from,
              std::uint32_t t);
  // Something reached the chips' receivers without an entry (edges, a damaged telegram, a
  // telegram every chip heard at once): the next entry follows nothing the log knows.
  void line_taken() { line_end_ = kNone; }
  // Every chip took the entries before `n`: the log starts at `n` (its memory kept).
  void forget(std::uint64_t n);
  // The first entry from `n` on that starts after `to` or cannot be folded into a run from `n`.
  [[nodiscard]] std::uint64_t folds_until(std::uint64_t n, std::uint64_t to) const;
  // The entries [n, m) (m > n, each linked and foldable: folds_until) as one run (Chip::hear_run);
  // n > first(): the entry before, which the chip heard one by one, is kept.
  [[nodiscard]] HeardRun run(std::uint64_t n, std::uint64_t m, std::uint32_t t) const;

 private:
  static void keep(std::vector<std::size_t>& list, std::size_t i, bool in);
  std::vector<Entry> entries_;
  std::uint64_t first_ = 0;
  // The line after the last entry: the end of its last stop bit (kNone: unknown), whether the
  // MAC skips after it, the last entry that cannot be folded and the last after TSYN.
  std::uint64_t line_end_ = kNone;
  bool line_skipping_ = false;
  std::uint64_t unfolded_ = kNone;
  std::uint64_t synced_ = kNone;
  std::vector<std::size_t> chips_;
  std::vector<std::size_t> eager_;
  std::vector<std::vector<std::size_t>> at_address_ = std::vector<std::vector<std::size_t>>(256);
  std::vector<std::size_t> hear_now_;
};

}  // namespace dpc31
