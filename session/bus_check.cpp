#include "bus_check.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "dp_master.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {
constexpr std::array<std::string_view, kBusViolationKinds> kNames = {
    "early_answer", "late_answer", "short_tsyn", "wrong_responder", "bad_frame",
    "unsolicited",  "collision",   "token_lost", "duplicate_token", "token_hold"};

bool is_token(const fdl::Frame& f) { return f.sd == fdl::SD4; }
bool is_request(const fdl::Frame& f) {
  return is_token(f) || (f.sd != fdl::SC && fdl::is_request(f.fc));
}
}  // namespace

bool mirrors(const fdl::Frame& answer, std::uint8_t request_sa, std::uint8_t request_da) {
  return answer.sd == fdl::SC || (answer.sa == request_da && answer.da == request_sa);
}

bool answers_request(const BusTiming& t, std::uint64_t delay, bool ok, bool mirroring) {
  return delay <= std::uint64_t{t.slot_bits} * t.bit_cycles ||
         (ok && mirroring && delay < (std::uint64_t{t.slot_bits} + t.tsyn_bits) * t.bit_cycles);
}

std::string_view bus_violation_name(BusViolation v) { return kNames[static_cast<std::size_t>(v)]; }

bool parse_bus_violation(std::string_view s, BusViolation& out) {
  const auto it = std::find(kNames.begin(), kNames.end(), s);
  if (it == kNames.end()) return false;
  out = static_cast<BusViolation>(it - kNames.begin());
  return true;
}

BusCheck::BusCheck(BusTiming timing, LogSink sink)
    : timing_(std::move(timing)), sink_(std::move(sink)) {
  arrived_.fill(kNever);
}

void BusCheck::watch(Segment& seg) {
  watch_from(seg.cycle());
  seg.on_telegram = [this, &seg](const LineTelegram& t) { telegram(t, seg.name(t.from)); };
  seg.on_collision = [this, &seg](const Collision& c) {
    collision(c, seg.name(c.first), seg.name(c.second));
  };
}

std::uint64_t BusCheck::total() const {
  std::uint64_t n = 0;
  for (const std::uint64_t c : counts_) n += c;
  return n;
}

void BusCheck::violation(BusViolation v, std::uint64_t cycle, const std::string& text) {
  ++counts_[static_cast<std::size_t>(v)];
  last_violation_ = cycle;
  for (std::string& line :
       limiter_.add(cycle, fmt::format("bus: {}: {}", bus_violation_name(v), text))) {
    if (sink_) sink_(LogRecord{cycle, LogLevel::warn, std::move(line)});
  }
}

void BusCheck::flush() {
  for (std::string& line : limiter_.flush()) {
    if (sink_) sink_(LogRecord{last_end_.value_or(0), LogLevel::warn, std::move(line)});
  }
}

void BusCheck::end_repeats() {
  for (std::string& line : limiter_.end_repeats()) {
    if (sink_) sink_(LogRecord{last_violation_, LogLevel::warn, std::move(line)});
  }
}

// TTO = TSL x (6 + 2 x n): the master with the lowest address n times out first.
std::uint64_t BusCheck::token_lost_timeout() const {
  const std::uint64_t n = timing_.masters.empty()
                              ? 0
                              : *std::min_element(timing_.masters.begin(), timing_.masters.end());
  return bits(std::uint64_t{timing_.slot_bits} * (6 + 2 * n));
}

void BusCheck::idle_until(std::uint64_t now) {
  if (timing_.masters.empty() || !last_end_ || token_lost_reported_) return;
  const std::uint64_t due = *last_end_ + token_lost_timeout();
  if (now < due) return;
  token_lost_reported_ = true;
  // The token is gone: the next request or token claims a new one (no hold of the old counts).
  holder_.reset();
  passing_.reset();
  violation(BusViolation::token_lost, due,
            fmt::format("the line idle for TTO ({} bit times) since cycle {}",
                        token_lost_timeout() / timing_.bit_cycles, *last_end_));
}

