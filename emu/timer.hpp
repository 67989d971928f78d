// The engine's time (docs/engine.md, docs/timing.md "Order within one cycle"). A block asks
// "wake me `cycles` clocks from now" (Clock::arm), whether the time has come (reached) or is
// still running (running), and when it fires (due); it never asks which engine runs. The engine
// keeps each timer its own way: the event engine as the absolute cycle it fires (`at`, a
// deadline it jumps to), the per-cycle engine as the clocks still to count (`left`, counted down
// once per clock, never derived from `at`), so the two engines agreeing (tests: Engine.*) checks
// the deadline arithmetic. Only the Clock and the engine (emu/engine.cpp) read or write a
// Timer's members.
#pragma once

#include <cstdint>
#include <limits>

#include "dpc31/chip.hpp"

namespace dpc31 {

inline constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

struct Timer {
  std::uint64_t at = kNever;    // event engine: the cycle it fires (kNever: off)
  std::uint64_t left = kNever;  // per-cycle engine: clocks still to count (kNever: off, 0: reached)
  // A timer that has already run out (the EOI inactive time after reset).
  static constexpr Timer elapsed() { return Timer{0, 0}; }
};

// The chip's time, shared by every block: the current cycle, the clock rate, and the timer
// operations. The engine (ChipCore::advance, emu/engine.cpp) moves `now`; the blocks only read it
// and arm their timers.
struct Clock {
  Engine engine = Engine::event;
  std::uint32_t hz = 0;
  std::uint64_t now = 0;
  // Event engine: no deadline falls before this cycle (a lower bound; 0 = unknown; always 0 in the
  // per-cycle engine). Lets a bus access that crosses no deadline skip the search for the next
  // event.
  std::uint64_t quiet_until = 0;

  [[nodiscard]] std::uint64_t cycles_for_us(std::uint64_t us) const {
    // Round up: the manuals give minimum times ("at least 1 us").
    return (std::uint64_t{hz} * us + 999'999u) / 1'000'000u;
  }
  // Whatever sets a deadline (arm, the MAC's receiver and transmitter) reports it here: a bus
  // access of the event engine then must not run past it.
  void note_deadline(std::uint64_t at) {
    if (at < quiet_until) quiet_until = 0;
  }
  // Fires `cycles` clocks from now; kNever: off.
  void arm(Timer& t, std::uint64_t cycles) {
    if (engine == Engine::event) {
      t.at = cycles == kNever ? kNever : now + cycles;
      note_deadline(t.at);
    } else {
      t.left = cycles;
    }
  }
  // Fires now (or has fired, not re-armed).
  [[nodiscard]] bool reached(const Timer& t) const {
    return engine == Engine::event ? t.at <= now : t.left == 0;
  }
  // Armed and not yet reached.
  [[nodiscard]] bool running(const Timer& t) const {
    return engine == Engine::event ? now < t.at : t.left != 0;
  }
  // The cycle it fires (kNever: off).
  [[nodiscard]] std::uint64_t due(const Timer& t) const {
    if (engine == Engine::event) return t.at;
    return t.left == kNever ? kNever : now + t.left;
  }
};

}  // namespace dpc31
