// How far the bridge's loop runs the chip each turn (docs/bridge.md, "Pacing"): chip time against
// the wall clock, with the clock the caller's, so that a test can drive it with made-up times.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace dpc31::bridge {

class Pacing {
 public:
  using Clock = std::chrono::steady_clock;

  // `turn`: the chip time one turn may run at most, so that a chip slower than the wall clock (a
  // polling firmware in a Debug build) does not run ever longer turns and never read the client.
  Pacing(bool realtime, std::uint32_t clock_hz, Clock::duration turn)
      : realtime_(realtime), hz_(clock_hz), turn_(turn) {}

  // Chip cycles in a wall-clock duration (no overflow for years).
  [[nodiscard]] std::uint64_t cycles(Clock::duration d) const {
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(d).count();
    if (ns <= 0) return 0;
    const auto u = static_cast<std::uint64_t>(ns);
    return u / 1'000'000'000 * hz_ + u % 1'000'000'000 * hz_ / 1'000'000'000;
  }

  // Chip cycle `chip` is wall time `wall`: at the start, and in free pacing after an exchange
  // (which took no wall time).
  void anchor(Clock::time_point wall, std::uint64_t chip) {
    wall_ = wall;
    chip_ = chip;
  }

  // The chip cycle a turn that starts at `now` (the chip at `chip`) runs to. Realtime: the
  // wall-clock time of the turn's wake-up, `now + wait`; free: `now`. Either way at most `turn`
  // of chip time. Realtime keeps what that leaves (caught up over the next turns, the lag
  // reported); free drops it, so a slow chip keeps no debt. A turn longer than its wait (the poll's
  // own overhead) loses nothing: free kept only one wait of chip time a turn once, and its chip
  // time fell to about 0.9 of the wall clock's (audit s30 a-master, finding 7).
  [[nodiscard]] std::uint64_t target(Clock::time_point now, Clock::duration wait,
                                     std::uint64_t chip) {
    const std::uint64_t due = wall_cycle(realtime_ ? now + wait : now);
    const std::uint64_t most = chip + cycles(turn_);
    if (due <= most) return due;
    if (!realtime_) anchor(now, most);
    return most;
  }

  // The chip cycle of wall time `t` by the anchor.
  [[nodiscard]] std::uint64_t wall_cycle(Clock::time_point t) const {
    return chip_ + cycles(t - wall_);
  }

 private:
  bool realtime_;
  std::uint32_t hz_;
  Clock::duration turn_;
  Clock::time_point wall_{};
  std::uint64_t chip_ = 0;
};

}  // namespace dpc31::bridge