void BusCheck::collision(const Collision& c, const std::string& first, const std::string& second) {
  violation(BusViolation::collision, c.cycle,
            fmt::format("{} drove the line while {} had it", second, first));
  // The second driver's telegram is lost in it (what is heard of it after is its rest,
  // LineTelegram::collided, no telegram of its own): it is judged by its start alone. Inside the
  // answer window of the request waiting then it may have been the answer, and the collision says
  // all; after that window (a station answering after TSL + TSYN drives into the asker's next
  // request), or with no request waiting, nobody asked for it. A request or a token
  // (Collision::answer) is no answer: the collision says all of it too.
  if (c.cycle < watched_from_ || !c.answer) return;
  if (pending_ &&
      (c.cycle < pending_->end || answers_request(timing_, c.cycle - pending_->end, false, false)))
    return;
  violation(
      BusViolation::unsolicited, c.cycle,
      pending_ ? fmt::format("a telegram from {} nobody asked for, begun {} bit times after "
                             "the request to station {} (slot time {}), lost in the collision",
                             second, (c.cycle - pending_->end) / timing_.bit_cycles,
                             pending_->request.da, timing_.slot_bits)
               : fmt::format("a telegram from {} nobody asked for, lost in the collision", second));
}

// An SC carries no address: its sender is named, as short_tsyn names it.
void BusCheck::unsolicited(const LineTelegram& t, const fdl::Frame& f, const std::string& sender) {
  const std::string from = f.sd != fdl::SC  ? fmt::format(" from station {}", f.sa)
                           : sender.empty() ? std::string()
                                            : " from " + sender;
  violation(BusViolation::unsolicited, t.start,
            fmt::format("{}{} nobody asked for", f.sd == fdl::SC ? "an SC" : "an answer", from));
}

// The telegram after a request that wants an answer (docs/timing.md, "The master's wait"): the
// answer window ends at the slot time TSL after the request's end. A telegram starting later is
// no answer: the asked station's, before the asker may send again (TSL + TSYN), is its late
// answer; any other stands on its own.
void BusCheck::answer(const LineTelegram& t, const fdl::Frame& f, bool ok,
                      const std::string& sender) {
  const Pending p = *pending_;
  pending_.reset();
  const std::uint64_t delay = t.start - p.end;
  const std::uint64_t tbits = delay / timing_.bit_cycles;
  const bool mirroring = mirrors(f, p.request.sa, p.request.da);
  if (!answers_request(timing_, delay, ok, mirroring)) {
    if (ok) unsolicited(t, f, sender);
    return;
  }
  if (on_answer) on_answer(delay);
  if (delay > bits(timing_.slot_bits)) {
    violation(BusViolation::late_answer, t.start,
              fmt::format("answer to station {} {} bit times after the request (slot time {})",
                          p.request.da, tbits, timing_.slot_bits));
    return;
  }
  if (delay < bits(timing_.min_tsdr_bits)) {
    violation(BusViolation::early_answer, t.start,
              fmt::format("answer to station {} {} bit times after the request (min TSDR {})",
                          p.request.da, tbits, timing_.min_tsdr_bits));
  }
  if (ok && !mirroring) {
    violation(BusViolation::wrong_responder, t.start,
              fmt::format("station {} answered to {}, asked: {} by {}", f.sa, f.da, p.request.da,
                          p.request.sa));
  }
}

// TTH = TTR - TRR, TRR the time since the same master's arrival before (docs/segment.md, "The
// token"); a late token (TRR >= TTR) allows the visit's first cycle only.
void BusCheck::arrive(std::uint8_t holder, std::uint64_t at, bool rotated) {
  std::uint64_t& before = arrived_[holder];
  hold_from(holder, at, rotated && before != kNever ? at - before : 0);
  before = at;
}

void BusCheck::hold_from(std::uint8_t holder, std::uint64_t at, std::uint64_t trr) {
  trr_ = trr;
  const std::uint64_t ttr = bits(timing_.ttr_bits);
  hold_ = trr_ < ttr ? ttr - trr_ : 0;
  holder_ = holder;
  token_at_ = at;
  held_cycle_started_ = false;
  passing_.reset();
}

