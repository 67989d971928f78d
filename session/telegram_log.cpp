#include "telegram_log.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <iterator>

#include "dpc31/fdl.hpp"

namespace dpc31 {

int TelegramLog::concerns(const HeardFrame& f) {
  if (f.bytes.empty()) return kEveryone;
  const fdl::Assembler::Status st = f.frame.status();
  // The frame ends before the telegram does or runs into a frame timeout: characters, events.
  if (f.verdict + 1 != f.bytes.size() || st == fdl::Assembler::Status::need_more) return kEveryone;
  if (st == fdl::Assembler::Status::error || f.decoded.error != fdl::Error::none) return kNobody;
  const fdl::Frame& fr = f.decoded.frame;
  const bool carries_data = fr.sd == fdl::SD1 || fr.sd == fdl::SD2 || fr.sd == fdl::SD3;
  if (!carries_data || !fdl::is_request(fr.fc)) return kNobody;  // a token, a short ack, an answer
  if (fr.da == fdl::kBroadcast) return kEveryone;
  return fr.da;
}

void TelegramLog::keep(std::vector<std::size_t>& list, std::size_t i, bool in) {
  const auto at = std::lower_bound(list.begin(), list.end(), i);
  if (in) {
    list.insert(at, i);
  } else {
    list.erase(at);
  }
}

void TelegramLog::set_address(std::size_t i, int from, int to) {
  if (from >= 0) keep(at_address_[static_cast<std::size_t>(from)], i, false);
  if (to >= 0) keep(at_address_[static_cast<std::size_t>(to)], i, true);
}

const std::vector<std::size_t>& TelegramLog::hear_now(const HeardFrame& f) {
  // A copy: looking at a chip that heard it changes the lists.
  const int who = concerns(f);
  if (who == kEveryone) {
    hear_now_ = chips_;
  } else if (who == kNobody) {
    hear_now_ = eager_;
  } else {
    const auto& at = at_address_[static_cast<std::size_t>(who)];
    hear_now_.clear();
    std::set_union(eager_.begin(), eager_.end(), at.begin(), at.end(),
                   std::back_inserter(hear_now_));
  }
  return hear_now_;
}

namespace {

// What a telegram after TSYN counts in a chip it does not address (Mac::frame_ended, on_frame):
// an error by class; a good frame offline, or a request with data for another station.
void count_verdict(const HeardFrame& f, TelegramLog::Entry& e) {
  const fdl::Assembler::Status st = f.frame.status();
  if (st == fdl::Assembler::Status::error || f.decoded.error != fdl::Error::none) {
    count_frame_error(e.started, f.frame, f.decoded.error);
    count_frame_error(e.offline, f.frame, f.decoded.error);
    return;
  }
  ++e.offline.offline;
  const fdl::Frame& fr = f.decoded.frame;
  const bool carries_data = fr.sd == fdl::SD1 || fr.sd == fdl::SD2 || fr.sd == fdl::SD3;
  if (carries_data && fdl::is_request(fr.fc)) ++e.started.foreign_address;
}

// Counter by counter: to -= from. Every counter is a std::uint32_t (kFdlCounterFields): as an
// array, one loop the compiler vectorises instead of one member pointer per counter.
void subtract(FdlCounters& to, const FdlCounters& from) {
  using Counts = std::array<std::uint32_t, kFdlCounterFields.size()>;
  static_assert(sizeof(Counts) == sizeof(FdlCounters));
  auto a = std::bit_cast<Counts>(to);
  const auto b = std::bit_cast<Counts>(from);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] -= b[i];
  to = std::bit_cast<FdlCounters>(a);
}

}  // namespace

void TelegramLog::append(std::shared_ptr<const HeardFrame> frame, std::uint64_t start,
                         std::size_t from, std::uint32_t t) {
  // Built in place, its sums from the entry before's (a verdict adds to one or two counters: no
  // counter-by-counter sum, no copy of the entry).
  Entry& e = entries_.emplace_back();
  if (entries_.size() > 1) {
    const Entry& before = entries_[entries_.size() - 2];
    e.started = before.started;
    e.offline = before.offline;
  }
  e.frame = std::move(frame);
  e.start = start;
  e.from = from;
  const HeardFrame& f = *e.frame;
  const std::uint64_t n = end() - 1;
  // Mac::hear_telegram's kind and take_heard's effect, with the receiver after the entry before
  // (UartRx::after_chars: idle from the end of its last stop bit).
  const bool linked = line_end_ != kNone && start >= line_end_;
  if (linked) e.idle = std::min((start - line_end_) / t, kUartMaxIdleBits);
  if (linked && e.idle >= kTsynBits) {
    count_verdict(f, e);
    e.skipping = f.frame.status() == fdl::Assembler::Status::error;
    synced_ = n;
  } else {
    e.no_sync = linked && !line_skipping_;
    if (e.no_sync) {
      ++e.started.no_sync;
      ++e.offline.no_sync;
    }
    e.skipping = true;
  }
  // Foldable: linked, and a verdict at its last character that shows nothing in a chip it does
  // not address (TelegramLog::concerns).
  if (!linked || concerns(f) == kEveryone) unfolded_ = n;
  e.unfolded = unfolded_;
  e.synced = synced_;
  line_end_ = start + f.bytes.size() * std::uint64_t{kUartCharBits} * t;
  line_skipping_ = e.skipping;
}

void TelegramLog::forget(std::uint64_t n) {
  if (n <= first_) return;
  entries_.erase(entries_.begin(), entries_.begin() + static_cast<std::ptrdiff_t>(n - first_));
  first_ = n;
}

std::uint64_t TelegramLog::folds_until(std::uint64_t n, std::uint64_t to) const {
  // Both grow along the log: the start, and the last entry that cannot be folded.
  const auto from = entries_.begin() + static_cast<std::ptrdiff_t>(n - first_);
  const auto it = std::partition_point(from, entries_.end(), [&](const Entry& e) {
    return e.start <= to && (e.unfolded == kNone || e.unfolded < n);
  });
  return n + static_cast<std::uint64_t>(it - from);
}

HeardRun TelegramLog::run(std::uint64_t n, std::uint64_t m, std::uint32_t t) const {
  const Entry& first = at(n);
  const Entry& last = at(m - 1);
  HeardRun r;
  r.first_start = first.start;
  r.first_idle = first.idle;
  // The sums from n on; the first entry's no_sync is the chip's own.
  r.started = last.started;
  r.offline = last.offline;
  subtract(r.started, at(n - 1).started);
  subtract(r.offline, at(n - 1).offline);
  if (first.no_sync) {
    --r.started.no_sync;
    --r.offline.no_sync;
  }
  r.skipping = last.skipping;
  if (last.synced != kNone && last.synced >= n) r.synced = at(last.synced).frame.get();
  const std::vector<std::uint8_t>& bytes = last.frame->bytes;
  r.last_start = last.start + (bytes.size() - 1) * std::uint64_t{kUartCharBits} * t;
  r.last_byte = bytes.back();
  r.last_idle = bytes.size() == 1 ? last.idle : 0;
  r.bit_cycles = t;
  return r;
}

}  // namespace dpc31
