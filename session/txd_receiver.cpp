#include "txd_receiver.hpp"

namespace dpc31 {

void TxdReceiver::take(const TxdRun& r) {
  const std::uint32_t t = rx_.bit_time();
  if (r.bytes.empty() || r.bit_cycles != t) {
    settle();
    rx_.take(r);
    return;
  }
  if (!run_.empty() && r.start == run_start_ + run_.size() * frame_cycles()) {
    run_.insert(run_.end(), r.bytes.begin(), r.bytes.end());
    return;
  }
  settle();
  // What the run's first start bit does to the receiver first: the samples before it (a character
  // begun before, finished by edges); the characters they end wait in early_.
  if (r.start > 0) rx_.advance(r.start - 1, early_);
  if (!rx_.idle_for(r.start, t)) {
    rx_.take(r);
    return;
  }
  run_.assign(r.bytes.begin(), r.bytes.end());
  run_start_ = r.start;
}

void TxdReceiver::edge(std::uint64_t cycle, bool level) {
  settle();
  rx_.edge(cycle, level);
}

void TxdReceiver::settle() {
  if (run_.empty()) return;
  if (rest_) {
    rx_.take(TxdRun{run_, run_start_, rx_.bit_time(), {}});
    run_.clear();
    rest_ = false;
    return;
  }
  // Something after the run: all its characters are sampled by then.
  const std::size_t first = early_.size();
  due_.swap(run_);
  due_start_ = run_start_;
  due_idle_bits_ = rx_.idle_bits_at(run_start_);
  due_chars(early_);
  rx_.after_chars(early_.back().start, due_.back(),
                  early_.size() - first == 1 ? due_idle_bits_ : 0);
  due_.clear();
  run_.clear();
}

void TxdReceiver::advance(std::uint64_t now, std::vector<UartChar>& out) {
  due_.clear();
  // Nothing kept, and the receiver neither sampling nor holding a character due by now: its
  // advance() would change nothing (the line is looked at far more often than a telegram ends).
  if (early_.empty() && run_.empty() && !rx_.receiving() && rx_.next_deadline() > now) return;
  // early_: every character in it ended before something taken since, so before now.
  out.insert(out.end(), early_.begin(), early_.end());
  early_.clear();
  rx_.advance(now, out);
  if (run_.empty()) return;
  // Character i's stop sample: run_start_ + (11 i + 10) T + T/2.
  const std::uint64_t first_stop = stop_sample(run_start_);
  const std::size_t k = now < first_stop
                            ? 0
                            : static_cast<std::size_t>(std::min<std::uint64_t>(
                                  run_.size(), (now - first_stop) / frame_cycles() + 1));
  if (k > 0) {
    due_start_ = run_start_;
    due_idle_bits_ = rx_.idle_bits_at(run_start_);
    // The receiver as take() and advance() leave it once these characters are reported.
    rx_.after_chars(run_start_ + (k - 1) * frame_cycles(), run_[k - 1],
                    k == 1 ? due_idle_bits_ : 0);
  }
  if (k == run_.size()) {
    due_.swap(run_);  // all of it due: no copy
    run_.clear();
    rest_ = false;
    return;
  }
  // The rest is not due yet: kept, the receiver as those k leave it (settle() gives it over).
  due_.assign(run_.begin(), run_.begin() + static_cast<std::ptrdiff_t>(k));
  run_.erase(run_.begin(), run_.begin() + static_cast<std::ptrdiff_t>(k));
  run_start_ += k * frame_cycles();
  rest_ = true;
}

void TxdReceiver::due_chars(std::vector<UartChar>& out) const {
  for (std::size_t i = 0; i < due_.size(); ++i) {
    const std::uint64_t at = due_start_ + i * frame_cycles();
    out.push_back(
        {due_[i], true, true, true, at, at + frame_cycles(), i == 0 ? due_idle_bits_ : 0});
  }
}

}  // namespace dpc31