// EN 50170 / IEC 61158-4-3 token passing: the passer watches the line for the slot time; when the
// addressee shows no activity it passes the token again, or to the station after. So a token
// passed is taken at its addressee's first request or token (arriving at the SD4's end, as
// DpMaster::wait_token takes it); until then the passer holds it, and its retry or its pass to
// another station once the slot time has passed is no second token (before, the addressee may
// still begin).
void BusCheck::token_rules(const LineTelegram& t, const fdl::Frame& f) {
  if (passing_ && f.sa == passing_->to) arrive(f.sa, passing_->end, true);
  if (holder_ && f.sa != *holder_) {
    violation(BusViolation::duplicate_token, t.start,
              fmt::format("station {} sent while station {} holds the token", f.sa, *holder_));
  } else if (passing_ && t.start < passing_->end + bits(timing_.slot_bits)) {
    violation(BusViolation::duplicate_token, t.start,
              fmt::format("station {} sent {} bit times after its token to station {}, inside the "
                          "slot time ({}) in which that station may take it",
                          f.sa, (t.start - passing_->end) / timing_.bit_cycles, passing_->to,
                          timing_.slot_bits));
  } else if (holder_ && timing_.ttr_bits != 0 && !is_token(f) && held_cycle_started_ &&
             t.start >= token_at_ + hold_) {
    violation(BusViolation::token_hold, t.start,
              fmt::format("station {} started a message cycle {} bit times after it got the "
                          "token (TTH {} = TTR {} - TRR {})",
                          f.sa, (t.start - token_at_) / timing_.bit_cycles,
                          hold_ / timing_.bit_cycles, timing_.ttr_bits, trr_ / timing_.bit_cycles));
  }
  // A claimed token: held from the TSYN its first request or token waited, no rotation before.
  // A claim by a token is no arrival (DpMaster::pass_token measures no TRR from it).
  const std::uint64_t claimed = t.start - std::min(t.start, bits(timing_.tsyn_bits));
  if (is_token(f)) {
    if (!holder_) hold_from(f.sa, claimed, 0);
    if (f.da == f.sa) {
      arrive(f.sa, t.end, true);  // a master alone takes its own token at the SD4's end
    } else {
      passing_ = Pass{f.da, t.end};
    }
  } else {
    if (!holder_) arrive(f.sa, claimed, false);
    held_cycle_started_ = true;
  }
}

void BusCheck::telegram(const LineTelegram& t, const std::string& sender) {
  if (t.start < watched_from_) {
    // Begun before the check (armed inside it, as after a call that returns at an answer's last
    // stop sample): its request was not seen, so it is no answer, nor unsolicited.
    last_end_ = t.end;
    return;
  }
  idle_until(t.start);
  token_lost_reported_ = false;
  if (t.collided) {
    // The rest of a telegram lost in a collision: judged there (collision), counted once.
    last_end_ = t.end;
    return;
  }
  const fdl::Decoded d = fdl::decode(t.bytes);
  // A broken character breaks the telegram whatever its bytes read (a chip discards it).
  const bool chars_ok = t.fault.kind == UartFault::Kind::none;
  const bool ok = chars_ok && d.error == fdl::Error::none;
  const bool request = ok && is_request(d.frame);
  if (!ok) {
    violation(BusViolation::bad_frame, t.start,
              fmt::format("{} bytes from cycle {} do not decode ({})", t.bytes.size(), t.start,
                          chars_ok ? std::string(fdl::error_name(d.error))
                                   : fmt::format("character {}: {}", t.fault.char_index,
                                                 fault_name(t.fault.kind))));
  }
  if (pending_ && !request) {
    answer(t, d.frame, ok, sender);
  } else if (!request && ok) {
    unsolicited(t, d.frame, sender);
  }
  if (request) {
    pending_.reset();
    if (last_end_ && t.start < *last_end_ + bits(timing_.tsyn_bits)) {
      // The sender, not the SA it wrote: a scripted station may send in another's name.
      violation(BusViolation::short_tsyn, t.start,
                fmt::format("{} sent after {} bit times of idle (TSYN {})",
                            sender.empty() ? fmt::format("station {}", d.frame.sa) : sender,
                            (t.start - *last_end_) / timing_.bit_cycles, timing_.tsyn_bits));
    }
    // Who holds the token needs only the masters; how long it may hold it, their TTR.
    if (!timing_.masters.empty()) token_rules(t, d.frame);
    if (wants_answer(d.frame)) pending_ = Pending{d.frame, t.end};
  }
  last_end_ = t.end;
}

}  // namespace dpc31
