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
  };
  // The concern of a telegram heard whole, read as Mac::heard_quiet reads it: a frame whose
  // verdict is not at its last character (the rest as characters), a broadcast and a request
  // with data concern more than the chips that cannot wait.
  [[nodiscard]] static int concerns(const HeardFrame& f);

  // The chips that hear a telegram at once: those that cannot wait (in station order) and those
  // at a request's destination address, kept as the segment looks at its chips.
  void add_chip(std::size_t i) { chips_.push_back(i); }
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
  void append(Entry e) { entries_.push_back(std::move(e)); }
  // Every chip took every entry: the log starts empty at end() (its memory kept).
  void clear() {
    first_ = end();
    entries_.clear();
  }

 private:
  static void keep(std::vector<std::size_t>& list, std::size_t i, bool in);
  std::vector<Entry> entries_;
  std::uint64_t first_ = 0;
  std::vector<std::size_t> chips_;
  std::vector<std::size_t> eager_;
  std::vector<std::vector<std::size_t>> at_address_ = std::vector<std::vector<std::size_t>>(256);
  std::vector<std::size_t> hear_now_;
};

}  // namespace dpc31
