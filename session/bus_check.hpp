// The bus checks of a segment (docs/segment.md, "Bus checks"): every telegram on the line
// against the timing rules of EN 50170 / IEC 61158-4-3 as docs/timing.md states them. Each
// violation is a count and a log line (through a LogLimiter: a babbling station cannot flood).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "dpc31/fdl.hpp"
#include "dpc31/log.hpp"
#include "segment.hpp"

namespace dpc31 {

enum class BusViolation : std::uint8_t {
  early_answer,     // an answer sooner than min TSDR after the request's end
  late_answer,      // the asked station's answer after the slot time (before TSL + TSYN)
  short_tsyn,       // a request or token with less than TSYN idle before it
  wrong_responder,  // an answer from another station than the one asked, or to another
  bad_frame,        // a telegram that does not decode (FCS, ED, length, truncated)
  unsolicited,      // an answer nobody asked for, or no longer (a babbling station)
  collision,        // two stations driving at once (Segment::collisions)
  token_lost,       // the line idle longer than the token-lost timeout TTO
  duplicate_token,  // a request or token from a station that does not hold the token
  token_hold,       // a new message cycle after the holder's TTR ran out
};
inline constexpr std::size_t kBusViolationKinds = 10;
[[nodiscard]] std::string_view bus_violation_name(BusViolation v);
[[nodiscard]] bool parse_bus_violation(std::string_view s, BusViolation& out);

struct BusTiming {
  std::uint32_t bit_cycles = 0;
  std::uint32_t min_tsdr_bits = 11;  // the smallest answer delay a slave may use
  std::uint32_t slot_bits = 100;     // TSL
  std::uint32_t tsyn_bits = 33;      // TSYN
  // TTR in bit times, for token_hold; 0: none (token_hold is not checked).
  std::uint64_t ttr_bits = 0;
  // The masters' addresses (for TTO = TSL x (6 + 2 x lowest address)); none: no token on this
  // line, no token checks (token_lost, duplicate_token, token_hold).
  std::vector<std::uint8_t> masters;
};

// Whether the frame `answer` is the asked station's answer to a request from `request_sa` to
// `request_da`: an SC, or the request's SA and DA mirrored.
[[nodiscard]] bool mirrors(const fdl::Frame& answer, std::uint8_t request_sa,
                           std::uint8_t request_da);
// Whether a frame that decodes (`ok`), starting `delay` clock cycles after a request's end, is
// that request's answer as the bus check pairs them: within the slot time, or the asked
// station's (`mirroring`) late answer before TSL + TSYN; anything later is unsolicited
// (docs/segment.md). The capture pairs its telegrams by it too (docs/capture.md).
[[nodiscard]] bool answers_request(const BusTiming& t, std::uint64_t delay, bool ok,
                                   bool mirroring);

class BusCheck {
 public:
  // `sink`: where each violation's log line goes (through the limiter).
  explicit BusCheck(BusTiming timing, LogSink sink = {});

  // Wires itself to the segment's telegrams and collisions, from the segment's cycle now
  // (watch_from).
  void watch(Segment& seg);
  // Judges the telegrams that begin at or after `cycle`: one that began before it (its request
  // unseen, when armed inside an answer) counts only by its end, for the idle time after it.
  void watch_from(std::uint64_t cycle) { watched_from_ = cycle; }
  // `sender`: the sending station's name (Segment::name), for the log; none: its frame's SA.
  void telegram(const LineTelegram& t, const std::string& sender = {});
  void collision(const Collision& c, const std::string& first, const std::string& second);
  // The line is idle up to `now` (a token lost is found once TTO has passed without a telegram).
  void idle_until(std::uint64_t now);
  // The rules from now on, the counts and the token's state kept (Python's check_bus follows the
  // masters added after it: their addresses, slot time and TTR where the call gave none).
  void retime(BusTiming timing) { timing_ = std::move(timing); }
  // Hands the sink what the limiter still owes.
  void flush();
  // A line of another source goes into the same log now (the limiter's end_repeats): the note of
  // the violations repeated before it is handed to the sink first, at the last one's cycle.
  void end_repeats();

  // Told of each telegram the check pairs with its request as its answer (answers_request): the
  // delay from the request's end to its first start bit, in clock cycles (`expect tsdr`).
  std::function<void(std::uint64_t delay)> on_answer;

  [[nodiscard]] std::uint64_t count(BusViolation v) const {
    return counts_[static_cast<std::size_t>(v)];
  }
  [[nodiscard]] std::uint64_t total() const;

 private:
  void violation(BusViolation v, std::uint64_t cycle, const std::string& text);
  void answer(const LineTelegram& t, const fdl::Frame& f, bool ok, const std::string& sender);
  void unsolicited(const LineTelegram& t, const fdl::Frame& f, const std::string& sender);
  [[nodiscard]] std::uint64_t bits(std::uint64_t n) const { return n * timing_.bit_cycles; }
  [[nodiscard]] std::uint64_t token_lost_timeout() const;

  BusTiming timing_;
  LogSink sink_;
  LogLimiter limiter_;
  std::array<std::uint64_t, kBusViolationKinds> counts_{};
  std::optional<std::uint64_t> last_end_;  // end of the last telegram on the line
  std::uint64_t watched_from_ = 0;         // the segment's cycle at watch()
  std::uint64_t last_violation_ = 0;       // the cycle of the last violation
  bool token_lost_reported_ = false;
  struct Pending {
    fdl::Frame request;
    std::uint64_t end;
  };
  std::optional<Pending> pending_;  // a request waiting for its answer
  // Who holds the token and how long (docs/segment.md, "The token"), for a request or token `f`.
  void token_rules(const LineTelegram& t, const fdl::Frame& f);
  // The token to `holder` at `at` (`rotated`: by an SD4; else claimed, no rotation before).
  void arrive(std::uint8_t holder, std::uint64_t at, bool rotated);
  // `holder` holds the token from `at`, after a rotation time `trr` (cycles).
  void hold_from(std::uint8_t holder, std::uint64_t at, std::uint64_t trr);

  static constexpr std::uint64_t kNever = UINT64_MAX;
  std::optional<std::uint8_t> holder_;        // who holds the token
  std::uint64_t token_at_ = 0;                // when the holder got it
  std::uint64_t trr_ = 0;                     // its TRR then, in cycles
  std::uint64_t hold_ = 0;                    // its TTH = TTR - TRR (0: a late token), in cycles
  bool held_cycle_started_ = false;           // the holder started a message cycle since then
  std::array<std::uint64_t, 256> arrived_{};  // each master's last arrival (kNever: none)
  struct Pass {
    std::uint8_t to;
    std::uint64_t end;
  };
  std::optional<Pass> passing_;  // a token passed, not yet taken (its addressee silent so far)
};

}  // namespace dpc31
