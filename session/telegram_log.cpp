#include "telegram_log.hpp"

#include <algorithm>
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

}  // namespace dpc31
